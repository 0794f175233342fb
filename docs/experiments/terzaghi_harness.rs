// The Terzaghi harness of docs/two_phase.md ("Terzaghi consolidation"): the CI check
// (tests/wet_soil.rs, `a_fresh_saturated_deposit_…`) with knobs, and per-layer diagnostics
// (porosity the water uses against the soil's own, excess pore pressure, relative flux, the
// floor's load). Not compiled. To run it, append this file to tests/wet_soil.rs (it uses that
// file's imports and `terzaghi_triangular`) and run
//   cargo test --release --test suite wet_soil::terzaghi_harness -- --nocapture
// Knobs (environment): TZ_D0 spacing (m, default 0.01), TZ_W box width (m, 0.05), TZ_H layer
// height (m, 0.2), TZ_HW top of the water (m, default the layer's top; above it the layer is
// submerged), TZ_C the water's sound speed (m/s, 50), TZ_EXTRA extra [sph] lines separated by
// ';', TZ_CHECKS the T_v list.

/// A 0.2 m saturated layer of soft elastic soil (E_oed = 0.1 MPa, k = 3.9 mm/s) that starts
/// with no effective stress: its buoyant weight first goes to the pore water (undrained), then
/// to the skeleton as the water drains through the free top.
fn fresh_deposit_knobs(end: f64) -> String {
    format!(
        "[simulation]\nend_time = {end}\nprecision = \"f64\"\n\n[sph]\nspacing = {d0}\n{extra}\n\n\
         [[materials]]\nname = \"silt\"\nmodel = \"elastic\"\ndensity = 1600\ngrain_density = 2650\n\
         permeability = 3.9e-3\nyoungs_modulus = {e}\npoisson_ratio = 0.3\n\
         [[materials]]\nname = \"water\"\nmodel = \"water\"\ndensity = 1000\nsound_speed = {c}\nviscosity = 1e-3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [{W}, {W}, {top}]\nsoil_contact = \"smooth\"\n\n\
         [[soil_blocks]]\nmaterial = \"silt\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [{W}, {W}, {H}]\n\
         initial_pressure = 1.0\n\n\
         [[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [{W}, {W}, {HW}]\n",
        HW = std::env::var("TZ_HW").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H_DEFAULT),
        // E_oed = E (1 − ν) / ((1 + ν)(1 − 2ν)) = 0.1 MPa.
        e = 1e5 * 1.3 * 0.4 / 0.7,
        top = 1.5 * std::env::var("TZ_H").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H_DEFAULT),
        extra = std::env::var("TZ_EXTRA").unwrap_or_default().replace(";", "\n"),
        d0 = std::env::var("TZ_D0").unwrap_or("0.01".into()),
        c = std::env::var("TZ_C").unwrap_or("50".into()),
        W = std::env::var("TZ_W").unwrap_or("0.05".into()),
        H = std::env::var("TZ_H").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H_DEFAULT),
    )
}

/// Layer height (m).
const H_DEFAULT: f64 = 0.2;
fn hh() -> f64 { std::env::var("TZ_H").ok().and_then(|v| v.parse::<f64>().ok()).unwrap_or(H_DEFAULT) }

/// The CI check's measurement with the knobs above, and per-layer diagnostics at each T_v.
/// Fails (as a test) when U is off the series by 10 % or more.
#[test]
fn terzaghi_harness() {
    let checks: Vec<f64> = std::env::var("TZ_CHECKS")
        .map(|v| {
            v.split(',')
                .map(|x| x.trim().parse().unwrap_or_else(|e| panic!("TZ_CHECKS: \"{x}\" is not a T_v ({e})")))
                .collect()
        })
        .unwrap_or(vec![0.05, 0.2, 0.5, 1.0]);
    let worst = consolidate(&fresh_deposit_knobs, hh(), &checks, |s, _| layers(s));
    assert!(worst < 0.10, "U off the series by up to {:.0} %", 100.0 * worst);
}

/// Per layer of one spacing: the porosity the water uses against the soil's own, the pore
/// pressure and its excess over hydrostatic, σ'_zz, both phases' vertical velocities and the
/// relative flux; the floor's load against the weight.
fn layers(s: &regolith::fsi::cpu::CpuSph<f64>) {
    let d0 = s.config().spacing;
    let (g, rho_w, n0) = (9.80665, 1000.0, 1.0 - 1600.0 / 2650.0);
    let mats = s.materials();
    let nl = (hh() / d0).round() as usize + 3;
    let mut acc = vec![[0.0f64; 10]; nl];
    let mut zw_top: f64 = 0.0;
    for i in 0..s.active() {
        let x = s.positions()[i].as_f64();
        let l = (x[2] / d0).floor() as usize;
        if l >= nl {
            continue;
        }
        let v = s.velocities()[i].as_f64();
        let szz = -s.stresses()[i].as_f64()[2];
        let a = &mut acc[l];
        if mats[s.material_ids()[i] as usize].is_water() {
            a[0] += szz;
            a[1] += v[2];
            a[2] += 1.0;
            a[6] += x[2];
            a[8] += s.densities()[i].as_f64() / (1000.0 + szz.max(0.0) / 2500.0);
            zw_top = zw_top.max(x[2]);
        } else {
            a[3] += szz;
            a[4] += v[2];
            a[5] += 1.0;
            a[7] += x[2];
            a[9] += 1.0 - s.densities()[i].as_f64() / 2650.0;
        }
    }
    for a in acc.iter().filter(|a| a[2] > 0.0 && a[5] > 0.0) {
        let z = a[6] / a[2];
        let pex = a[0] / a[2] - rho_w * g * (zw_top - z);
        eprintln!("  n_svf {:.5} n_soil {:.5} diff {:+.2e}", a[8] / a[2], a[9] / a[5], a[8] / a[2] - a[9] / a[5]);
        eprintln!(
            "  z {:.3}: p {:8.1} pex {:8.1} sv' {:8.1} vw {:+.3e} vs {:+.3e} q_rel {:+.3e} (nw {} ns {})",
            z,
            a[0] / a[2],
            pex,
            a[3] / a[5],
            a[1] / a[2],
            a[4] / a[5],
            n0 * (a[1] / a[2] - a[4] / a[5]),
            a[2],
            a[5]
        );
    }
    let fz: f64 = s.marker_forces().iter().map(|f| f.as_f64()[2]).sum();
    let wsum: f64 = (0..s.active()).map(|i| s.masses()[i].as_f64() * g).sum();
    eprintln!("  water top {zw_top:.4}; markers carry Fz = {fz:.3} N; weight {wsum:.3} N");
}
