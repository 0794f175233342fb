//! What the solver is built from: initial soil particles and boundary markers, and the errors
//! and reports of a step.

use crate::rheology::RheologyError;

/// One soil particle's initial state (SI units, world frame, tension-positive stress).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleInit {
    /// Position (m).
    pub pos: [f64; 3],
    /// Velocity (m/s).
    pub vel: [f64; 3],
    /// Density (kg/m³).
    pub rho: f64,
    /// Mass (kg).
    pub mass: f64,
    /// Cauchy stress xx, yy, zz, xy, xz, yz (Pa).
    pub sigma: [f64; 6],
    /// Preconsolidation pressure (Pa), MCC.
    pub pc: f64,
    /// Specific volume (MCC) or 1.
    pub specific_volume: f64,
    /// Index of the material.
    pub material: u16,
}

impl ParticleInit {
    /// Checks particles laid by a moving patch: a known material, a positive density and mass.
    pub fn check_laid(fresh: &[Self], materials: usize) -> Result<(), SolverError> {
        match fresh.iter().find(|p| p.material as usize >= materials || !(p.rho > 0.0 && p.mass > 0.0)) {
            None => Ok(()),
            Some(p) => Err(SolverError::Setup(format!(
                "particle laid at {:?} has material {} (of {materials}), density {} and mass {}",
                p.pos, p.material, p.rho, p.mass
            ))),
        }
    }
}

/// One boundary (BCE) marker. Markers of fixed walls never move; markers of bodies are moved
/// by the coupling layer every exchange.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkerInit {
    /// Position (m).
    pub pos: [f64; 3],
    /// Owner: 0 for fixed walls, `k + 1` for body `k`.
    pub owner: u32,
}

/// Why a step failed. The solver never replaces a bad value; it stops and says where.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// A constitutive update failed (e.g. a non-finite stress).
    #[error("step {step} (t = {time:.6e} s), particle {particle}: {source}")]
    Rheology {
        /// Step number.
        step: u64,
        /// Simulated time (s).
        time: f64,
        /// Original particle index.
        particle: u32,
        /// The model's error.
        source: RheologyError,
    },
    /// A position, velocity or density became NaN or infinite.
    #[error("step {step} (t = {time:.6e} s), particle {particle}: non-finite {what}")]
    NonFinite {
        /// Step number.
        step: u64,
        /// Simulated time (s).
        time: f64,
        /// Original particle index.
        particle: u32,
        /// Which quantity.
        what: &'static str,
    },
    /// The inputs are inconsistent.
    #[error("invalid setup: {0}")]
    Setup(String),
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Time step taken (s).
    pub dt: f64,
    /// Largest particle speed after the step (m/s).
    pub max_speed: f64,
    /// Largest particle acceleration of the step (m/s²).
    pub max_accel: f64,
    /// Soil particles still inside the domain.
    pub active: usize,
    /// Soil particles integrated this step (all of `active` unless an active region is kept).
    pub awake: usize,
    /// Soil–soil and soil–marker pairs listed per rate evaluation (within 2h + the Verlet skin
    /// on the CPU backend; those outside the support are skipped).
    pub pairs: usize,
    /// Soil particles whose density is held at its lower bound after the step (see
    /// [`crate::config::RAREFIED_DENSITY`]).
    pub rarefied: usize,
}
