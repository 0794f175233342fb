//! `regolith bench`.

use std::path::Path;

use anyhow::Context;

use super::{ActiveArg, BackendArg, BenchModelArg, Failure, Precision};
use crate::bench::{
    BenchModel, RoverBenchResult, bench_scene, column_scene, rover_patch_scene, rover_scene_file, run_bench, run_rover,
    run_wheel_long, wheel_long_scene,
};
use crate::input::InputError;
use crate::scene;

/// The skins to time (`--skin`, each checked; `None`: the scene's default, none given).
fn skins(skin: &[f64]) -> Result<Vec<Option<f64>>, Failure> {
    let max = regolith_fsi::config::MAX_NEIGHBOR_SKIN;
    if let Some(s) = skin.iter().find(|s| !(s.is_finite() && (0.0..=max).contains(*s))) {
        return Err(
            InputError::flag("--skin", format!("each skin must be in [0, {max}] (multiples of h; got {s})")).into()
        );
    }
    Ok(if skin.is_empty() { vec![None] } else { skin.iter().copied().map(Some).collect() })
}

/// The scene of `run`: the block (of about `particles`, default 100 000, and `model`, default
/// both) or the column.
pub(super) struct Kind {
    pub column: bool,
    pub particles: Option<usize>,
    pub model: Option<BenchModelArg>,
}

pub(super) fn run(
    kind: Kind,
    backend: BackendArg,
    precision: Precision,
    skin: &[f64],
    steps: u64,
    warmup: u64,
    json: Option<&Path>,
) -> Result<(), Failure> {
    let particles = kind.particles.unwrap_or(100_000);
    if !(1_000..=50_000_000).contains(&particles) {
        return Err(InputError::flag("--particles", format!("must be in 1000..=50000000 (got {particles})")).into());
    }
    timed_count(steps)?;
    let prec = match precision {
        Precision::F32 => scene::Precision::F32,
        Precision::F64 => scene::Precision::F64,
    };
    let models = match kind.model.unwrap_or(if kind.column { BenchModelArg::Dp } else { BenchModelArg::Both }) {
        BenchModelArg::Dp => vec![BenchModel::DruckerPrager],
        BenchModelArg::Mcc => vec![BenchModel::Mcc],
        BenchModelArg::Both => vec![BenchModel::DruckerPrager, BenchModel::Mcc],
    };
    let skins = skins(skin)?;
    let mut results = Vec::new();
    for (m, skin) in models.into_iter().flat_map(|m| skins.iter().map(move |&s| (m, s))) {
        let (name, mut scene) =
            if kind.column { ("column", column_scene(prec)?) } else { ("block", bench_scene(particles, m, prec)?) };
        if let Some(s) = skin {
            scene.solver.neighbor_skin = s;
        }
        on_backend(&mut scene, backend, skin)?;
        let r = run_bench(name, &scene, m, warmup, steps).context("bench run failed")?;
        println!(
            "bench {} {:<15} {} {} skin {} h: {} particles, {} markers, {} steps ({} list builds, {} steps redone) in {:.2} s: {:.3e} particle-steps/s, {:.3e} listed pairs/s ({:.1} listed neighbours/particle, {} threads, adapter {}); dt {:.3e} s, {:.3e} simulated s per wall s{}",
            r.scene,
            r.model,
            r.backend,
            r.precision,
            r.neighbor_skin,
            r.particles,
            r.markers,
            r.steps,
            r.list_builds,
            r.stage_retries,
            r.seconds,
            r.particle_steps_per_s,
            r.interactions_per_s,
            r.neighbours_per_particle,
            r.threads,
            r.adapter,
            r.dt_mean,
            r.sim_s_per_wall_s,
            r.bytes_per_particle.map_or(String::new(), |b| format!("; solver memory {b:.0} B per particle"))
        );
        results.push(r);
    }
    if let Some(p) = json {
        crate::output::write_json(p, &results).context("writing bench json")?;
    }
    Ok(())
}

/// Puts a bench scene on `--backend` (the run's own check of the adapter, precision and
/// lists); a skin above 0 on wgpu is a `--skin` error.
fn on_backend(scene: &mut scene::Scene, backend: BackendArg, skin: Option<f64>) -> Result<(), Failure> {
    scene.backend = match backend {
        BackendArg::Auto => scene::Backend::Auto,
        BackendArg::Cpu => scene::Backend::Cpu,
        BackendArg::Wgpu => scene::Backend::Wgpu,
    };
    scene.precision_set = true;
    let chosen = crate::build::backend::resolve_backend(scene).map_err(|m| InputError::flag("--backend", m))?;
    if let Some(skin) = skin.filter(|s| *s > 0.0 && scene.backend == scene::Backend::Wgpu) {
        return Err(InputError::flag(
            "--skin",
            format!("the wgpu backend rebuilds its neighbour lists every step: use 0 or --backend cpu (got {skin})"),
        )
        .into());
    }
    eprintln!("{chosen}");
    Ok(())
}

/// What `--scene wheel-long` runs: the active region, the backend, the bed and patch length.
pub(super) struct WheelLong {
    pub active: ActiveArg,
    pub backend: BackendArg,
    pub length: f64,
    pub patch: Option<f64>,
}

/// `regolith bench --scene wheel-long`: timed exchanges of the wheel on the long bed, with and
/// without the active region, and on a moving patch with and without it (`--patch`); `steps`
/// and `warmup` count exchanges (1 ms each).
pub(super) fn wheel_long(
    WheelLong { active, backend, length, patch }: WheelLong,
    skin: &[f64],
    steps: u64,
    warmup: u64,
    json: Option<&Path>,
) -> Result<(), Failure> {
    timed_count(steps)?;
    // (active region, patch length) of each run.
    let mut modes: Vec<(bool, Option<f64>)> = match active {
        ActiveArg::On => vec![(true, None)],
        ActiveArg::Off => vec![(false, None)],
        ActiveArg::Both => vec![(false, None), (true, None)],
    };
    // A patch alone, and (unless `--active off`) a patch with the active region inside it: what
    // a long traverse would use.
    if patch.is_some() {
        modes.push((false, patch));
        if !matches!(active, ActiveArg::Off) {
            modes.push((true, patch));
        }
    }
    let skins = skins(skin)?;
    let mut results = Vec::new();
    for (skin, (on, patch)) in skins.iter().flat_map(|&s| modes.iter().map(move |&m| (s, m))) {
        let mut scene = wheel_long_scene(length, on, patch)?;
        // The run's length, so that the neighbour grid (which covers where a prescribed body
        // can get by the end) spans this bench's drive, not the scene's open-ended one.
        scene.end_time = (warmup + steps + 1) as f64 * scene.exchange_interval;
        if let Some(s) = skin {
            scene.solver.neighbor_skin = s;
        }
        on_backend(&mut scene, backend, skin)?;
        let r = run_wheel_long(&scene, warmup, steps).context("bench run failed")?;
        println!(
            "bench wheel-long {} active {}{} skin {} h: {} particles ({:.0} integrated per step), {} markers; {} exchanges, {} steps (dt {:.3e} s, {} list builds, {} steps redone) in {:.2} s ({} classifications): {:.3e} simulated s per wall s, {:.3e} particle-steps/s; wheel force x {:.2} N, z {:.2} N ({} threads, adapter {})",
            r.backend,
            if r.active { "on " } else { "off" },
            r.patch.map_or(String::new(), |l| format!(" patch {l} m")),
            r.neighbor_skin,
            r.particles,
            r.awake_mean,
            r.markers,
            r.timed.exchanges,
            r.timed.steps,
            r.timed.dt_mean,
            r.list_builds,
            r.stage_retries,
            r.timed.seconds,
            r.classifications,
            r.timed.sim_s_per_wall_s,
            r.timed.particle_steps_per_s,
            r.force_xz[0],
            r.force_xz[1],
            r.threads,
            r.adapter
        );
        results.push(r);
    }
    // Every run against the first (full bed, first skin).
    if let [base, rest @ ..] = &results[..] {
        for r in rest {
            println!(
                "bench wheel-long: active {}{} skin {} h against active {} skin {} h: speed-up {:.2}x (simulated s per wall s); wheel force x {:+.2} %, z {:+.2} %",
                if r.active { "on" } else { "off" },
                r.patch.map_or(String::new(), |l| format!(" patch {l} m")),
                r.neighbor_skin,
                if base.active { "on" } else { "off" },
                base.neighbor_skin,
                r.timed.sim_s_per_wall_s / base.timed.sim_s_per_wall_s,
                100.0 * (r.force_xz[0] - base.force_xz[0]) / base.force_xz[0].abs(),
                100.0 * (r.force_xz[1] - base.force_xz[1]) / base.force_xz[1].abs()
            );
        }
    }
    if let Some(p) = json {
        crate::output::write_json(p, &results).context("writing bench json")?;
    }
    Ok(())
}

/// `regolith bench --scene rover-patch`: timed exchanges of the example rover on the whole bed
/// and on a moving patch, and their ratio; `steps` and `warmup` count exchanges (1 ms each).
pub(super) fn rover_patch(
    length: f64,
    patch: f64,
    steps: u64,
    warmup: u64,
    json: Option<&Path>,
) -> Result<(), Failure> {
    timed_count(steps)?;
    let file = rover_scene_file()?;
    let mut results: Vec<RoverBenchResult> = Vec::new();
    for on in [false, true] {
        let scene = rover_patch_scene(&file, length, patch, on)?;
        let r = run_rover(&scene, warmup, steps).context("bench run failed")?;
        println!(
            "bench rover-patch {}: {} → {} particles, {} markers, solver arrays {:.1} → {:.1} MB; {} exchanges, {} steps (dt {:.3e} s) in {:.2} s: {:.3e} simulated s per wall s, {:.3e} particle-steps/s; chassis x {:.3} → {:.3} m, {} advances ({} threads)",
            r.patch.map_or(format!("whole {length} m bed"), |l| format!("patch {l} m of {length} m")),
            r.particles[0],
            r.particles[1],
            r.markers,
            1e-6 * r.solver_bytes[0] as f64,
            1e-6 * r.solver_bytes[1] as f64,
            r.timed.exchanges,
            r.timed.steps,
            r.timed.dt_mean,
            r.timed.seconds,
            r.timed.sim_s_per_wall_s,
            r.timed.particle_steps_per_s,
            r.chassis_x[0],
            r.chassis_x[1],
            r.advances,
            r.threads
        );
        results.push(r);
    }
    if let [whole, on_patch] = &results[..] {
        println!(
            "bench rover-patch: patch {patch} m against the whole {length} m bed: speed-up {:.2}x (simulated s per wall s), particles {:.2}x fewer, solver memory {:.2}x less",
            on_patch.timed.sim_s_per_wall_s / whole.timed.sim_s_per_wall_s,
            whole.particles[1] as f64 / on_patch.particles[1] as f64,
            whole.solver_bytes[1] as f64 / on_patch.solver_bytes[1].max(1) as f64,
        );
    }
    if let Some(p) = json {
        crate::output::write_json(p, &results).context("writing bench json")?;
    }
    Ok(())
}

/// `regolith bench --carve`: the mesh-carving benchmark of `regolith_rigid::bench`.
pub(super) fn carve(json: Option<&Path>) -> Result<(), Failure> {
    let r = regolith_rigid::bench::carve_torus(100_000, 1_000_000, 0.5);
    println!(
        "bench carve: {} triangles × {} points (d0 = {:.3} mm, margin {:.3} mm): {:.3} s, {} points removed ({} threads)",
        r.triangles,
        r.points,
        1e3 * r.spacing,
        1e3 * r.margin,
        r.seconds,
        r.removed,
        rayon::current_num_threads()
    );
    if let Some(p) = json {
        let v = serde_json::json!({
            "bench": "carve",
            "triangles": r.triangles,
            "points": r.points,
            "spacing_m": r.spacing,
            "margin_m": r.margin,
            "removed": r.removed,
            "seconds": r.seconds,
            "threads": rayon::current_num_threads(),
        });
        crate::output::write_json(p, &v).context("writing bench json")?;
    }
    Ok(())
}

/// `--steps` counts what is timed: at least one.
fn timed_count(steps: u64) -> Result<(), Failure> {
    if steps == 0 {
        return Err(InputError::flag("--steps", "must be at least 1").into());
    }
    Ok(())
}
