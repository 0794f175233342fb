//! Axisymmetric granular column collapse against Lube et al. (2004): the normalised runout
//! (R∞ − R0)/R0 is 1.24 a for a ≲ 1.7 and 1.6 a^(1/2) above. One cohesionless Drucker–Prager
//! material (the example scenes), two aspect ratios, ±15 %.
//!
//! Also checks what must hold in any collapse: mass conserved exactly, nothing escapes, no NaN,
//! and cohesionless soil never carries tension.

use crate::common;

use regolith::run::{RunOptions, run_scene};

fn collapse(scene_file: &str, a: f64, sets: &[&str]) {
    let scene = common::example(scene_file, sets);
    let out = common::out_dir(scene_file);
    let summary = run_scene(&scene, &RunOptions::quiet(out.clone())).expect("run succeeds");
    let r = summary.runout.as_ref().expect("a column scene reports its runout");
    assert!((r.aspect_ratio - a).abs() < 1e-9);
    let lube = if a <= 1.7 { 1.24 * a } else { 1.6 * a.sqrt() };
    let err = (r.normalized - lube) / lube;
    eprintln!(
        "{scene_file}: (R∞ − R0)/R0 = {:.3} vs Lube {lube:.3} ({:+.1} %), {} particles, {} steps, {:.1} s",
        r.normalized,
        100.0 * err,
        summary.particles,
        summary.steps,
        summary.wall_time_s
    );
    assert!(err.abs() <= 0.15, "runout {:.3} vs Lube et al. 2004 {lube:.3}: {:+.1} %", r.normalized, 100.0 * err);
    assert_eq!(summary.escaped_particles, 0);
    assert_eq!(summary.mass_final, summary.mass_initial, "mass must be conserved exactly");
    assert!(!summary.nan_detected && summary.error.is_none());
    // The deposit has come to rest.
    assert!(summary.max_speed < 0.1, "still moving at {} m/s", summary.max_speed);
    // Tension-free: p ≥ 0 for every particle (CSV column 7).
    let csv = std::fs::read_to_string(out.join("particles_final.csv")).expect("csv");
    let mut n = 0;
    for line in csv.lines().skip(1) {
        let p: f64 = line.split(',').nth(6).and_then(|v| v.parse().ok()).expect("p column");
        assert!(p >= 0.0, "tensile mean stress {p} Pa in cohesionless soil");
        n += 1;
    }
    assert_eq!(n, summary.particles);
}

#[test]
fn squat_column_a1_matches_lube() {
    collapse("column_collapse.toml", 1.0, &[]);
}

#[test]
fn tall_column_a3_matches_lube() {
    // At d0 = 17.7 mm (R0/d0 = 5.7) rather than the scene's 10 mm, so that the suite stays
    // within CI's time (about a sixth of the cost of 12.5 mm). The accuracy study's ladder
    // (docs/accuracy/, case column_a3, the same scene) puts this level at −1.6 % and 12.5 mm at
    // +7.7 %: the coarse level is not the lucky one alone. The scene as shipped is the README's
    // figure.
    collapse("column_collapse_tall.toml", 3.0, &["sph.spacing=0.017678"]);
}
