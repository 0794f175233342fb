//! Times `ShapeDesc::contains_points` on a closed mesh, the query that carves a body out of the
//! soil when a scene starts: a torus of about `TRIANGLES` triangles (default 100 000) against a
//! lattice of about `POINTS` points (default 1 000 000) filling a box around it, with a margin of
//! `MARGIN` lattice spacings (default 0.5, what `Simulation::new` grows a body by).
//!
//! ```text
//! cargo run --release -p regolith-rigid --example carve_bench -- [TRIANGLES] [POINTS] [MARGIN]
//! ```
//!
//! The brute force that parry replaced is timed, on the small case
//! `carve_bench -- 1000 100000`, by the test `carve_timing_brute_force_vs_parry`
//! (`cargo test --release -p regolith-rigid --lib carve_timing -- --nocapture`).

use std::time::Instant;

use regolith_rigid::ShapeDesc;

fn main() {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<f64>().expect("a number"));
    let triangles = args.next().unwrap_or(100_000.0);
    let points = args.next().unwrap_or(1_000_000.0);
    let margin_d0 = args.next().unwrap_or(0.5);
    let (major, minor) = (0.3, 0.1);
    // Near-square quads: `around / across ≈ major / minor`, 2 · around · across triangles.
    let across = (triangles / (2.0 * major / minor)).sqrt().round().max(3.0);
    let around = (triangles / (2.0 * across)).round().max(3.0);
    let torus = ShapeDesc::torus_mesh(major, minor, around as u32, across as u32);
    let ShapeDesc::Mesh { vertices, indices } = &torus else { unreachable!("torus_mesh gives a mesh") };

    // The lattice: cell centres filling the mesh's box grown by a tenth of the tube radius,
    // spacing d0 from the count.
    let pad = 0.1 * minor;
    let lo = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MAX, f64::min) - pad);
    let hi = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MIN, f64::max) + pad);
    let size = [0, 1, 2].map(|k| hi[k] - lo[k]);
    let d0 = (size[0] * size[1] * size[2] / points).cbrt();
    let n = size.map(|s| (s / d0).round() as usize);
    let mut lattice = Vec::with_capacity(n[0] * n[1] * n[2]);
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                let c = [i, j, k].map(|x| x as f64 + 0.5);
                lattice.push([lo[0] + c[0] * d0, lo[1] + c[1] * d0, lo[2] + c[2] * d0]);
            }
        }
    }
    let margin = margin_d0 * d0;

    let t = Instant::now();
    let inside = torus.contains_points(&lattice, margin);
    let seconds = t.elapsed().as_secs_f64();
    let removed = inside.iter().filter(|x| **x).count();

    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("model name")).map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown".into());
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("CPU: {cpu} ({threads} hardware threads)");
    println!(
        "torus mesh: {} triangles; lattice: {} points ({} × {} × {}, d0 = {:.3} mm), margin {:.3} mm",
        indices.len(),
        lattice.len(),
        n[0],
        n[1],
        n[2],
        1e3 * d0,
        1e3 * margin
    );
    println!("contains_points: {seconds:.3} s (TriMesh build included), {removed} points removed");
}
