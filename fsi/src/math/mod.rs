//! Small fixed-size vectors and tensors used by the solver.
//!
//! Hand-written rather than taken from a linear-algebra crate so that the CPU code reads like
//! the WGSL kernels that mirror it (plain fields, no generic dimension machinery) and stays
//! generic over [`Real`](crate::Real).

mod mat3;
mod sym3;
mod vec3;

pub use mat3::Mat3;
pub use sym3::Sym3;
pub use vec3::Vec3;
