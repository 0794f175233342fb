//! Conservation on a closed box: particle masses never change, and the change of the soil's
//! total momentum equals the impulse of gravity plus the impulse of the walls (summed from the
//! marker forces) to round-off, because every soil–soil pair term is evaluated as an exact
//! negative of its partner. Both kernels, f32 and f64. Cohesionless soil never goes into
//! tension.

use crate::common;

use regolith::build::build_soil;
use regolith::fsi::Real;

fn block(kernel: &str, precision: &str, shifting: &str) -> String {
    format!(
        "[simulation]\nend_time = 1.0\nprecision = \"{precision}\"\n\n[sph]\nspacing = 0.02\nkernel = \"{kernel}\"\nshifting = \"{shifting}\"\n\n\
         [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.2, 0.3]\n\n\
         [[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.14, 0.2, 0.2]\n"
    )
}

fn check<T: Real>(kernel: &str, shifting: &str, tol: f64) {
    let scene = common::scene(&block(kernel, T::NAME, shifting));
    let mut m = build_soil::<T>(&scene).expect("builds");
    let mass0: Vec<f64> = m.solver.masses().iter().map(|x| x.as_f64()).collect();
    let total_mass: f64 = mass0.iter().sum();
    let p0 = m.solver.momentum();
    let g = scene.solver.gravity;
    let mut t = 0.0;
    for _ in 0..400 {
        t += m.solver.step(None).expect("step").dt;
    }
    let s = m.solver.as_cpu().expect("a CPU scene");
    assert_eq!(s.active(), s.len(), "nothing may leave a closed box");
    // Masses are carried unchanged (sorting permutes them).
    let mut a: Vec<f64> = s.masses().iter().map(|x| x.as_f64()).collect();
    let mut b = mass0.clone();
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    assert_eq!(a, b, "particle masses changed");
    let p1 = s.momentum();
    let walls = s.marker_impulse();
    let mut worst: f64 = 0.0;
    let scale = total_mass * 9.81 * t;
    for k in 0..3 {
        let expected = total_mass * g[k] * t + walls[k];
        worst = worst.max(((p1[k] - p0[k]) - expected).abs() / scale);
    }
    eprintln!(
        "{kernel} {} {shifting}: t = {t:.4} s, |ΔP − impulse| / (M g t) = {worst:.2e}, wall impulse {walls:?}",
        T::NAME
    );
    assert!(worst < tol, "momentum balance off by {worst:.3e} of M g t");
    // The walls did work: they are not a trivial zero.
    assert!(walls[2] > 0.1 * scale, "floor impulse {} too small", walls[2]);
    for sig in s.stresses() {
        assert!(sig.pressure().as_f64() >= 0.0, "tension in cohesionless soil: p = {}", sig.pressure());
    }
}

#[test]
fn wendland_f64() {
    check::<f64>("wendland", "xsph", 1e-12);
}

#[test]
fn cubic_f64() {
    check::<f64>("cubic", "ppst+xsph", 1e-12);
}

#[test]
fn wendland_f32() {
    check::<f32>("wendland", "xsph", 1e-6);
}

#[test]
fn cubic_f32() {
    check::<f32>("cubic", "none", 1e-6);
}
