//! # regolith-terrain
//!
//! Will build soil domains for the SPH solver: box patches in containers, heightmap patches,
//! soil blocks and columns, geostatic initial stress (σv = −ρ g depth, σh = K0 σv) and the MCC
//! initial state (p_c0 = OCR p0, specific volume from the compression lines), with several
//! materials per scene.
//!
//! Nothing here yet: the crate is filled by the terrain-solver work.
