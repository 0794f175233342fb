//! Driving the URDF rover over deformable soil through the Rust API: load the rover scene,
//! let the rover settle, drive straight at 3 rad/s, then skid-steer left, printing the rover's
//! position, heading and each wheel's slip and sinkage. Writes `OUT_DIR/urdf_rover.csv`.
//!
//! `cargo run --release --example urdf_rover [OUT_DIR]`

use std::io::Write;
use std::path::PathBuf;

use regolith::output::series::roll_pitch_yaw_deg;
use regolith::scene::load_scene;
use regolith::sim::Simulation;

fn main() -> anyhow::Result<()> {
    let out = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| PathBuf::from("out/urdf_rover"));
    std::fs::create_dir_all(&out)?;
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/rover.toml");
    let mut scene = load_scene(&path, &[])?;
    // This script drives the wheels itself: drop the scene's drive profiles and run 1.6 s.
    scene.vehicles[0].drive.clear();
    scene.end_time = 1.6;
    let mut sim = Simulation::<f32>::new(&scene)?;
    let chassis = sim.body("rover/base_link").ok_or_else(|| anyhow::anyhow!("no rover/base_link"))?;
    let wheels: Vec<String> =
        scene.vehicles[0].wheels.iter().map(|w| scene.vehicles[0].model.links[w.link].name.clone()).collect();
    let mut csv = std::io::BufWriter::new(std::fs::File::create(out.join("urdf_rover.csv"))?);
    write!(csv, "time,x,y,z,yaw_deg")?;
    for w in &wheels {
        write!(csv, ",{w}.slip,{w}.sinkage")?;
    }
    writeln!(csv)?;
    let mut phase = 0;
    let mut next_print = 0.0;
    while sim.time() < scene.end_time - 1e-9 {
        let t = sim.time();
        if phase == 0 && t >= 0.3 {
            sim.set_vehicle_drive("rover", 3.0, 3.0, 6.0)?;
            phase = 1;
        } else if phase == 1 && t >= 1.0 {
            sim.set_vehicle_drive("rover", 1.0, 4.0, 6.0)?;
            phase = 2;
        }
        sim.step()?;
        let st = sim.body_state(chassis);
        let yaw = roll_pitch_yaw_deg(st.rotation)[2];
        let ws = sim.wheel_states(0);
        write!(csv, "{},{},{},{},{yaw}", sim.time(), st.origin[0], st.origin[1], st.origin[2])?;
        for w in &ws {
            write!(csv, ",{},{}", w.slip, w.sinkage)?;
        }
        writeln!(csv)?;
        if sim.time() >= next_print {
            next_print += 0.1;
            let slips: Vec<String> = ws.iter().map(|w| format!("{:.2}", w.slip)).collect();
            let sink: Vec<String> = ws.iter().map(|w| format!("{:.1}", w.sinkage * 1e3)).collect();
            println!(
                "t = {:.2} s  x = {:.3} m  y = {:.3} m  yaw = {yaw:6.2}°  slip [{}]  sinkage [{}] mm",
                sim.time(),
                st.origin[0],
                st.origin[1],
                slips.join(", "),
                sink.join(", ")
            );
        }
    }
    println!("wrote {}", out.join("urdf_rover.csv").display());
    Ok(())
}
