//! The rapier plugin (`RapierSoil` over a world the caller owns) gives the same body trajectory
//! as the scene runner on the equivalent scene file, to round-off.

use crate::common;
#[path = "../examples/rapier_plugin.rs"]
mod example;

use regolith::sim::Simulation;

#[test]
fn plugin_over_a_plain_rapier_world_matches_the_scene_file() {
    let scene = common::example("rapier_plugin_equivalent.toml", &[]);
    // Both sides build the same soil: the scene's settings are the library's defaults where
    // the file is silent.
    assert_eq!(scene.solver, example::soil_config(), "scene defaults are the library's defaults");
    assert_eq!(
        scene.materials[0].params.build::<f64>().expect("builds"),
        example::sand().build::<f64>().expect("builds")
    );
    let steps = 60;
    let mut sim = Simulation::<f64>::new(&scene).expect("scene builds");
    let sphere = sim.body("sphere").expect("sphere");
    let mut from_scene = Vec::new();
    for _ in 0..steps {
        sim.step().expect("steps");
        from_scene.push(sim.body_state(sphere).origin);
    }
    let from_plugin = example::drop_sphere(steps).expect("plugin runs");
    let z0 = 0.13;
    let fall = z0 - from_scene.last().expect("steps")[2];
    let lift = sim.fsi_wrench(sphere).force[2];
    // A case where nothing happens would match trivially: the sphere must fall onto the soil
    // and the soil must carry it (weight 4.9 N).
    assert!(fall > 1e-3 && lift > 1.0, "the sphere falls onto the soil (fell {fall} m, soil force {lift} N)");
    let mut worst = 0.0_f64;
    for (a, b) in from_scene.iter().zip(&from_plugin) {
        for k in 0..3 {
            worst = worst.max((a[k] - b[k]).abs());
        }
    }
    println!("sphere fell {fall:.5} m, soil force {lift:.3} N; largest difference between the paths {worst:.3e} m");
    // Rapier stores positions in f32: 0.1 m carries a rounding of 7e-9 m. The two paths differ
    // only in the f32 rounding of the step length and of the accelerations fed to the markers.
    assert!(worst < 1e-6, "paths differ by {worst:e} m");
}

/// A body handle is tied to the simulation that gave it: used on another one (even of the same
/// scene, where the index would be in range) it panics with a message naming the mistake
/// instead of reading that simulation's body.
#[test]
#[should_panic(expected = "Body handle of another Simulation")]
fn a_body_handle_from_another_simulation_is_refused() {
    let scene = common::example("rapier_plugin_equivalent.toml", &[]);
    let a = Simulation::<f64>::new(&scene).expect("scene builds");
    let b = Simulation::<f64>::new(&scene).expect("scene builds");
    let sphere_of_a = a.body("sphere").expect("sphere");
    assert_eq!(a.body_state(sphere_of_a).origin, b.body_state(b.body("sphere").expect("sphere")).origin);
    let _ = b.body_state(sphere_of_a);
}
