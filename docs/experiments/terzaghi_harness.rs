// The Terzaghi harness of docs/two_phase.md ("Known miss: Terzaghi consolidation"). Not
// compiled: it misses issue 18's bound, and a test CI skips is not a passing test. To run it,
// append this file to tests/wet_soil.rs (it uses that file's imports: `common`, `build_soil`,
// `Real`) and run
//   cargo test --release --test suite wet_soil::a_fresh -- --nocapture
// Knobs (environment): TZ_D0 spacing (m, default 0.01), TZ_W box width (m, 0.05), TZ_H layer
// height (m, 0.2), TZ_HW top of the water (m, default the layer's top; above it the layer is
// submerged), TZ_EXTRA extra [sph] lines separated by ';', TZ_CHECKS the T_v list.

/// Terzaghi's average degree of consolidation for an initial excess pore pressure growing
/// linearly with depth from zero at the drained top (a freshly deposited layer consolidating
/// under its own buoyant weight, impermeable base): `U = 1 − Σ 4 (−1)^m / M³ exp(−M² T_v)`,
/// `M = π (2m + 1) / 2`.
fn terzaghi_triangular(tv: f64) -> f64 {
    let mut sum = 0.0;
    for m in 0..200 {
        let mm = std::f64::consts::PI * (2 * m + 1) as f64 / 2.0;
        sum += 4.0 * if m % 2 == 0 { 1.0 } else { -1.0 } / mm.powi(3) * (-mm * mm * tv).exp();
    }
    1.0 - sum
}

#[test]
fn the_triangular_series_starts_at_zero_and_ends_at_one() {
    assert!(terzaghi_triangular(0.0).abs() < 1e-4);
    assert!((terzaghi_triangular(5.0) - 1.0).abs() < 1e-5);
    // Between the limits it rises; at T_v = 0.2 about a third (the uniform case gives 0.50).
    let u = terzaghi_triangular(0.2);
    assert!(u > 0.2 && u < 0.5, "{u}");
}

/// A 0.2 m saturated layer of soft elastic soil (E_oed = 0.1 MPa, k = 3.9 mm/s) that starts
/// with no effective stress: its buoyant weight first goes to the pore water (undrained), then
/// to the skeleton as the water drains through the free top.
fn fresh_deposit(end: f64) -> String {
    format!(
        "[simulation]\nend_time = {end}\nprecision = \"f64\"\n\n[sph]\nspacing = {d0}\n{extra}\n\n\
         [[materials]]\nname = \"silt\"\nmodel = \"elastic\"\ndensity = 1600\ngrain_density = 2650\n\
         permeability = 3.9e-3\nyoungs_modulus = {e}\npoisson_ratio = 0.3\n\
         [[materials]]\nname = \"water\"\nmodel = \"water\"\ndensity = 1000\nsound_speed = 50\nviscosity = 1e-3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{W}, {W}, {top}]\nsoil_contact = \"smooth\"\n\n\
         [[soil_blocks]]\nmaterial = \"silt\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [{W}, {W}, {H}]\n\
         initial_pressure = 1.0\n\n\
         [[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [{W}, {W}, {HW}]\n",
        HW = std::env::var("TZ_HW").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H),
        // E_oed = E (1 − ν) / ((1 + ν)(1 − 2ν)) = 0.1 MPa.
        e = 1e5 * 1.3 * 0.4 / 0.7,
        top = 1.5 * std::env::var("TZ_H").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H),
        extra = std::env::var("TZ_EXTRA").unwrap_or_default().replace(";", "\n"),
        d0 = std::env::var("TZ_D0").unwrap_or("0.01".into()),
        W = std::env::var("TZ_W").unwrap_or("0.05".into()),
        H = std::env::var("TZ_H").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H),
    )
}

/// Layer height (m).
const H: f64 = 0.2;
fn hh() -> f64 { std::env::var("TZ_H").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H) }

/// Issue 18's Terzaghi check, U within 10 % of the series at T_v = 0.05, 0.2, 0.5 and 1. It
/// fails today and is ignored until it passes (docs/two_phase.md): the layer consolidates about
/// twice as fast as Terzaghi's c_v says (U = 0.18, 0.63, 1.0, 1.09 against 0.10, 0.37, 0.70,
/// 0.91), and settles 7–9 % more than γ' H² / (2 E_oed). Not the walls (the same in a box twice
/// as wide) nor the density diffusion (the same without); the cause is not found yet. About
/// 100 s: `cargo test --release --test suite -- --ignored wet_soil::`.
#[test]
fn a_fresh_saturated_deposit_consolidates_under_its_own_weight_along_terzaghi() {
    let mats: Vec<_> =
        common::scene(&fresh_deposit(1.0)).materials.iter().map(|m| m.params.build::<f64>().expect("m")).collect();
    let (rho_s, rho_w) = (mats[0].density, mats[1].density);
    let n0 = 1.0 - rho_s / mats[0].grain_density;
    let (e_oed, k_w, k) = (1e5, rho_w * 50.0 * 50.0, mats[0].permeability);
    // c_v with the water's compressibility (K_w / n is 62 × E_oed here).
    let cv = k / (rho_w * 9.80665 * (1.0 / e_oed + n0 / k_w));
    let checks: Vec<f64> = std::env::var("TZ_CHECKS")
        .map(|v| {
            v.split(',')
                .map(|x| x.trim().parse().unwrap_or_else(|e| panic!("TZ_CHECKS: \"{x}\" is not a T_v ({e})")))
                .collect()
        })
        .unwrap_or(vec![0.05, 0.2, 0.5, 1.0]);
    let scene = common::scene(&fresh_deposit(hh() * hh() / cv * 1.001));
    let mut m = build_soil::<f64>(&scene).expect("builds");
    let d0 = scene.solver.spacing;
    // The soil's top layer, followed by particle id.
    let top: std::collections::HashSet<u32> = {
        let s = m.solver.as_cpu().expect("cpu");
        (0..s.active())
            .filter(|&i| {
                !s.materials()[s.material_ids()[i] as usize].is_water() && s.positions()[i].as_f64()[2] > hh() - 0.5 * d0
            })
            .map(|i| s.ids()[i])
            .collect()
    };
    let top_layer = |s: &regolith::fsi::cpu::CpuSph<f64>| -> f64 {
        let z: Vec<f64> =
            (0..s.active()).filter(|&i| top.contains(&s.ids()[i])).map(|i| s.positions()[i].as_f64()[2]).collect();
        z.iter().sum::<f64>() / z.len() as f64
    };
    let z0 = top_layer(m.solver.as_cpu().expect("cpu"));
    let g = -scene.solver.gravity[2];
    let gamma_b = (rho_s + n0 * rho_w - rho_w) * g;
    // Settlement of the top under the triangular load γ' z: undrained (the water takes
    // K_w / n of the stiffness), and final.
    let s_inf = gamma_b * hh() * hh() / (2.0 * e_oed);
    let s_0 = gamma_b * hh() * hh() / (2.0 * (e_oed + k_w / n0));
    let mut worst: f64 = 0.0;
    for tv in checks.iter().copied() {
        let t_check = tv * hh() * hh() / cv;
        while m.solver.time() < t_check * (1.0 - 1e-12) {
            m.solver.step(Some(t_check - m.solver.time())).expect("step");
        }
        let s = z0 - top_layer(m.solver.as_cpu().expect("cpu"));
        let (u, u_ref) = ((s - s_0) / (s_inf - s_0), terzaghi_triangular(tv));
        eprintln!(
            "T_v = {tv:.2} (t = {:.3} s): settlement {:.3} mm, U = {u:.3} against {u_ref:.3} ({:+.1} %)",
            m.solver.time(),
            1e3 * s,
            100.0 * (u / u_ref - 1.0)
        );
        worst = worst.max((u / u_ref - 1.0).abs());
        {
            let s = m.solver.as_cpu().expect("cpu");
            let mats = s.materials();
            let nl = (hh() / d0).round() as usize + 3;
            let mut acc = vec![[0.0f64; 10]; nl];
            let mut zw_top: f64 = 0.0;
            for i in 0..s.active() {
                let x = s.positions()[i].as_f64();
                let l = (x[2] / d0).floor() as usize;
                if l >= nl { continue; }
                let v = s.velocities()[i].as_f64();
                let szz = -s.stresses()[i].as_f64()[2];
                let a = &mut acc[l];
                if mats[s.material_ids()[i] as usize].is_water() {
                    a[0] += szz; a[1] += v[2]; a[2] += 1.0; a[6] += x[2]; a[8] += s.densities()[i].as_f64() / (1000.0 + szz.max(0.0) / 2500.0);
                    zw_top = zw_top.max(x[2]);
                } else {
                    a[3] += szz; a[4] += v[2]; a[5] += 1.0; a[7] += x[2]; a[9] += 1.0 - s.densities()[i].as_f64() / 2650.0;
                }
            }
            let nn = n0;
            for (l, a) in acc.iter().enumerate() {
                if a[2] == 0.0 || a[5] == 0.0 { continue; }
                let z = a[6] / a[2];
                let pex = a[0] / a[2] - rho_w * g * (zw_top - z);
                eprintln!("  n_svf {:.5} n_soil {:.5} diff {:+.2e}", a[8]/a[2], a[9]/a[5], a[8]/a[2]-a[9]/a[5]); eprintln!("  z {:.3}: p {:8.1} pex {:8.1} sv' {:8.1} vw {:+.3e} vs {:+.3e} q_rel {:+.3e} (nw {} ns {})", z, a[0]/a[2], pex, a[3]/a[5], a[1]/a[2], a[4]/a[5], nn*(a[1]/a[2]-a[4]/a[5]), a[2], a[5]);
                let _ = l;
            }
            eprintln!("  water top {zw_top:.4}, k/gamma_w = {:.3e}", k / (rho_w * 9.80665));
            let fz: f64 = s.marker_forces().iter().map(|f| f.as_f64()[2]).sum();
            let fz_floor: f64 = s.marker_forces().iter().zip(s.marker_positions()).filter(|(_, x)| x.as_f64()[2] < 0.0 + 1e-9).map(|(f, _)| f.as_f64()[2]).sum();
            let wsum: f64 = (0..s.active()).map(|i| s.masses()[i].as_f64() * g).sum();
            eprintln!("  markers carry Fz = {fz:.3} N (floor markers z<=0: {fz_floor:.3}); weight {wsum:.3} N");
        }
    }
    assert!(worst < 0.10, "U off the series by up to {:.0} %", 100.0 * worst);
}
