//! Faults: a stop or a solver failure in the middle of a rig run leaves every output readable;
//! each run owns its stop token; a coupled run is bit-identical run to run; wrong study, soil
//! and step inputs are one-line errors.

use crate::common;

use regolith::driver::{Observer, RunError, RunStats, StopToken};
use regolith::fsi::Real;
use regolith::run::{RunOptions, run_scene, run_scene_observed};
use regolith::sim::Simulation;

const SAND: &str = "[[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n";

fn wheel_rig(sim: &str) -> String {
    format!(
        "[simulation]\n{sim}\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.01\n\n{SAND}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.36, 0.14, 0.25]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.05\n\n\
         [[bodies]]\nname = \"wheel\"\nshape = {{ type = \"wheel\", radius = 0.1, width = 0.08, grousers = 8, grouser_height = 0.01, grouser_thickness = 0.005 }}\nmass = 2.0\nposition = [0.18, 0.07, 0.3]\n\n\
         [rig]\ntype = \"wheel\"\nbody = \"wheel\"\nload = 40.0\nangular_velocity = 1.0\nslips = [0.2, 0.5]\n\n[output]\nevery = 0.002\n"
    )
}

/// Raises a stop token after a number of exchanges (what Ctrl-C does, at a known moment).
struct StopAfter(usize, StopToken);

impl<T: Real> Observer<T> for StopAfter {
    fn after_step(&mut self, _sim: &Simulation<T>, _stats: &RunStats) -> Result<(), RunError> {
        self.0 = self.0.saturating_sub(1);
        if self.0 == 0 {
            self.1.stop();
        }
        Ok(())
    }
}

fn summary(out: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary")).expect("json")
}

#[test]
fn an_interrupted_rig_run_keeps_its_series_summary_report_and_recording() {
    let scene = common::scene(&wheel_rig("end_time = 0.2"));
    let out = common::out_dir("faults_rig_interrupt");
    let opts = RunOptions::quiet(out.clone());
    let mut stopper = StopAfter(30, opts.stop.clone());
    let err = run_scene_observed(&scene, &opts, &mut stopper).expect_err("stopped");
    assert!(matches!(err, RunError::Interrupted { .. }), "{err}");
    let s = summary(&out);
    assert!(s["particles"].as_u64().unwrap_or(0) > 1000, "particles {}", s["particles"]);
    let t = s["sim_time"].as_f64().expect("time");
    assert!((t - 0.030).abs() < 1.5e-3, "stopped at {t} s, after 30 exchanges");
    // The report covers the run that was under way.
    let runs = s["rig"]["steady_state"].as_array().expect("rig report");
    assert_eq!(runs.len(), 1, "{runs:?}");
    assert!(runs[0]["drawbar_pull"].as_f64().is_some_and(f64::is_finite));
    let series = std::fs::read_to_string(out.join("series.csv")).expect("series");
    assert_eq!(series.lines().count(), 1 + 30, "header and 30 rows");
    let topics = common::read_validated(&out.join("recording.mcap"));
    // Frames every 2 ms over the 30 ms that ran.
    let n = topics["/rig/wheel"].len();
    assert!((14..=16).contains(&n), "{n} rig readings recorded");
}

#[test]
fn a_failed_rig_run_keeps_its_outputs_and_names_the_particle() {
    // A fixed step 3.4 times h / c, forced: the run blows up within a few steps. The first
    // check to catch it stops the run: soil faster than `runaway_speed` (since the density
    // floor, usually this one) or a non-finite value. Either way the report names the particle.
    let scene = common::scene(&wheel_rig("end_time = 0.2\ndt = 0.001\nallow_unstable_dt = true"));
    let out = common::out_dir("faults_rig_failure");
    let err = run_scene(&scene, &RunOptions::quiet(out.clone())).expect_err("fails");
    let line = err.to_string();
    let non_finite = matches!(err, RunError::Failed { .. });
    assert!(non_finite || matches!(err, RunError::Runaway { .. }), "{line}");
    for part in ["step ", "particle ", "material \"sand\"", "stress p = ", "p_c = "] {
        assert!(line.contains(part), "report lacks `{part}`: {line}");
    }
    let s = summary(&out);
    assert_eq!(s["nan_detected"], non_finite);
    assert_eq!(s["error"].as_str(), Some(line.as_str()));
    assert!(s["particles"].as_u64().unwrap_or(0) > 1000);
    assert!(s["rig"]["steady_state"].is_array(), "rig report written");
    assert!(out.join("series.csv").exists() && out.join("particles_final.csv").exists());
    common::read_validated(&out.join("recording.mcap"));
}

#[test]
fn each_run_owns_its_stop_token() {
    let text = format!(
        "[simulation]\nend_time = 0.01\nprecision = \"f32\"\n\n[sph]\nspacing = 0.01\n\n{SAND}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.06, 0.06, 0.06]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.03\n\n[output]\nmcap = false\n"
    );
    let scene = common::scene(&text);
    let first = RunOptions::quiet(common::out_dir("faults_stop_first"));
    first.stop.stop();
    let err = run_scene(&scene, &first).expect_err("stopped at once");
    assert!(matches!(err, RunError::Interrupted { time } if time == 0.0), "{err}");
    // A second scripted run in the same process is not stopped by the first one's token.
    let s = run_scene(&scene, &RunOptions::quiet(common::out_dir("faults_stop_second"))).expect("runs to the end");
    assert!((s.sim_time - 0.01).abs() < 1e-12);
}

#[test]
fn a_coupled_cpu_run_is_bit_identical_run_to_run() {
    let text = format!(
        "[simulation]\nend_time = 0.03\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.01\n\n{SAND}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.16, 0.16, 0.2]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.06\n\n\
         [[bodies]]\nname = \"ball\"\nshape = {{ type = \"sphere\", radius = 0.025 }}\ndensity = 7800\nposition = [0.08, 0.08, 0.1]\nmotion = {{ type = \"free\", velocity = [0.5, 0.0, -2.0] }}\n\n[output]\nmcap = false\n"
    );
    let scene = common::scene(&text);
    let mut files = Vec::new();
    for k in 0..2 {
        let out = common::out_dir(&format!("faults_determinism_{k}"));
        run_scene(&scene, &RunOptions::quiet(out.clone())).expect("runs");
        files.push(std::fs::read(out.join("particles_final.csv")).expect("particles"));
    }
    assert!(files[0].len() > 10_000);
    assert!(files[0] == files[1], "particles_final.csv differs between two identical runs");
}

fn rejected(name: &str, text: &str) -> String {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("faults");
    std::fs::create_dir_all(&dir).expect("tmp");
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).expect("write");
    let e = regolith::scene::load_scene(&p, &[]).expect_err("must be rejected").to_string();
    assert_eq!(e.lines().count(), 1, "{e}");
    e.replace(&p.display().to_string(), "FILE")
}

const BOX: &str = "[simulation]\nend_time = 0.1\n\n[sph]\nspacing = 0.01\n\n[[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n[container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.2, 0.2]\n";

#[test]
fn overlapping_soil_regions_are_refused() {
    let text = format!(
        "{BOX}\n[terrain]\nmaterial = \"sand\"\ndepth = 0.05\n\n[[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.04]\nmax = [0.1, 0.1, 0.1]\n"
    );
    // The lattice decides: the block and the bed both hold the points at z = 0.05.
    let scene = common::scene(&text);
    let e = Simulation::<f32>::new(&scene).err().expect("refused").to_string();
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains("soil_blocks[0] overlaps terrain (both hold the lattice point at ["), "{e}");
    assert!(e.contains("0.0500] m); soil regions must not overlap"), "{e}");
    // Touching is not overlapping; and a block beside a heightmap's low part is fine although
    // bounding boxes would overlap, so the check is on lattice points, not boxes.
    let ok = text.replace("min = [0.0, 0.0, 0.04]", "min = [0.0, 0.0, 0.05]");
    Simulation::<f32>::new(&common::scene(&ok)).expect("touching regions build");
}

#[test]
fn initial_velocities_start_the_soil_and_the_bodies_moving() {
    // A moving block beside a resting bed: the soil's momentum at t = 0 is exactly the block's
    // mass times its velocity.
    let text = format!(
        "{BOX}\n[terrain]\nmaterial = \"sand\"\ndepth = 0.05\n\n[[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.05, 0.05, 0.05]\nmax = [0.1, 0.1, 0.1]\nvelocity = [2.0, -1.0, 0.5]\n\n\
         [[bodies]]\nname = \"ball\"\nshape = {{ type = \"sphere\", radius = 0.01 }}\nmass = 0.1\nposition = [0.15, 0.15, 0.15]\nfsi = false\nmotion = {{ type = \"free\", velocity = [0.2, 0.0, 1.0] }}\n"
    );
    let scene = common::scene(&text);
    let mut sim = Simulation::<f64>::new(&scene).expect("builds");
    let f = &sim.system.fluid;
    let block_mass = 1600.0 * 0.05f64.powi(3);
    let moving: f64 = (0..f.len()).filter(|i| f.velocities()[*i].as_f64() != [0.0; 3]).map(|i| f.masses()[i]).sum();
    assert!((moving - block_mass).abs() < 1e-12, "{moving} kg moving, block {block_mass} kg");
    let p = f.momentum();
    for (k, v) in [2.0, -1.0, 0.5].iter().enumerate() {
        assert!((p[k] - block_mass * v).abs() < 1e-12, "axis {k}: {} vs {}", p[k], block_mass * v);
    }
    // The free ball (no markers) flies ballistically: x0 + v t + g t²/2, to rapier's
    // semi-implicit Euler error (g t dt / 2 in height) and its f32 round-off (1e-5 m here).
    let ball = sim.body("ball").expect("ball");
    while sim.time() < 0.05 - 1e-12 {
        sim.step().expect("step");
    }
    let t = sim.time();
    let c = sim.body_state(ball).com;
    assert!((c[0] - (0.15 + 0.2 * t)).abs() < 1e-5, "x {}", c[0]);
    let z = 0.15 + t - 0.5 * 9.81 * t * t;
    assert!((c[2] - z).abs() <= 0.5 * 9.81 * t * scene.exchange_interval + 1e-5, "z {} vs {z}", c[2]);
}

#[test]
fn a_fixed_step_above_the_stable_limit_is_refused_before_running() {
    let text = format!("{BOX}\n[terrain]\nmaterial = \"sand\"\ndepth = 0.05\n")
        .replace("end_time = 0.1", "end_time = 0.1\ndt = 0.001");
    let e = rejected("fixed_step", &text);
    assert!(e.contains("key `simulation.dt`: 1e-3 s is above the stable limit 0.5 h / c = 1.463e-4 s"), "{e}");
    assert!(e.contains("material \"sand\""), "{e}");
    let ok = text.replace("dt = 0.001", "dt = 0.0001");
    common::scene(&ok);
    let needless = text.replace("dt = 0.001", "dt = 0.0001\nallow_unstable_dt = true");
    assert!(rejected("needless_allow", &needless).contains("key `simulation.allow_unstable_dt`: is set but"));
}

#[test]
fn study_case_sections_are_checked() {
    use regolith::study::expect::read_case;
    let p = std::path::Path::new("case.toml");
    let base = "[[bodies]]\nname = \"ball\"\n\n[[expect]]\n";
    let e = |t: &str| read_case(p, &format!("{base}{t}")).expect_err("rejected").to_string();
    assert!(
        e("metric = \"speed\"\nmax = 1\nwhy = \"x\"")
            .contains("key `expect[0].metric`: \"speed\" is not a metric; allowed: max_soil_speed,")
    );
    assert!(e("metric = \"max_soil_speed\"\nmax = 1").contains("key `expect[0].why`: is required"));
    assert!(e("metric = \"max_soil_speed\"\nwhy = \"x\"").contains("needs a bound"));
    assert!(e("metric = \"body_z\"\nmax = 1\nwhy = \"x\"").contains("key `expect[0].body`: is required for body_z"));
    assert!(
        e("metric = \"body_z\"\nbody = \"cart\"\nmax = 1\nwhy = \"x\"")
            .contains("\"cart\" is not a body of this scene; bodies: ball")
    );
    assert!(e("metric = \"leaked\"\nmin = 2\nmax = 1\nwhy = \"x\"").contains("2 is above max = 1"));
    assert!(
        e("metric = \"leaked\"\nmax = 1\nwhy = \"x\"\n\n[study.huge]\nx = 1")
            .contains("key `study.huge`: is not a size")
    );
    let ok = read_case(p, &format!("{base}metric = \"body_depth\"\nbody = \"ball\"\nmin = 0.01\nwhy = \"it digs\"\n\n[study.ci]\n\"simulation.end_time\" = 0.1")).expect("valid");
    assert_eq!(ok.expect.len(), 1);
    assert!(ok.expect[0].holds(0.02) && !ok.expect[0].holds(0.0) && !ok.expect[0].holds(f64::NAN));
    assert_eq!(ok.sizes["ci"].len(), 1);
}

#[test]
fn every_hard_case_is_a_valid_case_and_scene() {
    use regolith::study::expect::{Metric, read_case};
    use regolith::study::stability::case_files;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/hard");
    let cases = case_files(&dir).expect("cases");
    assert!(cases.len() >= 16, "{} hard cases", cases.len());
    for (name, path) in cases {
        let text = std::fs::read_to_string(&path).expect("read");
        let spec = read_case(&path, &text).unwrap_or_else(|e| panic!("{e}"));
        let refused = spec.expect.iter().any(|x| x.metric == Metric::Refused);
        for size in ["ci", "full"] {
            let sets = spec.sizes.get(size).cloned().unwrap_or_default();
            match (regolith::scene::load_scene(&path, &sets), refused) {
                (Ok(_), false) | (Err(_), true) => {}
                (Ok(_), true) => panic!("{name} ({size}): accepted, but it expects a refusal"),
                (Err(e), false) => panic!("{name} ({size}): {e}"),
            }
        }
    }
}

#[test]
fn soil_thrown_out_of_the_domain_stops_the_run_loudly() {
    // A block shot upwards at 5 m/s leaves the open-topped container: once no soil is left in
    // the domain the run stops with a one-line error (its outputs kept) instead of stepping
    // on to the end time over nothing.
    let text = format!(
        "{BOX}\n[[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.08, 0.08, 0.12]\nmax = [0.12, 0.12, 0.16]\nvelocity = [0.0, 0.0, 5.0]\n"
    )
    .replace("end_time = 0.1", "end_time = 1.0");
    let scene = common::scene(&text);
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("faults_emptied");
    let e = run_scene(&scene, &RunOptions::quiet(&out)).expect_err("must stop");
    let msg = e.to_string();
    assert_eq!(msg.lines().count(), 1, "{msg}");
    let RunError::Emptied { particles, time, .. } = e else { panic!("not Emptied: {msg}") };
    assert_eq!(particles, 64, "4 × 4 × 4 lattice points at d0 = 1 cm");
    // It leaves through the top of the domain long before the end time (1 s).
    assert!(time > 0.0 && time < 0.2, "t = {time}");
    let s = summary(&out);
    assert_eq!(s["escaped_particles"], 64);
    assert!(s["error"].as_str().is_some_and(|m| m.contains("left the domain")), "{}", s["error"]);
}

#[test]
fn the_stability_suite_runs_on_the_shared_runner_and_resumes() {
    // Two cheap cases on two threads: each is one record of results.jsonl; a rerun with
    // --resume runs neither and writes the same table; without it both run again.
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("stability_batch");
    let _ = std::fs::remove_dir_all(&out);
    let run = |extra: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_regolith"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["study", "stability", "--cases", "fixed_step_refused,jet_at_wall", "--out"])
            .arg(&out)
            .args(extra)
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let first = run(&["--jobs", "2"]);
    assert!(first.contains("2 points, 0 already recorded, 2 to run on 2 thread(s)"), "{first}");
    let table = std::fs::read_to_string(out.join("stability.json")).expect("table");
    let records = regolith::sweep::read_all(&out).expect("records");
    assert_eq!(records.len(), 2);
    assert!(records.iter().all(|r| r.ok()));
    let resumed = run(&["--resume"]);
    assert!(resumed.contains("2 already recorded, 0 to run"), "{resumed}");
    assert_eq!(std::fs::read_to_string(out.join("stability.json")).expect("table"), table);
    let again = run(&[]);
    assert!(again.contains("0 already recorded, 2 to run"), "{again}");
}
