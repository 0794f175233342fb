//! Regolith soil under a rapier simulation you build yourself: a plain rapier world (no scene
//! file), a sand bed made with `regolith-terrain`, and a sphere dropped on it. The soil is a
//! plugin (`RapierSoil`): before each rapier step it advances the soil over that step and sets
//! the sphere's soil force.
//!
//! `examples/scenes/rapier_plugin_equivalent.toml` is the same setup as a scene file;
//! `tests/rapier_plugin.rs` checks that both give the same trajectory.
//!
//! Run: `cargo run --release --example rapier_plugin`

use rapier3d::prelude::*;
use regolith::coupling::{Attachment, RapierSoil, SoilInit, shape_of_body};
use regolith::fsi::config::SolverConfig;
use regolith::fsi::rheology::{MaterialParams, ModelKind};
use regolith::rigid::ShapeDesc;
use regolith::terrain::{Aabb, RegionSpec, SoilRegion, Surface, build_terrain};

/// Exchange step = rapier step (s).
pub const DT: f64 = 1e-3;

/// The soil settings: the library defaults at 1 cm spacing.
pub fn soil_config() -> SolverConfig {
    SolverConfig { spacing: 0.01, ..SolverConfig::default() }
}

/// The sand.
pub fn sand() -> MaterialParams {
    MaterialParams {
        name: Some("sand".into()),
        model: Some(ModelKind::DruckerPrager),
        density: Some(1600.0),
        youngs_modulus: Some(2e6),
        poisson_ratio: Some(0.3),
        friction_angle: Some(30.0),
        ..MaterialParams::default()
    }
}

/// A fixed box as the container walls are built (density 1000, friction 0.5).
fn fixed_box(world: &mut PhysicsWorld, min: [f64; 3], max: [f64; 3]) {
    let c = [0, 1, 2].map(|k| (0.5 * (min[k] + max[k])) as f32);
    let h = [0, 1, 2].map(|k| (0.5 * (max[k] - min[k])) as f32);
    let body = RigidBodyBuilder::fixed().translation(Vector::new(c[0], c[1], c[2])).can_sleep(false).ccd_enabled(false);
    let handle = world.bodies.insert(body.build());
    let collider = ColliderBuilder::cuboid(h[0], h[1], h[2]).density(1000.0).friction(0.5).build();
    world.colliders.insert_with_parent(collider, handle, &mut world.bodies);
}

/// Builds the world and the soil, drops the sphere for `steps` steps; returns the sphere's
/// centre after each step.
pub fn drop_sphere(steps: usize) -> Result<Vec<[f64; 3]>, Box<dyn std::error::Error>> {
    let config = soil_config();
    let material64 = sand().build::<f64>()?;
    // The soil: a 8 cm bed of sand in a 0.2 × 0.2 × 0.2 m container.
    let container = Aabb { min: [0.0; 3], max: [0.2, 0.2, 0.2] };
    let bed = RegionSpec {
        region: SoilRegion::Bed { container, surface: Surface::Flat(0.08) },
        material: 0,
        velocity: [0.0; 3],
        initial_pressure: None,
    };
    let terrain = build_terrain(&container, config.spacing, config.bce_layers, config.gravity, &[bed], &[material64])?;
    // The rapier world: the container's floor and walls, then the sphere.
    let mut world = PhysicsWorld { gravity: Vector::new(0.0, 0.0, -9.81), ..Default::default() };
    let c = terrain.container;
    let t = 0.25 * (c.size()[0].min(c.size()[1])).max(config.spacing);
    let ([x0, y0, z0], [x1, y1, z1]) = (c.min, c.max);
    fixed_box(&mut world, [x0 - t, y0 - t, z0 - t], [x1 + t, y1 + t, z0]);
    fixed_box(&mut world, [x0 - t, y0 - t, z0], [x0, y1 + t, z1]);
    fixed_box(&mut world, [x1, y0 - t, z0], [x1 + t, y1 + t, z1]);
    fixed_box(&mut world, [x0, y0 - t, z0], [x1, y0, z1]);
    fixed_box(&mut world, [x0, y1, z0], [x1, y1 + t, z1]);
    let radius = 0.04;
    let density = 0.5 / ShapeDesc::Sphere { radius }.volume();
    let sphere = world.bodies.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.1, 0.1, 0.13)).can_sleep(false).ccd_enabled(false),
    );
    let ball = ColliderBuilder::ball(radius as f32).density(density as f32).friction(0.5).build();
    world.colliders.insert_with_parent(ball, sphere, &mut world.bodies);
    // The plugin: soil attached to the sphere, markers from its collider.
    let shape = shape_of_body(&world.bodies, &world.colliders, sphere)?;
    let soil = SoilInit {
        config,
        materials: vec![material64],
        particles: &terrain.particles,
        wall_markers: &terrain.markers,
        domain: terrain.domain,
    };
    let attach = [Attachment { handle: sphere, shape, layers: config.bce_layers }];
    let mut plugin = RapierSoil::<f64>::new(soil, &world.bodies, &attach)?;
    let mut path = Vec::with_capacity(steps);
    world.integration_parameters.dt = DT as f32;
    for _ in 0..steps {
        plugin.advance(&mut world.bodies, DT)?;
        world.step();
        let p = world.bodies[sphere].translation();
        path.push([p.x, p.y, p.z].map(f64::from));
    }
    Ok(path)
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = drop_sphere(60)?;
    for (i, p) in path.iter().enumerate().step_by(10) {
        println!("t = {:.3} s  sphere centre z = {:.5} m", (i + 1) as f64 * DT, p[2]);
    }
    Ok(())
}
