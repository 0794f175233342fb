//! Shader assembly: the effects a scene resolves to become WGSL constants and the set of
//! modules compiled (a scene without MCC never compiles the MCC return mapping), and every
//! pipeline is built under an error scope so a bad shader is an error, not a panic.

use std::fmt::Write as _;

use crate::GpuError;
use crate::error_code::DeviceError;
use regolith_fsi::config::RAREFIED_DENSITY;
use regolith_fsi::cpu::DELTA_SPH;
use regolith_fsi::rheology::MIN_POROSITY;

/// What the pipeline is specialised for: fixed for a solver's lifetime.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Effects {
    /// Cubic spline instead of Wendland C2.
    pub cubic: bool,
    /// Artificial viscosity.
    pub viscosity: bool,
    /// XSPH.
    pub xsph: bool,
    /// Concentration-gradient shifting.
    pub ppst: bool,
    /// Zero stress on the free surface.
    pub zero_surface: bool,
    /// Midpoint (RK2) integration; explicit Euler otherwise.
    pub rk2: bool,
    /// Adaptive time step.
    pub adaptive: bool,
    /// Some material is Drucker–Prager.
    pub dp: bool,
    /// Some material is Modified Cam Clay.
    pub mcc: bool,
    /// The scene has water (the phase-coupling kernels are built).
    pub wet: bool,
}

impl Effects {
    /// The effects as a list of names, for `regolith check` and the variant set.
    pub fn names(&self) -> Vec<&'static str> {
        let mut v = vec![if self.cubic { "kernel=cubic" } else { "kernel=wendland" }];
        v.push(if self.rk2 { "integrator=rk2" } else { "integrator=euler" });
        v.push(if self.adaptive { "dt=adaptive" } else { "dt=fixed" });
        for (on, name) in [
            (self.viscosity, "artificial-viscosity"),
            (self.xsph, "xsph"),
            (self.ppst, "shifting"),
            (self.zero_surface, "zero-surface-stress"),
            (self.dp, "drucker-prager"),
            (self.mcc, "mcc"),
            (self.wet, "water"),
        ] {
            if on {
                v.push(name);
            }
        }
        v
    }
}

/// Counts one workgroup of `scan.wgsl`'s `scan_blocks` scans (256 threads, 8 counts each);
/// written into every kernel's source as `SCAN_BLOCK`.
pub(crate) const SCAN_BLOCK: u32 = 2048;

/// Blocks of [`SCAN_BLOCK`] counts that `len` counts fill (at least one): the words a scan's
/// buffer of block totals needs.
pub(crate) fn scan_blocks(len: u32) -> u32 {
    len.div_ceil(SCAN_BLOCK).max(1)
}

/// Per-pipeline switches on top of the effects.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Variant {
    /// First stage of a step: free-surface measure, flags and pair count.
    pub fs: bool,
    /// Advance to the midpoint.
    pub stage: bool,
    /// Words per point record (sorting).
    pub stride: u32,
    /// Bins to scan.
    pub len: u32,
}

const COMMON: &str = include_str!("kernels/common.wgsl");
const MATERIALS: &str = include_str!("kernels/materials.wgsl");
const DP: &str = include_str!("kernels/dp.wgsl");
const MCC: &str = include_str!("kernels/mcc.wgsl");

/// The full source of a kernel: constants, the common module, the rheology modules the
/// effects call for (`with_rheology`), and the kernel's own file.
pub(crate) fn source(e: &Effects, v: &Variant, kernel: &str, with_rheology: bool) -> String {
    let mut s = String::with_capacity(COMMON.len() + kernel.len() + 4096);
    let b = |x: bool| if x { "true" } else { "false" };
    let _ = writeln!(s, "const KERNEL_CUBIC: bool = {};", b(e.cubic));
    let _ = writeln!(s, "const VISC: bool = {};", b(e.viscosity));
    let _ = writeln!(s, "const XSPH: bool = {};", b(e.xsph));
    let _ = writeln!(s, "const PPST: bool = {};", b(e.ppst));
    let _ = writeln!(s, "const ZERO_SURFACE: bool = {};", b(e.zero_surface));
    let _ = writeln!(s, "const RK2: bool = {};", b(e.rk2));
    let _ = writeln!(s, "const ADAPTIVE: bool = {};", b(e.adaptive));
    let _ = writeln!(s, "const HAS_MCC: bool = {};", b(e.mcc));
    let _ = writeln!(s, "const HAS_DP: bool = {};", b(e.dp));
    let _ = writeln!(s, "const WET: bool = {};", b(e.wet));
    let _ = writeln!(s, "const RAREFIED_DENSITY: f32 = {:?};", RAREFIED_DENSITY as f32);
    let _ = writeln!(s, "const MIN_POROSITY: f32 = {:?};", MIN_POROSITY as f32);
    let _ = writeln!(s, "const DELTA_SPH: f32 = {:?};", DELTA_SPH as f32);
    let _ = writeln!(s, "const FS: bool = {};", b(v.fs));
    let _ = writeln!(s, "const STAGE: bool = {};", b(v.stage));
    let _ = writeln!(s, "const STRIDE: u32 = {}u;", v.stride.max(1));
    let _ = writeln!(s, "const LEN: u32 = {}u;", v.len.max(1));
    let _ = writeln!(s, "const SCAN_BLOCK: u32 = {SCAN_BLOCK}u;");
    let _ = writeln!(s, "const BLOCKS: u32 = {}u;", scan_blocks(v.len.max(1)));
    s.push_str(&DeviceError::wgsl_constants());
    s.push_str(COMMON);
    s.push_str(MATERIALS);
    if with_rheology {
        if e.dp {
            s.push_str(DP);
        }
        if e.mcc {
            s.push_str(MCC);
        }
        // The dispatch calls only the models present.
        s.push_str("fn material_correct(mat: Material, trial: Sym, pc: ptr<function, f32>, sv: f32, moduli: vec2<f32>, d: Sym, err: ptr<function, u32>) -> Sym {\n");
        if e.mcc {
            s.push_str("    if (mat.model == MODEL_MCC) { return mcc_correct(mat, trial, pc, sv, moduli, err); }\n");
        }
        if e.dp {
            s.push_str("    if (mat.model == MODEL_DP) { return dp_correct(mat, trial, d, err); }\n");
        }
        if e.wet {
            // A liquid's stress is set from its equation of state each stage.
            s.push_str("    if (mat.model == MODEL_WATER) { return trial; }\n");
        }
        s.push_str("    if (!sym_finite(trial)) { *err = ERR_ELASTIC_NONFINITE; }\n    return trial;\n}\n");
    }
    s.push_str(kernel);
    s
}

/// How a binding is used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Bind {
    Uniform,
    Read,
    ReadWrite,
}

/// A bind group layout with the given (binding, use) entries, all compute-visible.
pub(crate) fn layout(device: &wgpu::Device, label: &str, entries: &[(u32, Bind)]) -> wgpu::BindGroupLayout {
    let e: Vec<wgpu::BindGroupLayoutEntry> = entries
        .iter()
        .map(|&(binding, b)| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: match b {
                    Bind::Uniform => wgpu::BufferBindingType::Uniform,
                    Bind::Read => wgpu::BufferBindingType::Storage { read_only: true },
                    Bind::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &e })
}

/// A bind group over whole buffers, bindings in the layout's order.
pub(crate) fn bind(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    entries: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let e: Vec<wgpu::BindGroupEntry> = entries
        .iter()
        .map(|&(binding, buf)| wgpu::BindGroupEntry { binding, resource: buf.as_entire_binding() })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &e })
}

/// Compiles `source` (its `for_each_in_reach` statements expanded, see
/// [`crate::neighbour_loop`]) and builds one pipeline per entry point, all over `layout`; a
/// malformed statement, a WGSL or a validation error comes back as [`GpuError::Shader`].
pub(crate) fn pipelines(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layout: &wgpu::BindGroupLayout,
    entries: &[&str],
) -> Result<Vec<wgpu::ComputePipeline>, GpuError> {
    let source = crate::neighbour_loop::expand(source)
        .map_err(|e| GpuError::Shader { kernel: label.to_owned(), message: e.to_string() })?;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let out = entries
        .iter()
        .map(|entry| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&format!("{label}::{entry}")),
                layout: Some(&pl),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        })
        .collect();
    match pollster::block_on(scope.pop()) {
        Some(e) => Err(GpuError::Shader { kernel: label.to_string(), message: e.to_string() }),
        None => Ok(out),
    }
}

/// Storage a kernel reads or writes and the host copies to or from.
pub(crate) const USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_DST).union(wgpu::BufferUsages::COPY_SRC);

/// A buffer of at least `bytes` (16 at least, a whole number of words).
pub(crate) fn buffer(device: &wgpu::Device, label: &str, bytes: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16).next_multiple_of(4),
        usage,
        mapped_at_creation: false,
    })
}

/// Workgroups of 64 covering `n` items.
pub(crate) fn groups(n: usize) -> u32 {
    (n.div_ceil(64)).max(1) as u32
}
