//! `[[materials]]`, `[container]`, `[terrain]`, `[[soil_blocks]]` and `[[water_blocks]]`: the
//! soil, the water in and above it, and what they are made of.

use super::*;

/// Materials, container and soil regions.
pub(super) type Soil = (Vec<SceneMaterial>, Option<Aabb>, Vec<SoilSpec>);

pub(super) fn resolve_soil(
    path: &Path,
    source: &str,
    dir: &Path,
    file: &SceneFile,
    spacing: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Soil, InputError> {
    let materials = resolve_materials(path, source, dir, file, e)?;
    let container = resolve_container(file.container.as_ref(), spacing, e)?;
    let mut soil = Vec::new();
    if let Some(t) = &file.terrain {
        soil.push(resolve_terrain(path, source, dir, t, &materials, container, spacing, e)?);
    }
    let is_water = |m: usize| materials[m].is_water();
    if let Some(t) = soil.first()
        && is_water(t.material)
    {
        return Err(e("terrain.material", "is water: the bed is soil; put water in [[water_blocks]]".into()));
    }
    let blocks = file.soil_blocks.iter().enumerate().map(|(i, b)| ("soil_blocks", i, b));
    let blocks = blocks.chain(file.water_blocks.iter().enumerate().map(|(i, b)| ("water_blocks", i, b)));
    for (section, i, b) in blocks {
        soil.push(resolve_block(section, i, b, &materials, container, spacing, e)?);
    }
    if soil.is_empty() {
        return Err(InputError::file(path, "the scene has no soil: add [terrain] or [[soil_blocks]]"));
    }
    check_uses(&materials, &soil, e)?;
    Ok((materials, container, soil))
}

/// `[[materials]]`: inline, or from a file named relative to the scene; names unique.
fn resolve_materials(
    path: &Path,
    source: &str,
    dir: &Path,
    file: &SceneFile,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Vec<SceneMaterial>, InputError> {
    let mut materials = Vec::new();
    for (i, m) in file.materials.iter().enumerate() {
        let prefix = format!("materials[{i}].");
        let name = m.name.clone().ok_or_else(|| {
            e(&format!("materials[{i}].name"), "is required: the name terrain and soil blocks refer to".into())
        })?;
        if name.trim().is_empty() {
            return Err(e(&format!("materials[{i}].name"), "must not be empty".into()));
        }
        if materials.iter().any(|x: &SceneMaterial| x.name == name) {
            return Err(e(
                &format!("materials[{i}].name"),
                format!("\"{name}\" is defined twice; material names must be unique"),
            ));
        }
        let params = if let Some(f) = &m.file {
            let only_name = MaterialParams { name: m.name.clone(), file: m.file.clone(), ..Default::default() };
            if *m != only_name {
                return Err(e(
                    &format!("materials[{i}].file"),
                    "a material read from a file takes only `name` and `file` here; put the other keys in the file"
                        .into(),
                ));
            }
            let p = dir.join(f);
            let mut params = load_material_file(&p)?;
            params.name = Some(name.clone());
            params
        } else {
            build_material::<f64>(m, path, &prefix, source)?;
            m.clone()
        };
        materials.push(SceneMaterial { name, params });
    }
    Ok(materials)
}

/// The index of the material a soil region names at `key`.
fn find_material(
    materials: &[SceneMaterial],
    key: &str,
    name: &Option<String>,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<usize, InputError> {
    let n = name.as_ref().ok_or_else(|| e(key, "is required: the name of a [[materials]] entry".into()))?;
    materials.iter().position(|m| &m.name == n).ok_or_else(|| {
        let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
        e(
            key,
            format!(
                "\"{n}\" is not a defined material (defined: {})",
                if known.is_empty() { "none".into() } else { known.join(", ") }
            ),
        )
    })
}

/// `[container]`: two finite corners at least four spacings apart on every axis.
fn resolve_container(
    c: Option<&file::ContainerFile>,
    spacing: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Option<Aabb>, InputError> {
    let Some(c) = c else { return Ok(None) };
    let min = c.min.ok_or_else(|| e("container.min", "is required: lower corner [x, y, z] in m".into()))?;
    let max = c.max.ok_or_else(|| e("container.max", "is required: upper corner [x, y, z] in m".into()))?;
    if min.iter().chain(&max).any(|v| !v.is_finite()) {
        return Err(e("container.max", "corners must be finite".into()));
    }
    for k in 0..3 {
        if max[k] - min[k] < 4.0 * spacing {
            return Err(e(
                "container.max",
                format!(
                    "must exceed container.min by at least 4 × sph.spacing = {} m along each axis (axis {} spans {} m)",
                    4.0 * spacing,
                    ["x", "y", "z"][k],
                    max[k] - min[k]
                ),
            ));
        }
    }
    Ok(Some(Aabb { min, max }))
}

/// `[terrain]`: a bed filling the container's floor, flat to a depth or shaped by a heightmap.
#[allow(clippy::too_many_arguments)]
fn resolve_terrain(
    path: &Path,
    source: &str,
    dir: &Path,
    t: &file::TerrainFile,
    materials: &[SceneMaterial],
    container: Option<Aabb>,
    spacing: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<SoilSpec, InputError> {
    let material = find_material(materials, "terrain.material", &t.material, e)?;
    let c = container.ok_or_else(|| e("terrain", "needs a [container]: the bed fills the container floor".into()))?;
    let height = c.size()[2];
    let surface = match (t.depth, &t.heightmap) {
        (Some(_), Some(_)) => {
            return Err(e("terrain.depth", "and terrain.heightmap are both given: give one".into()));
        }
        (None, None) => {
            return Err(e("terrain.depth", "is required (or terrain.heightmap): bed depth in m".into()));
        }
        (Some(d), None) => {
            if t.heightmap_range.is_some() {
                return Err(e("terrain.heightmap_range", "applies only with terrain.heightmap".into()));
            }
            if !(d.is_finite() && d >= 2.0 * spacing && d <= height) {
                return Err(e(
                    "terrain.depth",
                    format!(
                        "must be in [2 × sph.spacing = {}, container height = {height}] m (got {d})",
                        2.0 * spacing
                    ),
                ));
            }
            Surface::Flat(d)
        }
        (None, Some(hm)) => {
            let range = t.heightmap_range.map(|r| (r[0], r[1]));
            let map = Heightmap::load(&dir.join(hm), range)
                .map_err(|err| InputError::key(path, "terrain.heightmap", err.to_string()).located(source))?;
            if map.max_height() > height {
                return Err(e(
                    "terrain.heightmap",
                    format!("heights reach {} m, above the container height {height} m", map.max_height()),
                ));
            }
            Surface::Heightmap(map)
        }
    };
    Ok(SoilSpec {
        material,
        region: SoilRegion::Bed { container: c, surface },
        key: "terrain".into(),
        velocity: [0.0; 3],
        initial_pressure: None,
    })
}

/// `{section}[i]` of `[[soil_blocks]]` or `[[water_blocks]]`: its material (soil or water as
/// the section says), its shape inside the container, its velocity and initial pressure.
fn resolve_block(
    section: &str,
    i: usize,
    b: &file::SoilBlockFile,
    materials: &[SceneMaterial],
    container: Option<Aabb>,
    spacing: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<SoilSpec, InputError> {
    let k = |s: &str| format!("{section}[{i}].{s}");
    let material = find_material(materials, &k("material"), &b.material, e)?;
    let water = section == "water_blocks";
    if water != materials[material].is_water() {
        return Err(e(
            &k("material"),
            if water {
                format!(
                    "\"{}\" is a soil: water blocks take a material with model = \"water\"",
                    materials[material].name
                )
            } else {
                format!("\"{}\" is water: put it in [[water_blocks]]", materials[material].name)
            },
        ));
    }
    if water && b.initial_pressure.is_some() {
        return Err(e(
            &k("initial_pressure"),
            "applies to soil blocks; water starts hydrostatic from the water above it".into(),
        ));
    }
    let region = block_region(b, &k, spacing, e)?;
    if let Some(c) = container {
        let (lo, hi) = region_bounds(&region);
        let eps = 1e-9 * spacing;
        if (0..3).any(|a| lo[a] < c.min[a] - eps || hi[a] > c.max[a] + eps) {
            return Err(e(
                &k("shape"),
                format!("the block [{lo:?} .. {hi:?}] must lie inside the container [{:?} .. {:?}]", c.min, c.max),
            ));
        }
    } else {
        return Err(e(&k("shape"), "soil blocks need a [container] to stand in (walls and floor)".into()));
    }
    let velocity = b.velocity.unwrap_or([0.0; 3]);
    if velocity.iter().any(|v| !v.is_finite()) {
        return Err(e(&k("velocity"), "must be finite [vx, vy, vz] in m/s".into()));
    }
    let initial_pressure = match b.initial_pressure {
        None => None,
        Some(p) if p.is_finite() && p > 0.0 => Some(p),
        Some(p) => {
            return Err(e(
                &k("initial_pressure"),
                format!("must be a compression > 0 Pa (got {p}); leave it out for the geostatic state"),
            ));
        }
    };
    Ok(SoilSpec { material, region, key: format!("{section}[{i}]"), velocity, initial_pressure })
}

/// A block's shape: a box from `min` and `max`, or a cylinder from `base_center`, `radius`
/// and `height`, each at least one spacing across; the other shape's keys are refused.
fn block_region(
    b: &file::SoilBlockFile,
    k: &dyn Fn(&str) -> String,
    spacing: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<SoilRegion, InputError> {
    let shape = b.shape.ok_or_else(|| e(&k("shape"), "is required: \"box\" or \"cylinder\"".into()))?;
    Ok(match shape {
        BlockShapeName::Box => {
            for (name, present) in [
                ("base_center", b.base_center.is_some()),
                ("radius", b.radius.is_some()),
                ("height", b.height.is_some()),
            ] {
                if present {
                    return Err(e(&k(name), "applies to shape = \"cylinder\" only; a box takes min and max".into()));
                }
            }
            let min = b.min.ok_or_else(|| e(&k("min"), "is required for a box: lower corner [x, y, z] in m".into()))?;
            let max = b.max.ok_or_else(|| e(&k("max"), "is required for a box: upper corner [x, y, z] in m".into()))?;
            if (0..3).any(|a| !min[a].is_finite() || !max[a].is_finite() || max[a] - min[a] < spacing * (1.0 - 1e-9)) {
                return Err(e(
                    &k("max"),
                    format!("must exceed min by at least sph.spacing = {spacing} m along each axis"),
                ));
            }
            SoilRegion::Block(Aabb { min, max })
        }
        BlockShapeName::Cylinder => {
            for (name, present) in [("min", b.min.is_some()), ("max", b.max.is_some())] {
                if present {
                    return Err(e(
                        &k(name),
                        "applies to shape = \"box\" only; a cylinder takes base_center, radius and height".into(),
                    ));
                }
            }
            let base_center = b.base_center.ok_or_else(|| {
                e(&k("base_center"), "is required for a cylinder: [x, y, z] of the bottom face centre in m".into())
            })?;
            let radius = b.radius.ok_or_else(|| e(&k("radius"), "is required for a cylinder (m)".into()))?;
            let height = b.height.ok_or_else(|| e(&k("height"), "is required for a cylinder (m)".into()))?;
            if !(radius.is_finite() && radius >= spacing * (1.0 - 1e-9)) {
                return Err(e(&k("radius"), format!("must be ≥ sph.spacing = {spacing} m (got {radius})")));
            }
            if !(height.is_finite() && height >= spacing * (1.0 - 1e-9)) {
                return Err(e(&k("height"), format!("must be ≥ sph.spacing = {spacing} m (got {height})")));
            }
            SoilRegion::Cylinder { base_center, radius, height }
        }
    })
}

/// Water takes one water material and a permeability on every soil; every material is used.
fn check_uses(
    materials: &[SceneMaterial],
    soil: &[SoilSpec],
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<(), InputError> {
    let is_water = |m: usize| materials[m].is_water();
    if soil.iter().any(|s| is_water(s.material)) {
        if materials.iter().filter(|m| m.is_water()).count() > 1 {
            return Err(e("water_blocks", "take one water material: a scene holds at most one".into()));
        }
        if let Some(i) = (0..materials.len()).find(|&i| !is_water(i) && materials[i].params.permeability.is_none()) {
            return Err(e(
                &format!("materials[{i}].permeability"),
                format!(
                    "is required for \"{}\": the scene has water, which flows through every soil (give permeability in m/s and grain_density)",
                    materials[i].name
                ),
            ));
        }
    }
    for (i, m) in materials.iter().enumerate() {
        if !soil.iter().any(|s| s.material == i) {
            return Err(e(
                &format!("materials[{i}].name"),
                format!("material \"{}\" is defined but not used by any soil", m.name),
            ));
        }
    }
    Ok(())
}

/// `[terrain] patch`: a moving patch needs the terrain's bed, container walls to move with
/// it, an FSI body to follow, the CPU backend and a dry scene; its length must hold the
/// trigger distance twice over and be shorter than the bed.
pub(super) fn resolve_patch(
    patch: Option<&PatchFile>,
    container: &Option<Aabb>,
    (solver, wet, walls): (&SolverConfig, bool, bool),
    bodies: &[BodySpec],
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Option<PatchSpec>, InputError> {
    let Some(p) = patch else { return Ok(None) };
    let Some(c) = container else {
        return Err(e("terrain.patch", "needs a [container]: the patch is a slice of its bed".into()));
    };
    let support = 2.0 * solver.h();
    let trigger = p.trigger.ok_or_else(|| {
        e("terrain.patch.trigger", "is required: soil kept ahead of the foremost FSI body (m)".into())
    })?;
    if !(trigger.is_finite() && trigger >= 2.0 * support) {
        return Err(e(
            "terrain.patch.trigger",
            format!("must be at least twice the kernel support, 4h = {} m (got {trigger})", 2.0 * support),
        ));
    }
    let length = p
        .length
        .ok_or_else(|| e("terrain.patch.length", "is required: length of the simulated patch along x (m)".into()))?;
    let bed = c.size()[0];
    if !(length.is_finite() && length >= 2.0 * trigger && length < bed) {
        return Err(e(
            "terrain.patch.length",
            format!(
                "must be at least twice terrain.patch.trigger ({} m) and shorter than the container along x ({bed} m) (got {length})",
                2.0 * trigger
            ),
        ));
    }
    if wet {
        return Err(e(
            "terrain.patch",
            "is not available with water yet: remove it from a scene with [[water_blocks]]".into(),
        ));
    }
    if !walls {
        return Err(e(
            "terrain.patch",
            "needs the container's walls (container.walls = false): they move with the patch".into(),
        ));
    }
    if !bodies.iter().any(|b| b.fsi) {
        return Err(e("terrain.patch", "follows the scene's FSI bodies, and the scene has none".into()));
    }
    // The patch starts at the container's low-x end: a body starting beyond it would have no
    // soil under it until the first advance.
    let end = c.min[0] + length;
    if let Some(b) = bodies.iter().find(|b| b.fsi && b.desc.pose.translation[0] + b.desc.shape.bounding_radius() > end)
    {
        return Err(e(
            "terrain.patch.length",
            format!(
                "{} starts at x = {} m, beyond the patch's start, which holds x = {}..{end} m: place the FSI bodies within it or lengthen it",
                b.key, b.desc.pose.translation[0], c.min[0]
            ),
        ));
    }
    Ok(Some(PatchSpec { length, trigger }))
}
