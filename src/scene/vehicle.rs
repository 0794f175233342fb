//! `[[vehicles]]`: URDF vehicles placed on the terrain and driven.
//!
//! ```toml
//! [[vehicles]]
//! name = "rover"
//! urdf = "../rover_description/urdf/rover.urdf"
//! package_path = [".."]            # roots for package:// (then $REGOLITH_PACKAGE_PATH, $ROS_PACKAGE_PATH)
//! position = [0.3, 0.3]            # x, y; the wheels are set just above the soil. [x, y, z] fixes the root's z
//! orientation = [0.0, 0.0, 0.0]    # roll, pitch, yaw (deg)
//! fsi_links = ["wheel_fl", ...]    # default: the wheel links; a link on a fixed joint selects its parent
//! grousers = { count = 12, height = 0.01, thickness = 0.004 }   # added to cylinder wheels
//! drive = { wheel_speed = 2.0, max_torque = 10.0 }              # rad/s, forward positive
//! # or  drive = { left = 2.0, right = -2.0, max_torque = 10.0 }   (skid steering)
//! # or  drive = { joints = { wheel_fl_joint = 2.0 }, max_torque = 10.0 }
//! # any speed may be a profile [[t, value], ...] (piecewise linear, held after the last point);
//! # steering = { steer_fl_joint = 15.0 } drives revolute (or non-wheel continuous) joints to an angle (deg).
//! differential = { left = "left_rocker_joint", right = "right_rocker_joint" }
//! self_collide = false             # default: a robot's links do not collide with one another
//! ```
//!
//! `differential` couples two rocker joints on the same parent link the way a rocker-bogie
//! rover's differential bar does: the rockers turn by equal and opposite angles relative to the
//! body, so the body's pitch is the mean of theirs. URDF has no closed loops to say so (a
//! Curio or Sawppy describes its bar only for Gazebo, or not at all); without it the body pivots
//! freely on the rocker axles.
//!
//! "Forward" for a wheel speed means the wheel rolls the vehicle along the root link's +x,
//! whatever the sign of the URDF joint axis.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use regolith_fsi::config::WallContact;
use regolith_rigid::{BodyDesc, Grousers, MassSpec, Motion, Pose, ShapeDesc};
use regolith_vehicles::{JointType, PackagePath, UrdfModel, combine, wheel_shape};
use serde::Deserialize;

use super::BodySpec;
use crate::input::InputError;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct VehicleFile {
    pub name: Option<String>,
    pub urdf: Option<String>,
    pub position: Option<Vec<f64>>,
    pub orientation: Option<[f64; 3]>,
    pub package_path: Option<Vec<String>>,
    pub fsi_links: Option<Vec<String>>,
    pub grousers: Option<GrouserFile>,
    pub friction: Option<f64>,
    pub bce_layers: Option<i64>,
    pub drive: Option<DriveFile>,
    pub differential: Option<DifferentialFile>,
    pub self_collide: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DifferentialFile {
    pub left: String,
    pub right: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct GrouserFile {
    pub count: u32,
    pub height: f64,
    pub thickness: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DriveFile {
    pub wheel_speed: Option<ProfileFile>,
    pub left: Option<ProfileFile>,
    pub right: Option<ProfileFile>,
    pub joints: Option<BTreeMap<String, ProfileFile>>,
    pub max_torque: Option<f64>,
    pub steering: Option<BTreeMap<String, ProfileFile>>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub(crate) enum ProfileFile {
    Constant(f64),
    Points(Vec<[f64; 2]>),
}

/// A value over time: piecewise linear through `(t, value)` points, held outside them.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile(Vec<(f64, f64)>);

impl Profile {
    /// A profile through `points` (time s, value): at least one, finite, times increasing.
    pub fn new(points: Vec<(f64, f64)>) -> Result<Self, String> {
        let finite = points.iter().all(|(t, v)| t.is_finite() && v.is_finite());
        if points.is_empty() || !finite || points.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err("must be a number or a list of [time s, value] pairs with increasing times".into());
        }
        Ok(Self(points))
    }

    /// The same value at all times.
    pub fn constant(value: f64) -> Result<Self, String> {
        Self::new(vec![(0.0, value)])
    }

    /// Its (time s, value) points.
    pub fn points(&self) -> &[(f64, f64)] {
        &self.0
    }

    /// The value at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        let p = &self.0;
        if t <= p[0].0 {
            return p[0].1;
        }
        for w in p.windows(2) {
            if t <= w[1].0 {
                let s = (t - w[0].0) / (w[1].0 - w[0].0);
                return w[0].1 + s * (w[1].1 - w[0].1);
            }
        }
        p[p.len() - 1].1
    }
}

/// A driven wheel: its joint, the sign that makes a positive speed roll forward, and its radius.
#[derive(Clone, Debug, PartialEq)]
pub struct WheelSpec {
    /// The wheel link (index into the model's links).
    pub link: usize,
    /// Its joint (index into the model's joints).
    pub joint: usize,
    /// +1 when rotation about the joint axis by a positive angle rolls the vehicle forward.
    pub forward_sign: f64,
    /// Rolling radius (m): the rim radius of a cylinder wheel.
    pub radius: f64,
    /// +1 on the left (root +y side), −1 on the right.
    pub side: f64,
}

/// A resolved `[[vehicles]]` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleSpec {
    /// Name; its links are the bodies `<name>/<link>`.
    pub name: String,
    /// `vehicles[i]`.
    pub key: String,
    /// The imported URDF.
    pub model: UrdfModel,
    /// Index of its first link body in [`super::Scene::bodies`] (links follow in model order).
    pub first_body: usize,
    /// Whether the simulation lowers it onto the soil (no z given).
    pub place_on_soil: bool,
    /// Wheels (children of continuous joints with a cylinder or mesh collision).
    pub wheels: Vec<WheelSpec>,
    /// Speed profile (rad/s, forward positive) per driven wheel joint (model joint index).
    pub drive: Vec<(usize, Profile)>,
    /// Motor torque limit (N m).
    pub max_torque: f64,
    /// Angle profile (rad) per steering joint.
    pub steering: Vec<(usize, Profile)>,
    /// A differential between two rocker joints (`differential`).
    pub differential: Option<Differential>,
    /// Whether its links collide with one another (`self_collide`, default false: as in Gazebo,
    /// PyBullet and Isaac, a URDF's link shapes may overlap near their joints).
    pub self_collide: bool,
}

/// Two revolute joints on one parent link held to equal and opposite angles (a rocker-bogie's
/// differential): `θ_left + sign θ_right = 0`, `sign` being +1 when their axes point the same
/// way and −1 when opposite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Differential {
    /// The left rocker's joint (index into the model's joints).
    pub left: usize,
    /// The right rocker's joint.
    pub right: usize,
    /// +1 for parallel axes, −1 for opposite ones.
    pub sign: f64,
}

impl VehicleSpec {
    /// Body index (into the scene's bodies) of a link.
    pub fn body(&self, link: usize) -> usize {
        self.first_body + link
    }
}

fn profile(v: &ProfileFile, scale: f64) -> Result<Profile, String> {
    match v {
        ProfileFile::Constant(c) if c.is_finite() => Profile::constant(c * scale),
        ProfileFile::Constant(c) => Err(format!("must be finite (got {c})")),
        ProfileFile::Points(p) => Profile::new(p.iter().map(|[t, v]| (*t, v * scale)).collect()),
    }
}

/// Resolves `vehicles[i]`, appending its link bodies to `bodies`.
pub(crate) fn resolve_vehicle(
    scene_path: &Path,
    i: usize,
    v: &VehicleFile,
    default_layers: usize,
    bodies: &mut Vec<BodySpec>,
    err: &dyn Fn(&str, String) -> InputError,
) -> Result<VehicleSpec, InputError> {
    let key = format!("vehicles[{i}]");
    let e = |k: &str, m: String| err(&format!("{key}.{k}"), m);
    let dir = scene_path.parent().unwrap_or(Path::new("."));
    let name = v.name.clone().ok_or_else(|| e("name", "is required: links become bodies `<name>/<link>`".into()))?;
    if name.trim().is_empty() || name.contains('/') {
        return Err(e("name", format!("must be non-empty and contain no `/` (got \"{name}\")")));
    }
    let urdf = v.urdf.as_ref().ok_or_else(|| e("urdf", "is required: the URDF file, relative to the scene".into()))?;
    let roots: Vec<PathBuf> = v.package_path.iter().flatten().map(|p| dir.join(p)).collect();
    let urdf_path = dir.join(urdf);
    let model = UrdfModel::load(&urdf_path, &PackagePath::with_env(&roots))
        .map_err(|u| InputError::file(&u.file, format!("{} (from {key}.urdf)", u.message)))?;
    let (xy, z) = match v.position.as_deref() {
        Some([x, y]) => ([*x, *y], None),
        Some([x, y, z]) => ([*x, *y], Some(*z)),
        _ => {
            return Err(e(
                "position",
                "is required: [x, y] (placed on the soil) or [x, y, z] of the root link (m)".into(),
            ));
        }
    };
    if xy.iter().chain(&z).any(|c| !c.is_finite()) {
        return Err(e("position", "must be finite".into()));
    }
    let orientation = v.orientation.unwrap_or([0.0; 3]);
    if orientation.iter().any(|a| !a.is_finite()) {
        return Err(e("orientation", "must be finite roll, pitch, yaw in degrees".into()));
    }
    let friction = v.friction.unwrap_or(0.8);
    if !(friction.is_finite() && friction >= 0.0) {
        return Err(e("friction", format!("must be ≥ 0 (got {friction})")));
    }
    let layers = v.bce_layers.unwrap_or(default_layers as i64);
    if !(1..=8).contains(&layers) {
        return Err(e("bce_layers", format!("must be an integer in 1..=8 (got {layers})")));
    }
    let grousers = match &v.grousers {
        None => None,
        Some(g) => {
            if g.count == 0
                || !(g.height > 0.0 && g.height.is_finite())
                || !(g.thickness > 0.0 && g.thickness.is_finite())
            {
                return Err(e("grousers", "needs count ≥ 1, height > 0 and thickness > 0 (m)".into()));
            }
            Some(Grousers { count: g.count, height: g.height, thickness: g.thickness })
        }
    };
    let wheel_links = model.wheel_links();
    let fsi = match v.fsi_links.as_deref() {
        None => wheel_links.clone(),
        Some(list) => fsi_links(&model, list, &urdf_path, &e)?,
    };
    let base = Pose::from_rpy_deg([xy[0], xy[1], z.unwrap_or(0.0)], orientation);
    let first_body = bodies.len();
    let links = Links {
        name: &name,
        key: &key,
        wheel_links: &wheel_links,
        fsi: &fsi,
        grousers,
        friction,
        layers: layers as usize,
    };
    let wheels = link_bodies(&model, &base, &links, bodies);
    for b in &bodies[first_body..] {
        check_fsi_meshes(b, &e)?;
    }
    let joint_names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    let find_joint = |k: &str, n: &str| {
        model.joints.iter().position(|j| j.name == n).ok_or_else(|| match model.frames.iter().find(|f| f.joint == n) {
            Some(f) => e(
                k,
                format!(
                    "joint `{n}` is fixed: link `{}` is lumped into `{}`; moving joints: {joint_names:?}",
                    f.name, model.links[f.link].name
                ),
            ),
            None => e(k, format!("no joint `{n}`; joints: {joint_names:?}")),
        })
    };
    let Drives { drive, steering, max_torque } = match &v.drive {
        None => Drives::default(),
        Some(d) => resolve_drive(&model, d, &wheels, &find_joint, &e)?,
    };
    if drive.is_empty() && v.drive.as_ref().is_some_and(|d| d.wheel_speed.is_some() || d.left.is_some()) {
        return Err(e(
            "drive",
            format!(
                "{} has no wheel joints (continuous joints with a cylinder or mesh collision)",
                urdf_path.display()
            ),
        ));
    }
    let differential = match &v.differential {
        None => None,
        Some(d) => Some(differential(&model, d, &find_joint, &e)?),
    };
    if let Some(d) = &differential {
        for (side, ji) in [("left", d.left), ("right", d.right)] {
            let name = &model.joints[ji].name;
            if wheels.iter().any(|w| w.joint == ji) {
                return Err(e(
                    &format!("differential.{side}"),
                    format!("joint `{name}` is a wheel joint, not a rocker"),
                ));
            }
            if steering.iter().any(|(s, _)| *s == ji) {
                return Err(e(
                    &format!("differential.{side}"),
                    format!("joint `{name}` is also in drive.steering: a rocker is moved by the differential only"),
                ));
            }
        }
    }
    Ok(VehicleSpec {
        name,
        key,
        model,
        first_body,
        place_on_soil: z.is_none(),
        wheels,
        drive,
        max_torque,
        steering,
        differential,
        self_collide: v.self_collide.unwrap_or(false),
    })
}

/// The links `fsi_links` names (without it, the wheel links get markers). A link lumped into
/// its parent by a fixed joint selects that parent; each needs collision geometry.
fn fsi_links(
    model: &UrdfModel,
    list: &[String],
    urdf_path: &Path,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Vec<usize>, InputError> {
    let names: Vec<&str> =
        model.links.iter().map(|l| l.name.as_str()).chain(model.frames.iter().map(|f| f.name.as_str())).collect();
    list.iter()
        .map(|n| {
            let (l, _) = model
                .locate(n)
                .ok_or_else(|| e("fsi_links", format!("no link `{n}` in {}; links: {names:?}", urdf_path.display())))?;
            if model.links[l].collision.is_empty() {
                return Err(e("fsi_links", format!("link `{n}` has no collision geometry to make markers from")));
            }
            Ok(l)
        })
        .collect()
}

/// What every link body of one vehicle shares.
struct Links<'a> {
    name: &'a str,
    key: &'a str,
    /// Links on a continuous joint whose collision is a wheel ([`UrdfModel::wheel_links`]).
    wheel_links: &'a [usize],
    fsi: &'a [usize],
    grousers: Option<Grousers>,
    friction: f64,
    layers: usize,
}

/// Appends one body per link, posed from the root at `base`, and returns the wheels: links
/// on a continuous joint whose collision is a wheel (an FSI wheel takes that shape, grousers
/// included).
fn link_bodies(model: &UrdfModel, base: &Pose, l: &Links, bodies: &mut Vec<BodySpec>) -> Vec<WheelSpec> {
    let poses = model.link_poses(base);
    let base_inv_rot = [-base.rotation[0], -base.rotation[1], -base.rotation[2], base.rotation[3]];
    let mut wheels = Vec::new();
    for (li, link) in model.links.iter().enumerate() {
        let joint = model.joints.iter().position(|j| j.child == li);
        let is_wheel = l.wheel_links.contains(&li);
        let mut shape = combine(&link.collision);
        if is_wheel && let Some(ji) = joint {
            let j = &model.joints[ji];
            // The axle in the link frame is the joint axis (the joint frame is the link frame).
            if let Some((s, radius)) = wheel_shape(link, j.axis, l.grousers) {
                let axle_root = regolith_rigid::quat_rotate(base_inv_rot, poses[li].rotate(j.axis));
                let centre_root = regolith_rigid::quat_rotate(
                    base_inv_rot,
                    [0, 1, 2].map(|k| poses[li].translation[k] - base.translation[k]),
                );
                wheels.push(WheelSpec {
                    link: li,
                    joint: ji,
                    forward_sign: if axle_root[1] >= 0.0 { 1.0 } else { -1.0 },
                    radius,
                    side: if centre_root[1] >= 0.0 { 1.0 } else { -1.0 },
                });
                if l.fsi.contains(&li) {
                    shape = Some(s);
                }
            }
        }
        bodies.push(BodySpec {
            desc: BodyDesc {
                name: format!("{}/{}", l.name, link.name),
                shape: shape.unwrap_or(ShapeDesc::Compound(Vec::new())),
                mass: MassSpec::Inertial { mass: link.mass, com: link.com, inertia: link.inertia },
                pose: poses[li],
                motion: Motion::Free,
                friction: l.friction,
                collides: !link.collision.is_empty(),
            },
            fsi: l.fsi.contains(&li),
            bce_layers: l.layers,
            key: format!("{} link `{}`", l.key, link.name),
            visual: combine(&link.visual),
            initial_velocity: None,
            active_margin: None,
            contact: WallContact::Rough,
            permeable: false,
        });
    }
    wheels
}

/// An FSI link's collision meshes must be closed: markers fill the inside.
fn check_fsi_meshes(b: &BodySpec, e: &dyn Fn(&str, String) -> InputError) -> Result<(), InputError> {
    if b.fsi
        && let ShapeDesc::Compound(parts) = &b.desc.shape
    {
        for (_, s) in parts {
            if let ShapeDesc::Mesh { vertices, indices } = s {
                regolith_coupling::check_watertight(vertices, indices)
                    .map_err(|m| e("fsi_links", format!("{}: collision mesh {m}", b.desc.name)))?;
            }
        }
    }
    Ok(())
}

/// The resolved `drive`: wheel and joint speed profiles, steering angle profiles, and the
/// motors' torque limit.
#[derive(Default)]
struct Drives {
    drive: Vec<(usize, Profile)>,
    steering: Vec<(usize, Profile)>,
    max_torque: f64,
}

/// `drive`: one of `wheel_speed`, `left`/`right` or `joints`, optional `steering`, and
/// `max_torque`.
fn resolve_drive(
    model: &UrdfModel,
    d: &DriveFile,
    wheels: &[WheelSpec],
    find_joint: &dyn Fn(&str, &str) -> Result<usize, InputError>,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Drives, InputError> {
    let mut drive = Vec::new();
    let mut steering = Vec::new();
    let given = [d.wheel_speed.is_some(), d.left.is_some() || d.right.is_some(), d.joints.is_some()];
    if given.iter().filter(|g| **g).count() > 1 {
        return Err(e("drive", "give one of wheel_speed, left/right or joints".into()));
    }
    if d.left.is_some() != d.right.is_some() {
        return Err(e("drive", "skid steering needs both left and right".into()));
    }
    let p = |k: &str, x: &ProfileFile, scale: f64| profile(x, scale).map_err(|m| e(&format!("drive.{k}"), m));
    if let Some(s) = &d.wheel_speed {
        let prof = p("wheel_speed", s, 1.0)?;
        drive.extend(wheels.iter().map(|w| (w.joint, prof.clone())));
    }
    if let (Some(l), Some(r)) = (&d.left, &d.right) {
        let (pl, pr) = (p("left", l, 1.0)?, p("right", r, 1.0)?);
        drive.extend(wheels.iter().map(|w| (w.joint, if w.side > 0.0 { pl.clone() } else { pr.clone() })));
    }
    for (n, x) in d.joints.iter().flatten() {
        let ji = find_joint("drive.joints", n)?;
        if !wheels.iter().any(|w| w.joint == ji) {
            return Err(e(
                "drive.joints",
                format!("joint `{n}` is not a wheel joint (continuous, with a cylinder or mesh wheel)"),
            ));
        }
        drive.push((ji, p(&format!("joints.{n}"), x, 1.0)?));
    }
    for (n, x) in d.steering.iter().flatten() {
        let ji = find_joint("drive.steering", n)?;
        // Continuous joints steer too (a Sawppy's corner joints are continuous), but not wheels.
        let steerable = match model.joints[ji].kind {
            JointType::Revolute { .. } => true,
            JointType::Continuous => !wheels.iter().any(|w| w.joint == ji),
            _ => false,
        };
        if !steerable {
            return Err(e("drive.steering", format!("joint `{n}` is not a revolute (or continuous, non-wheel) joint")));
        }
        steering.push((ji, p(&format!("steering.{n}"), x, std::f64::consts::PI / 180.0)?));
    }
    if drive.is_empty() && steering.is_empty() {
        return Err(e("drive", "drives nothing: give wheel_speed, left and right, joints or steering".into()));
    }
    if !wheels.is_empty() && drive.is_empty() && d.wheel_speed.is_some() {
        return Err(e("drive.wheel_speed", "the vehicle has no wheel joints".into()));
    }
    let max_torque =
        d.max_torque.ok_or_else(|| e("drive.max_torque", "is required: the motors' torque limit (N m)".into()))?;
    if !(max_torque > 0.0 && max_torque.is_finite()) {
        return Err(e("drive.max_torque", format!("must be > 0 N m (got {max_torque})")));
    }
    Ok(Drives { drive, steering, max_torque })
}

/// Resolves `differential`: two distinct revolute or continuous joints with the same parent
/// link and parallel (or opposite) axes.
fn differential(
    model: &UrdfModel,
    d: &DifferentialFile,
    find_joint: &dyn Fn(&str, &str) -> Result<usize, InputError>,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Differential, InputError> {
    let (left, right) = (find_joint("differential.left", &d.left)?, find_joint("differential.right", &d.right)?);
    if left == right {
        return Err(e("differential", format!("left and right are the same joint `{}`", d.left)));
    }
    for (side, ji) in [("left", left), ("right", right)] {
        let j = &model.joints[ji];
        if !matches!(j.kind, JointType::Revolute { .. } | JointType::Continuous) {
            return Err(e(
                &format!("differential.{side}"),
                format!("joint `{}` is not revolute or continuous", j.name),
            ));
        }
    }
    let (jl, jr) = (&model.joints[left], &model.joints[right]);
    if jl.parent != jr.parent {
        return Err(e(
            "differential",
            format!(
                "`{}` and `{}` must hang from the same link (the body the bar pivots on); their parents are `{}` and `{}`",
                jl.name, jr.name, model.links[jl.parent].name, model.links[jr.parent].name
            ),
        ));
    }
    // Both axes in the parent's frame.
    let (al, ar) = (jl.origin.rotate(jl.axis), jr.origin.rotate(jr.axis));
    let n = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let cos = (al[0] * ar[0] + al[1] * ar[1] + al[2] * ar[2]) / (n(al) * n(ar));
    if cos.abs() < 0.999 {
        return Err(e(
            "differential",
            format!(
                "the axes of `{}` and `{}` must be parallel or opposite (they are {:.1}° apart)",
                jl.name,
                jr.name,
                cos.clamp(-1.0, 1.0).acos().to_degrees()
            ),
        ));
    }
    Ok(Differential { left, right, sign: cos.signum() })
}
