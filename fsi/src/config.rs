//! Solver settings: what a scene's `[simulation]` and `[sph]` sections resolve to.

/// Default free-surface threshold on the smallest eigenvalue λ of `Σ V_b (x_b − x_a) ⊗ ∇W_ab`
/// (Marrone et al. 2010). On a resting lattice (Wendland and cubic kernels, h/d0 = 1.2–1.5),
/// λ is 1.0 in the bulk, at least 0.86 one layer below the surface, 0.49–0.5 in a flat top
/// layer and 0.19–0.3 at edges and corners. Unlike the trace `Σ V (−r·∇W)`, which drops to
/// 2.0–2.75 (from 3) throughout a sheared, disordered deposit and then flags its interior,
/// λ stays near 1 inside: the flag marks one-sided neighbourhoods only. 0.6 separates the top
/// layer from the next with margin; the free-surface test pins it.
pub const DEFAULT_FREE_SURFACE_THRESHOLD: f64 = 0.6;

/// Smoothing kernel. Support radius 2h for both.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelKind {
    /// Wendland C2 (default): no pairing instability, smooth.
    Wendland,
    /// Cubic B-spline (Monaghan).
    Cubic,
}

/// Time integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Explicit midpoint (second order, two rate evaluations per step). Default.
    Rk2,
    /// Symplectic-style explicit Euler (first order, one rate evaluation per step). The stress
    /// rate comes from the velocity gradient at the start of the step, so the elastic response
    /// is forward Euler on a wave equation: unstable for soil at rest (the accuracy study's
    /// geostatic bed blows apart), usable only where plastic flow damps it.
    Euler,
}

/// Time-step control.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeStep {
    /// Fixed step (s).
    Fixed(f64),
    /// `dt = C min(h / (c_s + |v|max), sqrt(h / |a|max))`, recomputed every step.
    Adaptive {
        /// Courant number C.
        cfl: f64,
        /// Upper bound on the step (s).
        max: f64,
    },
}

/// Default Verlet skin of the neighbour lists (multiple of h; see
/// [`SolverConfig::neighbor_skin`]).
pub const DEFAULT_NEIGHBOR_SKIN: f64 = 0.3;

/// Largest Verlet skin accepted, as a multiple of h.
pub const MAX_NEIGHBOR_SKIN: f64 = 1.0;

/// Below this value of the free-surface indicator λ a particle has almost no neighbours on
/// some side (λ ≤ 0.3 at the edges and corners of a resting block, 0 for an isolated particle):
/// it is detached from the soil and carries no stress, whatever the free-surface mode. Wall
/// and body markers count as neighbours: a particle against a wall has a full support, while
/// a parcel squeezed into a gap between two walls with little soil around it is detached.
pub const DETACHED_THRESHOLD: f64 = 0.2;

/// Lower bound of a soil particle's density, as a fraction of its material's bulk density ρ0.
///
/// A parcel spread to half its packed density is a granular gas (solid fraction below about
/// 0.3 for sands): its stress is already zero (the yield surfaces cut off tension), and the
/// continuity equation, evaluated over a support that the parcel's few neighbours no longer
/// fill, keeps lowering it. Its SPH volume m/ρ then grows without bound and enters every
/// neighbour's sums, which run away (a splash off a wall reached non-finite density this way).
/// The density is therefore held at `RAREFIED_DENSITY × ρ0` when continuity would take it
/// lower; compression raises it again as usual. Particles held there are counted every step
/// ([`crate::StepReport::rarefied`]); a bed, a wheel rut or a cone never comes near the bound.
pub const RAREFIED_DENSITY: f64 = 0.5;

/// What the free-surface flag does to the stress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FreeSurfaceStress {
    /// Surface particles keep their stress; only detached particles are stress-free (default).
    /// Zeroing the top layer imposes σ = 0 half a spacing inside the real surface, and the
    /// symmetric SPH stress gradient turns that step into an odd–even stress pattern that
    /// shifts a resting column by about ρ g d0/2 (9 % at mid-depth of a 12-layer bed).
    Keep,
    /// Surface particles carry zero stress and do not harden (Chrono's CRM behaviour).
    Zero,
}

/// Particle shifting (positions only), to keep the particle distribution regular.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shifting {
    /// None.
    None,
    /// XSPH velocity smoothing applied to the position update.
    Xsph,
    /// Particle shifting along the concentration gradient (PPST-style), switched off at the
    /// free surface.
    Ppst,
    /// Both.
    PpstXsph,
}

impl Shifting {
    /// True when XSPH is on.
    pub fn xsph(self) -> bool {
        matches!(self, Self::Xsph | Self::PpstXsph)
    }
    /// True when concentration-gradient shifting is on.
    pub fn ppst(self) -> bool {
        matches!(self, Self::Ppst | Self::PpstXsph)
    }
}

/// How the soil–water drag of a wet scene is spread between the particles of the two phases
/// (`[sph] drag`; see `cpu::wet`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Drag {
    /// Smooth volume fractions: each soil–water pair carries `C V_w V_s W / L` (L the kernel's
    /// lattice sum), so the drag a water particle feels fades with the soil volume in its
    /// support, across the faces of a soil layer over about h.
    #[default]
    Svf,
    /// Per particle ("bang-bang"): a water particle with any soil (or solid wall) in its
    /// support carries its whole drag `C V_w (v_w − v̄_s)`, spread over that soil by Shepard
    /// weights `V_s W / Σ V_s W`; the soil's volume fraction is an indicator, not smoothed.
    Particle,
}

/// How soil slides along a wall or a body's markers.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum WallContact {
    /// No slip (Adami's mirrored velocity), and the full extrapolated stress: the soil holds
    /// to the wall as it holds to itself (adhesive for cohesive soil).
    #[default]
    Rough,
    /// Free slip: no tangential traction, the tangential velocity carried through.
    Smooth,
    /// Coulomb friction: sliding soil meets a tangential traction of μ times the compressive
    /// normal one; below that the wall holds it (regularised: a creep of τ / (ρ c), see the
    /// CPU kernel). Free slip kinematics, so the wall adds no shear rate of its own.
    Friction(f64),
}

impl WallContact {
    /// The friction coefficient: `INFINITY` for rough, 0 for smooth.
    pub fn mu(self) -> f64 {
        match self {
            Self::Rough => f64::INFINITY,
            Self::Smooth => 0.0,
            Self::Friction(m) => m,
        }
    }

    /// Checks what a backend's `set_wall_contact` is given: at most one normal per marker
    /// (`markers` of them), each zero or of unit length, and finite, non-negative friction
    /// coefficients. The message names the marker or owner.
    pub fn check(contact: &[Self], normals: &[[f64; 3]], markers: usize) -> Result<(), String> {
        if normals.len() > markers {
            return Err(format!("{} wall normals for {markers} markers", normals.len()));
        }
        if let Some((i, n)) = normals.iter().enumerate().find(|(_, n)| {
            let l2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
            !(l2 == 0.0 || (l2 - 1.0).abs() < 1e-9)
        }) {
            return Err(format!("marker {i}: wall normal {n:?} is neither zero nor of unit length"));
        }
        for (o, c) in contact.iter().enumerate() {
            if let Self::Friction(m) = c
                && !(m.is_finite() && *m >= 0.0)
            {
                return Err(format!("owner {o}: friction coefficient {m} must be finite and ≥ 0"));
            }
        }
        Ok(())
    }
}

/// Everything the SPH solver needs besides particles and materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverConfig {
    /// Initial particle spacing d0 (m).
    pub spacing: f64,
    /// h / d0.
    pub h_factor: f64,
    /// Kernel.
    pub kernel: KernelKind,
    /// Integrator.
    pub integrator: Integrator,
    /// Time step.
    pub time_step: TimeStep,
    /// Artificial viscosity coefficient α.
    pub artificial_viscosity: f64,
    /// Shifting.
    pub shifting: Shifting,
    /// XSPH coefficient ε (fraction of the smoothed velocity difference).
    pub xsph_epsilon: f64,
    /// PPST shifting coefficient (dimensionless, scales h² |concentration gradient|).
    pub shifting_coefficient: f64,
    /// Free-surface threshold on the smallest eigenvalue of `Σ V_b (x_b − x_a) ⊗ ∇W_ab` (1 in
    /// the bulk); `None` disables the free-surface treatment.
    pub free_surface_threshold: Option<f64>,
    /// What happens to the stress of free-surface particles.
    pub free_surface_stress: FreeSurfaceStress,
    /// Gravity (m/s², world frame).
    pub gravity: [f64; 3],
    /// Layers of wall/body BCE markers.
    pub bce_layers: usize,
    /// Verlet skin of the neighbour lists, as a multiple of h: lists hold pairs within
    /// 2h + skin and are rebuilt only once some particle or body marker has moved far enough
    /// that a pair inside 2h could be missing (0: rebuild every step). Backends that do not
    /// reuse lists rebuild every step, which gives the same pairs.
    pub neighbor_skin: f64,
    /// Soil–water drag distribution (wet scenes only).
    pub drag: Drag,
}

impl SolverConfig {
    /// Smoothing length h = h_factor · d0 (m).
    pub fn h(&self) -> f64 {
        self.h_factor * self.spacing
    }
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            spacing: 0.01,
            h_factor: 1.2,
            kernel: KernelKind::Wendland,
            integrator: Integrator::Rk2,
            time_step: TimeStep::Adaptive { cfl: 0.3, max: 1e-3 },
            artificial_viscosity: 0.1,
            shifting: Shifting::Xsph,
            xsph_epsilon: 0.25,
            shifting_coefficient: 0.1,
            free_surface_threshold: Some(DEFAULT_FREE_SURFACE_THRESHOLD),
            free_surface_stress: FreeSurfaceStress::Keep,
            gravity: [0.0, 0.0, -9.81],
            bce_layers: 3,
            neighbor_skin: DEFAULT_NEIGHBOR_SKIN,
            drag: Drag::Svf,
        }
    }
}
