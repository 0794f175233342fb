//! The hand-written small-tensor math of the SPH pair loop against nalgebra's fixed-size types,
//! on the operations the solver does per particle and per pair:
//!
//! - the smallest eigenvalue of a symmetric 3×3 (the free-surface measure, once per particle
//!   and step): `Sym3::min_eigenvalue` (closed form) vs `Matrix3::symmetric_eigenvalues`;
//! - the pair term `(σ_a/ρ_a² + σ_b/ρ_b²) · ∇W` plus the velocity-gradient outer product
//!   `(v_b − v_a) ⊗ ∇W` accumulated over neighbours: `Sym3`/`Vec3`/`Mat3` vs `Matrix3`/`Vector3`.
//!
//! ```text
//! cargo run --release -p regolith-fsi --example math_bench
//! ```
//!
//! It prints the time per operation for each and the largest difference between the results.

use std::hint::black_box;
use std::time::Instant;

use nalgebra::{Matrix3, Vector3};
use regolith_fsi::math::{Mat3, Sym3, Vec3};

/// A small deterministic generator (xorshift), values in [−1, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 23) as f32 - 1.0
    }
}

fn main() {
    let n = 1_000_000;
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    // Symmetric matrices like the free-surface moment: close to the identity inside the soil.
    let syms: Vec<[f32; 6]> = (0..n)
        .map(|_| {
            let d = 0.3;
            [
                1.0 + d * rng.next(),
                1.0 + d * rng.next(),
                1.0 + d * rng.next(),
                d * rng.next(),
                d * rng.next(),
                d * rng.next(),
            ]
        })
        .collect();
    let hand: Vec<Sym3<f32>> = syms.iter().map(|s| Sym3::new(s[0], s[1], s[2], s[3], s[4], s[5])).collect();
    let nal: Vec<Matrix3<f32>> =
        syms.iter().map(|s| Matrix3::new(s[0], s[3], s[4], s[3], s[1], s[5], s[4], s[5], s[2])).collect();

    let t = Instant::now();
    let a: Vec<f32> = hand.iter().map(|s| black_box(*s).min_eigenvalue()).collect();
    let t_hand = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let b: Vec<f32> = nal.iter().map(|m| black_box(*m).symmetric_eigenvalues().min()).collect();
    let t_nal = t.elapsed().as_secs_f64();
    let diff = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0_f32, f32::max);
    println!(
        "smallest eigenvalue, {n} matrices (f32): hand {:.1} ns, nalgebra {:.1} ns ({:.2}×); largest difference {diff:.2e}",
        1e9 * t_hand / n as f64,
        1e9 * t_nal / n as f64,
        t_nal / t_hand
    );

    // Pair loop: 55 neighbours per particle, as in the bench block.
    let particles = 20_000;
    let k = 55;
    let grads: Vec<[f32; 3]> = (0..particles * k).map(|_| [rng.next(), rng.next(), rng.next()]).collect();
    let vels: Vec<[f32; 3]> = (0..particles * k).map(|_| [rng.next(), rng.next(), rng.next()]).collect();
    let rho = 1700.0_f32;

    let t = Instant::now();
    let mut acc_h = Vec::with_capacity(particles);
    for i in 0..particles {
        let sa = hand[i] * (1.0 / (rho * rho));
        let mut f = Vec3::zero();
        let mut l = Mat3::zero();
        for j in 0..k {
            let g = Vec3::new(grads[i * k + j][0], grads[i * k + j][1], grads[i * k + j][2]);
            let sb = hand[(i * 7 + j) % n] * (1.0 / (rho * rho));
            f += (sa + sb).mul_vec(g);
            let v = Vec3::new(vels[i * k + j][0], vels[i * k + j][1], vels[i * k + j][2]);
            l += Mat3::outer(v, g);
        }
        acc_h.push((black_box(f), black_box(l)));
    }
    let t_hand = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut acc_n = Vec::with_capacity(particles);
    for i in 0..particles {
        let sa = nal[i] * (1.0 / (rho * rho));
        let mut f = Vector3::zeros();
        let mut l = Matrix3::zeros();
        for j in 0..k {
            let g = Vector3::new(grads[i * k + j][0], grads[i * k + j][1], grads[i * k + j][2]);
            let sb = nal[(i * 7 + j) % n] * (1.0 / (rho * rho));
            f += (sa + sb) * g;
            let v = Vector3::new(vels[i * k + j][0], vels[i * k + j][1], vels[i * k + j][2]);
            l += v * g.transpose();
        }
        acc_n.push((black_box(f), black_box(l)));
    }
    let t_nal = t.elapsed().as_secs_f64();
    let mut diff = 0.0_f32;
    for ((fh, lh), (fnl, lnl)) in acc_h.iter().zip(&acc_n) {
        for r in 0..3 {
            diff = diff.max((fh.get(r) - fnl[r]).abs());
            for c in 0..3 {
                diff = diff.max((lh.m[r][c] - lnl[(r, c)]).abs());
            }
        }
    }
    let pairs = (particles * k) as f64;
    println!(
        "pair terms, {particles} particles × {k} neighbours (f32): hand {:.2} ns/pair, nalgebra {:.2} ns/pair ({:.2}×); largest difference {diff:.2e}",
        1e9 * t_hand / pairs,
        1e9 * t_nal / pairs,
        t_nal / t_hand
    );
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("model name")).map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown".into());
    println!("CPU: {cpu}; one thread");
}
