//! Soil–body coupling: equilibrium, action = reaction, bearing capacity, cone and wheel
//! behaviour, and rigid bodies without markers behaving exactly as in rapier. (The hard cases
//! are the stability suite's: `examples/hard/`, `regolith study stability`.)

use crate::common;

use regolith::run::{RunOptions, run_scene};
use regolith::sim::Simulation;
use regolith_rigid::{BodyDesc, MassSpec, Motion, Pose, RigidWorld, ShapeDesc};

const SAND: &str = "[[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n";

fn bed(end_time: f64, size: [f64; 3], depth: f64, extra: &str) -> String {
    format!(
        "[simulation]\nend_time = {end_time}\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.01\n\n{SAND}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{}, {}, {}]\n\n[terrain]\nmaterial = \"sand\"\ndepth = {depth}\n\n{extra}",
        size[0], size[1], size[2]
    )
}

#[test]
fn a_box_resting_on_the_soil_is_carried_by_its_weight() {
    // Box bottom one spacing above the top particle (z = 0.07): in contact from the start. The
    // box bounces on the soil with a period of about 0.16 s (measured from its force, which
    // swings between 8 and 41 N); the mean over one period from t = 0.24 s is the static load.
    let body = "[[bodies]]\nname = \"box\"\nshape = { type = \"box\", size = [0.08, 0.08, 0.03] }\nmass = 2.5\nposition = [0.11, 0.11, 0.095]\n";
    let scene = common::scene(&bed(0.4, [0.22, 0.22, 0.18], 0.07, body));
    let mut sim = Simulation::<f32>::new(&scene).expect("builds");
    let b = sim.body("box").expect("box");
    let weight = 2.5 * 9.81;
    let (mut sum, mut n) = (0.0, 0.0);
    let mut z_start = None;
    while sim.time() < scene.end_time - 1e-9 {
        sim.step().expect("step");
        if sim.time() > 0.24 {
            sum += sim.fsi_wrench(b).force[2];
            n += 1.0;
            z_start.get_or_insert(sim.body_state(b).com[2]);
        }
    }
    let mean = sum / n;
    eprintln!(
        "mean vertical soil force {mean:.3} N, weight {weight:.3} N ({:+.2} %)",
        100.0 * (mean - weight) / weight
    );
    assert!((mean - weight).abs() / weight < 0.05, "vertical FSI force {mean} N vs weight {weight} N");
    // Neither sinking nor lifting over that period: under a tenth of a spacing.
    let dz = sim.body_state(b).com[2] - z_start.expect("sampled");
    assert!(dz.abs() < 1e-3, "the box moved {dz} m over one bounce period");
}

#[test]
fn the_soil_feels_exactly_the_opposite_of_what_the_bodies_feel() {
    // A sphere pushed sideways through the soil and a free box: the impulse each body's markers
    // exert on the soil is minus the time integral of the body's FSI force, and the soil's
    // momentum change is gravity plus all marker impulses.
    let bodies = "[[bodies]]\nname = \"ball\"\nshape = { type = \"sphere\", radius = 0.03 }\nmass = 1.0\nposition = [0.06, 0.11, 0.07]\nmotion = { type = \"prescribed\", linear_velocity = [0.2, 0.0, 0.0] }\n\n\
                  [[bodies]]\nname = \"box\"\nshape = { type = \"box\", size = [0.05, 0.05, 0.03] }\nmass = 1.0\nposition = [0.16, 0.11, 0.1]\n";
    let scene = common::scene(&bed(0.1, [0.22, 0.22, 0.18], 0.07, bodies));
    let mut sim = Simulation::<f64>::new(&scene).expect("builds");
    let p0 = sim.system.fluid.momentum();
    let mass = sim.system.fluid.total_mass();
    let mut body_impulse = [[0.0; 3]; 2];
    for _ in 0..60 {
        let t0 = sim.time();
        sim.step().expect("step");
        let dt = sim.time() - t0;
        for (k, imp) in sim.system.fsi_bodies().zip(body_impulse.iter_mut()) {
            let f = sim.system.wrench(k).force;
            for a in 0..3 {
                imp[a] += f[a] * dt;
            }
        }
    }
    let owner = sim.system.fluid.as_cpu().expect("cpu").owner_impulse();
    let scale = mass * 9.81 * sim.time();
    for k in 0..2 {
        for a in 0..3 {
            let diff = (owner[k + 1][a] + body_impulse[k][a]).abs();
            assert!(diff < 1e-9 * scale, "body {k} axis {a}: soil {} vs body {}", owner[k + 1][a], body_impulse[k][a]);
        }
    }
    assert!(body_impulse[0][0].abs() > 1e-3 * scale, "the ball must push the soil");
    let p1 = sim.system.fluid.momentum();
    let total = sim.system.fluid.as_cpu().expect("cpu").marker_impulse();
    for a in 0..3 {
        let expected = mass * scene.solver.gravity[a] * sim.time() + total[a];
        assert!(((p1[a] - p0[a]) - expected).abs() < 1e-9 * scale, "momentum balance axis {a}");
    }
}

#[test]
fn rough_plate_on_weightless_cohesive_soil_reaches_its_bearing_capacity() {
    // d0 = 12.5 mm (plate radius 4 d0) to keep CI short: 6.08 c there, 5.99 c at 10 mm.
    let text = "[simulation]\nend_time = 0.3\nprecision = \"f32\"\ngravity = [0.0, 0.0, 0.0]\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.0125\n\n\
                [[materials]]\nname = \"clay\"\nmodel = \"drucker-prager\"\ndensity = 1800\nyoungs_modulus = 3e6\npoisson_ratio = 0.3\nfriction_angle = 0.0\ncohesion = 5000.0\n\n\
                [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.3, 0.3, 0.2]\n\n[terrain]\nmaterial = \"clay\"\ndepth = 0.14\n\n\
                [[bodies]]\nname = \"plate\"\nshape = { type = \"cylinder\", radius = 0.05, length = 0.02, axis = \"z\" }\nmass = 1.0\nposition = [0.15, 0.15, 0.2]\n\n\
                [rig]\ntype = \"plate\"\nbody = \"plate\"\nspeed = 0.04\ndepth = 0.006\n";
    let scene = common::scene(text);
    let out = common::out_dir("bearing_capacity");
    let s = run_scene(&scene, &RunOptions::quiet(out)).expect("runs");
    let run = &s.rig.as_ref().expect("rig report")["runs"][0];
    let diameter = 0.1;
    let c = 5000.0;
    let qu = run["curve"]
        .as_array()
        .expect("curve")
        .iter()
        .filter(|p| p[0].as_f64().unwrap_or(1.0) <= 0.05 * diameter)
        .filter_map(|p| p[1].as_f64())
        .fold(0.0, f64::max);
    eprintln!("ultimate pressure {:.2} c", qu / c);
    assert!(
        (4.8..=7.0).contains(&(qu / c)),
        "ultimate pressure {:.2} c outside [4.8, 7.0] c (theory 5.7–6.1 c)",
        qu / c
    );
}

/// Issue 14, item 7: the plate case of the accuracy study (examples/study/plate_bearing.toml:
/// R = 5 cm, c = 2 kPa, E = 3 MPa, weightless) at d0 = 1 cm, read where a bearing test is read:
/// the mean pressure over sinkages 0.09–0.11 B, against Eason & Shield's 6.05 c for a rough
/// circle. With the markers d0/2 inside the plate (`body_markers = "inset"`) the soil meets
/// the plate's geometry: −6.0 % here (the study's ladder at R/d0 = 3.5, 5, 7: −2.7, −6.0,
/// +4.1 %). With the markers on its surface the plate acts as R + d0/2 and reads +13.9 %
/// (+7.5, +13.9, +18.8 % on the ladder), which the 10 % bound refuses.
#[test]
fn a_rough_plate_with_inset_markers_reads_eason_shield_at_a_tenth_of_its_width() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/study/plate_bearing.toml");
    let sets = [regolith::scene::parse_set("sph.body_markers=\"inset\"").expect("set")];
    let scene = regolith::scene::load_scene(&p, &sets).expect("scene");
    assert_eq!(scene.solver.spacing, 0.01);
    let s = run_scene(&scene, &RunOptions::quiet(common::out_dir("plate_bearing_inset"))).expect("runs");
    let run = &s.rig.as_ref().expect("rig report")["runs"][0];
    let q = run["pressure_at_tenth_width"].as_f64().expect("pressure at 0.1 B");
    let reference = 6.05 * 2000.0;
    let err = q / reference - 1.0;
    eprintln!("pressure at 0.1 B: {q:.0} Pa = {:.2} c ({:+.1} % against Eason–Shield)", q / 2000.0, 100.0 * err);
    assert!(err.abs() <= 0.10, "{q:.0} Pa is {:+.1} % from 6.05 c = {reference} Pa (bound 10 %)", 100.0 * err);
}

#[test]
fn cone_force_grows_with_depth_and_no_soil_gets_inside() {
    // d0 = 6.25 mm (cone radius 3.2 d0), sized for CI.
    let d0 = 0.00625;
    let text = format!(
        "[simulation]\nend_time = 0.5\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = {d0}\n\n{SAND}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.09, 0.09, 0.13]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.075\n\n\
         [[bodies]]\nname = \"cone\"\nshape = {{ type = \"cone\", radius = 0.02, height = 0.01155 }}\nmass = 0.5\nposition = [0.045, 0.045, 0.12]\n\n\
         [rig]\ntype = \"cone\"\nbody = \"cone\"\nspeed = 0.15\ndepth = 0.03\n"
    );
    let scene = common::scene(&text);
    let out = common::out_dir("cone");
    let s = run_scene(&scene, &RunOptions::quiet(out.clone())).expect("runs");
    assert!(!s.nan_detected && s.error.is_none());
    let curve: Vec<(f64, f64)> = s.rig.as_ref().expect("rig")["curve"]
        .as_array()
        .expect("curve")
        .iter()
        .map(|p| (p["base_depth"].as_f64().unwrap_or(f64::NAN), p["force"].as_f64().unwrap_or(f64::NAN)))
        .collect();
    let at = |d: f64| {
        let near: Vec<f64> = curve.iter().filter(|p| (p.0 - d).abs() < 0.003).map(|p| p.1).collect();
        near.iter().sum::<f64>() / near.len().max(1) as f64
    };
    let (f1, f2, f3) = (at(0.0), at(0.015), at(0.028));
    eprintln!("cone force at base depth 0, 15, 28 mm: {f1:.2}, {f2:.2}, {f3:.2} N");
    assert!(f1 < f2 && f2 < f3, "force must grow with depth: {f1}, {f2}, {f3}");
    // No particle centre inside the cone at its final pose (tip from the series' last row).
    let h = 0.01155;
    let csv = std::fs::read_to_string(out.join("series.csv")).expect("series");
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    let last: Vec<f64> = csv.lines().last().expect("row").split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect();
    let tip_depth = last[header.iter().position(|c| *c == "tip_depth").expect("tip_depth")];
    let particles = std::fs::read_to_string(out.join("particles_final.csv")).expect("particles");
    // The rig's surface: the top particle plus d0/2, 12 layers of d0 here.
    let surface = 0.075;
    let tip = surface - tip_depth;
    let mut inside = 0;
    for line in particles.lines().skip(1) {
        let v: Vec<f64> = line.split(',').take(3).map(|x| x.parse().unwrap_or(f64::NAN)).collect();
        let z = v[2] - tip;
        if (0.0..=h).contains(&z) {
            let r = ((v[0] - 0.045).powi(2) + (v[1] - 0.045).powi(2)).sqrt();
            if r < z * 0.02 / h {
                inside += 1;
            }
        }
    }
    assert_eq!(inside, 0, "{inside} soil particles inside the cone");
}

#[test]
fn drawbar_pull_rises_with_slip_and_torque_is_positive() {
    // Sized for CI: d0 = 15 mm (5 layers of soil) and 0.3 s a slip. Measured there since the
    // rig's carriage only translates (issue 45; before it the axle motor stalled near its
    // 4 N m s × ω limit): DBP −1.67 N at s = 0 and +12.97 N at s = 0.4, torque 1.05 and
    // 2.29 N m (before: −6.9 and +1.1 N, 0.49 and 1.38 N m). The rise is checked.
    let text = format!(
        "[simulation]\nend_time = 0.3\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.015\n\n{SAND}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.14, 0.25]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.08\n\n\
         [[bodies]]\nname = \"wheel\"\nshape = {{ type = \"wheel\", radius = 0.1, width = 0.08, grousers = 12, grouser_height = 0.01, grouser_thickness = 0.005 }}\nmass = 2.0\nposition = [0.15, 0.07, 0.3]\n\n\
         [rig]\ntype = \"wheel\"\nbody = \"wheel\"\nload = 40.0\nangular_velocity = 1.0\nslips = [0.0, 0.4]\n"
    );
    let scene = common::scene(&text);
    let s = run_scene(&scene, &RunOptions::quiet(common::out_dir("wheel"))).expect("runs");
    let runs = s.rig.as_ref().expect("rig")["steady_state"].as_array().expect("runs").clone();
    let get = |i: usize, k: &str| runs[i][k].as_f64().unwrap_or(f64::NAN);
    eprintln!(
        "s = 0: DBP {:.2} N, torque {:.3} N m; s = 0.4: DBP {:.2} N, torque {:.3} N m",
        get(0, "drawbar_pull"),
        get(0, "torque"),
        get(1, "drawbar_pull"),
        get(1, "torque")
    );
    assert!(get(0, "drawbar_pull") < 0.0, "at zero slip the wheel is resisted");
    // A rise of a tenth of the 40 N load at least.
    assert!(get(1, "drawbar_pull") > get(0, "drawbar_pull") + 4.0, "DBP must rise with slip");
    assert!(get(0, "torque") > 0.0 && get(1, "torque") > get(0, "torque"), "driving torque positive and rising");
    assert!(get(1, "sinkage") > 0.0);
}

#[test]
fn a_body_without_markers_falls_exactly_as_in_rapier() {
    let body = "[[bodies]]\nname = \"ghost\"\nshape = { type = \"sphere\", radius = 0.02 }\nmass = 1.0\nposition = [0.11, 0.11, 0.3]\nfsi = false\n";
    let scene = common::scene(&bed(0.1, [0.22, 0.22, 0.4], 0.05, body));
    let mut sim = Simulation::<f32>::new(&scene).expect("builds");
    let b = sim.body("ghost").expect("ghost");
    let mut plain = RigidWorld::new([0.0, 0.0, -9.81]);
    let p = plain
        .add_body(&BodyDesc {
            name: "ghost".into(),
            shape: ShapeDesc::Sphere { radius: 0.02 },
            mass: MassSpec::Mass(1.0),
            pose: Pose::translation([0.11, 0.11, 0.3]),
            motion: Motion::Free,
            friction: 0.5,
            collides: true,
        })
        .expect("body");
    for _ in 0..100 {
        let t0 = sim.time();
        sim.step().expect("step");
        plain.step(sim.time() - t0);
        assert_eq!(sim.body_state(b).com, plain.state(p).com, "trajectories differ at t = {}", sim.time());
        assert_eq!(sim.fsi_wrench(b).force, [0.0; 3]);
    }
    assert!(sim.body_state(b).linvel[2] < -0.9);
}

#[test]
fn a_wheel_driven_up_a_slope_balances_the_downhill_load_and_slips_more() {
    // The single-wheel scene in slope mode, sized down (d0 2 cm, 0.6 s a slope): gravity is
    // tilted per slope, the carriage is free along the bed, the load (40 N) is carried along
    // gravity. Once the wheel climbs steadily the soil's force along the slope (the drawbar
    // pull) balances the load's downhill part, 40 sin θ N: a force balance, to 10 % of it
    // plus 1 N for what the carriage still accelerates over the averaged second half.
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/single_wheel.toml"),
    )
    .expect("read")
    .replace("slips = [0.0, 0.2, 0.4, 0.6]", "slopes = [0.0, 25.0]\nslip_radius = 0.11")
    .replace("end_time = 2.0 ", "end_time = 0.6 ")
    .replace("spacing = 0.01", "spacing = 0.02");
    let scene = common::scene(&text);
    let out = common::out_dir("wheel_slopes");
    let summary = run_scene(&scene, &RunOptions::quiet(&out)).expect("runs");
    let v = serde_json::to_value(&summary).expect("json");
    let rig = &v["rig"];
    assert_eq!(rig["drive"]["slopes_deg"], serde_json::json!([0.0, 25.0]));
    // Slip is defined with the rim plus the grousers here (0.1 + 0.01 m), as experiments do.
    assert_eq!((rig["radius_m"].as_f64(), rig["slip_radius_m"].as_f64()), (Some(0.1), Some(0.11)));
    let runs = rig["steady_state"].as_array().expect("runs");
    assert_eq!(runs.len(), 2);
    let num = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} in {r}"));
    for r in runs {
        let (dbp, want) = (num(r, "drawbar_pull"), num(r, "downhill_load_n"));
        eprintln!(
            "slope {}°: slip {:.3} ± {:.3}, DBP {dbp:.2} N vs load sin θ {want:.2} N, sinkage {:.4} m",
            num(r, "slope_deg"),
            num(r, "measured_slip"),
            num(r, "slip_std"),
            num(r, "sinkage")
        );
        assert!((dbp - want).abs() < 0.1 * want + 1.0, "DBP {dbp} N vs {want} N");
    }
    assert!((num(&runs[0], "downhill_load_n")).abs() < 1e-12);
    assert!((num(&runs[1], "downhill_load_n") - 40.0 * 25f64.to_radians().sin()).abs() < 1e-9);
    let (s0, s25) = (num(&runs[0], "measured_slip"), num(&runs[1], "measured_slip"));
    assert!(s25 > s0 + 0.05, "slip on 25° {s25} vs level {s0}");
}
