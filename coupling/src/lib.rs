//! # regolith-coupling
//!
//! Will hold `FsiSystem { fluid, rigid, interface }`: the co-simulation of SPH soil
//! (`regolith-fsi`) with rapier bodies (`regolith-rigid`) through BCE markers generated from
//! each body's parry3d shape, the body-state → marker-state update, the marker-force → body
//! wrench reduction averaged over the exchange interval, and the exchange schedule.
//!
//! Nothing here yet: the crate is filled by the rigid-coupling work.
