//! The test rigs: plate sinkage (bevameter), cone penetrometer and single-wheel rig. Each runs
//! one or more simulations of its scene, records `series.csv`, and reports its curves in
//! `summary.json` (under `rig`, and the Bekker fit under `bekker`).
//!
//! Every rig places its body vertically so that it starts in contact with the soil: its lowest
//! point one spacing above the top soil particle below it (the body's markers and the soil
//! particles then sit on one lattice spacing, the contact distance). Sinkage and depth are
//! measured from there.

pub mod bekker;

use regolith_fsi::Real;
use regolith_rigid::{BodyDesc, JointDesc, JointKind, MassSpec, Motion, Pose, ShapeDesc, VelocityMotor};
use serde::Serialize;

use crate::run::{RunError, Stepper};
use crate::scene::{PlateControl, RigSpec, Scene, WheelDrive};
use crate::series::Series;
use crate::sim::{Body, Simulation};
use bekker::{BekkerFit, PlateCurve};

/// Top of the soil (m) under a disc of radius `r` around `(x, y)`: the highest particle's
/// centre, from the scene's initial terrain.
pub fn soil_top(scene: &Scene, x: f64, y: f64, r: f64) -> Result<f64, RunError> {
    let (_, t) = crate::run::scene_terrain::<f64>(scene)?;
    t.particles
        .iter()
        .filter(|p| (p.pos[0] - x).powi(2) + (p.pos[1] - y).powi(2) <= r * r)
        .map(|p| p.pos[2])
        .reduce(f64::max)
        .ok_or_else(|| RunError::Build(format!("no soil under ({x}, {y}): place the rig body over the soil")))
}

/// Distance from a shape's origin down to its lowest point (m), upright.
fn bottom_offset(shape: &ShapeDesc) -> f64 {
    match shape {
        ShapeDesc::Box { size } => 0.5 * size[2],
        ShapeDesc::Sphere { radius } => *radius,
        ShapeDesc::Cylinder { radius, length, axis } => match axis {
            regolith_rigid::Axis::Z => 0.5 * length,
            _ => *radius,
        },
        ShapeDesc::Cone { height, .. } => 0.5 * height,
        ShapeDesc::Wheel { radius, grousers, .. } => radius + grousers.map_or(0.0, |g| g.height),
        ShapeDesc::Mesh { vertices, .. } => -vertices.iter().map(|v| v[2]).fold(f64::MAX, f64::min),
        ShapeDesc::Compound(_) => shape.bounding_radius(),
    }
}

fn footprint(shape: &ShapeDesc) -> f64 {
    match shape {
        ShapeDesc::Box { size } => 0.5 * size[0].min(size[1]),
        ShapeDesc::Cylinder { radius, .. } | ShapeDesc::Cone { radius, .. } => *radius,
        ShapeDesc::Wheel { width, .. } => 0.5 * width,
        s => s.bounding_radius(),
    }
}

/// Places body `i` so its lowest point is one spacing above the soil top; returns that height.
fn place_on_soil(scene: &mut Scene, i: usize) -> Result<f64, RunError> {
    let d0 = scene.solver.spacing;
    let b = &scene.bodies[i].desc;
    let [x, y, _] = b.pose.translation;
    let top = soil_top(scene, x, y, footprint(&b.shape).max(d0))?;
    let bottom = top + d0;
    let z = bottom + bottom_offset(&b.shape);
    scene.bodies[i].desc.pose.translation[2] = z;
    Ok(bottom)
}

/// What a rig run produced.
pub struct RigOutput<T: Real> {
    /// The series of all its runs.
    pub series: Series,
    /// Its report (`summary.json` → `rig`).
    pub report: serde_json::Value,
    /// The Bekker fit of a plate rig.
    pub bekker: Option<BekkerFit>,
    /// Plots to draw.
    pub figures: Vec<(String, crate::plot::Figure)>,
    /// The last simulation (for the final particles).
    pub last: Option<Simulation<T>>,
}

/// Runs a rig.
pub fn run_rig<T: Real>(scene: &Scene, rig: &RigSpec, stepper: &mut Stepper) -> Result<RigOutput<T>, RunError> {
    match rig {
        RigSpec::Plate { body, control, depth, sizes } => plate::<T>(scene, *body, *control, *depth, sizes, stepper),
        RigSpec::Cone { body, speed, depth } => cone::<T>(scene, *body, *speed, *depth, stepper),
        RigSpec::Wheel { body, load, angular_velocity, drive } => {
            wheel::<T>(scene, *body, *load, *angular_velocity, drive, stepper)
        }
    }
}

/// One plate's curve in the report.
#[derive(Clone, Debug, Serialize)]
struct PlateRun {
    /// Plate width b (m).
    b: f64,
    /// Plate area (m²).
    area: f64,
    /// Largest sinkage reached (m).
    max_sinkage: f64,
    /// Largest pressure (Pa).
    max_pressure: f64,
    /// (sinkage m, pressure Pa), every exchange.
    curve: Vec<(f64, f64)>,
}

fn plate<T: Real>(
    scene: &Scene,
    body: usize,
    control: PlateControl,
    depth: f64,
    sizes: &[f64],
    stepper: &mut Stepper,
) -> Result<RigOutput<T>, RunError> {
    let base = scene.bodies[body].desc.shape.clone();
    let sizes: Vec<Option<f64>> = if sizes.is_empty() { vec![None] } else { sizes.iter().map(|s| Some(*s)).collect() };
    let multi = sizes.len() > 1;
    let mut series: Option<Series> = None;
    let mut runs = Vec::new();
    let mut last: Option<Simulation<T>> = None;
    for size in sizes {
        let mut sc = scene.clone();
        let shape = match (&base, size) {
            (ShapeDesc::Cylinder { length, axis, radius }, s) => {
                ShapeDesc::Cylinder { radius: s.unwrap_or(*radius), length: *length, axis: *axis }
            }
            (ShapeDesc::Box { size: sz }, Some(s)) => {
                let k = s / sz[0].min(sz[1]);
                ShapeDesc::Box { size: [sz[0] * k, sz[1] * k, sz[2]] }
            }
            (other, _) => other.clone(),
        };
        let (b, area) = match &shape {
            ShapeDesc::Cylinder { radius, .. } => (*radius, std::f64::consts::PI * radius * radius),
            ShapeDesc::Box { size } => (size[0].min(size[1]), size[0] * size[1]),
            _ => return Err(RunError::Build("plate rig body must be a cylinder or a box".into())),
        };
        sc.bodies[body].desc.shape = shape;
        sc.bodies[body].desc.motion = match control {
            PlateControl::Speed(v) => Motion::Prescribed { linvel: [0.0, 0.0, -v], angvel: [0.0; 3] },
            PlateControl::Load(_) => Motion::Free,
        };
        let bottom0 = place_on_soil(&mut sc, body)?;
        let mut sim = Simulation::<T>::new(&sc)?;
        let id = sim.rigid_id(Body(body));
        if let PlateControl::Load(f) = control {
            sim.system.rigid.set_extra_force(id, [0.0, 0.0, -f]);
        }
        let offset = bottom_offset(&sc.bodies[body].desc.shape);
        let s = series.get_or_insert_with(|| Series::new(&sim, multi, &["sinkage", "pressure"]));
        s.push(&sim, multi.then_some(b), &[0.0, 0.0]);
        stepper.begin(&sim, multi.then_some(b))?;
        stepper.rig(&sim, "plate", &[("sinkage", 0.0), ("pressure", 0.0)])?;
        let mut curve = Vec::new();
        let (mut zmax, mut pmax) = (0.0_f64, 0.0_f64);
        while sim.time() < sc.end_time * (1.0 - 1e-12) {
            stepper.step(&mut sim)?;
            let st = sim.body_state(Body(body));
            let sinkage = bottom0 - (st.origin[2] - offset);
            let p = sim.fsi_wrench(Body(body)).force[2] / area;
            s.push(&sim, multi.then_some(b), &[sinkage, p]);
            stepper.rig(&sim, "plate", &[("sinkage", sinkage), ("pressure", p)])?;
            curve.push((sinkage, p));
            zmax = zmax.max(sinkage);
            pmax = pmax.max(p);
            if sinkage >= depth {
                break;
            }
        }
        runs.push(PlateRun { b, area, max_sinkage: zmax, max_pressure: pmax, curve });
        last = Some(sim);
    }
    let fit = bekker::fit(&runs.iter().map(|r| PlateCurve { b: r.b, points: r.curve.clone() }).collect::<Vec<_>>());
    let mut panel = crate::plot::Panel {
        title: "plate sinkage".into(),
        x_label: "sinkage z (mm)".into(),
        y_label: "pressure p (kPa)".into(),
        ..Default::default()
    };
    for r in &runs {
        panel.series.push(crate::plot::Series::line(
            format!("b = {} mm", r.b * 1e3),
            r.curve.iter().map(|(z, p)| (z * 1e3, p / 1e3)).collect(),
        ));
        if let Some(f) = &fit
            && let Some(k) = f.k_per_plate.iter().find(|(b, _)| (b - r.b).abs() < 1e-12).map(|(_, k)| *k)
        {
            panel.series.push(crate::plot::Series::line(
                format!("Bekker fit, b = {} mm", r.b * 1e3),
                (1..=50).map(|i| r.max_sinkage * i as f64 / 50.0).map(|z| (z * 1e3, k * z.powf(f.n) / 1e3)).collect(),
            ));
        }
    }
    let report = serde_json::json!({
        "type": "plate",
        "control": match control { PlateControl::Speed(v) => serde_json::json!({"speed": v}), PlateControl::Load(f) => serde_json::json!({"load": f}) },
        "runs": runs,
    });
    Ok(RigOutput {
        series: series.unwrap_or_default(),
        report,
        bekker: fit,
        figures: vec![("plate_sinkage".into(), crate::plot::Figure { panels: vec![panel] })],
        last,
    })
}

fn cone<T: Real>(
    scene: &Scene,
    body: usize,
    speed: f64,
    depth: f64,
    stepper: &mut Stepper,
) -> Result<RigOutput<T>, RunError> {
    let mut sc = scene.clone();
    let ShapeDesc::Cone { radius, height } = sc.bodies[body].desc.shape else {
        return Err(RunError::Build("cone rig body must be a cone".into()));
    };
    sc.bodies[body].desc.motion = Motion::Prescribed { linvel: [0.0, 0.0, -speed], angvel: [0.0; 3] };
    let tip0 = place_on_soil(&mut sc, body)?;
    // The soil surface: the tip starts one spacing above the top particle, whose cell ends
    // half a spacing above its centre.
    let surface = tip0 - 0.5 * sc.solver.spacing;
    let area = std::f64::consts::PI * radius * radius;
    let mut sim = Simulation::<T>::new(&sc)?;
    let mut series = Series::new(&sim, false, &["tip_depth", "base_depth", "cone_force", "cone_index"]);
    let row0 = [-0.5 * sc.solver.spacing, -(height + 0.5 * sc.solver.spacing), 0.0, 0.0];
    series.push(&sim, None, &row0);
    let names = ["tip_depth", "base_depth", "cone_force", "cone_index"];
    stepper.begin(&sim, None)?;
    stepper.rig(&sim, "cone", &[(names[0], row0[0]), (names[1], row0[1]), (names[2], 0.0), (names[3], 0.0)])?;
    let mut curve = Vec::new();
    while sim.time() < sc.end_time * (1.0 - 1e-12) {
        stepper.step(&mut sim)?;
        let st = sim.body_state(Body(body));
        let tip = st.origin[2] - 0.5 * height;
        let (tip_depth, base_depth) = (surface - tip, surface - (tip + height));
        let f = sim.fsi_wrench(Body(body)).force[2];
        series.push(&sim, None, &[tip_depth, base_depth, f, f / area]);
        let vals = [tip_depth, base_depth, f, f / area];
        stepper.rig(
            &sim,
            "cone",
            &[(names[0], vals[0]), (names[1], vals[1]), (names[2], vals[2]), (names[3], vals[3])],
        )?;
        curve.push((base_depth, f, f / area));
        if base_depth >= depth {
            break;
        }
    }
    let angle = 2.0 * (radius / height).atan().to_degrees();
    let report = serde_json::json!({
        "type": "cone",
        "apex_angle_deg": angle,
        "base_area_m2": area,
        "speed": speed,
        "max_force_n": curve.iter().map(|c| c.1).fold(0.0, f64::max),
        "final_base_depth_m": curve.last().map(|c| c.0),
        "final_cone_index_pa": curve.last().map(|c| c.2),
        "curve": curve.iter().map(|c| serde_json::json!({"base_depth": c.0, "force": c.1, "cone_index": c.2})).collect::<Vec<_>>(),
    });
    let force = crate::plot::Panel {
        title: format!("cone penetrometer ({angle:.0}°, {:.0} mm²)", area * 1e6),
        x_label: "base depth (mm)".into(),
        y_label: "force (N)".into(),
        series: vec![crate::plot::Series::line("force", curve.iter().map(|c| (c.0 * 1e3, c.1)).collect())],
        ..Default::default()
    };
    let ci = crate::plot::Panel {
        title: "cone index".into(),
        x_label: "base depth (mm)".into(),
        y_label: "cone index (kPa)".into(),
        series: vec![crate::plot::Series::line("cone index", curve.iter().map(|c| (c.0 * 1e3, c.2 / 1e3)).collect())],
        ..Default::default()
    };
    Ok(RigOutput {
        series,
        report,
        bekker: None,
        figures: vec![("cone_penetrometer".into(), crate::plot::Figure { panels: vec![force, ci] })],
        last: Some(sim),
    })
}

/// Steady-state means of one wheel run.
#[derive(Clone, Debug, Serialize)]
struct WheelRun {
    /// Prescribed slip (slip mode) or the measured mean slip (tow mode).
    slip: f64,
    /// Mean measured slip `1 − v / (ω R)` over the second half.
    measured_slip: f64,
    /// Mean drawbar pull: the soil's horizontal force on the wheel along travel (N).
    drawbar_pull: f64,
    /// Mean driving torque: minus the soil's torque about the axle (N m).
    torque: f64,
    /// Mean sinkage of the wheel centre from its start (m).
    sinkage: f64,
}

fn wheel<T: Real>(
    scene: &Scene,
    body: usize,
    load: f64,
    omega: f64,
    drive: &WheelDrive,
    stepper: &mut Stepper,
) -> Result<RigOutput<T>, RunError> {
    let g = -scene.solver.gravity[2];
    let radius = match scene.bodies[body].desc.shape {
        ShapeDesc::Wheel { radius, .. } | ShapeDesc::Cylinder { radius, .. } => radius,
        _ => return Err(RunError::Build("wheel rig body must be a wheel".into())),
    };
    let slips: Vec<Option<f64>> = match drive {
        WheelDrive::Slips(s) => s.iter().map(|x| Some(*x)).collect(),
        WheelDrive::Tow(_) => vec![None],
    };
    let multi = slips.len() > 1;
    let mut series: Option<Series> = None;
    let mut runs = Vec::new();
    let mut last: Option<Simulation<T>> = None;
    for slip in slips {
        let mut sc = scene.clone();
        sc.bodies[body].desc.motion = Motion::Free;
        place_on_soil(&mut sc, body)?;
        let centre = sc.bodies[body].desc.pose.translation;
        let wheel_mass = sc.bodies[body].desc.mass.mass_of(&sc.bodies[body].desc.shape);
        let mut sim = Simulation::<T>::new(&sc)?;
        let wheel_id = sim.rigid_id(Body(body));
        let v = slip.map_or(0.0, |s| omega * radius * (1.0 - s));
        let small = |name: &str, motion: Motion| BodyDesc {
            name: name.into(),
            shape: ShapeDesc::Box { size: [0.05, 0.05, 0.05] },
            mass: MassSpec::Mass(1.0),
            pose: Pose::translation(centre),
            motion,
            friction: 0.0,
            collides: false,
        };
        let rig_err = |e: regolith_rigid::RigidError| RunError::Build(e.to_string());
        let rigid = &mut sim.system.rigid;
        // sled (moves along x) —prismatic z→ carriage —revolute y→ wheel
        let sled = match drive {
            WheelDrive::Slips(_) => rigid
                .add_body(&small("rig sled", Motion::Prescribed { linvel: [v, 0.0, 0.0], angvel: [0.0; 3] }))
                .map_err(rig_err)?,
            WheelDrive::Tow(f) => {
                let rail = rigid.add_body(&small("rig rail", Motion::Fixed)).map_err(rig_err)?;
                let sled = rigid.add_body(&small("rig sled", Motion::Free)).map_err(rig_err)?;
                rigid
                    .add_joint(&JointDesc {
                        name: "rig rail".into(),
                        body1: rail,
                        body2: sled,
                        kind: JointKind::Prismatic,
                        anchor: centre,
                        axis: [1.0, 0.0, 0.0],
                        motor: None,
                    })
                    .map_err(rig_err)?;
                rigid.set_extra_force(sled, [-f, 0.0, 0.0]);
                sled
            }
        };
        let carriage = rigid.add_body(&small("rig carriage", Motion::Free)).map_err(rig_err)?;
        // The carriage carries the rest of the load: total vertical load on the soil = `load`.
        let extra = load - (wheel_mass + rigid.mass(carriage)) * g;
        rigid.set_extra_force(carriage, [0.0, 0.0, -extra]);
        rigid
            .add_joint(&JointDesc {
                name: "rig vertical".into(),
                body1: sled,
                body2: carriage,
                kind: JointKind::Prismatic,
                anchor: centre,
                axis: [0.0, 0.0, 1.0],
                motor: None,
            })
            .map_err(rig_err)?;
        rigid
            .add_joint(&JointDesc {
                name: "rig axle".into(),
                body1: carriage,
                body2: wheel_id,
                kind: JointKind::Revolute,
                anchor: centre,
                axis: [0.0, 1.0, 0.0],
                motor: Some(VelocityMotor { target: omega, max_effort: 1.0e5 }),
            })
            .map_err(rig_err)?;
        let label = slip.unwrap_or(f64::NAN);
        let s = series.get_or_insert_with(|| Series::new(&sim, multi, &["slip", "drawbar_pull", "torque", "sinkage"]));
        let mut rows: Vec<(f64, f64, f64, f64, f64)> = Vec::new();
        let names = ["slip", "drawbar_pull", "torque", "sinkage"];
        let record = |stepper: &mut Stepper, sim: &Simulation<T>, v: [f64; 4]| {
            stepper.rig(sim, "wheel", &[(names[0], v[0]), (names[1], v[1]), (names[2], v[2]), (names[3], v[3])])
        };
        stepper.begin(&sim, multi.then_some(label))?;
        record(stepper, &sim, [1.0, 0.0, 0.0, 0.0])?;
        while sim.time() < sc.end_time * (1.0 - 1e-12) {
            stepper.step(&mut sim)?;
            let st = sim.body_state(Body(body));
            let w = sim.fsi_wrench(Body(body));
            let measured = 1.0 - st.linvel[0] / (omega * radius);
            let (dbp, torque, sinkage) = (w.force[0], -w.torque[1], centre[2] - st.origin[2]);
            s.push(&sim, multi.then_some(label), &[measured, dbp, torque, sinkage]);
            record(stepper, &sim, [measured, dbp, torque, sinkage])?;
            rows.push((sim.time(), measured, dbp, torque, sinkage));
        }
        let half: Vec<_> = rows.iter().filter(|r| r.0 >= 0.5 * sc.end_time).collect();
        let n = half.len().max(1) as f64;
        let mean = |f: fn(&(f64, f64, f64, f64, f64)) -> f64| half.iter().map(|r| f(r)).sum::<f64>() / n;
        let measured = mean(|r| r.1);
        runs.push(WheelRun {
            slip: slip.unwrap_or(measured),
            measured_slip: measured,
            drawbar_pull: mean(|r| r.2),
            torque: mean(|r| r.3),
            sinkage: mean(|r| r.4),
        });
        last = Some(sim);
    }
    let mut figures = Vec::new();
    let s = series.clone().unwrap_or_default();
    let col = |name: &str| s.column(name);
    if let (Some(t), Some(d), Some(q), Some(z)) = (col("time"), col("drawbar_pull"), col("torque"), col("sinkage")) {
        let run_col = col("run");
        let mut panels = vec![
            crate::plot::Panel {
                title: "drawbar pull".into(),
                x_label: "time (s)".into(),
                y_label: "DBP (N)".into(),
                ..Default::default()
            },
            crate::plot::Panel {
                title: "driving torque".into(),
                x_label: "time (s)".into(),
                y_label: "torque (N m)".into(),
                ..Default::default()
            },
            crate::plot::Panel {
                title: "sinkage".into(),
                x_label: "time (s)".into(),
                y_label: "sinkage (mm)".into(),
                ..Default::default()
            },
        ];
        for r in &runs {
            let rows: Vec<&Vec<f64>> =
                s.rows.iter().filter(|row| run_col.is_none_or(|c| (row[c] - r.slip).abs() < 1e-12)).collect();
            let name = format!("s = {:.2}", r.slip);
            panels[0]
                .series
                .push(crate::plot::Series::line(name.clone(), rows.iter().map(|row| (row[t], row[d])).collect()));
            panels[1]
                .series
                .push(crate::plot::Series::line(name.clone(), rows.iter().map(|row| (row[t], row[q])).collect()));
            panels[2]
                .series
                .push(crate::plot::Series::line(name, rows.iter().map(|row| (row[t], row[z] * 1e3)).collect()));
        }
        figures.push(("wheel_time".into(), crate::plot::Figure { panels }));
    }
    if runs.len() > 1 {
        let dbp = crate::plot::Panel {
            title: "drawbar pull – slip".into(),
            x_label: "slip".into(),
            y_label: "drawbar pull (N)".into(),
            series: vec![crate::plot::Series::line("DBP", runs.iter().map(|r| (r.slip, r.drawbar_pull)).collect())],
            ..Default::default()
        };
        let tq = crate::plot::Panel {
            title: "torque – slip".into(),
            x_label: "slip".into(),
            y_label: "torque (N m)".into(),
            series: vec![crate::plot::Series::line("torque", runs.iter().map(|r| (r.slip, r.torque)).collect())],
            ..Default::default()
        };
        figures.push(("wheel_slip".into(), crate::plot::Figure { panels: vec![dbp, tq] }));
    }
    let report = serde_json::json!({
        "type": "wheel",
        "load_n": load,
        "angular_velocity": omega,
        "radius_m": radius,
        "drive": match drive { WheelDrive::Slips(_) => serde_json::json!("slip"), WheelDrive::Tow(f) => serde_json::json!({"tow_force": f}) },
        "steady_state": runs,
    });
    Ok(RigOutput { series: series.unwrap_or_default(), report, bekker: None, figures, last })
}
