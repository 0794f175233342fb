//! Single-wheel rig: a wheel on a motorised axle, its carriage driven at `v = ωR(1 − s)` for
//! each slip of a list, towed by a force, or left free on each slope of a list (gravity
//! tilted about y, the load carried along it); drawbar pull, torque, sinkage and slip.

use regolith_fsi::Real;
use regolith_rigid::{
    BodyDesc, BodyId, JointDesc, JointKind, MassSpec, Motion, Pose, RigidWorld, ShapeDesc, VelocityMotor,
};
use serde::Serialize;

use super::{RigOutput, halt, place_on_soil};
use crate::build::BuildError;
use crate::driver::{Driver, RunError};
use crate::output::Series;
use crate::output::plot::Figure;
use crate::scene::{Scene, WheelDrive};
use crate::sim::Simulation;

/// Steady-state means of one wheel run.
#[derive(Clone, Debug, Serialize)]
struct WheelRun {
    /// Prescribed slip (slip mode) or the measured mean slip (tow mode).
    slip: f64,
    /// Measured slip over the second half, `1 − v̄ / (ω̄ R)` from the carriage's mean speed
    /// and the wheel's mean measured spin (as Chrono's CRM study reads it).
    measured_slip: f64,
    /// Mean measured spin of the wheel about its axle over the second half (rad/s): the
    /// motor holds the commanded ω to within its compliance.
    spin: f64,
    /// Mean drawbar pull: the soil's horizontal force on the wheel along travel (N).
    drawbar_pull: f64,
    /// Mean driving torque: minus the soil's torque about the axle (N m).
    torque: f64,
    /// Mean sinkage of the wheel centre from its start (m).
    sinkage: f64,
    /// Slope (degrees; slope mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    slope_deg: Option<f64>,
    /// Standard deviation of the measured slip over the second half (free-carriage modes).
    #[serde(skip_serializing_if = "Option::is_none")]
    slip_std: Option<f64>,
    /// Weight of the load resolved along the slope, `load sin θ` (N; slope mode): in steady
    /// state the drawbar pull balances it.
    #[serde(skip_serializing_if = "Option::is_none")]
    downhill_load_n: Option<f64>,
    /// The run's label in the series (its slip, slope or NaN).
    #[serde(skip)]
    label: f64,
}

pub(super) fn wheel<T: Real>(
    scene: &Scene,
    body: usize,
    load: f64,
    omega: f64,
    drive: &WheelDrive,
    slip_radius: Option<f64>,
    driver: &mut Driver<'_, T>,
) -> Result<RigOutput<T>, RunError> {
    let g_norm = scene.solver.gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
    let rim = match scene.bodies[body].desc.shape {
        ShapeDesc::Wheel { radius, .. } | ShapeDesc::Cylinder { radius, .. } => radius,
        _ => return Err(BuildError::RigShape { rig: "wheel", allowed: "a wheel" }.into()),
    };
    // The radius of the slip's definition (and of v = ω r (1 − s) in slip mode).
    let radius = slip_radius.unwrap_or(rim);
    // (prescribed slip, slope in degrees) of each run.
    let cases: Vec<(Option<f64>, Option<f64>)> = match drive {
        WheelDrive::Slips(s) => s.iter().map(|x| (Some(*x), None)).collect(),
        WheelDrive::Tow(_) => vec![(None, None)],
        WheelDrive::Slopes(s) => s.iter().map(|x| (None, Some(*x))).collect(),
    };
    let multi = cases.len() > 1;
    let mut series: Option<Series> = None;
    let mut runs = Vec::new();
    let mut last: Option<Simulation<T>> = None;
    let mut stopped = None;
    for (slip, slope) in cases {
        let mut sc = scene.clone();
        sc.bodies[body].desc.motion = Motion::Free;
        if let Some(deg) = slope {
            // The slope rises along +x: gravity tilted about y, downhill along −x.
            let a = deg.to_radians();
            sc.solver.gravity = [-g_norm * a.sin(), 0.0, -g_norm * a.cos()];
        }
        let gravity = sc.solver.gravity;
        place_on_soil(&mut sc, body)?;
        let centre = sc.bodies[body].desc.pose.translation;
        let wheel_mass = sc.bodies[body].desc.mass.mass_of(&sc.bodies[body].desc.shape);
        let mut sim = Simulation::<T>::new(&sc)?;
        let wheel_id = sim.rigid_id(sim.body_at(body));
        let v = slip.map_or(0.0, |s| omega * radius * (1.0 - s));
        let mount = Mount { centre, sled_speed: v, slope: slope.is_some(), gravity, load, wheel_mass, omega };
        mount.build(&mut sim.system.rigid, wheel_id, drive)?;
        let label = slip.or(slope).unwrap_or(f64::NAN);
        let names = ["slip", "drawbar_pull", "torque", "sinkage", "omega"];
        let s = series.get_or_insert_with(|| Series::new(&sim, multi, &names));
        // (time, slip, DBP, torque, sinkage, carriage speed, spin) per exchange.
        let mut rows: Vec<[f64; 7]> = Vec::new();
        let record = |driver: &mut Driver<'_, T>, sim: &Simulation<T>, v: [f64; 5]| {
            let fields: Vec<(&str, f64)> = names.iter().copied().zip(v).collect();
            driver.publish(sim, "/rig/wheel", "regolith.Rig.wheel", &fields)
        };
        driver.begin(&sim, multi.then_some(label))?;
        record(driver, &sim, [1.0, 0.0, 0.0, 0.0, 0.0])?;
        while sim.time() < sc.end_time * (1.0 - 1e-12) {
            if let Err(e) = driver.step(&mut sim) {
                stopped = Some(halt(e)?);
                break;
            }
            let st = sim.body_state(sim.body_at(body));
            let w = sim.fsi_wrench(sim.body_at(body));
            // The wheel's own spin about the axle (y), as an encoder on the axle reads it; the
            // slip of each sample uses it (the commanded ω while the wheel is at rest).
            let spin = st.angvel[1];
            let turning = if spin.abs() > 1e-9 { spin } else { omega };
            let measured = 1.0 - st.linvel[0] / (turning * radius);
            let (dbp, torque, sinkage) = (w.force[0], -w.torque[1], centre[2] - st.origin[2]);
            s.push(&sim, multi.then_some(label), &[measured, dbp, torque, sinkage, spin]);
            record(driver, &sim, [measured, dbp, torque, sinkage, spin])?;
            rows.push([sim.time(), measured, dbp, torque, sinkage, st.linvel[0], spin]);
        }
        runs.push(WheelRun::steady(&rows, 0.5 * sc.end_time, radius, (slip, slope), load, label));
        last = Some(sim);
        if stopped.is_some() {
            break;
        }
    }
    let figures = figures(series.as_ref(), &runs, drive);
    let report = serde_json::json!({
        "type": "wheel",
        "load_n": load,
        "angular_velocity": omega,
        "radius_m": rim,
        "slip_radius_m": radius,
        "drive": match drive {
            WheelDrive::Slips(_) => serde_json::json!("slip"),
            WheelDrive::Tow(f) => serde_json::json!({"tow_force": f}),
            WheelDrive::Slopes(s) => serde_json::json!({"slopes_deg": s}),
        },
        "steady_state": runs,
    });
    Ok(RigOutput { series: series.unwrap_or_default(), report, bekker: None, figures, last, stopped })
}

/// How the wheel hangs: a sled along x (prescribed in slip mode, free on a fixed rail when
/// towed or on a slope), a carriage on a vertical slider from it carrying the load, and the
/// wheel on a motorised axle (y) from the carriage.
struct Mount {
    /// The wheel's centre at the start (m): the joints' anchor.
    centre: [f64; 3],
    /// The sled's speed along x in slip mode (m/s).
    sled_speed: f64,
    /// Slope mode: the load is a mass under the tilted gravity.
    slope: bool,
    /// Gravity of the run (m/s², tilted on a slope).
    gravity: [f64; 3],
    /// Vertical load on the soil (N), the wheel's weight included.
    load: f64,
    /// The wheel's own mass (kg).
    wheel_mass: f64,
    /// The axle motor's target spin (rad/s).
    omega: f64,
}

impl Mount {
    /// Adds the sled, the carriage and the joints to `rigid` and hangs `wheel` from them.
    fn build(&self, rigid: &mut RigidWorld, wheel: BodyId, drive: &WheelDrive) -> Result<(), RunError> {
        let centre = self.centre;
        let small = |name: &str, motion: Motion| BodyDesc {
            name: name.into(),
            shape: ShapeDesc::Box { size: [0.05, 0.05, 0.05] },
            mass: MassSpec::Mass(1.0),
            pose: Pose::translation(centre),
            motion,
            friction: 0.0,
            collides: false,
        };
        let rig_err = |source| RunError::Build(BuildError::Rigid { key: "rig".into(), source });
        // sled (moves along x) —prismatic z→ carriage —revolute y→ wheel
        let sled = match drive {
            WheelDrive::Slips(_) => rigid
                .add_body(&small(
                    "rig sled",
                    Motion::Prescribed { linvel: [self.sled_speed, 0.0, 0.0], angvel: [0.0; 3] },
                ))
                .map_err(rig_err)?,
            WheelDrive::Tow(_) | WheelDrive::Slopes(_) => {
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
                if let WheelDrive::Tow(f) = drive {
                    rigid.set_extra_force(sled, [-f, 0.0, 0.0]);
                }
                sled
            }
        };
        let carriage = rigid.add_body(&small("rig carriage", Motion::Free)).map_err(rig_err)?;
        // The sled and carriage only translate, as on a real rig's rails. Left free to turn,
        // the 1 kg carriage (4e-4 kg m²) is all the axle motor pushes against: rapier's
        // iterative solver then passes on a stall torque of only about 4 N m s × ω, and a
        // loaded wheel stops turning (the slip ≈ 1 of the GRC-1 study).
        rigid.lock_rotations(carriage);
        if !matches!(drive, WheelDrive::Slips(_)) {
            rigid.lock_rotations(sled);
        }
        if self.slope {
            // The load is a mass `load / |g|` under the tilted gravity: the carriage carries
            // what the wheel and carriage do not weigh (normal to the bed), and along the
            // slope what the wheel, carriage and sled do not (the sled rides the rail).
            let gravity = self.gravity;
            let m = self.load / gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
            let (mw, mc, ms) = (self.wheel_mass, rigid.mass(carriage), rigid.mass(sled));
            rigid.set_extra_force(carriage, [(m - mw - mc - ms) * gravity[0], 0.0, (m - mw - mc) * gravity[2]]);
        } else {
            // The carriage carries the rest of the load: total vertical load on the soil = `load`.
            let extra = self.load - (self.wheel_mass + rigid.mass(carriage)) * -self.gravity[2];
            rigid.set_extra_force(carriage, [0.0, 0.0, -extra]);
        }
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
                body2: wheel,
                kind: JointKind::Revolute,
                anchor: centre,
                axis: [0.0, 1.0, 0.0],
                motor: Some(VelocityMotor { target: self.omega, max_effort: 1.0e5 }),
            })
            .map_err(rig_err)?;
        Ok(())
    }
}

impl WheelRun {
    /// The means over the rows from `from` s on (time, slip, DBP, torque, sinkage, carriage
    /// speed, spin) of a run with this (prescribed slip, slope) under `load` N; slip is
    /// measured with the slip radius `radius`.
    fn steady(
        rows: &[[f64; 7]],
        from: f64,
        radius: f64,
        (slip, slope): (Option<f64>, Option<f64>),
        load: f64,
        label: f64,
    ) -> WheelRun {
        let half: Vec<_> = rows.iter().filter(|r| r[0] >= from).collect();
        let n = half.len().max(1) as f64;
        let mean = |k: usize| half.iter().map(|r| r[k]).sum::<f64>() / n;
        let spin = mean(6);
        let measured = if spin.abs() > 1e-9 { 1.0 - mean(5) / (spin * radius) } else { mean(1) };
        let spread = (half.iter().map(|r| (r[1] - measured).powi(2)).sum::<f64>() / n).sqrt();
        WheelRun {
            slip: slip.unwrap_or(measured),
            measured_slip: measured,
            spin,
            drawbar_pull: mean(2),
            torque: mean(3),
            sinkage: mean(4),
            slope_deg: slope,
            slip_std: slip.is_none().then_some(spread),
            downhill_load_n: slope.map(|d| load * d.to_radians().sin()),
            label,
        }
    }
}

/// The time series of every run (drawbar pull, torque, sinkage) and, with several runs, slip
/// against slope or drawbar pull and torque against slip.
fn figures(series: Option<&Series>, runs: &[WheelRun], drive: &WheelDrive) -> Vec<(String, Figure)> {
    let mut figures = Vec::new();
    let empty = Series::default();
    let s = series.unwrap_or(&empty);
    let col = |name: &str| s.column(name);
    if let (Some(t), Some(d), Some(q), Some(z)) = (col("time"), col("drawbar_pull"), col("torque"), col("sinkage")) {
        let run_col = col("run");
        let mut panels = vec![
            crate::output::plot::Panel {
                title: "drawbar pull".into(),
                x_label: "time (s)".into(),
                y_label: "DBP (N)".into(),
                ..Default::default()
            },
            crate::output::plot::Panel {
                title: "driving torque".into(),
                x_label: "time (s)".into(),
                y_label: "torque (N m)".into(),
                ..Default::default()
            },
            crate::output::plot::Panel {
                title: "sinkage".into(),
                x_label: "time (s)".into(),
                y_label: "sinkage (mm)".into(),
                ..Default::default()
            },
        ];
        for r in runs {
            let rows: Vec<&Vec<f64>> =
                s.rows.iter().filter(|row| run_col.is_none_or(|c| (row[c] - r.label).abs() < 1e-12)).collect();
            let name = match r.slope_deg {
                Some(d) => format!("{d}°"),
                None => format!("s = {:.2}", r.slip),
            };
            panels[0].series.push(crate::output::plot::Series::line(
                name.clone(),
                rows.iter().map(|row| (row[t], row[d])).collect(),
            ));
            panels[1].series.push(crate::output::plot::Series::line(
                name.clone(),
                rows.iter().map(|row| (row[t], row[q])).collect(),
            ));
            panels[2]
                .series
                .push(crate::output::plot::Series::line(name, rows.iter().map(|row| (row[t], row[z] * 1e3)).collect()));
        }
        figures.push(("wheel_time".into(), Figure { panels }));
    }
    if runs.len() > 1 && matches!(drive, WheelDrive::Slopes(_)) {
        let slip = crate::output::plot::Panel {
            title: "slip – slope".into(),
            x_label: "slope (°)".into(),
            y_label: "steady slip".into(),
            series: vec![crate::output::plot::Series::line(
                "slip (mean of the second half)",
                runs.iter().map(|r| (r.slope_deg.unwrap_or(f64::NAN), r.measured_slip)).collect(),
            )],
            ..Default::default()
        };
        figures.push(("wheel_slope".into(), Figure { panels: vec![slip] }));
    } else if runs.len() > 1 {
        let dbp = crate::output::plot::Panel {
            title: "drawbar pull – slip".into(),
            x_label: "slip".into(),
            y_label: "drawbar pull (N)".into(),
            series: vec![crate::output::plot::Series::line(
                "DBP",
                runs.iter().map(|r| (r.slip, r.drawbar_pull)).collect(),
            )],
            ..Default::default()
        };
        let tq = crate::output::plot::Panel {
            title: "torque – slip".into(),
            x_label: "slip".into(),
            y_label: "torque (N m)".into(),
            series: vec![crate::output::plot::Series::line(
                "torque",
                runs.iter().map(|r| (r.slip, r.torque)).collect(),
            )],
            ..Default::default()
        };
        figures.push(("wheel_slip".into(), Figure { panels: vec![dbp, tq] }));
    }
    figures
}
