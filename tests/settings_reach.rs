//! Every `[simulation]` and `[sph]` setting a scene gives reaches the solver (issue 45, item
//! 1c): the GRC-1 study found `sph.free_surface = false` gave a bit-identical run, which is
//! the mark of a key that goes nowhere. Each key below, changed alone from a small scene (a
//! box resting on one end of a bed, so that the other end has a free surface, CPU), changes the run's particles bit for bit, stops it, or (for the
//! keys that only change how the same answer is computed) shows in the solver's settings.
//! A key that is set but could not matter is refused at load (`scene_errors`).

use crate::common;

use regolith::scene::Scene;
use regolith::sim::Simulation;
use regolith_fsi::Real;
use regolith_fsi::config::{FreeSurfaceStress, TimeStep};

const BASE: &str = "[simulation]\nend_time = 0.006\nprecision = \"f64\"\nexchange_interval = 0.001\n\n\
[sph]\nspacing = 0.02\n\n\
[[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
[container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.2, 0.2]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.08\n\n\
[[bodies]]\nname = \"box\"\nshape = { type = \"box\", size = [0.08, 0.08, 0.04] }\nmass = 2.0\nposition = [0.1, 0.1, 0.11]\n";

/// The scene with `extra` lines added at the end of `[section]` (or replacing `from` by `to`).
fn with(section: &str, extra: &str) -> String {
    let head = format!("[{section}]\n");
    assert!(BASE.contains(&head), "{section}");
    BASE.replace(&head, &format!("{head}{extra}\n"))
}

/// Every particle's position and stress and the box's position after the run, as bits.
fn run<T: Real>(scene: &Scene) -> Result<Vec<u64>, String> {
    let mut sim = Simulation::<T>::new(scene).map_err(|e| e.to_string())?;
    while sim.time() < scene.end_time - 1e-12 {
        sim.step().map_err(|e| e.to_string())?;
    }
    let f = &sim.system.fluid;
    let mut bits: Vec<u64> = Vec::new();
    for (x, s) in f.positions().iter().zip(f.stresses()) {
        bits.extend(x.as_f64().iter().chain(s.as_f64().iter()).map(|v| v.to_bits()));
    }
    let b = sim.body("box").expect("box");
    bits.extend(sim.body_state(b).com.iter().map(|v| v.to_bits()));
    Ok(bits)
}

fn run_text(text: &str) -> Result<Vec<u64>, String> {
    let scene = common::scene(text);
    match scene.precision {
        regolith::scene::Precision::F32 => run::<f32>(&scene),
        regolith::scene::Precision::F64 => run::<f64>(&scene),
    }
}

#[test]
fn each_simulation_and_sph_key_changes_the_run_it_should() {
    let base = run_text(BASE).expect("base runs");
    // Keys whose change must change the particles (or the box) bit for bit.
    let changes = [
        ("simulation", "dt = 2e-5"),
        ("simulation", "cfl = 0.1"),
        ("simulation", "max_dt = 2e-5"),
        ("simulation", "gravity = [0.0, 0.0, -5.0]"),
        ("sph", "h_factor = 1.5"),
        ("sph", "kernel = \"cubic\""),
        ("sph", "artificial_viscosity = 0.5"),
        ("sph", "shifting = \"none\""),
        ("sph", "shifting = \"ppst\""),
        ("sph", "xsph_epsilon = 0.5"),
        ("sph", "free_surface_stress = \"zero\""),
        ("sph", "bce_layers = 2"),
        ("sph", "body_markers = \"inset\""),
    ];
    let mut unchanged = Vec::new();
    for (section, line) in changes {
        let got = run_text(&with(section, line)).unwrap_or_else(|e| panic!("{section}.{line}: {e}"));
        if got == base {
            unchanged.push(format!("{section}: {line}"));
        }
    }
    // Whole-scene keys: precision and spacing change the particle count or their type.
    let f32_run = run_text(&BASE.replace("precision = \"f64\"", "precision = \"f32\"")).expect("f32");
    if f32_run == base {
        unchanged.push("simulation: precision = \"f32\"".into());
    }
    let coarse = run_text(&BASE.replace("spacing = 0.02", "spacing = 0.025")).expect("coarse");
    if coarse == base {
        unchanged.push("sph: spacing = 0.025".into());
    }
    let exchange =
        run_text(&BASE.replace("exchange_interval = 0.001", "exchange_interval = 0.0005")).expect("exchange");
    if exchange == base {
        unchanged.push("simulation: exchange_interval = 0.0005".into());
    }
    let longer = run_text(&BASE.replace("end_time = 0.006", "end_time = 0.008")).expect("longer");
    if longer == base {
        unchanged.push("simulation: end_time = 0.008".into());
    }
    // Keys that act only with another setting, tried with it (from a base that has it).
    let ppst = with("sph", "shifting = \"ppst\"");
    let ppst_base = run_text(&ppst).expect("ppst");
    for line in ["shifting_coefficient = 0.3", "free_surface_threshold = 0.3", "free_surface = false"] {
        let got = run_text(&ppst.replace("shifting = \"ppst\"", &format!("shifting = \"ppst\"\n{line}")))
            .unwrap_or_else(|e| panic!("sph.{line}: {e}"));
        if got == ppst_base {
            unchanged.push(format!("sph (with ppst): {line}"));
        }
    }
    let zero = with("sph", "free_surface_stress = \"zero\"");
    let zero_base = run_text(&zero).expect("zero");
    let line = "free_surface_threshold = 0.3";
    let got =
        run_text(&zero.replace("free_surface_stress = \"zero\"", &format!("free_surface_stress = \"zero\"\n{line}")))
            .unwrap_or_else(|e| panic!("sph.{line}: {e}"));
    if got == zero_base {
        unchanged.push(format!("sph (with zero surface stress): {line}"));
    }
    assert!(unchanged.is_empty(), "settings that did not change the run: {unchanged:?}");
    // A runaway limit below the soil's speed stops a run (the run loop checks it; scripting
    // through `Simulation` steps on, see NOTES.md).
    let scene = common::scene(&with("simulation", "runaway_speed = 1e-6"));
    let stopped = regolith::run::run_scene(&scene, &regolith::run::RunOptions::quiet(common::out_dir("runaway_reach")));
    assert!(stopped.as_ref().is_err_and(|e| e.to_string().contains("runaway")), "{:?}", stopped.map(|_| ()));
}

#[test]
fn keys_that_change_how_not_what_reach_the_solver() {
    // The neighbour skin changes when lists are rebuilt, the active domain which particles
    // step: both are checked for their answer elsewhere (tests/verlet.rs, tests/active.rs);
    // here, that the setting arrives.
    let s = common::scene(&with("sph", "neighbor_skin = 0.0"));
    let sim = Simulation::<f64>::new(&s).expect("builds");
    assert_eq!(sim.system.fluid.config().neighbor_skin, 0.0);
    let s = common::scene(BASE);
    let sim = Simulation::<f64>::new(&s).expect("builds");
    assert!(sim.system.fluid.config().neighbor_skin > 0.0, "the default skin is on");
    assert!(matches!(sim.system.fluid.config().time_step, TimeStep::Adaptive { .. }));
    assert_eq!(sim.system.fluid.config().free_surface_stress, FreeSurfaceStress::Keep);
    // On a bed three times the box's reach long, part of it sleeps once the domain is kept.
    let wide = BASE.replace("max = [0.4, 0.2, 0.2]", "max = [0.8, 0.2, 0.2]");
    for (text, sleeps) in [(wide.clone(), false), (format!("{wide}\n[sph.active]\nenabled = true\n"), true)] {
        let mut sim = Simulation::<f64>::new(&common::scene(&text)).expect("builds");
        sim.step().expect("step");
        let f = &sim.system.fluid;
        assert_eq!(f.awake() < f.active(), sleeps, "awake {} of {}", f.awake(), f.active());
    }
}
