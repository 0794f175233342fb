//! The static angle of repose test (`regolith calibrate repose`) and the open container it
//! stands in.

use regolith::calibrate::repose::{ReposeInputs, ReposeSettings, calibrate_repose};
use regolith::scene::load_scene_source;
use regolith::sim::Simulation;

use crate::common;

const BLOCK: &str = r#"
[simulation]
end_time = 0.35
precision = "f64"
[sph]
spacing = 0.02
[[materials]]
name = "sand"
model = "drucker-prager"
density = 1600
youngs_modulus = 1e6
poisson_ratio = 0.3
friction_angle = 30
[container]
min = [0.0, 0.0, 0.0]
max = [0.12, 0.12, 0.12]
WALLS
[[soil_blocks]]
material = "sand"
shape = "box"
min = [0.03, 0.03, 0.04]
max = [0.09, 0.09, 0.08]
[output]
mcap = false
"#;

fn run_block(walls: &str) -> (usize, usize) {
    let scene = common::scene(&BLOCK.replace("WALLS", walls));
    let mut sim = Simulation::<f64>::new(&scene).unwrap_or_else(|e| panic!("{e}"));
    while sim.time() < scene.end_time * (1.0 - 1e-12) {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
    }
    (sim.system.fluid.len(), sim.system.fluid.active())
}

#[test]
fn an_open_container_lets_soil_fall_out_of_the_domain() {
    // With walls the block lands on the floor and stays; without, it falls 0.16 m past the
    // domain's lower edge (six spacings under the floor) in √(2 · 0.16 / 9.81) = 0.18 s.
    let (n, active) = run_block("");
    assert_eq!(active, n, "with walls every particle stays");
    let (n, active) = run_block("walls = false");
    assert!(n > 0);
    assert_eq!(active, 0, "without walls every particle has left the domain");
    // `regolith check` says so, and counts no wall markers.
    let plan = regolith::scene::describe(&common::scene(&BLOCK.replace("WALLS", "walls = false")));
    assert!(plan.contains("open (walls = false)") && plan.contains("+ 0 wall markers"), "{plan}");
}

#[test]
fn an_open_container_refuses_a_wall_contact() {
    let text = BLOCK.replace("WALLS", "walls = false\nsoil_contact = \"smooth\"");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("inline.toml");
    let e = load_scene_source(&path, &text, &[]).unwrap_err().to_string();
    assert!(e.contains("container.soil_contact") && e.contains("walls = false"), "{e}");
}

/// A Drucker–Prager sand of friction angle `phi`, soft (E = 0.1 MPa) so that the test takes
/// few steps: the column's weight strains it by under 3 %.
fn sand(phi: f64) -> std::path::PathBuf {
    let dir = common::out_dir(&format!("repose_material_{phi}"));
    let p = dir.join("sand.toml");
    std::fs::write(
        &p,
        format!(
            "model = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 1e5\npoisson_ratio = 0.3\nfriction_angle = {phi}\n"
        ),
    )
    .expect("write material");
    p
}

#[test]
fn the_pile_angle_grows_with_the_friction_angle_and_soil_leaves_only_into_the_sink() {
    // Sized for CI: R = 8 d0 (AGX recommends 15 and more; docs/calibration.md has the default
    // size), a 2 R column, lifted at 0.2 m/s, two friction angles. What is checked does not depend on the size: a
    // steeper friction angle makes a steeper pile, soil leaves the base only downward (nothing
    // through the base, nothing carried up by the cylinder), and the pile comes to rest.
    let mut s = ReposeSettings::for_radius(0.08);
    s.spacing = 0.01;
    s.cell_radius = 0.01;
    s.lift_speed = 0.2;
    s.relax_time = 1.0;
    let mut angles = Vec::new();
    for phi in [20.0, 40.0] {
        let out = common::out_dir(&format!("repose_{phi}"));
        let r = calibrate_repose(&ReposeInputs {
            material: sand(phi),
            settings: s.clone(),
            out: out.clone(),
            target_angle: None,
            tolerance: regolith::calibrate::repose::ANGLE_TOLERANCE,
        })
        .unwrap_or_else(|e| panic!("φ = {phi}: {e}"));
        let u = &r.run;
        eprintln!(
            "φ = {phi}: pile {:.2}° ± {:.2}° ({} slices, min {:.2}, max {:.2}); {} on base, {} sunk, {} falling, settled {} at {:.2} s, {:.1} s wall",
            r.analysis.mean_deg,
            r.analysis.std_deg,
            r.IndividualAnglesOfRepose.len(),
            r.analysis.min_deg,
            r.analysis.max_deg,
            u.on_base,
            u.sunk,
            u.falling,
            u.settled,
            u.end_time,
            u.wall_time_s
        );
        assert_eq!(u.through_base, 0, "φ = {phi}: soil through the base");
        assert_eq!(u.lifted, 0, "φ = {phi}: soil carried up");
        assert!(u.on_base > 0 && u.sunk > 0, "φ = {phi}: some soil stays and some falls off");
        assert_eq!(u.on_base + u.sunk + u.falling, u.particles);
        assert!(u.settled, "φ = {phi}: the pile is still moving (rms {} m/s)", u.final_rms_speed);
        assert!(r.IndividualAnglesOfRepose.len() >= 10, "φ = {phi}: most slices have a slope");
        assert!(r.analysis.std_deg > 0.0, "the slice spread is reported");
        for f in ["repose.json", "particles.csv", "series.csv", "scene.toml", "tube.obj"] {
            assert!(out.join(f).is_file(), "{f} written");
        }
        angles.push(r.analysis.mean_deg);
    }
    assert!(angles[0] < angles[1], "angles {angles:?} grow with φ = 20, 40");
}
