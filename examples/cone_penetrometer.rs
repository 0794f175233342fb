//! Runs `examples/scenes/cone_penetrometer.toml` through the Rust API and prints the rig's results.
//! `cargo run --release --example cone_penetrometer [OUT_DIR]`

use std::path::PathBuf;

use regolith::run::{RunOptions, run_scene};
use regolith::scene::load_scene;

fn main() -> anyhow::Result<()> {
    let out = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| PathBuf::from("out/cone_penetrometer"));
    let scene =
        load_scene(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/cone_penetrometer.toml"), &[])?;
    let summary = run_scene(&scene, &RunOptions::new(out.clone()))?;
    println!("{}", serde_json::to_string_pretty(&summary.rig)?);
    if let Some(b) = &summary.bekker {
        println!("Bekker: k_c = {:?}, k_phi = {:?}, n = {:.3}", b.kc, b.kphi, b.n);
    }
    println!("outputs in {}", out.display());
    Ok(())
}
