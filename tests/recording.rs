//! `recording.mcap`, plots and `regolith inspect`: the recording read back with the mcap crate
//! validates against the schemas embedded in it, its frame and point counts follow the
//! `[output]` section, a failed run still leaves a readable file, and every rig draws its plots.
#![cfg(feature = "mcap")]

use crate::common;

use std::path::Path;

use base64::Engine as _;
use regolith::run::{RunError, RunOptions, run_scene};

const SAND: &str = "[[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n";

fn bed(sim: &str, output: &str, extra: &str) -> String {
    format!(
        "[simulation]\n{sim}\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.01\n\n{SAND}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.12, 0.12, 0.15]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.05\n\n\
         [output]\n{output}\n\n{extra}"
    )
}

const BOX: &str = "[[bodies]]\nname = \"box\"\nshape = { type = \"box\", size = [0.04, 0.04, 0.02] }\nmass = 0.5\nposition = [0.06, 0.06, 0.08]\n";

/// Decoded point-cloud points: (x, y, z, p, q, pc, speed, material).
fn points(msg: &serde_json::Value) -> Vec<([f32; 7], u32)> {
    points_with_phase(msg).into_iter().map(|(v, m, _)| (v, m)).collect()
}

/// Decoded point-cloud points: (x, y, z, p, q, pc, speed), material, phase.
fn points_with_phase(msg: &serde_json::Value) -> Vec<([f32; 7], u32, u32)> {
    let stride = msg["point_stride"].as_u64().expect("stride") as usize;
    assert_eq!(stride, 36);
    let names: Vec<&str> =
        msg["fields"].as_array().expect("fields").iter().map(|f| f["name"].as_str().expect("name")).collect();
    assert_eq!(names, ["x", "y", "z", "p", "q", "pc", "speed", "material", "phase"]);
    let data = base64::engine::general_purpose::STANDARD.decode(msg["data"].as_str().expect("data")).expect("base64");
    assert_eq!(data.len() % stride, 0);
    data.chunks(stride)
        .map(|c| {
            let f = |k: usize| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().expect("4 bytes"));
            let u = |k: usize| u32::from_le_bytes(c[4 * k..4 * k + 4].try_into().expect("4 bytes"));
            ([f(0), f(1), f(2), f(3), f(4), f(5), f(6)], u(7), u(8))
        })
        .collect()
}

#[test]
fn a_recording_validates_and_follows_the_output_section() {
    // 0.04 s at a frame every 5 ms: frames at 0, 5, ..., 40 ms = 9; every 3rd particle.
    let scene = common::scene(&bed("end_time = 0.04", "every = 0.005\ndecimate = 3", BOX));
    let out = common::out_dir("recording_terrain");
    let summary = run_scene(&scene, &RunOptions::quiet(out.clone())).expect("runs");
    let topics = common::read_validated(&out.join("recording.mcap"));
    let count = |t: &str| topics.get(t).map_or(0, |v| v.len());
    assert_eq!(count("/terrain/particles"), 9);
    assert_eq!(count("/tf"), 9);
    assert_eq!(count("/bodies/wrench"), 9);
    assert_eq!(count("/bodies/shapes"), 1);
    // Frame times: the first exchange at or after each multiple of `every`.
    for (k, (t, _)) in topics["/terrain/particles"].iter().enumerate() {
        assert!((t - 0.005 * k as f64).abs() < 0.001 + 1e-9, "frame {k} at {t} s");
    }
    // Decimation by particle id: ids 0, 3, 6, ... of the N particles (none escaped).
    assert_eq!(summary.escaped_particles, 0);
    let expected = summary.particles.div_ceil(3);
    for (t, msg) in &topics["/terrain/particles"] {
        let pts = points(msg);
        assert_eq!(pts.len(), expected, "points at t = {t}");
        for (v, mat) in &pts {
            assert!(v.iter().all(|x| x.is_finite()) && *mat == 0);
            assert!((-0.001..0.121).contains(&v[0]) && (-0.001..0.151).contains(&v[2]), "point outside the box: {v:?}");
        }
    }
    // The body frame follows the body; the shape is its box, locked to that frame.
    let (_, last_tf) = topics["/tf"].last().expect("tf");
    let tf = &last_tf["transforms"][0];
    assert_eq!(tf["child_frame_id"], "box");
    assert_eq!(tf["parent_frame_id"], "world");
    let z = tf["translation"]["z"].as_f64().expect("z");
    assert!((summary.bodies[0].position[2] - z).abs() < 1e-9, "tf z {z} vs body {}", summary.bodies[0].position[2]);
    let shapes = &topics["/bodies/shapes"][0].1["entities"][0];
    assert_eq!(shapes["frame_id"], "box");
    assert_eq!(shapes["frame_locked"], true);
    assert_eq!(shapes["cubes"][0]["size"]["x"].as_f64(), Some(0.04));
    let (_, w) = topics["/bodies/wrench"].last().expect("wrench");
    let fz = w["bodies"][0]["force"]["z"].as_f64().expect("fz");
    assert!((fz - summary.bodies[0].fsi_force[2]).abs() < 1e-9);
    assert!(summary.outputs.iter().any(|o| o.ends_with("recording.mcap")));
}

#[test]
fn the_region_of_interest_keeps_only_the_points_inside_it() {
    let roi = "every = 0.01\nroi_min = [0.0, 0.0, 0.0]\nroi_max = [0.06, 0.12, 0.15]";
    let scene = common::scene(&bed("end_time = 0.01", roi, ""));
    let out = common::out_dir("recording_roi");
    let summary = run_scene(&scene, &RunOptions::quiet(out.clone())).expect("runs");
    let topics = common::read_validated(&out.join("recording.mcap"));
    assert_eq!(topics["/terrain/particles"].len(), 2);
    assert!(!topics.contains_key("/tf"), "no bodies, no frames");
    // A terrain-only run still writes its time series: the soil settling.
    let csv = std::fs::read_to_string(out.join("series.csv")).expect("series.csv");
    assert_eq!(csv.lines().next(), Some("time,soil.max_speed,soil.kinetic_energy"));
    assert_eq!(csv.lines().count(), 1 + 11, "a row at t = 0 and after each of the 10 exchanges");
    let first = points(&topics["/terrain/particles"][0].1);
    // Half the bed in x (the lattice is symmetric about x = 0.06: exactly half the columns).
    assert!(first.iter().all(|(v, _)| v[0] <= 0.06));
    let frac = first.len() as f64 / summary.particles as f64;
    assert!((frac - 0.5).abs() < 0.05, "ROI holds {frac} of the particles");
}

/// A wet scene's point cloud tells the phases apart: `phase` is 1 exactly on the water's
/// particles (material 1 here) and 0 on the soil's, and both are recorded.
#[test]
fn a_wet_recording_carries_the_phase_of_each_point() {
    let text = "[simulation]\nend_time = 0.004\nprecision = \"f64\"\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.01\n\n\
         [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\ngrain_density = 2650\n\
         permeability = 1e-3\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
         [[materials]]\nname = \"water\"\nmodel = \"water\"\ndensity = 1000\nsound_speed = 100\nviscosity = 1e-3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.06, 0.06, 0.1]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.04\n\n\
         [[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.06, 0.06, 0.06]\n\n\
         [output]\nevery = 0.002\n";
    let scene = common::scene(text);
    let out = common::out_dir("recording_wet");
    run_scene(&scene, &RunOptions::quiet(out.clone())).expect("runs");
    let topics = common::read_validated(&out.join("recording.mcap"));
    let (_, msg) = topics["/terrain/particles"].last().expect("a frame");
    let pts = points_with_phase(msg);
    let water = pts.iter().filter(|(_, _, phase)| *phase == 1).count();
    assert!(water > 0 && water < pts.len(), "{water} water points of {}", pts.len());
    for (_, material, phase) in &pts {
        assert_eq!(*phase, u32::from(*material == 1), "material {material} recorded as phase {phase}");
    }
}

#[test]
fn a_run_that_fails_midway_leaves_a_readable_recording() {
    // A fixed step ten times the CFL limit: the explicit scheme blows up after a few steps,
    // caught as a runaway speed or a non-finite value, whichever comes first.
    let scene = common::scene(&bed("end_time = 0.5\ndt = 0.001\nallow_unstable_dt = true", "every = 0.001", BOX));
    let out = common::out_dir("recording_failure");
    let err = run_scene(&scene, &RunOptions::quiet(out.clone())).expect_err("must fail");
    let non_finite = matches!(err, RunError::Failed { .. });
    assert!(non_finite || matches!(err, RunError::Runaway { .. }), "{err}");
    // The one-line report names the particle, its material, position, stress and p_c.
    let line = err.to_string();
    for part in ["particle ", "material \"sand\"", " at [", "stress p = ", "p_c = ", "step "] {
        assert!(line.contains(part), "report lacks `{part}`: {line}");
    }
    assert!(!line.contains('\n'), "{line}");
    let topics = common::read_validated(&out.join("recording.mcap"));
    let frames = topics["/terrain/particles"].len();
    assert!(frames >= 2, "frames before the failure: {frames}");
    assert_eq!(topics["/tf"].len(), frames);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary")).expect("json");
    assert_eq!(summary["nan_detected"], non_finite);
    let t_fail = summary["sim_time"].as_f64().expect("sim_time");
    let t_last = topics["/terrain/particles"].last().expect("frame").0;
    assert!(t_last <= t_fail + 1e-9 && t_fail - t_last < 0.0011, "last frame {t_last} s, failure at {t_fail} s");
}

fn assert_image(path: &Path) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if path.extension().is_some_and(|e| e == "svg") {
        let text = String::from_utf8(bytes).expect("svg is text");
        assert!(text.contains("<svg") && text.matches("<polyline").count() + text.matches("<path").count() > 0);
        return;
    }
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("png data");
    assert!(info.width >= 400 && info.height >= 300, "{}: {}x{}", path.display(), info.width, info.height);
    let px = &buf[..info.buffer_size()];
    let distinct: std::collections::BTreeSet<&[u8]> = px.chunks(3).collect();
    assert!(distinct.len() > 8, "{} looks blank ({} colours)", path.display(), distinct.len());
}

#[test]
fn every_rig_and_the_terrain_run_draw_their_plots() {
    let plate = "[[bodies]]\nname = \"plate\"\nshape = { type = \"cylinder\", radius = 0.03, length = 0.02, axis = \"z\" }\nmass = 1.0\nposition = [0.06, 0.06, 0.1]\n\n\
                 [rig]\ntype = \"plate\"\nbody = \"plate\"\nspeed = 0.1\ndepth = 0.01\n";
    let cone = "[[bodies]]\nname = \"cone\"\nshape = { type = \"cone\", radius = 0.02, height = 0.035 }\nmass = 0.5\nposition = [0.06, 0.06, 0.1]\n\n\
                [rig]\ntype = \"cone\"\nbody = \"cone\"\nspeed = 0.2\ndepth = 0.01\n";
    let wheel = "[[bodies]]\nname = \"wheel\"\nshape = { type = \"wheel\", radius = 0.03, width = 0.04, grousers = 8, grouser_height = 0.005, grouser_thickness = 0.004 }\nmass = 0.5\nposition = [0.04, 0.06, 0.1]\n\n\
                 [rig]\ntype = \"wheel\"\nbody = \"wheel\"\nload = 8.0\nangular_velocity = 2.0\nslips = [0.1, 0.5]\n";
    let cases = [
        ("plate", plate, "end_time = 0.1", vec!["plate_sinkage"], "/rig/plate"),
        ("cone", cone, "end_time = 0.05", vec!["cone_penetrometer"], "/rig/cone"),
        ("wheel", wheel, "end_time = 0.02", vec!["wheel_time", "wheel_slip"], "/rig/wheel"),
        ("terrain", "", "end_time = 0.01", vec!["deposit_profile"], ""),
    ];
    for (name, extra, sim, stems, rig_topic) in cases {
        let scene = common::scene(&bed(sim, "every = 0.005", extra));
        let out = common::out_dir(&format!("plots_{name}"));
        let summary = run_scene(&scene, &RunOptions::quiet(out.clone())).unwrap_or_else(|e| panic!("{name}: {e}"));
        for stem in stems {
            for ext in ["png", "svg"] {
                let p = out.join(format!("{stem}.{ext}"));
                assert!(summary.outputs.iter().any(|o| Path::new(o) == p), "{name}: {} not listed", p.display());
                assert_image(&p);
            }
        }
        if !rig_topic.is_empty() {
            let topics = common::read_validated(&out.join("recording.mcap"));
            let rig = &topics[rig_topic];
            assert_eq!(rig.len(), topics["/terrain/particles"].len(), "{name}: one rig message per frame");
            assert!(!topics["/bodies/shapes"].is_empty());
            if name == "wheel" {
                // Two slips, one after the other on one timeline, labelled.
                assert_eq!(topics["/bodies/shapes"].len(), 2);
                let runs: std::collections::BTreeSet<String> = rig.iter().map(|(_, m)| m["run"].to_string()).collect();
                assert_eq!(runs.len(), 2, "{runs:?}");
                assert!(rig.windows(2).all(|w| w[0].0 < w[1].0), "timeline must increase");
            }
        }
    }
}

#[test]
fn inspect_lists_topics_counts_and_the_time_range() {
    let scene = common::scene(&bed("end_time = 0.01", "every = 0.005", BOX));
    let out = common::out_dir("recording_inspect");
    run_scene(&scene, &RunOptions::quiet(out.clone())).expect("runs");
    let file = out.join("recording.mcap");
    let o =
        std::process::Command::new(env!("CARGO_BIN_EXE_regolith")).arg("inspect").arg(&file).output().expect("runs");
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("10 messages, t = 0.0000 .. 0.0100 s"), "{text}");
    let line = |topic: &str| text.lines().find(|l| l.trim_start().starts_with(topic)).unwrap_or_default().to_string();
    assert!(line("/terrain/particles").contains("       3 "), "{text}");
    assert!(line("/bodies/shapes").contains("foxglove.SceneUpdate"), "{text}");
    // Not a recording: one line, exit code 2.
    let bad = out.join("summary.json");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_regolith")).arg("inspect").arg(&bad).output().expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("summary.json") && err.contains("not a readable MCAP"), "{err}");
}

#[test]
fn the_embedded_schemas_reject_a_message_that_lacks_a_field() {
    use regolith::output::record::foxglove;
    let schema = jsonschema::validator_for(&foxglove::point_cloud_schema()).expect("compiles");
    let mut msg = foxglove::point_cloud(0.25, "world", &[0u8; 32]);
    assert!(schema.validate(&msg).is_ok());
    assert_eq!(msg["timestamp"], serde_json::json!({"sec": 0, "nsec": 250_000_000}));
    msg.as_object_mut().expect("object").remove("data");
    assert!(schema.validate(&msg).is_err());
    let tf = jsonschema::validator_for(&foxglove::frame_transforms_schema()).expect("compiles");
    let mut m = foxglove::frame_transforms(1.5, &[("wheel".into(), regolith_rigid::Pose::default())], &[]);
    assert!(tf.validate(&m).is_ok());
    m["transforms"][0]["rotation"]["w"] = serde_json::json!("one");
    assert!(tf.validate(&m).is_err());
}
