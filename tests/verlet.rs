//! Neighbour-list reuse with a Verlet skin (`sph.neighbor_skin`): lists are rebuilt only when
//! some particle or body marker has moved far enough that a pair inside the support could be
//! missing, so a run with a skin visits exactly the pairs of a run that rebuilds every step.
//! What may differ is the order of the sums (particles are re-sorted less often) and the few
//! pairs that enter the support between a step's two stages, which a list built at the step's
//! start misses without a skin. Checked on a resting geostatic bed and a collapsing column, in
//! f64 (where the two runs agree to round-off) and f32, and on a box pushed through the soil
//! (moving body markers).

use crate::common;

use regolith::build::build_soil;
use regolith::fsi::Real;
use regolith::sim::Simulation;

/// Per particle (by original index): position, velocity and stress components.
struct Snapshot {
    pos: Vec<[f64; 3]>,
    vel: Vec<[f64; 3]>,
    sigma: Vec<[f64; 6]>,
    builds: u64,
    steps: u64,
}

fn soil_run<T: Real>(name: &str, sets: &[&str], steps: usize) -> Snapshot {
    let scene = common::example(name, sets);
    let mut m = build_soil::<T>(&scene).expect("builds");
    for _ in 0..steps {
        m.solver.step(None).expect("step");
    }
    let s = m.solver.as_cpu().expect("a CPU scene");
    let n = s.len();
    let (mut pos, mut vel, mut sigma) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n], vec![[0.0; 6]; n]);
    for i in 0..n {
        let id = s.ids()[i] as usize;
        pos[id] = s.positions()[i].as_f64();
        vel[id] = s.velocities()[i].as_f64();
        let g = s.stresses()[i];
        sigma[id] = [g.xx, g.yy, g.zz, g.xy, g.xz, g.yz].map(|x| x.as_f64());
    }
    Snapshot { pos, vel, sigma, builds: s.list_builds(), steps: s.steps() }
}

/// Largest differences: position (over d0), velocity (over the largest speed), stress (over
/// the largest stress component).
fn differences(a: &Snapshot, b: &Snapshot, d0: f64) -> (f64, f64, f64) {
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let vmax = max_abs(&a.vel.iter().flatten().copied().collect::<Vec<_>>()).max(1e-12);
    let smax = max_abs(&a.sigma.iter().flatten().copied().collect::<Vec<_>>()).max(1e-12);
    let diff = |x: &[[f64; 3]], y: &[[f64; 3]]| {
        x.iter().zip(y).flat_map(|(p, q)| p.iter().zip(q).map(|(u, v)| (u - v).abs())).fold(0.0, f64::max)
    };
    let ds =
        a.sigma.iter().zip(&b.sigma).flat_map(|(p, q)| p.iter().zip(q).map(|(u, v)| (u - v).abs())).fold(0.0, f64::max);
    (diff(&a.pos, &b.pos) / d0, diff(&a.vel, &b.vel) / vmax, ds / smax)
}

fn compare<T: Real>(name: &str, sets: &[&str], steps: usize, d0: f64, tol: (f64, f64, f64)) -> (u64, u64) {
    let with = |skin: &str| {
        let mut s: Vec<&str> = sets.to_vec();
        s.push(skin);
        soil_run::<T>(name, &s, steps)
    };
    let every = with("sph.neighbor_skin=0");
    let reused = with("sph.neighbor_skin=0.3");
    assert_eq!(every.builds, every.steps, "without a skin the lists are rebuilt every step");
    let (dx, dv, ds) = differences(&every, &reused, d0);
    eprintln!(
        "{name} {}: {} steps, {} list builds with the skin; |Δx|/d0 = {dx:.2e}, |Δv|/v_max = {dv:.2e}, |Δσ|/σ_max = {ds:.2e}",
        T::NAME,
        reused.steps,
        reused.builds
    );
    assert!(dx <= tol.0, "positions differ by {dx:.3e} d0 (allowed {:.1e})", tol.0);
    assert!(dv <= tol.1, "velocities differ by {dv:.3e} of the largest speed (allowed {:.1e})", tol.1);
    assert!(ds <= tol.2, "stresses differ by {ds:.3e} of the largest stress (allowed {:.1e})", tol.2);
    (reused.builds, reused.steps)
}

const GEOSTATIC: [&str; 3] = ["sph.spacing=0.04", "simulation.dt=5e-5", "container.max=[0.4, 0.4, 0.5]"];

#[test]
fn a_resting_bed_reuses_its_lists_and_matches_rebuilding_every_step() {
    let (builds, steps) = compare::<f64>("geostatic_box.toml", &GEOSTATIC, 300, 0.04, (1e-12, 1e-10, 1e-12));
    assert!(builds * 20 <= steps, "a bed at rest should rebuild rarely: {builds} builds in {steps} steps");
    compare::<f32>(
        "geostatic_box.toml",
        &[&GEOSTATIC[..], &["simulation.precision=f32"]].concat(),
        300,
        0.04,
        (1e-5, 1e-3, 1e-5),
    );
}

const COLUMN: [&str; 2] = ["sph.spacing=0.02", "simulation.dt=2e-4"];

#[test]
fn a_collapsing_column_rebuilds_as_it_flows_and_matches_rebuilding_every_step() {
    let f64_sets = [&COLUMN[..], &["simulation.precision=f64"]].concat();
    let (builds, steps) = compare::<f64>("column_collapse.toml", &f64_sets, 500, 0.02, (1e-9, 1e-8, 1e-8));
    assert!(builds > 2 && builds * 3 <= steps, "a flowing column should rebuild now and then: {builds} in {steps}");
    compare::<f32>("column_collapse.toml", &COLUMN, 500, 0.02, (1e-4, 1e-4, 1e-4));
}

/// A sphere ploughing sideways through the soil at 0.5 m/s and a box dropped onto it, f64: the
/// body markers move every exchange, so the lists must be rebuilt for them as well.
#[test]
fn moving_bodies_get_the_same_soil_forces_with_reused_lists() {
    let text = |skin: f64| {
        format!(
            "[simulation]\nend_time = 0.1\nprecision = \"f64\"\nexchange_interval = 0.001\ndt = 1e-4\n\n[sph]\nspacing = 0.01\nneighbor_skin = {skin}\n\n\
             [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
             [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.22, 0.16, 0.16]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.07\n\n\
             [[bodies]]\nname = \"ball\"\nshape = {{ type = \"sphere\", radius = 0.03 }}\nmass = 1.0\nposition = [0.05, 0.08, 0.07]\n\
             motion = {{ type = \"prescribed\", linear_velocity = [0.5, 0.0, 0.0] }}\n\n\
             [[bodies]]\nname = \"box\"\nshape = {{ type = \"box\", size = [0.05, 0.05, 0.03] }}\nmass = 1.0\nposition = [0.16, 0.08, 0.09]\n"
        )
    };
    let run = |skin: f64| {
        let scene = common::scene(&text(skin));
        let mut sim = Simulation::<f64>::new(&scene).expect("builds");
        let bodies = [sim.body("ball").expect("ball"), sim.body("box").expect("box")];
        let mut forces = Vec::new();
        for _ in 0..60 {
            sim.step().expect("step");
            forces.push(bodies.map(|b| sim.fsi_wrench(b).force));
        }
        let s = sim.system.fluid.as_cpu().expect("cpu");
        (forces, s.list_builds(), s.steps(), sim.body_state(bodies[1]).origin, s.stage_retries())
    };
    let (f0, b0, n0, box0, r0) = run(0.0);
    let (f1, b1, n1, box1, r1) = run(0.3);
    // Without a skin nothing is ever redone; with one, a redone step is one of the builds.
    assert_eq!(r0, 0);
    assert!(r1 <= b1, "{r1} steps redone but only {b1} builds");
    assert_eq!(b0, n0);
    let scale = f0.iter().flatten().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let worst = f0
        .iter()
        .zip(&f1)
        .flat_map(|(a, b)| a.iter().zip(b).flat_map(|(u, v)| u.iter().zip(v).map(|(x, y)| (x - y).abs())))
        .fold(0.0, f64::max);
    let dbox = (0..3).map(|k| (box0[k] - box1[k]).abs()).fold(0.0, f64::max);
    eprintln!(
        "ploughing sphere: {n1} steps, {b1} list builds ({r1} steps redone) with the skin; largest force difference {:.2e} of the largest force ({scale:.3} N); box position differs by {dbox:.2e} m",
        worst / scale
    );
    assert!(scale > 1.0, "the sphere must meet the soil ({scale} N)");
    assert!(b1 > 2 && b1 * 3 <= n1, "{b1} builds in {n1} steps");
    assert!(worst <= 1e-7 * scale, "FSI forces differ by {:.3e} of the largest force", worst / scale);
    assert!(dbox <= 1e-10, "the free box ended {dbox:.3e} m apart");
}
