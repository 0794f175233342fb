//! `series.csv`: one row per sample, `time` first, then an optional `run` label (a rig's slip
//! or plate size), then for every body `<name>.fx,.fy,.fz,.tx,.ty,.tz,.x,.y,.z,.vx,.vy,.vz`
//! (soil force and torque about the centre of mass in N and N m, centre-of-mass position and
//! velocity, world frame), then the rig's own columns.

use std::io::Write as _;
use std::path::Path;

use regolith_fsi::Real;

use crate::run::RunError;
use crate::sim::{Body, Simulation};

/// Rows of a time series.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows, each `columns.len()` long.
    pub rows: Vec<Vec<f64>>,
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
        columns.extend(extra.iter().map(|s| s.to_string()));
        Self { columns, rows: Vec::new() }
    }

    /// Appends a row: time, optional run label, every body's wrench and state, `extra`.
    pub fn push<T: Real>(&mut self, sim: &Simulation<T>, run: Option<f64>, extra: &[f64]) {
        let mut row = vec![sim.time()];
        if let Some(r) = run {
            row.push(r);
        }
        for i in 0..sim.scene.bodies.len() {
            let w = sim.fsi_wrench(Body(i));
            let s = sim.body_state(Body(i));
            row.extend(w.force);
            row.extend(w.torque);
            row.extend(s.com);
            row.extend(s.linvel);
        }
        row.extend_from_slice(extra);
        self.rows.push(row);
    }

    /// Index of a column.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// Writes the CSV.
    pub fn write(&self, path: &Path) -> Result<(), RunError> {
        let io = |e: std::io::Error| RunError::Output { path: path.to_path_buf(), message: e.to_string() };
        let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        writeln!(w, "{}", self.columns.join(",")).map_err(io)?;
        for r in &self.rows {
            let line: Vec<String> = r.iter().map(|v| format!("{v}")).collect();
            writeln!(w, "{}", line.join(",")).map_err(io)?;
        }
        w.flush().map_err(io)
    }
}
