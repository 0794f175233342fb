//! A moving patch (`[terrain] patch = { length, trigger }`): the soil solver holds `length`
//! metres of a longer bed along x and moves forward with the scene's FSI bodies, so that a long
//! traverse costs what the patch costs.
//!
//! The patch is a slice of the container's lattice between two end walls (lattice columns
//! `a < b`, see [`regolith_terrain::build_terrain_in`]). When less than `trigger` metres of
//! soil lie ahead of the foremost FSI marker, the patch advances by whole spacings, far enough
//! that `trigger + 2h` lie ahead again: the soil behind the new back wall is lifted, the
//! columns between the old and the new front wall are laid in exactly the state the generator
//! gives them (geostatic stress, p_c, specific volume, density, at rest), and the walls'
//! markers shift with it (the side walls and floor are a lattice along x, so a whole-spacing
//! shift leaves them where a longer wall would have markers). What is laid ahead is the
//! undisturbed bed; what is lifted behind is gone (its ruts included). A body must stay at
//! least the kernel support (2h) ahead of the back wall, or the run stops with an error
//! naming `terrain.patch.length`.

use regolith_fsi::ParticleInit;
use regolith_fsi::rheology::Material;
use regolith_terrain::{Aabb, Lattice, RegionSpec, TerrainError, build_terrain_in};

use crate::scene::{PatchSpec, Scene};

/// The patch's place in the bed and what it needs to lay new soil.
#[derive(Clone, Debug)]
pub struct Patch {
    spec: PatchSpec,
    lattice: Lattice,
    container: Aabb,
    spacing: f64,
    bce_layers: usize,
    gravity: [f64; 3],
    regions: Vec<RegionSpec>,
    materials: Vec<Material<f64>>,
    /// Kernel support 2h (m).
    support: f64,
    /// Lattice columns of the back and front end walls.
    window: [i64; 2],
    /// Times it advanced, particles lifted and laid so far.
    advances: u64,
    lifted: u64,
    laid: u64,
    /// The file and key named by errors.
    file: String,
}

/// One advance: what the solver does (see `SphSolver::relay`).
#[derive(Clone, Debug)]
pub struct Relay {
    /// Soil at `x < cut` is lifted (m).
    pub cut: f64,
    /// The walls move this far along x (m).
    pub shift: f64,
    /// The soil laid ahead.
    pub fresh: Vec<ParticleInit>,
}

impl Patch {
    /// The patch of a scene at its start: the first `length` metres (whole spacings) of the
    /// container along x.
    pub(crate) fn new(
        scene: &Scene,
        spec: PatchSpec,
        regions: Vec<RegionSpec>,
        materials: Vec<Material<f64>>,
        container: &Aabb,
    ) -> Self {
        let d0 = scene.solver.spacing;
        let lattice = Lattice::of(container, d0);
        let b = ((spec.length / d0).round() as i64).clamp(4, lattice.n[0]);
        Self {
            spec,
            lattice,
            container: *container,
            spacing: d0,
            bce_layers: scene.solver.bce_layers,
            gravity: scene.solver.gravity,
            regions,
            materials,
            support: 2.0 * scene.solver.h(),
            window: [0, b],
            advances: 0,
            lifted: 0,
            laid: 0,
            file: scene.path.display().to_string(),
        }
    }

    /// Lattice columns of the back and front end walls now.
    pub fn window(&self) -> [i64; 2] {
        self.window
    }

    /// x of the back and front end walls now (m).
    pub fn span(&self) -> [f64; 2] {
        self.window.map(|i| self.lattice.point([i, 0, 0])[0])
    }

    /// How many times it advanced, and the particles lifted and laid in all.
    pub fn counts(&self) -> (u64, u64, u64) {
        (self.advances, self.lifted, self.laid)
    }

    /// The patch's settings.
    pub fn spec(&self) -> PatchSpec {
        self.spec
    }

    /// The soil and walls of a window (the lattice columns of its end walls), as the
    /// generator gives them.
    pub(crate) fn generate(&self, window: [i64; 2]) -> Result<regolith_terrain::TerrainBuild, TerrainError> {
        build_terrain_in(
            &self.container,
            self.spacing,
            self.bce_layers,
            self.gravity,
            &self.regions,
            &self.materials,
            Some(window),
        )
    }

    /// Advances the patch if less than `trigger` of soil lies ahead of `front` (the foremost
    /// FSI marker's x, m), and returns what the solver must do; `None` while enough lies ahead
    /// or the patch has reached the bed's end. `back` is the rearmost FSI marker's x: an
    /// advance that would put the back wall within 2h of it is an error.
    pub fn follow(&mut self, front: f64, back: f64) -> Result<Option<Relay>, String> {
        let [a, b] = self.window;
        let nx = self.lattice.n[0];
        let d0 = self.spacing;
        let x_front = self.lattice.point([b, 0, 0])[0];
        if b >= nx || front + self.spec.trigger <= x_front {
            return Ok(None);
        }
        let want = front + self.spec.trigger + self.support - x_front;
        let m = ((want / d0).ceil() as i64).clamp(1, nx - b);
        let new = [a + m, b + m];
        let x_back = self.lattice.point([new[0], 0, 0])[0];
        if back < x_back + self.support {
            return Err(format!(
                "{}: terrain.patch.length = {} m is too short for the scene's FSI bodies: they span x = {back:.3}..{front:.3} m, and keeping {} m of soil ahead would put the patch's back wall at x = {x_back:.3} m, within the kernel support ({:.3} m) of them; make it at least {:.3} m",
                self.file,
                self.spec.length,
                self.spec.trigger,
                self.support,
                (front - back) + self.spec.trigger + 2.0 * self.support + 2.0 * d0,
            ));
        }
        // Columns b .. b + m - 1 (the slice between the old front wall and the new one).
        let fresh = self.generate([b - 1, b + m]).map_err(|e| format!("{}: terrain.patch: {e}", self.file))?.particles;
        self.window = new;
        self.advances += 1;
        self.laid += fresh.len() as u64;
        // Soil behind the new back wall's plane plus half a spacing (the first soil column of a
        // wall sits one spacing in) is lifted.
        Ok(Some(Relay { cut: x_back + 0.5 * d0, shift: m as f64 * d0, fresh }))
    }

    /// Records how many particles the solver lifted.
    pub fn lifted(&mut self, n: usize) {
        self.lifted += n as u64;
    }
}
