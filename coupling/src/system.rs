//! The co-simulation of SPH soil and rapier bodies.
//!
//! # Exchange schedule
//! Time advances in exchange intervals Δ (`exchange_interval`). One interval [t, t + Δ]:
//! 1. **Body states → markers.** Each FSI body's state at t (pose, velocities, accelerations
//!    of the last rigid step) places its markers. During the interval the markers move with
//!    the body's rigid motion extrapolated from t at constant velocity, so the soil never sees
//!    a body standing still between exchanges.
//! 2. **Fluid substeps** (the soil's own, usually adaptive, steps) cover [t, t + Δ] exactly.
//!    After each, the force on every marker from the soil (the exact negative of what the soil
//!    particles receive) is summed per body into a force and a torque about the body's centre
//!    of mass, weighted by the substep length.
//! 3. **Average.** The wrench is divided by Δ: the mean soil load over the interval.
//! 4. **Rigid substeps** cover [t, t + Δ] with that wrench applied at each body's centre of
//!    mass (rapier steps of at most `rigid_substep`).
//!
//! The first interval already runs with the soil's real force (the fluid goes first), so
//! there is no zero-force start. The lag: the soil during an interval reacts to the body
//! motion known at its start; the bodies during an interval feel the soil's mean force over
//! that same interval. Both are first-order in Δ; keep Δ at the soil's time step or a small
//! multiple of it (the default is 1 ms, about 10 to 20 soil steps for typical soils).

use std::ops::Range;

use regolith_body::{BodyState, Wrench};
use regolith_fsi::config::SolverConfig;
use regolith_fsi::cpu::CpuSph;
use regolith_fsi::rheology::Material;
use regolith_fsi::{BodyMarkers, MarkerInit, ParticleInit, Real, SolverError, SphSolver};
use regolith_rigid::{BodyId, Motion, RigidWorld};

use crate::CouplingError;

/// An FSI body of an [`FsiSystem`]: made only by the system, so it always names one of its
/// bodies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FsiBodyId(usize);

impl FsiBodyId {
    /// Position among the system's FSI bodies (their order in the marker array).
    pub fn index(self) -> usize {
        self.0
    }
}

/// A body that interacts with the soil.
#[derive(Clone, Debug, PartialEq)]
pub struct FsiBody {
    /// The rigid body.
    pub body: BodyId,
    /// Its markers' positions in the body frame (m).
    pub local: Vec<[f64; 3]>,
    /// Where its markers sit in the soil solver's marker array.
    pub markers: Range<usize>,
}

/// The body list and what crosses between soil and bodies.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FsiInterface {
    /// FSI bodies.
    pub bodies: Vec<FsiBody>,
    /// Mean soil wrench on each body over the last exchange interval.
    pub wrenches: Vec<Wrench>,
}

/// A body's state advanced by τ at constant linear and angular velocity.
pub fn extrapolate(s: &BodyState, tau: f64) -> BodyState {
    s.extrapolate(tau)
}

/// Builds the CPU soil solver (the default [`SolverMaker`]).
pub fn cpu_solver<T: Real>(
    config: SolverConfig,
    materials: Vec<Material<T>>,
    particles: &[ParticleInit],
    markers: &[MarkerInit],
    domain: ([f64; 3], [f64; 3]),
) -> Result<Box<dyn SphSolver<T>>, SolverError> {
    Ok(Box::new(CpuSph::new(config, materials, particles, markers, domain)?))
}

/// `domain` grown to hold a sphere of `radius` about `centre` (the neighbour grid must cover
/// every place a body's markers can reach).
pub fn grow_domain(domain: ([f64; 3], [f64; 3]), centre: [f64; 3], radius: f64) -> ([f64; 3], [f64; 3]) {
    let (mut lo, mut hi) = domain;
    for k in 0..3 {
        lo[k] = lo[k].min(centre[k] - radius);
        hi[k] = hi[k].max(centre[k] + radius);
    }
    (lo, hi)
}

/// The soil side of one exchange interval of length `delta`, whatever owns the bodies:
/// 1. before each soil substep, every body's markers are placed from its state at the
///    interval's start (`start`) extrapolated at constant velocity to the substep's start;
/// 2. the soil takes its own substeps until they cover the interval exactly;
/// 3. after each, the force on each body's markers (the negative of what the soil feels) is
///    summed into a force and a torque about the body's centre of mass at mid-substep,
///    weighted by the substep's length.
///
/// Returns the report, the mean wrench of each body over the interval, and the time covered.
pub fn soil_interval<T: Real>(
    fluid: &mut dyn SphSolver<T>,
    sets: &[BodyMarkers<'_>],
    start: &[BodyState],
    delta: f64,
) -> Result<(ExchangeReport, Vec<Wrench>, f64), SolverError> {
    let at = |tau: f64| -> Vec<BodyState> { start.iter().map(|s| s.extrapolate(tau)).collect() };
    let wrenches = |fluid: &dyn SphSolver<T>, states: &[BodyState]| -> Vec<Wrench> {
        let about: Vec<[f64; 3]> = states.iter().map(|s| s.com).collect();
        fluid.body_wrenches(sets, &about).into_iter().map(|[force, torque]| Wrench { force, torque }).collect()
    };
    let mut tau = 0.0;
    let mut sum = vec![Wrench::default(); start.len()];
    let mut report = ExchangeReport { dt_min: f64::INFINITY, ..Default::default() };
    while tau < delta * (1.0 - 1e-12) {
        fluid.place_bodies(sets, &at(tau));
        let r = fluid.step(Some(delta - tau))?;
        // Forces of the substep's final stage, torques about the mid-substep centre of mass.
        let mid = at(tau + 0.5 * r.dt);
        for (acc, w) in sum.iter_mut().zip(wrenches(&*fluid, &mid)) {
            *acc = acc.add_scaled(&w, r.dt);
        }
        tau += r.dt;
        report.fluid_steps += 1;
        report.max_speed = r.max_speed;
        report.pairs = r.pairs;
        report.rarefied_max = report.rarefied_max.max(r.rarefied);
        report.dt_min = report.dt_min.min(r.dt);
        report.dt_max = report.dt_max.max(r.dt);
    }
    let mean = sum.iter().map(|w| w.scaled(1.0 / tau)).collect();
    Ok((report, mean, tau))
}

impl FsiInterface {
    fn marker_sets(&self) -> Vec<BodyMarkers<'_>> {
        self.bodies.iter().map(|b| BodyMarkers { first: b.markers.start, local: &b.local }).collect()
    }

    /// Places every FSI body's markers (position, velocity, acceleration) from its state.
    pub fn place_markers<T: Real>(&self, fluid: &mut dyn SphSolver<T>, states: &[BodyState]) {
        fluid.place_bodies(&self.marker_sets(), states);
    }

    /// The soil's wrench on each body from the last step's marker forces, torques about
    /// `states'` centres of mass.
    pub fn wrenches<T: Real>(&self, fluid: &dyn SphSolver<T>, states: &[BodyState]) -> Vec<Wrench> {
        let about: Vec<[f64; 3]> = states.iter().map(|s| s.com).collect();
        fluid
            .body_wrenches(&self.marker_sets(), &about)
            .into_iter()
            .map(|[force, torque]| Wrench { force, torque })
            .collect()
    }
}

/// What one exchange interval did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExchangeReport {
    /// Time at the end of the interval (s).
    pub time: f64,
    /// Soil substeps taken.
    pub fluid_steps: u32,
    /// Rigid substeps taken.
    pub rigid_steps: u32,
    /// Largest soil particle speed at the end (m/s).
    pub max_speed: f64,
    /// Soil–soil and soil–marker pairs of the last substep.
    pub pairs: usize,
    /// Most soil particles held at the density floor after a substep (see
    /// `regolith_fsi::config::RAREFIED_DENSITY`).
    pub rarefied_max: usize,
    /// Smallest soil step of the interval (s).
    pub dt_min: f64,
    /// Largest soil step of the interval (s).
    pub dt_max: f64,
}

/// Soil, bodies and the interface between them.
pub struct FsiSystem<T: Real> {
    /// The SPH soil (CPU or wgpu backend).
    pub fluid: Box<dyn SphSolver<T>>,
    /// The rigid bodies.
    pub rigid: RigidWorld,
    /// What crosses between them.
    pub interface: FsiInterface,
    /// Exchange interval Δ (s).
    pub exchange_interval: f64,
    /// Largest rigid step (s).
    pub rigid_substep: f64,
    time: f64,
}

/// What the soil solver of an [`FsiSystem`] is built from.
pub struct SoilInit<'a, T> {
    /// Solver settings.
    pub config: SolverConfig,
    /// Materials.
    pub materials: Vec<Material<T>>,
    /// Soil particles.
    pub particles: &'a [ParticleInit],
    /// Fixed (wall) markers.
    pub wall_markers: &'a [MarkerInit],
    /// The neighbour grid's domain (min, max corners, m).
    pub domain: ([f64; 3], [f64; 3]),
}

/// Builds a soil solver from its settings, materials, particles, markers and domain: how a
/// caller picks the backend.
pub type SolverMaker<'a, T> = &'a dyn Fn(
    SolverConfig,
    Vec<Material<T>>,
    &[ParticleInit],
    &[MarkerInit],
    ([f64; 3], [f64; 3]),
) -> Result<Box<dyn SphSolver<T>>, SolverError>;

impl<T: Real> FsiSystem<T> {
    /// Builds the system on the CPU backend. Each `(body, local markers)` pair adds an FSI
    /// body whose markers are placed from the rigid world's current state.
    pub fn new(
        soil: SoilInit<'_, T>,
        rigid: RigidWorld,
        fsi_bodies: Vec<(BodyId, Vec<[f64; 3]>)>,
        exchange_interval: f64,
    ) -> Result<Self, CouplingError> {
        Self::with_solver(soil, rigid, fsi_bodies, exchange_interval, &cpu_solver::<T>)
    }

    /// As [`FsiSystem::new`], with the soil solver built by `make`.
    pub fn with_solver(
        soil: SoilInit<'_, T>,
        rigid: RigidWorld,
        fsi_bodies: Vec<(BodyId, Vec<[f64; 3]>)>,
        exchange_interval: f64,
        make: SolverMaker<'_, T>,
    ) -> Result<Self, CouplingError> {
        let SoilInit { config: fluid_config, materials, particles, wall_markers, domain } = soil;
        if !(exchange_interval > 0.0 && exchange_interval.is_finite()) {
            return Err(CouplingError::Invalid(format!("exchange interval {exchange_interval} s must be positive")));
        }
        let mut markers = wall_markers.to_vec();
        let mut bodies = Vec::new();
        for (k, (body, local)) in fsi_bodies.into_iter().enumerate() {
            let s = rigid.state(body);
            let start = markers.len();
            markers.extend(local.iter().map(|l| MarkerInit { pos: s.to_world(*l), owner: k as u32 + 1 }));
            bodies.push(FsiBody { body, local, markers: start..markers.len() });
        }
        let fluid = make(fluid_config, materials, particles, &markers, domain).map_err(CouplingError::Solver)?;
        let n = bodies.len();
        let mut sys = Self {
            fluid,
            rigid,
            interface: FsiInterface { bodies, wrenches: vec![Wrench::default(); n] },
            exchange_interval,
            rigid_substep: exchange_interval.min(1e-3),
            time: 0.0,
        };
        let states = sys.states_at(0.0);
        sys.interface.place_markers(sys.fluid.as_mut(), &states);
        Ok(sys)
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// FSI body states (marker order) extrapolated `tau` seconds past the rigid world's
    /// current state.
    pub fn states_at(&self, tau: f64) -> Vec<BodyState> {
        self.interface.bodies.iter().map(|b| extrapolate(&self.rigid.state(b.body), tau)).collect()
    }

    /// The FSI body of a rigid body, if it has markers.
    pub fn fsi_body(&self, body: BodyId) -> Option<FsiBodyId> {
        self.interface.bodies.iter().position(|b| b.body == body).map(FsiBodyId)
    }

    /// Every FSI body, in marker order.
    pub fn fsi_bodies(&self) -> impl Iterator<Item = FsiBodyId> + use<T> {
        (0..self.interface.bodies.len()).map(FsiBodyId)
    }

    /// Mean soil wrench on an FSI body over the last interval.
    pub fn wrench(&self, k: FsiBodyId) -> Wrench {
        self.interface.wrenches[k.0]
    }

    /// Advances one exchange interval (shorter if `max` is smaller, to land on an end time).
    pub fn advance(&mut self, max: Option<f64>) -> Result<ExchangeReport, SolverError> {
        let delta = max.map_or(self.exchange_interval, |m| m.min(self.exchange_interval));
        let t0 = self.time;
        // 1.–3. The soil over the interval, from the bodies' states at its start.
        let start: Vec<BodyState> = self.interface.bodies.iter().map(|b| self.rigid.state(b.body)).collect();
        let sets = self.interface.marker_sets();
        let (mut report, mean, tau) = soil_interval(self.fluid.as_mut(), &sets, &start, delta)?;
        self.interface.wrenches = mean;
        // 4. Rigid substeps with that wrench.
        for (b, w) in self.interface.bodies.iter().zip(&self.interface.wrenches) {
            if matches!(self.rigid.motion(b.body), Motion::Free) {
                self.rigid.set_wrench(b.body, w.force, w.torque);
            }
        }
        let substeps = (tau / self.rigid_substep).ceil().max(1.0) as u32;
        for _ in 0..substeps {
            self.rigid.step(tau / substeps as f64);
        }
        report.rigid_steps = substeps;
        self.time = t0 + tau;
        report.time = self.time;
        Ok(report)
    }
}
