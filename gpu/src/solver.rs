//! [`GpuSph`]: the soil on the device, stepped by the kernels in the CPU backend's order.

use std::sync::mpsc;

use bytemuck::Zeroable;
use regolith_fsi::active::ActiveDomain;
use regolith_fsi::config::{FreeSurfaceStress, Integrator, KernelKind, SolverConfig, TimeStep};
use regolith_fsi::cpu::{ActiveRegion, GridSpec, WetSetup, lattice_sums};
use regolith_fsi::math::{Sym3, Vec3};
use regolith_fsi::rheology::{Material, PointState, Rheology};
use regolith_fsi::{BodyMarkers, BodyState, MarkerInit, ParticleInit, SolverError, SphSolver, StepReport};

use crate::GpuError;
use crate::active::{ActiveParts, Shared, Sizes};
use crate::error_code::DeviceError;
use crate::kernels::dispatch;
use crate::layout::{self, Body, Info, Marker, Params, Particle, Rate};
use crate::resources::{Buffers, Counts, Groups, Kernels, WetParts, check_limits, gpu_material, params};
use crate::shader::{Effects, groups};

impl Effects {
    /// The effects of a solver configuration and its materials.
    pub fn resolve(cfg: &SolverConfig, materials: &[Material<f32>]) -> Self {
        Self {
            cubic: cfg.kernel == KernelKind::Cubic,
            viscosity: cfg.artificial_viscosity > 0.0,
            xsph: cfg.shifting.xsph(),
            ppst: cfg.shifting.ppst(),
            zero_surface: cfg.free_surface_stress == FreeSurfaceStress::Zero,
            rk2: cfg.integrator == Integrator::Rk2,
            adaptive: matches!(cfg.time_step, TimeStep::Adaptive { .. }),
            dp: materials.iter().any(|m| matches!(m.rheology, Rheology::DruckerPrager(_))),
            mcc: materials.iter().any(|m| matches!(m.rheology, Rheology::Mcc(_))),
            wet: materials.iter().any(Material::is_water),
        }
    }
}

/// Host copy of the particles, refreshed by `sync`.
#[derive(Default)]
struct Mirror {
    pos: Vec<Vec3<f32>>,
    vel: Vec<Vec3<f32>>,
    rho: Vec<f32>,
    sigma: Vec<Sym3<f32>>,
    state: Vec<PointState<f32>>,
    material: Vec<u16>,
    mass: Vec<f32>,
    id: Vec<u32>,
    flags: Vec<u32>,
    acc: Vec<Vec3<f32>>,
    fs: Vec<f32>,
    /// Device index of each host entry.
    order: Vec<u32>,
}

/// SPH soil on a wgpu device, in f32.
pub struct GpuSph {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: String,
    cfg: SolverConfig,
    materials: Vec<Material<f32>>,
    effects: Effects,
    variants: Vec<String>,
    grid: GridSpec,
    n: usize,
    /// Particles the device buffers hold room for.
    capacity: usize,
    /// Id of the next particle a moving patch lays.
    next_id: u32,
    /// Fixed-wall markers (the first ones).
    n_walls: usize,
    nm: usize,
    n_cells: usize,
    k: Kernels,
    b: Buffers,
    g: Groups,
    active: usize,
    time: f64,
    steps: u64,
    markers_dirty: bool,
    /// Bodies (owners 1..=n_bodies).
    n_bodies: usize,
    /// Body-frame marker positions are on the device (after the first `place_bodies`).
    locals_uploaded: bool,
    /// Bodies to place at the start of the next step (their largest marker count).
    place_pending: Option<usize>,
    /// Reference point of each body's device wrench: its centre of mass when placed (m).
    wrench_ref: Vec<[f64; 3]>,
    /// Force and torque about `wrench_ref` on each body in the last step.
    last_wrench: Vec<[[f64; 3]; 2]>,
    m_host: Vec<Marker>,
    m_pos: Vec<Vec3<f32>>,
    m_force: Vec<Vec3<f32>>,
    mirror: Mirror,
    /// Wet scenes only.
    wet: Option<WetParts>,
    /// Markers given a wall normal by the last `set_wall_contact` (the first ones).
    normals_set: usize,
    /// The active region kept (shared with the CPU backend).
    region: ActiveRegion,
    /// Its kernel and cell mask, once a domain is set.
    act: Option<ActiveParts>,
    /// Particles the device sorts and steps: awake and extended while the region is kept
    /// (`partitioned`), all of them otherwise.
    live: usize,
    /// The particle buffer is in the order of a classification: awake and extended (flagged
    /// frozen) first, then asleep, then outside.
    partitioned: bool,
    /// Awake and asleep particles at the last classification.
    awake: usize,
    asleep: usize,
    /// Some awake particle left the cells it may be in during the last step.
    uncovered: bool,
}

/// A particle record from its initial state.
fn record(p: &ParticleInit, id: u32) -> Particle {
    Particle {
        pos: p.pos.map(|x| x as f32),
        vel: p.vel.map(|x| x as f32),
        rho: p.rho as f32,
        sigma: p.sigma.map(|x| x as f32),
        pc: p.pc as f32,
        sv: p.specific_volume as f32,
        mass: p.mass as f32,
        material: u32::from(p.material),
        id,
        flags: 0,
        pad: 0,
    }
}

impl GpuSph {
    /// Builds the solver on the caller's device. `domain` bounds everything that can take part,
    /// as for the CPU backend; `adapter` names the device for reports.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        adapter: &str,
        cfg: SolverConfig,
        materials: Vec<Material<f32>>,
        particles: &[ParticleInit],
        markers: &[MarkerInit],
        domain: ([f64; 3], [f64; 3]),
    ) -> Result<Self, GpuError> {
        Self::with_capacity(device, queue, adapter, cfg, materials, particles, markers, domain, particles.len())
    }

    /// As [`GpuSph::new`], with device buffers for `capacity` particles (at least the ones
    /// given): a moving patch ([`SphSolver::relay`]) may lay more soil than it lifts.
    #[allow(clippy::too_many_arguments)]
    pub fn with_capacity(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        adapter: &str,
        cfg: SolverConfig,
        materials: Vec<Material<f32>>,
        particles: &[ParticleInit],
        markers: &[MarkerInit],
        domain: ([f64; 3], [f64; 3]),
        capacity: usize,
    ) -> Result<Self, GpuError> {
        if materials.is_empty() {
            return Err(GpuError::Setup("no materials".into()));
        }
        let wet = WetSetup::<f32>::of(&materials, lattice_sums(&cfg), cfg.drag).map_err(GpuError::Setup)?;
        if let Some(p) = particles.iter().find(|p| p.material as usize >= materials.len()) {
            return Err(GpuError::Setup(format!("particle material index {} out of range", p.material)));
        }
        if let Some(p) = particles.iter().find(|p| !(p.rho > 0.0 && p.mass > 0.0)) {
            return Err(GpuError::Setup(format!("particle at {:?} has non-positive density or mass", p.pos)));
        }
        let grid = GridSpec::covering(domain.0, domain.1, cfg.h());
        let n = particles.len();
        let cap = capacity.max(n);
        let nm = markers.len();
        let n_cells = grid.cells();
        let first_body_marker = markers.iter().position(|m| m.owner > 0).unwrap_or(nm);
        if markers[first_body_marker..].iter().any(|m| m.owner == 0) {
            return Err(GpuError::Setup("wall markers must come before every body marker".into()));
        }
        let n_bodies = markers.iter().map(|m| m.owner as usize).max().unwrap_or(0);
        let counts = Counts { cap, nm, n_cells, n_bodies, n_materials: materials.len() };
        check_limits(&device.limits(), &counts, wet.is_some())?;
        let params = params(&cfg, &materials, &grid, wet.as_ref(), n, nm);
        let effects = Effects::resolve(&cfg, &materials);
        let k = Kernels::new(device, &effects, n_cells)?;
        let variants = Kernels::names(&effects);

        let b = Buffers::new(device, &counts);
        let init_parts: Vec<Particle> = particles.iter().enumerate().map(|(i, p)| record(p, i as u32)).collect();
        let m_host: Vec<Marker> = markers
            .iter()
            .map(|m| Marker { pos: m.pos.map(|x| x as f32), owner: m.owner, ..Marker::zeroed() })
            .collect();
        queue.write_buffer(&b.owner_mu, 0, bytemuck::cast_slice(&vec![f32::INFINITY; n_bodies + 1]));
        let gpu_mats: Vec<layout::Material> = materials.iter().map(gpu_material).collect();
        queue.write_buffer(&b.params, 0, bytemuck::bytes_of(&params));
        queue.write_buffer(&b.materials, 0, bytemuck::cast_slice(&gpu_mats));
        if n > 0 {
            queue.write_buffer(&b.parts, 0, bytemuck::cast_slice(&init_parts));
        }
        if nm > 0 {
            queue.write_buffer(&b.markers, 0, bytemuck::cast_slice(&m_host));
        }
        queue.write_buffer(&b.m_limit, 0, bytemuck::bytes_of(&(nm as u32)));
        let info0 = Info { active: n as u32, max_dt: f32::MAX, err_key: crate::error_code::NO_ERROR, ..Info::zeroed() };
        queue.write_buffer(&b.info, 0, bytemuck::bytes_of(&info0));

        let g = Groups::new(device, &k, &b);
        let wet = match wet {
            None => None,
            Some(_) => Some(WetParts::new(device, queue, &effects, &b, &counts)?),
        };
        let mut s = Self {
            device: device.clone(),
            queue: queue.clone(),
            adapter: adapter.to_string(),
            cfg,
            materials,
            effects,
            variants,
            grid,
            n,
            capacity: cap,
            next_id: n as u32,
            n_walls: first_body_marker,
            nm,
            n_cells,
            k,
            b,
            g,
            active: n,
            time: 0.0,
            steps: 0,
            markers_dirty: true,
            n_bodies,
            locals_uploaded: false,
            place_pending: None,
            wrench_ref: vec![[0.0; 3]; n_bodies],
            last_wrench: vec![[[0.0; 3]; 2]; n_bodies],
            m_pos: m_host.iter().map(|m| Vec3::of(m.pos.map(f64::from))).collect(),
            m_host,
            m_force: vec![Vec3::zero(); nm],
            mirror: Mirror::default(),
            wet,
            normals_set: 0,
            region: ActiveRegion::default(),
            act: None,
            live: n,
            partitioned: false,
            awake: n,
            asleep: 0,
            uncovered: false,
        };
        s.sync().map_err(|e| GpuError::Device(e.to_string()))?;
        s.sync_diagnostics()?;
        Ok(s)
    }

    /// The effects the kernels were specialised for.
    pub fn effects(&self) -> &Effects {
        &self.effects
    }

    /// The neighbour grid.
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }

    /// Awake and extended particles (extended ones: `awake()..near()` of the host copy); all of
    /// them while no active region is kept.
    pub fn near(&self) -> usize {
        if self.partitioned { self.live } else { self.active }
    }

    /// Free-surface flags of the last step (host copy, after `sync`).
    pub fn free_surface(&self) -> Vec<bool> {
        self.mirror.flags.iter().map(|f| f & layout::FLAG_FREE != 0).collect()
    }

    /// Detached flags of the last step (host copy, after `sync`).
    pub fn detached(&self) -> Vec<bool> {
        self.mirror.flags.iter().map(|f| f & layout::FLAG_DETACHED != 0).collect()
    }

    /// Accelerations of the last stage (host copy, after `sync_diagnostics`).
    pub fn accelerations(&self) -> &[Vec3<f32>] {
        &self.mirror.acc[..SphSolver::awake(self)]
    }

    /// Free-surface measure of the last first stage (host copy, after `sync_diagnostics`).
    pub fn free_surface_measure(&self) -> &[f32] {
        &self.mirror.fs[..SphSolver::awake(self)]
    }

    fn record_sort(&self, enc: &mut wgpu::CommandEncoder) {
        let (k, b, g) = (&self.k, &self.b, &self.g);
        let live = self.live;
        enc.clear_buffer(&b.counts, 0, None);
        dispatch(enc, &k.sort_soil.bin, &g.sort_soil, groups(live));
        k.scan.record(enc, &g.scan_soil);
        enc.clear_buffer(&b.counts, 0, None);
        dispatch(enc, &k.sort_soil.scatter, &g.sort_soil, groups(live));
        dispatch(enc, &k.sort_soil.order_bins, &g.sort_soil, groups(self.n_cells + 1));
        dispatch(enc, &k.permute.permute_particles, &g.permute, groups(live));
        if live > 0 {
            enc.copy_buffer_to_buffer(&b.tmp, 0, &b.parts, 0, Some((live * size_of::<Particle>()) as u64));
        }
        dispatch(enc, &k.permute.set_active, &g.set_active, 1);
        if self.markers_dirty {
            enc.clear_buffer(&b.m_counts, 0, None);
            dispatch(enc, &k.sort_markers.bin, &g.sort_markers, groups(self.nm));
            k.scan.record(enc, &g.scan_markers);
            enc.clear_buffer(&b.m_counts, 0, None);
            dispatch(enc, &k.sort_markers.scatter, &g.sort_markers, groups(self.nm));
            dispatch(enc, &k.sort_markers.order_bins, &g.sort_markers, groups(self.n_cells + 1));
            dispatch(enc, &k.permute.gather_markers, &g.gather, groups(self.nm));
        }
    }

    /// Pack, extrapolate and rates from the current (`0`) or midpoint (`1`) state.
    fn record_evaluate(&self, enc: &mut wgpu::CommandEncoder, from: usize, forces: bool) {
        let (k, g) = (&self.k, &self.g);
        if let Some(w) = &self.wet {
            self.record_pores(enc, w, from);
            let (kw, n, nm) = (&w.k, groups(self.live), groups(self.nm));
            dispatch(enc, &kw.extrapolate.pipeline, &w.extrapolate[from], nm);
            dispatch(enc, &kw.rates[from].pipeline, &w.rates[from], n);
            if forces {
                enc.clear_buffer(&self.b.m_force, 0, None);
                dispatch(enc, &kw.marker_forces.pipeline, &w.marker_forces, nm);
            }
            return;
        }
        dispatch(enc, &k.pack.pack, &g.pack[from], groups(self.live));
        dispatch(enc, &k.extrapolate.extrapolate, &g.extrapolate[from], groups(self.nm));
        let rates = if from == 0 { &k.rates.first } else { &k.rates.second };
        dispatch(enc, rates, &g.rates[from], groups(self.live));
        if forces {
            enc.clear_buffer(&self.b.m_force, 0, None);
            dispatch(enc, &k.forces.marker_forces, &g.forces, groups(self.nm));
        }
    }

    /// The passes of a wet evaluation up to the porosity (CPU twin: `CpuSph::wet_pores`):
    /// records packed, phases, the markers' solid shares, the water's porosity and pressure,
    /// the soil's saturation and interpolated pore pressure.
    fn record_pores(&self, enc: &mut wgpu::CommandEncoder, w: &WetParts, from: usize) {
        let (kw, n, nm) = (&w.k, groups(self.live), groups(self.nm));
        dispatch(enc, &self.k.pack.pack, &self.g.pack[from], n);
        dispatch(enc, &kw.phases.pipeline, &w.phases, n);
        dispatch(enc, &kw.marker_solids.pipeline, &w.marker_solids, nm);
        dispatch(enc, &kw.porosity.pipeline, &w.porosity, n);
        dispatch(enc, &kw.soil_pressures.pipeline, &w.soil_pressures, n);
    }

    /// Copies `src` into a mappable buffer, waits, and hands the bytes to `f`.
    fn read_back<R>(
        &self,
        src: &wgpu::Buffer,
        dst: &wgpu::Buffer,
        bytes: u64,
        f: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, GpuError> {
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("read") });
        enc.copy_buffer_to_buffer(src, 0, dst, 0, Some(bytes));
        self.queue.submit([enc.finish()]);
        self.map(dst, bytes, f)
    }

    fn map<R>(&self, dst: &wgpu::Buffer, bytes: u64, f: impl FnOnce(&[u8]) -> R) -> Result<R, GpuError> {
        let (tx, rx) = mpsc::channel();
        dst.map_async(wgpu::MapMode::Read, 0..bytes, move |r| {
            let _ = tx.send(r);
        });
        self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::Device(e.to_string()))?;
        rx.recv().map_err(|e| GpuError::Device(e.to_string()))?.map_err(|e| GpuError::Device(e.to_string()))?;
        let out = {
            let view = dst.get_mapped_range(0..bytes).map_err(|e| GpuError::Device(e.to_string()))?;
            f(&view)
        };
        dst.unmap();
        Ok(out)
    }

    fn step_gpu(&mut self, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
        let dev = |e: GpuError| SolverError::Setup(format!("wgpu: {e}"));
        // The active region, as the CPU keeps it at a list build (`CpuSph::build_lists`).
        if self.region.partitioned(self.time) {
            if self.region.needs_classification() || self.uncovered || !self.partitioned {
                self.classify().map_err(dev)?;
            }
        } else {
            self.region.forget();
            if self.partitioned {
                self.unpartition().map_err(dev)?;
            }
        }
        let live = groups(self.live);
        let limit = max_dt.map_or(f32::MAX, |m| m as f32);
        self.queue.write_buffer(&self.b.info, 8, bytemuck::bytes_of(&limit));
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("step") });
        let rk2 = self.effects.rk2;
        dispatch(&mut enc, &self.k.info.reset, &self.g.info, 1);
        if let Some(most) = self.place_pending.take() {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
            pass.set_pipeline(&self.k.bodies.place);
            pass.set_bind_group(0, &self.g.bodies, &[]);
            pass.dispatch_workgroups(groups(most), self.n_bodies as u32, 1);
        }
        self.record_sort(&mut enc);
        self.markers_dirty = false;
        if let Some(w) = self.wet.as_ref().filter(|w| !w.ready) {
            // The water's partial density and mass from the porosity it starts in
            // (CPU twin: `CpuSph::init_water`).
            self.record_pores(&mut enc, w, 0);
            dispatch(&mut enc, &w.k.init_water.pipeline, &w.init_water, live);
        }
        if let Some(w) = self.wet.as_mut() {
            w.ready = true;
        }
        self.record_evaluate(&mut enc, 0, !rk2);
        dispatch(&mut enc, &self.k.info.maxima, &self.g.info, live);
        dispatch(&mut enc, &self.k.info.choose_dt, &self.g.info, 1);
        if let (true, Some(stage)) = (rk2, &self.k.advance.stage) {
            dispatch(&mut enc, stage, &self.g.advance, live);
            self.record_evaluate(&mut enc, 1, true);
        }
        dispatch(&mut enc, &self.k.advance.finish, &self.g.advance, live);
        if let Some(w) = &self.wet {
            // A water particle's stress is its pore pressure (from the last evaluation).
            dispatch(&mut enc, &w.k.water_stress.pipeline, &w.water_stress, live);
        }
        if let (true, Some(a)) = (self.partitioned, &self.act) {
            dispatch(&mut enc, &a.k.cover, &a.group, live);
        }
        enc.copy_buffer_to_buffer(&self.b.info, 0, &self.b.info_read, 0, Some(size_of::<Info>() as u64));
        let nb = self.n_bodies;
        if nb > 0 {
            // One workgroup per body sums its markers' force and torque.
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
            pass.set_pipeline(&self.k.bodies.wrench);
            pass.set_bind_group(0, &self.g.bodies, &[]);
            pass.dispatch_workgroups(nb as u32, 1, 1);
            drop(pass);
            enc.copy_buffer_to_buffer(&self.b.wrenches, 0, &self.b.wrench_read, 0, Some((nb * 24) as u64));
        }
        self.queue.submit([enc.finish()]);
        let info: Info =
            self.map(&self.b.info_read, size_of::<Info>() as u64, |b| *bytemuck::from_bytes(b)).map_err(dev)?;
        if nb > 0 {
            let w: Vec<[f32; 6]> =
                self.map(&self.b.wrench_read, (nb * 24) as u64, |b| bytemuck::cast_slice(b).to_vec()).map_err(dev)?;
            for (dst, w) in self.last_wrench.iter_mut().zip(w) {
                *dst = [[0, 1, 2].map(|k| f64::from(w[k])), [3, 4, 5].map(|k| f64::from(w[k]))];
            }
        }
        let dt = match max_dt {
            Some(m) if info.dt == m as f32 => m,
            _ => f64::from(info.dt),
        };
        let time = self.time + dt;
        self.active = info.active as usize + self.asleep;
        self.uncovered = info.uncovered != 0;
        if let Some((particle, code)) = crate::error_code::decode(info.err_key) {
            return Err(match DeviceError::from_code(code) {
                Some(e) => e.into_solver_error(self.steps, time, particle),
                None => SolverError::Setup(format!("wgpu: unknown kernel error code {code}")),
            });
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SolverError::Setup(format!("time step {dt} s is not positive")));
        }
        self.time = time;
        self.steps += 1;
        Ok(StepReport {
            dt,
            max_speed: f64::from(f32::from_bits(info.vmax_end)),
            max_accel: f64::from(f32::from_bits(info.amax_end)),
            active: self.active,
            awake: if self.partitioned { self.awake } else { self.active },
            pairs: info.pairs as usize,
            rarefied: info.rarefied as usize,
        })
    }

    /// The particle records, in device order.
    fn read_particles(&self) -> Result<Vec<Particle>, GpuError> {
        let n = self.n;
        let mut parts: Vec<Particle> =
            self.read_back(&self.b.parts, &self.b.parts_read, (n.max(1) * size_of::<Particle>()) as u64, |b| {
                bytemuck::cast_slice::<u8, Particle>(b).to_vec()
            })?;
        parts.truncate(n);
        Ok(parts)
    }

    fn sync_gpu(&mut self) -> Result<(), GpuError> {
        let parts = self.read_particles()?;
        self.fill_mirror(&parts);
        Ok(())
    }

    /// Classifies the particles on the device (the twin of the CPU's `ActiveRegion::classify`)
    /// and puts them in its order: awake, extended (flagged frozen), asleep, outside. The
    /// device then sorts and steps the first `awake + extended`. Only the four counts come
    /// back; the host copy is refreshed by the next `sync`. CPU twin: `CpuSph::classify`.
    fn classify(&mut self) -> Result<(), GpuError> {
        let act = self.act.as_ref().ok_or(GpuError::Internal("active region without its kernels"))?;
        let n = self.n;
        let mut enc = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("classify") });
        act.record(&self.queue, &mut enc, &self.region, n, self.n_cells);
        if n > 0 {
            enc.copy_buffer_to_buffer(&self.b.tmp, 0, &self.b.parts, 0, Some((n * size_of::<Particle>()) as u64));
        }
        self.queue.submit([enc.finish()]);
        let count: [u32; 4] = self.map(&act.counts_read, 16, |b| *bytemuck::from_bytes(b))?;
        if count.iter().map(|&c| c as usize).sum::<usize>() != n {
            return Err(GpuError::Internal("the classification's counts do not add up to the particles"));
        }
        let count = count.map(|c| c as usize);
        self.region.note_classification();
        let near = count[0] + count[1];
        self.live = near;
        self.awake = count[0];
        self.asleep = count[2];
        self.active = near + count[2];
        self.partitioned = true;
        self.uncovered = false;
        Ok(())
    }

    /// Gives every particle back to the device's sort and step (the region was switched off
    /// or the free-flow time not reached): frozen flags cleared, all of them sorted.
    fn unpartition(&mut self) -> Result<(), GpuError> {
        let mut parts = self.read_particles()?;
        for p in &mut parts {
            p.flags &= !layout::FLAG_FROZEN;
        }
        self.live = self.n;
        self.asleep = 0;
        self.partitioned = false;
        self.uncovered = false;
        self.upload(&parts, self.n);
        Ok(())
    }

    /// Writes the particle records and the count the next sort takes, and refreshes the host
    /// copy (the records' order changed).
    fn upload(&mut self, parts: &[Particle], sorted: usize) {
        if !parts.is_empty() {
            self.queue.write_buffer(&self.b.parts, 0, bytemuck::cast_slice(parts));
        }
        self.queue.write_buffer(&self.b.info, 0, bytemuck::bytes_of(&(sorted as u32)));
        self.fill_mirror(parts);
    }

    /// Refreshes the host copy from records in device order. While an active region is kept,
    /// the device sorts awake and extended particles together; the host copy puts the awake
    /// ones first (then extended, asleep, outside), as the CPU backend orders them.
    /// The moving patch (CPU twin: `CpuSph::relay`): lifts the soil at `x < cut`, lays `fresh`
    /// with new ids after the soil kept, shifts the fixed walls by `shift`, and gives every
    /// particle back to the next step's sort (and classification). Made on the host: a patch
    /// advances every few centimetres of travel.
    fn relay_gpu(&mut self, cut: f64, shift: f64, fresh: &[ParticleInit]) -> Result<usize, SolverError> {
        let dev = |e: GpuError| SolverError::Setup(format!("wgpu: {e}"));
        if self.wet.is_some() {
            return Err(SolverError::Setup("a moving patch does not carry water yet".into()));
        }
        ParticleInit::check_laid(fresh, self.materials.len())?;
        if self.next_id as usize + fresh.len() >= u32::MAX as usize {
            return Err(SolverError::Setup("too many particles laid by the moving patch (ids exhausted)".into()));
        }
        let parts = self.read_particles().map_err(dev)?;
        // Kept in their order, escaped ones included (the next sort puts those last, as the
        // CPU keeps them), then the fresh soil: the sort that follows gives the CPU's order.
        let cut = cut as f32;
        let mut next: Vec<Particle> = parts.iter().filter(|p| p.pos[0] >= cut).copied().collect();
        let lifted = parts.len() - next.len();
        let n = next.len() + fresh.len();
        if n > self.capacity {
            return Err(SolverError::Setup(format!(
                "the moving patch now holds {n} particles, more than the {} the wgpu buffers were made for; a shorter terrain.patch.length, or backend = \"cpu\", keeps it",
                self.capacity
            )));
        }
        next.extend(fresh.iter().zip(self.next_id..).map(|(p, id)| record(p, id)));
        self.next_id += fresh.len() as u32;
        self.n = n;
        self.live = n;
        self.active = n;
        self.asleep = 0;
        self.partitioned = false;
        self.uncovered = false;
        self.region.forget();
        self.queue.write_buffer(
            &self.b.params,
            std::mem::offset_of!(Params, n) as u64,
            bytemuck::bytes_of(&(n as u32)),
        );
        self.upload(&next, n);
        let dx = shift as f32;
        for (m, p) in self.m_host[..self.n_walls].iter_mut().zip(&mut self.m_pos) {
            m.pos[0] += dx;
            p.x = m.pos[0];
        }
        if self.n_walls > 0 {
            self.queue.write_buffer(&self.b.markers, 0, bytemuck::cast_slice(&self.m_host[..self.n_walls]));
        }
        self.markers_dirty = true;
        Ok(lifted)
    }

    fn fill_mirror(&mut self, device_order: &[Particle]) {
        let m = &mut self.mirror;
        m.order.clear();
        if self.partitioned {
            let inside = (self.active - self.asleep).min(device_order.len());
            let frozen = |p: &Particle| p.flags & layout::FLAG_FROZEN != 0;
            m.order.extend((0..inside).filter(|&i| !frozen(&device_order[i])).map(|i| i as u32));
            m.order.extend((0..inside).filter(|&i| frozen(&device_order[i])).map(|i| i as u32));
            m.order.extend(inside as u32..device_order.len() as u32);
        } else {
            m.order.extend(0..device_order.len() as u32);
        }
        let parts: Vec<Particle> = m.order.iter().map(|&i| device_order[i as usize]).collect();
        let v3 = |a: [f32; 3]| Vec3::new(a[0], a[1], a[2]);
        m.pos = parts.iter().map(|p| v3(p.pos)).collect();
        m.vel = parts.iter().map(|p| v3(p.vel)).collect();
        m.rho = parts.iter().map(|p| p.rho).collect();
        m.sigma = parts
            .iter()
            .map(|p| Sym3::new(p.sigma[0], p.sigma[1], p.sigma[2], p.sigma[3], p.sigma[4], p.sigma[5]))
            .collect();
        m.state = parts.iter().map(|p| PointState { pc: p.pc, v: p.sv }).collect();
        m.material = parts.iter().map(|p| p.material as u16).collect();
        m.mass = parts.iter().map(|p| p.mass).collect();
        m.id = parts.iter().map(|p| p.id).collect();
        m.flags = parts.iter().map(|p| p.flags).collect();
    }

    /// Reads back what only diagnostics and tests look at: the last stage's rates
    /// (accelerations, free-surface measure, in the host copy's order: call after `sync`) and
    /// every marker's position and force. Not part
    /// of `sync`, which runs once per exchange: with walls the markers outnumber the particles.
    pub fn sync_diagnostics(&mut self) -> Result<(), GpuError> {
        let n = self.n;
        let rates: Vec<Rate> =
            self.read_back(&self.b.rates, &self.b.rates_read, (n.max(1) * size_of::<Rate>()) as u64, |b| {
                bytemuck::cast_slice::<u8, Rate>(b).to_vec()
            })?;
        let order = &self.mirror.order;
        self.mirror.acc = order.iter().map(|&i| rates[i as usize].acc).map(|a| Vec3::new(a[0], a[1], a[2])).collect();
        self.mirror.fs = order.iter().map(|&i| rates[i as usize].fs).collect();
        let nm = self.nm;
        if nm > 0 {
            let markers: Vec<Marker> =
                self.read_back(&self.b.markers, &self.b.markers_read, (nm * size_of::<Marker>()) as u64, |b| {
                    bytemuck::cast_slice::<u8, Marker>(b).to_vec()
                })?;
            self.m_pos = markers.iter().map(|m| Vec3::new(m.pos[0], m.pos[1], m.pos[2])).collect();
            let forces: Vec<[f32; 3]> = self.read_back(&self.b.m_force, &self.b.force_read, (nm * 12) as u64, |b| {
                bytemuck::cast_slice(b).to_vec()
            })?;
            self.m_force = forces.iter().map(|f| Vec3::new(f[0], f[1], f[2])).collect();
        }
        Ok(())
    }
}

impl SphSolver<f32> for GpuSph {
    fn backend(&self) -> &'static str {
        "wgpu"
    }
    fn adapter(&self) -> String {
        self.adapter.clone()
    }
    fn config(&self) -> &SolverConfig {
        &self.cfg
    }
    fn materials(&self) -> &[Material<f32>] {
        &self.materials
    }
    fn time(&self) -> f64 {
        self.time
    }
    fn steps(&self) -> u64 {
        self.steps
    }
    fn len(&self) -> usize {
        self.n
    }
    fn active(&self) -> usize {
        self.active
    }
    fn awake(&self) -> usize {
        if self.partitioned { self.awake } else { self.active }
    }
    fn set_active_domain(&mut self, domain: Option<ActiveDomain>) -> Result<(), SolverError> {
        self.region.set(domain, self.n_bodies, self.wet.is_some()).map_err(SolverError::Setup)?;
        if self.region.domain().is_some() && self.act.is_none() {
            let dev = |e: GpuError| SolverError::Setup(format!("wgpu: {e}"));
            let shared = Shared { params: &self.b.params, parts: &self.b.parts, tmp: &self.b.tmp, info: &self.b.info };
            let reach = regolith_fsi::cpu::reach(2.0 * self.cfg.h(), self.grid.cell) as u32;
            let act = ActiveParts::new(
                &self.device,
                &self.queue,
                &self.effects,
                &shared,
                &Sizes { cells: self.n_cells, capacity: self.capacity, boxes: self.n_bodies, reach },
            )
            .map_err(dev)?;
            self.act = Some(act);
            self.variants.push("classify".into());
            self.variants.push("cover".into());
        }
        Ok(())
    }
    fn classifications(&self) -> u64 {
        self.region.classifications()
    }
    fn relay(&mut self, cut: f64, shift: f64, fresh: &[ParticleInit]) -> Result<usize, SolverError> {
        self.relay_gpu(cut, shift, fresh)
    }
    fn step(&mut self, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
        self.step_gpu(max_dt)
    }
    fn sync(&mut self) -> Result<(), SolverError> {
        self.sync_gpu().map_err(|e| SolverError::Setup(format!("wgpu: {e}")))
    }
    fn positions(&self) -> &[Vec3<f32>] {
        &self.mirror.pos
    }
    fn velocities(&self) -> &[Vec3<f32>] {
        &self.mirror.vel
    }
    fn densities(&self) -> &[f32] {
        &self.mirror.rho
    }
    fn stresses(&self) -> &[Sym3<f32>] {
        &self.mirror.sigma
    }
    fn states(&self) -> &[PointState<f32>] {
        &self.mirror.state
    }
    fn material_ids(&self) -> &[u16] {
        &self.mirror.material
    }
    fn masses(&self) -> &[f32] {
        &self.mirror.mass
    }
    fn ids(&self) -> &[u32] {
        &self.mirror.id
    }
    fn marker_positions(&self) -> &[Vec3<f32>] {
        &self.m_pos
    }
    fn marker_forces(&self) -> &[Vec3<f32>] {
        &self.m_force
    }
    fn set_marker_kinematics(&mut self, first: usize, pos: &[Vec3<f32>], vel: &[Vec3<f32>], acc: &[Vec3<f32>]) {
        for (i, ((p, v), a)) in pos.iter().zip(vel).zip(acc).enumerate() {
            let m = &mut self.m_host[first + i];
            m.pos = [p.x, p.y, p.z];
            m.vel = [v.x, v.y, v.z];
            m.acc = [a.x, a.y, a.z];
            self.m_pos[first + i] = *p;
        }
        let end = first + pos.len();
        if end > first {
            self.queue.write_buffer(
                &self.b.markers,
                (first * size_of::<Marker>()) as u64,
                bytemuck::cast_slice(&self.m_host[first..end]),
            );
        }
        self.markers_dirty = true;
    }
    fn place_bodies(&mut self, bodies: &[BodyMarkers<'_>], states: &[BodyState]) {
        self.region.place(states);
        if bodies.len() != self.n_bodies || states.len() != bodies.len() {
            // Not the bodies the markers were built for: place them from the host.
            regolith_fsi::place_on_host(self, bodies, states);
            return;
        }
        if !self.locals_uploaded {
            let mut locals = vec![[0.0f32; 3]; self.nm.max(1)];
            for b in bodies {
                for (i, l) in b.local.iter().enumerate() {
                    locals[b.first + i] = l.map(|x| x as f32);
                }
            }
            self.queue.write_buffer(&self.b.locals, 0, bytemuck::cast_slice(&locals));
            self.locals_uploaded = true;
        }
        let f = |a: [f64; 3]| a.map(|x| x as f32);
        let table: Vec<Body> = bodies
            .iter()
            .zip(states)
            .map(|(b, s)| Body {
                rotation: s.rotation.map(|x| x as f32),
                origin: f(s.origin),
                com: f(s.com),
                linvel: f(s.linvel),
                angvel: f(s.angvel),
                linacc: f(s.linacc),
                angacc: f(s.angacc),
                first: b.first as u32,
                count: b.local.len() as u32,
            })
            .collect();
        // The device sums torques about the f32 centre of mass it was given.
        self.wrench_ref = table.iter().map(|b| b.com.map(f64::from)).collect();
        self.queue.write_buffer(&self.b.body_states, 0, bytemuck::cast_slice(&table));
        self.place_pending = Some(bodies.iter().map(|b| b.local.len()).max().unwrap_or(0));
        self.markers_dirty = true;
    }
    fn body_wrenches(&self, bodies: &[BodyMarkers<'_>], about: &[[f64; 3]]) -> Vec<[[f64; 3]; 2]> {
        bodies
            .iter()
            .zip(about)
            .enumerate()
            .map(|(k, (_, a))| {
                let [force, t_ref] = self.last_wrench[k];
                // Sum (x - a) × f = sum (x - c) × f + (c - a) × F.
                let arm = Vec3::<f64>::of(self.wrench_ref[k]) - Vec3::of(*a);
                [force, (Vec3::of(t_ref) + arm.cross(Vec3::of(force))).as_f64()]
            })
            .collect()
    }
    fn variants(&self) -> Vec<String> {
        self.variants.clone()
    }
    fn set_wall_contact(
        &mut self,
        contact: &[regolith_fsi::config::WallContact],
        normals: &[[f64; 3]],
    ) -> Result<(), SolverError> {
        regolith_fsi::config::WallContact::check(contact, normals, self.nm).map_err(SolverError::Setup)?;
        let mu: Vec<f32> =
            (0..=self.n_bodies).map(|o| contact.get(o).map_or(f32::INFINITY, |c| c.mu() as f32)).collect();
        self.queue.write_buffer(&self.b.owner_mu, 0, bytemuck::cast_slice(&mu));
        // Only the markers that have or had a normal (the walls, which come first) are
        // rewritten: body markers placed on the device are newer there than on the host.
        let upto = normals.len().max(self.normals_set).min(self.nm);
        for (i, m) in self.m_host[..upto].iter_mut().enumerate() {
            m.normal = normals.get(i).map_or([0.0; 3], |n| n.map(|x| x as f32));
        }
        if upto > 0 {
            self.queue.write_buffer(&self.b.markers, 0, bytemuck::cast_slice(&self.m_host[..upto]));
        }
        self.normals_set = normals.len();
        self.markers_dirty = true;
        Ok(())
    }
    fn set_permeable(&mut self, permeable: &[bool]) -> Result<(), SolverError> {
        let Some(w) = &self.wet else {
            if permeable.iter().any(|p| *p) {
                return Err(SolverError::Setup("permeable markers need water in the scene".into()));
            }
            return Ok(());
        };
        let flags: Vec<u32> = (0..w.n_owners).map(|o| u32::from(permeable.get(o).copied().unwrap_or(false))).collect();
        self.queue.write_buffer(&w.owner_perm, 0, bytemuck::cast_slice(&flags));
        Ok(())
    }
    fn as_cpu(&self) -> Option<&regolith_fsi::cpu::CpuSph<f32>> {
        None
    }
}
