//! Scripting a penetrometer probe through the Rust API: push the cone into the soil at
//! 3 cm/s to a depth of 3 cm, hold it, then withdraw it, reading the soil's force on it
//! between steps. Writes `OUT_DIR/cone_script.csv` (time, depth, force).
//!
//! `cargo run --release --example cone_script [OUT_DIR]`

use std::io::Write;
use std::path::PathBuf;

use regolith::sim::Simulation;

fn main() -> anyhow::Result<()> {
    let out = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| PathBuf::from("out/cone_script"));
    std::fs::create_dir_all(&out)?;
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/cone_probe.toml");
    let mut sim = Simulation::<f32>::load(&scene)?;
    let cone = sim.body("cone").ok_or_else(|| anyhow::anyhow!("the scene has no body named cone"))?;
    let start_tip = sim.body_state(cone).origin[2] - 0.5 * 0.03784;
    let (speed, depth, hold) = (0.03, 0.03, 0.1);
    let mut csv = std::io::BufWriter::new(std::fs::File::create(out.join("cone_script.csv"))?);
    writeln!(csv, "time,tip_travel,force_z")?;
    let mut phase = "push";
    let mut hold_until = 0.0;
    while sim.time() < sim.scene.end_time {
        let travel = start_tip - (sim.body_state(cone).origin[2] - 0.5 * 0.03784);
        match phase {
            "push" if travel >= depth => {
                sim.set_body_velocity(cone, [0.0; 3], [0.0; 3]);
                hold_until = sim.time() + hold;
                phase = "hold";
            }
            "push" => sim.set_body_velocity(cone, [0.0, 0.0, -speed], [0.0; 3]),
            "hold" if sim.time() >= hold_until => {
                sim.set_body_velocity(cone, [0.0, 0.0, speed], [0.0; 3]);
                phase = "withdraw";
            }
            "withdraw" if travel <= 0.0 => break,
            _ => {}
        }
        sim.step()?;
        let f = sim.fsi_wrench(cone).force[2];
        writeln!(csv, "{},{},{}", sim.time(), travel, f)?;
        if ((sim.time() * 1000.0).round() as u64).is_multiple_of(100) {
            println!("t = {:.2} s  {phase:<8} travel = {:6.1} mm  force = {f:7.3} N", sim.time(), travel * 1e3);
        }
    }
    csv.flush()?;
    println!("wrote {}", out.join("cone_script.csv").display());
    Ok(())
}
