//! Device record layouts: `#[repr(C)]` + `Pod` mirrors of the structs in `kernels/common.wgsl`
//! (every field 4 bytes, so WGSL's array strides equal `size_of`).

use bytemuck::{Pod, Zeroable};

/// Solver constants (uniform).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Params {
    pub origin: [f32; 3],
    pub inv_cell: f32,
    pub dims: [u32; 3],
    pub n_cells: u32,
    pub n: u32,
    pub nm: u32,
    pub reach: u32,
    pub radius2: f32,
    pub h: f32,
    pub inv_h: f32,
    pub alpha: f32,
    pub support2: f32,
    pub visc_alpha: f32,
    pub eta2: f32,
    pub m_volume: f32,
    pub ref_rho: f32,
    pub gravity: [f32; 3],
    pub ref_cs: f32,
    pub xsph_eps: f32,
    pub shift: f32,
    pub max_shift: f32,
    pub fs_threshold: f32,
    pub detach_threshold: f32,
    pub cfl: f32,
    pub dt_max: f32,
    pub dt_fixed: f32,
    /// Water (wet scenes; zero otherwise): rest density ρ_w, sound speed, viscosity, unit
    /// weight at standard gravity, the lattice sum's inverse and itself, the full-support
    /// fraction χ and the drag distribution (0 SVF, 1 per particle). See `cpu::WetSetup`.
    pub w_rest: f32,
    pub w_c: f32,
    pub w_mu: f32,
    pub w_gamma: f32,
    pub inv_lsum: f32,
    pub lsum: f32,
    pub full_support: f32,
    pub drag_particle: u32,
}

/// One soil particle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Particle {
    pub pos: [f32; 3],
    pub vel: [f32; 3],
    pub rho: f32,
    pub sigma: [f32; 6],
    pub pc: f32,
    pub sv: f32,
    pub mass: f32,
    pub material: u32,
    pub id: u32,
    pub flags: u32,
    pub pad: u32,
}

/// Flag bit: free surface.
pub const FLAG_FREE: u32 = 1;
/// Flag bit: detached (no stress).
pub const FLAG_DETACHED: u32 = 2;
/// Flag: extended particle of an active region (a neighbour only, its state frozen).
pub const FLAG_FROZEN: u32 = 4;

/// What a neighbour reads of a particle or marker.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Packed {
    pub x: [f32; 3],
    pub v: [f32; 3],
    pub s: [f32; 6],
    pub vol: f32,
    pub mass: f32,
    pub rho: f32,
    pub cs: f32,
}

/// The rates of one stage.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Rate {
    pub drho: f32,
    pub acc: [f32; 3],
    pub dsigma: [f32; 6],
    pub d: [f32; 6],
    pub xsph: [f32; 3],
    pub grad_c: [f32; 3],
    pub fs: f32,
    pub bulk: f32,
    pub shear: f32,
    pub pad: f32,
}

/// A boundary marker (original order): kinematics, owner, and the wall's unit normal into the
/// soil (zero: the marker is rough whatever its owner's contact).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Marker {
    pub pos: [f32; 3],
    pub vel: [f32; 3],
    pub acc: [f32; 3],
    pub owner: u32,
    pub normal: [f32; 3],
}

/// Step bookkeeping (see `Info` in common.wgsl); maxima are f32 bit patterns.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Info {
    pub active: u32,
    pub dt: f32,
    pub max_dt: f32,
    pub rarefied: u32,
    pub cmax: u32,
    pub vmax: u32,
    pub amax: u32,
    pub pairs: u32,
    /// The failing particle with the smallest id and its error (`error_code::decode`).
    pub err_key: u32,
    pub vmax_end: u32,
    pub amax_end: u32,
    /// Largest drag rate λ = Σ C V W / m of the first stage (1/s, wet scenes).
    pub drag: u32,
    /// Set when an awake particle left the cells awake particles may be in (active regions).
    pub uncovered: u32,
}

/// What the phase coupling knows of a particle at a stage (see `Pore` in wet.wgsl; CPU twins
/// `cpu::wet::Phase` and `cpu::wet::Pore`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Pore {
    pub water: u32,
    pub vg: f32,
    pub inv_k: f32,
    pub n: f32,
    pub p: f32,
    pub cw: f32,
    pub inv_sum: f32,
    pub sat: f32,
    pub gv: [f32; 9],
}

/// A marker's share of the phase coupling (see `MarkerPore` in wet.wgsl; CPU twin
/// `cpu::wet::MarkerPore`), and whether its owner is permeable.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MarkerPore {
    pub vg: f32,
    pub inv_k: f32,
    pub p: f32,
    pub vel: [f32; 3],
    pub permeable: u32,
}

/// A material (see `Material` in materials.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Material {
    pub model: u32,
    pub density: f32,
    pub bulk: f32,
    pub shear: f32,
    pub poisson: f32,
    pub mu_s: f32,
    pub mu_2: f32,
    pub i0: f32,
    pub grain_d: f32,
    pub grain_rho: f32,
    pub k: f32,
    pub m: f32,
    pub kappa: f32,
    pub lambda: f32,
    pub clamp: u32,
    pub clamp_lo: f32,
    pub clamp_hi: f32,
    pub pc_floor: f32,
    /// `1 / k` (s/m) of a soil water flows through; 0 otherwise.
    pub inv_perm: f32,
    /// Grain density ρ_g (kg/m³) of a soil water flows through; 0 otherwise.
    pub grain_por: f32,
}

/// A body's state for marker placement and its marker range (see `Body` in bodies.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Body {
    pub rotation: [f32; 4],
    pub origin: [f32; 3],
    pub com: [f32; 3],
    pub linvel: [f32; 3],
    pub angvel: [f32; 3],
    pub linacc: [f32; 3],
    pub angacc: [f32; 3],
    pub first: u32,
    pub count: u32,
}

/// An active region's box in the world (see `Box` in classify.wgsl; host twin
/// `regolith_fsi::active::WorldBox`): centre and half-size `h0`, then each axis and its
/// half-size.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ActiveBox {
    pub center: [f32; 3],
    pub h0: f32,
    pub a0: [f32; 3],
    pub h1: f32,
    pub a1: [f32; 3],
    pub h2: f32,
    pub a2: [f32; 3],
    pub pad: f32,
}

/// What the classification's `roles` kernel reads (see `Classify` in classify.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ClassifyParams {
    pub n_boxes: u32,
    /// Sleep speed squared (m²/s²).
    pub v2: f32,
    /// Travel allowance (m).
    pub travel: f32,
    pub pad: u32,
}

/// One axis of a cell-mask dilation (see `Dilate` in dilate.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct DilateParams {
    pub axis: u32,
    pub radius: u32,
    pub pad: [u32; 2],
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fields of WGSL struct `name` in `src`, as (name, type).
    fn wgsl_fields(src: &str, name: &str) -> Vec<(String, String)> {
        let head = format!("struct {name} {{");
        let start = src.find(&head).unwrap_or_else(|| panic!("no `struct {name}` in the kernels")) + head.len();
        let body = &src[start..start + src[start..].find('}').expect("closing brace")];
        let body: String = body.lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join(" ");
        body.split(',')
            .filter(|f| !f.trim().is_empty())
            .map(|f| {
                let (n, t) = f.split_once(':').unwrap_or_else(|| panic!("`{f}` in struct {name}"));
                (n.trim().to_string(), t.trim().to_string())
            })
            .collect()
    }

    /// Each host record has the size of its WGSL struct, read from the kernels' own source, and
    /// every WGSL field is one 4-byte scalar (no `vec3`, whose 16-byte alignment would open gaps
    /// the `#[repr(C)]` mirror does not have).
    #[test]
    fn sizes_match_the_wgsl_structs() {
        let src = [
            include_str!("kernels/common.wgsl"),
            include_str!("kernels/materials.wgsl"),
            include_str!("kernels/bodies.wgsl"),
            include_str!("kernels/wet.wgsl"),
            include_str!("kernels/classify.wgsl"),
            include_str!("kernels/dilate.wgsl"),
        ]
        .join("\n");
        let host = [
            ("Params", size_of::<Params>()),
            ("Particle", size_of::<Particle>()),
            ("Packed", size_of::<Packed>()),
            ("Rate", size_of::<Rate>()),
            ("Marker", size_of::<Marker>()),
            ("Info", size_of::<Info>()),
            ("Material", size_of::<Material>()),
            ("Body", size_of::<Body>()),
            ("Pore", size_of::<Pore>()),
            ("MarkerPore", size_of::<MarkerPore>()),
            ("Box", size_of::<ActiveBox>()),
            ("Classify", size_of::<ClassifyParams>()),
            ("Dilate", size_of::<DilateParams>()),
        ];
        for (name, bytes) in host {
            let fields = wgsl_fields(&src, name);
            for (f, t) in &fields {
                assert!(
                    matches!(t.as_str(), "f32" | "u32" | "i32" | "atomic<u32>" | "atomic<i32>"),
                    "{name}.{f}: {t} is not a 4-byte scalar"
                );
            }
            assert_eq!(bytes, 4 * fields.len(), "{name}: host {bytes} B, WGSL {} fields", fields.len());
        }
        // The parser sees what is there (a guard against a check that reads nothing).
        assert_eq!(wgsl_fields("struct S { a: f32, // x\n b: u32,\n}", "S").len(), 2);
        assert_eq!(size_of::<Particle>(), 20 * 4);
    }
}
