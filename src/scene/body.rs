//! `[[bodies]]`: rigid bodies, their shapes, mass, pose, motion and markers.

use super::*;

pub(super) fn resolve_body(
    path: &Path,
    source: &str,
    dir: &Path,
    i: usize,
    b: &BodyFile,
    default_layers: usize,
    earlier: &[BodySpec],
) -> Result<BodySpec, InputError> {
    let key = format!("bodies[{i}]");
    let e = |k: &str, msg: String| key_err(path, source, format!("{key}.{k}"), msg);
    let name = b.name.clone().ok_or_else(|| e("name", "is required: the body's name in outputs".into()))?;
    if name.trim().is_empty() || name.contains(',') || name.contains('/') {
        return Err(e("name", format!("\"{name}\" is not allowed: a non-empty name without ',' or '/'")));
    }
    if earlier.iter().any(|x| x.desc.name == name) {
        return Err(e("name", format!("\"{name}\" is used twice; body names must be unique")));
    }
    let shape_file = b.shape.clone().ok_or_else(|| {
        e(
            "shape",
            "is required: { type = \"box\" | \"sphere\" | \"cylinder\" | \"cone\" | \"mesh\" | \"wheel\", ... }".into(),
        )
    })?;
    let fsi = b.fsi.unwrap_or(true);
    let shape = body_shape(shape_file, dir, fsi, &e)?;
    let mass = match (b.mass, b.density) {
        (Some(_), Some(_)) => return Err(e("mass", "and density are both given: give one".into())),
        (None, None) => return Err(e("mass", "is required (kg), or give density (kg/m³)".into())),
        (Some(m), None) if m.is_finite() && m > 0.0 => MassSpec::Mass(m),
        (None, Some(d)) if d.is_finite() && d > 0.0 => MassSpec::Density(d),
        (Some(m), None) => return Err(e("mass", format!("must be > 0 kg (got {m})"))),
        (None, Some(d)) => return Err(e("density", format!("must be > 0 kg/m³ (got {d})"))),
    };
    let position =
        b.position.ok_or_else(|| e("position", "is required: [x, y, z] of the body's centre in m".into()))?;
    if position.iter().any(|x| !x.is_finite()) {
        return Err(e("position", "must be finite".into()));
    }
    let orientation = b.orientation.unwrap_or([0.0; 3]);
    if orientation.iter().any(|x| !x.is_finite()) {
        return Err(e("orientation", "must be finite roll, pitch, yaw in degrees".into()));
    }
    let (motion, initial_velocity) = body_motion(b.motion.clone(), &e)?;
    let Markers { layers, contact, permeable } = body_markers(b, fsi, default_layers, &e)?;
    let friction = b.friction.unwrap_or(0.5);
    if !(friction.is_finite() && friction >= 0.0) {
        return Err(e("friction", format!("must be ≥ 0 (got {friction})")));
    }
    Ok(BodySpec {
        desc: BodyDesc {
            name,
            shape,
            mass,
            pose: Pose::from_rpy_deg(position, orientation),
            motion,
            friction,
            collides: true,
        },
        fsi,
        bce_layers: layers,
        key,
        visual: None,
        initial_velocity,
        active_margin: b.active_margin,
        contact,
        permeable,
    })
}

/// `v` if it is a finite length > 0, else an error at `shape.{k}`.
fn positive(k: &str, v: f64, e: &dyn Fn(&str, String) -> InputError) -> Result<f64, InputError> {
    if v.is_finite() && v > 0.0 { Ok(v) } else { Err(e(&format!("shape.{k}"), format!("must be > 0 m (got {v})"))) }
}

/// `shape`: a primitive, a closed mesh read relative to the scene (closed only when the body
/// has markers), or a wheel.
fn body_shape(
    shape_file: ShapeFile,
    dir: &Path,
    fsi: bool,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<ShapeDesc, InputError> {
    let pos = |k: &str, v: f64| positive(k, v, e);
    Ok(match shape_file {
        ShapeFile::Box { size } => {
            for s in size {
                pos("size", s)?;
            }
            ShapeDesc::Box { size }
        }
        ShapeFile::Sphere { radius } => ShapeDesc::Sphere { radius: pos("radius", radius)? },
        ShapeFile::Cylinder { radius, length, axis } => ShapeDesc::Cylinder {
            radius: pos("radius", radius)?,
            length: pos("length", length)?,
            axis: match axis.unwrap_or(AxisName::Z) {
                AxisName::X => Axis::X,
                AxisName::Y => Axis::Y,
                AxisName::Z => Axis::Z,
            },
        },
        ShapeFile::Cone { radius, height } => {
            ShapeDesc::Cone { radius: pos("radius", radius)?, height: pos("height", height)? }
        }
        ShapeFile::Mesh { file, scale } => {
            let scale = match scale {
                None => [1.0; 3],
                Some(ScaleFile::Uniform(s)) => [s; 3],
                Some(ScaleFile::PerAxis(s)) => s,
            };
            if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
                return Err(e("shape.scale", format!("must be positive (got {scale:?})")));
            }
            let mesh =
                regolith_rigid::load_mesh(&dir.join(&file), scale).map_err(|m| e("shape.file", m.to_string()))?;
            if fsi {
                regolith_coupling::check_watertight(&mesh.vertices, &mesh.indices)
                    .map_err(|m| e("shape.file", format!("{}: {m}", dir.join(&file).display())))?;
            }
            ShapeDesc::Mesh { vertices: mesh.vertices, indices: mesh.indices }
        }
        ShapeFile::Wheel { radius, width, grousers, grouser_height, grouser_thickness } => {
            wheel_desc(radius, width, grousers, grouser_height, grouser_thickness, e)?
        }
    })
}

/// A wheel shape: radius and width, and grousers with a height and thickness when their
/// count is above 0 (and neither when it is 0).
fn wheel_desc(
    radius: f64,
    width: f64,
    grousers: Option<u32>,
    grouser_height: Option<f64>,
    grouser_thickness: Option<f64>,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<ShapeDesc, InputError> {
    let pos = |k: &str, v: f64| positive(k, v, e);
    let radius = pos("radius", radius)?;
    let width = pos("width", width)?;
    let grousers = match grousers.unwrap_or(0) {
        0 => {
            if grouser_height.is_some() || grouser_thickness.is_some() {
                return Err(e("shape.grousers", "is 0 but grouser_height or grouser_thickness is given".into()));
            }
            None
        }
        n => Some(Grousers {
            count: n,
            height: pos(
                "grouser_height",
                grouser_height.ok_or_else(|| e("shape.grouser_height", "is required when grousers > 0 (m)".into()))?,
            )?,
            thickness: pos(
                "grouser_thickness",
                grouser_thickness
                    .ok_or_else(|| e("shape.grouser_thickness", "is required when grousers > 0 (m)".into()))?,
            )?,
        }),
    };
    Ok(ShapeDesc::Wheel { radius, width, grousers })
}

/// `motion`: free (with an optional initial velocity, returned beside it), fixed, or
/// prescribed linear and angular (deg/s) velocities.
fn body_motion(
    motion: Option<MotionFile>,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<(Motion, Option<[f64; 3]>), InputError> {
    let mut initial_velocity = None;
    let motion = match motion.unwrap_or(MotionFile::Free { velocity: None }) {
        MotionFile::Free { velocity } => {
            if let Some(v) = velocity {
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(e("motion.velocity", "must be finite [vx, vy, vz] in m/s".into()));
                }
                initial_velocity = Some(v);
            }
            Motion::Free
        }
        MotionFile::Fixed => Motion::Fixed,
        MotionFile::Prescribed { linear_velocity, angular_velocity } => {
            let l = linear_velocity.unwrap_or([0.0; 3]);
            let a = angular_velocity.unwrap_or([0.0; 3]);
            if l.iter().chain(&a).any(|x| !x.is_finite()) {
                return Err(e("motion", "velocities must be finite".into()));
            }
            Motion::Prescribed { linvel: l, angvel: a.map(f64::to_radians) }
        }
    };
    Ok((motion, initial_velocity))
}

/// What a body's markers take: their layers, soil contact and permeability.
struct Markers {
    layers: usize,
    contact: WallContact,
    permeable: bool,
}

/// `bce_layers`, `active_margin`, `soil_contact` and `permeable`: each only on a body with
/// markers (`fsi = true`).
fn body_markers(
    b: &BodyFile,
    fsi: bool,
    default_layers: usize,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Markers, InputError> {
    let layers = b.bce_layers.unwrap_or(default_layers as i64);
    if !(1..=8).contains(&layers) {
        return Err(e("bce_layers", format!("must be an integer in 1..=8 (got {layers})")));
    }
    if !fsi && b.bce_layers.is_some() {
        return Err(e("bce_layers", "is set but fsi = false (the body has no markers)".into()));
    }
    if let Some(m) = b.active_margin {
        if !fsi {
            return Err(e("active_margin", "is set but fsi = false (only FSI bodies have active boxes)".into()));
        }
        if !(m.is_finite() && m >= 0.0) {
            return Err(e("active_margin", format!("must be >= 0 m (got {m})")));
        }
    }
    let contact = match &b.soil_contact {
        None => WallContact::Rough,
        Some(_) if !fsi => {
            return Err(e("soil_contact", "is set but fsi = false (the body does not touch the soil)".into()));
        }
        Some(v) => match contact::parse_contact(v).map_err(|m| e("soil_contact", m))? {
            WallContact::Rough => WallContact::Rough,
            _ => {
                return Err(e(
                    "soil_contact",
                    "bodies have rough soil contact only so far (smooth and frictional contact is for [container] walls); remove it or set \"rough\"".into(),
                ));
            }
        },
    };
    let permeable = b.permeable.unwrap_or(false);
    if permeable && !fsi {
        return Err(e("permeable", "is set but fsi = false (the body has no markers to let water through)".into()));
    }
    Ok(Markers { layers: layers as usize, contact, permeable })
}
