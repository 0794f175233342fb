//! `regolith calibrate plate`: a plate rig scene run at three plate sizes on the sweep runner,
//! Bekker's law fitted to the three curves together. The fit itself is verified against exact
//! and noisy synthetic curves in `rig::bekker` (parameters recovered exactly; standard errors
//! within 20 % of a Monte-Carlo spread); here the command's plumbing is: every size runs once
//! and is recorded, the report's curves are the runs' own, a resumed calibration runs nothing
//! and writes the same report, and a wrong input is one line before anything runs.
//!
//! The sample is sized to seconds (d0 = 1 cm under plates of 2–4 cm radius, pushed 1 cm at
//! 0.1 m/s), far too coarse for a usable k: docs/calibration.md has the worked example.

use std::path::PathBuf;

use regolith::calibrate::plate::{PlateInputs, calibrate_plate};

const SCENE: &str = r#"
[simulation]
end_time = 0.5
precision = "f32"
exchange_interval = 0.001

[sph]
spacing = 0.01

[[materials]]
name = "sand"
model = "drucker-prager"
density = 1600
youngs_modulus = 2e6
poisson_ratio = 0.3
friction_angle = 30
cohesion = 500

[container]
min = [0.0, 0.0, 0.0]
max = [0.2, 0.2, 0.12]

[terrain]
material = "sand"
depth = 0.06

[[bodies]]
name = "plate"
shape = { type = "cylinder", radius = 0.03, length = 0.01, axis = "z" }
mass = 1.0
position = [0.1, 0.1, 0.1]

[rig]
type = "plate"
body = "plate"
speed = 0.1
depth = 0.01
sizes = [0.02, 0.03, 0.04]

[output]
every = 0.05
mcap = false
"#;

fn inputs(name: &str, scene_text: &str, sizes: Vec<f64>, resume: bool) -> PlateInputs {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("plate_calibration").join(name);
    std::fs::create_dir_all(&dir).expect("tmp");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, scene_text).expect("write");
    PlateInputs { scene, sizes, sets: Vec::new(), out: dir.join("out"), jobs: 2, resume }
}

#[test]
fn three_plate_sizes_give_one_bekker_fit_and_a_resumed_calibration_runs_nothing() {
    let inp = inputs("three", SCENE, Vec::new(), false);
    let r = calibrate_plate(&inp).unwrap_or_else(|e| panic!("{e}"));
    let b = &r.bekker;
    eprintln!(
        "k_c = {:?} ± {:?}, k_φ = {:?} ± {:?}, n = {} ± {:?}, R² {}",
        b.kc, b.standard_error_kc, b.kphi, b.standard_error_kphi, b.n, b.standard_error_n, b.r2
    );
    assert_eq!(r.runs.iter().map(|p| p.b).collect::<Vec<_>>(), vec![0.02, 0.03, 0.04], "the rig's sizes, in order");
    assert_eq!(b.k_per_plate.len(), 3);
    assert!(b.kc.is_some() && b.kphi.is_some() && b.n.is_finite());
    for se in [b.standard_error_kc, b.standard_error_kphi, b.standard_error_n] {
        assert!(se.is_some_and(|s| s.is_finite() && s >= 0.0), "{se:?}");
    }
    // k_c and k_φ are the least-squares line through the plates' k against 1/b: the residuals
    // of that line sum to zero.
    let (kc, kphi) = (b.kc.unwrap_or(f64::NAN), b.kphi.unwrap_or(f64::NAN));
    let residual: f64 = b.k_per_plate.iter().map(|(w, k)| k - (kc / w + kphi)).sum();
    let scale: f64 = b.k_per_plate.iter().map(|(_, k)| k.abs()).sum();
    assert!(residual.abs() <= 1e-9 * scale, "residuals sum to {residual}");
    // Each run's curve is the one its own summary recorded.
    let records = regolith::sweep::read_all(&inp.out).expect("records");
    assert_eq!(records.len(), 3);
    for p in &r.runs {
        let rec = records.iter().find(|x| x.id == p.id).expect("recorded");
        let rig = &rec.summary.as_ref().expect("summary")["rig"]["runs"][0];
        assert_eq!(rig["b"].as_f64(), Some(p.b));
        assert_eq!(rig["max_pressure"].as_f64(), Some(p.max_pressure));
        assert!(p.command.contains("rig.sizes=[") && p.command.starts_with("regolith run "));
    }
    let report = std::fs::read_to_string(inp.out.join("bekker.json")).expect("bekker.json");
    assert!(inp.out.join("bekker.png").is_file() && inp.out.join("bekker.svg").is_file());
    // Resumed: every size is recorded, so nothing runs and the report is the same.
    let t0 = std::time::Instant::now();
    let again = calibrate_plate(&PlateInputs { resume: true, ..inp.clone() }).unwrap_or_else(|e| panic!("{e}"));
    assert!(t0.elapsed().as_secs_f64() < 5.0, "a recorded calibration ran again");
    assert_eq!(again.bekker, r.bekker);
    assert_eq!(std::fs::read_to_string(inp.out.join("bekker.json")).expect("bekker.json"), report);
}

#[test]
fn wrong_plate_calibrations_are_one_line_before_running() {
    let err = |inp: PlateInputs| calibrate_plate(&inp).map(|_| ()).map_err(|e| e.to_string()).expect_err("refused");
    // A scene without a rig.
    let bare = SCENE.replace(
        "[rig]\ntype = \"plate\"\nbody = \"plate\"\nspeed = 0.1\ndepth = 0.01\nsizes = [0.02, 0.03, 0.04]\n",
        "",
    );
    let e = err(inputs("not_plate", &bare, Vec::new(), false));
    assert!(e.contains("`rig.type`") && e.contains("calibrate plate needs a plate rig"), "{e}");
    let e = err(inputs("one_size", SCENE, vec![0.03, 0.03], false));
    assert!(e.contains("--sizes: needs two or more different plate sizes"), "{e}");
    let e = err(inputs("negative", SCENE, vec![0.03, -0.01], false));
    assert!(e.contains("--sizes: plate sizes must be > 0 m"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}
