//! The CPU backend: rayon over cell-sorted structure-of-arrays particles. It is the reference
//! every other backend is compared with, and the fast path on machines without a GPU.
//!
//! One step:
//! 1. counting-sort the soil particles by cell and permute every array (particles stay in cell
//!    order, so a neighbour loop reads nearby memory); markers are sorted indirectly so their
//!    indices stay stable for the coupling layer;
//! 2. build soil–soil, soil–marker and marker–soil neighbour lists (radius 2h + skin), reused
//!    by both stages and, with a Verlet skin, by later steps while the moves since the build
//!    cannot have brought an unlisted pair inside 2h (steps 1–2 are then skipped);
//! 3. stage 1: extrapolate marker velocity and stress, evaluate the soil rates, flag the free
//!    surface, choose dt;
//! 4. midpoint: advance to t + dt/2 (plastic correction), evaluate again (with marker forces),
//!    advance from t to t + dt (plastic correction from the state at t). Euler does one
//!    evaluation and a symplectic (velocity-first) update.

mod grid;
mod lanes;
mod memory;
mod neighbors;
mod pair;
mod rates;
mod region;
mod wet;

pub use grid::GridSpec;
pub use memory::MemoryUse;
pub use neighbors::reach;
pub use region::{ActiveRegion, Classification};
pub use wet::{DELTA_SPH, WetSetup};

use rayon::prelude::*;

use crate::active::{ActiveDomain, RoleCounts};
use crate::config::{
    DETACHED_THRESHOLD, FreeSurfaceStress, Integrator, KernelKind, RAREFIED_DENSITY, SolverConfig, TimeStep,
};
use crate::kernel::{CubicSpline, Kernel, WendlandC2};
use crate::math::{Sym3, Vec3};
use crate::particles::{MarkerInit, ParticleInit, SolverError, StepReport};
use crate::rheology::{Material, Moduli, PointState, RheologyError};
use crate::{ByPrecision, PerPrecision, Real};
use regolith_body::BodyState;

use grid::{CellIndexer, CellSort};
use neighbors::{NeighborList, TargetGroup};
use pair::{Packed, PairConsts};
use rates::Rate;

/// Scratch buffers for permutations, one per element type.
#[derive(Default)]
struct Scratch<T> {
    v3: Vec<Vec3<T>>,
    t: Vec<T>,
    sym: Vec<Sym3<T>>,
    st: Vec<PointState<T>>,
    u16: Vec<u16>,
    u32: Vec<u32>,
    b: Vec<bool>,
}

/// Mutable access to the markers' prescribed motion (original order).
pub struct MarkerKinematics<'a, T> {
    /// Positions (m).
    pub pos: &'a mut [Vec3<T>],
    /// Velocities (m/s).
    pub vel: &'a mut [Vec3<T>],
    /// Accelerations (m/s²), used by the boundary-stress extrapolation.
    pub acc: &'a mut [Vec3<T>],
    /// Owners (0 = fixed walls, k + 1 = body k).
    pub owner: &'a [u32],
}

/// Particles and markers below which [`CpuSph::step`] runs inside rayon's pool. Measured on 2
/// vCPUs (AMD EPYC, 2 threads): a 20 m patch drive with 2 100 particles and markers stepped
/// 1.44× faster inside the pool (10.0 → 6.95 s for 2 s simulated; 1.9× with one thread),
/// Curio's bed (24 000) the same either way (23.2 and 23.6 s), the 250 000 of the benchmark
/// block 15 % slower inside (6.3e5 → 5.4e5 particle-steps/s; why is not measured). The
/// threshold sits between the first two.
pub const SMALL_STEP: usize = 10_000;

/// SPH soil on the CPU, in precision `T`.
pub struct CpuSph<T: Real> {
    cfg: SolverConfig,
    consts: PairConsts<T>,
    materials: Vec<Material<T>>,
    // Soil, cell-sorted.
    pos: Vec<Vec3<T>>,
    vel: Vec<Vec3<T>>,
    rho: Vec<T>,
    sigma: Vec<Sym3<T>>,
    state: Vec<PointState<T>>,
    material: Vec<u16>,
    mass: Vec<T>,
    id: Vec<u32>,
    /// The id the next particle laid by [`CpuSph::relay`] gets.
    next_id: u32,
    free_surface: Vec<bool>,
    detached: Vec<bool>,
    active: usize,
    // Midpoint stage.
    s_pos: Vec<Vec3<T>>,
    s_vel: Vec<Vec3<T>>,
    s_rho: Vec<T>,
    s_sigma: Vec<Sym3<T>>,
    s_state: Vec<PointState<T>>,
    packed: Vec<Packed<T>>,
    moduli: Vec<Moduli<T>>,
    rates: Vec<Rate<T>>,
    // Markers, in their original order.
    m_pos: Vec<Vec3<T>>,
    m_vel: Vec<Vec3<T>>,
    m_acc: Vec<Vec3<T>>,
    m_owner: Vec<u32>,
    /// Coulomb μ of each marker owner (`INFINITY`: rough); empty while every owner is rough.
    owner_mu: Vec<T>,
    /// Wall normal of each marker (original order) for smooth and frictional contact; zero
    /// where none was given (the marker stays rough).
    m_normal: Vec<Vec3<T>>,
    m_force: Vec<Vec3<T>>,
    /// Diagonal pair moment of each marker's force (original order), while recorded
    /// ([`CpuSph::record_marker_moments`]); empty otherwise.
    m_moment: Vec<Vec3<T>>,
    // Markers inside the grid, walls then bodies, each in cell order (index k ↔ original
    // ms_orig[k]).
    ms_pos: Vec<Vec3<T>>,
    ms_vel: Vec<Vec3<T>>,
    ms_acc: Vec<Vec3<T>>,
    /// Sorted markers with soil in reach this step; `m_packed`, `ms_force` and the rows of
    /// `nl_ms` are indexed like it, and `nl_sm` lists rows of it.
    touched: Vec<u32>,
    m_packed: Vec<Packed<T>>,
    ms_force: Vec<Vec3<T>>,
    /// `m_moment` of the touched markers (empty unless recorded).
    ms_moment: Vec<Vec3<T>>,
    /// Marker kinematics changed since the markers were last sorted.
    markers_dirty: bool,
    m_volume: T,
    ref_rho: T,
    ref_cs: T,
    grid: GridSpec,
    idx: CellIndexer<T>,
    soil_sort: CellSort,
    /// Fixed-wall (owner 0) and body markers, original indices.
    wall_ids: Vec<u32>,
    body_ids: Vec<u32>,
    wall_sort: CellSort,
    body_sort: CellSort,
    walls_sorted: bool,
    /// Walls inside the grid: the first `n_wall_sorted` sorted markers.
    n_wall_sorted: usize,
    /// Original index of each sorted marker.
    ms_orig: Vec<u32>,
    nl_ss: NeighborList,
    nl_sm: NeighborList,
    nl_ms: NeighborList,
    scratch: Scratch<T>,
    time: f64,
    steps: u64,
    c_max: f64,
    marker_impulse: [f64; 3],
    owner_impulse: Vec<[f64; 3]>,
    // Active region (see `crate::active`). Soil order: awake | extended | asleep | escaped.
    region: ActiveRegion,
    awake: usize,
    near: usize,
    ext_sort: CellSort,
    // Verlet lists (see `lists_still_hold`).
    /// Skin length (m); 0 rebuilds every step.
    skin: f64,
    /// The lists were built for the current particle order and marker set.
    lists_valid: bool,
    /// Whether the lists were built with the active region kept.
    lists_partitioned: bool,
    /// Awake positions at the last build (soil order).
    x_ref: Vec<Vec3<T>>,
    /// Body-marker positions at the last build (order of `body_ids`), and whether each was
    /// inside the grid.
    bm_ref: Vec<Vec3<T>>,
    bm_inside: Vec<bool>,
    /// Largest body-marker displacement since the last build (m).
    bm_moved: f64,
    /// Largest move from a step's start to its midpoint stage, last step (m).
    stage_motion: f64,
    list_builds: u64,
    /// Steps made again from fresh lists because the midpoint stage left the skin.
    stage_retries: u64,
    // Wet scenes (see `wet`); empty for dry ones.
    wet: Option<WetSetup<T>>,
    /// The water's densities were set from the porosity the soil gives them at the start.
    water_ready: bool,
    phase: Vec<wet::Phase<T>>,
    pore: Vec<wet::Pore<T>>,
    /// Drag rate λ of each particle at the last evaluation (1/s).
    drag_rate: Vec<T>,
    /// The markers' water records (the soil's are `m_packed`) and coupling shares.
    m_packed_w: Vec<Packed<T>>,
    m_pore: Vec<wet::MarkerPore<T>>,
    /// Owners whose markers water passes through (empty: none).
    owner_permeable: Vec<bool>,
    /// Whether each touched marker is permeable (wet scenes).
    m_permeable: Vec<bool>,
}

/// Calls a rate function instantiated for the effects that are on: each combination is its
/// own monomorphised loop, so an effect that is off costs nothing per pair.
macro_rules! dispatch_effects {
    ($visc:expr, $xsph:expr, $ppst:expr, $fs:expr, $f:ident :: <$t:ty, $k:ty> ($($arg:expr),* $(,)?)) => {
        match ($visc, $xsph, $ppst, $fs) {
            (true, true, true, true) => $f::<$t, $k, true, true, true, true>($($arg),*),
            (true, true, false, true) => $f::<$t, $k, true, true, false, true>($($arg),*),
            (true, false, true, true) => $f::<$t, $k, true, false, true, true>($($arg),*),
            (true, false, false, true) => $f::<$t, $k, true, false, false, true>($($arg),*),
            (false, true, true, true) => $f::<$t, $k, false, true, true, true>($($arg),*),
            (false, true, false, true) => $f::<$t, $k, false, true, false, true>($($arg),*),
            (false, false, true, true) => $f::<$t, $k, false, false, true, true>($($arg),*),
            (false, false, false, true) => $f::<$t, $k, false, false, false, true>($($arg),*),
            (true, true, true, false) => $f::<$t, $k, true, true, true, false>($($arg),*),
            (true, true, false, false) => $f::<$t, $k, true, true, false, false>($($arg),*),
            (true, false, true, false) => $f::<$t, $k, true, false, true, false>($($arg),*),
            (true, false, false, false) => $f::<$t, $k, true, false, false, false>($($arg),*),
            (false, true, true, false) => $f::<$t, $k, false, true, true, false>($($arg),*),
            (false, true, false, false) => $f::<$t, $k, false, true, false, false>($($arg),*),
            (false, false, true, false) => $f::<$t, $k, false, false, true, false>($($arg),*),
            (false, false, false, false) => $f::<$t, $k, false, false, false, false>($($arg),*),
        }
    };
}

impl<T: Real> CpuSph<T> {
    /// Builds the solver. `domain` bounds everything that can take part: a soil particle that
    /// leaves it is counted as escaped and no longer integrated.
    pub fn new(
        cfg: SolverConfig,
        materials: Vec<Material<T>>,
        particles: &[ParticleInit],
        markers: &[MarkerInit],
        domain: ([f64; 3], [f64; 3]),
    ) -> Result<Self, SolverError> {
        if materials.is_empty() {
            return Err(SolverError::Setup("no materials".into()));
        }
        if let Some(p) = particles.iter().find(|p| p.material as usize >= materials.len()) {
            return Err(SolverError::Setup(format!("particle material index {} out of range", p.material)));
        }
        if let Some(p) = particles.iter().find(|p| !(p.rho > 0.0 && p.mass > 0.0)) {
            return Err(SolverError::Setup(format!("particle at {:?} has non-positive density or mass", p.pos)));
        }
        if particles.len() >= u32::MAX as usize || markers.len() >= u32::MAX as usize {
            return Err(SolverError::Setup("too many particles".into()));
        }
        if !(cfg.neighbor_skin.is_finite() && (0.0..=crate::config::MAX_NEIGHBOR_SKIN).contains(&cfg.neighbor_skin)) {
            return Err(SolverError::Setup(format!(
                "neighbour skin {} h is outside [0, {}] h",
                cfg.neighbor_skin,
                crate::config::MAX_NEIGHBOR_SKIN
            )));
        }
        let h = cfg.h();
        let wet = WetSetup::of(&materials, lattice_sums(&cfg), cfg.drag).map_err(SolverError::Setup)?;
        let grid = GridSpec::covering(domain.0, domain.1, h);
        let n = particles.len();
        let n_wet = if wet.is_some() { n } else { 0 };
        let ref_rho = materials.iter().map(|m| m.density.as_f64()).fold(0.0, f64::max);
        let ref_cs = materials.iter().map(|m| m.wave_speed().as_f64()).fold(0.0, f64::max);
        let consts = PairConsts {
            h: T::of(h),
            inv_h: T::of(1.0 / h),
            alpha: match cfg.kernel {
                KernelKind::Wendland => <WendlandC2 as Kernel<T>>::alpha(T::of(h)),
                KernelKind::Cubic => <CubicSpline as Kernel<T>>::alpha(T::of(h)),
            },
            support2: T::of(4.0 * h * h),
            visc_alpha: T::of(cfg.artificial_viscosity),
            eta2: T::of(0.01 * h * h),
            gravity: Vec3::of(cfg.gravity),
        };
        let v3 = |f: &dyn Fn(&ParticleInit) -> [f64; 3]| -> Vec<Vec3<T>> {
            particles.iter().map(|p| Vec3::of(f(p))).collect()
        };
        let nm = markers.len();
        Ok(Self {
            cfg,
            consts,
            pos: v3(&|p| p.pos),
            vel: v3(&|p| p.vel),
            rho: particles.iter().map(|p| T::of(p.rho)).collect(),
            sigma: particles.iter().map(|p| Sym3::of(p.sigma)).collect(),
            state: particles.iter().map(|p| PointState { pc: T::of(p.pc), v: T::of(p.specific_volume) }).collect(),
            material: particles.iter().map(|p| p.material).collect(),
            mass: particles.iter().map(|p| T::of(p.mass)).collect(),
            id: (0..n as u32).collect(),
            next_id: n as u32,
            free_surface: vec![false; n],
            detached: vec![false; n],
            active: n,
            s_pos: vec![Vec3::zero(); n],
            s_vel: vec![Vec3::zero(); n],
            s_rho: vec![T::zero(); n],
            s_sigma: vec![Sym3::zero(); n],
            s_state: vec![PointState::default(); n],
            packed: vec![Packed::default(); n],
            moduli: vec![Moduli { bulk: T::zero(), shear: T::zero() }; n],
            rates: vec![Rate::default(); n],
            m_pos: markers.iter().map(|m| Vec3::of(m.pos)).collect(),
            m_vel: vec![Vec3::zero(); nm],
            m_acc: vec![Vec3::zero(); nm],
            m_owner: markers.iter().map(|m| m.owner).collect(),
            owner_mu: Vec::new(),
            m_normal: Vec::new(),
            m_force: vec![Vec3::zero(); nm],
            m_moment: Vec::new(),
            ms_pos: Vec::new(),
            ms_vel: Vec::new(),
            ms_acc: Vec::new(),
            touched: Vec::new(),
            m_packed: Vec::new(),
            ms_force: Vec::new(),
            ms_moment: Vec::new(),
            markers_dirty: true,
            m_volume: T::of(cfg.spacing.powi(3)),
            ref_rho: T::of(ref_rho),
            ref_cs: T::of(ref_cs),
            materials,
            idx: CellIndexer::new(&grid),
            grid,
            soil_sort: CellSort::default(),
            wall_ids: (0..nm as u32).filter(|&k| markers[k as usize].owner == 0).collect(),
            body_ids: (0..nm as u32).filter(|&k| markers[k as usize].owner != 0).collect(),
            wall_sort: CellSort::default(),
            body_sort: CellSort::default(),
            walls_sorted: false,
            n_wall_sorted: 0,
            ms_orig: Vec::new(),
            nl_ss: NeighborList::default(),
            nl_sm: NeighborList::default(),
            nl_ms: NeighborList::default(),
            scratch: Scratch::default(),
            time: 0.0,
            steps: 0,
            c_max: ref_cs,
            marker_impulse: [0.0; 3],
            owner_impulse: vec![[0.0; 3]; markers.iter().map(|m| m.owner as usize + 1).max().unwrap_or(1)],
            region: ActiveRegion::default(),
            awake: n,
            near: n,
            ext_sort: CellSort::default(),
            skin: cfg.neighbor_skin * h,
            lists_valid: false,
            lists_partitioned: false,
            x_ref: Vec::new(),
            bm_ref: Vec::new(),
            bm_inside: Vec::new(),
            bm_moved: 0.0,
            stage_motion: 0.0,
            list_builds: 0,
            stage_retries: 0,
            wet,
            water_ready: false,
            phase: vec![wet::Phase::default(); n_wet],
            pore: vec![wet::Pore::default(); n_wet],
            drag_rate: vec![T::zero(); n_wet],
            m_packed_w: Vec::new(),
            m_pore: Vec::new(),
            owner_permeable: Vec::new(),
            m_permeable: Vec::new(),
        })
    }

    /// Whether the scene has a water phase.
    pub fn is_wet(&self) -> bool {
        self.wet.is_some()
    }

    /// Solver settings.
    pub fn config(&self) -> &SolverConfig {
        &self.cfg
    }
    /// Materials, by index.
    pub fn materials(&self) -> &[Material<T>] {
        &self.materials
    }
    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }
    /// The neighbour grid.
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }
    /// Total number of soil particles (active and escaped).
    pub fn len(&self) -> usize {
        self.pos.len()
    }
    /// True when there are no soil particles.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }
    /// Particles still inside the domain; they are the first `active()` entries of every array.
    pub fn active(&self) -> usize {
        self.active
    }
    /// Particles integrated in the last step: the first `awake()` entries of every array
    /// (all of `active()` unless an active region is kept).
    pub fn awake(&self) -> usize {
        self.awake
    }
    /// Awake and extended particles (extended ones: `awake()..near()`).
    pub fn near(&self) -> usize {
        self.near
    }
    /// Classifications of the active region made so far.
    pub fn classifications(&self) -> u64 {
        self.region.classifications()
    }
    /// Neighbour-list builds so far (one per step without a Verlet skin).
    pub fn list_builds(&self) -> u64 {
        self.list_builds
    }
    /// Steps whose first stage was made again from fresh lists, because the midpoint stage
    /// moved some particle or marker out of the skin (counted in [`Self::list_builds`] too).
    pub fn stage_retries(&self) -> u64 {
        self.stage_retries
    }
    /// Keeps an active region from now on (`None`: the whole domain is awake). `domain.boxes`
    /// has one box per FSI body, in marker-owner order (owner `k + 1` is box `k`).
    pub fn set_active_domain(&mut self, domain: Option<ActiveDomain>) -> Result<(), SolverError> {
        self.region.set(domain, self.owner_impulse.len() - 1, self.wet.is_some()).map_err(SolverError::Setup)?;
        self.lists_valid = false;
        Ok(())
    }
    /// Places the active-region boxes from the bodies' states (owner order).
    pub fn place_boxes(&mut self, states: &[BodyState]) {
        self.region.place(states);
    }
    /// The roles the particles would get if classified now, with the boxes placed at
    /// `states` (what `regolith check` reports before a run; ignores the free-flow time).
    pub fn expected_roles(&self, states: &[BodyState]) -> Option<RoleCounts> {
        let n = self.active;
        self.region.expected(&self.grid, &self.pos[..n], &self.vel[..n], 2.0 * self.cfg.h(), states)
    }
    /// Positions (m), cell-sorted.
    pub fn positions(&self) -> &[Vec3<T>] {
        &self.pos
    }
    /// Velocities (m/s).
    pub fn velocities(&self) -> &[Vec3<T>] {
        &self.vel
    }
    /// Densities (kg/m³).
    pub fn densities(&self) -> &[T] {
        &self.rho
    }
    /// Cauchy stresses (Pa, tension positive).
    pub fn stresses(&self) -> &[Sym3<T>] {
        &self.sigma
    }
    /// State variables (p_c, specific volume).
    pub fn states(&self) -> &[PointState<T>] {
        &self.state
    }
    /// Material index of each particle.
    pub fn material_ids(&self) -> &[u16] {
        &self.material
    }
    /// Masses (kg).
    pub fn masses(&self) -> &[T] {
        &self.mass
    }
    /// Original index of each particle (as passed to `new`).
    pub fn ids(&self) -> &[u32] {
        &self.id
    }
    /// Free-surface flags of the last step.
    pub fn free_surface(&self) -> &[bool] {
        &self.free_surface
    }
    /// Detached flags of the last step (see [`crate::config::DETACHED_THRESHOLD`]): these
    /// particles carry no stress.
    pub fn detached(&self) -> &[bool] {
        &self.detached
    }
    /// Free-surface indicator of the last step's first stage: the smallest eigenvalue of
    /// `Σ V_b (x_b − x_a) ⊗ ∇W_ab` (1 in the bulk, about 0.5 in a flat top layer).
    pub fn free_surface_measure(&self) -> Vec<T> {
        self.rates[..self.awake].iter().map(|r| r.fs).collect()
    }
    /// Accelerations of the last stage used for the update (m/s²).
    pub fn accelerations(&self) -> Vec<Vec3<T>> {
        self.rates[..self.awake].iter().map(|r| r.acc).collect()
    }
    /// Marker positions (m), original order.
    pub fn marker_positions(&self) -> &[Vec3<T>] {
        &self.m_pos
    }
    /// Sets how soil slides along the markers of each owner (`contact[0]` the fixed walls,
    /// `contact[k + 1]` body k; owners past the end are rough), with the wall's unit normal into
    /// the soil at each marker (original order; markers past the end of `normals`, or with a
    /// zero normal, stay rough). A coefficient that is negative or not finite, or a normal
    /// that is not zero or unit, is an error. All rough leaves the solver bit-identical to no
    /// call.
    pub fn set_wall_contact(
        &mut self,
        contact: &[crate::config::WallContact],
        normals: &[[f64; 3]],
    ) -> Result<(), SolverError> {
        crate::config::WallContact::check(contact, normals, self.m_owner.len()).map_err(SolverError::Setup)?;
        let owners = self.m_owner.iter().map(|&o| o as usize + 1).max().unwrap_or(0).max(contact.len());
        if contact.iter().all(|c| *c == crate::config::WallContact::Rough) {
            self.owner_mu = Vec::new();
            self.m_normal = Vec::new();
        } else {
            self.owner_mu = (0..owners).map(|o| T::of(contact.get(o).map_or(f64::INFINITY, |c| c.mu()))).collect();
            self.m_normal =
                (0..self.m_owner.len()).map(|i| normals.get(i).map_or(Vec3::zero(), |n| Vec3::of(*n))).collect();
        }
        Ok(())
    }
    /// Makes the markers of the owners flagged in `permeable` (`[0]` the fixed walls, `[k + 1]`
    /// body k) permeable to water: a filter that holds the soil and lets the water through.
    /// Refused in a dry scene, where it would mean nothing.
    pub fn set_permeable(&mut self, permeable: &[bool]) -> Result<(), SolverError> {
        if self.wet.is_none() && permeable.iter().any(|p| *p) {
            return Err(SolverError::Setup("permeable markers need water in the scene".into()));
        }
        self.owner_permeable = permeable.to_vec();
        Ok(())
    }
    /// Marker owners (0 = fixed walls, k + 1 = body k), original order.
    pub fn marker_owners(&self) -> &[u32] {
        &self.m_owner
    }
    /// Force on each marker from the soil during the last step's final stage (N), original
    /// order.
    pub fn marker_forces(&self) -> &[Vec3<T>] {
        &self.m_force
    }
    /// Records from the next step on, beside each marker's force, the diagonal of its pair
    /// moment `Σ_a (x_a − x_m) ∘ f_am` over the soil particles `a` that push it (N m, original
    /// order, [`CpuSph::marker_moments`]): what a mean stress from the walls' forces needs to
    /// take each force at the particle it acts on rather than at the marker. Dry soil only:
    /// a wet scene's marker forces carry the pore pressure's terms too, and are refused.
    pub fn record_marker_moments(&mut self) -> Result<(), SolverError> {
        if self.wet.is_some() {
            return Err(SolverError::Setup(
                "marker moments are recorded for dry soil only (the scene has water)".into(),
            ));
        }
        self.m_moment = vec![Vec3::zero(); self.m_pos.len()];
        self.ms_moment = vec![Vec3::zero(); self.ms_force.len()];
        Ok(())
    }
    /// The diagonal pair moment of each marker's force during the last step's final stage
    /// (N m, original order; see [`CpuSph::record_marker_moments`]); empty unless recorded.
    pub fn marker_moments(&self) -> &[Vec3<T>] {
        &self.m_moment
    }
    /// Prescribed marker kinematics (original order), for markers that belong to moving
    /// bodies. Taking it marks every marker, fixed walls included, for re-sorting at the next
    /// step; [`CpuSph::set_marker_range`] re-sorts only what it moves.
    pub fn marker_kinematics_mut(&mut self) -> MarkerKinematics<'_, T> {
        self.markers_dirty = true;
        self.walls_sorted = false;
        MarkerKinematics { pos: &mut self.m_pos, vel: &mut self.m_vel, acc: &mut self.m_acc, owner: &self.m_owner }
    }
    /// Sets the kinematics of the markers `first..first + pos.len()` (original order); the
    /// fixed walls are sorted again only if the range holds some.
    pub fn set_marker_range(&mut self, first: usize, pos: &[Vec3<T>], vel: &[Vec3<T>], acc: &[Vec3<T>]) {
        let r = first..first + pos.len();
        self.m_pos[r.clone()].copy_from_slice(pos);
        self.m_vel[r.clone()].copy_from_slice(vel);
        self.m_acc[r.clone()].copy_from_slice(acc);
        self.markers_dirty = true;
        if self.m_owner[r].contains(&0) {
            self.walls_sorted = false;
        }
    }
    /// Total impulse the markers have exerted on the soil since the start (N s).
    pub fn marker_impulse(&self) -> [f64; 3] {
        self.marker_impulse
    }
    /// Impulse the markers of each owner (0 = walls, k + 1 = body k) have exerted on the soil
    /// since the start (N s).
    pub fn owner_impulse(&self) -> &[[f64; 3]] {
        &self.owner_impulse
    }
    /// Total mass of the active soil (kg).
    pub fn active_mass(&self) -> f64 {
        self.mass[..self.active].iter().map(|m| m.as_f64()).sum()
    }
    /// Total mass of all soil particles, escaped included (kg).
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().map(|m| m.as_f64()).sum()
    }
    /// Total momentum of the active soil (kg m/s).
    pub fn momentum(&self) -> [f64; 3] {
        let mut p = [0.0; 3];
        for i in 0..self.active {
            let v = self.vel[i].as_f64();
            let m = self.mass[i].as_f64();
            for a in 0..3 {
                p[a] += m * v[a];
            }
        }
        p
    }

    /// Moves a patch of the bed forward along x: lifts every soil particle inside the domain
    /// with `x < cut`, lays `fresh` in their place (ids counting on from the highest so far,
    /// at rest unless `fresh` says otherwise) and shifts the fixed walls by `shift` along x.
    /// Escaped particles behind the cut are lifted too; those ahead stay escaped. The next
    /// step sorts, lists and classifies afresh. Returns how many particles were lifted.
    pub fn relay(&mut self, cut: f64, shift: f64, fresh: &[ParticleInit]) -> Result<usize, SolverError> {
        if self.wet.is_some() {
            return Err(SolverError::Setup("a moving patch does not carry water yet".into()));
        }
        ParticleInit::check_laid(fresh, self.materials.len())?;
        let (active, cut) = (self.active, T::of(cut));
        let kept: Vec<usize> = (0..active).filter(|&i| self.pos[i].x >= cut).collect();
        // Escaped particles behind the cut go too (thrown over the back wall: they are gone
        // with the soil they left); those ahead stay escaped.
        let escaped: Vec<usize> = (active..self.pos.len()).filter(|&i| self.pos[i].x >= cut).collect();
        let lifted = self.pos.len() - kept.len() - escaped.len();
        if self.next_id as usize + fresh.len() >= u32::MAX as usize {
            return Err(SolverError::Setup("too many particles laid by the moving patch (ids exhausted)".into()));
        }
        // Kept (in their order) | fresh | escaped.
        let f = fresh.iter();
        self.pos = relaid(&self.pos, (&kept, &escaped), f.clone().map(|p| Vec3::of(p.pos)));
        self.vel = relaid(&self.vel, (&kept, &escaped), f.clone().map(|p| Vec3::of(p.vel)));
        self.rho = relaid(&self.rho, (&kept, &escaped), f.clone().map(|p| T::of(p.rho)));
        self.sigma = relaid(&self.sigma, (&kept, &escaped), f.clone().map(|p| Sym3::of(p.sigma)));
        self.state = relaid(
            &self.state,
            (&kept, &escaped),
            f.clone().map(|p| PointState { pc: T::of(p.pc), v: T::of(p.specific_volume) }),
        );
        self.material = relaid(&self.material, (&kept, &escaped), f.clone().map(|p| p.material));
        self.mass = relaid(&self.mass, (&kept, &escaped), f.clone().map(|p| T::of(p.mass)));
        let first = self.next_id;
        self.id = relaid(&self.id, (&kept, &escaped), (first..).take(fresh.len()));
        self.next_id = first + fresh.len() as u32;
        self.free_surface = relaid(&self.free_surface, (&kept, &escaped), f.clone().map(|_| false));
        self.detached = relaid(&self.detached, (&kept, &escaped), f.map(|_| false));
        let n = self.pos.len();
        self.s_pos.resize(n, Vec3::zero());
        self.s_vel.resize(n, Vec3::zero());
        self.s_rho.resize(n, T::zero());
        self.s_sigma.resize(n, Sym3::zero());
        self.s_state.resize(n, PointState::default());
        self.packed.resize(n, Packed::default());
        self.moduli.resize(n, Moduli { bulk: T::zero(), shear: T::zero() });
        self.rates.resize(n, Rate::default());
        self.active = kept.len() + fresh.len();
        self.awake = self.active;
        self.near = self.active;
        // Shift the walls; the whole order changed: sort, list and classify again.
        let dx = T::of(shift);
        for &o in &self.wall_ids {
            let m = &mut self.m_pos[o as usize];
            m.x += dx;
        }
        self.walls_sorted = false;
        self.markers_dirty = true;
        self.region.forget();
        self.lists_valid = false;
        self.x_ref.clear();
        Ok(lifted)
    }

    /// Reorders every per-particle array over `lo..lo + order.len()`: the particle at
    /// `lo + k` becomes the one that was at `lo + order[k]`.
    fn permute_soil(&mut self, lo: usize, order: &[u32]) {
        let s = &mut self.scratch;
        let r = lo..lo + order.len();
        macro_rules! perm {
            ($v:expr, $tmp:expr) => {{
                let src = &$v[r.clone()];
                $tmp.clear();
                $tmp.resize(order.len(), Default::default());
                $tmp.par_iter_mut().zip(order.par_iter()).for_each(|(t, &o)| *t = src[o as usize]);
                $v[r.clone()].copy_from_slice(&$tmp);
            }};
        }
        perm!(self.pos, s.v3);
        perm!(self.vel, s.v3);
        perm!(self.rho, s.t);
        perm!(self.sigma, s.sym);
        perm!(self.state, s.st);
        perm!(self.material, s.u16);
        perm!(self.mass, s.t);
        perm!(self.id, s.u32);
        perm!(self.free_surface, s.b);
        perm!(self.detached, s.b);
    }

    /// Sorts the awake particles (the first `awake`) by cell; those that left the grid go to
    /// the end of the awake block.
    fn sort_awake(&mut self) {
        self.soil_sort.sort(&self.idx, &self.pos[..self.awake]);
        let order = std::mem::take(&mut self.soil_sort.order);
        self.permute_soil(0, &order);
        self.soil_sort.order = order;
    }

    /// True while the active region is kept (see [`ActiveRegion::partitioned`]).
    fn partitioned(&self) -> bool {
        self.region.partitioned(self.time)
    }

    /// Every awake particle (just sorted) is inside the grid and in a cell awake particles may
    /// be in since the last classification (one it held, or a neighbour of one).
    fn awake_still_covered(&self) -> bool {
        self.soil_sort.inside() == self.awake
            && self.pos[..self.awake].par_iter().all(|p| {
                self.idx.coords(*p).is_some_and(|c| self.region.awake_cells().get(self.idx.linear(c)) == Some(&true))
            })
    }

    /// Gives every particle inside the domain its role (see [`crate::active`]) and reorders
    /// the arrays into awake | extended (cell-sorted) | asleep | escaped.
    fn classify(&mut self) {
        if self.region.domain().is_none() {
            return;
        }
        let n = self.active;
        let Classification { order, count } =
            self.region.classify(&self.grid, &self.pos[..n], &self.vel[..n], 2.0 * self.cfg.h());
        self.permute_soil(0, &order);
        self.awake = count[0];
        self.near = count[0] + count[1];
        self.active = self.near + count[2];
        // The extended block is cell-sorted once: it does not move until the next
        // classification.
        self.ext_sort.sort(&self.idx, &self.pos[self.awake..self.near]);
        let ext_order = std::mem::take(&mut self.ext_sort.order);
        self.permute_soil(self.awake, &ext_order);
        self.ext_sort.order = ext_order;
        // Frozen particles read the same state at both stages.
        let r = self.awake..self.near;
        self.s_pos[r.clone()].copy_from_slice(&self.pos[r.clone()]);
        self.s_vel[r.clone()].copy_from_slice(&self.vel[r.clone()]);
        self.s_rho[r.clone()].copy_from_slice(&self.rho[r.clone()]);
        self.s_sigma[r.clone()].copy_from_slice(&self.sigma[r.clone()]);
        self.s_state[r.clone()].copy_from_slice(&self.state[r]);
    }

    /// Sorts and builds the neighbour lists, or keeps the last ones when they still hold
    /// every pair within 2h (see [`CpuSph::lists_still_hold`]); `force` always rebuilds.
    /// Returns whether it rebuilt.
    fn sort_and_search(&mut self, force: bool) -> bool {
        if !force && self.lists_still_hold() {
            if self.markers_dirty {
                // Same sorted marker set and order; new kinematics.
                self.gather_markers();
            }
            return false;
        }
        self.build_lists();
        true
    }

    /// Copies the markers' kinematics into sorted order (`ms_orig`).
    fn gather_markers(&mut self) {
        let mo = &self.ms_orig;
        self.ms_pos.clear();
        self.ms_pos.extend(mo.iter().map(|&o| self.m_pos[o as usize]));
        self.ms_vel.clear();
        self.ms_vel.extend(mo.iter().map(|&o| self.m_vel[o as usize]));
        self.ms_acc.clear();
        self.ms_acc.extend(mo.iter().map(|&o| self.m_acc[o as usize]));
        self.markers_dirty = false;
    }

    /// True when the lists of the last build still list every pair closer than 2h at this
    /// step's two stages, so that reusing them gives exactly the pairs a rebuild would. A pair
    /// closer than 2h now was closer than 2h + D_a + D_b at the build, D being how far each
    /// point has moved since; it is listed if D_a + D_b ≤ skin. Soil moves within a step (the
    /// midpoint stage is checked again in [`CpuSph::step`]); markers only between steps. Also
    /// false when the particle order must change: a particle left the grid, an awake one left
    /// the cells it may occupy, the active region needs a new classification or was switched
    /// on or off, or fixed walls moved.
    fn lists_still_hold(&mut self) -> bool {
        if self.skin <= 0.0 || !self.lists_valid || !self.walls_sorted {
            return false;
        }
        let partitioned = self.partitioned();
        if partitioned != self.lists_partitioned || (partitioned && self.region.needs_classification()) {
            return false;
        }
        let n = self.awake;
        if self.x_ref.len() != n {
            return false;
        }
        let (idx, cells) = (&self.idx, self.region.awake_cells());
        let moved = self.pos[..n]
            .par_iter()
            .zip(self.x_ref.par_iter())
            .map(|(p, r)| match idx.coords(*p) {
                Some(c) if !partitioned || cells.get(idx.linear(c)) == Some(&true) => (*p - *r).norm().as_f64(),
                _ => f64::INFINITY,
            })
            .reduce(|| 0.0, f64::max);
        if self.markers_dirty {
            let (m_pos, grid_idx) = (&self.m_pos, &self.idx);
            let bm = self
                .body_ids
                .par_iter()
                .zip(self.bm_ref.par_iter().zip(self.bm_inside.par_iter()))
                .map(|(&o, (r, &inside))| {
                    let p = m_pos[o as usize];
                    if grid_idx.coords(p).is_some() == inside { (p - *r).norm().as_f64() } else { f64::INFINITY }
                })
                .reduce(|| 0.0, f64::max);
            self.bm_moved = bm;
        }
        // The midpoint stage will have moved about as far as last step's did.
        let soil = moved + 1.5 * self.stage_motion;
        within_skin(soil, self.bm_moved, self.skin)
    }

    fn build_lists(&mut self) {
        if self.partitioned() {
            if self.region.needs_classification() {
                self.classify();
            }
            self.sort_awake();
            if !self.awake_still_covered() {
                self.classify();
                self.sort_awake();
            }
        } else {
            // The whole domain is awake.
            self.region.forget();
            self.awake = self.active;
            self.sort_awake();
            self.active = self.soil_sort.inside();
            self.awake = self.active;
            self.near = self.active;
        }

        // Markers: fixed walls are sorted once; bodies re-sort when their kinematics change.
        // Sorted markers are walls (cell order) then bodies (cell order); `ms_orig` maps each
        // back to its original index.
        if !self.walls_sorted {
            let wall_pos: Vec<Vec3<T>> = self.wall_ids.iter().map(|&o| self.m_pos[o as usize]).collect();
            self.wall_sort.sort(&self.idx, &wall_pos);
            let inside = self.wall_sort.inside();
            self.ms_orig.clear();
            self.ms_orig.extend(self.wall_sort.order[..inside].iter().map(|&k| self.wall_ids[k as usize]));
            self.n_wall_sorted = inside;
            self.walls_sorted = true;
            self.markers_dirty = true;
        }
        if self.markers_dirty {
            let body_pos: Vec<Vec3<T>> = self.body_ids.iter().map(|&o| self.m_pos[o as usize]).collect();
            self.body_sort.sort(&self.idx, &body_pos);
            let inside = self.body_sort.inside();
            self.ms_orig.truncate(self.n_wall_sorted);
            self.ms_orig.extend(self.body_sort.order[..inside].iter().map(|&k| self.body_ids[k as usize]));
            self.gather_markers();
        }

        let radius = T::of(2.0 * self.cfg.h() + self.skin);
        let (awake, near) = (&self.pos[..self.awake], &self.pos[..self.near]);
        let mut groups = vec![TargetGroup { sort: &self.soil_sort, targets: awake, offset: 0 }];
        if self.near > self.awake {
            groups.push(TargetGroup {
                sort: &self.ext_sort,
                targets: &self.pos[self.awake..self.near],
                offset: self.awake as u32,
            });
        }
        self.nl_ss.build_groups(awake, &self.idx, &groups, radius, true);
        // Extended particles query the markers too, so that a marker's extrapolation sees all
        // the soil a full-domain run would give it next to awake soil.
        let nw = self.n_wall_sorted;
        let marker_groups = [
            TargetGroup { sort: &self.wall_sort, targets: &self.ms_pos[..nw], offset: 0 },
            TargetGroup { sort: &self.body_sort, targets: &self.ms_pos[nw..], offset: nw as u32 },
        ];
        self.nl_sm.build_groups(near, &self.idx, &marker_groups, radius, false);
        // Only markers with soil in reach take part: the marker→soil list is the transpose.
        self.nl_ms.transpose_compact(&mut self.nl_sm, self.ms_pos.len(), &mut self.touched);
        self.m_packed.resize(self.touched.len(), Packed::default());
        self.ms_force.resize(self.touched.len(), Vec3::zero());
        if !self.m_moment.is_empty() {
            self.ms_moment.resize(self.touched.len(), Vec3::zero());
        }
        if self.wet.is_some() {
            self.m_packed_w.resize(self.touched.len(), Packed::default());
            self.m_pore.resize(self.touched.len(), wet::MarkerPore::default());
        }
        // References for the reuse test.
        self.list_builds += 1;
        self.lists_partitioned = self.partitioned();
        if self.skin > 0.0 {
            self.x_ref.clear();
            self.x_ref.extend_from_slice(&self.pos[..self.awake]);
            self.bm_ref.clear();
            self.bm_ref.extend(self.body_ids.iter().map(|&o| self.m_pos[o as usize]));
            self.bm_inside.clear();
            self.bm_inside.extend(self.bm_ref.iter().map(|p| self.idx.coords(*p).is_some()));
            self.bm_moved = 0.0;
            self.lists_valid = true;
        }
    }

    fn evaluate(&mut self, from_stage: bool, with_forces: bool) {
        match self.cfg.kernel {
            KernelKind::Wendland => self.evaluate_k::<WendlandC2>(from_stage, with_forces),
            KernelKind::Cubic => self.evaluate_k::<CubicSpline>(from_stage, with_forces),
        }
    }

    /// Packs the records and moduli of the awake and extended particles from the current state
    /// or (`from_stage`) the midpoint one.
    fn pack(&mut self, from_stage: bool) {
        let m = self.near;
        let (pos, vel, rho, sigma, state) = if from_stage {
            (&self.s_pos[..m], &self.s_vel[..m], &self.s_rho[..m], &self.s_sigma[..m], &self.s_state[..m])
        } else {
            (&self.pos[..m], &self.vel[..m], &self.rho[..m], &self.sigma[..m], &self.state[..m])
        };
        let view =
            rates::SoilView { pos, vel, rho, sigma, state, material: &self.material[..m], mass: &self.mass[..m] };
        rates::pack_soil(&self.materials, &view, &mut self.packed[..m], &mut self.moduli[..m]);
    }

    fn evaluate_k<K: Kernel<T>>(&mut self, from_stage: bool, with_forces: bool) {
        if let Some(setup) = self.wet {
            return self.evaluate_wet::<K>(setup, from_stage, with_forces);
        }
        // Rates for the awake particles; records for the awake and extended ones.
        let (n, m) = (self.awake, self.near);
        self.pack(from_stage);
        let sigma = if from_stage { &self.s_sigma[..m] } else { &self.sigma[..m] };
        let c = self.consts;
        self.c_max = self.packed[..n].par_iter().map(|p| p.cs.as_f64()).reduce(|| self.ref_cs.as_f64(), f64::max);
        rates::extrapolate_markers::<T, K, _>(
            &c,
            &self.ms_pos,
            &self.ms_vel,
            &self.ms_acc,
            self.m_volume,
            self.ref_rho,
            self.ref_cs,
            &self.touched,
            &self.nl_ms,
            &self.packed[..m],
            |a| Some((sigma[a], self.packed[a].rho)),
            (!self.owner_mu.is_empty()).then_some(rates::ContactView {
                orig: &self.ms_orig,
                owner: &self.m_owner,
                normal: &self.m_normal,
                mu: &self.owner_mu,
            }),
            &mut self.m_packed,
        );
        let visc = self.cfg.artificial_viscosity > 0.0;
        let (xsph, ppst) = (self.cfg.shifting.xsph(), self.cfg.shifting.ppst());
        use rates::soil_rates;
        dispatch_effects!(
            visc,
            xsph,
            ppst,
            !from_stage,
            soil_rates::<T, K>(
                &c,
                &self.packed[..m],
                &self.m_packed,
                &self.nl_ss,
                &self.nl_sm,
                sigma,
                &self.moduli[..m],
                &mut self.rates[..n]
            )
        );
        if with_forces {
            if visc {
                rates::marker_forces::<T, K, true>(
                    &c,
                    &self.packed[..n],
                    &self.m_packed,
                    &self.nl_ms,
                    &mut self.ms_force,
                    &mut self.ms_moment,
                );
            } else {
                rates::marker_forces::<T, K, false>(
                    &c,
                    &self.packed[..n],
                    &self.m_packed,
                    &self.nl_ms,
                    &mut self.ms_force,
                    &mut self.ms_moment,
                );
            }
        }
    }

    /// The packing and marker passes of a wet evaluation, up to the porosity: records packed,
    /// phases known, the markers' solid shares, the water's porosity, pressure and partial
    /// stress, the soil's saturation.
    fn wet_pores<K: Kernel<T>>(&mut self, setup: &WetSetup<T>, from_stage: bool) {
        let m = self.near;
        let c = self.consts;
        self.pack(from_stage);
        let setup = *setup;
        wet::phases(&setup, &self.materials, &self.material[..m], &self.mass[..m], &mut self.phase[..m]);
        wet::marker_solids::<T, K>(
            &c,
            &self.ms_pos,
            &self.ms_vel,
            self.m_volume,
            &self.touched,
            &self.nl_ms,
            &self.packed[..m],
            &self.phase[..m],
            &mut self.m_pore,
        );
        let (orig, owner, perm) = (&self.ms_orig, &self.m_owner, &self.owner_permeable);
        self.m_permeable.clear();
        self.m_permeable.extend(
            self.touched.iter().map(|&k| perm.get(owner[orig[k as usize] as usize] as usize).copied().unwrap_or(false)),
        );
        let (touched, ms_pos) = (&self.touched, &self.ms_pos);
        wet::porosity::<T, K>(
            &c,
            &setup,
            &self.nl_ss,
            &self.nl_sm,
            &self.phase[..m],
            &self.m_pore,
            (&self.m_permeable, self.m_volume),
            |k| ms_pos[touched[k] as usize],
            &mut self.packed[..m],
            &mut self.pore[..m],
        );
        wet::soil_pressures::<T, K>(&c, &self.nl_ss, &self.packed[..m], &self.phase[..m], &mut self.pore[..m]);
    }

    /// A rate evaluation of a wet scene (see [`wet`]); the dry one is [`Self::evaluate_k`].
    fn evaluate_wet<K: Kernel<T>>(&mut self, setup: WetSetup<T>, from_stage: bool, with_forces: bool) {
        self.wet_pores::<K>(&setup, from_stage);
        let (n, m) = (self.awake, self.near);
        let sigma = if from_stage { &self.s_sigma[..m] } else { &self.sigma[..m] };
        let c = self.consts;

        self.c_max = self.packed[..n].par_iter().map(|p| p.cs.as_f64()).reduce(|| self.ref_cs.as_f64(), f64::max);
        let contact = (!self.owner_mu.is_empty()).then_some(rates::ContactView {
            orig: &self.ms_orig,
            owner: &self.m_owner,
            normal: &self.m_normal,
            mu: &self.owner_mu,
        });
        let (packed, phase, pore) = (&self.packed[..m], &self.phase[..m], &self.pore[..m]);
        // The soil's record of each marker, with the hydrostatic step of the effective stress:
        // a saturated soil weighs ρ − ρ_w (1 − n) in its own stress.
        rates::extrapolate_markers::<T, K, _>(
            &c,
            &self.ms_pos,
            &self.ms_vel,
            &self.ms_acc,
            self.m_volume,
            self.ref_rho,
            self.ref_cs,
            &self.touched,
            &self.nl_ms,
            packed,
            |a| {
                let ph = &phase[a];
                (!ph.water).then(|| (sigma[a], packed[a].rho - setup.rest * ph.vg / packed[a].vol * pore[a].sat))
            },
            contact,
            &mut self.m_packed,
        );
        wet::marker_pressures::<T, K>(
            &c,
            &setup,
            &self.ms_pos,
            &self.ms_acc,
            &self.touched,
            &self.nl_ms,
            packed,
            phase,
            pore,
            &mut self.m_pore,
        );
        // The water's record: its stress −p I, stepped with its intrinsic density; walls are
        // smooth or rough for it as for the soil.
        rates::extrapolate_markers::<T, K, _>(
            &c,
            &self.ms_pos,
            &self.ms_vel,
            &self.ms_acc,
            self.m_volume,
            setup.rest,
            setup.water.sound_speed,
            &self.touched,
            &self.nl_ms,
            packed,
            |a| phase[a].water.then(|| (Sym3::iso(-pore[a].p), packed[a].rho / pore[a].n)),
            contact,
            &mut self.m_packed_w,
        );
        let visc = self.cfg.artificial_viscosity > 0.0;
        let (xsph, ppst) = (self.cfg.shifting.xsph(), self.cfg.shifting.ppst());
        use wet::wet_rates;
        dispatch_effects!(
            visc,
            xsph,
            ppst,
            !from_stage,
            wet_rates::<T, K>(
                &c,
                &setup,
                packed,
                &self.m_packed,
                &self.m_packed_w,
                (&self.m_pore, &self.m_permeable),
                phase,
                pore,
                (&self.nl_ss, &self.nl_sm),
                sigma,
                &self.moduli[..m],
                &mut self.rates[..n],
                &mut self.drag_rate[..n]
            )
        );
        if with_forces {
            wet::wet_marker_forces::<T, K>(
                &c,
                (visc, setup.lattice_sum),
                &self.packed[..n],
                (&self.m_packed, &self.m_packed_w),
                (&self.m_pore, &self.m_permeable),
                phase,
                pore,
                &self.nl_ms,
                &mut self.ms_force,
            );
        }
    }

    /// Sets each water particle's partial density from the porosity the soil gives it where it
    /// starts and the pore pressure it was given (its initial stress −p I): `ρ̄ = n ρ_w(p)`, so
    /// that the discrete porosity, not the nominal one, starts the water at that pressure; and
    /// its mass so that it starts with the volume of its lattice cell, `m / ρ̄ = d0³`.
    fn init_water(&mut self) {
        let Some(setup) = self.wet else { return };
        match self.cfg.kernel {
            KernelKind::Wendland => self.wet_pores::<WendlandC2>(&setup, false),
            KernelKind::Cubic => self.wet_pores::<CubicSpline>(&setup, false),
        }
        let m = self.near;
        let (phase, pore, sigma) = (&self.phase[..m], &self.pore[..m], &self.sigma[..m]);
        // Each water particle starts with the volume of its lattice cell, `m / ρ̄ = d0³`,
        // wherever it sits: its mass follows the porosity it reads. The generator's mass
        // (`n0 ρ_w d0³` in the soil, `ρ_w d0³` in free water) is right only away from the
        // soil's faces; at a face the water's SPH partition of space would otherwise be uneven
        // (up to 1 / n0 in volume) just where the drainage boundary is.
        let vol = T::of(self.cfg.spacing.powi(3));
        self.rho[..m].par_iter_mut().zip(self.mass[..m].par_iter_mut()).enumerate().for_each(|(i, (r, ms))| {
            if phase[i].water {
                *r = pore[i].n * setup.water.density_at(sigma[i].pressure().max(T::zero()), setup.rest);
                *ms = *r * vol;
            }
        });
        self.water_ready = true;
    }

    fn choose_dt(&self, limit: Option<f64>) -> f64 {
        let dt = match self.cfg.time_step {
            TimeStep::Fixed(dt) => dt,
            TimeStep::Adaptive { cfl, max } => {
                let h = self.cfg.h();
                let n = self.awake;
                let vmax = self.vel[..n].par_iter().map(|v| v.norm().as_f64()).reduce(|| 0.0, f64::max);
                let amax = self.rates[..n].par_iter().map(|r| r.acc.norm().as_f64()).reduce(|| 0.0, f64::max);
                let mut dt = cfl * h / (self.c_max + vmax);
                if amax > 0.0 {
                    dt = dt.min(cfl * (h / amax).sqrt());
                }
                if self.wet.is_some() {
                    // Explicit drag: stable below 2 / λ.
                    let lambda = self.drag_rate[..n].par_iter().map(|l| l.as_f64()).reduce(|| 0.0, f64::max);
                    if lambda > 0.0 {
                        dt = dt.min(1.0 / lambda);
                    }
                }
                dt.min(max)
            }
        };
        limit.map_or(dt, |l| dt.min(l))
    }

    /// Advances by one step of the configured (fixed or adaptive) size, at most `max_dt` when
    /// given (to land exactly on an output or end time).
    ///
    /// A small problem (fewer than [`SMALL_STEP`] particles and markers) runs its step on one
    /// of rayon's worker threads (`rayon::scope` hands it over once), so that the step's few
    /// dozen parallel loops start from inside the pool instead of each handing work over from
    /// the caller's thread and sleeping until it is done: there those handovers (a context
    /// switch each) cost more than the loops. The work is split the same way either way, so the
    /// results do not change (NOTES.md, "Where the suite's time goes").
    ///
    /// The step is compiled once per precision, in this crate ([`Real::by_precision`]), not
    /// again in every crate that steps a solver.
    pub fn step(&mut self, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
        match T::by_precision::<StepMut<'_>>(self) {
            ByPrecision::F32(sph) => step_f32(sph, max_dt),
            ByPrecision::F64(sph) => step_f64(sph, max_dt),
        }
    }

    fn step_generic(&mut self, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
        if self.len() + self.marker_positions().len() < SMALL_STEP {
            rayon::scope(|_| self.step_in_pool(max_dt))
        } else {
            self.step_in_pool(max_dt)
        }
    }

    fn step_in_pool(&mut self, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
        let rk2 = self.cfg.integrator == Integrator::Rk2;
        let mut force = false;
        let dt = loop {
            let rebuilt = self.sort_and_search(force);
            if self.wet.is_some() && !self.water_ready {
                self.init_water();
            }
            self.evaluate(false, !rk2);
            let n = self.awake;
            {
                // A particle with wall or body markers in its support is in contact, not free:
                // it keeps its stress, so that it resists penetration and carries basal
                // friction. Detachment counts the markers as neighbours (the indicator sums
                // over both): a parcel whose support neither soil nor markers fill is
                // detached, walls or not (a grain squeezed out between a grouser and a wall
                // otherwise keeps a stress no neighbour balances).
                let th = T::of(self.cfg.free_surface_threshold.unwrap_or(0.0));
                let detach = T::of(DETACHED_THRESHOLD);
                let rates = &self.rates[..n];
                self.free_surface[..n].par_iter_mut().zip(self.detached[..n].par_iter_mut()).enumerate().for_each(
                    |(i, (f, d))| {
                        let free = !rates[i].contact;
                        *f = free && rates[i].fs < th;
                        *d = rates[i].fs < detach;
                    },
                );
            }
            let dt = self.choose_dt(max_dt);
            if !(dt.is_finite() && dt > 0.0) {
                return Err(SolverError::Setup(format!("time step {dt} s is not positive")));
            }
            if !rk2 {
                break dt;
            }
            self.advance(dt, 0.5 * dt, true)?;
            if self.skin > 0.0 {
                // The midpoint positions must be covered too. Stage 1 wrote no state, so the
                // step is simply made again from fresh lists when they are not; fresh lists
                // are kept whatever the midpoint's move, as without a skin.
                let (pos, s_pos, x_ref) = (&self.pos[..n], &self.s_pos[..n], &self.x_ref[..n]);
                let (moved, stage) = s_pos
                    .par_iter()
                    .zip(x_ref.par_iter().zip(pos.par_iter()))
                    .map(|(s, (r, p))| ((*s - *r).norm().as_f64(), (*s - *p).norm().as_f64()))
                    .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
                self.stage_motion = stage;
                if !rebuilt && !within_skin(moved, self.bm_moved, self.skin) {
                    self.stage_retries += 1;
                    force = true;
                    continue;
                }
            }
            self.evaluate(true, true);
            break dt;
        };
        self.advance(dt, dt, false)?;
        let n = self.awake;
        if self.wet.is_some() {
            // A water particle's stress is its pore pressure (from the last evaluation).
            let (phase, pore) = (&self.phase[..n], &self.pore[..n]);
            self.sigma[..n].par_iter_mut().enumerate().for_each(|(i, s)| {
                if phase[i].water {
                    *s = Sym3::iso(-pore[i].p);
                }
            });
        }
        // Marker forces back to original order; impulse on the soil from the markers.
        let mut total = [0.0; 3];
        for f in self.m_force.iter_mut() {
            *f = Vec3::zero();
        }
        if !self.m_moment.is_empty() {
            self.m_moment.fill(Vec3::zero());
            for (k, &sorted) in self.touched.iter().enumerate() {
                self.m_moment[self.ms_orig[sorted as usize] as usize] = self.ms_moment[k];
            }
        }
        for (k, &sorted) in self.touched.iter().enumerate() {
            let o = self.ms_orig[sorted as usize] as usize;
            self.m_force[o] = self.ms_force[k];
            let f = self.ms_force[k].as_f64();
            for (t, fa) in total.iter_mut().zip(f) {
                *t += fa;
            }
            let own = &mut self.owner_impulse[self.m_owner[o] as usize];
            for (i, fa) in own.iter_mut().zip(f) {
                *i -= dt * fa;
            }
        }
        for (imp, t) in self.marker_impulse.iter_mut().zip(total) {
            *imp -= dt * t;
        }
        self.time += dt;
        self.steps += 1;
        let max_speed = self.vel[..n].par_iter().map(|v| v.norm().as_f64()).reduce(|| 0.0, f64::max);
        let max_accel = self.rates[..n].par_iter().map(|r| r.acc.norm().as_f64()).reduce(|| 0.0, f64::max);
        let (materials, floor) = (&self.materials, T::of(RAREFIED_DENSITY));
        let rarefied = self.rho[..n]
            .par_iter()
            .zip(self.material[..n].par_iter())
            .filter(|(r, m)| **r <= density_floor(&materials[**m as usize], floor))
            .count();
        Ok(StepReport {
            dt,
            max_speed,
            max_accel,
            active: self.active,
            awake: n,
            pairs: self.nl_ss.pairs() + self.nl_sm.pairs(),
            rarefied,
        })
    }

    /// Integrates from the current state with the latest rates over `dt_s`. With `to_stage`
    /// the result goes to the midpoint arrays; otherwise it replaces the current state (the
    /// positions then move with the midpoint velocity for RK2).
    fn advance(&mut self, dt: f64, dt_s: f64, to_stage: bool) -> Result<(), SolverError> {
        let n = self.awake;
        let h = T::of(dt_s);
        let eps = T::of(if self.cfg.shifting.xsph() { self.cfg.xsph_epsilon } else { 0.0 });
        let shift =
            if self.cfg.shifting.ppst() { T::of(self.cfg.shifting_coefficient * self.cfg.h()) } else { T::zero() };
        let max_shift = T::of(0.2 * self.cfg.spacing);
        let rk2 = self.cfg.integrator == Integrator::Rk2;
        let (step, time) = (self.steps, self.time + dt);
        let materials = &self.materials;
        let floor = T::of(RAREFIED_DENSITY);
        let rates = &self.rates[..n];
        let fsf = &self.free_surface[..n];
        let det = &self.detached[..n];
        let zero_surface = self.cfg.free_surface_stress == FreeSurfaceStress::Zero;
        let mats = &self.material[..n];
        let ids = &self.id[..n];
        let err_rheo = |i: usize, source: RheologyError| SolverError::Rheology { step, time, particle: ids[i], source };
        if to_stage {
            let (pos, vel, rho, sigma, state) =
                (&self.pos[..n], &self.vel[..n], &self.rho[..n], &self.sigma[..n], &self.state[..n]);
            self.s_pos[..n]
                .par_iter_mut()
                .zip(self.s_vel[..n].par_iter_mut())
                .zip(self.s_rho[..n].par_iter_mut())
                .zip(self.s_sigma[..n].par_iter_mut().zip(self.s_state[..n].par_iter_mut()))
                .enumerate()
                .try_for_each(|(i, (((sp, sv), sr), (ss, sst)))| {
                    let r = &rates[i];
                    *sv = vel[i] + r.acc * h;
                    *sp = pos[i] + (vel[i] + r.xsph * eps) * h;
                    *sr = at_least(rho[i] + r.drho * h, density_floor(&materials[mats[i] as usize], floor));
                    let (s, st) = correct(
                        &materials[mats[i] as usize],
                        &sigma[i],
                        &state[i],
                        r,
                        h,
                        det[i] || (zero_surface && fsf[i]),
                    )
                    .map_err(|e| err_rheo(i, e))?;
                    *ss = s;
                    *sst = st;
                    Ok(())
                })
        } else {
            let s_vel = &self.s_vel[..n];
            self.pos[..n]
                .par_iter_mut()
                .zip(self.vel[..n].par_iter_mut())
                .zip(self.rho[..n].par_iter_mut())
                .zip(self.sigma[..n].par_iter_mut().zip(self.state[..n].par_iter_mut()))
                .enumerate()
                .try_for_each(|(i, (((p, v), rh), (s, st)))| {
                    let r = &rates[i];
                    let v_old = *v;
                    *v = v_old + r.acc * h;
                    let v_move = if rk2 { s_vel[i] } else { *v };
                    let mut dx = (v_move + r.xsph * eps) * h;
                    if shift > T::zero() && !fsf[i] {
                        let mut d = r.grad_c * (-(shift * v_move.norm() * h));
                        let len = d.norm();
                        if len > max_shift {
                            d = d * (max_shift / len);
                        }
                        dx += d;
                    }
                    *p += dx;
                    *rh = at_least(*rh + r.drho * h, density_floor(&materials[mats[i] as usize], floor));
                    let (s_new, st_new) =
                        correct(&materials[mats[i] as usize], s, st, r, h, det[i] || (zero_surface && fsf[i]))
                            .map_err(|e| err_rheo(i, e))?;
                    *s = s_new;
                    *st = st_new;
                    if !p.is_finite() {
                        return Err(SolverError::NonFinite { step, time, particle: ids[i], what: "position" });
                    }
                    if !v.is_finite() {
                        return Err(SolverError::NonFinite { step, time, particle: ids[i], what: "velocity" });
                    }
                    if !(rh.is_finite() && *rh > T::zero()) {
                        return Err(SolverError::NonFinite { step, time, particle: ids[i], what: "density" });
                    }
                    Ok(())
                })
        }
    }
}

/// The density below which a particle of `mat` is held (`floor` × the rest density; for
/// water, whose density is partial, `floor` × the smallest porosity × the rest density).
#[inline(always)]
fn density_floor<T: Real>(mat: &Material<T>, floor: T) -> T {
    if mat.is_water() { mat.density * floor * T::of(crate::rheology::MIN_POROSITY) } else { mat.density * floor }
}

/// The entries of `v` at `kept`, then `fresh`, then those at `escaped` (see
/// [`CpuSph::relay`]).
fn relaid<V: Copy>(v: &[V], (kept, escaped): (&[usize], &[usize]), fresh: impl Iterator<Item = V>) -> Vec<V> {
    let mut out = Vec::with_capacity(kept.len() + escaped.len() + fresh.size_hint().0);
    out.extend(kept.iter().map(|&i| v[i]));
    out.extend(fresh);
    out.extend(escaped.iter().map(|&i| v[i]));
    out
}

/// `Σ d0³ W(|x|)` over the points of a cubic lattice of spacing d0 (the particles' starting
/// lattice) seen from a lattice site, for the configured kernel and h; and the least fraction
/// of it seen from any point of a cell (searched on a grid of eighths of d0 over the eighth
/// of the cell that symmetry leaves).
pub fn lattice_sums(cfg: &SolverConfig) -> (f64, f64) {
    let (h, d0) = (cfg.h(), cfg.spacing);
    let reach = (2.0 * h / d0).ceil() as i64 + 1;
    let w = |r: f64| match cfg.kernel {
        KernelKind::Wendland => <WendlandC2 as Kernel<f64>>::w(r, 1.0 / h, <WendlandC2 as Kernel<f64>>::alpha(h)),
        KernelKind::Cubic => <CubicSpline as Kernel<f64>>::w(r, 1.0 / h, <CubicSpline as Kernel<f64>>::alpha(h)),
    };
    let sum_at = |o: [f64; 3]| {
        let mut sum = 0.0;
        for i in -reach..=reach {
            for j in -reach..=reach {
                for k in -reach..=reach {
                    let r =
                        d0 * ((i as f64 - o[0]).powi(2) + (j as f64 - o[1]).powi(2) + (k as f64 - o[2]).powi(2)).sqrt();
                    if r < 2.0 * h {
                        sum += d0 * d0 * d0 * w(r);
                    }
                }
            }
        }
        sum
    };
    let site = sum_at([0.0; 3]);
    let mut least: f64 = 1.0;
    for a in 0..=4 {
        for b in 0..=a {
            for c in 0..=b {
                least = least.min(sum_at([a as f64 / 8.0, b as f64 / 8.0, c as f64 / 8.0]) / site);
            }
        }
    }
    (site, least)
}

/// `x`, or `floor` when `x` is below it; NaN stays NaN (for the finiteness check that follows).
#[inline]
fn at_least<T: Real>(x: T, floor: T) -> T {
    if x < floor { floor } else { x }
}

/// Whether lists built with `skin` still hold every pair within the support after the soil
/// moved at most `soil` and the body markers at most `markers` (m) since their build: a
/// soil–soil pair needs `2 soil ≤ skin`, a soil–marker pair `soil + markers ≤ skin`. A part in
/// a thousand of the skin is kept back for round-off in the distance tests.
fn within_skin(soil: f64, markers: f64, skin: f64) -> bool {
    soil + soil.max(markers) <= 0.999 * skin
}

/// Stress update with the plastic correction: `σ + dt σ̇` corrected by the material, state from
/// the start of the step; stress-free particles (detached, or on the surface in the `Zero`
/// mode) carry no stress and do not harden.
#[inline]
fn correct<T: Real>(
    mat: &Material<T>,
    sigma: &Sym3<T>,
    state: &PointState<T>,
    r: &Rate<T>,
    dt: T,
    stress_free: bool,
) -> Result<(Sym3<T>, PointState<T>), RheologyError> {
    let mut st = *state;
    let s = if stress_free {
        Sym3::zero()
    } else {
        let trial = *sigma + r.dsigma * dt;
        mat.correct(trial, &mut st, r.moduli, &r.d)?
    };
    st.advance_volume(r.d.trace() * dt);
    Ok((s, st))
}

/// `&mut CpuSph<T>` as a [`PerPrecision`] family, for [`CpuSph::step`].
struct StepMut<'a>(std::marker::PhantomData<&'a ()>);

impl<'a> PerPrecision for StepMut<'a> {
    type Of<T: Real> = &'a mut CpuSph<T>;
}

/// The `f32` step, compiled here once (never inlined into another crate, which would compile
/// the generic step there again).
#[inline(never)]
fn step_f32(sph: &mut CpuSph<f32>, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
    sph.step_generic(max_dt)
}

/// The `f64` step, compiled here once.
#[inline(never)]
fn step_f64(sph: &mut CpuSph<f64>, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
    sph.step_generic(max_dt)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lattice sums against a direct evaluation (python, 11³ points): Wendland C2 at
    /// h = 1.2 d0 sums to 1.0175 at a site and, at the cell's centre, to 0.9728 of that;
    /// the dip deepens as h shrinks (0.948 at h = d0) and a wider kernel fills it.
    #[test]
    fn a_full_lattice_reads_least_at_the_cell_centre() {
        let (site, least) = lattice_sums(&SolverConfig::default());
        assert!((site - 1.0175).abs() < 5e-4, "{site}");
        assert!((least - 0.9728).abs() < 5e-4, "{least}");
        let narrow = lattice_sums(&SolverConfig { h_factor: 1.0, ..Default::default() }).1;
        let wide = lattice_sums(&SolverConfig { h_factor: 1.5, ..Default::default() }).1;
        assert!((narrow - 0.9484).abs() < 5e-4 && (wide - 0.9955).abs() < 5e-4, "{narrow} {wide}");
    }
}
