//! `regolith calibrate plate` and `cone`.
//!
//! Plate: a plate rig scene run at three plate sizes on the sweep runner,
//! Bekker's law fitted to the three curves together. The fit itself is verified against exact
//! and noisy synthetic curves in `rig::bekker` (parameters recovered exactly; standard errors
//! within 20 % of a Monte-Carlo spread); here the command's plumbing is: every size runs once
//! and is recorded, the report's curves are the runs' own, a resumed calibration runs nothing
//! and writes the same report, and a wrong input is one line before anything runs.
//!
//! The sample is sized to seconds (d0 = 1 cm under plates of 2–4 cm radius, pushed 1 cm at
//! 0.1 m/s), far too coarse for a usable k: docs/calibration.md has the worked example.
//!
//! Cone: the profile's layer means are the run's own cone index averaged over each layer, the
//! gradient is the least-squares line through them (verified exactly on a linear profile in
//! `calibrate::cone`), and a resumed calibration runs nothing.

use std::path::PathBuf;

use regolith::calibrate::cone::{ConeInputs, calibrate_cone};
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

const CONE: &str = r#"
[simulation]
end_time = 0.6
precision = "f32"
exchange_interval = 0.001

[sph]
spacing = 0.008

[[materials]]
name = "sand"
model = "drucker-prager"
density = 1600
youngs_modulus = 2e5
poisson_ratio = 0.3
friction_angle = 30.0

[container]
min = [0.0, 0.0, 0.0]
max = [0.08, 0.08, 0.1]

[terrain]
material = "sand"
depth = 0.05

[[bodies]]
name = "cone"
shape = { type = "cone", radius = 0.012, height = 0.02 }
mass = 0.5
position = [0.04, 0.04, 0.09]

[rig]
type = "cone"
body = "cone"
speed = 0.1
depth = 0.02

[output]
every = 0.1
mcap = false
"#;

fn cone_inputs(name: &str, text: &str, layer: f64, resume: bool) -> ConeInputs {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cone_calibration").join(name);
    std::fs::create_dir_all(&dir).expect("tmp");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).expect("write");
    ConeInputs { scene, sets: Vec::new(), layer, out: dir.join("out"), resume }
}

#[test]
fn a_cone_profile_averages_the_run_per_layer_and_resumes() {
    let inp = cone_inputs("profile", CONE, 0.005, false);
    let r = calibrate_cone(&inp).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("G = {:?} ± {:?}; layers {:?}", r.gradient, r.standard_error_gradient, r.layers);
    assert!(r.layers.len() >= 3, "{} layers of 5 mm over a 2 cm push", r.layers.len());
    for (k, l) in r.layers.iter().enumerate() {
        assert!((l.from - 0.005 * k as f64).abs() < 1e-12 && (l.to - l.from - 0.005).abs() < 1e-12);
    }
    // The layer means are the run's own cone index over each layer.
    let rec = regolith::sweep::read_all(&inp.out).expect("records").pop().expect("one record");
    let curve: Vec<(f64, f64)> = rec.summary.as_ref().expect("summary")["rig"]["curve"]
        .as_array()
        .expect("curve")
        .iter()
        .map(|c| (c["base_depth"].as_f64().expect("z"), c["cone_index"].as_f64().expect("ci")))
        .collect();
    for l in &r.layers {
        let v: Vec<f64> = curve.iter().filter(|c| c.0 >= l.from && c.0 < l.to).map(|c| c.1).collect();
        assert_eq!(v.len(), l.samples);
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        assert!((mean - l.cone_index).abs() <= 1e-9 * mean.abs(), "{mean} vs {}", l.cone_index);
    }
    assert!(r.gradient.is_some_and(|g| g > 0.0), "the cone index grows with depth in sand: {:?}", r.gradient);
    assert!(r.standard_error_gradient.is_some_and(f64::is_finite));
    assert!(inp.out.join("cone.json").is_file() && inp.out.join("cone_index.png").is_file());
    let t0 = std::time::Instant::now();
    let again = calibrate_cone(&ConeInputs { resume: true, ..inp.clone() }).unwrap_or_else(|e| panic!("{e}"));
    assert!(t0.elapsed().as_secs_f64() < 5.0, "a recorded cone run ran again");
    assert_eq!(again.layers, r.layers);
}

#[test]
fn wrong_cone_calibrations_are_one_line_before_running() {
    let err = |inp: ConeInputs| calibrate_cone(&inp).map(|_| ()).map_err(|e| e.to_string()).expect_err("refused");
    let e = err(cone_inputs("thick", CONE, 0.05, false));
    assert!(e.contains("--layer: 0.05 m is thicker than the push"), "{e}");
    let e = err(cone_inputs("zero", CONE, 0.0, false));
    assert!(e.contains("--layer: must be > 0 m"), "{e}");
    let e = err(cone_inputs("plate", SCENE, 0.005, false));
    assert!(e.contains("`rig.type`") && e.contains("calibrate cone needs a cone rig"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}
