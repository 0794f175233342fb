//! The rigid world behaves as rapier does, and its additions (wrenches, motors, prescribed
//! motion) do what they say.

use rapier3d::prelude::*;
use regolith_rigid::{
    Axis, BodyDesc, JointDesc, JointKind, MassSpec, Motion, Pose, RigidWorld, ShapeDesc, VelocityMotor,
};

fn body(name: &str, shape: ShapeDesc, mass: f64, at: [f64; 3], motion: Motion) -> BodyDesc {
    BodyDesc {
        name: name.into(),
        shape,
        mass: MassSpec::Mass(mass),
        pose: Pose::translation(at),
        motion,
        friction: 0.5,
        collides: true,
    }
}

#[test]
fn a_free_body_falls_exactly_as_in_plain_rapier() {
    let mut w = RigidWorld::new([0.0, 0.0, -9.81]);
    let b = w
        .add_body(&body("box", ShapeDesc::Box { size: [0.2, 0.3, 0.1] }, 3.0, [0.0, 0.0, 1.0], Motion::Free))
        .expect("body");
    w.add_fixed_box("floor", [-1.0, -1.0, -0.1], [1.0, 1.0, 0.0], 0.5).expect("floor");

    let mut r = PhysicsWorld { gravity: Vector::new(0.0, 0.0, -9.81), ..Default::default() };
    let h =
        r.bodies.insert(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.0, 1.0)).can_sleep(false).build());
    let vol = 0.2 * 0.3 * 0.1;
    r.colliders.insert_with_parent(
        ColliderBuilder::cuboid(0.1, 0.15, 0.05).density((3.0 / vol) as f32).friction(0.5).build(),
        h,
        &mut r.bodies,
    );
    let g = r.bodies.insert(RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.0, -0.05)).build());
    r.colliders.insert_with_parent(
        ColliderBuilder::cuboid(1.0, 1.0, 0.05).density(1000.0).friction(0.5).build(),
        g,
        &mut r.bodies,
    );

    for _ in 0..400 {
        w.step(1.0 / 240.0);
        r.integration_parameters.dt = 1.0 / 240.0;
        r.step();
        let a = w.state(b);
        let p = r.bodies[h].translation();
        assert_eq!(a.origin, [f64::from(p.x), f64::from(p.y), f64::from(p.z)], "trajectories diverge");
    }
    // It landed on the floor: half its height above z = 0.
    assert!((w.state(b).origin[2] - 0.05).abs() < 2e-3);
    assert!((w.mass(b) - 3.0).abs() < 1e-5);
}

#[test]
fn a_wrench_at_the_centre_of_mass_accelerates_without_spin() {
    let mut w = RigidWorld::new([0.0; 3]);
    let b = w.add_body(&body("ball", ShapeDesc::Sphere { radius: 0.1 }, 2.0, [0.0; 3], Motion::Free)).expect("body");
    w.set_wrench(b, [4.0, 0.0, 0.0], [0.0; 3]);
    for _ in 0..100 {
        w.step(0.01);
    }
    let s = w.state(b);
    // v = F/m t = 2 m/s after 1 s; the force is applied every step, not accumulated.
    assert!((s.linvel[0] - 2.0).abs() < 1e-4, "v = {:?}", s.linvel);
    assert!((s.linacc[0] - 2.0).abs() < 1e-3);
    assert!(s.angvel.iter().all(|w| w.abs() < 1e-9));
    // A pure torque spins it: I = 2/5 m r² = 0.008 kg m², τ = 0.008 → α = 1 rad/s².
    w.set_wrench(b, [0.0; 3], [0.0, 0.0, 0.008]);
    for _ in 0..100 {
        w.step(0.01);
    }
    let s = w.state(b);
    assert!((s.angvel[2] - 1.0).abs() < 1e-3, "ω = {:?}", s.angvel);
}

#[test]
fn a_revolute_motor_drives_a_wheel_at_its_target_speed() {
    let mut w = RigidWorld::new([0.0, 0.0, -9.81]);
    let frame = w
        .add_body(&body("frame", ShapeDesc::Box { size: [0.1, 0.1, 0.1] }, 1.0, [0.0, 0.0, 1.0], Motion::Fixed))
        .expect("frame");
    let wheel = w
        .add_body(&body(
            "wheel",
            ShapeDesc::Wheel { radius: 0.2, width: 0.1, grousers: None },
            5.0,
            [0.0, 0.0, 1.0],
            Motion::Free,
        ))
        .expect("wheel");
    let j = w
        .add_joint(&JointDesc {
            name: "axle".into(),
            body1: frame,
            body2: wheel,
            kind: JointKind::Revolute,
            anchor: [0.0, 0.0, 1.0],
            axis: [0.0, 1.0, 0.0],
            motor: Some(VelocityMotor { target: 2.0, max_effort: 100.0 }),
        })
        .expect("joint");
    for _ in 0..200 {
        w.step(1.0 / 200.0);
    }
    let s = w.state(wheel);
    assert!((s.angvel[1] - 2.0).abs() < 0.02, "ω = {:?}", s.angvel);
    assert!((s.origin[2] - 1.0).abs() < 1e-3, "the axle holds the wheel up");
    w.set_motor_target(j, -1.0);
    for _ in 0..200 {
        w.step(1.0 / 200.0);
    }
    assert!((w.state(wheel).angvel[1] + 1.0).abs() < 0.02);
}

#[test]
fn prescribed_and_waypoint_motion_follow_their_paths() {
    let mut w = RigidWorld::new([0.0, 0.0, -9.81]);
    let a = w
        .add_body(&body(
            "plate",
            ShapeDesc::Cylinder { radius: 0.1, length: 0.02, axis: Axis::Z },
            1.0,
            [0.0, 0.0, 0.5],
            Motion::Prescribed { linvel: [0.0, 0.0, -0.1], angvel: [0.0; 3] },
        ))
        .expect("plate");
    let c = w
        .add_body(&body(
            "cone",
            ShapeDesc::Cone { radius: 0.02, height: 0.05 },
            1.0,
            [0.0, 0.0, 0.5],
            Motion::Waypoints(vec![(0.0, [0.0, 0.0, 0.5]), (1.0, [0.0, 0.0, 0.3]), (2.0, [0.0, 0.0, 0.5])]),
        ))
        .expect("cone");
    for _ in 0..100 {
        w.step(0.01);
    }
    assert!((w.state(a).origin[2] - 0.4).abs() < 1e-5);
    assert!((w.state(c).origin[2] - 0.3).abs() < 1e-5);
    w.set_prescribed_velocity(a, [0.0; 3], [0.0; 3]);
    for _ in 0..50 {
        w.step(0.01);
    }
    assert!((w.state(a).origin[2] - 0.4).abs() < 1e-5);
    assert!((w.state(c).origin[2] - 0.4).abs() < 1e-5);
}

#[test]
fn invalid_descriptions_are_errors() {
    let mut w = RigidWorld::new([0.0; 3]);
    assert!(w.add_body(&body("a", ShapeDesc::Sphere { radius: -1.0 }, 1.0, [0.0; 3], Motion::Free)).is_err());
    w.add_body(&body("a", ShapeDesc::Sphere { radius: 1.0 }, 1.0, [0.0; 3], Motion::Free)).expect("ok");
    assert!(
        w.add_body(&body("a", ShapeDesc::Sphere { radius: 1.0 }, 1.0, [0.0; 3], Motion::Free)).is_err(),
        "duplicate name"
    );
}

#[test]
fn positions_integrate_the_reported_velocity() {
    let mut w = RigidWorld::new([0.0, 0.0, -9.81]);
    let b = w
        .add_body(&body("box", ShapeDesc::Box { size: [0.1, 0.1, 0.04] }, 4.0, [0.0, 0.0, 1.0], Motion::Free))
        .expect("body");
    w.set_wrench(b, [0.0, 0.0, 1.5 * 4.0 * 9.81], [0.0; 3]);
    let dt = 1e-3;
    let mut z = w.state(b).com[2];
    for _ in 0..500 {
        w.step(dt);
        let s = w.state(b);
        // Rapier takes 4 substeps per step: under a constant acceleration a the position moves
        // v_n dt + (k + 1)/(2k) a dt² = v_n dt + 0.625 a dt² (a = g/2 here).
        let v_old = s.linvel[2] - 0.5 * 9.81 * dt;
        let expect = z + v_old * dt + 0.625 * 0.5 * 9.81 * dt * dt;
        assert!((s.com[2] - expect).abs() < 1e-6, "z {} vs {expect}", s.com[2]);
        z = s.com[2];
    }
    assert!((w.state(b).linvel[2] - 0.5 * 9.81 * 0.5).abs() < 1e-3);
}

#[test]
fn a_carriage_on_a_moving_sled_drops_freely_and_rolls_its_wheel() {
    // The single-wheel rig without soil: sled (prescribed x) —prismatic z→ carriage —revolute y→
    // wheel. The wheel must fall to the floor and then roll along with the sled.
    let mut w = RigidWorld::new([0.0, 0.0, -9.81]);
    w.add_fixed_box("floor", [-5.0, -1.0, -0.1], [5.0, 1.0, 0.0], 0.8).expect("floor");
    let c = [0.0, 0.0, 0.3];
    let ghost = |name: &str, motion: Motion| BodyDesc {
        name: name.into(),
        shape: ShapeDesc::Box { size: [0.05; 3] },
        mass: MassSpec::Mass(1.0),
        pose: Pose::translation(c),
        motion,
        friction: 0.0,
        collides: false,
    };
    let sled =
        w.add_body(&ghost("sled", Motion::Prescribed { linvel: [0.1, 0.0, 0.0], angvel: [0.0; 3] })).expect("sled");
    let carriage = w.add_body(&ghost("carriage", Motion::Free)).expect("carriage");
    let wheel = w
        .add_body(&body("wheel", ShapeDesc::Wheel { radius: 0.1, width: 0.05, grousers: None }, 2.0, c, Motion::Free))
        .expect("wheel");
    let joint = |name: &str, b1, b2, kind, axis| JointDesc {
        name: name.into(),
        body1: b1,
        body2: b2,
        kind,
        anchor: c,
        axis,
        motor: None,
    };
    w.add_joint(&joint("vertical", sled, carriage, JointKind::Prismatic, [0.0, 0.0, 1.0])).expect("prismatic");
    w.add_joint(&JointDesc {
        motor: Some(VelocityMotor { target: 1.0, max_effort: 100.0 }),
        ..joint("axle", carriage, wheel, JointKind::Revolute, [0.0, 1.0, 0.0])
    })
    .expect("revolute");
    for _ in 0..1000 {
        w.step(1e-3);
    }
    let s = w.state(wheel);
    assert!((s.origin[2] - 0.1).abs() < 5e-3, "the wheel rests on the floor: z = {}", s.origin[2]);
    assert!((s.linvel[0] - 0.1).abs() < 1e-3, "it follows the sled: vx = {}", s.linvel[0]);
    assert!((s.angvel[1] - 1.0).abs() < 0.05, "it spins at the motor speed: ω = {:?}", s.angvel);
}

/// A fixed chassis with two 2 kg rockers on revolute joints about y (pivots at their centres,
/// no gravity), coupled by a differential; returns the world, the rockers and their joints.
fn rockers_on_a_differential() -> (RigidWorld, [regolith_rigid::BodyId; 2], [regolith_rigid::JointId; 2]) {
    let mut w = RigidWorld::new([0.0; 3]);
    let chassis = w
        .add_body(&body("chassis", ShapeDesc::Box { size: [0.2, 0.2, 0.1] }, 10.0, [0.0, 0.0, 1.0], Motion::Fixed))
        .expect("chassis");
    let mut rockers = Vec::new();
    let mut joints = Vec::new();
    for (name, y) in [("left", 0.3), ("right", -0.3)] {
        let r = w
            .add_body(&body(name, ShapeDesc::Box { size: [0.4, 0.05, 0.05] }, 2.0, [0.0, y, 1.0], Motion::Free))
            .expect("rocker");
        let j = w
            .add_joint(&JointDesc {
                name: format!("{name}_rocker"),
                body1: chassis,
                body2: r,
                kind: JointKind::Revolute,
                anchor: [0.0, y, 1.0],
                axis: [0.0, 1.0, 0.0],
                motor: None,
            })
            .expect("joint");
        rockers.push(r);
        joints.push(j);
    }
    w.add_differential(joints[0], joints[1], 1.0).expect("differential");
    (w, [rockers[0], rockers[1]], [joints[0], joints[1]])
}

#[test]
fn a_differential_lets_the_rockers_swing_oppositely_and_holds_them_against_a_common_swing() {
    // Opposite torques (the differential's free mode): each rocker turns as if alone,
    // θ = ½ (τ / I) t² with I = m (L² + h²) / 12 about y; the other mirrors it.
    let (mut w, [l, r], [jl, jr]) = rockers_on_a_differential();
    let (tau, inertia, t) = (0.5, 2.0 * (0.4f64.powi(2) + 0.05f64.powi(2)) / 12.0, 0.2);
    w.set_wrench(l, [0.0; 3], [0.0, tau, 0.0]);
    w.set_wrench(r, [0.0; 3], [0.0, -tau, 0.0]);
    for _ in 0..200 {
        w.step(t / 200.0);
    }
    let (al, wl) = w.joint_position(jl).expect("revolute");
    let (ar, wr) = w.joint_position(jr).expect("revolute");
    let expected = 0.5 * tau / inertia * t * t;
    assert!((al - expected).abs() < 0.02 * expected, "left rocker {al} rad, free rotation gives {expected}");
    assert!((al + ar).abs() < 1e-3 && (wl + wr).abs() < 1e-2, "θ {al} + {ar}, ω {wl} + {wr}");
    // The joint angle is the rocker's own rotation about y (the chassis is fixed).
    let q = w.state(l).rotation;
    assert!((2.0 * q[1].atan2(q[3]) - al).abs() < 1e-5, "{q:?} against {al}");

    // Equal torques (the mode the bar forbids): the rockers barely move against the fixed
    // chassis; left alone each would turn `expected` rad in the same time.
    let (mut w, [l, r], [jl, jr]) = rockers_on_a_differential();
    w.set_wrench(l, [0.0; 3], [0.0, tau, 0.0]);
    w.set_wrench(r, [0.0; 3], [0.0, tau, 0.0]);
    for _ in 0..200 {
        w.step(t / 200.0);
    }
    let (al, ar) = (w.joint_position(jl).expect("revolute").0, w.joint_position(jr).expect("revolute").0);
    assert!(al.abs() < 1e-3 && ar.abs() < 1e-3, "held: θ = {al}, {ar} rad");
}

#[test]
fn a_differential_needs_two_distinct_revolute_joints() {
    let (mut w, _, [jl, _]) = rockers_on_a_differential();
    assert!(w.add_differential(jl, jl, 1.0).is_err());
    let a = w.add_body(&body("a", ShapeDesc::Box { size: [0.1; 3] }, 1.0, [2.0, 0.0, 1.0], Motion::Free)).expect("a");
    let b = w.add_body(&body("b", ShapeDesc::Box { size: [0.1; 3] }, 1.0, [2.2, 0.0, 1.0], Motion::Free)).expect("b");
    let fixed = w
        .add_joint(&JointDesc {
            name: "weld".into(),
            body1: a,
            body2: b,
            kind: JointKind::Fixed,
            anchor: [2.1, 0.0, 1.0],
            axis: [1.0, 0.0, 0.0],
            motor: None,
        })
        .expect("fixed");
    let e = w.add_differential(jl, fixed, 1.0).expect_err("a fixed joint has no angle");
    assert!(e.to_string().contains("weld"), "{e}");
    assert!(w.joint_position(fixed).is_none());
}

#[test]
fn bodies_that_ignore_collisions_among_themselves_still_meet_the_rest() {
    // Two boxes overlapping by 5 cm along x and a third overlapping the second by 5 cm along z
    // (clear of the first), no gravity: rapier pushes overlapping bodies apart, except the two
    // made to ignore each other.
    let make = |ignore: bool| {
        let mut w = RigidWorld::new([0.0; 3]);
        let at = [[0.0, 0.0, 0.0], [0.15, 0.0, 0.0], [0.25, 0.0, 0.15]];
        let ids: Vec<_> = at
            .iter()
            .enumerate()
            .map(|(i, p)| {
                w.add_body(&body(&format!("b{i}"), ShapeDesc::Box { size: [0.2; 3] }, 1.0, *p, Motion::Free))
                    .expect("body")
            })
            .collect();
        if ignore {
            w.ignore_collisions_among(&ids[..2]).expect("a group");
        }
        for _ in 0..50 {
            w.step(1e-3);
        }
        let x = |i: usize| w.state(ids[i]).origin;
        (x(1)[0] - x(0)[0], x(2)[2] - x(1)[2])
    };
    let (apart, above) = make(false);
    assert!(apart > 0.16 && above > 0.16, "all three collide: {apart}, {above}");
    let (apart, above) = make(true);
    assert!((apart - 0.15).abs() < 1e-6, "the pair ignores its overlap: {apart}");
    assert!(above > 0.16, "the third body still pushes the second away: {above}");

    let mut w = RigidWorld::new([0.0; 3]);
    for _ in 0..32 {
        w.ignore_collisions_among(&[]).expect("32 groups");
    }
    assert!(w.ignore_collisions_among(&[]).expect_err("33rd").to_string().contains("more than 32"));
}
