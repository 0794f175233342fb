//! `[simulation]` and `[sph]`: time, time step, integrator, gravity, backend, precision and
//! the SPH settings, resolved into a [`SolverConfig`]. What a scene leaves out takes
//! `SolverConfig::default()`.

use super::*;

/// The resolved `[simulation]` and `[sph]` sections.
pub(super) struct Settings {
    pub end_time: f64,
    pub backend: Backend,
    pub precision: Precision,
    pub precision_set: bool,
    pub solver: SolverConfig,
    pub exchange_interval: f64,
    pub active: Option<ActiveSpec>,
    pub body_markers: BodyMarkers,
}

pub(super) fn resolve_settings(
    sim: Option<&file::SimulationFile>,
    sph: Option<&file::SphFile>,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Settings, InputError> {
    let sim = sim.ok_or_else(|| e("simulation", "section [simulation] is required (at least end_time)".into()))?;
    let end_time =
        sim.end_time.ok_or_else(|| e("simulation.end_time", "is required: simulated time in s, > 0".into()))?;
    if !(end_time.is_finite() && end_time > 0.0) {
        return Err(e("simulation.end_time", format!("must be > 0 s (got {end_time})")));
    }
    // Defaults are the library's: what a scene does not set, SolverConfig::default() decides.
    let d = SolverConfig::default();
    let time_step = resolve_time_step(sim, end_time, &d, e)?;
    let integrator = resolve_integrator(sim, &d, e)?;
    let gravity = sim.gravity.unwrap_or(d.gravity);
    if gravity.iter().any(|g| !g.is_finite()) {
        return Err(e("simulation.gravity", format!("must be three finite numbers in m/s² (got {gravity:?})")));
    }
    if gravity[2] > 0.0 {
        return Err(e(
            "simulation.gravity",
            format!("must not point up (z ≤ 0; soil is layered along −z, tilt g for a slope) (got {gravity:?})"),
        ));
    }
    let (backend, precision) = resolve_backend(sim, e)?;
    let precision_set = sim.precision.is_some();

    let sph = sph.ok_or_else(|| e("sph", "section [sph] is required (at least spacing)".into()))?;
    let solver = SolverConfig { integrator, time_step, gravity, ..resolve_sph(sph, backend, &d, e)? };
    let exchange_interval = sim.exchange_interval.unwrap_or(1e-3);
    if !(exchange_interval.is_finite() && exchange_interval > 0.0 && exchange_interval <= end_time) {
        return Err(e(
            "simulation.exchange_interval",
            format!("must be in (0, end_time = {end_time}] s (got {exchange_interval})"),
        ));
    }
    let active = resolve_active(sph.active.as_ref(), &solver, e)?;
    let body_markers = match sph.body_markers {
        None | Some(file::BodyMarkersName::Surface) => BodyMarkers::Surface,
        Some(file::BodyMarkersName::Inset) => BodyMarkers::Inset,
    };
    Ok(Settings { end_time, backend, precision, precision_set, solver, exchange_interval, active, body_markers })
}

/// `simulation.dt`, `cfl` and `max_dt`: adaptive (the default, or `dt = "auto"`) or fixed.
fn resolve_time_step(
    sim: &file::SimulationFile,
    end_time: f64,
    d: &SolverConfig,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<TimeStep, InputError> {
    let TimeStep::Adaptive { cfl: default_cfl, max: default_max_dt } = d.time_step else {
        unreachable!("the default time step is adaptive")
    };
    let cfl = sim.cfl.unwrap_or(default_cfl);
    if !(cfl.is_finite() && cfl > 0.0 && cfl <= 1.0) {
        return Err(e("simulation.cfl", format!("must be in (0, 1] (got {cfl})")));
    }
    let max_dt = sim.max_dt.unwrap_or(default_max_dt);
    if !(max_dt.is_finite() && max_dt > 0.0) {
        return Err(e("simulation.max_dt", format!("must be > 0 s (got {max_dt})")));
    }
    Ok(match &sim.dt {
        None => TimeStep::Adaptive { cfl, max: max_dt },
        Some(toml::Value::String(s)) if s == "auto" => TimeStep::Adaptive { cfl, max: max_dt },
        Some(v) => {
            let dt = v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
            match dt {
                Some(dt) if dt.is_finite() && dt > 0.0 && dt <= end_time => {
                    if sim.cfl.is_some() || sim.max_dt.is_some() {
                        return Err(e(
                            "simulation.cfl",
                            "and max_dt apply to dt = \"auto\" only; remove them or set dt = \"auto\"".into(),
                        ));
                    }
                    TimeStep::Fixed(dt)
                }
                _ => {
                    return Err(e(
                        "simulation.dt",
                        format!("must be \"auto\" or a step in s in (0, end_time = {end_time}] (got {v})"),
                    ));
                }
            }
        }
    })
}

/// `simulation.integrator`: RK2; forward Euler is refused.
fn resolve_integrator(
    sim: &file::SimulationFile,
    d: &SolverConfig,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Integrator, InputError> {
    Ok(match sim.integrator {
        None => d.integrator,
        Some(IntegratorName::Rk2) => Integrator::Rk2,
        Some(IntegratorName::Euler) => {
            // The stress rate from the start-of-step velocity gradient is forward Euler on the
            // soil's elastic wave equation: a bed at rest blows apart (the accuracy study's
            // geostatic case read −99.5 %). Refused until a second velocity-gradient pass
            // after the velocity update makes it symplectic (NOTES.md).
            return Err(e(
                "simulation.integrator",
                "\"euler\" is unstable for soil at rest (a geostatic bed blows apart); use \"rk2\"".into(),
            ));
        }
    })
}

/// `simulation.backend` and `precision` (f64 on the CPU unless set; wgpu runs in f32 only).
fn resolve_backend(
    sim: &file::SimulationFile,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<(Backend, Precision), InputError> {
    let backend = match sim.backend.unwrap_or(BackendName::Cpu) {
        BackendName::Auto => Backend::Auto,
        BackendName::Cpu => Backend::Cpu,
        BackendName::Wgpu => Backend::Wgpu,
    };
    if backend == Backend::Wgpu && matches!(sim.precision, Some(PrecisionName::F64)) {
        return Err(e("simulation.precision", "the wgpu backend runs in f32: use \"f32\" or backend \"cpu\"".into()));
    }
    let precision =
        match sim.precision.unwrap_or(if backend == Backend::Wgpu { PrecisionName::F32 } else { PrecisionName::F64 }) {
            PrecisionName::F32 => Precision::F32,
            PrecisionName::F64 => Precision::F64,
        };
    Ok((backend, precision))
}

/// `[sph]`: the solver's SPH settings (the time step, integrator and gravity are the caller's).
fn resolve_sph(
    sph: &file::SphFile,
    backend: Backend,
    d: &SolverConfig,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<SolverConfig, InputError> {
    let spacing =
        sph.spacing.ok_or_else(|| e("sph.spacing", "is required: initial particle spacing in m, > 0".into()))?;
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(e("sph.spacing", format!("must be > 0 m (got {spacing})")));
    }
    let h_factor = sph.h_factor.unwrap_or(d.h_factor);
    if !(h_factor.is_finite() && (1.0..=2.0).contains(&h_factor)) {
        return Err(e("sph.h_factor", format!("must be in [1.0, 2.0] (h/d0; got {h_factor})")));
    }
    let alpha = sph.artificial_viscosity.unwrap_or(d.artificial_viscosity);
    if !(alpha.is_finite() && (0.0..=5.0).contains(&alpha)) {
        return Err(e("sph.artificial_viscosity", format!("must be in [0, 5] (got {alpha})")));
    }
    let (shifting, xsph_epsilon, shifting_coefficient) = resolve_shifting(sph, d, e)?;
    let (free_surface_threshold, free_surface_stress) = resolve_free_surface(sph, shifting, d, e)?;
    let bce_layers = sph.bce_layers.unwrap_or(d.bce_layers as i64);
    if !(1..=8).contains(&bce_layers) {
        return Err(e("sph.bce_layers", format!("must be an integer in 1..=8 (got {bce_layers})")));
    }
    let kernel = match sph.kernel {
        None => d.kernel,
        Some(KernelName::Wendland) => KernelKind::Wendland,
        Some(KernelName::Cubic) => KernelKind::Cubic,
    };
    // The wgpu backend rebuilds its lists every step: its default skin is 0.
    let default_skin = if backend == Backend::Wgpu { 0.0 } else { d.neighbor_skin };
    let neighbor_skin = sph.neighbor_skin.unwrap_or(default_skin);
    let max_skin = regolith_fsi::config::MAX_NEIGHBOR_SKIN;
    if !(neighbor_skin.is_finite() && (0.0..=max_skin).contains(&neighbor_skin)) {
        return Err(e(
            "sph.neighbor_skin",
            format!(
                "must be in [0, {max_skin}] (a multiple of h; 0 rebuilds the lists every step; got {neighbor_skin})"
            ),
        ));
    }
    if backend == Backend::Wgpu && sph.neighbor_skin.is_some_and(|s| s > 0.0) {
        return Err(e(
            "sph.neighbor_skin",
            "the wgpu backend rebuilds its neighbour lists every step: use 0 or backend \"cpu\"".into(),
        ));
    }
    Ok(SolverConfig {
        spacing,
        h_factor,
        kernel,
        integrator: d.integrator,
        time_step: d.time_step,
        artificial_viscosity: alpha,
        shifting,
        xsph_epsilon,
        shifting_coefficient,
        free_surface_threshold,
        free_surface_stress,
        gravity: d.gravity,
        bce_layers: bce_layers as usize,
        neighbor_skin,
        drag: match sph.drag {
            None | Some(DragName::Svf) => Drag::Svf,
            Some(DragName::Particle) => Drag::Particle,
        },
    })
}

/// `sph.shifting` with `xsph_epsilon` and `shifting_coefficient`, each only with its scheme.
fn resolve_shifting(
    sph: &file::SphFile,
    d: &SolverConfig,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<(Shifting, f64, f64), InputError> {
    let shifting = match sph.shifting {
        None => d.shifting,
        Some(ShiftingName::None) => Shifting::None,
        Some(ShiftingName::Xsph) => Shifting::Xsph,
        Some(ShiftingName::Ppst) => Shifting::Ppst,
        Some(ShiftingName::PpstXsph) => Shifting::PpstXsph,
    };
    let xsph_epsilon = sph.xsph_epsilon.unwrap_or(d.xsph_epsilon);
    if !(xsph_epsilon.is_finite() && (0.0..=1.0).contains(&xsph_epsilon)) {
        return Err(e("sph.xsph_epsilon", format!("must be in [0, 1] (got {xsph_epsilon})")));
    }
    if sph.xsph_epsilon.is_some() && !shifting.xsph() {
        return Err(e("sph.xsph_epsilon", "applies only when shifting includes \"xsph\"".into()));
    }
    let shifting_coefficient = sph.shifting_coefficient.unwrap_or(d.shifting_coefficient);
    if !(shifting_coefficient.is_finite() && (0.0..=1.0).contains(&shifting_coefficient)) {
        return Err(e("sph.shifting_coefficient", format!("must be in [0, 1] (got {shifting_coefficient})")));
    }
    if sph.shifting_coefficient.is_some() && !shifting.ppst() {
        return Err(e("sph.shifting_coefficient", "applies only when shifting includes \"ppst\"".into()));
    }
    Ok((shifting, xsph_epsilon, shifting_coefficient))
}

/// `sph.free_surface`, `free_surface_threshold` and `free_surface_stress`; a flag that would
/// change nothing is refused.
fn resolve_free_surface(
    sph: &file::SphFile,
    shifting: Shifting,
    d: &SolverConfig,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<(Option<f64>, FreeSurfaceStress), InputError> {
    let free_surface = sph.free_surface.unwrap_or(d.free_surface_threshold.is_some());
    let threshold = sph
        .free_surface_threshold
        .or(d.free_surface_threshold)
        .unwrap_or(regolith_fsi::config::DEFAULT_FREE_SURFACE_THRESHOLD);
    if !(threshold.is_finite() && threshold > 0.0 && threshold < 1.0) {
        return Err(e(
            "sph.free_surface_threshold",
            format!(
                "must be in (0, 1): the smallest eigenvalue of Σ V (x_b − x_a) ⊗ ∇W is 1 inside the soil (got {threshold})"
            ),
        ));
    }
    if !free_surface && sph.free_surface_threshold.is_some() {
        return Err(e("sph.free_surface_threshold", "is set but free_surface = false".into()));
    }
    if !free_surface && sph.free_surface_stress.is_some() {
        return Err(e("sph.free_surface_stress", "is set but free_surface = false".into()));
    }
    let free_surface_stress = match sph.free_surface_stress {
        None => d.free_surface_stress,
        Some(FreeSurfaceStressName::Keep) => FreeSurfaceStress::Keep,
        Some(FreeSurfaceStressName::Zero) => FreeSurfaceStress::Zero,
    };
    // The free-surface flags act through two things only: zeroing the stress of flagged
    // particles and keeping PPST shifting off them. With neither, setting them changes nothing
    // (a run with `free_surface = false` was bit-identical to one without it, issue 45): say so.
    if free_surface_stress == FreeSurfaceStress::Keep && !shifting.ppst() {
        for (key, given) in [
            ("sph.free_surface", sph.free_surface.is_some()),
            ("sph.free_surface_threshold", sph.free_surface_threshold.is_some()),
        ] {
            if given {
                return Err(e(
                    key,
                    "changes nothing here: the free-surface flags act only with free_surface_stress = \"zero\" or PPST shifting (shifting = \"ppst\" or \"ppst+xsph\")".into(),
                ));
            }
        }
    }
    Ok((free_surface.then_some(threshold), free_surface_stress))
}

/// `[sph.active]`. Every key but `enabled` needs `enabled = true`, so that a setting is never
/// silently ignored.
fn resolve_active(
    a: Option<&file::ActiveFile>,
    solver: &SolverConfig,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<Option<ActiveSpec>, InputError> {
    let Some(a) = a else { return Ok(None) };
    if !a.enabled.unwrap_or(false) {
        let set = [
            ("margin", a.margin.is_some()),
            ("depth_factor", a.depth_factor.is_some()),
            ("travel", a.travel.is_some()),
            ("sleep_speed", a.sleep_speed.is_some()),
            ("free_flow_time", a.free_flow_time.is_some()),
        ];
        if let Some((k, _)) = set.iter().find(|(_, s)| *s) {
            return Err(e(&format!("sph.active.{k}"), "is set but enabled is not true".into()));
        }
        return Ok(None);
    }
    let h = solver.h();
    let settings = regolith_fsi::active::ActiveSettings {
        travel: a.travel.unwrap_or(2.0 * h),
        sleep_speed: a.sleep_speed.unwrap_or(DEFAULT_SLEEP_SPEED),
        free_flow_time: a.free_flow_time.unwrap_or(0.0),
    };
    if let Err((k, msg)) = settings.validate() {
        return Err(e(&format!("sph.active.{k}"), msg));
    }
    if let Some(m) = a.margin
        && !(m.is_finite() && m >= 0.0)
    {
        return Err(e("sph.active.margin", format!("must be >= 0 m (got {m})")));
    }
    let depth_factor = a.depth_factor.unwrap_or(DEFAULT_ACTIVE_DEPTH_FACTOR);
    if !(depth_factor.is_finite() && (0.0..=10.0).contains(&depth_factor)) {
        return Err(e("sph.active.depth_factor", format!("must be in [0, 10] (got {depth_factor})")));
    }
    if a.margin.is_some() && a.depth_factor.is_some() {
        return Err(e(
            "sph.active.depth_factor",
            "and margin are exclusive: margin replaces 2h + depth_factor x size".into(),
        ));
    }
    Ok(Some(ActiveSpec { settings, margin: a.margin, depth_factor }))
}

/// Largest fixed step, as a fraction of `h / c` (c the stiffest material's P-wave speed): half
/// the smoothing length per step for the fastest elastic wave. The adaptive step stays at or
/// below CFL 0.3 of it; explicit SPH with RK2 is not stable much above this (the stability
/// suite's `fixed_step_above_limit` case runs a step past it to show the blow-up is reported).
pub const FIXED_STEP_CFL_LIMIT: f64 = 0.5;

/// Refuses a fixed `simulation.dt` above [`FIXED_STEP_CFL_LIMIT`] `· h / c` unless the scene
/// says `allow_unstable_dt = true` (for tests of failure handling).
pub(super) fn check_fixed_step(
    solver: &SolverConfig,
    materials: &[SceneMaterial],
    allow: bool,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<(), InputError> {
    let TimeStep::Fixed(dt) = solver.time_step else {
        if allow {
            return Err(e("simulation.allow_unstable_dt", "applies to a fixed dt only; remove it".into()));
        }
        return Ok(());
    };
    let mut stiffest: Option<(&str, f64)> = None;
    for (i, m) in materials.iter().enumerate() {
        let built = m.params.build::<f64>().map_err(|err| e(&format!("materials[{i}]"), err.to_string()))?;
        let c = built.wave_speed();
        if stiffest.is_none_or(|(_, best)| c > best) {
            stiffest = Some((m.name.as_str(), c));
        }
    }
    let Some((name, c)) = stiffest else {
        return Ok(());
    };
    let limit = FIXED_STEP_CFL_LIMIT * solver.h() / c;
    if dt > limit && !allow {
        return Err(e(
            "simulation.dt",
            format!(
                "{dt:e} s is above the stable limit {FIXED_STEP_CFL_LIMIT} h / c = {limit:.3e} s (h = {:.4} m, c = {c:.1} m/s of material \"{name}\"); use dt = \"auto\", a step ≤ {limit:.3e} s, or allow_unstable_dt = true to run it anyway",
                solver.h()
            ),
        ));
    }
    if allow && dt <= limit {
        return Err(e(
            "simulation.allow_unstable_dt",
            format!("is set but dt = {dt:e} s is within the stable limit {limit:.3e} s; remove it"),
        ));
    }
    Ok(())
}
