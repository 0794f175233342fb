//! A bed at rest under gravity keeps its geostatic state: σv = ρ g depth and σh = K0 σv, the
//! soil does not move and nothing leaves the container.

use crate::common;

use regolith::build::build_soil;
use regolith::fsi::Real;

fn bed(model: &str, precision: &str, kernel: &str) -> String {
    let material = match model {
        "mcc" => "model = \"mcc\"\nmcc_m = 1.2\nmcc_kappa = 0.02\nmcc_lambda = 0.1\nmcc_v_lambda = 2.4\nocr = 2.0\n",
        _ => "model = \"drucker-prager\"\nfriction_angle = 32.0\n",
    };
    format!(
        "[simulation]\nend_time = 0.15\nprecision = \"{precision}\"\n\n[sph]\nspacing = 0.02\nkernel = \"{kernel}\"\n\n\
         [[materials]]\nname = \"soil\"\ndensity = 1800\nyoungs_modulus = 2e7\npoisson_ratio = 0.3\n{material}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.3, 0.3, 0.3]\n\n[terrain]\nmaterial = \"soil\"\ndepth = 0.24\n"
    )
}

struct Outcome {
    sigma_v: f64,
    expected_v: f64,
    k_ratio: f64,
    k0: f64,
    /// −σxz / σzz at mid-depth (tan of the tilt of g about y in the infinite-slope state).
    shear_ratio: f64,
    max_speed: f64,
    speed_scale: f64,
    escaped: usize,
}

fn settle<T: Real>(text: &str) -> Outcome {
    let scene = common::scene(text);
    let mut m = build_soil::<T>(&scene).expect("builds");
    let mut max_speed = 0.0;
    while m.solver.time() < scene.end_time {
        max_speed = m.solver.step(Some(scene.end_time - m.solver.time())).expect("step").max_speed;
    }
    let s = m.solver.as_cpu().expect("a CPU scene");
    let n = s.active();
    let d0 = scene.solver.spacing;
    let pos: Vec<[f64; 3]> = s.positions()[..n].iter().map(|p| p.as_f64()).collect();
    let top = pos.iter().map(|p| p[2]).fold(f64::MIN, f64::max) + 0.5 * d0;
    let depth_total = top - 0.5 * d0;
    // Central columns (three spacings from the walls), the layer nearest mid-depth.
    // The lattice layer nearest mid-depth of the soil, which spans [d0/2, top].
    let mid_z = ((0.5 * d0 + 0.5 * depth_total) / d0).round() * d0;
    let (mut sv, mut sh, mut sxz, mut count, mut z_sum) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (i, p) in pos.iter().enumerate() {
        let central = p[0] > 3.0 * d0 && p[0] < 0.3 - 3.0 * d0 && p[1] > 3.0 * d0 && p[1] < 0.3 - 3.0 * d0;
        if central && (p[2] - mid_z).abs() < 0.25 * d0 {
            let sig = s.stresses()[i].as_f64();
            sv += -sig[2];
            sh += -0.5 * (sig[0] + sig[1]);
            sxz += sig[4];
            z_sum += p[2];
            count += 1.0;
        }
    }
    assert!(count > 10.0, "no particles at mid-depth");
    let rho = s.materials()[0].density.as_f64();
    let g = -scene.solver.gravity[2];
    let depth = top - z_sum / count;
    Outcome {
        sigma_v: sv / count,
        expected_v: rho * g * depth,
        k_ratio: sh / sv,
        k0: s.materials()[0].k0().as_f64(),
        shear_ratio: sxz / sv,
        max_speed,
        speed_scale: (g * depth_total).sqrt(),
        escaped: s.len() - s.active(),
    }
}

fn check(o: Outcome, what: &str) {
    let ev = (o.sigma_v - o.expected_v).abs() / o.expected_v;
    assert!(ev < 0.03, "{what}: σv = {:.1} Pa vs ρ g depth = {:.1} Pa ({:.2} %)", o.sigma_v, o.expected_v, 100.0 * ev);
    let ek = (o.k_ratio - o.k0).abs() / o.k0;
    assert!(ek < 0.10, "{what}: σh/σv = {:.3} vs K0 = {:.3}", o.k_ratio, o.k0);
    assert!(
        o.max_speed < 0.01 * o.speed_scale,
        "{what}: max speed {:.3e} m/s ≥ 1 % of sqrt(g depth) = {:.3e}",
        o.max_speed,
        o.speed_scale
    );
    assert_eq!(o.escaped, 0, "{what}: particles escaped");
    eprintln!(
        "{what}: σv error {:.2} %, K error {:.2} %, max speed / sqrt(g d) = {:.2e}",
        100.0 * ev,
        100.0 * ek,
        o.max_speed / o.speed_scale
    );
}

#[test]
fn mcc_bed_stays_geostatic_f64_wendland() {
    check(settle::<f64>(&bed("mcc", "f64", "wendland")), "mcc f64 wendland");
}

#[test]
fn dp_bed_stays_geostatic_f32_cubic() {
    check(settle::<f32>(&bed("dp", "f32", "cubic")), "dp f32 cubic");
}

#[test]
fn mcc_bed_stays_geostatic_f32_wendland() {
    check(settle::<f32>(&bed("mcc", "f32", "wendland")), "mcc f32 wendland");
}

#[test]
fn dp_bed_stays_geostatic_f64_wendland() {
    check(settle::<f64>(&bed("dp", "f64", "wendland")), "dp f64 wendland");
}

#[test]
fn a_bed_under_gravity_tilted_15_degrees_starts_in_the_infinite_slope_state_and_does_not_slide() {
    // A slope modelled by tilting g (15° about y, below φ = 32°). The bed is generated in the
    // infinite-slope state (σxz = ρ g sin15° depth; exact, see the terrain crate's unit test)
    // and must not slide: speeds stay below 1 % of sqrt(g depth) and nothing leaves the box.
    // Known miss, measured here and reported, not asserted: the walls' stress extrapolation
    // (Adami: isotropic, `σ_w = σ̄ − ρ (g − a)·r I`) cannot carry the shear gradient the floor
    // needs, so within one wave transit the soil leans on the downhill wall instead: at
    // t = 0.05 s −σxz/σzz at mid-depth is 0.02 (tan 15° = 0.27) and σzz is 21 % above
    // ρ g cos15° depth. See NOTES.md (tilted gravity).
    let a = 15f64.to_radians();
    let text = bed("dp", "f64", "wendland").replace(
        "end_time = 0.15\n",
        &format!("end_time = 0.05\ngravity = [{}, 0.0, {}]\n", -9.81 * a.sin(), -9.81 * a.cos()),
    );
    let o = settle::<f64>(&text);
    eprintln!(
        "tilted 15°: −σxz/σzz = {:.4} (tan 15° = {:.4}); σzz {:.1} Pa vs ρ g cos15° depth {:.1} Pa ({:+.1} %); max speed / sqrt(g d) = {:.2e}",
        o.shear_ratio,
        a.tan(),
        o.sigma_v,
        o.expected_v,
        100.0 * (o.sigma_v / o.expected_v - 1.0),
        o.max_speed / o.speed_scale
    );
    assert!(o.max_speed < 0.01 * o.speed_scale, "slides: max speed {:.3e} m/s", o.max_speed);
    assert_eq!(o.escaped, 0, "particles escaped");
}

#[test]
fn a_pressurised_block_in_a_closed_box_stays_at_its_pressure_with_its_ocr() {
    // A clay block filling a container closed by a fixed lid, no gravity, started at 20 kPa
    // with OCR 3: the walls and the lid hold it, so nothing moves and every particle keeps p = 20 kPa and p_c = 60 kPa
    // (elastic inside its yield surface). The lid covers the soil's columns only: laid over the
    // walls' top markers too, it doubled the markers along the edges, an uneven marker density
    // that a uniform stress pushes against (29 % off p and 0.14 m/s when tried).
    let text = "[simulation]\nend_time = 0.02\nprecision = \"f64\"\ngravity = [0.0, 0.0, 0.0]\n\n[sph]\nspacing = 0.02\n\n\
                [[materials]]\nname = \"clay\"\nmodel = \"mcc\"\ndensity = 1800\nyoungs_modulus = 5e6\npoisson_ratio = 0.3\n\
                mcc_m = 1.2\nmcc_kappa = 0.02\nmcc_lambda = 0.1\nmcc_v_lambda = 2.2\nocr = 3.0\n\n\
                [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.16, 0.16, 0.16]\n\n\
                [[soil_blocks]]\nmaterial = \"clay\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.16, 0.16, 0.16]\ninitial_pressure = 2e4\n\n\
                [[bodies]]\nname = \"lid\"\nshape = { type = \"box\", size = [0.12, 0.12, 0.04] }\nmass = 1.0\nposition = [0.08, 0.08, 0.18]\n\
                motion = { type = \"prescribed\", linear_velocity = [0.0, 0.0, 0.0] }\n";
    let scene = common::scene(text);
    assert!(regolith::scene::describe(&scene).contains("isotropic pressure of 20000 Pa"));
    let mut sim = regolith::sim::Simulation::<f64>::new(&scene).expect("builds");
    let pc0: Vec<f64> = sim.system.fluid.states().iter().map(|s| s.pc).collect();
    assert!(pc0.iter().all(|pc| (pc - 6e4).abs() < 1e-6 * 6e4), "p_c0 = OCR · p: {:?}", &pc0[..3]);
    let mut max_speed: f64 = 0.0;
    while sim.time() < scene.end_time - 1e-12 {
        sim.step().expect("step");
        let v = sim.system.fluid.velocities().iter().map(|v| v.norm()).fold(0.0, f64::max);
        max_speed = max_speed.max(v);
    }
    let f = &sim.system.fluid;
    let (mut worst, mut n) = (0.0f64, 0);
    for (sig, st) in f.stresses().iter().zip(f.states()) {
        let p = -(sig.xx + sig.yy + sig.zz) / 3.0;
        worst = worst.max((p - 2e4).abs() / 2e4);
        assert!((st.pc - 6e4).abs() < 1e-3 * 6e4, "p_c moved to {}", st.pc);
        n += 1;
    }
    eprintln!("{n} particles: largest |p − 20 kPa| {:.3e} of it, max speed {max_speed:.3e} m/s", worst);
    // An acoustic wave carrying 1 % of p moves the soil at v = 0.01 p / (ρ c) = 2.5e-3 m/s, with
    // c = 44 m/s from the MCC moduli at 20 kPa (K = v p / κ = 2.2 MPa, ν = 0.3). Measured
    // (2026-12-03): 0.30 % and 1.1e-3 m/s, the lid's edges being the largest disturbance.
    assert!(worst < 0.01 && max_speed < 2.5e-3, "p off by {worst:.3e}, speed {max_speed:.3e}");
}
