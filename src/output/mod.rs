//! What a run leaves behind: `particles_final.csv`, `series.csv`, `recording.mcap`, JSON
//! files and PNG/SVG plots. The series and the recording are [`crate::driver::Observer`]s of
//! the run loop; the rest is written once at the end.

pub mod element_plot;
pub mod figure_file;
pub mod figures;
pub mod json;
pub mod particles;
pub mod plot;
#[cfg(feature = "mcap")]
pub mod record;
#[cfg(feature = "plots")]
mod render;
pub mod series;

pub use figure_file::{DRAWS_PLOTS, write_figure};
pub use json::write_json;
pub use particles::{ParticleRow, particle_row, write_particles_csv};
pub use plot::{Figure, Panel, PlotError};
#[cfg(feature = "mcap")]
pub use record::Recorder;
pub use series::{Series, TerrainSeries};
