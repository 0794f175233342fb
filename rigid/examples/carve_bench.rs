//! Times `ShapeDesc::contains_points` on a closed mesh, the query that carves a body out of the
//! soil when a scene starts: a torus of about `TRIANGLES` triangles (default 100 000) against a
//! lattice of about `POINTS` points (default 1 000 000) filling a box around it, with a margin of
//! `MARGIN` lattice spacings (default 0.5, what `Simulation::new` grows a body by). The same as
//! `regolith bench --carve`.
//!
//! ```text
//! cargo run --release -p regolith-rigid --example carve_bench -- [TRIANGLES] [POINTS] [MARGIN]
//! ```
//!
//! The brute force that parry replaced is timed, on the small case
//! `carve_bench -- 1000 100000`, by the test `carve_timing_brute_force_vs_parry`
//! (`cargo test --release -p regolith-rigid --lib carve_timing -- --nocapture`).

use regolith_rigid::bench::carve_torus;

fn main() -> std::process::ExitCode {
    let mut args = std::env::args().skip(1);
    let mut next = |name: &str, default: f64| -> Result<f64, String> {
        match args.next() {
            None => Ok(default),
            Some(a) => a.parse().map_err(|_| format!("{name}: must be a number (got {a})")),
        }
    };
    let parsed =
        (|| Ok::<_, String>((next("TRIANGLES", 100_000.0)?, next("POINTS", 1_000_000.0)?, next("MARGIN", 0.5)?)))();
    let (triangles, points, margin) = match parsed {
        Ok(v) => v,
        Err(e) => {
            eprintln!("error: {e} (usage: carve_bench [TRIANGLES] [POINTS] [MARGIN])");
            return std::process::ExitCode::from(2);
        }
    };
    let r = carve_torus(triangles as usize, points as usize, margin);
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("model name")).map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown".into());
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("CPU: {cpu} ({threads} hardware threads)");
    println!(
        "torus mesh: {} triangles; lattice: {} points (d0 = {:.3} mm), margin {:.3} mm",
        r.triangles,
        r.points,
        1e3 * r.spacing,
        1e3 * r.margin
    );
    println!("contains_points: {:.3} s (TriMesh build included), {} points removed", r.seconds, r.removed);
    std::process::ExitCode::SUCCESS
}
