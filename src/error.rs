//! [`Error`]: every way a Regolith call can fail, as one type for library users.
//!
//! Each stage has its own error — [`InputError`] (files and flags), [`BuildError`] (scene →
//! objects), [`SolverError`] (stepping), [`RunError`] (a whole run, outputs included) and
//! [`ElementError`] (the material-point driver) — and each wraps what it was caused by as its
//! [`std::error::Error::source`], down to the member crates' own errors. `Error` gathers them;
//! [`Error::report`] prints the whole chain on one line, as the command-line tool does.

pub use crate::build::BuildError;
pub use crate::driver::RunError;
pub use crate::element::ElementError;
pub use crate::input::InputError;
pub use crate::study::StudyError;
pub use regolith_fsi::SolverError;

/// Any Regolith failure.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A wrong file or flag: one line naming the file, the key and what is allowed.
    #[error(transparent)]
    Input(#[from] InputError),
    /// A scene could not be built.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// The soil solver stopped.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// A run failed or was stopped.
    #[error(transparent)]
    Run(#[from] RunError),
    /// A material-point test failed.
    #[error(transparent)]
    Element(#[from] ElementError),
    /// A study could not be carried out.
    #[error(transparent)]
    Study(#[from] StudyError),
}

impl Error {
    /// The error and its causes on one line, joined by `: `.
    pub fn report(&self) -> String {
        report(self)
    }
}

pub use crate::input::report;

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as StdError;

    #[test]
    fn report_keeps_the_chain_without_repeats() {
        let inner = regolith_rigid::RigidError::Invalid("mass must be > 0".into());
        let e = Error::from(RunError::from(BuildError::Rigid { key: "bodies[0]".into(), source: inner }));
        assert_eq!(e.report(), "building the scene: bodies[0]: mass must be > 0");
        assert_eq!(e.to_string(), "building the scene");
        assert!(e.source().is_some(), "the chain is kept");
    }
}
