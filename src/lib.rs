//! # Regolith
//!
//! Deformable soil simulated with SPH (the continuum representation model) and coupled to rigid
//! bodies. This facade re-exports the member crates and holds what ties them together. Its
//! modules read in the order the data flows (see `ARCHITECTURE.md`); each imports only the
//! ones before it:
//!
//! 1. [`input`]: one-line user-input errors and TOML helpers;
//! 2. [`material`], [`element`]: material files and the material-point driver;
//! 3. [`scene`]: scene files → a validated [`scene::Scene`];
//! 4. [`build`]: Scene → terrain, rigid world, markers, soil solver;
//! 5. [`sim`]: the scripting API, [`sim::Simulation`];
//! 6. [`driver`]: the run loop, its stop token and observers;
//! 7. [`output`]: series, recording, particles CSV, JSON, plots;
//! 8. [`rig`]: the plate, cone and wheel rigs (body controllers with their reports);
//! 9. [`run`]: a whole `regolith run` — build, drive, write, summarise;
//! 10. [`study`]: many runs of shipped scenes, checked and tabulated (the stability suite);
//! 11. [`calibrate`]: soil parameters from measurements (MCC from lab data, fits with
//!     standard errors, the Mohr–Coulomb envelope);
//! 12. [`error`]: the facade [`Error`] over every stage's error type;
//! 13. [`sweep`]: one scene at many points (grid or Latin hypercube), resumable, in shards;
//! 14. [`accuracy`]: what accuracy costs in time — d0 ladders and knobs over the cases of
//!     `examples/study/`, run through the sweep runner, against closed forms, experiments or
//!     their own Richardson limit;
//! 15. [`bench`](mod@bench), [`cli`]: the benchmark and the command-line tool.
//!
//! `tests/architecture.rs` fails on an import against this order.
//!
//! Features (all on by default): `cli` (the `regolith` tool, with `mcap` and `plots`), `wgpu`
//! (the GPU backend), `mcap` (`recording.mcap`), `plots` (PNG/SVG). A library user can turn
//! them off: `default-features = false`.
#![warn(missing_docs)]

pub mod accuracy;
pub mod bench;
pub mod build;
pub mod calibrate;
#[cfg(feature = "cli")]
pub mod cli;
pub mod driver;
pub mod element;
pub mod error;
pub mod input;
pub mod material;
pub mod output;
pub mod rig;
pub mod run;
pub mod runner;
pub mod scene;
pub mod sim;
pub mod study;
pub mod sweep;

pub use error::Error;
pub use regolith_body as body;
pub use regolith_coupling as coupling;
pub use regolith_fsi as fsi;
pub use regolith_rigid as rigid;
pub use regolith_terrain as terrain;
pub use regolith_vehicles as vehicles;
#[cfg(feature = "wgpu")]
pub use regolith_wgpu as wgpu_backend;

pub use regolith_fsi::config::DEFAULT_FREE_SURFACE_THRESHOLD;
