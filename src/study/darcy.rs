//! `regolith study darcy`: steady seepage through a sand layer on a filter stone (the test case
//! of the multiphase-drag slides), over a ladder of spacings and for each drag distribution
//! (`[sph] drag = "svf" | "particle"`), with the observed order of the error.
//!
//! The column: a 0.08 m square container; a sand layer from z = 0.1 m up to 0.2 m (φ = 30°,
//! E = 10 MPa, k = 1e-3 m/s, grains 2650 kg/m³, bulk 1600 kg/m³) rests on a fixed permeable box
//! (the filter stone, which holds the soil and lets the water through) above an empty sump;
//! water fills the layer's pores and stands 0.1 m above it (ρ_w = 1000 kg/m³, c = 100 m/s,
//! μ = 1e-3 Pa s). The water drains through the layer into the sump. Between 0.06 and 0.12 s
//! (steady: the flux changes by under 1 % there) the study samples, every ten exchanges:
//!
//! - the Darcy flux `q = Σ_w V_w v_w,z / Σ_s V_s` (water volume flux per unit area of
//!   mixture) inside the layer, more than 2h from its faces;
//! - the slope dp/dz of the pore pressure there (least squares over the water particles).
//!
//! Two references: `k Δh / L` from the imposed heads (the water's surface 0.1 m above the layer,
//! zero pressure at its underside: gradient 2) — what a user designing a drain would compare
//! with, and where the drag's treatment of the layer's faces shows (a face error of order h / L
//! falls linearly with d0); and `−k (dp/dz / γ_w + 1)` from the measured gradient inside the
//! layer — Darcy's law locally, free of the faces.
//!
//! The column runs on the CPU backend in f64 (the reference), or with `--backend wgpu` on the
//! device in f32: the same study of the wgpu twin of the wet loop.

use std::path::{Path, PathBuf};
use std::time::Instant;

use regolith_fsi::config::Drag;
use regolith_fsi::{Real, SphSolver};
use serde::Serialize;

use super::StudyError;
use crate::input::InputError;
use crate::scene::{Backend, Precision, Scene, load_scene_source};

/// Layer thickness (m).
const LAYER: f64 = 0.1;
/// Water standing above the layer (m).
const ABOVE: f64 = 0.1;
/// Column width (m).
const WIDTH: f64 = 0.08;
/// Simulated time (s).
const END: f64 = 0.12;
/// Sand permeability (m/s at standard gravity).
const PERMEABILITY: f64 = 1e-3;

/// The drag distributions, as scene values.
pub fn drag_name(d: Drag) -> &'static str {
    match d {
        Drag::Svf => "svf",
        Drag::Particle => "particle",
    }
}

/// The filter-stone column at spacing `d0` with drag `drag`, run to `end` s.
pub fn filter_column(d0: f64, drag: Drag, end: f64) -> Result<Scene, InputError> {
    let top = 0.1 + LAYER + ABOVE;
    let text = format!(
        "[simulation]\nend_time = {end}\nprecision = \"f64\"\n\n[sph]\nspacing = {d0}\ndrag = \"{drag}\"\n\n\
         [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\ngrain_density = 2650\n\
         permeability = {PERMEABILITY}\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
         [[materials]]\nname = \"water\"\nmodel = \"water\"\ndensity = 1000\nsound_speed = 100\nviscosity = 1e-3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{WIDTH}, {WIDTH}, {h}]\n\n\
         [[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.1]\nmax = [{WIDTH}, {WIDTH}, {zs}]\n\n\
         [[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.1]\nmax = [{WIDTH}, {WIDTH}, {top}]\n\n\
         [[bodies]]\nname = \"filter\"\nshape = {{ type = \"box\", size = [{w}, {w}, {t}] }}\nmass = 1.0\n\
         position = [{c}, {c}, {zc}]\nmotion = {{ type = \"fixed\" }}\nfsi = true\npermeable = true\n",
        drag = drag_name(drag),
        h = top + 0.05,
        zs = 0.1 + LAYER,
        w = WIDTH - d0,
        c = 0.5 * WIDTH,
        t = 3.0 * d0,
        zc = 0.1 - 1.5 * d0,
    );
    load_scene_source(Path::new("<study darcy>"), &text, &[])
}

/// The Darcy flux through the soil between `z0` and `z1` and the slope dp/dz of the pore
/// pressure there (see the module docs).
pub fn flux_and_gradient<T: Real>(s: &dyn SphSolver<T>, z0: f64, z1: f64) -> (f64, f64) {
    let mats = s.materials();
    let (mut flux, mut volume) = (0.0, 0.0);
    let (mut n, mut sz, mut sp, mut szz, mut szp) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..s.active() {
        let x = s.positions()[i].as_f64();
        if !(z0..z1).contains(&x[2]) {
            continue;
        }
        let mat = &mats[s.material_ids()[i] as usize];
        let m = s.masses()[i].as_f64();
        if mat.is_water() {
            flux += m / mat.density.as_f64() * s.velocities()[i].as_f64()[2];
            let p = -s.stresses()[i].as_f64()[2];
            n += 1.0;
            sz += x[2];
            sp += p;
            szz += x[2] * x[2];
            szp += x[2] * p;
        } else {
            volume += m / s.densities()[i].as_f64();
        }
    }
    (flux / volume, (n * szp - sz * sp) / (n * szz - sz * sz))
}

/// One run of the column.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DarcyPoint {
    /// Spacing d0 (m).
    pub d0: f64,
    /// Drag distribution.
    pub drag: &'static str,
    /// Backend (`cpu` in f64, `wgpu` in f32).
    pub backend: &'static str,
    /// Soil and water particles.
    pub particles: usize,
    /// Exchanges run.
    pub exchanges: u64,
    /// Measured Darcy flux (m/s, downward negative).
    pub q: f64,
    /// `k Δh / L` from the imposed heads (m/s).
    pub q_heads: f64,
    /// `−k (dp/dz / γ_w + 1)` from the measured gradient (m/s); NaN where the layer holds no
    /// region more than 2h from its faces (written as `null` in JSON).
    pub q_local: f64,
    /// `q / q_heads − 1`.
    pub err_heads: f64,
    /// `q / q_local − 1`.
    pub err_local: f64,
    /// Wall time (s).
    pub wall_s: f64,
    /// Soil particles that left the layer (through the filter stone or elsewhere).
    pub escaped: usize,
}

/// Runs the column at `d0` with `drag` on the CPU backend (f64).
pub fn darcy_point(d0: f64, drag: Drag) -> Result<DarcyPoint, StudyError> {
    darcy_point_on(d0, drag, Backend::Cpu)
}

/// Runs the column at `d0` with `drag` on `backend`: the CPU in f64, wgpu in f32 (`auto` is
/// refused: a study names the backend its numbers come from).
pub fn darcy_point_on(d0: f64, drag: Drag, backend: Backend) -> Result<DarcyPoint, StudyError> {
    let mut scene = filter_column(d0, drag, END)?;
    match backend {
        Backend::Wgpu => {
            // The column is written in f64 for the CPU; on wgpu it runs in f32, and the run
            // takes the backend as `regolith run --backend wgpu` would (an adapter must exist).
            scene.backend = Backend::Wgpu;
            scene.precision = Precision::F32;
            scene.precision_set = false;
            crate::build::backend::resolve_backend(&mut scene).map_err(|e| InputError::flag("--backend", e))?;
            run_column::<f32>(&scene, d0, drag)
        }
        Backend::Cpu => run_column::<f64>(&scene, d0, drag),
        Backend::Auto => Err(InputError::flag("--backend", "a study runs on cpu or wgpu, not auto").into()),
    }
}

fn run_column<T: Real>(scene: &Scene, d0: f64, drag: Drag) -> Result<DarcyPoint, StudyError> {
    let case = format!("darcy d0 = {d0}, drag = {}, backend {}", drag_name(drag), scene.backend.name());
    let run_err = |source| StudyError::Run { case: case.clone(), source };
    let start = Instant::now();
    let mut a = crate::build::assemble::<T>(scene).map_err(|e| run_err(e.into()))?;
    let reach = 2.0 * scene.solver.h();
    let (z0, z1) = (0.1 + 0.5 * d0 + reach, 0.1 + LAYER + 0.5 * d0 - reach);
    let (mut q_sum, mut grad_sum, mut samples, mut exchanges) = (0.0, 0.0, 0.0, 0u64);
    while a.system.fluid.time() < END {
        a.system.advance(Some(END - a.system.fluid.time())).map_err(|e| run_err(e.into()))?;
        exchanges += 1;
        if a.system.fluid.time() > 0.5 * END && exchanges % 10 == 0 {
            // A device backend refreshes its host copy here (a no-op on the CPU).
            a.system.fluid.sync().map_err(|e| run_err(e.into()))?;
            let (q, g) = flux_and_gradient(a.system.fluid.as_ref(), z0, z1);
            q_sum += q;
            grad_sum += g;
            samples += 1.0;
        }
    }
    a.system.fluid.sync().map_err(|e| run_err(e.into()))?;
    let wall_s = start.elapsed().as_secs_f64();
    if samples == 0.0 {
        return Err(StudyError::Incomplete(format!("{case}: no sample of the steady flow")));
    }
    let s = a.system.fluid.as_ref();
    let g = -scene.solver.gravity[2];
    let gamma = 1000.0 * 9.80665;
    let (q, dpdz) = (q_sum / samples, grad_sum / samples);
    let q_heads = -PERMEABILITY * (LAYER + ABOVE) / LAYER * g / 9.80665;
    // Inside the layer more than 2h from its faces: at the coarsest spacings nothing is left
    // (a 0.1 m layer at d0 = 2 cm is 5 spacings, 4h = 4.8 spacings), and there is no local
    // measurement.
    let q_local = if z1 - z0 >= 2.0 * d0 { -PERMEABILITY * (dpdz / gamma + g / 9.80665) } else { f64::NAN };
    let escaped = (0..s.active())
        .filter(|&i| !s.materials()[s.material_ids()[i] as usize].is_water())
        .filter(|&i| s.positions()[i].as_f64()[2] < 0.1 - d0)
        .count()
        + (s.len() - s.active());
    Ok(DarcyPoint {
        d0,
        drag: drag_name(drag),
        backend: scene.backend.name(),
        particles: s.len(),
        exchanges,
        q,
        q_heads,
        q_local,
        err_heads: q / q_heads - 1.0,
        err_local: q / q_local - 1.0,
        wall_s,
        escaped,
    })
}

/// What `regolith study darcy` runs.
#[derive(Clone, Debug)]
pub struct DarcyOptions {
    /// Spacings, coarse to fine.
    pub spacings: Vec<f64>,
    /// Drag distributions.
    pub drags: Vec<Drag>,
    /// Backend: `cpu` (f64) or `wgpu` (f32).
    pub backend: Backend,
    /// Output folder.
    pub out: PathBuf,
}

/// Runs every (drag, spacing) point and writes `darcy.json` and `darcy.md` under `out`.
pub fn darcy_study(opts: &DarcyOptions) -> Result<Vec<DarcyPoint>, StudyError> {
    if opts.spacings.is_empty() || opts.spacings.iter().any(|d| !(d.is_finite() && (0.002..=0.02).contains(d))) {
        return Err(InputError::flag("--spacings", "each spacing must be in [0.002, 0.02] m".to_string()).into());
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| StudyError::output(&opts.out, e))?;
    let mut points = Vec::new();
    for &drag in &opts.drags {
        for &d0 in &opts.spacings {
            let p = darcy_point_on(d0, drag, opts.backend)?;
            eprintln!(
                "darcy ({}): d0 = {d0} m, drag {}: q = {:.4e} m/s, {} against k Δh / L, {} against k i ({:.1} s)",
                p.backend,
                p.drag,
                p.q,
                percent(p.err_heads),
                percent(p.err_local),
                p.wall_s
            );
            points.push(p);
        }
    }
    let json = serde_json::to_string_pretty(&points).map_err(|e| StudyError::output(&opts.out, e))?;
    super::write_text(&opts.out.join("darcy.json"), &json)?;
    super::write_text(&opts.out.join("darcy.md"), &table(&points))?;
    Ok(points)
}

/// A relative error in percent, or a dash where there is none.
fn percent(x: f64) -> String {
    if x.is_finite() { format!("{:+.2} %", 100.0 * x) } else { "—".to_string() }
}

/// The markdown table: per point its errors; then per drag with three spacings or more the
/// Richardson estimate of the flux over the ladder (observed order, limit and its error
/// against `k Δh / L`, Roache's GCI), or why there is none.
pub fn table(points: &[DarcyPoint]) -> String {
    let mut t = String::from(
        "| drag | backend | d0 (m) | particles | q (m/s) | vs k Δh / L | vs k i (inside) | wall (s) |\n\
         |---|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for p in points {
        t.push_str(&format!(
            "| {} | {} | {} | {} | {:.4e} | {} | {} | {:.1} |\n",
            p.drag,
            p.backend,
            p.d0,
            p.particles,
            p.q,
            percent(p.err_heads),
            percent(p.err_local),
            p.wall_s
        ));
    }
    let mut drags: Vec<&str> = points.iter().map(|p| p.drag).collect();
    drags.dedup();
    for drag in drags {
        let ladder: Vec<&DarcyPoint> = points.iter().filter(|p| p.drag == drag).collect();
        if ladder.len() < 3 {
            continue;
        }
        let h: Vec<f64> = ladder.iter().map(|p| p.d0).collect();
        let q: Vec<f64> = ladder.iter().map(|p| p.q).collect();
        t.push_str(&match super::convergence::richardson(&h, &q) {
            Ok(c) => format!(
                "\n{drag}: the flux converges at observed order {:.2} (three-level range {:.2}–{:.2}) to {:.4e} m/s \
                 ({:+.1} % against k Δh / L; GCI ±{:.2e} m/s).\n",
                c.order,
                c.order_range.0,
                c.order_range.1,
                c.limit,
                100.0 * (c.limit / ladder[0].q_heads - 1.0),
                c.gci
            ),
            Err(e) => format!("\n{drag}: no Richardson estimate of the flux: {e}.\n"),
        });
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(d0: f64, q: f64) -> DarcyPoint {
        DarcyPoint {
            d0,
            drag: "svf",
            backend: "cpu",
            particles: 1,
            exchanges: 1,
            q,
            q_heads: -2e-3,
            q_local: f64::NAN,
            err_heads: q / -2e-3 - 1.0,
            err_local: f64::NAN,
            wall_s: 1.0,
            escaped: 0,
        }
    }

    /// A first-order ladder `q = −2e-3 (1 + 5 d0)` reads order 1 and the limit k Δh / L (0 %),
    /// and a missing local measurement is a dash, not "NaN %".
    #[test]
    fn the_table_reads_the_order_and_limit_of_a_first_order_ladder() {
        let pts: Vec<DarcyPoint> = [0.02, 0.01, 0.005].iter().map(|&d| point(d, -2e-3 * (1.0 + 5.0 * d))).collect();
        let t = table(&pts);
        assert!(t.contains("observed order 1.00"), "{t}");
        assert!(t.contains("to -2.0000e-3 m/s (+0.0 % against k Δh / L"), "{t}");
        assert!(t.contains("| — |") && !t.contains("NaN"), "{t}");
    }
}
