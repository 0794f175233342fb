//! The facade's side of the wgpu backend: it opens the device (the library crates only take
//! one), chooses between the backends, and builds the soil solver a scene asks for. Without the
//! `wgpu` feature only the CPU backend exists, and asking for wgpu is a one-line error.

#[cfg(feature = "wgpu")]
use std::any::Any;
#[cfg(feature = "wgpu")]
use std::sync::OnceLock;

use regolith_coupling::cpu_solver;
use regolith_fsi::config::SolverConfig;
use regolith_fsi::rheology::Material;
use regolith_fsi::{MarkerInit, ParticleInit, Real, SolverError, SphSolver};
#[cfg(feature = "wgpu")]
use regolith_wgpu::GpuSph;

/// What a build without the `wgpu` feature says when the wgpu backend is asked for.
pub const NO_WGPU: &str = "this build of regolith has no `wgpu` feature: use the cpu backend";

#[cfg(feature = "wgpu")]
/// An opened wgpu device.
#[derive(Clone, Debug)]
pub struct GpuDevice {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name and driver, for reports.
    pub name: String,
    /// True for a real (discrete, integrated or virtual) GPU, false for a software one such as
    /// Mesa's lavapipe.
    pub hardware: bool,
}

#[cfg(feature = "wgpu")]
fn open() -> Result<GpuDevice, String> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::PRIMARY,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
    // A real GPU first; a software adapter (lavapipe) otherwise.
    let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let adapter = adapters
        .into_iter()
        .min_by_key(rank)
        .ok_or_else(|| "no wgpu adapter (no Vulkan, Metal or DX12 driver found; on Linux without a GPU install mesa-vulkan-drivers for lavapipe)".to_string())?;
    let info = adapter.get_info();
    let hardware = rank(&adapter) <= 2;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("regolith"),
        required_features: wgpu::Features::empty(),
        // The adapter's own limits: lavapipe's 128 MiB storage bindings, a real GPU's more.
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .map_err(|e| format!("adapter {}: {e}", info.name))?;
    Ok(GpuDevice { device, queue, name: format!("{} ({:?}, {})", info.name, info.backend, info.driver), hardware })
}

#[cfg(feature = "wgpu")]
/// The process's wgpu device, opened on first use.
pub fn device() -> Result<&'static GpuDevice, String> {
    static DEVICE: OnceLock<Result<GpuDevice, String>> = OnceLock::new();
    DEVICE.get_or_init(open).as_ref().map_err(Clone::clone)
}

#[cfg(feature = "wgpu")]
/// Whether `--backend auto` picks wgpu: only for a real GPU (a software adapter is slower
/// than the CPU backend).
pub fn real_gpu() -> Option<&'static GpuDevice> {
    device().ok().filter(|d| d.hardware)
}

/// Builds the soil solver: the CPU backend, or with `wgpu` the device one (f32 only, with
/// buffers for `room` times the particles given: a moving patch lays more than it lifts).
pub fn make_solver<T: Real>(
    wgpu: bool,
    room: f64,
    cfg: SolverConfig,
    materials: Vec<Material<T>>,
    particles: &[ParticleInit],
    markers: &[MarkerInit],
    domain: ([f64; 3], [f64; 3]),
) -> Result<Box<dyn SphSolver<T>>, SolverError> {
    if !wgpu {
        return cpu_solver(cfg, materials, particles, markers, domain);
    }
    #[cfg(not(feature = "wgpu"))]
    {
        let _ = (room, cfg, materials, particles, markers, domain);
        Err(SolverError::Setup(NO_WGPU.into()))
    }
    #[cfg(feature = "wgpu")]
    {
        let f32_only = || SolverError::Setup("the wgpu backend runs in f32; use precision f32".into());
        let mats: Box<dyn Any> = Box::new(materials);
        let mats = mats.downcast::<Vec<Material<f32>>>().map_err(|_| f32_only())?;
        let d = device().map_err(|e| SolverError::Setup(format!("wgpu: {e}")))?;
        let capacity = (particles.len() as f64 * room.max(1.0)).ceil() as usize;
        let s = GpuSph::with_capacity(&d.device, &d.queue, &d.name, cfg, *mats, particles, markers, domain, capacity)
            .map_err(|e| SolverError::Setup(format!("wgpu: {e}")))?;
        let b: Box<dyn SphSolver<f32>> = Box::new(s);
        let any: Box<dyn Any> = Box::new(b);
        any.downcast::<Box<dyn SphSolver<T>>>().map(|b| *b).map_err(|_| f32_only())
    }
}

/// Resolves `auto` to `cpu` or `wgpu` and checks that `wgpu` can run: a real GPU for `auto`
/// (unless f64 was asked for), any adapter (lavapipe included) for `wgpu`. The soil then runs
/// in f32 on wgpu. Returns the line that says what was chosen, or the error for `--backend`.
pub fn resolve_backend(scene: &mut crate::scene::Scene) -> Result<String, String> {
    use crate::scene::{Backend, Precision};
    let f64_asked = scene.precision_set && scene.precision == Precision::F64;
    #[cfg(not(feature = "wgpu"))]
    {
        let _ = f64_asked;
        match scene.backend {
            Backend::Cpu => Ok("backend: cpu".into()),
            Backend::Auto => {
                scene.backend = Backend::Cpu;
                Ok("backend auto: cpu (this build has no wgpu feature)".into())
            }
            Backend::Wgpu => Err(NO_WGPU.into()),
        }
    }
    #[cfg(feature = "wgpu")]
    match scene.backend {
        Backend::Cpu => Ok("backend: cpu".into()),
        Backend::Auto => match real_gpu() {
            Some(d) if !f64_asked => {
                scene.backend = Backend::Wgpu;
                scene.precision = Precision::F32;
                let lists = if scene.solver.neighbor_skin > 0.0 {
                    // The wgpu backend has no Verlet lists; the same pairs come from a rebuild.
                    scene.solver.neighbor_skin = 0.0;
                    "; neighbour lists rebuilt every step, sph.neighbor_skin applies to the cpu backend"
                } else {
                    ""
                };
                Ok(format!("backend auto: wgpu on {} (f32{lists})", d.name))
            }
            Some(_) => {
                scene.backend = Backend::Cpu;
                Ok("backend auto: cpu (f64 asked for; the wgpu backend runs in f32)".into())
            }
            None => {
                scene.backend = Backend::Cpu;
                Ok("backend auto: cpu (no GPU adapter)".into())
            }
        },
        Backend::Wgpu => {
            if f64_asked {
                return Err("wgpu runs in f32: use --precision f32 or --backend cpu".into());
            }
            let d = device().map_err(|e| format!("wgpu: {e}"))?;
            scene.precision = Precision::F32;
            // A scene that asks for a skin on wgpu was refused when read; what is left here is
            // the default, which on wgpu is a rebuild every step.
            scene.solver.neighbor_skin = 0.0;
            Ok(format!("backend: wgpu on {} (f32)", d.name))
        }
    }
}
