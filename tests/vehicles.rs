//! URDF vehicles: the example rover imports with the expected links, joints, masses and
//! inertias; wrong URDFs get errors naming the link and URI; on soil the rover is carried by its
//! weight, drives forward with a slip in (0, 1) and skid-steers; on rigid ground the import
//! behaves as the same rover built by hand in plain rapier.

use crate::common;

use std::path::{Path, PathBuf};

use regolith::build::build_vehicle_joints;
use regolith::sim::{Body, Simulation};
use regolith_rigid::{RigidWorld, ShapeDesc};
use regolith_vehicles::{JointType, PackagePath, UrdfModel};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

fn rover() -> UrdfModel {
    let p = examples().join("rover_description/urdf/rover.urdf");
    UrdfModel::load(&p, &PackagePath(vec![examples()])).unwrap_or_else(|e| panic!("{e}"))
}

fn extent(shape: &ShapeDesc) -> [f64; 3] {
    let ShapeDesc::Mesh { vertices, .. } = shape else { panic!("not a mesh: {shape:?}") };
    [0, 1, 2].map(|k| {
        let (lo, hi) = vertices.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v[k]), b.max(v[k])));
        hi - lo
    })
}

#[test]
fn the_example_rover_imports_links_joints_masses_and_inertias() {
    let m = rover();
    // The mast and camera hang on fixed joints: lumped into the chassis, kept as frames.
    let names: Vec<&str> = m.links.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["base_link", "wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"]);
    let frames: Vec<(&str, &str, usize)> =
        m.frames.iter().map(|f| (f.name.as_str(), f.joint.as_str(), f.link)).collect();
    assert_eq!(frames, [("mast", "mast_joint", 0), ("camera", "camera_joint", 0)]);
    assert_eq!(m.frames[1].pose.translation, [0.12, 0.0, 0.26]);
    assert_eq!(m.root, 0);
    assert!((m.mass() - 8.5).abs() < 1e-12);
    assert!(m.joints.iter().all(|j| j.kind == JointType::Continuous) && m.joints.len() == 4);
    assert!(m.unsupported.is_empty() && m.substitutions.is_empty(), "{:?}", m.unsupported);
    // Wheel: m = 0.5 kg, r = 0.07 m, h = 0.06 m; axle along the link's y.
    let w = &m.links[1];
    let (ia, iy) = (0.5 * (3.0 * 0.07 * 0.07 + 0.06 * 0.06) / 12.0, 0.5 * 0.07 * 0.07 / 2.0);
    for (got, want) in w.inertia.iter().zip([ia, iy, ia, 0.0, 0.0, 0.0]) {
        assert!((got - want).abs() < 1e-6 * ia, "wheel inertia {:?}", w.inertia);
    }
    // Chassis (6 kg at its origin) + mast (0.3 kg, centre 0.1 m above its frame at (0.12, 0,
    // 0.04)) + camera (0.2 kg at (0.12, 0, 0.26)): one 6.5 kg body, by the parallel-axis theorem.
    let base = &m.links[0];
    let parts = [(6.0, [0.0, 0.0, 0.0]), (0.3, [0.12, 0.0, 0.14]), (0.2, [0.12, 0.0, 0.26])];
    let own = [[0.037, 0.0832, 0.1138], [0.001023, 0.001023, 0.000045], [0.000133, 0.0000683, 0.000148]];
    let com = [0, 1, 2].map(|k| parts.iter().map(|(m, c)| m * c[k]).sum::<f64>() / 6.5);
    let d = |i: usize, k: usize| parts[i].1[k] - com[k];
    let ixx: f64 = (0..3).map(|i| own[i][0] + parts[i].0 * (d(i, 1).powi(2) + d(i, 2).powi(2))).sum();
    let iyy: f64 = (0..3).map(|i| own[i][1] + parts[i].0 * (d(i, 0).powi(2) + d(i, 2).powi(2))).sum();
    let izz: f64 = (0..3).map(|i| own[i][2] + parts[i].0 * (d(i, 0).powi(2) + d(i, 1).powi(2))).sum();
    let ixz: f64 = (0..3).map(|i| -parts[i].0 * d(i, 0) * d(i, 2)).sum();
    assert!((base.mass - 6.5).abs() < 1e-12);
    assert!(base.com.iter().zip(com).all(|(a, b)| (a - b).abs() < 1e-15), "com {:?} vs {com:?}", base.com);
    for (got, want) in base.inertia.iter().zip([ixx, iyy, izz, 0.0, ixz, 0.0]) {
        assert!((got - want).abs() < 1e-12, "chassis inertia {:?} vs {:?}", base.inertia, [ixx, iyy, izz, ixz]);
    }
    assert!(ixz < -1e-3, "the mast and camera sit forward and up: Ixz = {ixz}");
    assert_eq!(m.wheel_links(), vec![1, 2, 3, 4]);
    // Chassis mesh from package://, then the mast box and the camera head (a COLLADA file in
    // centimetres) at their frames' poses.
    assert_eq!((base.collision.len(), base.visual.len()), (3, 3));
    let chassis = extent(&base.collision[0].1);
    for (g, w) in chassis.iter().zip([0.40, 0.26, 0.08]) {
        assert!((g - w).abs() < 1e-6, "chassis {chassis:?}");
    }
    assert_eq!(base.collision[1].0.translation, [0.12, 0.0, 0.14]);
    let head = extent(&base.visual[2].1);
    for (g, w) in head.iter().zip([0.05, 0.08, 0.04]) {
        assert!((g - w).abs() < 1e-9, "camera head {head:?} (the dae unit is cm)");
    }
    assert_eq!(base.visual[2].0.translation, [0.12, 0.0, 0.26]);
    // Forward kinematics with all joints at zero.
    let poses = m.link_poses(&regolith_rigid::Pose::from_rpy_deg([1.0, 2.0, 0.5], [0.0, 0.0, 90.0]));
    let fl = poses[1].translation;
    for (g, w) in fl.iter().zip([1.0 - 0.17, 2.0 + 0.15, 0.47]) {
        assert!((g - w).abs() < 1e-12, "wheel_fl at {fl:?}");
    }
    let (li, at) = m.locate("camera").expect("camera frame");
    let cam = poses[li].compose(&at).translation;
    assert!((cam[2] - (0.5 + 0.04 + 0.22)).abs() < 1e-12 && (cam[1] - 2.12).abs() < 1e-12, "camera at {cam:?}");
}

fn urdf_err(name: &str, text: &str, packages: &[PathBuf]) -> String {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("urdf_errors");
    std::fs::create_dir_all(&dir).expect("dir");
    let p = dir.join(format!("{name}.urdf"));
    std::fs::write(&p, text).expect("write");
    let e = UrdfModel::load(&p, &PackagePath(packages.to_vec())).expect_err("must be rejected");
    let s = e.to_string();
    assert!(s.starts_with(&p.display().to_string()), "names the file: {s}");
    assert_eq!(s.lines().count(), 1, "one line: {s}");
    s
}

const INERTIAL: &str = "<inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>";

fn one_link(geometry: &str) -> String {
    format!(
        "<robot name=\"r\"><link name=\"body\">{INERTIAL}<collision><geometry>{geometry}</geometry></collision></link></robot>"
    )
}

#[test]
fn wrong_urdfs_are_errors_naming_the_link_and_the_uri() {
    let e = urdf_err(
        "missing_mesh",
        &one_link("<mesh filename=\"package://rover_description/meshes/nope.stl\"/>"),
        &[examples()],
    );
    assert!(e.contains("link `body` (collision)") && e.contains("package://rover_description/meshes/nope.stl"), "{e}");
    assert!(e.contains("nope.stl does not exist"), "{e}");
    let e = urdf_err("unknown_package", &one_link("<mesh filename=\"package://martian_pkg/m.stl\"/>"), &[examples()]);
    assert!(e.contains("link `body`") && e.contains("package `martian_pkg`") && e.contains("searched"), "{e}");
    assert!(e.contains(&examples().display().to_string()), "lists the places searched: {e}");
    let e = urdf_err("relative_missing", &one_link("<mesh filename=\"meshes/gone.obj\"/>"), &[]);
    assert!(e.contains("`meshes/gone.obj` not found"), "{e}");
    let e = urdf_err("malformed", "<robot name=\"r\"><link name=\"a\">", &[]);
    assert!(e.contains("not a valid URDF"), "{e}");
    let e = urdf_err("no_inertial", "<robot name=\"r\"><link name=\"floaty\"/></robot>", &[]);
    assert!(e.contains("link `floaty` has no <inertial>"), "{e}");
    let e = urdf_err(
        "unknown_parent",
        &format!(
            "<robot name=\"r\"><link name=\"a\">{INERTIAL}</link><joint name=\"j\" type=\"fixed\"><parent link=\"ghost\"/><child link=\"a\"/></joint></robot>"
        ),
        &[],
    );
    assert!(e.contains("joint `j`: parent link `ghost` is not defined"), "{e}");
    // Massless links may only hang on fixed joints.
    let e = urdf_err(
        "massless_wheel",
        &format!(
            "<robot name=\"r\"><link name=\"a\">{INERTIAL}</link><link name=\"wheel\"/>\
             <joint name=\"spin\" type=\"continuous\"><parent link=\"a\"/><child link=\"wheel\"/><axis xyz=\"0 1 0\"/></joint></robot>"
        ),
        &[],
    );
    assert!(e.contains("link `wheel` has no <inertial> or a zero mass but moves on joint `spin` (continuous)"), "{e}");
    assert!(e.contains("only links on fixed joints may be massless"), "{e}");
    let e = urdf_err(
        "massless_root",
        "<robot name=\"r\"><link name=\"footprint\"/><link name=\"imu\"/>\
         <joint name=\"j\" type=\"fixed\"><parent link=\"footprint\"/><child link=\"imu\"/></joint></robot>",
        &[],
    );
    assert!(
        e.contains(
            "link `footprint` has no <inertial> or a zero mass (nor do the links fixed to it: imu) but is the root"
        ),
        "{e}"
    );
    let e = urdf_err("negative_mass", &one_link("<box size=\"1 1 1\"/>").replace("value=\"1\"", "value=\"-1\""), &[]);
    assert!(e.contains("link `body`: <mass> must be finite and ≥ 0 kg (got -1)"), "{e}");
    // xacro: only $(optenv) and $(env) are resolved; the rest points at the xacro tool.
    let e = urdf_err("xacro_find", &one_link("<mesh filename=\"$(find rover_description)/meshes/chassis.stl\"/>"), &[]);
    assert!(
        e.contains(": line 1: `$(find rover_description)` is a xacro substitution") && e.contains("`xacro`"),
        "{e}"
    );
    let e = urdf_err(
        "xacro_element",
        "<robot name=\"r\" xmlns:xacro=\"http://ros.org/wiki/xacro\">\n<xacro:property name=\"w\" value=\"1\"/>\n</robot>",
        &[],
    );
    assert!(e.contains(": line 2: element <xacro:property> is xacro") && e.contains("xacro robot.urdf.xacro"), "{e}");
    let e = urdf_err("xacro_expression", &one_link("<box size=\"${w} 1 1\"/>"), &[]);
    assert!(e.contains("`${w}` is a xacro expression"), "{e}");
    let e = urdf_err("env_unset", &one_link("<box size=\"$(env REGOLITH_TEST_SURELY_UNSET) 1 1\"/>"), &[]);
    assert!(e.contains("environment variable REGOLITH_TEST_SURELY_UNSET is not set"), "{e}");
}

#[test]
fn joints_the_importer_cannot_honour_are_reported_once_by_name() {
    let text = format!(
        "<robot name=\"r\"><link name=\"a\">{INERTIAL}</link><link name=\"b\">{INERTIAL}</link><link name=\"c\">{INERTIAL}</link>\
         <joint name=\"slide\" type=\"planar\"><parent link=\"a\"/><child link=\"b\"/></joint>\
         <joint name=\"follow\" type=\"continuous\"><parent link=\"a\"/><child link=\"c\"/><axis xyz=\"0 1 0\"/><mimic joint=\"slide\"/></joint></robot>"
    );
    let p = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("unsupported.urdf");
    std::fs::write(&p, text).expect("write");
    let m = UrdfModel::load(&p, &PackagePath::default()).expect("loads");
    assert_eq!(m.unsupported.len(), 2, "{:?}", m.unsupported);
    assert!(m.unsupported[0].contains("joint `slide`: planar joints are not supported"));
    assert!(m.unsupported[1].contains("joint `follow`: <mimic> is not supported"));
    assert_eq!(m.joints.len(), 1);
    // The scene check prints each once.
    let scene = format!(
        "{}\n[[vehicles]]\nname = \"r\"\nurdf = \"{}\"\nposition = [0.3, 0.3, 0.3]\n",
        bed_text(0.1),
        p.display()
    );
    let sp = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("unsupported_scene.toml");
    std::fs::write(&sp, scene).expect("write");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_regolith")).arg("check").arg(&sp).output().expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.matches("planar joints are not supported").count(), 1, "{out}");
    assert_eq!(out.matches("<mimic> is not supported").count(), 1, "{out}");
}

/// A small MCC bed for the rover (0.8 × 0.6 m, 8 cm deep, d0 = 2 cm).
fn bed_text(end_time: f64) -> String {
    format!(
        "[simulation]\nend_time = {end_time}\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = 0.02\n\n\
         [[materials]]\nname = \"soil\"\nmodel = \"mcc\"\ndensity = 1600\nyoungs_modulus = 5e6\npoisson_ratio = 0.3\n\
         mcc_m = 1.2\nmcc_kappa = 0.02\nmcc_lambda = 0.1\nmcc_v_lambda = 2.2\nocr = 2.0\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.8, 0.6, 0.3]\n\n[terrain]\nmaterial = \"soil\"\ndepth = 0.08\n"
    )
}

fn rover_scene(end_time: f64, drive: &str) -> regolith::scene::Scene {
    let urdf = examples().join("rover_description/urdf/rover.urdf");
    let text = format!(
        "{}\n[[vehicles]]\nname = \"rover\"\nurdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.25, 0.3]\n{drive}\n",
        bed_text(end_time),
        urdf.display(),
        examples().display()
    );
    common::scene(&text)
}

const WHEELS: [&str; 4] = ["wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"];

#[test]
fn a_rover_at_rest_on_the_soil_is_carried_by_its_weight_and_does_not_tunnel() {
    // 0.3 s (sized for CI): measured, the mean force over 0.15–0.3 s is within 0.03 % of the
    // weight and the sinkage moves 0.01 mm between 0.2 and 0.3 s.
    let scene = rover_scene(0.3, "");
    let mut sim = Simulation::<f32>::new(&scene).expect("builds");
    let links: Vec<Body> =
        scene.vehicles[0].model.links.iter().map(|l| sim.body(&format!("rover/{}", l.name)).expect("link")).collect();
    let weight = 8.5 * 9.81;
    let (mut sum, mut n) = (0.0, 0.0);
    let mut sink_at = Vec::new();
    while sim.time() < scene.end_time - 1e-9 {
        sim.step().expect("step");
        if sim.time() > 0.15 {
            sum += links.iter().map(|b| sim.fsi_wrench(*b).force[2]).sum::<f64>();
            n += 1.0;
        }
        if (sim.time() - 0.2).abs() < 5e-4 || sim.time() > scene.end_time - 5e-4 {
            sink_at.push(sim.wheel_states(0).iter().map(|w| w.sinkage).sum::<f64>() / 4.0);
        }
    }
    let mean = sum / n;
    eprintln!(
        "mean vertical soil force on the rover {mean:.2} N, weight {weight:.2} N ({:+.2} %)",
        100.0 * (mean / weight - 1.0)
    );
    assert!((mean - weight).abs() < 0.05 * weight, "FSI {mean} N vs weight {weight} N");
    // Sinkage: small (under a third of the wheel radius) and steady over the last 0.1 s.
    let d0 = scene.solver.spacing;
    eprintln!("mean wheel sinkage at 0.2 s and 0.3 s: {sink_at:?} m");
    assert!(sink_at.iter().all(|s| s.abs() < 0.07 / 3.0), "sinkage {sink_at:?}");
    assert!((sink_at[1] - sink_at[0]).abs() < 0.25 * d0, "still sinking: {sink_at:?}");
    // No tunnelling: every wheel stays above the floor and no soil particle is inside a wheel.
    for w in WHEELS {
        let b = sim.body(&format!("rover/{w}")).expect("wheel");
        let st = sim.body_state(b);
        assert!(st.origin[2] - 0.07 > 0.04, "{w} at {:?}", st.origin);
        let inv = [-st.rotation[0], -st.rotation[1], -st.rotation[2], st.rotation[3]];
        let local: Vec<[f64; 3]> = sim
            .system
            .fluid
            .positions()
            .iter()
            .map(|p| p.as_f64())
            .map(|p| regolith_rigid::quat_rotate(inv, [0, 1, 2].map(|k| p[k] - st.origin[k])))
            .collect();
        let shape = &scene.bodies[b.index()].desc.shape;
        let inside = shape.contains_points(&local, 0.0).iter().filter(|x| **x).count();
        assert_eq!(inside, 0, "{inside} soil particles inside {w}");
    }
}

#[test]
fn driving_forward_moves_the_rover_with_positive_slip() {
    // Settle 0.1 s, ramp to 3 rad/s by 0.25 s, average over 0.35–0.45 s (sized for CI: to
    // 0.55 s the rover moved 59 mm at 27 % slip over 0.4–0.55 s; to 0.45 s, 44 mm at 27 %).
    let drive = "drive = { wheel_speed = [[0.0, 0.0], [0.1, 0.0], [0.25, 3.0]], max_torque = 6.0 }";
    let scene = rover_scene(0.45, drive);
    let mut sim = Simulation::<f32>::new(&scene).expect("builds");
    let chassis = sim.body("rover/base_link").expect("chassis");
    let x0 = sim.body_state(chassis).origin[0];
    let mut slips = Vec::new();
    let mut omegas = Vec::new();
    while sim.time() < scene.end_time - 1e-9 {
        sim.step().expect("step");
        if sim.time() > 0.35 {
            let w = sim.wheel_states(0);
            slips.push(w.iter().map(|w| w.slip).sum::<f64>() / 4.0);
            omegas.push(w.iter().map(|w| w.omega).sum::<f64>() / 4.0);
        }
    }
    let dx = sim.body_state(chassis).origin[0] - x0;
    let slip = slips.iter().sum::<f64>() / slips.len() as f64;
    let omega = omegas.iter().sum::<f64>() / omegas.len() as f64;
    eprintln!("rover moved {dx:.4} m; mean slip {slip:.3}, mean wheel speed {omega:.3} rad/s over 0.35–0.45 s");
    assert!((omega - 3.0).abs() < 0.3, "wheels must turn at the commanded 3 rad/s (got {omega})");
    assert!(dx > 0.02, "the rover must move forward (moved {dx} m)");
    assert!(slip > 0.0 && slip < 1.0, "slip {slip}");
    let st = sim.body_state(chassis);
    let [_, _, yaw] = regolith::output::series::roll_pitch_yaw_deg(st.rotation);
    assert!(yaw.abs() < 5.0, "straight drive turned by {yaw}°");
}

#[test]
fn skid_steering_turns_the_rover() {
    // Left wheels backwards, right wheels forwards: a turn to the left (positive yaw).
    // Settle 0.1 s, ramp by 0.2 s; by 0.35 s the rover has turned 4.8° (6.8° at 0.45 s,
    // 9.4° at 0.6 s).
    let drive = "drive = { left = [[0.0, 0.0], [0.1, 0.0], [0.2, -3.0]], right = [[0.0, 0.0], [0.1, 0.0], [0.2, 3.0]], max_torque = 6.0 }";
    let scene = rover_scene(0.35, drive);
    let mut sim = Simulation::<f32>::new(&scene).expect("builds");
    let chassis = sim.body("rover/base_link").expect("chassis");
    while sim.time() < scene.end_time - 1e-9 {
        sim.step().expect("step");
    }
    let st = sim.body_state(chassis);
    let [_, _, yaw] = regolith::output::series::roll_pitch_yaw_deg(st.rotation);
    eprintln!("skid steering: yaw {yaw:.2}°, yaw rate {:.3} rad/s", st.angvel[2]);
    assert!(yaw > 3.0, "the rover must turn left (yaw {yaw}°)");
}

/// The rover on a rigid floor, built twice: by Regolith's importer into a `RigidWorld`, and by
/// hand with plain rapier from the same URDF (urdf-rs), with the same motors. Both drive their
/// wheels at 3 rad/s for 1 s.
#[test]
fn on_rigid_ground_the_imported_rover_behaves_as_in_plain_rapier() {
    use rapier3d::prelude::*;
    let g = -9.81;
    let base_z = 0.12; // wheel bottoms 1 cm above the floor
    let text = format!(
        "{}\n[[vehicles]]\nname = \"rover\"\nurdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.0, 0.0, {base_z}]\nfriction = 0.8\n\
         drive = {{ wheel_speed = 3.0, max_torque = 6.0 }}\n",
        bed_text(1.0),
        examples().join("rover_description/urdf/rover.urdf").display(),
        examples().display()
    );
    let scene = common::scene(&text);
    let v = &scene.vehicles[0];
    // Regolith.
    let mut ours = RigidWorld::new([0.0, 0.0, g]);
    ours.add_fixed_box("floor", [-2.0, -2.0, -0.1], [2.0, 2.0, 0.0], 0.8).expect("floor");
    let ids: Vec<_> = scene.bodies.iter().map(|b| ours.add_body(&b.desc).expect("link")).collect();
    let joints = build_vehicle_joints(&mut ours, v, &scene.bodies, &ids).expect("joints");
    for w in &v.wheels {
        ours.set_motor_target(joints[w.joint].expect("joint"), w.forward_sign * 3.0);
    }
    // Plain rapier.
    let robot = urdf_rs::read_file(examples().join("rover_description/urdf/rover.urdf")).expect("urdf");
    let mut world = PhysicsWorld { gravity: Vector::new(0.0, 0.0, g as f32), ..Default::default() };
    let floor = world.bodies.insert(RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.0, -0.05)));
    world.colliders.insert_with_parent(ColliderBuilder::cuboid(2.0, 2.0, 0.05).friction(0.8), floor, &mut world.bodies);
    let urdf_pose = |p: &urdf_rs::Pose| {
        let [r, pi, y] = p.rpy.0.map(|a| a as f32);
        let t = p.xyz.0.map(|a| a as f32);
        Pose::from_parts(
            Vector::new(t[0], t[1], t[2]),
            Rotation::from_rotation_z(y) * Rotation::from_rotation_y(pi) * Rotation::from_rotation_x(r),
        )
    };
    let mut link_pose =
        vec![Pose::from_parts(Vector::new(0.0, 0.0, base_z as f32), Rotation::IDENTITY); robot.links.len()];
    for j in &robot.joints {
        let p = robot.links.iter().position(|l| l.name == j.parent.link).expect("parent");
        let c = robot.links.iter().position(|l| l.name == j.child.link).expect("child");
        link_pose[c] = link_pose[p] * urdf_pose(&j.origin);
    }
    // Fixed joints lumped by hand, as Gazebo does: a link on a fixed joint puts its colliders
    // and its mass (on a massive sensor collider) on its parent's body, and rapier combines the
    // mass properties itself — an independent check of the importer's parallel-axis sums.
    let mut owner: Vec<usize> = (0..robot.links.len()).collect();
    let mut rel = vec![Pose::IDENTITY; robot.links.len()];
    for j in robot.joints.iter().filter(|j| j.joint_type == urdf_rs::JointType::Fixed) {
        let p = robot.links.iter().position(|l| l.name == j.parent.link).expect("parent");
        let c = robot.links.iter().position(|l| l.name == j.child.link).expect("child");
        owner[c] = owner[p];
        rel[c] = rel[p] * urdf_pose(&j.origin);
    }
    let mut handles: Vec<RigidBodyHandle> = Vec::new();
    for (i, l) in robot.links.iter().enumerate() {
        let i_ = &l.inertial.inertia;
        let m = Matrix::from_cols_array(
            &[i_.ixx, i_.ixy, i_.ixz, i_.ixy, i_.iyy, i_.iyz, i_.ixz, i_.iyz, i_.izz].map(|x| x as f32),
        );
        let com = l.inertial.origin.xyz.0.map(|x| x as f32);
        let mass =
            MassProperties::with_inertia_matrix(Vector::new(com[0], com[1], com[2]), l.inertial.mass.value as f32, m);
        let h = if owner[i] == i {
            let h = world.bodies.insert(RigidBodyBuilder::dynamic().pose(link_pose[i]).can_sleep(false));
            world.bodies[h].set_additional_mass_properties(mass, true);
            h
        } else {
            let h = handles[owner[i]];
            let carrier = ColliderBuilder::ball(1e-3).sensor(true).position(rel[i]).mass_properties(mass);
            world.colliders.insert_with_parent(carrier, h, &mut world.bodies);
            h
        };
        for c in &l.collision {
            let at = rel[i] * urdf_pose(&c.origin);
            let (shape, at) = match &c.geometry {
                urdf_rs::Geometry::Box { size } => {
                    let s = size.0.map(|x| 0.5 * x as f32);
                    (ColliderBuilder::cuboid(s[0], s[1], s[2]), at)
                }
                // rapier's cylinders run along y, URDF's along z.
                urdf_rs::Geometry::Cylinder { radius, length } => (
                    ColliderBuilder::cylinder(0.5 * *length as f32, *radius as f32),
                    at * Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2)),
                ),
                urdf_rs::Geometry::Mesh { filename, .. } => {
                    let file = examples().join(filename.trim_start_matches("package://"));
                    let mesh = regolith_rigid::load_mesh(&file, [1.0; 3]).expect("mesh");
                    let pts: Vec<Vector> =
                        mesh.vertices.iter().map(|v| Vector::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect();
                    (ColliderBuilder::convex_hull(&pts).expect("hull"), at)
                }
                other => panic!("unexpected geometry {other:?}"),
            };
            world.colliders.insert_with_parent(shape.position(at).density(0.0).friction(0.8), h, &mut world.bodies);
        }
        handles.push(h);
    }
    for j in robot.joints.iter().filter(|j| j.joint_type != urdf_rs::JointType::Fixed) {
        let p = robot.links.iter().position(|l| l.name == j.parent.link).expect("parent");
        let c = robot.links.iter().position(|l| l.name == j.child.link).expect("child");
        let frame1 = rel[p] * urdf_pose(&j.origin);
        let a = j.axis.xyz.0.map(|x| x as f32);
        let joint: GenericJoint = RevoluteJointBuilder::new(Vector::new(a[0], a[1], a[2]))
            .local_anchor1(frame1.translation)
            .local_anchor2(Vector::ZERO)
            .motor_velocity(3.0, regolith_rigid::MOTOR_GAIN)
            .motor_max_force(6.0)
            .contacts_enabled(false)
            .build()
            .into();
        world.impulse_joints.insert(handles[owner[p]], handles[c], joint, true);
    }
    let dt = 1e-3;
    world.integration_parameters.dt = dt as f32;
    let chassis = sim_index(&scene, "rover/base_link");
    let mut worst: f64 = 0.0;
    for k in 0..1000 {
        ours.step(dt);
        world.step();
        let a = ours.state(ids[chassis]).origin;
        let b = world.bodies[handles[0]].translation();
        let d = ((a[0] - f64::from(b.x)).powi(2) + (a[1] - f64::from(b.y)).powi(2) + (a[2] - f64::from(b.z)).powi(2))
            .sqrt();
        worst = worst.max(d);
        if k == 999 {
            eprintln!("after 1 s: Regolith chassis at {a:?}, plain rapier at {b:?}; largest gap {worst:.2e} m");
            // Rolling without slip on rigid ground: 3 rad/s × 0.07 m = 0.21 m/s.
            let v = ours.state(ids[chassis]).linvel[0];
            assert!((v - 0.21).abs() < 0.02, "chassis speed {v} m/s vs ωR = 0.21 m/s");
            // Resting on the wheels: base 3 cm above the wheel centres, wheels of 7 cm radius.
            assert!((a[2] - 0.10).abs() < 0.003, "chassis height {}", a[2]);
        }
    }
    assert!(worst < 2e-3, "trajectories differ by up to {worst} m");
}

fn sim_index(scene: &regolith::scene::Scene, name: &str) -> usize {
    scene.bodies.iter().position(|b| b.desc.name == name).expect("body")
}

#[test]
fn vehicle_scene_mistakes_are_one_line_errors() {
    let urdf = examples().join("rover_description/urdf/rover.urdf");
    let cases = [
        (
            format!(
                "urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3, 0.3]\nfsi_links = [\"wheel_xx\"]",
                urdf.display(),
                examples().display()
            ),
            "key `vehicles[0].fsi_links`: no link `wheel_xx`",
        ),
        (
            format!("urdf = \"{}\"\nposition = [0.3, 0.3]", urdf.display()),
            "package `rover_description` of `package://rover_description/meshes/chassis.stl` not found",
        ),
        ("urdf = \"nowhere.urdf\"\nposition = [0.3, 0.3]".to_string(), "nowhere.urdf: cannot read"),
        (
            format!("urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3]", urdf.display(), examples().display()),
            "key `vehicles[0].position`: is required: [x, y]",
        ),
        (
            format!(
                "urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3, 0.3]\ndrive = {{ left = 1.0, right = 1.0 }}",
                urdf.display(),
                examples().display()
            ),
            "key `vehicles[0].drive.max_torque`: is required",
        ),
        (
            format!(
                "urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3, 0.3]\ndrive = {{ joints = {{ mast_joint = 1.0 }}, max_torque = 2.0 }}",
                urdf.display(),
                examples().display()
            ),
            "key `vehicles[0].drive.joints`: joint `mast_joint` is fixed: link `mast` is lumped into `base_link`",
        ),
        (
            format!(
                "urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3, 0.3]\ndrive = {{ wheel_speed = [[1.0, 2.0], [0.5, 1.0]], max_torque = 2.0 }}",
                urdf.display(),
                examples().display()
            ),
            "key `vehicles[0].drive.wheel_speed`: must be a number or a list of [time s, value] pairs with increasing times",
        ),
        (
            format!(
                "urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3, 0.3]\ndifferential = {{ left = \"wheel_fl_joint\", right = \"wheel_fr_joint\" }}",
                urdf.display(),
                examples().display()
            ),
            "key `vehicles[0].differential.left`: joint `wheel_fl_joint` is a wheel joint, not a rocker",
        ),
        (
            format!(
                "urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3, 0.3]\ndifferential = {{ left = \"mast_joint\", right = \"wheel_fr_joint\" }}",
                urdf.display(),
                examples().display()
            ),
            "key `vehicles[0].differential.left`: joint `mast_joint` is fixed",
        ),
        (
            format!(
                "urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.3, 0.3]\ndifferential = {{ left = \"wheel_fl_joint\", right = \"wheel_fl_joint\" }}",
                urdf.display(),
                examples().display()
            ),
            "key `vehicles[0].differential`: left and right are the same joint `wheel_fl_joint`",
        ),
    ];
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("vehicle_scene_errors");
    std::fs::create_dir_all(&dir).expect("dir");
    // The environment must not supply the package for the unknown-package case.
    for (i, (vehicle, expected)) in cases.iter().enumerate() {
        let p = dir.join(format!("case{i}.toml"));
        std::fs::write(&p, format!("{}\n[[vehicles]]\nname = \"rover\"\n{vehicle}\n", bed_text(0.1))).expect("write");
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_regolith"))
            .arg("check")
            .arg(&p)
            .env_remove("ROS_PACKAGE_PATH")
            .env_remove("REGOLITH_PACKAGE_PATH")
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "case {i}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "case {i}: {err}");
        assert!(err.contains(expected), "case {i}: expected `{expected}` in: {err}");
    }
    // Placed through a side wall: found when the scene is built (exit 1, as a vehicle placed
    // off the soil), still one line naming the link, its reach and the wall.
    let p = dir.join("through_wall.toml");
    let vehicle =
        format!("urdf = \"{}\"\npackage_path = [\"{}\"]\nposition = [0.05, 0.3]", urdf.display(), examples().display());
    std::fs::write(&p, format!("{}\n[[vehicles]]\nname = \"rover\"\n{vehicle}\n", bed_text(0.1))).expect("write");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_regolith")).arg("check").arg(&p).output().expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!((o.status.code(), err.trim().lines().count()), (Some(1), 1), "{err}");
    assert!(
        err.contains("vehicles[0]: vehicle \"rover\" does not fit in the container: link `base_link` reaches x = -0.150 m, beyond the wall at 0.000 m"),
        "{err}"
    );
}

#[test]
fn a_vehicle_run_records_every_link_and_its_wheels() {
    let scene = rover_scene(0.02, "drive = { wheel_speed = 1.0, max_torque = 6.0 }\n\n[output]\nevery = 0.01");
    let out = common::out_dir("vehicle_run");
    regolith::run::run_scene(&scene, &regolith::run::RunOptions::quiet(out.clone())).expect("runs");
    let topics = common::read_validated(&out.join("recording.mcap"));
    assert_eq!(topics["/tf"].len(), 3);
    let tf = &topics["/tf"][0].1["transforms"];
    let children: Vec<&str> =
        tf.as_array().expect("list").iter().map(|t| t["child_frame_id"].as_str().expect("id")).collect();
    assert_eq!(
        children,
        [
            "rover/base_link",
            "rover/wheel_fl",
            "rover/wheel_fr",
            "rover/wheel_rl",
            "rover/wheel_rr",
            "rover/mast",
            "rover/camera"
        ]
    );
    // The mast and camera head, lumped into the chassis by their fixed joints, stay frames of
    // their own under it, at their URDF poses (the mast joint's origin, then the camera's).
    let (mast, camera) = (&tf[5], &tf[6]);
    assert_eq!(
        (mast["parent_frame_id"].as_str(), camera["parent_frame_id"].as_str()),
        (Some("rover/base_link"), Some("rover/base_link"))
    );
    for (frame, at) in [(mast, [0.12, 0.0, 0.04]), (camera, [0.12, 0.0, 0.04 + 0.22])] {
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            assert!((frame["translation"][axis].as_f64().expect("number") - at[k]).abs() < 1e-9, "{frame}");
        }
    }
    // Shapes: the URDF's visual geometry — the STL chassis and the COLLADA camera head as
    // triangle lists and the mast as a cube, all on the chassis they are lumped into; the
    // wheels as cylinders.
    let ents = topics["/bodies/shapes"][0].1["entities"].as_array().expect("entities").clone();
    let by_id = |id: &str| ents.iter().find(|e| e["id"] == id).unwrap_or_else(|| panic!("no entity {id}")).clone();
    let base = by_id("rover/base_link");
    assert_eq!(base["triangles"][0]["indices"].as_array().expect("indices").len(), 3 * 28);
    assert_eq!(base["triangles"][1]["indices"].as_array().expect("indices").len(), 3 * 12);
    assert_eq!(base["cubes"].as_array().expect("cubes").len(), 1);
    assert_eq!(by_id("rover/wheel_fl")["cylinders"].as_array().expect("cyl").len(), 1);
    let v = &topics["/vehicles/rover"];
    assert_eq!(v.len(), 3);
    assert!(v[2].1["wheel_rr.sinkage"].is_number() && v[2].1["yaw"].is_number());
    let csv = std::fs::read_to_string(out.join("series.csv")).expect("series");
    let header = csv.lines().next().expect("header");
    for c in
        ["rover.x", "rover.yaw", "rover.speed", "rover/wheel_fl.slip", "rover/wheel_rr.sinkage", "rover/wheel_fl.fz"]
    {
        assert!(header.split(',').any(|h| h == c), "series.csv lacks {c}: {header}");
    }
    for ext in ["png", "svg"] {
        let p = out.join(format!("vehicle_rover.{ext}"));
        assert!(std::fs::metadata(&p).map(|m| m.len() > 1000).unwrap_or(false), "{} missing", p.display());
    }
}
