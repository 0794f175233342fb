//! What `regolith check` prints: the resolved scene.

use std::fmt::Write;

use regolith_fsi::config::{Integrator, KernelKind, Shifting, TimeStep};
use regolith_fsi::rheology::Rheology;
use regolith_terrain::{SoilRegion, Surface};

use super::{Scene, region_bounds};

fn volume(r: &SoilRegion) -> f64 {
    match r {
        SoilRegion::Bed { container, surface } => {
            let s = container.size();
            match surface {
                Surface::Flat(d) => s[0] * s[1] * d,
                Surface::Heightmap(h) => s[0] * s[1] * h.heights.iter().sum::<f64>() / h.heights.len() as f64,
            }
        }
        SoilRegion::Block(b) => {
            let s = b.size();
            s[0] * s[1] * s[2]
        }
        SoilRegion::Cylinder { radius, height, .. } => std::f64::consts::PI * radius * radius * height,
    }
}

/// A human-readable description of what the scene would run: one line (or a few) per part of
/// the scene, in the order the sections below write them.
pub fn describe(scene: &Scene) -> String {
    let mut s = String::new();
    write_run(&mut s, scene);
    let min_dt = write_materials(&mut s, scene);
    let particles = write_soil(&mut s, scene);
    let walls = write_container(&mut s, scene);
    write_bodies(&mut s, scene);
    for v in &scene.vehicles {
        write_vehicle(&mut s, v);
    }
    if let Some(r) = &scene.rig {
        write_rig(&mut s, scene, r);
    }
    write_recording(&mut s, scene);
    write_size(&mut s, scene, particles, walls, min_dt);
    write_effects(&mut s, scene);
    s
}

/// The run, time stepping, SPH settings, neighbour lists and the effects the solver is
/// specialised for (the wgpu pipeline's constants and modules, the CPU backend's loops).
fn write_run(s: &mut String, scene: &Scene) {
    let sv = &scene.solver;
    let _ = writeln!(s, "scene {}", scene.path.display());
    let _ = writeln!(
        s,
        "  run: {} s of simulated time on backend {} in {}",
        scene.end_time,
        scene.backend.name(),
        scene.precision.name()
    );
    let integ = match sv.integrator {
        Integrator::Rk2 => "explicit midpoint (rk2)",
        Integrator::Euler => "explicit Euler",
    };
    let dt = match sv.time_step {
        TimeStep::Fixed(dt) => format!("fixed dt = {dt} s"),
        TimeStep::Adaptive { cfl, max } => format!("adaptive dt (CFL {cfl}, at most {max} s)"),
    };
    let _ = writeln!(s, "  time: {integ}, {dt}");
    let kernel = match sv.kernel {
        KernelKind::Wendland => "Wendland C2",
        KernelKind::Cubic => "cubic spline",
    };
    let _ = writeln!(
        s,
        "  sph: d0 = {} m, h = {:.4} m (h/d0 = {}), {kernel} kernel, artificial viscosity α = {}",
        sv.spacing,
        sv.h(),
        sv.h_factor,
        sv.artificial_viscosity
    );
    let lists = if sv.neighbor_skin > 0.0 {
        format!(
            "reused within a Verlet skin of {} h = {:.4} m (the wgpu backend rebuilds every step)",
            sv.neighbor_skin,
            sv.neighbor_skin * sv.h()
        )
    } else {
        "rebuilt every step".to_string()
    };
    let _ = writeln!(s, "  neighbour lists: {lists}");
    // The effects the solver is specialised for (the wgpu pipeline's constants and modules,
    // the CPU backend's monomorphised loops).
    #[cfg(feature = "wgpu")]
    let mut effects = {
        // Every material of a validated scene builds; one that would not is named, not dropped.
        match scene.materials.iter().map(|m| m.params.build::<f32>()).collect::<Result<Vec<_>, _>>() {
            Ok(mats32) => regolith_wgpu::Effects::resolve(sv, &mats32).names(),
            Err(_) => vec!["(a material does not build in f32: effects unknown)"],
        }
    };
    // Without the wgpu backend only the choices below are listed.
    #[cfg(not(feature = "wgpu"))]
    let mut effects: Vec<&str> = Vec::new();
    let fs = match sv.free_surface_threshold {
        Some(t) => format!("free-surface(λ < {t})"),
        None => "free-surface off".into(),
    };
    let fsi = scene.bodies.iter().filter(|b| b.fsi).count();
    let fsi = format!("fsi-bodies={fsi}");
    effects.push(&fs);
    effects.push(&fsi);
    let _ = writeln!(s, "  effects: {}", effects.join(", "));
}

/// One line per material; returns the smallest h / c over them (s), the stable step's scale.
fn write_materials(s: &mut String, scene: &Scene) -> f64 {
    let sv = &scene.solver;
    let mut min_dt = f64::INFINITY;
    for m in &scene.materials {
        let Ok(mat) = m.params.build::<f64>() else { continue };
        let detail = match &mat.rheology {
            Rheology::Elastic => String::new(),
            Rheology::Water(w) => format!(", sound speed {} m/s, viscosity {} Pa s", w.sound_speed, w.viscosity),
            Rheology::DruckerPrager(dp) => format!(
                ", φ = {}°, c = {} Pa{}",
                mat.friction_angle_deg,
                mat.cohesion,
                if dp.has_mu_i() { " with μ(I)" } else { "" }
            ),
            Rheology::Mcc(mcc) => format!(
                ", M = {}, κ = {}, λ = {}, v_λ = {}, OCR = {}, clamp {}, p_c floor {} Pa",
                mcc.m,
                mcc.kappa,
                mcc.lambda,
                mcc.v_lambda,
                mat.ocr,
                if mcc.safeguards.moduli_clamp.is_some() { "on" } else { "off" },
                mcc.safeguards.pc_floor
            ),
        };
        let c = mat.wave_speed();
        min_dt = min_dt.min(sv.h() / c);
        let _ = writeln!(
            s,
            "  material \"{}\": {}, ρ = {} kg/m³, E = {} Pa, ν = {}{detail}; wave speed {:.1} m/s",
            m.name,
            mat.rheology.name(),
            mat.density,
            m.params.youngs_modulus.unwrap_or(f64::NAN),
            mat.poisson,
            c
        );
    }
    min_dt
}

/// One line per soil region and the moving patch; returns about how many particles the
/// solver holds.
fn write_soil(s: &mut String, scene: &Scene) -> f64 {
    let sv = &scene.solver;
    let d3 = sv.spacing.powi(3);
    let mut total = 0.0;
    for spec in &scene.soil {
        let n = volume(&spec.region) / d3;
        total += n;
        let (lo, hi) = region_bounds(&spec.region);
        let _ = writeln!(
            s,
            "  soil {}: \"{}\" in [{:?} .. {:?}], about {:.0} particles{}",
            spec.key,
            scene.materials[spec.material].name,
            lo,
            hi,
            n,
            spec.initial_pressure
                .map_or(String::new(), |p| format!(", starting at an isotropic pressure of {p} Pa (not geostatic)"))
        );
    }
    if let (Some(p), Some(c)) = (scene.patch, scene.container) {
        let bed = c.size()[0];
        // Particles scale with the length held (the walls too, roughly).
        total *= p.length / bed;
        let _ = writeln!(
            s,
            "  moving patch: {} m of the {bed} m bed along x (about {total:.0} particles), advancing to keep {} m of soil ahead of the foremost FSI body; soil laid ahead in its generated state",
            p.length, p.trigger
        );
    }
    total
}

/// The container and its walls; returns about how many wall markers it holds.
fn write_container(s: &mut String, scene: &Scene) -> f64 {
    let sv = &scene.solver;
    let mut walls = 0.0;
    if let Some(c) = scene.container
        && !scene.container_walls
    {
        let _ = writeln!(
            s,
            "  container [{:?} .. {:?}]: open (walls = false): no walls; soil leaving the domain escapes",
            c.min, c.max
        );
    } else if let Some(c) = scene.container {
        let mut sz = c.size();
        if let Some(p) = scene.patch {
            // The walls are those of the patch.
            sz[0] = p.length;
        }
        let area = sz[0] * sz[1] + 2.0 * sz[2] * (sz[0] + sz[1]);
        walls = area / sv.spacing.powi(2) * sv.bce_layers as f64;
        let _ = writeln!(
            s,
            "  container [{:?} .. {:?}]: floor and four walls, {} BCE layers, about {:.0} markers",
            c.min, c.max, sv.bce_layers, walls
        );
    }
    walls
}

/// One line per rigid body: shape, mass, pose, motion and soil contact.
fn write_bodies(s: &mut String, scene: &Scene) {
    let sv = &scene.solver;
    for b in &scene.bodies {
        let n = if b.fsi {
            regolith_coupling::shape_markers(
                &b.desc.shape,
                sv.spacing,
                b.bce_layers,
                scene.body_markers.inset(sv.spacing),
            )
            .map(|m| m.len())
            .unwrap_or(0)
        } else {
            0
        };
        let motion = match &b.desc.motion {
            regolith_rigid::Motion::Free => "free".to_string(),
            regolith_rigid::Motion::Fixed => "fixed".to_string(),
            regolith_rigid::Motion::Prescribed { linvel, angvel } => {
                format!("prescribed v = {linvel:?} m/s, ω = {angvel:?} rad/s")
            }
            regolith_rigid::Motion::Waypoints(w) => format!("{} waypoints", w.len()),
        };
        let mass = match b.desc.mass {
            regolith_rigid::MassSpec::Mass(m) => format!("{m} kg"),
            regolith_rigid::MassSpec::Density(d) => format!("{d} kg/m³ ({:.3} kg)", d * b.desc.shape.volume()),
            regolith_rigid::MassSpec::Inertial { mass, .. } => format!("{mass} kg (inertial)"),
        };
        let _ = writeln!(
            s,
            "  body \"{}\": {}, {mass}, at [{:.4}, {:.4}, {:.4}], {motion}, {}",
            b.desc.name,
            shape_name(&b.desc.shape),
            b.desc.pose.translation[0],
            b.desc.pose.translation[1],
            b.desc.pose.translation[2],
            if b.fsi {
                format!("{n} BCE markers in {} layers, {}", b.bce_layers, scene.body_markers.describe())
            } else {
                "no soil contact".into()
            }
        );
    }
}

/// A vehicle: its model, wheels, drive, lumped links, differential and what was substituted.
fn write_vehicle(s: &mut String, v: &super::VehicleSpec) {
    let m = &v.model;
    let wheels: Vec<String> = v
        .wheels
        .iter()
        .map(|w| {
            format!("{} (R = {} m, {})", m.links[w.link].name, w.radius, if w.side > 0.0 { "left" } else { "right" })
        })
        .collect();
    let _ = writeln!(
        s,
        "  vehicle \"{}\": {} ({} links, {} joints, {:.3} kg), wheels {}; {}; {}",
        v.name,
        m.path.display(),
        m.links.len(),
        m.joints.len(),
        m.mass(),
        if wheels.is_empty() { "none".to_string() } else { wheels.join(", ") },
        if v.drive.is_empty() {
            "not driven".to_string()
        } else {
            format!("{} wheel motors (≤ {} N m), {} steering joints", v.drive.len(), v.max_torque, v.steering.len())
        },
        if v.place_on_soil { "lowered onto the soil" } else { "at the given height" }
    );
    // Links lumped by fixed joints, under the link that carries them.
    for (li, l) in m.links.iter().enumerate() {
        let lumped: Vec<&str> = m.frames.iter().filter(|f| f.link == li).map(|f| f.name.as_str()).collect();
        if !lumped.is_empty() {
            let _ = writeln!(
                s,
                "    {} carries the links fixed to it: {} ({:.3} kg in all)",
                l.name,
                lumped.join(", "),
                l.mass
            );
        }
    }
    if let Some(d) = &v.differential {
        let _ = writeln!(
            s,
            "    differential: `{}` and `{}` turn by equal and opposite angles about `{}`",
            m.joints[d.left].name, m.joints[d.right].name, m.links[m.joints[d.left].parent].name
        );
    }
    for sub in &m.substitutions {
        let _ = writeln!(s, "    substitution {sub}");
    }
    for u in &m.unsupported {
        let _ = writeln!(s, "  warning: vehicle \"{}\": {u}", v.name);
    }
}

/// The rig and what it drives.
fn write_rig(s: &mut String, scene: &Scene, r: &super::RigSpec) {
    let line = match r {
        super::RigSpec::Plate { body, control, depth, sizes } => format!(
            "plate sinkage on \"{}\", {}, to {depth} m{}",
            scene.bodies[*body].desc.name,
            match control {
                super::PlateControl::Speed(v) => format!("pushed at {v} m/s"),
                super::PlateControl::Load(f) => format!("loaded with {f} N"),
            },
            if sizes.is_empty() { String::new() } else { format!(", plate sizes {sizes:?} m") }
        ),
        super::RigSpec::Cone { body, speed, depth } => format!(
            "cone penetrometer \"{}\" pushed at {speed} m/s to a base depth of {depth} m",
            scene.bodies[*body].desc.name
        ),
        super::RigSpec::Wheel { body, load, angular_velocity, drive, .. } => format!(
            "single wheel \"{}\", load {load} N, ω = {angular_velocity} rad/s, {}",
            scene.bodies[*body].desc.name,
            match drive {
                super::WheelDrive::Slips(s) => format!("slips {s:?} ({} runs of {} s)", s.len(), scene.end_time),
                super::WheelDrive::Tow(f) => format!("towed with {f} N"),
                super::WheelDrive::Slopes(s) => {
                    format!("up slopes {s:?}° ({} runs of {} s, gravity tilted about y)", s.len(), scene.end_time)
                }
            }
        ),
    };
    let _ = writeln!(s, "  rig: {line}; the rig body starts in contact with the soil");
}

/// The coupling interval and the recording.
fn write_recording(s: &mut String, scene: &Scene) {
    if !scene.bodies.is_empty() {
        let _ =
            writeln!(s, "  coupling: soil and bodies exchange state and wrenches every {} s", scene.exchange_interval);
    }
    let o = &scene.output;
    if o.mcap {
        let pts = if !o.particles {
            "no particles".to_string()
        } else {
            let roi = o.roi.map_or(String::new(), |(lo, hi)| format!(" inside {lo:?}..{hi:?}"));
            format!("every {} particle(s){roi}", o.decimate)
        };
        let frames = (scene.end_time / o.every + 1e-9).floor() + 1.0;
        let _ =
            writeln!(s, "  recording: recording.mcap, a frame every {} s, {frames} frames per run ({pts})", o.every);
    } else {
        let _ = writeln!(s, "  recording: off (output.mcap = false)");
    }
}

/// The problem's size: particles, markers, memory, the step and the step count.
fn write_size(s: &mut String, scene: &Scene, total: f64, walls: f64, min_dt: f64) {
    let sv = &scene.solver;
    let dt_est = match sv.time_step {
        TimeStep::Fixed(dt) => dt,
        TimeStep::Adaptive { cfl, max } => (cfl * min_dt).min(max),
    };
    let steps = (scene.end_time / dt_est).ceil();
    // Per particle: SoA state (position, velocity, density, stress, pc, v, material) twice for
    // the RK2 stage, rates, the cell sort, and a neighbour list of about 60 entries (4 B each).
    let bytes_per = if scene.precision.name() == "f32" { 4.0 } else { 8.0 };
    let mem = (total + walls) * (bytes_per * 2.0 * 22.0 + 60.0 * 4.0 + 16.0) / (1024.0 * 1024.0);
    let _ = writeln!(
        s,
        "  size: about {:.0} soil particles + {:.0} wall markers, about {:.0} MiB; dt ≈ {:.2e} s, about {:.0} steps",
        total, walls, mem, dt_est, steps
    );
}

/// The physics switched on, and the water's coupling when there is water.
fn write_effects(s: &mut String, scene: &Scene) {
    let sv = &scene.solver;
    let mut models: Vec<&str> = scene.materials.iter().filter_map(|m| m.params.model).map(|k| k.name()).collect();
    models.sort_unstable();
    models.dedup();
    let shifting = match sv.shifting {
        Shifting::None => "none",
        Shifting::Xsph => "xsph",
        Shifting::Ppst => "ppst",
        Shifting::PpstXsph => "ppst+xsph",
    };
    let hardening = models.contains(&"mcc");
    let _ = writeln!(
        s,
        "  effects: rheology {{{}}}, hardening {}, free surface {}, shifting {shifting}, artificial viscosity {}, FSI bodies {}",
        models.join(", "),
        if hardening { "on" } else { "off" },
        match sv.free_surface_threshold {
            Some(t) => format!(
                "on (threshold {t}, surface stress {})",
                match sv.free_surface_stress {
                    regolith_fsi::config::FreeSurfaceStress::Keep => "kept",
                    regolith_fsi::config::FreeSurfaceStress::Zero => "zeroed",
                }
            ),
            None => "off".into(),
        },
        if sv.artificial_viscosity > 0.0 { "on" } else { "off" },
        scene.bodies.iter().filter(|b| b.fsi).count()
    );
    if models.contains(&"water") {
        let _ = writeln!(
            s,
            "  water: pore pressure and drag coupling on, drag {}",
            match sv.drag {
                regolith_fsi::config::Drag::Svf => "svf (smooth volume fractions)",
                regolith_fsi::config::Drag::Particle => "particle (per-particle, bang-bang)",
            }
        );
    }
}

fn shape_name(s: &regolith_rigid::ShapeDesc) -> String {
    use regolith_rigid::ShapeDesc as S;
    match s {
        S::Box { size } => format!("box {size:?} m"),
        S::Sphere { radius } => format!("sphere r = {radius} m"),
        S::Cylinder { radius, length, axis } => format!("cylinder r = {radius} m, length {length} m along {axis:?}"),
        S::Cone { radius, height } => {
            format!("cone r = {radius} m, h = {height} m ({:.1}° apex)", 2.0 * (radius / height).atan().to_degrees())
        }
        S::Mesh { vertices, indices } => format!("mesh ({} vertices, {} triangles)", vertices.len(), indices.len()),
        S::Wheel { radius, width, grousers } => format!(
            "wheel r = {radius} m, width {width} m{}",
            grousers.map(|g| format!(", {} grousers {} × {} m", g.count, g.height, g.thickness)).unwrap_or_default()
        ),
        S::Compound(p) => format!("compound of {} shapes", p.len()),
    }
}
