//! Regolith's integration tests, one binary: each file of tests/ is a module here, so the
//! release build compiles and links them once (20 test binaries took about 20 s each to build
//! on 2 cores). Run one file's tests with `cargo test --release --test suite coupling::`.

mod common;

#[path = "accuracy.rs"]
mod accuracy;
#[path = "active.rs"]
mod active;
#[path = "architecture.rs"]
mod architecture;
#[path = "cli_errors.rs"]
mod cli_errors;
#[path = "column_collapse.rs"]
mod column_collapse;
#[path = "conservation.rs"]
mod conservation;
#[path = "contact.rs"]
mod contact;
#[path = "coupling.rs"]
mod coupling;
#[path = "element_dp.rs"]
mod element_dp;
#[path = "element_mcc.rs"]
mod element_mcc;
#[path = "faults.rs"]
mod faults;
#[path = "free_surface.rs"]
mod free_surface;
#[path = "fuzz_inputs.rs"]
mod fuzz_inputs;
#[path = "geostatic.rs"]
mod geostatic;
#[path = "interrupt.rs"]
mod interrupt;
#[path = "material_errors.rs"]
mod material_errors;
#[path = "memory.rs"]
mod memory;
#[path = "patch.rs"]
mod patch;
#[path = "rapier_plugin.rs"]
mod rapier_plugin;
#[path = "recording.rs"]
mod recording;
#[path = "repose.rs"]
mod repose;
#[path = "rig_calibration.rs"]
mod rig_calibration;
#[path = "scene_errors.rs"]
mod scene_errors;
#[path = "settings_reach.rs"]
mod settings_reach;
#[path = "traction.rs"]
mod traction;
#[path = "triaxial.rs"]
mod triaxial;
#[path = "urdf_gallery.rs"]
mod urdf_gallery;
#[path = "vehicles.rs"]
mod vehicles;
#[path = "verlet.rs"]
mod verlet;
#[path = "wet_soil.rs"]
mod wet_soil;
#[path = "wgpu_parity.rs"]
mod wgpu_parity;
