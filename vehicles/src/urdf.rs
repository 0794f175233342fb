//! URDF import: links with their inertials and geometry, joints, mesh files resolved from
//! `package://`, `file://` and relative URIs.

use std::path::{Path, PathBuf};

use regolith_rigid::{Axis, Pose, ShapeDesc, load_mesh};

use crate::lump::{MassProperties, combine_mass, rotate_inertia};
use crate::xacro::Substitution;

/// A URDF that cannot be used: the file and what is wrong (naming the link or joint).
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", file.display())]
pub struct UrdfError {
    /// The URDF file.
    pub file: PathBuf,
    /// What is wrong.
    pub message: String,
}

/// Joint kinds the importer honours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointType {
    /// Rigidly attached.
    Fixed,
    /// Rotation about the axis without limits (wheels).
    Continuous,
    /// Rotation about the axis within `[lower, upper]` rad (steering).
    Revolute {
        /// Lower limit (rad).
        lower: f64,
        /// Upper limit (rad).
        upper: f64,
    },
    /// Translation along the axis within `[lower, upper]` m (suspension).
    Prismatic {
        /// Lower limit (m).
        lower: f64,
        /// Upper limit (m).
        upper: f64,
    },
}

impl JointType {
    /// Its URDF name: `fixed`, `continuous`, `revolute` or `prismatic`.
    pub fn describe(&self) -> &'static str {
        match self {
            Self::Fixed => "fixed",
            Self::Continuous => "continuous",
            Self::Revolute { .. } => "revolute",
            Self::Prismatic { .. } => "prismatic",
        }
    }
}

/// A link: its inertial (link frame) and its geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkModel {
    /// Name.
    pub name: String,
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the link frame (m).
    pub com: [f64; 3],
    /// Inertia about the centre of mass in link-frame axes, `[ixx, iyy, izz, ixy, ixz, iyz]`.
    pub inertia: [f64; 6],
    /// Collision shapes at their poses in the link frame.
    pub collision: Vec<(Pose, ShapeDesc)>,
    /// Visual shapes at their poses in the link frame.
    pub visual: Vec<(Pose, ShapeDesc)>,
}

/// A joint between two links.
#[derive(Clone, Debug, PartialEq)]
pub struct JointModel {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: JointType,
    /// Parent link (index into [`UrdfModel::links`]).
    pub parent: usize,
    /// Child link.
    pub child: usize,
    /// Child (joint) frame in the parent link frame.
    pub origin: Pose,
    /// Unit axis in the joint frame.
    pub axis: [f64; 3],
    /// Effort limit from `<limit>` (N m or N; 0 when not given).
    pub effort: f64,
}

/// A URDF robot ready to be built into a rigid world.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfModel {
    /// Robot name.
    pub name: String,
    /// The file it came from.
    pub path: PathBuf,
    /// The links that move, each with the links fixed to it lumped in (masses, inertias and
    /// shapes; see [`UrdfModel::parse_with_env`]).
    pub links: Vec<LinkModel>,
    /// The moving joints the importer honours (fixed joints are lumped: see `frames`).
    pub joints: Vec<JointModel>,
    /// URDF links lumped into [`UrdfModel::links`] by their fixed joints, kept as frames.
    pub frames: Vec<FrameModel>,
    /// The root link (no parent joint).
    pub root: usize,
    /// Joints and features it could not honour, one line each (`joint "x": planar joints are
    /// not supported; the child link moves freely`), for the caller to report once.
    pub unsupported: Vec<String>,
    /// The `$(optenv …)` and `$(env …)` substitutions resolved in the file, in order.
    pub substitutions: Vec<Substitution>,
}

/// A URDF link lumped into another by a fixed joint: no body of its own, but a named frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameModel {
    /// The URDF link's name.
    pub name: String,
    /// The fixed joint that attached it.
    pub joint: String,
    /// The link it is part of (index into [`UrdfModel::links`]).
    pub link: usize,
    /// Its frame in that link's frame.
    pub pose: Pose,
}

/// Where `package://` URIs are looked up: the search roots in order. A root either contains
/// the package as a sub-directory (`ROOT/NAME/…`) or is the package directory itself
/// (its last component is `NAME`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PackagePath(pub Vec<PathBuf>);

impl PackagePath {
    /// Roots from the scene (`extra`, first) then the `REGOLITH_PACKAGE_PATH` and
    /// `ROS_PACKAGE_PATH` environment variables (`:`-separated, like ROS).
    pub fn with_env(extra: &[PathBuf]) -> Self {
        let mut roots = extra.to_vec();
        for var in ["REGOLITH_PACKAGE_PATH", "ROS_PACKAGE_PATH"] {
            if let Some(v) = std::env::var_os(var) {
                roots.extend(std::env::split_paths(&v).filter(|p| !p.as_os_str().is_empty()));
            }
        }
        Self(roots)
    }

    fn find(&self, package: &str) -> Option<PathBuf> {
        self.0.iter().find_map(|root| {
            if root.file_name().is_some_and(|n| n == package) && root.is_dir() {
                return Some(root.clone());
            }
            let p = root.join(package);
            p.is_dir().then_some(p)
        })
    }

    fn describe(&self) -> String {
        if self.0.is_empty() {
            "no search roots (set the vehicle's package_path or REGOLITH_PACKAGE_PATH / ROS_PACKAGE_PATH)".into()
        } else {
            let list: Vec<String> = self.0.iter().map(|p| p.display().to_string()).collect();
            format!("searched {}", list.join(", "))
        }
    }
}

/// Resolves a mesh URI: `package://NAME/rest`, `file:///abs/path`, or a path relative to the
/// URDF's directory.
pub fn resolve_uri(uri: &str, urdf_dir: &Path, packages: &PackagePath) -> Result<PathBuf, String> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let (pkg, file) = rest.split_once('/').ok_or_else(|| format!("`{uri}` names no file inside the package"))?;
        let dir = packages
            .find(pkg)
            .ok_or_else(|| format!("package `{pkg}` of `{uri}` not found: {}", packages.describe()))?;
        let p = dir.join(file);
        return if p.is_file() {
            Ok(p)
        } else {
            Err(format!(
                "mesh `{uri}` not found: package `{pkg}` is {}, but {} does not exist",
                dir.display(),
                p.display()
            ))
        };
    }
    let p = match uri.strip_prefix("file://") {
        Some(abs) => PathBuf::from(abs),
        None => urdf_dir.join(uri),
    };
    if p.is_file() { Ok(p) } else { Err(format!("mesh `{uri}` not found: {} does not exist", p.display())) }
}

fn pose(p: &urdf_rs::Pose) -> Pose {
    Pose::from_rpy_deg(p.xyz.0, p.rpy.0.map(f64::to_degrees))
}

/// A URDF link before fixed joints are lumped: its mass properties may be zero (a frame).
struct RawLink {
    name: String,
    mass: MassProperties,
    collision: Vec<(Pose, ShapeDesc)>,
    visual: Vec<(Pose, ShapeDesc)>,
}

impl UrdfModel {
    /// Reads a URDF file, resolving `$(optenv …)` and `$(env …)` from the process
    /// environment; meshes are loaded (and scaled) now, so every missing file is found at load
    /// time.
    pub fn load(path: &Path, packages: &PackagePath) -> Result<Self, UrdfError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| UrdfError { file: path.to_path_buf(), message: format!("cannot read: {e}") })?;
        Self::parse(&text, path, packages)
    }

    /// Parses URDF text; `path` names it in errors and anchors relative mesh paths. The
    /// environment resolves `$(optenv …)` and `$(env …)`.
    pub fn parse(text: &str, path: &Path, packages: &PackagePath) -> Result<Self, UrdfError> {
        Self::parse_with_env(text, path, packages, &|name| std::env::var(name).ok())
    }

    /// [`UrdfModel::parse`] with the variables of `$(optenv …)` and `$(env …)` read through
    /// `env` (the process environment in [`UrdfModel::parse`]).
    ///
    /// Links joined by fixed joints become one link (the parent, as Gazebo and Isaac lump
    /// them): masses add, inertias combine by the parallel-axis theorem, collision and visual
    /// shapes are gathered at their poses in the parent frame, and each lumped link is kept as
    /// a [`FrameModel`]. Links on fixed joints may be massless (sensor and footprint frames);
    /// a link that moves (on a continuous, revolute or prismatic joint, or the root) needs a
    /// mass once its fixed children are added.
    pub fn parse_with_env(
        text: &str,
        path: &Path,
        packages: &PackagePath,
        env: &dyn Fn(&str) -> Option<String>,
    ) -> Result<Self, UrdfError> {
        let fail = |message: String| UrdfError { file: path.to_path_buf(), message };
        let (text, substitutions) = crate::xacro::substitute(text, env).map_err(fail)?;
        let robot = urdf_rs::read_from_string(&text).map_err(|e| fail(format!("not a valid URDF: {e}")))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut unsupported = Vec::new();
        let raw = read_links(&robot.links, dir, packages, &fail, &mut unsupported)?;
        if raw.is_empty() {
            return Err(fail("the robot has no links".into()));
        }
        let (all_joints, has_parent) = read_joints(&robot.joints, &raw, &fail, &mut unsupported)?;
        let roots: Vec<usize> = (0..raw.len()).filter(|&i| !has_parent[i]).collect();
        let root = match roots.as_slice() {
            [r] => *r,
            [r, ..] if !unsupported.is_empty() => *r,
            _ => {
                let names: Vec<&str> = roots.iter().map(|&i| raw[i].name.as_str()).collect();
                return Err(fail(format!(
                    "the links form {} trees (roots {names:?}); a robot has one root",
                    roots.len()
                )));
            }
        };
        let Lumped { links, frames, joints, root } = lump(&raw, all_joints, root, &fail)?;
        Ok(Self { name: robot.name, path: path.to_path_buf(), links, joints, frames, root, unsupported, substitutions })
    }

    /// Where a URDF link is, lumped or not: the index of the link (in [`UrdfModel::links`]) it
    /// is part of and its frame's pose in that link's frame.
    pub fn locate(&self, name: &str) -> Option<(usize, Pose)> {
        self.link(name)
            .map(|l| (l, Pose::default()))
            .or_else(|| self.frames.iter().find(|f| f.name == name).map(|f| (f.link, f.pose)))
    }

    /// Index of a link by name.
    pub fn link(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// World pose of every link frame with all joints at zero and the root at `base`.
    pub fn link_poses(&self, base: &Pose) -> Vec<Pose> {
        let mut poses: Vec<Option<Pose>> = vec![None; self.links.len()];
        poses[self.root] = Some(*base);
        // Parents come first in any order of the joint list after enough passes.
        for _ in 0..self.links.len() {
            for j in &self.joints {
                if let (Some(p), None) = (poses[j.parent], poses[j.child]) {
                    poses[j.child] = Some(p.compose(&j.origin));
                }
            }
        }
        // Links left unattached by an unsupported joint sit at the base.
        poses.into_iter().map(|p| p.unwrap_or(*base)).collect()
    }

    /// The wheel links: children of continuous joints whose collision geometry is a cylinder or
    /// a mesh.
    pub fn wheel_links(&self) -> Vec<usize> {
        self.joints
            .iter()
            .filter(|j| j.kind == JointType::Continuous)
            .map(|j| j.child)
            .filter(|&c| {
                self.links[c]
                    .collision
                    .iter()
                    .any(|(_, s)| matches!(s, ShapeDesc::Cylinder { .. } | ShapeDesc::Mesh { .. }))
            })
            .collect()
    }

    /// Total mass (kg).
    pub fn mass(&self) -> f64 {
        self.links.iter().map(|l| l.mass).sum()
    }
}

/// The links of a URDF with their mass and shapes in the link frame. A visual mesh that is
/// not there leaves its links drawn without it (one line in `unsupported` per URI); a missing
/// collision mesh is an error.
fn read_links(
    links: &[urdf_rs::Link],
    dir: &Path,
    packages: &PackagePath,
    fail: &dyn Fn(String) -> UrdfError,
    unsupported: &mut Vec<String>,
) -> Result<Vec<RawLink>, UrdfError> {
    let mut raw: Vec<RawLink> = Vec::with_capacity(links.len());
    let mut missing_visual: Vec<(String, String, Vec<String>)> = Vec::new();
    for l in links {
        if raw.iter().any(|x| x.name == l.name) {
            return Err(fail(format!("link `{}` is defined twice", l.name)));
        }
        let m = l.inertial.mass.value;
        if !(m >= 0.0 && m.is_finite()) {
            return Err(fail(format!("link `{}`: <mass> must be finite and ≥ 0 kg (got {m})", l.name)));
        }
        let i = &l.inertial.inertia;
        let at = pose(&l.inertial.origin);
        let inertia = rotate_inertia(&at, [i.ixx, i.iyy, i.izz, i.ixy, i.ixz, i.iyz]);
        if m > 0.0 && inertia[..3].iter().any(|v| v.is_nan() || *v <= 0.0) {
            return Err(fail(format!(
                "link `{}`: inertia must have ixx, iyy, izz > 0 (got {:?})",
                l.name,
                [i.ixx, i.iyy, i.izz]
            )));
        }
        let mut collision = Vec::new();
        for c in &l.collision {
            collision.extend(geometry(
                &l.name,
                "collision",
                &c.origin,
                &c.geometry,
                dir,
                packages,
                fail,
                &mut missing_visual,
            )?);
        }
        let mut visual = Vec::new();
        for v in &l.visual {
            visual.extend(geometry(
                &l.name,
                "visual",
                &v.origin,
                &v.geometry,
                dir,
                packages,
                fail,
                &mut missing_visual,
            )?);
        }
        let mass = MassProperties { mass: m, com: at.translation, inertia };
        raw.push(RawLink { name: l.name.clone(), mass, collision, visual });
    }
    for (_, m, links) in missing_visual {
        let s = if links.len() > 1 { "s" } else { "" };
        unsupported.push(format!("visual {m}; link{s} `{}` drawn without it", links.join("`, `")));
    }
    Ok(raw)
}

/// One collision or visual element of `link` in the link frame: sizes and mesh scales finite
/// and positive (non-zero for a scale), origins finite, so that a NaN radius never reaches
/// the marker generator. `None` for a visual mesh that is not there (noted in `missing_visual`).
#[allow(clippy::too_many_arguments)]
fn geometry(
    link: &str,
    what: &str,
    origin: &urdf_rs::Pose,
    g: &urdf_rs::Geometry,
    dir: &Path,
    packages: &PackagePath,
    fail: &dyn Fn(String) -> UrdfError,
    missing_visual: &mut Vec<(String, String, Vec<String>)>,
) -> Result<Option<(Pose, ShapeDesc)>, UrdfError> {
    let (sizes, scale): (Vec<f64>, Vec<f64>) = match g {
        urdf_rs::Geometry::Box { size } => (size.0.to_vec(), Vec::new()),
        urdf_rs::Geometry::Cylinder { radius, length } | urdf_rs::Geometry::Capsule { radius, length } => {
            (vec![*radius, *length], Vec::new())
        }
        urdf_rs::Geometry::Sphere { radius } => (vec![*radius], Vec::new()),
        urdf_rs::Geometry::Mesh { scale, .. } => (Vec::new(), scale.as_ref().map_or_else(Vec::new, |s| s.0.to_vec())),
    };
    if sizes.iter().any(|d| !(d.is_finite() && *d > 0.0)) || scale.iter().any(|d| !(d.is_finite() && *d != 0.0)) {
        return Err(fail(format!(
            "link `{}` ({what}): geometry sizes must be finite and > 0 m, mesh scales finite and non-zero (got {:?})",
            link,
            if sizes.is_empty() { scale } else { sizes }
        )));
    }
    if origin.xyz.0.iter().chain(&origin.rpy.0).any(|v| !v.is_finite()) {
        return Err(fail(format!("link `{}` ({what}): <origin> xyz and rpy must be finite", link)));
    }
    let at = pose(origin);
    let shape = match g {
        urdf_rs::Geometry::Box { size } => ShapeDesc::Box { size: size.0 },
        urdf_rs::Geometry::Cylinder { radius, length } => {
            ShapeDesc::Cylinder { radius: *radius, length: *length, axis: Axis::Z }
        }
        urdf_rs::Geometry::Sphere { radius } => ShapeDesc::Sphere { radius: *radius },
        urdf_rs::Geometry::Capsule { radius, length } => ShapeDesc::Compound(vec![
            (Pose::default(), ShapeDesc::Cylinder { radius: *radius, length: *length, axis: Axis::Z }),
            (Pose::translation([0.0, 0.0, 0.5 * length]), ShapeDesc::Sphere { radius: *radius }),
            (Pose::translation([0.0, 0.0, -0.5 * length]), ShapeDesc::Sphere { radius: *radius }),
        ]),
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let file = match resolve_uri(filename, dir, packages) {
                Ok(f) => f,
                Err(m) if what == "visual" => {
                    match missing_visual.iter_mut().find(|(uri, _, _)| uri == filename) {
                        Some((_, _, links)) => links.push(link.to_string()),
                        None => missing_visual.push((filename.clone(), m, vec![link.to_string()])),
                    }
                    return Ok(None);
                }
                Err(m) => return Err(fail(format!("link `{}` ({what}): {m}", link))),
            };
            let scale = scale.as_ref().map_or([1.0; 3], |s| s.0);
            let mesh = load_mesh(&file, scale).map_err(|e| fail(format!("link `{}` ({what}): {e}", link)))?;
            ShapeDesc::Mesh { vertices: mesh.vertices, indices: mesh.indices }
        }
    };
    Ok(Some((at, shape)))
}

/// Every honoured joint in URDF link indices, fixed ones included, and which links have a
/// parent. An unsupported joint leaves its child unattached (a line in `unsupported`).
fn read_joints(
    joints: &[urdf_rs::Joint],
    raw: &[RawLink],
    fail: &dyn Fn(String) -> UrdfError,
    unsupported: &mut Vec<String>,
) -> Result<(Vec<JointModel>, Vec<bool>), UrdfError> {
    let index = |name: &str, joint: &str, role: &str| {
        raw.iter()
            .position(|l| l.name == name)
            .ok_or_else(|| fail(format!("joint `{joint}`: {role} link `{name}` is not defined")))
    };
    let mut all_joints = Vec::new();
    let mut has_parent = vec![false; raw.len()];
    for j in joints {
        let parent = index(&j.parent.link, &j.name, "parent")?;
        let child = index(&j.child.link, &j.name, "child")?;
        if has_parent[child] {
            return Err(fail(format!("joint `{}`: link `{}` already has a parent joint", j.name, j.child.link)));
        }
        has_parent[child] = true;
        let a = j.axis.xyz.0;
        let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let limits = |kind: &str| {
            let (lo, hi) = (j.limit.lower, j.limit.upper);
            if lo <= hi {
                Ok((lo, hi))
            } else {
                Err(fail(format!("joint `{}` ({kind}): lower limit {lo} > upper {hi}", j.name)))
            }
        };
        let kind = match j.joint_type {
            urdf_rs::JointType::Fixed => JointType::Fixed,
            urdf_rs::JointType::Continuous => JointType::Continuous,
            urdf_rs::JointType::Revolute => {
                let (lower, upper) = limits("revolute")?;
                JointType::Revolute { lower, upper }
            }
            urdf_rs::JointType::Prismatic => {
                let (lower, upper) = limits("prismatic")?;
                JointType::Prismatic { lower, upper }
            }
            ref other => {
                let what = format!("{other:?}").to_lowercase();
                unsupported.push(format!(
                    "joint `{}`: {what} joints are not supported; link `{}` is left unattached",
                    j.name, j.child.link
                ));
                continue;
            }
        };
        if kind != JointType::Fixed && !(n > 0.0 && n.is_finite()) {
            return Err(fail(format!("joint `{}`: axis {a:?} has zero length", j.name)));
        }
        if j.joint_type == urdf_rs::JointType::Fixed {
            // A fixed joint's axis means nothing; its origin must still be finite.
            if j.origin.xyz.0.iter().chain(&j.origin.rpy.0).any(|v| !v.is_finite()) {
                return Err(fail(format!("joint `{}`: <origin> xyz and rpy must be finite", j.name)));
            }
        }
        if j.mimic.is_some() {
            unsupported.push(format!("joint `{}`: <mimic> is not supported; the joint moves on its own", j.name));
        }
        all_joints.push(JointModel {
            name: j.name.clone(),
            kind,
            parent,
            child,
            origin: pose(&j.origin),
            axis: if n > 0.0 { a.map(|x| x / n) } else { [1.0, 0.0, 0.0] },
            effort: if j.limit.effort.is_finite() { j.limit.effort } else { 0.0 },
        });
    }
    Ok((all_joints, has_parent))
}

/// The links lumped along fixed joints: one body per moving link, the lumped ones as frames.
struct Lumped {
    links: Vec<LinkModel>,
    frames: Vec<FrameModel>,
    joints: Vec<JointModel>,
    root: usize,
}

/// Lumps each link into its body, the nearest ancestor (itself included) that does not hang
/// on a fixed joint: masses combine, shapes are placed in the body's frame, and each moving
/// joint's frame is given in its parent body's frame.
fn lump(
    raw: &[RawLink],
    all_joints: Vec<JointModel>,
    root: usize,
    fail: &dyn Fn(String) -> UrdfError,
) -> Result<Lumped, UrdfError> {
    // Lumping: each link's body (the nearest ancestor, itself included, that does not hang
    // on a fixed joint) and its pose in that body's frame.
    let fixed_parent: Vec<Option<&JointModel>> =
        (0..raw.len()).map(|c| all_joints.iter().find(|j| j.child == c && j.kind == JointType::Fixed)).collect();
    let mut body_of = Vec::with_capacity(raw.len());
    for l in 0..raw.len() {
        let (mut at, mut cur, mut steps) = (Pose::default(), l, 0);
        while let Some(j) = fixed_parent[cur] {
            at = j.origin.compose(&at);
            cur = j.parent;
            steps += 1;
            if steps > raw.len() {
                return Err(fail(format!("link `{}`: its fixed joints form a loop", raw[l].name)));
            }
        }
        body_of.push((cur, at));
    }
    let bodies: Vec<usize> = (0..raw.len()).filter(|&l| body_of[l].0 == l).collect();
    let new_index = |raw_link: usize| bodies.iter().position(|&b| b == body_of[raw_link].0).unwrap_or(0);
    let mut links = Vec::with_capacity(bodies.len());
    for &b in &bodies {
        let parts: Vec<usize> = (0..raw.len()).filter(|&l| body_of[l].0 == b).collect();
        let mass = combine_mass(&parts.iter().map(|&l| (body_of[l].1, raw[l].mass)).collect::<Vec<_>>());
        if mass.mass <= 0.0 {
            let how = match all_joints.iter().find(|j| j.child == b) {
                Some(j) => format!("moves on joint `{}` ({})", j.name, j.kind.describe()),
                None if b == root => "is the root, which moves freely".to_string(),
                None => "is left unattached by an unsupported joint".to_string(),
            };
            let lumped: Vec<&str> = parts.iter().filter(|&&l| l != b).map(|&l| raw[l].name.as_str()).collect();
            let with = if lumped.is_empty() {
                String::new()
            } else {
                format!(" (nor do the links fixed to it: {})", lumped.join(", "))
            };
            return Err(fail(format!(
                "link `{}` has no <inertial> or a zero mass{with} but {how}: a moving link needs a mass (kg) \
                 and an inertia (kg m²); only links on fixed joints may be massless",
                raw[b].name
            )));
        }
        let place = |l: usize, shapes: &[(Pose, ShapeDesc)]| {
            shapes.iter().map(|(at, s)| (body_of[l].1.compose(at), s.clone())).collect::<Vec<_>>()
        };
        links.push(LinkModel {
            name: raw[b].name.clone(),
            mass: mass.mass,
            com: mass.com,
            inertia: mass.inertia,
            collision: parts.iter().flat_map(|&l| place(l, &raw[l].collision)).collect(),
            visual: parts.iter().flat_map(|&l| place(l, &raw[l].visual)).collect(),
        });
    }
    let frames = all_joints
        .iter()
        .filter(|j| j.kind == JointType::Fixed)
        .map(|j| FrameModel {
            name: raw[j.child].name.clone(),
            joint: j.name.clone(),
            link: new_index(j.child),
            pose: body_of[j.child].1,
        })
        .collect();
    // The moving joints between bodies: a joint's frame in its parent body's frame.
    let joints = all_joints
        .into_iter()
        .filter(|j| j.kind != JointType::Fixed)
        .map(|j| JointModel {
            origin: body_of[j.parent].1.compose(&j.origin),
            parent: new_index(j.parent),
            child: new_index(j.child),
            ..j
        })
        .collect();
    Ok(Lumped { links, frames, joints, root: new_index(root) })
}

/// One shape from a list of posed shapes: the shape itself when there is one at the identity
/// pose, a compound otherwise (`None` when empty).
pub fn combine(parts: &[(Pose, ShapeDesc)]) -> Option<ShapeDesc> {
    match parts {
        [] => None,
        [(p, s)] if *p == Pose::default() => Some(s.clone()),
        _ => Some(ShapeDesc::Compound(parts.to_vec())),
    }
}
