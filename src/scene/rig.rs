//! `[rig]`: the plate, cone and wheel test rigs.

use super::*;

pub(super) fn resolve_rig(
    path: &Path,
    source: &str,
    r: &RigFile,
    bodies: &[BodySpec],
    files: &[BodyFile],
    gravity: [f64; 3],
) -> Result<RigSpec, InputError> {
    let e = |k: &str, msg: String| key_err(path, source, format!("rig.{k}"), msg);
    let kind = r.kind.ok_or_else(|| e("type", "is required: \"plate\", \"cone\" or \"wheel\"".into()))?;
    let kind_name = match kind {
        RigKind::Plate => "plate",
        RigKind::Cone => "cone",
        RigKind::Wheel => "wheel",
    };
    let name = r
        .body
        .as_ref()
        .ok_or_else(|| e("body", "is required: the name of the [[bodies]] entry the rig drives".into()))?;
    let body = bodies
        .iter()
        .position(|b| &b.desc.name == name)
        .ok_or_else(|| e("body", format!("\"{name}\" is not a body of the scene")))?;
    if !bodies[body].fsi {
        return Err(e("body", format!("\"{name}\" has fsi = false: a rig measures the soil's force on it")));
    }
    if files[body].motion.is_some() {
        return Err(key_err(
            path,
            source,
            format!("{}.motion", bodies[body].key),
            format!("is set, but the {kind_name} rig drives body \"{name}\"; remove it"),
        ));
    }
    let k = Keys { e: &e, kind: kind_name };
    let shape = &bodies[body].desc.shape;
    match kind {
        RigKind::Plate => plate_rig(r, &k, name, body, shape),
        RigKind::Cone => cone_rig(r, &k, name, body, shape),
        RigKind::Wheel => wheel_rig(r, &k, name, body, shape, gravity),
    }
}

/// The rig's key errors, which name its kind.
struct Keys<'a> {
    e: &'a dyn Fn(&str, String) -> InputError,
    kind: &'a str,
}

impl Keys<'_> {
    /// An error if a key that does not apply to this rig is given.
    fn forbid(&self, k: &str, present: bool) -> Result<(), InputError> {
        if present { Err((self.e)(k, format!("does not apply to a {} rig", self.kind))) } else { Ok(()) }
    }

    /// A required value > 0 in `unit`.
    fn positive(&self, k: &str, v: Option<f64>, unit: &str) -> Result<f64, InputError> {
        let v = v.ok_or_else(|| (self.e)(k, format!("is required for a {} rig ({unit})", self.kind)))?;
        if v.is_finite() && v > 0.0 { Ok(v) } else { Err((self.e)(k, format!("must be > 0 {unit} (got {v})"))) }
    }
}

/// A plate (a z-axis cylinder or a box) pushed at a speed or under a load to a depth.
fn plate_rig(r: &RigFile, k: &Keys, name: &str, body: usize, shape: &ShapeDesc) -> Result<RigSpec, InputError> {
    k.forbid("angular_velocity", r.angular_velocity.is_some())?;
    k.forbid("slips", r.slips.is_some())?;
    k.forbid("tow_force", r.tow_force.is_some())?;
    k.forbid("slopes", r.slopes.is_some())?;
    k.forbid("slip_radius", r.slip_radius.is_some())?;
    match shape {
        ShapeDesc::Cylinder { axis: Axis::Z, .. } | ShapeDesc::Box { .. } => {}
        _ => {
            return Err((k.e)(
                "body",
                format!("\"{name}\" must be a plate: a cylinder with axis = \"z\" (circular) or a box (rectangular)"),
            ));
        }
    }
    let control = match (r.speed, r.load) {
        (Some(_), Some(_)) => {
            return Err((k.e)("speed", "and load are both given: a plate is speed- or load-controlled".into()));
        }
        (None, None) => return Err((k.e)("speed", "is required (m/s, downward), or give load (N)".into())),
        (Some(_), None) => PlateControl::Speed(k.positive("speed", r.speed, "m/s")?),
        (None, Some(_)) => PlateControl::Load(k.positive("load", r.load, "N")?),
    };
    let depth = k.positive("depth", r.depth, "m")?;
    let sizes = r.sizes.clone().unwrap_or_default();
    if let Some(s) = sizes.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
        return Err((k.e)("sizes", format!("must all be > 0 m (got {s})")));
    }
    Ok(RigSpec::Plate { body, control, depth, sizes })
}

/// A cone pushed at a speed to a depth.
fn cone_rig(r: &RigFile, k: &Keys, name: &str, body: usize, shape: &ShapeDesc) -> Result<RigSpec, InputError> {
    for (key, p) in [
        ("load", r.load.is_some()),
        ("sizes", r.sizes.is_some()),
        ("angular_velocity", r.angular_velocity.is_some()),
        ("slips", r.slips.is_some()),
        ("tow_force", r.tow_force.is_some()),
        ("slopes", r.slopes.is_some()),
        ("slip_radius", r.slip_radius.is_some()),
    ] {
        k.forbid(key, p)?;
    }
    if !matches!(shape, ShapeDesc::Cone { .. }) {
        return Err((k.e)("body", format!("\"{name}\" must have shape type = \"cone\"")));
    }
    Ok(RigSpec::Cone { body, speed: k.positive("speed", r.speed, "m/s")?, depth: k.positive("depth", r.depth, "m")? })
}

/// A wheel (or a y-axis cylinder) on a carriage, under a load, spun at an angular velocity.
fn wheel_rig(
    r: &RigFile,
    k: &Keys,
    name: &str,
    body: usize,
    shape: &ShapeDesc,
    gravity: [f64; 3],
) -> Result<RigSpec, InputError> {
    for (key, p) in [("speed", r.speed.is_some()), ("depth", r.depth.is_some()), ("sizes", r.sizes.is_some())] {
        k.forbid(key, p)?;
    }
    match shape {
        ShapeDesc::Wheel { .. } | ShapeDesc::Cylinder { axis: Axis::Y, .. } => {}
        _ => {
            return Err((k.e)(
                "body",
                format!("\"{name}\" must be a wheel: shape type = \"wheel\" (or a cylinder with axis = \"y\")"),
            ));
        }
    }
    let given = [("slips", r.slips.is_some()), ("tow_force", r.tow_force.is_some()), ("slopes", r.slopes.is_some())];
    let named: Vec<&str> = given.iter().filter(|g| g.1).map(|g| g.0).collect();
    if named.len() > 1 {
        return Err((k.e)(
            named[0],
            format!(
                "and {} are both given: prescribe slips, tow the carriage, or drive up slopes",
                named[1..].join(" and ")
            ),
        ));
    }
    let drive = wheel_drive(r, k, gravity)?;
    Ok(RigSpec::Wheel {
        body,
        load: k.positive("load", r.load, "N")?,
        angular_velocity: k.positive("angular_velocity", r.angular_velocity, "rad/s")?,
        drive,
        slip_radius: match r.slip_radius {
            None => None,
            Some(_) => Some(k.positive("slip_radius", r.slip_radius, "m")?),
        },
    })
}

/// The wheel's drive: prescribed slips, a tow force on the carriage, or slopes to climb
/// (one of the three).
fn wheel_drive(r: &RigFile, k: &Keys, gravity: [f64; 3]) -> Result<WheelDrive, InputError> {
    Ok(match (&r.slips, r.tow_force, &r.slopes) {
        (Some(s), _, _) => {
            if s.is_empty() {
                return Err((k.e)("slips", "must list at least one slip ratio".into()));
            }
            if let Some(x) = s.iter().find(|x| !(x.is_finite() && (0.0..=1.0).contains(*x))) {
                return Err((k.e)("slips", format!("must be in [0, 1] (got {x})")));
            }
            WheelDrive::Slips(s.clone())
        }
        (None, Some(t), _) => {
            if !(t.is_finite() && t >= 0.0) {
                return Err((k.e)("tow_force", format!("must be ≥ 0 N (got {t})")));
            }
            WheelDrive::Tow(t)
        }
        (None, None, Some(s)) => {
            if s.is_empty() {
                return Err((k.e)("slopes", "must list at least one slope angle (degrees)".into()));
            }
            if let Some(x) = s.iter().find(|x| !(x.is_finite() && (0.0..60.0).contains(*x))) {
                return Err((k.e)("slopes", format!("must be in [0, 60) degrees (got {x})")));
            }
            if gravity[0] != 0.0 || gravity[1] != 0.0 || gravity[2] >= 0.0 {
                return Err((k.e)(
                    "slopes",
                    format!(
                        "tilt simulation.gravity themselves: give gravity along −z (got {gravity:?}) and the rig tilts it per slope"
                    ),
                ));
            }
            WheelDrive::Slopes(s.clone())
        }
        (None, None, None) => {
            return Err((k.e)(
                "slips",
                "is required (a list of slip ratios in [0, 1]), or give tow_force (N) or slopes (degrees)".into(),
            ));
        }
    })
}
