//! The device resources of a [`crate::GpuSph`], made once for a capacity: the limits they must
//! fit, the uniform parameters, the compiled kernels, the buffers and the bind groups that tie
//! each kernel's bindings to them (the wet scene's too). `GpuSph::with_capacity` calls these in
//! order; the step only records dispatches over what they return.

use bytemuck::Zeroable;
use regolith_fsi::config::{DETACHED_THRESHOLD, Drag, KernelKind, SolverConfig, TimeStep};
use regolith_fsi::cpu::{GridSpec, WetSetup};
use regolith_fsi::kernel::{CubicSpline, Kernel, WendlandC2};
use regolith_fsi::rheology::{Material, Rheology};

use crate::GpuError;
use crate::kernels::{
    advance::Advance, bodies::Bodies, extrapolate::Extrapolate, forces::Forces, pack::Pack, permute::Permute,
    rates::Rates, scan::Scan, sort::Sort, step_info::StepInfo, wet::Wet,
};
use crate::layout::{self, Body, Info, Marker, MarkerPore, Packed, Params, Particle, Pore, Rate};
use crate::shader::{Effects, USAGE, bind, buffer};

/// How many of each thing the buffers hold.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Counts {
    /// Particles (the capacity: at least the ones given).
    pub cap: usize,
    /// Markers, walls first.
    pub nm: usize,
    /// Grid cells.
    pub n_cells: usize,
    /// Bodies (owners 1..=n_bodies).
    pub n_bodies: usize,
    /// Materials.
    pub n_materials: usize,
}

/// Bytes of `count` records of `each` bytes, at least one record (a binding may not be empty).
pub(crate) fn bytes(count: usize, each: usize) -> u64 {
    (count.max(1) * each) as u64
}

/// The buffers and dispatches fit the device: each storage binding, the workgroup rows of the
/// widest dispatch and, for a wet scene, the storage buffers of its widest kernel.
pub(crate) fn check_limits(limits: &wgpu::Limits, c: &Counts, wet: bool) -> Result<(), GpuError> {
    let Counts { cap, nm, n_cells, .. } = *c;
    let check = |what: &str, needed: u64| -> Result<(), GpuError> {
        let allowed = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if needed > allowed {
            return Err(GpuError::Limit {
                what: what.into(),
                needed,
                allowed,
                limit: "max_storage_buffer_binding_size",
            });
        }
        Ok(())
    };
    check("the particle buffer", bytes(cap, size_of::<Particle>()))?;
    check("the rate buffer", bytes(cap, size_of::<Rate>()))?;
    check("the cell table", bytes(n_cells + 2, 4))?;
    check("the marker buffer", bytes(nm, size_of::<Packed>()))?;
    // Wide dispatches come in rows of ROW_GROUPS workgroups (`kernels::dispatch`); the
    // flat thread index is a u32.
    let max_groups = u64::from(limits.max_compute_workgroups_per_dimension);
    let rows = u64::from(crate::kernels::ROW_GROUPS);
    let need_groups = (cap.max(nm).max(n_cells + 1) as u64).div_ceil(64);
    let allowed = (rows * max_groups).min(u64::from(u32::MAX) / 256);
    if max_groups < rows || need_groups > allowed {
        return Err(GpuError::Limit {
            what: "one thread per particle, marker or cell".into(),
            needed: need_groups,
            allowed,
            limit: "max_compute_workgroups_per_dimension",
        });
    }
    if wet && limits.max_storage_buffers_per_shader_stage < crate::kernels::wet::MOST_STORAGE_BUFFERS {
        return Err(GpuError::Limit {
            what: "the wet rates kernel".into(),
            needed: u64::from(crate::kernels::wet::MOST_STORAGE_BUFFERS),
            allowed: u64::from(limits.max_storage_buffers_per_shader_stage),
            limit: "max_storage_buffers_per_shader_stage",
        });
    }
    if n_cells as u64 + 2 > u64::from(u32::MAX) {
        return Err(GpuError::Setup(format!("{n_cells} grid cells is too many for u32 indices")));
    }
    Ok(())
}

/// The uniform parameters every kernel reads.
pub(crate) fn params(
    cfg: &SolverConfig,
    materials: &[Material<f32>],
    grid: &GridSpec,
    wet: Option<&WetSetup<f32>>,
    n: usize,
    nm: usize,
) -> Params {
    let h = cfg.h();
    let n_cells = grid.cells();
    let ref_rho = materials.iter().map(|m| m.density as f64).fold(0.0, f64::max);
    let ref_cs = materials.iter().map(|m| m.wave_speed() as f64).fold(0.0, f64::max);
    let alpha = match cfg.kernel {
        KernelKind::Wendland => <WendlandC2 as Kernel<f32>>::alpha(h as f32),
        KernelKind::Cubic => <CubicSpline as Kernel<f32>>::alpha(h as f32),
    };
    let radius = (2.0 * h) as f32;
    let (cfl, dt_max, dt_fixed) = match cfg.time_step {
        TimeStep::Fixed(dt) => (0.0, dt as f32, dt as f32),
        TimeStep::Adaptive { cfl, max } => (cfl as f32, max as f32, max as f32),
    };
    Params {
        origin: grid.origin.map(|x| x as f32),
        inv_cell: 1.0 / grid.cell as f32,
        dims: grid.dims.map(|d| d as u32),
        n_cells: n_cells as u32,
        n: n as u32,
        nm: nm as u32,
        reach: regolith_fsi::cpu::reach(2.0 * h, grid.cell) as u32,
        radius2: radius * radius,
        h: h as f32,
        inv_h: (1.0 / h) as f32,
        alpha,
        support2: (4.0 * h * h) as f32,
        visc_alpha: cfg.artificial_viscosity as f32,
        eta2: (0.01 * h * h) as f32,
        m_volume: cfg.spacing.powi(3) as f32,
        ref_rho: ref_rho as f32,
        gravity: cfg.gravity.map(|g| g as f32),
        ref_cs: ref_cs as f32,
        xsph_eps: if cfg.shifting.xsph() { cfg.xsph_epsilon as f32 } else { 0.0 },
        shift: if cfg.shifting.ppst() { (cfg.shifting_coefficient * h) as f32 } else { 0.0 },
        max_shift: (0.2 * cfg.spacing) as f32,
        fs_threshold: cfg.free_surface_threshold.unwrap_or(0.0) as f32,
        detach_threshold: DETACHED_THRESHOLD as f32,
        cfl,
        dt_max,
        dt_fixed,
        w_rest: wet.map_or(0.0, |w| w.rest),
        w_c: wet.map_or(0.0, |w| w.water.sound_speed),
        w_mu: wet.map_or(0.0, |w| w.water.viscosity),
        w_gamma: wet.map_or(0.0, |w| w.gamma),
        inv_lsum: wet.map_or(0.0, |w| w.inv_lattice_sum),
        lsum: wet.map_or(0.0, |w| w.lattice_sum),
        full_support: wet.map_or(0.0, |w| w.full_support),
        drag_particle: u32::from(wet.is_some_and(|w| w.drag == Drag::Particle)),
    }
}

/// The compiled kernels of a dry step (a wet scene adds those of [`WetParts`]).
pub(crate) struct Kernels {
    pub(crate) sort_soil: Sort,
    pub(crate) sort_markers: Sort,
    pub(crate) scan: Scan,
    pub(crate) permute: Permute,
    pub(crate) pack: Pack,
    pub(crate) extrapolate: Extrapolate,
    pub(crate) rates: Rates,
    pub(crate) forces: Forces,
    pub(crate) info: StepInfo,
    pub(crate) advance: Advance,
    pub(crate) bodies: Bodies,
}

impl Kernels {
    /// Compiles every kernel of a dry step for these effects.
    pub(crate) fn new(device: &wgpu::Device, effects: &Effects, n_cells: usize) -> Result<Self, GpuError> {
        Ok(Self {
            sort_soil: Sort::new(device, effects, (size_of::<Particle>() / 4) as u32, "sort[soil]")?,
            sort_markers: Sort::new(device, effects, (size_of::<Marker>() / 4) as u32, "sort[markers]")?,
            scan: Scan::new(device, effects, n_cells as u32 + 1)?,
            permute: Permute::new(device, effects)?,
            pack: Pack::new(device, effects)?,
            extrapolate: Extrapolate::new(device, effects)?,
            rates: Rates::new(device, effects)?,
            forces: Forces::new(device, effects)?,
            info: StepInfo::new(device, effects)?,
            advance: Advance::new(device, effects)?,
            bodies: Bodies::new(device, effects)?,
        })
    }

    /// The kernels' labels, as `regolith check` lists them.
    pub(crate) fn names(effects: &Effects) -> Vec<String> {
        let mut variants = vec![
            "sort[soil]".to_string(),
            "sort[markers]".into(),
            "scan".into(),
            "permute".into(),
            "pack".into(),
            "extrapolate".into(),
            "soil_rates[fs]".into(),
            "soil_rates".into(),
            "marker_forces".into(),
            "step_info".into(),
            "bodies".into(),
        ];
        let rheo: Vec<&str> =
            [(effects.dp, "dp"), (effects.mcc, "mcc")].iter().filter(|(on, _)| *on).map(|(_, s)| *s).collect();
        let rheo = if rheo.is_empty() { "elastic".to_string() } else { rheo.join("+") };
        if effects.rk2 {
            variants.push(format!("advance[stage,{rheo}]"));
        }
        variants.push(format!("advance[{rheo}]"));
        if effects.wet {
            variants.extend(Wet::names().iter().map(|s| s.to_string()));
        }
        variants
    }
}

/// The buffers of a dry step (a wet scene adds its own in [`WetParts`]).
pub(crate) struct Buffers {
    pub(crate) params: wgpu::Buffer,
    pub(crate) materials: wgpu::Buffer,
    pub(crate) parts: wgpu::Buffer,
    pub(crate) tmp: wgpu::Buffer,
    pub(crate) stage: wgpu::Buffer,
    pub(crate) packed: wgpu::Buffer,
    pub(crate) moduli: wgpu::Buffer,
    pub(crate) rates: wgpu::Buffer,
    pub(crate) info: wgpu::Buffer,
    pub(crate) cell_of: wgpu::Buffer,
    pub(crate) counts: wgpu::Buffer,
    pub(crate) start: wgpu::Buffer,
    pub(crate) sums: wgpu::Buffer,
    pub(crate) order: wgpu::Buffer,
    pub(crate) markers: wgpu::Buffer,
    pub(crate) m_sorted: wgpu::Buffer,
    pub(crate) m_limit: wgpu::Buffer,
    pub(crate) m_cell_of: wgpu::Buffer,
    pub(crate) m_counts: wgpu::Buffer,
    pub(crate) m_start: wgpu::Buffer,
    pub(crate) m_sums: wgpu::Buffer,
    pub(crate) m_order: wgpu::Buffer,
    pub(crate) m_packed: wgpu::Buffer,
    pub(crate) m_force: wgpu::Buffer,
    pub(crate) info_read: wgpu::Buffer,
    pub(crate) force_read: wgpu::Buffer,
    pub(crate) body_states: wgpu::Buffer,
    pub(crate) locals: wgpu::Buffer,
    pub(crate) wrenches: wgpu::Buffer,
    pub(crate) wrench_read: wgpu::Buffer,
    pub(crate) markers_read: wgpu::Buffer,
    pub(crate) parts_read: wgpu::Buffer,
    pub(crate) rates_read: wgpu::Buffer,
    /// μ per owner (0 = walls, k + 1 = body k): infinite for rough.
    pub(crate) owner_mu: wgpu::Buffer,
}

impl Buffers {
    /// Allocates every buffer, uninitialised (the solver writes the first contents).
    pub(crate) fn new(device: &wgpu::Device, c: &Counts) -> Self {
        let Counts { cap, nm, n_cells, n_bodies, n_materials } = *c;
        let mk = |label: &str, bytes: u64, usage: wgpu::BufferUsages| buffer(device, label, bytes, usage);
        let read = wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST;
        Self {
            params: mk(
                "params",
                size_of::<Params>() as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            materials: mk("materials", bytes(n_materials, size_of::<layout::Material>()), USAGE),
            parts: mk("particles", bytes(cap, size_of::<Particle>()), USAGE),
            tmp: mk("particles.tmp", bytes(cap, size_of::<Particle>()), USAGE),
            stage: mk("particles.stage", bytes(cap, size_of::<Particle>()), USAGE),
            packed: mk("packed", bytes(cap, size_of::<Packed>()), USAGE),
            moduli: mk("moduli", bytes(cap, 8), USAGE),
            rates: mk("rates", bytes(cap, size_of::<Rate>()), USAGE),
            info: mk("info", size_of::<Info>() as u64, USAGE),
            cell_of: mk("cell_of", bytes(cap, 4), USAGE),
            counts: mk("counts", bytes(n_cells + 1, 4), USAGE),
            start: mk("start", bytes(n_cells + 2, 4), USAGE),
            sums: mk("sums", bytes(scan_blocks(n_cells + 1), 4), USAGE),
            order: mk("order", bytes(cap, 4), USAGE),
            markers: mk("markers", bytes(nm, size_of::<Marker>()), USAGE),
            m_sorted: mk("markers.sorted", bytes(nm, size_of::<Marker>()), USAGE),
            m_limit: mk("markers.count", 4, USAGE),
            m_cell_of: mk("markers.cell_of", bytes(nm, 4), USAGE),
            m_counts: mk("markers.counts", bytes(n_cells + 1, 4), USAGE),
            m_start: mk("markers.start", bytes(n_cells + 2, 4), USAGE),
            m_sums: mk("markers.sums", bytes(scan_blocks(n_cells + 1), 4), USAGE),
            m_order: mk("markers.order", bytes(nm, 4), USAGE),
            m_packed: mk("markers.packed", bytes(nm, size_of::<Packed>()), USAGE),
            m_force: mk("markers.force", bytes(nm, 12), USAGE),
            info_read: mk("info.read", size_of::<Info>() as u64, read),
            force_read: mk("force.read", bytes(nm, 12), read),
            body_states: mk("bodies", bytes(n_bodies, size_of::<Body>()), USAGE),
            locals: mk("bodies.local", bytes(nm, 12), USAGE),
            wrenches: mk("bodies.wrench", bytes(n_bodies, 24), USAGE),
            wrench_read: mk("bodies.wrench.read", bytes(n_bodies, 24), read),
            markers_read: mk("markers.read", bytes(nm, size_of::<Marker>()), read),
            parts_read: mk("particles.read", bytes(cap, size_of::<Particle>()), read),
            rates_read: mk("rates.read", bytes(cap, size_of::<Rate>()), read),
            owner_mu: mk("owners.mu", bytes(n_bodies + 1, 4), USAGE),
        }
    }
}

/// Each kernel's bindings over the buffers: one table per kernel, in its layout's order.
pub(crate) struct Groups {
    pub(crate) sort_soil: wgpu::BindGroup,
    pub(crate) sort_markers: wgpu::BindGroup,
    pub(crate) scan_soil: wgpu::BindGroup,
    pub(crate) scan_markers: wgpu::BindGroup,
    pub(crate) permute: wgpu::BindGroup,
    pub(crate) set_active: wgpu::BindGroup,
    pub(crate) gather: wgpu::BindGroup,
    pub(crate) pack: [wgpu::BindGroup; 2],
    pub(crate) extrapolate: [wgpu::BindGroup; 2],
    pub(crate) rates: [wgpu::BindGroup; 2],
    pub(crate) forces: wgpu::BindGroup,
    pub(crate) info: wgpu::BindGroup,
    pub(crate) advance: wgpu::BindGroup,
    pub(crate) bodies: wgpu::BindGroup,
}

impl Groups {
    /// The bind groups of the dry step's kernels over `b`.
    pub(crate) fn new(device: &wgpu::Device, k: &Kernels, b: &Buffers) -> Self {
        Self {
            sort_soil: bind(
                device,
                "sort[soil]",
                &k.sort_soil.layout,
                &[
                    (0, &b.params),
                    (1, &b.parts),
                    (2, &b.info),
                    (3, &b.cell_of),
                    (4, &b.counts),
                    (5, &b.start),
                    (6, &b.order),
                ],
            ),
            sort_markers: bind(
                device,
                "sort[markers]",
                &k.sort_markers.layout,
                &[
                    (0, &b.params),
                    (1, &b.markers),
                    (2, &b.m_limit),
                    (3, &b.m_cell_of),
                    (4, &b.m_counts),
                    (5, &b.m_start),
                    (6, &b.m_order),
                ],
            ),
            scan_soil: bind(
                device,
                "scan[soil]",
                &k.scan.layout,
                &[(0, &b.params), (1, &b.counts), (2, &b.start), (3, &b.sums)],
            ),
            scan_markers: bind(
                device,
                "scan[markers]",
                &k.scan.layout,
                &[(0, &b.params), (1, &b.m_counts), (2, &b.m_start), (3, &b.m_sums)],
            ),
            permute: bind(
                device,
                "permute_particles",
                &k.permute.particles_layout,
                &[(0, &b.params), (1, &b.order), (2, &b.start), (3, &b.parts), (4, &b.tmp)],
            ),
            set_active: bind(
                device,
                "set_active",
                &k.permute.active_layout,
                &[(0, &b.params), (2, &b.start), (5, &b.info)],
            ),
            gather: bind(
                device,
                "gather_markers",
                &k.permute.markers_layout,
                &[(0, &b.params), (1, &b.m_order), (2, &b.m_start), (6, &b.markers), (7, &b.m_sorted)],
            ),
            pack: [&b.parts, &b.stage].map(|p| {
                bind(
                    device,
                    "pack",
                    &k.pack.layout,
                    &[(0, &b.params), (1, p), (2, &b.materials), (3, &b.packed), (4, &b.moduli), (5, &b.info)],
                )
            }),
            extrapolate: [&b.parts, &b.stage].map(|p| {
                bind(
                    device,
                    "extrapolate",
                    &k.extrapolate.layout,
                    &[
                        (0, &b.params),
                        (1, &b.m_sorted),
                        (2, &b.m_start),
                        (3, &b.packed),
                        (4, p),
                        (5, &b.start),
                        (6, &b.m_packed),
                        (7, &b.owner_mu),
                    ],
                )
            }),
            rates: [&b.parts, &b.stage].map(|p| {
                bind(
                    device,
                    "soil_rates",
                    &k.rates.layout,
                    &[
                        (0, &b.params),
                        (1, &b.packed),
                        (2, &b.start),
                        (3, &b.m_packed),
                        (4, &b.m_start),
                        (5, &b.moduli),
                        (6, p),
                        (7, &b.rates),
                        (8, &b.info),
                    ],
                )
            }),
            forces: bind(
                device,
                "marker_forces",
                &k.forces.layout,
                &[
                    (0, &b.params),
                    (1, &b.m_packed),
                    (2, &b.m_start),
                    (3, &b.m_order),
                    (4, &b.packed),
                    (5, &b.start),
                    (6, &b.m_force),
                    (7, &b.parts),
                ],
            ),
            info: bind(
                device,
                "step_info",
                &k.info.layout,
                &[(0, &b.params), (1, &b.parts), (2, &b.rates), (3, &b.info)],
            ),
            advance: bind(
                device,
                "advance",
                &k.advance.layout,
                &[(0, &b.params), (1, &b.parts), (2, &b.stage), (3, &b.rates), (4, &b.materials), (5, &b.info)],
            ),
            bodies: bind(
                device,
                "bodies",
                &k.bodies.layout,
                &[
                    (0, &b.params),
                    (1, &b.body_states),
                    (2, &b.locals),
                    (3, &b.markers),
                    (4, &b.m_force),
                    (5, &b.wrenches),
                ],
            ),
        }
    }
}

/// The phase coupling of a wet scene: its kernels, buffers and bind groups.
pub(crate) struct WetParts {
    pub(crate) k: Wet,
    /// Per owner (0 = walls, k + 1 = body k): 1 where water passes through its markers.
    pub(crate) owner_perm: wgpu::Buffer,
    pub(crate) n_owners: usize,
    pub(crate) phases: wgpu::BindGroup,
    pub(crate) marker_solids: wgpu::BindGroup,
    pub(crate) porosity: wgpu::BindGroup,
    pub(crate) soil_pressures: wgpu::BindGroup,
    pub(crate) extrapolate: [wgpu::BindGroup; 2],
    pub(crate) rates: [wgpu::BindGroup; 2],
    pub(crate) marker_forces: wgpu::BindGroup,
    pub(crate) init_water: wgpu::BindGroup,
    pub(crate) water_stress: wgpu::BindGroup,
    /// The water's partial densities and masses were set from the porosity (first step).
    pub(crate) ready: bool,
}

impl WetParts {
    /// Compiles the phase-coupling kernels and makes their buffers and bind groups over `b`.
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        effects: &Effects,
        b: &Buffers,
        c: &Counts,
    ) -> Result<Self, GpuError> {
        let Counts { cap, nm, n_bodies, .. } = *c;
        let mk = |label: &str, bytes: u64, usage: wgpu::BufferUsages| buffer(device, label, bytes, usage);
        let kw = Wet::new(device, effects)?;
        let n_owners = n_bodies + 1;
        // The bind groups keep these alive: per particle (sorted order) its phase,
        // porosity, pore pressure and velocity gradient; per sorted marker its solid
        // share, pore pressure, drag velocity and permeability, and the water's record
        // (the soil's is `Buffers::m_packed`).
        let pore = mk("pore", bytes(cap, size_of::<Pore>()), USAGE);
        let m_pore = mk("markers.pore", bytes(nm, size_of::<MarkerPore>()), USAGE);
        let m_packed_w = mk("markers.packed.water", bytes(nm, size_of::<Packed>()), USAGE);
        let owner_perm = mk("owners.permeable", bytes(n_owners, 4), USAGE);
        queue.write_buffer(&owner_perm, 0, bytemuck::cast_slice(&vec![0u32; n_owners]));
        let group = |label: &str, e: &crate::kernels::wet::Entry, used: &[u32], from: usize| {
            let buf = |binding: u32| -> &wgpu::Buffer {
                match binding {
                    0 => &b.params,
                    1 => &b.packed,
                    2 => &b.start,
                    3 => &b.m_packed,
                    4 => &m_packed_w,
                    5 => &b.m_start,
                    6 => &b.moduli,
                    7 if from == 0 => &b.parts,
                    7 => &b.stage,
                    8 => &b.rates,
                    9 => &b.info,
                    10 => &b.materials,
                    11 => &pore,
                    12 => &m_pore,
                    13 => &b.m_sorted,
                    14 => &owner_perm,
                    15 => &b.m_order,
                    16 => &b.m_force,
                    _ => &b.owner_mu,
                }
            };
            let entries: Vec<(u32, &wgpu::Buffer)> = used.iter().map(|&u| (u, buf(u))).collect();
            bind(device, label, &e.layout, &entries)
        };
        use crate::kernels::wet::bindings as wb;
        Ok(Self {
            phases: group("phases", &kw.phases, wb::PHASES, 0),
            marker_solids: group("marker_solids", &kw.marker_solids, wb::MARKER_SOLIDS, 0),
            porosity: group("porosity", &kw.porosity, wb::POROSITY, 0),
            soil_pressures: group("soil_pressures", &kw.soil_pressures, wb::SOIL_PRESSURES, 0),
            extrapolate: [0, 1].map(|f| group("wet_extrapolate", &kw.extrapolate, wb::EXTRAPOLATE, f)),
            rates: [0, 1].map(|f| group("wet_rates", &kw.rates[f], wb::RATES, f)),
            marker_forces: group("wet_marker_forces", &kw.marker_forces, wb::MARKER_FORCES, 0),
            init_water: group("init_water", &kw.init_water, wb::PARTICLE_STATE, 0),
            water_stress: group("water_stress", &kw.water_stress, wb::PARTICLE_STATE, 0),
            k: kw,
            owner_perm,
            n_owners,
            ready: false,
        })
    }
}

/// The material record the kernels read.
pub(crate) fn gpu_material(m: &Material<f32>) -> layout::Material {
    let mut g = layout::Material {
        density: m.density,
        bulk: m.elastic.bulk,
        shear: m.elastic.shear,
        poisson: m.poisson,
        ..layout::Material::zeroed()
    };
    match &m.rheology {
        Rheology::Elastic => g.model = 0,
        Rheology::DruckerPrager(dp) => {
            g.model = 1;
            g.mu_s = dp.mu_s;
            g.mu_2 = dp.mu_2;
            g.i0 = dp.i0;
            g.grain_d = dp.grain_diameter;
            g.grain_rho = dp.grain_density;
            g.k = dp.k;
        }
        Rheology::Mcc(mcc) => {
            g.model = 2;
            g.m = mcc.m;
            g.kappa = mcc.kappa;
            g.lambda = mcc.lambda;
            g.poisson = mcc.poisson;
            g.bulk = mcc.reference.bulk;
            g.shear = mcc.reference.shear;
            if let Some((lo, hi)) = mcc.safeguards.moduli_clamp {
                g.clamp = 1;
                g.clamp_lo = lo;
                g.clamp_hi = hi;
            }
            g.pc_floor = mcc.safeguards.pc_floor;
        }
        Rheology::Water(_) => g.model = 3,
    }
    if m.permeability > 0.0 {
        g.inv_perm = 1.0 / m.permeability;
        g.grain_por = m.grain_density;
    }
    g
}

/// Words of a scan's block totals for `len` counts (`len` fits a u32: `check_limits` refuses
/// more cells than u32 indices reach before any buffer is made).
fn scan_blocks(len: usize) -> usize {
    crate::shader::scan_blocks(u32::try_from(len).unwrap_or(u32::MAX)) as usize
}
