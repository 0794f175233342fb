//! The interface every soil backend offers the coupling layer and the run loop.
//!
//! [`CpuSph`](crate::cpu::CpuSph) implements it for `f32` and `f64`; the wgpu backend
//! (crate `regolith-wgpu`) for `f32`. Particle arrays are in the backend's own order (cell
//! order), and on a device backend they are a host copy refreshed by [`SphSolver::sync`]:
//! call it before reading particles.

use crate::Real;
use crate::config::SolverConfig;
use crate::cpu::CpuSph;
use crate::math::{Sym3, Vec3};
use crate::particles::{SolverError, StepReport};
use crate::rheology::{Material, PointState};

/// A soil solver.
pub trait SphSolver<T: Real> {
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
    /// Marker positions (m), original order.
    fn marker_positions(&self) -> &[Vec3<T>];
    /// Force on each body marker from the soil in the last step (N), original order. The
    /// wgpu backend reads back only the markers of bodies (walls read zero).
    fn marker_forces(&self) -> &[Vec3<T>];
    /// Sets the kinematics of the markers `first..first + pos.len()` (original order).
    fn set_marker_kinematics(&mut self, first: usize, pos: &[Vec3<T>], vel: &[Vec3<T>], acc: &[Vec3<T>]);
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
        let k = self.marker_kinematics_mut();
        let r = first..first + pos.len();
        k.pos[r.clone()].copy_from_slice(pos);
        k.vel[r.clone()].copy_from_slice(vel);
        k.acc[r].copy_from_slice(acc);
    }
    fn variants(&self) -> Vec<String> {
        Vec::new()
    }
    fn as_cpu(&self) -> Option<&CpuSph<T>> {
        Some(self)
    }
}
