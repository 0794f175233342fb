//! The interface every soil backend offers the coupling layer and the run loop.
//!
//! [`CpuSph`](crate::cpu::CpuSph) implements it for `f32` and `f64`; the wgpu backend
//! (crate `regolith-wgpu`) for `f32`. Particle arrays are in the backend's own order (cell
//! order), and on a device backend they are a host copy refreshed by [`SphSolver::sync`]:
//! call it before reading particles.

use regolith_body::BodyState;

use crate::Real;
use crate::active::ActiveDomain;
use crate::config::SolverConfig;
use crate::cpu::CpuSph;
use crate::math::{Sym3, Vec3};
use crate::particles::{ParticleInit, SolverError, StepReport};
use crate::rheology::{Material, PointState};

/// The markers of one body: where they sit in the marker array and their body-frame positions.
#[derive(Clone, Copy, Debug)]
pub struct BodyMarkers<'a> {
    /// First marker (original order).
    pub first: usize,
    /// Body-frame positions (m), one per marker from `first` on.
    pub local: &'a [[f64; 3]],
}

/// Places body markers from body states on the host (in f64, rounded to `T`) and hands them to
/// the solver: what [`SphSolver::place_bodies`] does unless a backend places them itself.
pub fn place_on_host<T: Real, S: SphSolver<T> + ?Sized>(
    solver: &mut S,
    bodies: &[BodyMarkers<'_>],
    states: &[BodyState],
) {
    let (mut pos, mut vel, mut acc) = (Vec::new(), Vec::new(), Vec::new());
    for (b, s) in bodies.iter().zip(states) {
        pos.clear();
        vel.clear();
        acc.clear();
        for l in b.local {
            let [x, v, a] = s.point(*l);
            pos.push(Vec3::of(x));
            vel.push(Vec3::of(v));
            acc.push(Vec3::of(a));
        }
        solver.set_marker_kinematics(b.first, &pos, &vel, &acc);
    }
}

/// A soil solver.
pub trait SphSolver<T: Real>: Send {
    /// `"cpu"` or `"wgpu"`.
    fn backend(&self) -> &'static str;
    /// The device it runs on (`"cpu"` for the CPU backend).
    fn adapter(&self) -> String;
    /// Solver settings.
    fn config(&self) -> &SolverConfig;
    /// Materials, by index.
    fn materials(&self) -> &[Material<T>];
    /// Simulated time (s).
    fn time(&self) -> f64;
    /// Steps taken.
    fn steps(&self) -> u64;
    /// Soil particles, escaped included.
    fn len(&self) -> usize;
    /// True when there are no soil particles.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Particles inside the domain (the first `active()` entries).
    fn active(&self) -> usize;
    /// Particles integrated in the last step (the first `awake()`; all of `active()` unless an
    /// active region is kept).
    fn awake(&self) -> usize {
        self.active()
    }
    /// Keeps an active region (see [`crate::active`]) from now on, or the whole domain awake
    /// (`None`). Backends without active regions refuse `Some`.
    fn set_active_domain(&mut self, domain: Option<ActiveDomain>) -> Result<(), SolverError> {
        match domain {
            None => Ok(()),
            Some(_) => Err(SolverError::Setup(format!("the {} backend has no active domains", self.backend()))),
        }
    }
    /// Records, from the next step on, each marker's diagonal pair moment beside its force
    /// (see [`CpuSph::record_marker_moments`]). Backends that cannot refuse.
    fn record_marker_moments(&mut self) -> Result<(), SolverError> {
        Err(SolverError::Setup(format!(
            "the {} backend does not record marker moments; use backend = \"cpu\"",
            self.backend()
        )))
    }
    /// Each marker's diagonal pair moment of the last step (N m, original order); empty unless
    /// recorded.
    fn marker_moments(&self) -> &[Vec3<T>] {
        &[]
    }
    /// How soil slides along the markers of each owner (`contact[0]` the fixed walls,
    /// `contact[k + 1]` body k; owners past the end are rough), with each marker's wall normal
    /// into the soil (original order; zero or missing: rough). Backends without smooth or
    /// frictional walls refuse anything but rough.
    fn set_wall_contact(
        &mut self,
        contact: &[crate::config::WallContact],
        normals: &[[f64; 3]],
    ) -> Result<(), SolverError> {
        let _ = normals;
        match contact.iter().find(|c| **c != crate::config::WallContact::Rough) {
            None => Ok(()),
            Some(c) => Err(SolverError::Setup(format!(
                "the {} backend has rough walls only ({c:?} asked for); use backend = \"cpu\"",
                self.backend()
            ))),
        }
    }
    /// Makes the markers of the flagged owners (`[0]` the fixed walls, `[k + 1]` body k)
    /// permeable to water. Backends without water refuse any flag.
    fn set_permeable(&mut self, permeable: &[bool]) -> Result<(), SolverError> {
        if permeable.iter().any(|p| *p) {
            return Err(SolverError::Setup(format!("the {} backend has no water phase", self.backend())));
        }
        Ok(())
    }
    /// Classifications of the active region so far (0 without one).
    fn classifications(&self) -> u64 {
        0
    }
    /// Moves a patch of the bed forward along x (see [`CpuSph::relay`]): lifts the soil at
    /// `x < cut`, lays `fresh` particles and shifts the fixed walls by `shift`. Returns how
    /// many particles were lifted. Backends without moving patches refuse.
    fn relay(&mut self, cut: f64, shift: f64, fresh: &[ParticleInit]) -> Result<usize, SolverError> {
        let _ = (cut, shift, fresh);
        Err(SolverError::Setup(format!("the {} backend has no moving patch", self.backend())))
    }
    /// One step of at most `max_dt` (s).
    fn step(&mut self, max_dt: Option<f64>) -> Result<StepReport, SolverError>;
    /// Brings the host copy of the particles up to date (no-op on the CPU).
    fn sync(&mut self) -> Result<(), SolverError>;
    /// Positions (m).
    fn positions(&self) -> &[Vec3<T>];
    /// Velocities (m/s).
    fn velocities(&self) -> &[Vec3<T>];
    /// Densities (kg/m³).
    fn densities(&self) -> &[T];
    /// Cauchy stresses (Pa).
    fn stresses(&self) -> &[Sym3<T>];
    /// State variables.
    fn states(&self) -> &[PointState<T>];
    /// Material indices.
    fn material_ids(&self) -> &[u16];
    /// Masses (kg).
    fn masses(&self) -> &[T];
    /// Original particle indices.
    fn ids(&self) -> &[u32];
    /// Marker positions (m), original order (on the wgpu backend, as of the last
    /// `GpuSph::sync_diagnostics` or `set_marker_kinematics`).
    fn marker_positions(&self) -> &[Vec3<T>];
    /// Force on each marker from the soil in the last step (N), original order (on the wgpu
    /// backend, as of the last `GpuSph::sync_diagnostics`; bodies get their wrenches from
    /// [`SphSolver::body_wrenches`]).
    fn marker_forces(&self) -> &[Vec3<T>];
    /// Sets the kinematics of the markers `first..first + pos.len()` (original order).
    fn set_marker_kinematics(&mut self, first: usize, pos: &[Vec3<T>], vel: &[Vec3<T>], acc: &[Vec3<T>]);
    /// Places the markers of each body from its state (position, velocity, acceleration of
    /// every marker from the rigid motion). The wgpu backend keeps the body-frame positions on
    /// the device and takes only the states.
    fn place_bodies(&mut self, bodies: &[BodyMarkers<'_>], states: &[BodyState]) {
        place_on_host(self, bodies, states);
    }
    /// The force (N) and the torque about `about[k]` (N m) the soil exerted on each body's
    /// markers in the last step. The wgpu backend sums them on the device.
    fn body_wrenches(&self, bodies: &[BodyMarkers<'_>], about: &[[f64; 3]]) -> Vec<[[f64; 3]; 2]> {
        let f = self.marker_forces();
        let x = self.marker_positions();
        bodies
            .iter()
            .zip(about)
            .map(|(b, c)| {
                let (mut force, mut torque) = (Vec3::<f64>::zero(), Vec3::<f64>::zero());
                for i in b.first..b.first + b.local.len() {
                    let fi = Vec3::of(f[i].as_f64());
                    force += fi;
                    torque += (Vec3::of(x[i].as_f64()) - Vec3::of(*c)).cross(fi);
                }
                [force.as_f64(), torque.as_f64()]
            })
            .collect()
    }
    /// The shader variants compiled for this scene (empty on the CPU).
    fn variants(&self) -> Vec<String>;
    /// The CPU solver, when this is one (for diagnostics only it has: impulses, flags).
    fn as_cpu(&self) -> Option<&CpuSph<T>>;
    /// Total mass of the active soil (kg).
    fn active_mass(&self) -> f64 {
        self.masses()[..self.active()].iter().map(|m| m.as_f64()).sum()
    }
    /// Total mass of all particles (kg).
    fn total_mass(&self) -> f64 {
        self.masses().iter().map(|m| m.as_f64()).sum()
    }
    /// Momentum of the active soil (kg m/s).
    fn momentum(&self) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (v, m) in self.velocities()[..self.active()].iter().zip(self.masses()) {
            let v = v.as_f64();
            for a in 0..3 {
                p[a] += m.as_f64() * v[a];
            }
        }
        p
    }
}

impl<T: Real> SphSolver<T> for CpuSph<T> {
    fn backend(&self) -> &'static str {
        "cpu"
    }
    fn adapter(&self) -> String {
        "cpu".into()
    }
    fn config(&self) -> &SolverConfig {
        CpuSph::config(self)
    }
    fn materials(&self) -> &[Material<T>] {
        CpuSph::materials(self)
    }
    fn time(&self) -> f64 {
        CpuSph::time(self)
    }
    fn steps(&self) -> u64 {
        CpuSph::steps(self)
    }
    fn len(&self) -> usize {
        CpuSph::len(self)
    }
    fn active(&self) -> usize {
        CpuSph::active(self)
    }
    fn awake(&self) -> usize {
        CpuSph::awake(self)
    }
    fn set_active_domain(&mut self, domain: Option<ActiveDomain>) -> Result<(), SolverError> {
        CpuSph::set_active_domain(self, domain)
    }
    fn classifications(&self) -> u64 {
        CpuSph::classifications(self)
    }
    fn relay(&mut self, cut: f64, shift: f64, fresh: &[ParticleInit]) -> Result<usize, SolverError> {
        CpuSph::relay(self, cut, shift, fresh)
    }
    fn set_permeable(&mut self, permeable: &[bool]) -> Result<(), SolverError> {
        CpuSph::set_permeable(self, permeable)
    }
    fn set_wall_contact(
        &mut self,
        contact: &[crate::config::WallContact],
        normals: &[[f64; 3]],
    ) -> Result<(), SolverError> {
        CpuSph::set_wall_contact(self, contact, normals)
    }
    fn record_marker_moments(&mut self) -> Result<(), SolverError> {
        CpuSph::record_marker_moments(self)
    }
    fn marker_moments(&self) -> &[Vec3<T>] {
        CpuSph::marker_moments(self)
    }
    fn place_bodies(&mut self, bodies: &[BodyMarkers<'_>], states: &[BodyState]) {
        place_on_host(self, bodies, states);
        self.place_boxes(states);
    }
    fn step(&mut self, max_dt: Option<f64>) -> Result<StepReport, SolverError> {
        CpuSph::step(self, max_dt)
    }
    fn sync(&mut self) -> Result<(), SolverError> {
        Ok(())
    }
    fn positions(&self) -> &[Vec3<T>] {
        CpuSph::positions(self)
    }
    fn velocities(&self) -> &[Vec3<T>] {
        CpuSph::velocities(self)
    }
    fn densities(&self) -> &[T] {
        CpuSph::densities(self)
    }
    fn stresses(&self) -> &[Sym3<T>] {
        CpuSph::stresses(self)
    }
    fn states(&self) -> &[PointState<T>] {
        CpuSph::states(self)
    }
    fn material_ids(&self) -> &[u16] {
        CpuSph::material_ids(self)
    }
    fn masses(&self) -> &[T] {
        CpuSph::masses(self)
    }
    fn ids(&self) -> &[u32] {
        CpuSph::ids(self)
    }
    fn marker_positions(&self) -> &[Vec3<T>] {
        CpuSph::marker_positions(self)
    }
    fn marker_forces(&self) -> &[Vec3<T>] {
        CpuSph::marker_forces(self)
    }
    fn set_marker_kinematics(&mut self, first: usize, pos: &[Vec3<T>], vel: &[Vec3<T>], acc: &[Vec3<T>]) {
        self.set_marker_range(first, pos, vel, acc);
    }
    fn variants(&self) -> Vec<String> {
        Vec::new()
    }
    fn as_cpu(&self) -> Option<&CpuSph<T>> {
        Some(self)
    }
}
