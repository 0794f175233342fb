//! URDF import: links with their inertials and geometry, joints, mesh files resolved from
//! `package://`, `file://` and relative URIs.

use std::path::{Path, PathBuf};

use regolith_rigid::{Axis, Pose, ShapeDesc, load_mesh};

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
    /// Links.
    pub links: Vec<LinkModel>,
    /// Joints the importer honours.
    pub joints: Vec<JointModel>,
    /// The root link (no parent joint).
    pub root: usize,
    /// Joints and features it could not honour, one line each (`joint "x": planar joints are
    /// not supported; the child link moves freely`), for the caller to report once.
    pub unsupported: Vec<String>,
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

/// `R I Rᵀ` for a symmetric tensor given as `[ixx, iyy, izz, ixy, ixz, iyz]`.
fn rotate_inertia(rot: &Pose, i: [f64; 6]) -> [f64; 6] {
    let [xx, yy, zz, xy, xz, yz] = i;
    let m = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
    let cols = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| rot.rotate(e));
    // r[a][b] = R_ab: column b of R is the image of e_b.
    let r = |a: usize, b: usize| cols[b][a];
    let mut out = [[0.0; 3]; 3];
    for (a, row) in out.iter_mut().enumerate() {
        for (b, o) in row.iter_mut().enumerate() {
            *o = m
                .iter()
                .enumerate()
                .flat_map(|(k, mk)| mk.iter().enumerate().map(move |(l, mkl)| (k, l, *mkl)))
                .map(|(k, l, mkl)| r(a, k) * mkl * r(b, l))
                .sum();
        }
    }
    [out[0][0], out[1][1], out[2][2], out[0][1], out[0][2], out[1][2]]
}

impl UrdfModel {
    /// Reads a URDF file; meshes are loaded (and scaled) now, so every missing file is found at
    /// load time.
    pub fn load(path: &Path, packages: &PackagePath) -> Result<Self, UrdfError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| UrdfError { file: path.to_path_buf(), message: format!("cannot read: {e}") })?;
        Self::parse(&text, path, packages)
    }

    /// Parses URDF text; `path` names it in errors and anchors relative mesh paths.
    pub fn parse(text: &str, path: &Path, packages: &PackagePath) -> Result<Self, UrdfError> {
        let fail = |message: String| UrdfError { file: path.to_path_buf(), message };
        let robot = urdf_rs::read_from_string(text).map_err(|e| fail(format!("not a valid URDF: {e}")))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut links = Vec::with_capacity(robot.links.len());
        let mut unsupported = Vec::new();
        for l in &robot.links {
            if links.iter().any(|x: &LinkModel| x.name == l.name) {
                return Err(fail(format!("link `{}` is defined twice", l.name)));
            }
            let m = l.inertial.mass.value;
            if !(m > 0.0 && m.is_finite()) {
                return Err(fail(format!(
                    "link `{}` has no <inertial> or a zero mass: every link needs a mass (kg) and an inertia (kg m²)",
                    l.name
                )));
            }
            let i = &l.inertial.inertia;
            let at = pose(&l.inertial.origin);
            let inertia = rotate_inertia(&at, [i.ixx, i.iyy, i.izz, i.ixy, i.ixz, i.iyz]);
            if inertia[..3].iter().any(|v| v.is_nan() || *v <= 0.0) {
                return Err(fail(format!(
                    "link `{}`: inertia must have ixx, iyy, izz > 0 (got {:?})",
                    l.name,
                    [i.ixx, i.iyy, i.izz]
                )));
            }
            let geometry = |what: &str,
                            origin: &urdf_rs::Pose,
                            g: &urdf_rs::Geometry|
             -> Result<(Pose, ShapeDesc), UrdfError> {
                // Sizes and mesh scales finite and positive (non-zero for a scale), origins
                // finite: a NaN radius would otherwise reach the marker generator.
                let (sizes, scale): (Vec<f64>, Vec<f64>) = match g {
                    urdf_rs::Geometry::Box { size } => (size.0.to_vec(), Vec::new()),
                    urdf_rs::Geometry::Cylinder { radius, length } | urdf_rs::Geometry::Capsule { radius, length } => {
                        (vec![*radius, *length], Vec::new())
                    }
                    urdf_rs::Geometry::Sphere { radius } => (vec![*radius], Vec::new()),
                    urdf_rs::Geometry::Mesh { scale, .. } => {
                        (Vec::new(), scale.as_ref().map_or_else(Vec::new, |s| s.0.to_vec()))
                    }
                };
                if sizes.iter().any(|d| !(d.is_finite() && *d > 0.0))
                    || scale.iter().any(|d| !(d.is_finite() && *d != 0.0))
                {
                    return Err(fail(format!(
                        "link `{}` ({what}): geometry sizes must be finite and > 0 m, mesh scales finite and non-zero (got {:?})",
                        l.name,
                        if sizes.is_empty() { scale } else { sizes }
                    )));
                }
                if origin.xyz.0.iter().chain(&origin.rpy.0).any(|v| !v.is_finite()) {
                    return Err(fail(format!("link `{}` ({what}): <origin> xyz and rpy must be finite", l.name)));
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
                        let file = resolve_uri(filename, dir, packages)
                            .map_err(|m| fail(format!("link `{}` ({what}): {m}", l.name)))?;
                        let scale = scale.as_ref().map_or([1.0; 3], |s| s.0);
                        let mesh =
                            load_mesh(&file, scale).map_err(|e| fail(format!("link `{}` ({what}): {e}", l.name)))?;
                        ShapeDesc::Mesh { vertices: mesh.vertices, indices: mesh.indices }
                    }
                };
                Ok((at, shape))
            };
            let collision =
                l.collision.iter().map(|c| geometry("collision", &c.origin, &c.geometry)).collect::<Result<_, _>>()?;
            let visual =
                l.visual.iter().map(|v| geometry("visual", &v.origin, &v.geometry)).collect::<Result<_, _>>()?;
            links.push(LinkModel { name: l.name.clone(), mass: m, com: at.translation, inertia, collision, visual });
        }
        if links.is_empty() {
            return Err(fail("the robot has no links".into()));
        }
        let index = |name: &str, joint: &str, role: &str| {
            links
                .iter()
                .position(|l| l.name == name)
                .ok_or_else(|| fail(format!("joint `{joint}`: {role} link `{name}` is not defined")))
        };
        let mut joints = Vec::new();
        let mut has_parent = vec![false; links.len()];
        for j in &robot.joints {
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
            if j.mimic.is_some() {
                unsupported.push(format!("joint `{}`: <mimic> is not supported; the joint moves on its own", j.name));
            }
            joints.push(JointModel {
                name: j.name.clone(),
                kind,
                parent,
                child,
                origin: pose(&j.origin),
                axis: if n > 0.0 { a.map(|x| x / n) } else { [1.0, 0.0, 0.0] },
                effort: if j.limit.effort.is_finite() { j.limit.effort } else { 0.0 },
            });
        }
        let roots: Vec<usize> = (0..links.len()).filter(|&i| !has_parent[i]).collect();
        let root = match roots.as_slice() {
            [r] => *r,
            _ if !unsupported.is_empty() => roots[0],
            _ => {
                let names: Vec<&str> = roots.iter().map(|&i| links[i].name.as_str()).collect();
                return Err(fail(format!(
                    "the links form {} trees (roots {names:?}); a robot has one root",
                    roots.len()
                )));
            }
        };
        Ok(Self { name: robot.name, path: path.to_path_buf(), links, joints, root, unsupported })
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

/// One shape from a list of posed shapes: the shape itself when there is one at the identity
/// pose, a compound otherwise (`None` when empty).
pub fn combine(parts: &[(Pose, ShapeDesc)]) -> Option<ShapeDesc> {
    match parts {
        [] => None,
        [(p, s)] if *p == Pose::default() => Some(s.clone()),
        _ => Some(ShapeDesc::Compound(parts.to_vec())),
    }
}
