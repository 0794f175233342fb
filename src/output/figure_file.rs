//! Writing a [`Figure`] to files: PNG and SVG in a build with the `plots` feature (drawn by
//! `render.rs`), nothing in one without.

use std::path::{Path, PathBuf};

use super::plot::{Figure, PlotError};

/// Whether this build draws plots (the `plots` feature).
pub const DRAWS_PLOTS: bool = cfg!(feature = "plots");

/// Writes `dir/stem.png` and `dir/stem.svg` and returns their paths; a build without the
/// `plots` feature writes nothing and returns no path (see [`DRAWS_PLOTS`]).
pub fn write_figure(fig: &Figure, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
    #[cfg(feature = "plots")]
    {
        super::render::draw(fig, dir, stem)
    }
    #[cfg(not(feature = "plots"))]
    {
        let _ = (fig, dir, stem);
        Ok(Vec::new())
    }
}
