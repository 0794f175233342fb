//! Frictional traction at the body–soil interface (issue 45): a plate dragged over the soil
//! carries a tangential force of about the soil's friction times its weight at any drag speed,
//! and a wheel held at 100 % slip needs a torque of about μ × load × r that follows the load,
//! not the speed. Before the rig fix the GRC-1 wheel's torque was 4 N m s × ω whatever its
//! load: the rig's light carriage, free to turn, was all its axle motor pushed against (NOTES.md,
//! "A driven wheel that did not drive").

use crate::common;

use regolith::run::{RunOptions, run_scene};
use regolith::sim::Simulation;
use regolith_rigid::{BodyDesc, JointDesc, JointKind, MassSpec, Motion, Pose, ShapeDesc};

/// Soil friction angle of both tests (degrees) and the Drucker–Prager cone it gives in
/// `√J2 = μ p` form, `μ = 2√3 sin φ / (3 − sin φ)` (0.693 at 30°).
const PHI: f64 = 30.0;

fn sand(d0: f64, end: f64, container: [f64; 3], depth: f64, extra: &str) -> String {
    format!(
        "[simulation]\nend_time = {end}\nprecision = \"f32\"\nexchange_interval = 0.001\n\n[sph]\nspacing = {d0}\n\n\
         [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = {PHI}\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{}, {}, {}]\n\n[terrain]\nmaterial = \"sand\"\ndepth = {depth}\n\n{extra}",
        container[0], container[1], container[2]
    )
}

/// Where the drag is read: from 20 to 40 mm of travel. A plate on this bed mobilises its
/// friction over its first 15–20 mm (about 1.5 d0, the marker and particle lattices locking),
/// so a window in time rather than in travel compares a slow plate still loading with a fast
/// one sliding (NOTES.md, "The plate's rate dependence was its travel").
const WINDOW: (f64, f64) = (0.020, 0.040);

/// A 0.1 × 0.1 m plate of 4 kg (3.9 kPa) resting on a 5 cm bed, dragged along x at `speed`
/// from t = 0.05 s by a prescribed sled through a vertical slider (the plate only translates
/// and carries its own weight) until it has travelled the end of [`WINDOW`]. Returns the mean
/// soil force ratio −F_x / F_z over the window's travel and the time the window took.
fn drag_plate(speed: f64) -> (f64, f64) {
    let settle = 0.05;
    let end = settle + WINDOW.1 / speed + 0.01;
    let plate = "[[bodies]]\nname = \"plate\"\nshape = { type = \"box\", size = [0.1, 0.1, 0.03] }\nmass = 4.0\nposition = [0.1, 0.1, 0.09]\n";
    let mut text = sand(0.0125, end, [0.4, 0.2, 0.2], 0.05, plate);
    // The plate's lowest markers one spacing above the top particle centre (z = 0.04375).
    text = text.replace("position = [0.1, 0.1, 0.09]", "position = [0.1, 0.1, 0.07125]");
    let scene = common::scene(&text);
    let mut sim = Simulation::<f32>::new(&scene).expect("builds");
    let b = sim.body("plate").expect("plate");
    let plate = sim.rigid_id(b);
    let centre = sim.body_state(b).com;
    let rigid = &mut sim.system.rigid;
    let sled = rigid
        .add_body(&BodyDesc {
            name: "sled".into(),
            shape: ShapeDesc::Box { size: [0.05; 3] },
            mass: MassSpec::Mass(1.0),
            pose: Pose::translation(centre),
            motion: Motion::Prescribed { linvel: [0.0; 3], angvel: [0.0; 3] },
            friction: 0.0,
            collides: false,
        })
        .expect("sled");
    rigid.lock_rotations(plate);
    rigid
        .add_joint(&JointDesc {
            name: "slider".into(),
            body1: sled,
            body2: plate,
            kind: JointKind::Prismatic,
            anchor: centre,
            axis: [0.0, 0.0, 1.0],
            motor: None,
        })
        .expect("slider");
    let (mut fx, mut fz, mut span) = (0.0, 0.0, None::<(f64, f64)>);
    while sim.time() < end - 1e-9 {
        if sim.time() >= settle - 1e-9 {
            sim.system.rigid.set_prescribed_velocity(sled, [speed, 0.0, 0.0], [0.0; 3]);
        }
        sim.step().expect("step");
        let travel = sim.body_state(b).com[0] - centre[0];
        if travel >= WINDOW.0 && travel < WINDOW.1 {
            let w = sim.fsi_wrench(b);
            fx += w.force[0];
            fz += w.force[2];
            let t = sim.time();
            span = Some(span.map_or((t, t), |(t0, _)| (t0, t)));
        }
    }
    let (t0, t1) = span.expect("the plate travelled through the window");
    (-fx / fz, t1 - t0)
}

#[test]
fn a_plate_dragged_over_sand_carries_its_friction_at_any_speed() {
    // Measured (d0 = 12.5 mm, 2 vCPU, 2026-12-07), mean −Fx/Fz from 20 to 40 mm of travel:
    // 0.734 at 0.05 m/s, 0.765 at 0.15 m/s, 0.783 at 0.5 m/s (+7 % over a tenfold speed). Read
    // over the same time window instead (the test before session 28), the slow plate was still
    // mobilising (0.482) and the fast one sliding (0.850): +76 % that was travel, not rate.
    let tan_phi = PHI.to_radians().tan();
    let (slow, t_slow) = drag_plate(0.05);
    let (fast, t_fast) = drag_plate(0.5);
    eprintln!(
        "−Fx/Fz from 20 to 40 mm of travel: {slow:.3} at 0.05 m/s ({t_slow:.3} s), {fast:.3} at 0.5 m/s ({t_fast:.3} s); tan φ = {tan_phi:.3}"
    );
    // The plate follows the sled (it slides over the soil, not with it): 20 mm of travel in
    // the time the sled takes, within 15 %.
    let want = WINDOW.1 - WINDOW.0;
    assert!((t_slow * 0.05 - want).abs() < 0.15 * want, "slow plate took {t_slow} s for {want} m");
    assert!((t_fast * 0.5 - want).abs() < 0.15 * want, "fast plate took {t_fast} s for {want} m");
    // Sliding: at least the soil's friction on the sliding plane, tan φ, and at most the
    // cone's √J2 = μ p friction (0.693) plus the bow wave of a plate sinking 5 mm, 0.9.
    for (k, v) in [(slow, 0.05), (fast, 0.5)] {
        assert!(k > tan_phi && k < 0.9, "friction ratio {k} at {v} m/s (tan φ = {tan_phi})");
    }
    // The goal: independent of speed within 15 % over a tenfold speed (a viscous
    // interface gives ten times the force).
    assert!((fast - slow).abs() < 0.15 * slow, "slow {slow} vs fast {fast}");
}

/// Steady torque (N m) and measured spin (rad/s) of a smooth wheel (r = 0.1 m) held at 100 %
/// slip on sand, under `load` (N) at `omega` (rad/s) for `end` seconds: the rig's means over
/// the second half of the run.
fn full_slip_torque(load: f64, omega: f64, end: f64) -> (f64, f64) {
    let wheel = "[[bodies]]\nname = \"wheel\"\nshape = { type = \"wheel\", radius = 0.1, width = 0.08, grousers = 0 }\nmass = 2.0\nposition = [0.2, 0.1, 0.3]\n\n";
    let rig = format!(
        "[rig]\ntype = \"wheel\"\nbody = \"wheel\"\nload = {load}\nangular_velocity = {omega}\nslips = [1.0]\n\n[output]\nmcap = false\n"
    );
    let scene = common::scene(&sand(0.0125, end, [0.4, 0.2, 0.3], 0.075, &format!("{wheel}{rig}")));
    let s = run_scene(&scene, &RunOptions::quiet(common::out_dir(&format!("full_slip_{load}_{omega}")))).expect("runs");
    let r = &s.rig.as_ref().expect("rig")["steady_state"][0];
    let num = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} in {r}"));
    (num("torque"), num("spin"))
}

#[test]
fn a_wheel_at_full_slip_needs_a_torque_that_follows_its_load_not_its_speed() {
    // A wheel spinning in place digs in, and its torque grows with the rim's travel (with the
    // sinkage): 2.21 N m over its second 10 mm, 2.68 over 50–60 mm, 2.91 over 100–120 mm at
    // 2 rad/s (measured 2026-12-07, d0 = 12.5 mm). So the two speeds are read over the same
    // rim travel, 45–90 mm (the second half of each run): 0.45 s at 2 rad/s, 0.1125 s at
    // 8 rad/s. Read over the same time instead (0.15–0.3 s, the test before session 28), the
    // fast wheel had travelled four times as far and needed 15 % more torque.
    let r = 0.1;
    let base = full_slip_torque(40.0, 2.0, 0.45);
    let fast = full_slip_torque(40.0, 8.0, 0.1125);
    let heavy = full_slip_torque(80.0, 2.0, 0.45);
    let ratio = |t: f64, load: f64| t / (load * r);
    eprintln!(
        "torque / (load r): {:.3} (40 N, 2 rad/s, spin {:.3}), {:.3} (40 N, 8 rad/s, spin {:.3}), {:.3} (80 N, 2 rad/s, spin {:.3})",
        ratio(base.0, 40.0),
        base.1,
        ratio(fast.0, 40.0),
        fast.1,
        ratio(heavy.0, 80.0),
        heavy.1
    );
    // The motor holds the commanded spin (to its compliance, 5 %).
    for (spin, want) in [(base.1, 2.0), (fast.1, 8.0), (heavy.1, 2.0)] {
        assert!((spin - want).abs() < 0.05 * want, "spin {spin} rad/s vs {want}");
    }
    // Friction: about the soil's friction at the rim.
    for (t, load) in [(base.0, 40.0), (fast.0, 40.0), (heavy.0, 80.0)] {
        let k = ratio(t, load);
        assert!(k > 0.45 && k < 0.9, "torque / (load r) = {k}");
    }
    // The goal: a fourfold speed within 15 % (measured 0.682 and 0.689 of load × r,
    // +1 %; the stalled rig gave +300 %). Twice the load: 1.6 to 2.4 times the torque
    // (measured 1.75: 0.597 at 80 N).
    assert!((fast.0 - base.0).abs() < 0.15 * base.0, "ω × 4: {} vs {} N m", fast.0, base.0);
    let k = heavy.0 / base.0;
    assert!(k > 1.6 && k < 2.4, "load × 2: torque × {k}");
}
