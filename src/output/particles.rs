//! `particles_final.csv` and the per-particle values the recording packs.

use std::io::Write as _;
use std::path::Path;

use regolith_fsi::rheology::Rheology;
use regolith_fsi::{Real, SphSolver};

use crate::driver::RunError;

/// One particle's output values.
#[derive(Clone, Copy, Debug)]
pub struct ParticleRow {
    /// Position (m).
    pub pos: [f64; 3],
    /// Velocity (m/s).
    pub vel: [f64; 3],
    /// Pressure p = −tr σ / 3 (Pa, compression positive).
    pub p: f64,
    /// Von Mises deviatoric stress q (Pa).
    pub q: f64,
    /// MCC preconsolidation pressure (Pa), 0 for other models.
    pub pc: f64,
    /// Material id.
    pub material: u16,
    /// The particle is water (a wet scene's pore or free water), not soil.
    pub water: bool,
}

/// The output values of active particle `i`.
pub fn particle_row<T: Real>(s: &dyn SphSolver<T>, i: usize) -> ParticleRow {
    let sig = s.stresses()[i];
    let material = s.material_ids()[i];
    let mat = &s.materials()[material as usize];
    let pc = match mat.rheology {
        Rheology::Mcc(_) => s.states()[i].pc.as_f64(),
        _ => 0.0,
    };
    ParticleRow {
        pos: s.positions()[i].as_f64(),
        vel: s.velocities()[i].as_f64(),
        p: sig.pressure().as_f64(),
        q: sig.von_mises().as_f64(),
        pc,
        material,
        water: mat.is_water(),
    }
}

/// `x,y,z,vx,vy,vz,p,q,pc,material` for every active particle.
pub fn write_particles_csv<T: Real>(path: &Path, s: &dyn SphSolver<T>) -> Result<(), RunError> {
    let io = |e: std::io::Error| RunError::output(path, e);
    let f = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::new(f);
    writeln!(w, "x,y,z,vx,vy,vz,p,q,pc,material").map_err(io)?;
    for i in 0..s.active() {
        let r = particle_row(s, i);
        let [x, y, z] = r.pos;
        let [vx, vy, vz] = r.vel;
        writeln!(w, "{x},{y},{z},{vx},{vy},{vz},{},{},{},{}", r.p, r.q, r.pc, r.material).map_err(io)?;
    }
    w.flush().map_err(io)
}
