//! Axisymmetric granular column collapse against Lube et al. (2004): the normalised runout
//! (R∞ − R0)/R0 is 1.24 a for a ≲ 1.7 and 1.6 a^(1/2) above. One cohesionless Drucker–Prager
//! material (the example scenes), two aspect ratios, ±15 %. And the plane-strain collapse of
//! Bui et al. (2008) (examples/study/bui_collapse.toml) between smooth side walls.
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

/// Bui et al. (2008)'s aluminium bars, 0.2 × 0.1 m, slumping along a rough floor between smooth
/// side walls (the accuracy case, at d0 = 10 mm, the coarsest level of its ladder: 32 s for
/// both runs at 2 test threads, against 113 s at 7.07 mm). The experiment (digitised profile
/// and failure line, see the case file): reach at a tenth of the height (x₁₀ − L0)/L0 = 0.842,
/// failure surface at 34.9°, the height at the wall unchanged. Measured here: 0.850 (+1.0 %)
/// and 28.6°, height at the wall 0.1046 m; the study's ladder (docs/accuracy) reads +1.0,
/// −4.4, +3.6, +2.4 % and 28.6°, 28.3°, 31.9°, 27.5° at 10, 7.07, 5 and 3.54 mm, and its knobs
/// at 5 mm scatter the reach over +2.0 to +7.6 %: the coarse level is not the lucky one alone.
/// The same run with rough side walls, the only walls a container had before
/// `{ floor, walls }`, reads 0.430 (−49 %) and 68.6° (0.484 and 53° at 7.07 mm): the walls
/// hold the soil, which is why a plane-strain test needs them smooth.
#[test]
fn bui_2008s_plane_strain_slump_runs_out_between_smooth_walls_and_is_held_by_rough_ones() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/study/bui_collapse.toml");
    let run = |contact: &str| {
        let sets: Vec<_> = ["sph.spacing=0.01".to_string(), format!("container.soil_contact={contact}")]
            .iter()
            .map(|s| regolith::scene::parse_set(s).expect("set"))
            .collect();
        let scene = regolith::scene::load_scene(&path, &sets).unwrap_or_else(|e| panic!("{e}"));
        let out = common::out_dir(&format!("bui_{}", contact.len()));
        let summary = run_scene(&scene, &RunOptions::quiet(out)).expect("run succeeds");
        assert!(!summary.nan_detected && summary.error.is_none());
        assert_eq!(summary.escaped_particles, 0);
        assert_eq!(summary.mass_final, summary.mass_initial, "mass must be conserved exactly");
        assert!(summary.max_speed < 0.05, "still moving at {} m/s", summary.max_speed);
        summary.slump.expect("a block against an end wall reports its slump")
    };
    let plane = run("{ floor = \"rough\", walls = \"smooth\" }");
    let held = run("\"rough\"");
    let angle = |s: &regolith::run::Slump| s.failure_angle_deg.expect("a failure surface");
    for (name, s) in [("smooth walls", &plane), ("rough walls", &held)] {
        eprintln!(
            "Bui 2008, {name}: (x10 − L0)/L0 = {:.3} (experiment 0.842), failure surface {:.1}° (34.9°) over {} rows, \
             99 % reach {:.3} m, height at the wall {:.4} m",
            s.reach_tenth_normalized,
            angle(s),
            s.failure_rows,
            s.final_length,
            s.final_height
        );
    }
    // Within 10 % of the experiment's reach (the knobs' scatter reaches 7.6 %) and 25 % of its
    // angle (measured −19 % here; the ladder's surfaces are 9–21 % shallower than the
    // experiment's, a miss refinement does not close).
    assert!(
        (plane.reach_tenth_normalized / 0.842 - 1.0).abs() < 0.1,
        "reach {:.3} vs 0.842",
        plane.reach_tenth_normalized
    );
    assert!((angle(&plane) / 34.9 - 1.0).abs() < 0.25, "failure surface {:.1}° vs 34.9°", angle(&plane));
    // The soil at the wall stays put, as in the experiment (the top layer's half spacing and
    // its elastic rebound aside).
    assert!((plane.final_height / 0.1 - 1.0).abs() < 0.05, "height at the wall {}", plane.final_height);
    // Rough side walls hold the slide: a shorter reach and a steeper failure surface.
    assert!(held.reach_tenth_normalized < 0.8 * plane.reach_tenth_normalized);
    assert!(angle(&held) > angle(&plane) + 10.0, "rough walls {:.1}° vs smooth {:.1}°", angle(&held), angle(&plane));
}
