//! # regolith-vehicles
//!
//! Will import URDF vehicles onto deformable terrain (links, inertials, collision and visual
//! geometry, `package://` resolution), pick the links that touch the soil, and drive them:
//! wheel velocity motors, skid steering, steering joints, plus the wheel-with-grousers, cone and
//! plate builders used by the test rigs.
//!
//! Nothing here yet: the crate is filled by the URDF-vehicle work.
