//! Public robot descriptions as their projects ship them (tests/data/urdf, see its README for
//! sources and licences): pybullet_data's Clearpath Husky, a Clearpath Jackal (its xacro's
//! default expansion), Curio (a Sawppy rocker-bogie rover) and ROBOTIS' TurtleBot3 Waffle. Each
//! imports with its fixed joints lumped (massless frames included) and its substitutions
//! resolved. The Husky, the Jackal and Curio settle on a small soil bed and are driven forward
//! for 0.3 s with a scene `drive` (Curio with its `differential`): everything stays finite, no
//! soil particle ends inside a body, and each moves along its heading without turning away. The
//! TurtleBot3 only imports here: its caster skids and belly sit 1 cm above its wheel bottoms,
//! and on loose soil its spinning wheels dig down until the belly carries it, as on a real one
//! (NOTES.md, issue 47).
//!
//! Meshes: the Husky's and the Jackal's are shipped; the TurtleBot3's and Curio's are
//! visual-only and not shipped, so each import reports them as warnings and draws those links
//! without them (checked below). The beds are coarse (4–6 spacings per wheel radius) and small,
//! sized for CI.

use crate::common;

use std::path::{Path, PathBuf};

use regolith::sim::Simulation;
use regolith_rigid::Pose;
use regolith_vehicles::{PackagePath, UrdfModel};

fn gallery() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/urdf")
}

/// Imports with no environment variables set (substitutions take their defaults).
fn import(rel: &str) -> UrdfModel {
    UrdfModel::parse_with_env(
        &std::fs::read_to_string(gallery().join(rel)).expect("read"),
        &gallery().join(rel),
        &PackagePath(vec![gallery()]),
        &|_| None,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

fn names(m: &UrdfModel) -> Vec<&str> {
    m.links.iter().map(|l| l.name.as_str()).collect()
}

#[test]
fn the_husky_imports_as_shipped_with_its_frames_lumped_and_optenv_defaults() {
    let m = import("husky/husky.urdf");
    assert_eq!(
        names(&m),
        [
            "base_footprint",
            "front_left_wheel_link",
            "front_right_wheel_link",
            "rear_left_wheel_link",
            "rear_right_wheel_link"
        ]
    );
    let frames: Vec<&str> = m.frames.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        frames,
        ["base_link", "imu_link", "top_plate_link", "user_rail_link", "front_bumper_link", "rear_bumper_link"]
    );
    assert!(m.frames.iter().all(|f| f.link == 0));
    assert!(m.unsupported.is_empty(), "{:?}", m.unsupported);
    // The chassis mass and its centre of mass, moved up by the chassis joint (0.14493 m).
    let base = &m.links[0];
    assert!((base.mass - 33.455).abs() < 1e-12 && (m.mass() - (33.455 + 4.0 * 2.637)).abs() < 1e-9);
    let com = [-0.08748, -0.00085, 0.09947 + 0.14493];
    assert!(base.com.iter().zip(com).all(|(a, b)| (a - b).abs() < 1e-12), "{:?}", base.com);
    assert_eq!(base.inertia, [0.6022, 1.7386, 2.0296, -0.02364, -0.1197, -0.001544]);
    // The chassis box and five visual meshes (base, top plate, rail, two bumpers), all on the
    // lumped body at their frames' poses: the rear bumper turned half a turn about z.
    assert_eq!((base.collision.len(), base.visual.len()), (1, 5));
    assert!((base.collision[0].0.translation[2] - (0.14493 + 0.12498)).abs() < 1e-12);
    let rear = &base.visual[4].0;
    assert!((rear.translation[0] + 0.48).abs() < 1e-12 && (rear.translation[2] - (0.14493 + 0.091)).abs() < 1e-12);
    assert!((rear.rotate([1.0, 0.0, 0.0])[0] + 1.0).abs() < 1e-5, "{rear:?}");
    // The wheel joints now hang on base_footprint: their origins include the chassis joint.
    let fl = &m.joints[0];
    assert_eq!((fl.name.as_str(), fl.parent, fl.child), ("front_left_wheel", 0, 1));
    assert!((fl.origin.translation[2] - (0.14493 + 0.03282)).abs() < 1e-12);
    // The IMU frame from the optenv defaults: xyz 0.19 0 0.149, rpy 0 −1.5708 3.1416.
    assert_eq!(m.substitutions.len(), 2);
    assert_eq!(
        m.substitutions.iter().map(|s| (s.variable.as_str(), s.value.as_str(), s.from_env)).collect::<Vec<_>>(),
        [("HUSKY_IMU_RPY", "0 -1.5708 3.1416", false), ("HUSKY_IMU_XYZ", "0.19 0 0.149", false)]
    );
    let (link, imu) = m.locate("imu_link").expect("imu frame");
    assert_eq!(link, 0);
    // The file's own rounded angles (not π/2 and π): the pose must be what it says.
    let (pitch, yaw): (f64, f64) = ("-1.5708".parse().expect("f64"), "3.1416".parse().expect("f64"));
    let want = Pose::translation([0.0, 0.0, 0.14493])
        .compose(&Pose::from_rpy_deg([0.19, 0.0, 0.149], [0.0, pitch.to_degrees(), yaw.to_degrees()]));
    assert!(imu.translation.iter().zip(want.translation).all(|(a, b)| (a - b).abs() < 1e-12), "{imu:?}");
    assert!(imu.rotation.iter().zip(want.rotation).all(|(a, b)| (a - b).abs() < 1e-12), "{imu:?}");
    // Set in the environment, the variable wins.
    let text = std::fs::read_to_string(gallery().join("husky/husky.urdf")).expect("read");
    let env = |n: &str| (n == "HUSKY_IMU_XYZ").then(|| "0.1 0.2 0.3".to_string());
    let m = UrdfModel::parse_with_env(&text, &gallery().join("husky/husky.urdf"), &PackagePath::default(), &env)
        .expect("loads");
    assert!(m.substitutions[1].from_env && !m.substitutions[0].from_env);
    let imu = m.locate("imu_link").expect("imu").1.translation;
    assert!((imu[0] - 0.1).abs() < 1e-12 && (imu[2] - (0.14493 + 0.3)).abs() < 1e-12, "{imu:?}");
}

#[test]
fn the_turtlebot3_and_curio_import_with_their_visual_meshes_reported_missing() {
    let m = import("turtlebot3_description/urdf/turtlebot3_waffle.urdf");
    assert_eq!(names(&m), ["base_footprint", "wheel_left_link", "wheel_right_link"]);
    assert_eq!(m.frames.len(), 10, "{:?}", m.frames);
    // The camera link has no inertial (commented out upstream) and is lumped like the others.
    assert_eq!(m.locate("camera_depth_optical_frame").map(|(l, _)| l), Some(0));
    assert!((m.links[0].mass - (1.3729096 + 2.0 * 0.005 + 0.114)).abs() < 1e-9);
    // Base box, two caster boxes, the lidar cylinder and the camera box on one body.
    assert_eq!(m.links[0].collision.len(), 5);
    assert_eq!(m.wheel_links(), [1, 2]);
    // Five visual meshes, none shipped: one warning each, naming the URI and the link.
    assert_eq!(m.unsupported.len(), 5, "{:#?}", m.unsupported);
    assert!(m.unsupported.iter().all(|u| u.starts_with("visual ") && u.contains("drawn without it")));
    assert!(m.unsupported[1].contains("meshes/wheels/left_tire.stl") && m.unsupported[1].contains("`wheel_left_link`"));
    assert!(m.links[1].visual.is_empty());

    let m = import("curio_description/urdf/curio.urdf");
    assert_eq!(m.links.len(), 16, "{:?}", names(&m));
    assert_eq!(m.frames.iter().map(|f| f.name.as_str()).collect::<Vec<_>>(), ["body_box_link"]);
    assert_eq!(m.wheel_links().len(), 6);
    assert!((m.mass() - (0.01 + 0.5 + 0.1 + 2.0 * 0.1 + 4.0 * 0.1 + 2.0 * 0.1 + 6.0 * 0.1)).abs() < 1e-9);
    // One URI used by the six wheels: one warning listing them.
    assert_eq!(m.unsupported.len(), 1, "{:?}", m.unsupported);
    assert_eq!(m.unsupported[0].matches("_wheel_link`").count(), 6, "{}", m.unsupported[0]);
}

/// One gallery robot on its bed.
struct Drive<'a> {
    name: &'a str,
    urdf: &'a str,
    /// Soil spacing (m), bed extent in x and y (m), soil depth (m), and the container's walls
    /// above the soil (m; the walls' markers cost as much as the soil on these small beds).
    spacing: f64,
    bed: [f64; 2],
    depth: f64,
    walls: f64,
    /// Root position [x, y] on the bed.
    at: [f64; 2],
    /// Extra vehicle keys (fsi_links).
    extra: &'a str,
    /// Steering joints held at an angle (`drive.steering` entries).
    steering: &'a str,
    /// Wheel speed (rad/s) and motor torque limit (N m).
    speed: f64,
    torque: f64,
    /// Rolling radius (m): the advance at no slip over the drive is `speed × radius ×
    /// (DRIVE − 0.05 s)` (a 0.1 s ramp, then the rest at speed).
    radius: f64,
}

/// How long each robot is driven (s): 0.3 (0.5 until issue 46 sized the suite; the three
/// drives then took 250 s of its time).
const DRIVE: f64 = 0.3;

/// Settles 0.15 s, then drives forward for `DRIVE` (ramping up over the first 0.1 s) and checks
/// what every gallery robot must do. The soil is a loose Modified Cam Clay, softer than the
/// example rover's (E = 2 MPa, not 5: a wave speed of 41 m/s, so 1.6× fewer steps). Returns
/// (advance, drift, yaw in degrees) and the simulation where it ended.
fn drive(d: &Drive) -> (f64, f64, f64, Simulation<f32>) {
    let settle = 0.15;
    let end = settle + DRIVE;
    let text = format!(
        "[simulation]\nend_time = {end}\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = {}\n\n\
         [[materials]]\nname = \"soil\"\nmodel = \"mcc\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\n\
         mcc_m = 1.2\nmcc_kappa = 0.02\nmcc_lambda = 0.1\nmcc_v_lambda = 2.2\nocr = 2.0\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{}, {}, {}]\n\n[terrain]\nmaterial = \"soil\"\ndepth = {}\n\n\
         [[vehicles]]\nname = \"{}\"\nurdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [{}, {}]\n{}\n\
         drive = {{ wheel_speed = [[0.0, 0.0], [{settle}, 0.0], [{}, {}]], max_torque = {}{} }}\n",
        d.spacing,
        d.bed[0],
        d.bed[1],
        d.depth + d.walls,
        d.depth,
        d.name,
        gallery().join(d.urdf).display(),
        gallery().display(),
        d.at[0],
        d.at[1],
        d.extra,
        settle + 0.1,
        d.speed,
        d.torque,
        d.steering
    );
    let scene = common::scene(&text);
    let v = &scene.vehicles[0];
    let mut sim = Simulation::<f32>::new(&scene).expect("builds");
    let root = sim.body(&format!("{}/{}", d.name, v.model.links[v.model.root].name)).expect("root");
    let mut start = None;
    while sim.time() < scene.end_time - 1e-9 {
        sim.step().expect("step");
        if start.is_none() && sim.time() >= settle - 1e-9 {
            start = Some(sim.body_state(root));
        }
    }
    let (s0, s1) = (start.expect("settled"), sim.body_state(root));
    // Finite: every link's state and every particle.
    for b in sim.bodies() {
        let st = sim.body_state(b);
        let all = st.origin.iter().chain(&st.rotation).chain(&st.linvel).chain(&st.angvel);
        assert!(all.clone().all(|x| x.is_finite()), "{}: {st:?}", d.name);
    }
    let soil: Vec<[f64; 3]> = sim.system.fluid.positions().iter().map(|p| p.as_f64()).collect();
    assert!(soil.iter().flatten().all(|x| x.is_finite()), "{}: a particle is not finite", d.name);
    // No soil particle inside any body that touches the soil.
    for (i, spec) in scene.bodies.iter().enumerate().filter(|(_, b)| b.fsi) {
        let st = sim.body_state(sim.bodies().nth(i).expect("body"));
        let inv = [-st.rotation[0], -st.rotation[1], -st.rotation[2], st.rotation[3]];
        let local: Vec<[f64; 3]> =
            soil.iter().map(|p| regolith_rigid::quat_rotate(inv, [0, 1, 2].map(|k| p[k] - st.origin[k]))).collect();
        let inside = spec.desc.shape.contains_points(&local, 0.0).iter().filter(|x| **x).count();
        assert_eq!(inside, 0, "{}: {inside} soil particles inside {}", d.name, spec.desc.name);
    }
    // Along the heading it had when the drive started.
    let fwd = regolith_rigid::quat_rotate(s0.rotation, [1.0, 0.0, 0.0]);
    let h = (fwd[0] * fwd[0] + fwd[1] * fwd[1]).sqrt();
    let (dx, dy) = (s1.origin[0] - s0.origin[0], s1.origin[1] - s0.origin[1]);
    let advance = (dx * fwd[0] + dy * fwd[1]) / h;
    let drift = (dy * fwd[0] - dx * fwd[1]) / h;
    let yaw = |q: [f64; 4]| regolith::output::series::roll_pitch_yaw_deg(q)[2];
    let turn = yaw(s1.rotation) - yaw(s0.rotation);
    let ideal = d.speed * d.radius * (DRIVE - 0.05);
    eprintln!(
        "{}: advanced {advance:.4} m (no-slip {ideal:.4} m), drift {drift:+.4} m, turned {turn:+.2}°, root z {:.3} → {:.3} m",
        d.name, s0.origin[2], s1.origin[2]
    );
    assert!(advance > 0.25 * ideal, "{}: advanced {advance} m of {ideal} m at no slip", d.name);
    assert!(drift.abs() < 0.5 * advance, "{}: drifted {drift} m sideways for {advance} m ahead", d.name);
    assert!(turn.abs() < 10.0, "{}: turned {turn}°", d.name);
    (advance, drift, turn, sim)
}

#[test]
fn the_husky_drives_forward_on_soil() {
    // 44 kg on four 0.178 m wheels, 0.57 m apart; 3 cm spacing.
    drive(&Drive {
        name: "husky",
        urdf: "husky/husky.urdf",
        spacing: 0.03,
        bed: [1.15, 0.8],
        depth: 0.09,
        walls: 0.15,
        at: [0.52, 0.4],
        extra: "",
        steering: "",
        speed: 2.0,
        torque: 40.0,
        radius: 0.17775,
    });
}

#[test]
fn the_jackal_imports_and_drives_forward_on_soil() {
    let m = import("rtabmap_drone_example/urdf/jackal.urdf");
    let mut links = names(&m);
    links.sort_unstable();
    assert_eq!(
        links,
        [
            "base_link",
            "front_left_wheel_link",
            "front_right_wheel_link",
            "rear_left_wheel_link",
            "rear_right_wheel_link"
        ]
    );
    // The massless root carries the chassis, fenders, IMU, GPS and mounts: 16.523 + 0.001 kg.
    let root = &m.links[m.root];
    assert_eq!(root.name, "base_link");
    assert!((root.mass - 16.524).abs() < 1e-9 && (m.mass() - 18.432).abs() < 1e-9, "{} kg", root.mass);
    assert_eq!(m.frames.len(), 8, "{:?}", m.frames);
    assert!(m.unsupported.is_empty(), "{:?}", m.unsupported);
    // 18.4 kg on four 0.098 m wheels, 0.376 m apart; 2 cm spacing (5 per wheel radius).
    drive(&Drive {
        name: "jackal",
        urdf: "rtabmap_drone_example/urdf/jackal.urdf",
        spacing: 0.02,
        bed: [0.8, 0.6],
        depth: 0.06,
        walls: 0.1,
        at: [0.33, 0.3],
        extra: "",
        steering: "",
        speed: 3.0,
        torque: 20.0,
        radius: 0.098,
    });
}

#[test]
fn curio_drives_forward_on_soil_with_its_differential() {
    // 2 kg on six 0.06 m wheels on a rocker-bogie, 0.63 m across its middle wheels; the corner
    // steering joints held straight; the rockers coupled by the differential its URDF cannot say.
    let sim = drive(&Drive {
        name: "curio",
        urdf: "curio_description/urdf/curio.urdf",
        spacing: 0.02,
        bed: [0.95, 0.85],
        depth: 0.05,
        walls: 0.1,
        at: [0.38, 0.425],
        extra: "differential = { left = \"left_rocker_joint\", right = \"right_rocker_joint\" }",
        steering: ", steering = { front_left_corner_joint = 0.0, front_right_corner_joint = 0.0, \
                   back_left_corner_joint = 0.0, back_right_corner_joint = 0.0 }",
        speed: 4.0,
        torque: 2.0,
        radius: 0.06,
    })
    .3;
    // The differential held: the rockers turned by equal and opposite angles.
    let angle = |j: &str| {
        let id = sim.vehicle_joint("curio", j).expect("joint");
        sim.system.rigid.joint_position(id).expect("revolute").0
    };
    let (l, r) = (angle("left_rocker_joint"), angle("right_rocker_joint"));
    assert!((l + r).abs() < 5e-3, "rockers at {l} and {r} rad");
}

#[test]
fn regolith_check_lists_the_substitutions_and_lumped_links_and_refuses_unset_env() {
    let dir = common::out_dir("urdf_gallery_check");
    let scene = |urdf: &Path| {
        format!(
            "[simulation]\nend_time = 0.1\n\n[sph]\nspacing = 0.05\n\n[[materials]]\nname = \"soil\"\nmodel = \"drucker-prager\"\n\
             density = 1600\nyoungs_modulus = 5e6\npoisson_ratio = 0.3\nfriction_angle = 30\n\n\
             [container]\nmin = [0.0, 0.0, 0.0]\nmax = [1.5, 1.0, 0.8]\n\n[terrain]\nmaterial = \"soil\"\ndepth = 0.1\n\n\
             [[vehicles]]\nname = \"husky\"\nurdf = \"{}\"\nposition = [0.6, 0.5]\n",
            urdf.display()
        )
    };
    let check = |p: &Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_regolith"))
            .arg("check")
            .arg(p)
            .env_remove("HUSKY_IMU_RPY")
            .env("HUSKY_IMU_XYZ", "0.19 0 0.2")
            .output()
            .expect("runs")
    };
    let p = dir.join("husky.toml");
    std::fs::write(&p, scene(&gallery().join("husky/husky.urdf"))).expect("write");
    let o = check(&p);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}{out}", String::from_utf8_lossy(&o.stderr));
    for want in [
        "base_footprint carries the links fixed to it: base_link, imu_link, top_plate_link, user_rail_link, \
         front_bumper_link, rear_bumper_link (33.455 kg in all)",
        "substitution line 97: $(optenv HUSKY_IMU_RPY 0 -1.5708 3.1416) = \"0 -1.5708 3.1416\" (the default, \
         HUSKY_IMU_RPY is not set)",
        "substitution line 97: $(optenv HUSKY_IMU_XYZ 0.19 0 0.149) = \"0.19 0 0.2\" (from the environment, \
         HUSKY_IMU_XYZ is set)",
    ] {
        assert!(out.contains(want), "`{want}` not in:\n{out}");
    }
    assert!(!out.contains("warning"), "{out}");
    // `$(env NAME)` with NAME unset: a one-line error naming the file, the line and the variable.
    let text = std::fs::read_to_string(gallery().join("husky/husky.urdf")).expect("read");
    let urdf = dir.join("husky_env.urdf");
    std::fs::write(&urdf, text.replace("$(optenv HUSKY_IMU_RPY 0 -1.5708 3.1416)", "$(env HUSKY_IMU_RPY)"))
        .expect("write");
    let p = dir.join("husky_env.toml");
    std::fs::write(&p, scene(&urdf)).expect("write");
    let o = check(&p);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!(
            "{}: line 97: `$(env HUSKY_IMU_RPY)`: environment variable HUSKY_IMU_RPY is not set",
            urdf.display()
        )) && err.contains("(from vehicles[0].urdf)"),
        "{err}"
    );
}
