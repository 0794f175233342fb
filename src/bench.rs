//! `regolith bench`: a fixed granular block collapse, timed.
//!
//! A block of soil `n × n × 2n` particles (n chosen from the requested count) stands in the
//! corner of a container three blocks wide and collapses under gravity: the neighbour grid
//! changes every step, part of the soil yields, part rests. Rheology Drucker–Prager or MCC,
//! RK2, h/d0 = 1.2, Wendland kernel, XSPH, artificial viscosity — the defaults users run.
//! Warm-up steps are not timed.

use std::path::Path;
use std::time::Instant;

use regolith_fsi::Real;
use serde::Serialize;

use crate::build::build_soil;
use crate::driver::RunError;
use crate::input::InputError;
use crate::scene::{Precision, Scene, load_scene_source};

/// Which rheology the bench block uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchModel {
    /// Drucker–Prager, φ = 30°.
    DruckerPrager,
    /// Modified Cam Clay, M = 1.2, OCR = 1.5.
    Mcc,
}

impl BenchModel {
    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::DruckerPrager => "drucker-prager",
            Self::Mcc => "mcc",
        }
    }
}

/// One bench result.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BenchResult {
    /// Rheology.
    pub model: &'static str,
    /// Backend.
    pub backend: String,
    /// Precision.
    pub precision: &'static str,
    /// Soil particles.
    pub particles: usize,
    /// Wall markers.
    pub markers: usize,
    /// Timed steps.
    pub steps: u64,
    /// Wall time of the timed steps (s).
    pub seconds: f64,
    /// Soil particles × steps / s.
    pub particle_steps_per_s: f64,
    /// Neighbour interactions (soil–soil and soil–marker pairs, each rate evaluation) per s.
    pub interactions_per_s: f64,
    /// Mean neighbours per soil particle.
    pub neighbours_per_particle: f64,
    /// Rayon threads.
    pub threads: usize,
    /// Device adapter (`cpu` for the CPU backend).
    pub adapter: String,
}

/// The smallest bench block: 4 × 4 × 8 particles.
pub const MIN_BENCH_PARTICLES: usize = 128;

/// The bench scene for about `particles` soil particles (at least [`MIN_BENCH_PARTICLES`]).
pub fn bench_scene(particles: usize, model: BenchModel, precision: Precision) -> Result<Scene, InputError> {
    let d0 = 0.01;
    if particles < MIN_BENCH_PARTICLES {
        return Err(InputError::flag(
            "--particles",
            format!("{particles} is below the smallest block, {MIN_BENCH_PARTICLES} particles (4 x 4 x 8)"),
        ));
    }
    let n = ((particles as f64 / 2.0).cbrt().round() as usize).max(4);
    let side = n as f64 * d0;
    let material = match model {
        BenchModel::DruckerPrager => "model = \"drucker-prager\"\nfriction_angle = 30.0\n",
        BenchModel::Mcc => {
            "model = \"mcc\"\nmcc_m = 1.2\nmcc_kappa = 0.02\nmcc_lambda = 0.1\nmcc_v_lambda = 2.2\nocr = 1.5\n"
        }
    };
    let text = format!(
        "[simulation]\nend_time = 1.0\ndt = \"auto\"\nintegrator = \"rk2\"\nprecision = \"{prec}\"\n\n\
         [sph]\nspacing = {d0}\nh_factor = 1.2\nkernel = \"wendland\"\nartificial_viscosity = 0.5\nshifting = \"xsph\"\n\n\
         [[materials]]\nname = \"soil\"\ndensity = 1700\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\n{material}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{w}, {w}, {hgt}]\n\n\
         [[soil_blocks]]\nmaterial = \"soil\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [{side}, {side}, {top}]\n",
        prec = precision.name(),
        w = 3.0 * side + 2.0 * d0,
        hgt = 2.0 * side + 2.0 * d0,
        top = 2.0 * side,
    );
    load_scene_source(Path::new("<bench>"), &text, &[])
}

/// Runs the bench: `warmup` untimed steps, then `steps` timed ones.
pub fn run_bench(scene: &Scene, model: BenchModel, warmup: u64, steps: u64) -> Result<BenchResult, RunError> {
    match scene.precision {
        Precision::F32 => bench_t::<f32>(scene, model, warmup, steps),
        Precision::F64 => bench_t::<f64>(scene, model, warmup, steps),
    }
}

fn bench_t<T: Real>(scene: &Scene, model: BenchModel, warmup: u64, steps: u64) -> Result<BenchResult, RunError> {
    let mut m = build_soil::<T>(scene)?;
    for _ in 0..warmup {
        m.solver.step(None)?;
    }
    let evals = if scene.solver.integrator == regolith_fsi::config::Integrator::Rk2 { 2.0 } else { 1.0 };
    let start = Instant::now();
    let mut pairs = 0.0;
    for _ in 0..steps {
        pairs += m.solver.step(None)?.pairs as f64;
    }
    let secs = start.elapsed().as_secs_f64();
    let n = m.solver.active();
    Ok(BenchResult {
        model: model.name(),
        backend: m.solver.backend().into(),
        precision: T::NAME,
        particles: n,
        markers: m.solver.marker_positions().len(),
        steps,
        seconds: secs,
        particle_steps_per_s: n as f64 * steps as f64 / secs,
        interactions_per_s: pairs * evals / secs,
        neighbours_per_particle: pairs / (steps as f64 * n as f64),
        threads: rayon::current_num_threads(),
        adapter: m.solver.adapter(),
    })
}
