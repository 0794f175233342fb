//! Studies: many runs of shipped scenes, checked and tabulated. `stability` runs the hard
//! cases of `examples/hard/` against the bounds each states in its `[[expect]]` section;
//! `convergence` estimates a result's observed order and limit over a resolution ladder.

pub mod convergence;
pub mod darcy;
pub mod expect;
mod probe;
pub mod stability;

pub use probe::{Figures, Probe};

use std::path::{Path, PathBuf};

use crate::driver::RunError;
use crate::input::InputError;

/// Why a study could not be carried out (a case that misses its bounds is a result, not this).
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A wrong case file or flag.
    #[error(transparent)]
    Input(#[from] InputError),
    /// A case's run failed in a way no check covers (its scene did not build, an output could
    /// not be written).
    #[error("case {case}")]
    Run {
        /// The case.
        case: String,
        /// Why.
        #[source]
        source: RunError,
    },
    /// Cases or points that could not be carried out, each with its one-line error.
    #[error("not carried out: {0}")]
    Incomplete(String),
    /// Writing a table failed.
    #[error("writing {}", path.display())]
    Output {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

impl StudyError {
    /// An output error about a file.
    pub fn output(path: &Path, source: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        Self::Output { path: path.to_path_buf(), source: source.into() }
    }
}

/// Writes a text file, as a study error naming it.
pub fn write_text(path: &Path, text: &str) -> Result<(), StudyError> {
    std::fs::write(path, text).map_err(|e| StudyError::output(path, e))
}
