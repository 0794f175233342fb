//! The command-line tool answers wrong input with one line and exit code 2, never a panic.

use std::path::PathBuf;
use std::process::Command;

fn regolith(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_regolith")).args(args).output().expect("run regolith");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn material(name: &str, text: &str) -> String {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_errors");
    std::fs::create_dir_all(&dir).expect("tmp");
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p.display().to_string()
}

fn assert_one_line_error(args: &[&str], contains: &str) {
    let (code, _out, err) = regolith(args);
    assert_eq!(code, 2, "exit code for {args:?}: stderr {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
    assert!(err.contains(contains), "{err} does not contain {contains}");
    assert!(!err.contains("panicked"), "{err}");
}

const CLAY: &str = "examples/materials/clay_mcc.toml";

#[test]
fn element_flag_errors_are_one_line() {
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "isotropic", "--p0", "-5", "--p-end", "1e5"],
        "--p0: must be > 0 Pa (got -5)",
    );
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "isotropic", "--p0", "5e4"],
        "--p-end: is required for a isotropic test",
    );
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "isotropic", "--p0", "5e4", "--axial-strain", "0.1"],
        "--axial-strain: does not apply to an isotropic test",
    );
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "drained-triaxial", "--p0", "5e4", "--axial-strain", "7"],
        "--axial-strain: must be in (0, 5]",
    );
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "isotropic", "--p0", "5e4", "--p-end", "1e5", "--p-unload", "2e5"],
        "--p-unload: must be in (0, --p-end = 100000) Pa (got 200000)",
    );
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "shear", "--p0", "5e4"],
        "invalid value 'shear' for '--test <TEST>'",
    );
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "isotropic", "--p0", "abc"],
        "invalid value 'abc' for '--p0 <PA>'",
    );
    assert_one_line_error(
        &["element", "--material", CLAY, "--test", "oedometer", "--p0", "5e4", "--ocr", "0.5", "--axial-strain", "0.1"],
        "--ocr: must be ≥ 1 (got 0.5)",
    );
    let dp = "examples/materials/sand_dp.toml";
    assert_one_line_error(
        &[
            "element",
            "--material",
            dp,
            "--test",
            "drained-triaxial",
            "--p0",
            "5e4",
            "--ocr",
            "2",
            "--axial-strain",
            "0.1",
        ],
        "--ocr: applies to model \"mcc\" only",
    );
    assert_one_line_error(
        &["element", "--material", "nope.toml", "--test", "isotropic", "--p0", "5e4", "--p-end", "1e5"],
        "nope.toml: cannot read:",
    );
}

#[test]
fn material_errors_reach_the_cli_as_one_line() {
    let m = material(
        "swapped.toml",
        "model = \"mcc\"\ndensity = 1700.0\nyoungs_modulus = 2e7\npoisson_ratio = 0.3\nmcc_m = 1.2\nmcc_kappa = 0.1\nmcc_lambda = 0.02\nmcc_v_lambda = 2.2\n",
    );
    assert_one_line_error(
        &["element", "--material", &m, "--test", "isotropic", "--p0", "5e4", "--p-end", "1e5"],
        ":7: key `mcc_lambda`: λ = 0.02 is smaller than κ = 0.1: they look swapped.",
    );
}

#[test]
fn element_writes_json_and_plots() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_element_out");
    let _ = std::fs::remove_dir_all(&out);
    let o = out.display().to_string();
    let (code, stdout, err) = regolith(&[
        "element",
        "--material",
        CLAY,
        "--test",
        "undrained-triaxial",
        "--p0",
        "1e5",
        "--axial-strain",
        "0.5",
        "--out",
        &o,
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("critical state (closed form)"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("element.json")).expect("json")).expect("valid json");
    for k in ["p", "q", "pc", "v", "eps_axial", "eps_vol"] {
        let arr = json[k].as_array().unwrap_or_else(|| panic!("array {k}"));
        assert_eq!(arr.len(), 2001, "{k}");
    }
    for k in ["p", "q", "pc", "v", "eps_axial", "eps_vol"] {
        assert!(json["final"][k].is_number(), "final.{k}");
    }
    for f in ["element.png", "element.svg"] {
        let len = std::fs::metadata(out.join(f)).expect(f).len();
        assert!(len > 10_000, "{f} is only {len} bytes");
    }
    // The PNG decodes as an image with the expected size.
    let png = std::fs::read(out.join("element.png")).expect("png");
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn calibrate_mcc_writes_a_material_that_loads_and_names_bad_data_in_one_line() {
    // Exact rows: recompression at κ = 0.02 to p_c0 = 40 kPa, the NCL (λ = 0.1, v_λ = 2.3),
    // an unload at κ.
    let ncl = |p: f64| 2.3 - 0.1 * (p / 1000.0f64).ln();
    let mut rows = String::from("# isotropic test\np,e\n");
    for p in [20e3f64, 25e3, 30e3, 35e3] {
        rows += &format!("{p},{}\n", ncl(40e3) + 0.02 * (40e3 / p).ln() - 1.0);
    }
    for p in [40e3, 60e3, 90e3, 140e3, 200e3] {
        rows += &format!("{p},{}\n", ncl(p) - 1.0);
    }
    for p in [150e3f64, 100e3, 60e3] {
        rows += &format!("{p},{}\n", ncl(200e3) + 0.02 * (200e3 / p).ln() - 1.0);
    }
    let iso = material("iso.csv", &rows);
    let crit = material("crit.csv", "p,q\n50e3,60e3\n100e3,120e3\n");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_calibrate_out");
    let _ = std::fs::remove_dir_all(&out);
    let o = out.display().to_string();
    let (code, stdout, err) =
        regolith(&["calibrate", "mcc", "--isotropic", &iso, "--critical", &crit, "--base", CLAY, "--out", &o]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("OCR = 2.000"), "{stdout}");
    let m = regolith::material::load_material_file(&out.join("material.toml")).expect("the written material loads");
    let near = |a: Option<f64>, b: f64| (a.expect("key written") - b).abs() < 1e-9 * b;
    assert!(near(m.mcc_lambda, 0.1) && near(m.mcc_kappa, 0.02) && near(m.mcc_v_lambda, 2.3), "{m:?}");
    assert!(near(m.ocr, 2.0) && near(m.mcc_m, 1.2) && near(m.density, 1800.0), "{m:?}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("mcc.json")).expect("json")).expect("valid json");
    assert!((json["critical_state"]["phi_cs"].as_f64().expect("φ_cs") - 30.0).abs() < 1e-9);
    assert!(std::fs::metadata(out.join("isotropic.png")).expect("plot").len() > 10_000);
    // Wrong data: one line naming the file, the line and the column.
    let bad = material("bad.csv", "p,v\n1e4,2.0\n2e4,x\n");
    assert_one_line_error(&["calibrate", "mcc", "--isotropic", &bad, "--out", &o], "bad.csv:3: key `column v`");
    let nocol = material("nocol.csv", "p,w\n1e4,2.0\n");
    assert_one_line_error(&["calibrate", "mcc", "--isotropic", &nocol, "--out", &o], "columns needed: p, v, e");
    let flat = material("flat.csv", "p,v\n1e4,2.0\n2e4,1.9\n3e4,1.85\n4e4,1.82\n");
    assert_one_line_error(&["calibrate", "mcc", "--isotropic", &flat, "--out", &o], "κ cannot be fitted");
    assert_one_line_error(&["calibrate", "mcc", "--isotropic", &iso, "--critical", &bad, "--out", &o], "column q");
}

#[test]
fn calibrate_envelope_fits_c_and_phi_with_agx_field_names() {
    // Failure on τ = 2 kPa + σ tan 30°: σ1 = 3 σ3 + 2 c √3.
    let mut rows = String::from("sigma3,sigma1\n");
    for s3 in [5e3f64, 10e3, 20e3, 40e3] {
        rows += &format!("{s3},{}\n", 3.0 * s3 + 4e3 * 3.0f64.sqrt());
    }
    let tests = material("triaxial.csv", &rows);
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_envelope_out");
    let _ = std::fs::remove_dir_all(&out);
    let o = out.display().to_string();
    let (code, stdout, err) = regolith(&["calibrate", "envelope", "--tests", &tests, "--out", &o]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("φ = 30.000°"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("envelope.json")).expect("json")).expect("valid json");
    assert!((json["c"].as_f64().expect("c") - 2000.0).abs() < 1e-6, "{json}");
    assert!((json["phi"].as_f64().expect("phi") - 30.0).abs() < 1e-9);
    assert!(json["standardError_c"].as_f64().expect("se") < 1e-6);
    assert_eq!(json["consolidationStress"].as_array().expect("array").len(), 4);
    assert_eq!(json["verticalStress"].as_array().expect("array").len(), 4);
    assert!(std::fs::metadata(out.join("mohr.svg")).expect("plot").len() > 10_000);
    let bad = material("tx_bad.csv", "sigma3,sigma1\n5e3,4e3\n1e4,3e4\n");
    assert_one_line_error(
        &["calibrate", "envelope", "--tests", &bad, "--out", &o],
        "failure needs 0 ≤ sigma3 < sigma1",
    );
    let one = material("tx_one.csv", "sigma3,sigma1\n5e3,2e4\n");
    assert_one_line_error(&["calibrate", "envelope", "--tests", &one, "--out", &o], "at least 2 tests");
}

#[test]
fn sweep_flag_errors_are_one_line() {
    let scene = "examples/scenes/single_wheel.toml";
    let t = ["--runner", "threads"];
    let with = |extra: &[&'static str]| [&["sweep", scene][..], extra, &t[..]].concat();
    assert_one_line_error(&with(&[]), "--vary: a sweep needs at least one --vary key=values");
    assert_one_line_error(&with(&["--vary", "rig.slips"]), "--vary: `rig.slips` is not key=values");
    assert_one_line_error(&with(&["--vary", "a=1:2"]), "a grid needs listed values");
    assert_one_line_error(&with(&["--vary", "a=1,,2"]), "a: empty value");
    assert_one_line_error(&with(&["--vary", "a=1,2,1"]), "--vary: a: value 1 is listed twice (each point must differ)");
    assert_one_line_error(&with(&["--vary", "a=1", "--vary", "a=2"]), "a is varied twice");
    assert_one_line_error(&with(&["--vary", "a=1", "--set", "a=2"]), "a is both --set and --vary");
    assert_one_line_error(&with(&["--vary", "a=1", "--design", "lhs"]), "--samples: is required with --design lhs");
    assert_one_line_error(&with(&["--vary", "a=1", "--samples", "4"]), "--samples: applies to --design lhs only");
    assert_one_line_error(&with(&["--vary", "a=1", "--shard", "3/2"]), "--shard: `3/2` is not i/n");
    assert_one_line_error(&with(&["--vary", "a=1", "--num-gpus", "1"]), "--num-gpus: applies to --runner ray only");
    assert_one_line_error(&with(&["--vary", "a=1", "--jobs", "0"]), "--jobs: must be at least 1");
    assert_one_line_error(&["sweep", "examples/scenes/missing.toml", "--vary", "a=1"], "missing.toml: cannot read");
    let empty = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("empty-sweep");
    std::fs::create_dir_all(&empty).expect("tmp");
    assert_one_line_error(&["sweep", "merge", &empty.display().to_string()], "holds no results.jsonl");
    let e = empty.display().to_string();
    assert_one_line_error(&["sweep", "converge", &e, "--metric", "runout.runout_m"], "holds no results.jsonl");
    // The Ray runner without a Python to run it: one line saying what to do.
    let out = Command::new(env!("CARGO_BIN_EXE_regolith"))
        .args(["sweep", scene, "--vary", "rig.slips=0.2"])
        .env("REGOLITH_PYTHON", "/nonexistent/python3")
        .output()
        .expect("run regolith");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("cannot start /nonexistent/python3") && err.contains("--runner threads"), "{err}");
}

#[test]
fn calibrate_repose_flags_and_materials_are_checked_before_running() {
    let o = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_repose_out").display().to_string();
    let sand = "examples/materials/sand_dp.toml";
    assert_one_line_error(
        &["calibrate", "repose", "--material", sand, "--radius", "0.1", "--spacing", "0.05", "--out", &o],
        "--spacing: 0.05 m leaves fewer than 4 spacings",
    );
    assert_one_line_error(
        &["calibrate", "repose", "--material", sand, "--lift-speed", "0", "--out", &o],
        "--lift-speed: must be a finite number > 0",
    );
    assert_one_line_error(&["calibrate", "repose", "--material", sand, "--cells", "2", "--out", &o], "--cells");
    assert_one_line_error(
        &["calibrate", "repose", "--material", sand, "--set", "sph.artificial_viscosity=-1", "--out", &o],
        "sph.artificial_viscosity`: must be in [0, 5] (got -1) (value from --set)",
    );
    assert_one_line_error(
        &["calibrate", "repose", "--material", sand, "--set", "sph.spacing=0.02", "--out", &o],
        "--set: `sph.spacing` is the test's own (sph.spacing): set it with --spacing",
    );
    let bad = material(
        "repose_bad.toml",
        "model = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 1e6\npoisson_ratio = 0.7\nfriction_angle = 30\n",
    );
    assert_one_line_error(&["calibrate", "repose", "--material", &bad, "--out", &o], "poisson_ratio");
    assert_one_line_error(
        &["calibrate", "repose", "--material", "no/such/file.toml", "--out", &o],
        "no/such/file.toml",
    );
}

#[test]
fn calibrate_triaxial_flags_and_materials_are_checked_before_running() {
    let o = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_triaxial_out").display().to_string();
    let sand = "examples/materials/sand_dp.toml";
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--width", "0.1", "--spacing", "0.05", "--out", &o],
        "--spacing: 0.05 m leaves fewer than 4 spacings",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--confining", "5e3,-1", "--out", &o],
        "--confining: must be one or more stresses > 0 Pa",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--max-strain", "0.7", "--out", &o],
        "--max-strain: must lie in (0, 0.3]",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--filter", "butterworth", "--filter-order", "0", "--out", &o],
        "--filter-order: must be 1 to 8",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--filter-order", "4", "--out", &o],
        "--filter-order: applies to --filter butterworth only",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--match", "plates", "--out", &o],
        "--match: applies to --target-phi or --target-c only",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--target-phi", "95", "--out", &o],
        "--target-phi",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--target-phi", "30", "--confining", "5e3,1e4", "--out", &o],
        "--confining: --target-phi needs at least three confining stresses",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--servo-crossings", "0", "--out", &o],
        "--servo-crossings",
    );
    // --target-c: a cohesion ≥ 0, a tolerance > 0, three tests, a Drucker–Prager material, and
    // not on Ray (its rounds depend on each other).
    assert_one_line_error(&["calibrate", "triaxial", "--material", sand, "--target-c=-5", "--out", &o], "--target-c");
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--target-c", "2e3", "--confining", "5e3,1e4", "--out", &o],
        "--confining: --target-c needs at least three confining stresses",
    );
    assert_one_line_error(
        &[
            "calibrate",
            "triaxial",
            "--material",
            sand,
            "--target-phi",
            "30",
            "--target-c",
            "2e3",
            "--tolerance-c",
            "0",
            "--out",
            &o,
        ],
        "--tolerance-c: must be > 0 Pa",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", CLAY, "--target-c", "2e3", "--out", &o],
        "--target-c adjusts `cohesion`, a key of drucker-prager materials only",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--target-c", "2e3", "--runner", "ray", "--out", &o],
        "--target-c: its rounds run one after another",
    );
    let bad = material(
        "triaxial_bad.toml",
        "model = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = -1e6\npoisson_ratio = 0.3\nfriction_angle = 30\n",
    );
    assert_one_line_error(&["calibrate", "triaxial", "--material", &bad, "--out", &o], "youngs_modulus");
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", "no/such/file.toml", "--out", &o],
        "no/such/file.toml",
    );
    // calibrate plate: a scene without a plate rig, one size.
    assert_one_line_error(
        &["calibrate", "plate", "--scene", "examples/scenes/cone_penetrometer.toml", "--out", &o],
        "calibrate plate needs a plate rig",
    );
    assert_one_line_error(
        &["calibrate", "plate", "--scene", "examples/scenes/plate_sinkage.toml", "--sizes", "0.05", "--out", &o],
        "--sizes: needs two or more different plate sizes",
    );
    // The accuracy study always resumes: --resume would be a flag that does nothing.
    assert_one_line_error(
        &["study", "accuracy", "--resume", "--out", &o],
        "--resume: the accuracy study always resumes",
    );
    // The runner's flags: each belongs to one runner.
    assert_one_line_error(&["calibrate", "triaxial", "--material", sand, "--jobs", "0", "--out", &o], "--jobs");
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--address", "auto", "--out", &o],
        "--address: applies to --runner ray only",
    );
    assert_one_line_error(
        &["calibrate", "triaxial", "--material", sand, "--runner", "ray", "--jobs", "2", "--out", &o],
        "--jobs: applies to --runner threads only",
    );
    assert_one_line_error(
        &["study", "stability", "--runner", "ray", "--num-cpus", "0", "--out", &o],
        "--num-cpus: must be a number > 0",
    );
}

#[test]
fn bench_flags_that_do_not_apply_to_the_scene_are_one_line_errors() {
    assert_one_line_error(&["bench", "--scene", "column", "--particles", "5000"], "--particles");
    assert_one_line_error(&["bench", "--scene", "column", "--model", "mcc"], "applies to --scene block only");
    assert_one_line_error(&["bench", "--scene", "wheel-long", "--model", "dp"], "--model");
    assert_one_line_error(&["bench", "--scene", "column", "--active", "on"], "--active");
    assert_one_line_error(&["bench", "--particles", "10"], "--particles");
    assert_one_line_error(&["bench", "--scene", "rover-patch", "--active", "on"], "--active");
    assert_one_line_error(&["bench", "--scene", "rover-patch", "--skin", "0"], "--skin");
    assert_one_line_error(&["bench", "--scene", "rover-patch", "--patch", "1.5"], "--patch: must be at least 2 m");
    assert_one_line_error(
        &["bench", "--scene", "rover-patch", "--length", "4", "--patch", "4"],
        "shorter than --length",
    );
    assert_one_line_error(
        &["bench", "--scene", "column", "--patch", "3"],
        "applies to --scene wheel-long or rover-patch",
    );
    assert_one_line_error(&["bench", "--scene", "rover-patch", "--backend", "wgpu"], "--backend: rover-patch times");
    assert_one_line_error(&["bench", "--scene", "wheel-long", "--precision", "f64"], "--precision: wheel-long");
    assert_one_line_error(
        &["bench", "--scene", "wheel-long", "--backend", "wgpu", "--skin", "0.3"],
        "--skin: the wgpu backend rebuilds",
    );
}

/// The wheel-long bench with `--patch` times the patch alone and with the active region inside
/// it, after the whole bed without and with it, and runs on wgpu too (the moving patch and the
/// active region have device twins): one exchange each on a 3 m bed, the same wheel force in
/// every run (the wheel has met no laid soil yet).
#[test]
fn the_wheel_long_bench_times_a_patch_with_and_without_the_active_region_on_wgpu() {
    let args = [
        "bench",
        "--scene",
        "wheel-long",
        "--backend",
        "wgpu",
        "--length",
        "3",
        "--patch",
        "2.5",
        "--steps",
        "1",
        "--warmup",
        "0",
    ];
    let (code, stdout, err) = regolith(&args);
    assert_eq!(code, 0, "{err}");
    let runs: Vec<&str> = stdout.lines().filter(|l| l.starts_with("bench wheel-long wgpu")).collect();
    assert_eq!(runs.len(), 4, "the whole bed and the patch, each without and with the active region: {stdout}");
    assert!(runs[2].contains("active off patch 2.5 m") && runs[3].contains("active on  patch 2.5 m"), "{stdout}");
    let force = |l: &str| l.split("wheel force").nth(1).and_then(|f| f.split(" (").next()).map(str::to_string);
    assert!(runs.iter().all(|r| force(r) == force(runs[0]) && force(r).is_some()), "same wheel force: {stdout}");
}

/// The rover-patch bench runs the example rover on the whole bed and on a patch, in one run:
/// the patch holds the particles, markers and memory of its own length, not the bed's (two
/// timed exchanges each: the figures belong in BENCHMARKS.md).
#[test]
fn the_rover_patch_bench_holds_the_patch_not_the_bed() {
    let json = std::env::temp_dir().join(format!("regolith-rover-bench-{}.json", std::process::id()));
    let j = json.to_string_lossy().to_string();
    let args = ["bench", "--scene", "rover-patch", "--length", "4", "--patch", "2", "--steps", "2", "--warmup", "0"];
    let (code, stdout, err) = regolith(&[&args[..], &["--json", &j]].concat());
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("bench rover-patch: patch 2 m against the whole 4 m bed: speed-up"), "{stdout}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parse");
    let _ = std::fs::remove_file(&json);
    let (whole, patch) = (&v[0], &v[1]);
    assert!(whole["patch"].is_null() && patch["patch"] == 2.0, "{v}");
    let n = |r: &serde_json::Value, k: &str| r[k][1].as_f64().expect(k);
    // The soil and the floor and side walls scale with the length along x (2 m of 4 m); the
    // rover's markers and the end walls do not.
    for k in ["particles", "solver_bytes"] {
        let ratio = n(patch, k) / n(whole, k);
        assert!(ratio > 0.45 && ratio < 0.6, "{k}: patch/whole = {ratio}");
    }
    assert!(patch["markers"].as_f64() < whole["markers"].as_f64(), "{v}");
    // Both start the rover at the same place.
    assert_eq!(whole["chassis_x"][0], patch["chassis_x"][0]);
}

/// The column bench builds its 67 626-particle column and reports dt and the simulated time
/// per wall second (one timed step: the figure itself belongs in BENCHMARKS.md).
#[test]
fn the_column_bench_reports_its_particles_dt_and_simulated_rate() {
    let json = std::env::temp_dir().join(format!("regolith-column-bench-{}.json", std::process::id()));
    let j = json.to_string_lossy().to_string();
    let (code, stdout, err) = regolith(&["bench", "--scene", "column", "--steps", "1", "--warmup", "0", "--json", &j]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("bench column"), "{stdout}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parse");
    let r = &v[0];
    assert_eq!(r["scene"], "column");
    assert_eq!(r["particles"], 67_626);
    let dt = r["dt_mean"].as_f64().expect("dt");
    // The acoustic CFL step of E = 1 MPa sand at h = 9.36 mm is of order 1e-4 s.
    assert!(dt > 1e-5 && dt < 1e-3, "dt = {dt}");
    assert!(r["sim_s_per_wall_s"].as_f64().expect("rate") > 0.0);
    std::fs::remove_file(&json).ok();
}
