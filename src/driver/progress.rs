//! The terminal progress bar: simulated time, real-time factor, particle-steps/s and ETA.

use regolith_fsi::Real;

use super::Observer;
#[cfg(feature = "cli")]
use super::{RunError, RunStats};
#[cfg(feature = "cli")]
use crate::sim::Simulation;

/// A progress bar on stdout, shown only on a terminal (and only with the `cli` feature).
#[derive(Debug, Default)]
pub struct Progress {
    #[cfg(feature = "cli")]
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    /// A bar, unless `quiet` or stdout is not a terminal (then it draws nothing).
    #[cfg(not(feature = "cli"))]
    pub fn new(_quiet: bool) -> Self {
        Self {}
    }

    /// A bar, unless `quiet` or stdout is not a terminal (then it draws nothing).
    #[cfg(feature = "cli")]
    pub fn new(quiet: bool) -> Self {
        use std::io::IsTerminal as _;
        let bar = (!quiet && std::io::stdout().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new(1000);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:30} {msg} ETA {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        Self { bar }
    }
}

#[cfg(not(feature = "cli"))]
impl<T: Real> Observer<T> for Progress {}

#[cfg(feature = "cli")]
impl<T: Real> Observer<T> for Progress {
    fn begin(&mut self, _sim: &Simulation<T>, _label: Option<f64>) -> Result<(), RunError> {
        if let Some(b) = &self.bar {
            b.reset_eta();
        }
        Ok(())
    }

    fn after_step(&mut self, sim: &Simulation<T>, stats: &RunStats) -> Result<(), RunError> {
        if let Some(b) = &self.bar {
            let el = stats.elapsed().max(1e-9);
            let t = sim.time();
            b.set_position((1000.0 * t / stats.end_time).round() as u64);
            b.set_message(format!(
                "t = {t:.4}/{} s  RTF {:.2e}  {:.2e} particle-steps/s",
                stats.end_time,
                t / el,
                stats.particle_steps / el
            ));
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<(), RunError> {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
        Ok(())
    }
}
