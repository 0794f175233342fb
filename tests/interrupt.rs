//! Ctrl-C: a run stopped by SIGINT finishes its outputs — a readable `recording.mcap` with the
//! frames so far, `summary.json` — and exits with code 130. (A test binary of its own: the stop
//! request is process-wide.)

use crate::common;

use std::time::{Duration, Instant};

const SCENE: &str = "[simulation]\nend_time = 30.0\nprecision = \"f32\"\n\n[sph]\nspacing = 0.01\n\n\
    [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
    [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.12, 0.12, 0.15]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.05\n\n\
    [output]\nevery = 0.002\n";

#[test]
fn sigint_stops_the_cli_run_with_its_outputs_written() {
    let out = common::out_dir("interrupt_cli");
    let scene = out.join("long.toml");
    std::fs::write(&scene, SCENE).expect("scene");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_regolith"))
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("starts");
    // Let it record a few frames (the file grows as chunks are written), then press Ctrl-C.
    let rec = out.join("recording.mcap");
    let start = Instant::now();
    while std::fs::metadata(&rec).map(|m| m.len()).unwrap_or(0) < 10_000 {
        assert!(start.elapsed() < Duration::from_secs(120), "the run did not start recording");
        std::thread::sleep(Duration::from_millis(100));
    }
    let pid = child.id().to_string();
    let kill = std::process::Command::new("kill").args(["-INT", &pid]).status().expect("kill");
    assert!(kill.success());
    let o = child.wait_with_output().expect("exits");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    let topics = common::read_validated(&rec);
    let frames = topics["/terrain/particles"].len();
    assert!(frames >= 2, "{frames} frames");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary")).expect("json");
    let t = summary["sim_time"].as_f64().expect("time");
    assert!(t > 0.0 && t < 30.0, "stopped at {t} s");
    let last = topics["/terrain/particles"].last().expect("frame").0;
    assert!((last - t).abs() <= 0.002 + 1e-9, "last frame {last} s, stop at {t} s");
}
