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

/// A dry elastic layer `h` m deep (E_oed = 0.1 MPa, ν = 0.3, ρ = 1600 kg/m³, spacing `d0`, a
/// 0.05 m box with smooth walls) that starts without stress, run to `end` s.
fn stress_free_layer(h: f64, d0: f64, end: f64) -> String {
    format!(
        "[simulation]\nend_time = {end}\nprecision = \"f64\"\n\n[sph]\nspacing = {d0}\n\n\
         [[materials]]\nname = \"silt\"\nmodel = \"elastic\"\ndensity = 1600\nyoungs_modulus = {e}\npoisson_ratio = 0.3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.05, 0.05, {top}]\nsoil_contact = \"smooth\"\n\n\
         [[soil_blocks]]\nmaterial = \"silt\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.05, 0.05, {h}]\n\
         initial_pressure = 1.0\n",
        // E_oed = E (1 − ν) / ((1 + ν)(1 − 2ν)) = 0.1 MPa.
        e = 1e5 * 1.3 * 0.4 / 0.7,
        top = 1.5 * h,
    )
}

/// The settlement of the layer's top row of particles (followed by id) at every step.
fn settlement_history(h: f64, d0: f64, end: f64) -> Vec<(f64, f64)> {
    let scene = common::scene(&stress_free_layer(h, d0, end));
    let mut m = build_soil::<f64>(&scene).expect("builds");
    let ids: std::collections::HashSet<u32> = {
        let s = m.solver.as_cpu().expect("cpu");
        (0..s.active()).filter(|&i| s.positions()[i].as_f64()[2] > h - 0.5 * d0).map(|i| s.ids()[i]).collect()
    };
    let mean_z = |s: &regolith::fsi::cpu::CpuSph<f64>| -> f64 {
        let z: Vec<f64> =
            (0..s.active()).filter(|&i| ids.contains(&s.ids()[i])).map(|i| s.positions()[i].as_f64()[2]).collect();
        z.iter().sum::<f64>() / z.len() as f64
    };
    let z0 = mean_z(m.solver.as_cpu().expect("cpu"));
    let mut out = vec![(0.0, 0.0)];
    while m.solver.time() < end - 1e-12 {
        m.solver.step(Some(end - m.solver.time())).expect("step");
        out.push((m.solver.time(), z0 - mean_z(m.solver.as_cpu().expect("cpu"))));
    }
    out
}

/// A layer that starts without stress under gravity is a step load: until the compression
/// wave from the floor reaches it the top falls freely, then the layer rings about its static
/// state. Closed form (1-D elastic wave, fixed base, free top): the static settlement
/// `γ h² / (2 E_oed)` (0.785 mm), an oscillation between none and twice that, with period
/// `4 h / c`, `c = sqrt(E_oed / ρ)` (50.6 ms). Checked over the first three periods, at
/// d0 = 1 cm and 5 mm: the Hann-windowed mean settlement within 8 % (measured +3.6 % and
/// +5.4 %), the period from the upward crossings of the static level within 10 % (+6.8 %,
/// +4.3 %), the first peak within 10 % of twice the static settlement (+3.2 %, +5.3 %). The
/// bounds are loose because the mean does not converge with d0: the SPH layer is 3–5 % softer
/// than E_oed in a box five or ten spacings wide (NOTES.md, "A dry layer's self-weight
/// settlement").
///
/// Known miss, not asserted: left to ring for 1 s (20 periods) the mean creeps on at the
/// default h/d0 = 1.2, more at finer d0 (+3.3 % at 1 cm, +14 % at 5 mm, +49 % at 2.5 mm by
/// 1 s); at h/d0 = 1.5 it converges (+5.6, +1.6, −0.2 %; NOTES.md).
#[test]
fn a_stress_free_elastic_layer_rings_about_its_self_weight_settlement_with_the_wave_period() {
    let (h, rho, e_oed): (f64, f64, f64) = (0.1, 1600.0, 1e5);
    let s_static = rho * 9.80665 * h * h / (2.0 * e_oed);
    let period = 4.0 * h / (e_oed / rho).sqrt();
    for d0 in [0.01, 0.005] {
        let hist = settlement_history(h, d0, 3.0 * period);
        // Hann-windowed mean over the three periods.
        let (mut sum, mut wsum) = (0.0, 0.0);
        for w in hist.windows(2) {
            let ((t0, _), (t1, s1)) = (w[0], w[1]);
            let hann = 1.0 - (2.0 * std::f64::consts::PI * t1 / (3.0 * period)).cos();
            sum += (t1 - t0) * hann * s1;
            wsum += (t1 - t0) * hann;
        }
        let mean = sum / wsum;
        // Upward crossings of the static level (linear interpolation between steps).
        let ups: Vec<f64> = hist
            .windows(2)
            .filter(|w| w[0].1 < s_static && w[1].1 >= s_static)
            .map(|w| w[0].0 + (w[1].0 - w[0].0) * (s_static - w[0].1) / (w[1].1 - w[0].1))
            .collect();
        assert!(ups.len() >= 3, "d0 = {d0}: {} upward crossings in three periods", ups.len());
        let measured_period = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
        let first_peak = hist.iter().take_while(|&&(t, _)| t < 0.75 * period).map(|&(_, s)| s).fold(0.0, f64::max);
        let (e_mean, e_period, e_peak) =
            (mean / s_static - 1.0, measured_period / period - 1.0, first_peak / (2.0 * s_static) - 1.0);
        eprintln!(
            "d0 = {d0}: mean settlement {:.4} mm against {:.4} mm ({:+.2} %), period {:.2} ms against {:.2} ms ({:+.2} %), first peak {:.4} mm against {:.4} mm ({:+.2} %)",
            1e3 * mean,
            1e3 * s_static,
            100.0 * e_mean,
            1e3 * measured_period,
            1e3 * period,
            100.0 * e_period,
            1e3 * first_peak,
            2e3 * s_static,
            100.0 * e_peak
        );
        assert!(e_mean.abs() < 0.08, "d0 = {d0}: mean settlement {:+.2} %", 100.0 * e_mean);
        assert!(e_period.abs() < 0.10, "d0 = {d0}: period {:+.2} %", 100.0 * e_period);
        assert!(e_peak.abs() < 0.10, "d0 = {d0}: first peak {:+.2} %", 100.0 * e_peak);
    }
}
