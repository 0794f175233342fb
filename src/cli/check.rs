//! `regolith check`.

use std::path::Path;

use super::Failure;
use crate::scene::{describe, load_scene};

pub(super) fn run(path: &Path, sets: &[(String, toml::Value)]) -> Result<(), Failure> {
    let scene = load_scene(path, sets)?;
    print!("{}", describe(&scene));
    match scene.precision {
        crate::scene::Precision::F32 => print_built::<f32>(&scene)?,
        crate::scene::Precision::F64 => print_built::<f64>(&scene)?,
    }
    println!("ok: the scene is valid");
    Ok(())
}

/// Builds the scene on the CPU backend in its precision and prints what a run's cost and
/// memory follow: with an active region, how many particles it integrates at the start; then,
/// after one soil step (so that the neighbour lists exist), the bytes the solver's arrays
/// reserve per particle, by kind.
fn print_built<T: regolith_fsi::Real>(scene: &crate::scene::Scene) -> Result<(), Failure> {
    let mut cpu = scene.clone();
    cpu.backend = crate::scene::Backend::Cpu;
    let mut a = crate::build::assemble::<T>(&cpu).map_err(|e| Failure::from(anyhow::Error::new(e)))?;
    if scene.active.is_some() {
        print_active(scene, &a.system);
    }
    a.system.fluid.step(None).map_err(|e| Failure::from(anyhow::Error::new(e)))?;
    let fluid = &a.system.fluid;
    let Some(m) = fluid.as_cpu().map(|c| c.memory()) else { return Ok(()) };
    let (n, markers) = (fluid.len().max(1), fluid.marker_positions().len());
    let per = |b: usize| b as f64 / n as f64;
    println!(
        "  memory (CPU backend, {}, after one step): {:.0} B per particle ({:.1} MB for {} particles and {} markers, {:.2} markers per particle): particles {:.0} B, markers {:.0} B, neighbour lists {:.0} B, sorting {:.0} B",
        scene.precision.name(),
        per(m.total()),
        1e-6 * m.total() as f64,
        fluid.len(),
        markers,
        markers as f64 / n as f64,
        per(m.particles),
        per(m.markers),
        per(m.lists),
        per(m.sorting),
    );
    Ok(())
}

/// How many particles the active region integrates at the start of `system`.
fn print_active<T: regolith_fsi::Real>(scene: &crate::scene::Scene, system: &regolith_coupling::FsiSystem<T>) {
    let fluid = &system.fluid;
    let states = system.states_at(0.0);
    let roles = fluid.as_cpu().and_then(|c| c.expected_roles(&states));
    match roles {
        Some(r) => {
            let n = fluid.active().max(1);
            println!(
                "  active region at the start: {} awake ({:.1} % of {} particles), {} extended (frozen neighbours), {} asleep{}",
                r.awake,
                100.0 * r.awake as f64 / n as f64,
                fluid.active(),
                r.extended,
                r.asleep,
                match scene.active.map(|s| s.settings.free_flow_time) {
                    Some(t) if t > 0.0 => format!("; the whole domain is awake until t = {t} s"),
                    _ => String::new(),
                }
            );
        }
        None => println!("  active region: none (no FSI body): the whole domain is awake"),
    }
}
