//! `regolith run`.

use std::path::Path;

use super::{BackendArg, Failure, Precision};
use crate::input::InputError;
use crate::run::{RunOptions, run_scene};
use crate::scene::{self, Backend, load_scene};

pub(super) fn run(
    path: &Path,
    out: Option<&Path>,
    backend: Option<BackendArg>,
    precision: Option<Precision>,
    sets: &[(String, toml::Value)],
    quiet: bool,
) -> Result<(), Failure> {
    let mut scene = load_scene(path, sets)?;
    if let Some(b) = backend {
        scene.backend = match b {
            BackendArg::Auto => Backend::Auto,
            BackendArg::Cpu => Backend::Cpu,
            BackendArg::Wgpu => Backend::Wgpu,
        };
    }
    if let Some(p) = precision {
        scene.precision = match p {
            Precision::F32 => scene::Precision::F32,
            Precision::F64 => scene::Precision::F64,
        };
        scene.precision_set = true;
    }
    let chosen = crate::build::backend::resolve_backend(&mut scene).map_err(|m| InputError::flag("--backend", m))?;
    if !quiet {
        println!("{chosen}");
    }
    if !quiet {
        print!("{}", scene::describe(&scene));
    } else {
        // Joints a URDF importer could not honour are reported once, quiet or not.
        for v in &scene.vehicles {
            for u in &v.model.unsupported {
                eprintln!("warning: vehicle \"{}\": {u}", v.name);
            }
        }
    }
    let out = match (out, &scene.output.dir) {
        (Some(o), _) => o.to_path_buf(),
        (None, Some(d)) => d.clone(),
        (None, None) => {
            Path::new("out").join(path.file_stem().map_or_else(|| "run".into(), |s| s.to_string_lossy().into_owned()))
        }
    };
    // Ctrl-C stops the run at the next exchange; the outputs (and the recording) are finished.
    // A second handler cannot be installed (e.g. the CLI called twice in one process): the run
    // then simply has no graceful stop, which is not worth failing it for.
    let opts = RunOptions { out: out.clone(), quiet, stop: crate::driver::StopToken::new() };
    let token = opts.stop.clone();
    let _ = ctrlc::set_handler(move || token.stop());
    let summary = run_scene(&scene, &opts).map_err(|e| match e {
        crate::driver::RunError::Interrupted { .. } => {
            Failure::Interrupted(format!("{e}; outputs in {}", out.display()))
        }
        e => Failure::Run(anyhow::Error::new(e).context(format!(
            "run of {} failed (outputs written to {})",
            path.display(),
            out.display()
        ))),
    })?;
    for note in &summary.notes {
        println!("note: {note}");
    }
    println!(
        "done: {} particles, {} steps to t = {:.4} s in {:.1} s ({:.3e} particle-steps/s); max speed {:.3e} m/s; escaped {}; outputs in {}",
        summary.particles,
        summary.steps,
        summary.sim_time,
        summary.wall_time_s,
        summary.particle_steps_per_s,
        summary.max_speed,
        summary.escaped_particles,
        out.display()
    );
    if let Some(r) = &summary.runout {
        println!(
            "runout: R0 = {:.4} m, a = {:.2}, R∞ = {:.4} m, (R∞ − R0)/R0 = {:.3} (Lube et al. 2004: {:.3})",
            r.initial_radius, r.aspect_ratio, r.final_radius, r.normalized, r.lube_2004
        );
    }
    Ok(())
}
