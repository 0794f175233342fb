//! `series.csv`: one row per sample, `time` first, then an optional `run` label (a rig's slip
//! or plate size), then for every body `<name>.fx,.fy,.fz,.tx,.ty,.tz,.x,.y,.z,.vx,.vy,.vz`
//! (soil force and torque about the centre of mass in N and N m, centre-of-mass position and
//! velocity, world frame), then per vehicle `<name>.x,.y,.z,.roll,.pitch,.yaw,.speed` (root link
//! pose, roll–pitch–yaw in degrees, horizontal speed in m/s) and per wheel
//! `<vehicle>/<link>.slip,.sinkage,.omega`, then the rig's own columns (or, for scenes without a
//! rig, `soil.max_speed` in m/s and `soil.kinetic_energy` in J).

use std::io::Write as _;
use std::path::Path;

use regolith_fsi::Real;

use crate::driver::{Observer, RunError, RunStats};
use crate::scene::VehicleSpec;
use crate::sim::Simulation;

/// Rows of a time series.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows, each `columns.len()` long.
    pub rows: Vec<Vec<f64>>,
}

/// Per-vehicle column suffixes.
pub const VEHICLE_COLUMNS: [&str; 7] = ["x", "y", "z", "roll", "pitch", "yaw", "speed"];

/// Roll, pitch, yaw (deg; z-y-x convention, as URDF's rpy) of a unit quaternion `[x, y, z, w]`.
pub fn roll_pitch_yaw_deg(q: [f64; 4]) -> [f64; 3] {
    let [x, y, z, w] = q;
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw].map(f64::to_degrees)
}

/// A vehicle's quantities: `x, y, z, roll, pitch, yaw, speed` of the root link, then
/// `<wheel link>.slip, .sinkage, .omega` per wheel.
pub fn vehicle_columns(v: &VehicleSpec) -> Vec<String> {
    let mut c: Vec<String> = VEHICLE_COLUMNS.iter().map(|s| s.to_string()).collect();
    for w in &v.wheels {
        for q in ["slip", "sinkage", "omega"] {
            c.push(format!("{}.{q}", v.model.links[w.link].name));
        }
    }
    c
}

/// The values of [`vehicle_columns`] for vehicle `vi` now.
pub fn vehicle_values<T: Real>(sim: &Simulation<T>, vi: usize) -> Vec<f64> {
    let v = &sim.scene.vehicles[vi];
    let st = sim.body_state(sim.body_at(v.body(v.model.root)));
    let mut row = st.origin.to_vec();
    row.extend(roll_pitch_yaw_deg(st.rotation));
    row.push(st.linvel[0].hypot(st.linvel[1]));
    for w in sim.wheel_states(vi) {
        row.extend([w.slip, w.sinkage, w.omega]);
    }
    row
}

/// Per-body column suffixes.
pub const BODY_COLUMNS: [&str; 12] = ["fx", "fy", "fz", "tx", "ty", "tz", "x", "y", "z", "vx", "vy", "vz"];

impl Series {
    /// Columns for the bodies of a simulation plus `extra` rig columns; `with_run` adds `run`.
    pub fn new<T: Real>(sim: &Simulation<T>, with_run: bool, extra: &[&str]) -> Self {
        let mut columns = vec!["time".to_string()];
        if with_run {
            columns.push("run".into());
        }
        for b in &sim.scene.bodies {
            for c in BODY_COLUMNS {
                columns.push(format!("{}.{c}", b.desc.name));
            }
        }
        for v in &sim.scene.vehicles {
            columns.extend(vehicle_columns(v).into_iter().map(|c| {
                // `x` → `rover.x`, `wheel_fl.slip` → `rover/wheel_fl.slip`.
                if c.contains('.') { format!("{}/{c}", v.name) } else { format!("{}.{c}", v.name) }
            }));
        }
        columns.extend(extra.iter().map(|s| s.to_string()));
        if sim.scene.active.is_some() {
            columns.push("soil.awake".into());
        }
        Self { columns, rows: Vec::new() }
    }

    /// Appends a row: time, optional run label, every body's wrench and state, `extra`, and
    /// with an active region the particles integrated in the last step (`soil.awake`).
    pub fn push<T: Real>(&mut self, sim: &Simulation<T>, run: Option<f64>, extra: &[f64]) {
        let mut row = vec![sim.time()];
        if let Some(r) = run {
            row.push(r);
        }
        for i in 0..sim.scene.bodies.len() {
            let w = sim.fsi_wrench(sim.body_at(i));
            let s = sim.body_state(sim.body_at(i));
            row.extend(w.force);
            row.extend(w.torque);
            row.extend(s.com);
            row.extend(s.linvel);
        }
        for vi in 0..sim.scene.vehicles.len() {
            row.extend(vehicle_values(sim, vi));
        }
        row.extend_from_slice(extra);
        if sim.scene.active.is_some() {
            row.push(sim.system.fluid.awake() as f64);
        }
        self.rows.push(row);
    }

    /// Index of a column.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// Writes the CSV.
    pub fn write(&self, path: &Path) -> Result<(), RunError> {
        let io = |e: std::io::Error| RunError::output(path, e);
        let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        writeln!(w, "{}", self.columns.join(",")).map_err(io)?;
        for r in &self.rows {
            let line: Vec<String> = r.iter().map(|v| format!("{v}")).collect();
            writeln!(w, "{}", line.join(",")).map_err(io)?;
        }
        w.flush().map_err(io)
    }
}

/// The series of a terrain scene without a rig: bodies and vehicles, then the soil's largest
/// speed and kinetic energy (how a bed settles), one row at the start and one per exchange.
#[derive(Clone, Debug, Default)]
pub struct TerrainSeries(pub Series);

impl TerrainSeries {
    /// Soil columns after the bodies' and vehicles'.
    pub const SOIL_COLUMNS: [&str; 2] = ["soil.max_speed", "soil.kinetic_energy"];
}

impl<T: Real> Observer<T> for TerrainSeries {
    fn begin(&mut self, sim: &Simulation<T>, _label: Option<f64>) -> Result<(), RunError> {
        self.0 = Series::new(sim, false, &Self::SOIL_COLUMNS);
        self.0.push(sim, None, &[0.0, sim.soil_kinetic_energy()]);
        Ok(())
    }

    fn after_step(&mut self, sim: &Simulation<T>, stats: &RunStats) -> Result<(), RunError> {
        self.0.push(sim, None, &[stats.last_speed, sim.soil_kinetic_energy()]);
        Ok(())
    }
}
