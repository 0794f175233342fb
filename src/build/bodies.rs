//! Bodies meet the soil: soil that starts inside an FSI body is carved out, and the container
//! gets rigid walls for body–wall contact.

use regolith_rigid::RigidWorld;
use regolith_terrain::TerrainBuild;

use super::BuildError;
use crate::scene::Scene;

/// Removes the soil particles that start inside an FSI body grown by half a spacing less the
/// markers' inset (the distance at which its outermost markers and the soil would overlap),
/// with a note per body.
pub fn carve_bodies(scene: &Scene, terrain: &mut TerrainBuild) {
    let margin = scene.body_markers.contact_offset(scene.solver.spacing);
    for b in scene.bodies.iter().filter(|b| b.fsi) {
        let local: Vec<[f64; 3]> = terrain.particles.iter().map(|p| b.desc.pose.to_local(p.pos)).collect();
        let inside = b.desc.shape.contains_points(&local, margin);
        let removed = inside.iter().filter(|x| **x).count();
        if removed > 0 {
            let mut it = inside.iter();
            terrain.particles.retain(|_| !it.next().copied().unwrap_or(false));
            terrain
                .notes
                .push(format!("removed {removed} soil particles that started inside body \"{}\"", b.desc.name));
        }
    }
}

/// The container's floor and walls as fixed rapier boxes just outside the soil's walls.
pub(super) fn add_container(rigid: &mut RigidWorld, terrain: &TerrainBuild, d0: f64) -> Result<(), BuildError> {
    let c = terrain.container;
    let t = 0.25 * (c.size()[0].min(c.size()[1])).max(d0);
    let [x0, y0, z0] = c.min;
    let [x1, y1, z1] = c.max;
    let walls = [
        ("container floor", [x0 - t, y0 - t, z0 - t], [x1 + t, y1 + t, z0]),
        ("container wall -x", [x0 - t, y0 - t, z0], [x0, y1 + t, z1]),
        ("container wall +x", [x1, y0 - t, z0], [x1 + t, y1 + t, z1]),
        ("container wall -y", [x0, y0 - t, z0], [x1, y0, z1]),
        ("container wall +y", [x0, y1, z0], [x1, y1 + t, z1]),
    ];
    for (name, lo, hi) in walls {
        rigid.add_fixed_box(name, lo, hi, 0.5).map_err(BuildError::rigid("container"))?;
    }
    Ok(())
}
