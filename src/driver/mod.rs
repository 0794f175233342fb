//! The run loop: steps a [`Simulation`] one exchange interval at a time to an end time, keeps
//! the counters a summary needs ([`RunStats`]), stops at the next exchange when a
//! [`StopToken`] is raised (what Ctrl-C does), and hands every step to its [`Observer`]s: the
//! recording, the series, the progress bar, a rig's report. Observers only read the
//! simulation; what moves bodies (a rig's carriage, a vehicle's drive) is the caller's.

mod progress;

pub use progress::Progress;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use regolith_fsi::{Real, SolverError};

use crate::build::BuildError;
use crate::sim::Simulation;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene cannot be built.
    #[error("building the scene")]
    Build(#[from] BuildError),
    /// The solver stopped.
    #[error("solver")]
    Solver(#[from] SolverError),
    /// The solver stopped at a particle: `report` names it, its material, position, stress,
    /// p_c and the step (what [`Driver::step`] returns when the solver fails).
    #[error("{report}")]
    Failed {
        /// One line about the particle (the solver's error included).
        report: String,
        /// The solver's error (already in `report`, so not a `source`).
        cause: SolverError,
    },
    /// A particle ran away: faster than `[simulation] runaway_speed`.
    #[error("{report}")]
    Runaway {
        /// One line about the particle (as for [`Self::Failed`]).
        report: String,
    },
    /// Writing an output failed.
    #[error("writing {}", path.display())]
    Output {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// Every soil particle has left the domain: nothing is left to simulate, so the run stops
    /// rather than stepping rigid bodies over no soil to the end time.
    #[error(
        "all {particles} soil particles left the domain by step {step} (t = {time:.6e} s); \
         nothing is left to simulate (enlarge [container] or check the soil's initial velocity)"
    )]
    Emptied {
        /// Soil particles generated.
        particles: usize,
        /// Simulated time (s).
        time: f64,
        /// Soil steps taken.
        step: u64,
    },
    /// A stop was requested (Ctrl-C); the outputs up to that point were written.
    #[error("interrupted (outputs up to t = {time:.4} s were written)")]
    Interrupted {
        /// Simulated time reached (s).
        time: f64,
    },
}

impl RunError {
    /// Whether the run ends with its outputs written up to this point (a solver failure, a
    /// runaway, a stop request) rather than at once (a build or output error).
    pub fn keeps_outputs(&self) -> bool {
        matches!(
            self,
            Self::Solver(_)
                | Self::Failed { .. }
                | Self::Runaway { .. }
                | Self::Emptied { .. }
                | Self::Interrupted { .. }
        )
    }

    /// The solver's error `cause` with a one-line report on the particle it names.
    fn failed<T: Real>(sim: &Simulation<T>, cause: SolverError) -> Self {
        let particle = match &cause {
            SolverError::NonFinite { particle, .. } | SolverError::Rheology { particle, .. } => Some(*particle),
            SolverError::Setup(_) => None,
        };
        let report = match particle {
            Some(id) => format!("solver failed: {cause}; {}", sim.particle_report(id)),
            None => format!("solver failed: {cause}"),
        };
        Self::Failed { report, cause }
    }

    /// An output error for `path`.
    pub fn output(path: &Path, source: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        Self::Output { path: path.to_path_buf(), source: source.into() }
    }
}

/// Asks a run to stop at its next exchange. Each run owns one (the CLI raises its run's
/// token on Ctrl-C); clones share the flag, so a thread or a signal handler can hold one.
#[derive(Clone, Debug, Default)]
pub struct StopToken(Arc<AtomicBool>);

impl StopToken {
    /// A fresh, unraised token.
    pub fn new() -> Self {
        Self::default()
    }
    /// Raises it.
    pub fn stop(&self) {
        self.0.store(true, Ordering::SeqCst);
    }
    /// Whether it was raised.
    pub fn is_stopped(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// What a run did, for the summary.
#[derive(Clone, Debug)]
pub struct RunStats {
    start: Instant,
    /// Simulated end time of each run (s).
    pub end_time: f64,
    /// Soil steps taken.
    pub steps: u64,
    /// Integrated (awake) soil particles × steps.
    pub particle_steps: f64,
    /// Sum of neighbour pairs over steps (for the mean).
    pub pairs: f64,
    /// Largest particle speed seen (m/s).
    pub max_speed_run: f64,
    /// Largest particle speed at the last step (m/s).
    pub last_speed: f64,
    /// Smallest soil step (s).
    pub dt_min: f64,
    /// Largest soil step (s).
    pub dt_max: f64,
    /// Fewest particles integrated in a step (the whole domain without an active region).
    pub awake_min: usize,
    /// Most particles integrated in a step.
    pub awake_max: usize,
    /// Most soil particles held at the density floor after a step
    /// (`regolith_fsi::config::RAREFIED_DENSITY`).
    pub rarefied_max: usize,
}

impl RunStats {
    fn new(end_time: f64) -> Self {
        Self {
            start: Instant::now(),
            end_time,
            steps: 0,
            particle_steps: 0.0,
            pairs: 0.0,
            max_speed_run: 0.0,
            last_speed: 0.0,
            dt_min: f64::INFINITY,
            dt_max: 0.0,
            awake_min: usize::MAX,
            awake_max: 0,
            rarefied_max: 0,
        }
    }

    /// Wall-clock time since the run started (s).
    pub fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

/// Something that watches a run: told when each run starts, after every exchange, of the
/// named quantities a rig publishes, and when everything is done. Every method defaults to
/// doing nothing.
pub trait Observer<T: Real> {
    /// A run starts (the only one, or the next of a rig's runs; `label`: its slip or plate size).
    fn begin(&mut self, _sim: &Simulation<T>, _label: Option<f64>) -> Result<(), RunError> {
        Ok(())
    }
    /// An exchange interval was stepped.
    fn after_step(&mut self, _sim: &Simulation<T>, _stats: &RunStats) -> Result<(), RunError> {
        Ok(())
    }
    /// Named quantities of this exchange on `topic` (schema `title`), e.g. a rig's readings.
    fn values(
        &mut self,
        _sim: &Simulation<T>,
        _topic: &str,
        _title: &str,
        _fields: &[(&str, f64)],
    ) -> Result<(), RunError> {
        Ok(())
    }
    /// Every run is over (also after a failure or a stop).
    fn finish(&mut self) -> Result<(), RunError> {
        Ok(())
    }
}

/// The run loop with its observers.
pub struct Driver<'o, T: Real> {
    /// Counters so far.
    pub stats: RunStats,
    stop: StopToken,
    observers: Vec<&'o mut dyn Observer<T>>,
}

impl<'o, T: Real> Driver<'o, T> {
    /// A loop for runs that end at `end_time` (s), stopping when `stop` is raised.
    pub fn new(end_time: f64, stop: StopToken) -> Self {
        Self { stats: RunStats::new(end_time), stop, observers: Vec::new() }
    }

    /// Adds an observer (called in the order added).
    pub fn observe(&mut self, o: &'o mut dyn Observer<T>) {
        self.observers.push(o);
    }

    /// Starts a run of `sim` (`label`: a rig run's slip or plate size).
    pub fn begin(&mut self, sim: &Simulation<T>, label: Option<f64>) -> Result<(), RunError> {
        for o in &mut self.observers {
            o.begin(sim, label)?;
        }
        Ok(())
    }

    /// Whether `sim` has reached the end time.
    pub fn done(&self, sim: &Simulation<T>) -> bool {
        sim.time() >= self.stats.end_time * (1.0 - 1e-12)
    }

    /// Advances `sim` by one exchange interval (at most to the end time) and tells the observers.
    pub fn step(&mut self, sim: &mut Simulation<T>) -> Result<(), RunError> {
        if self.stop.is_stopped() {
            return Err(RunError::Interrupted { time: sim.time() });
        }
        let remaining = self.stats.end_time - sim.time();
        let r = sim.step_max(Some(remaining)).map_err(|e| RunError::failed(sim, e))?;
        if r.max_speed > sim.scene.runaway_speed {
            let fluid = &sim.system.fluid;
            let n = fluid.active();
            let fastest = (0..n).max_by(|a, b| {
                fluid.velocities()[*a].norm().as_f64().total_cmp(&fluid.velocities()[*b].norm().as_f64())
            });
            let what = fastest.map_or_else(String::new, |i| sim.particle_report(fluid.ids()[i]));
            return Err(RunError::Runaway {
                report: format!(
                    "runaway particle: speed {:.3e} m/s above simulation.runaway_speed = {} m/s at step {} (t = {:.6e} s); {what}",
                    r.max_speed,
                    sim.scene.runaway_speed,
                    fluid.steps(),
                    sim.time()
                ),
            });
        }
        let fluid = &sim.system.fluid;
        if fluid.active() == 0 && !fluid.is_empty() {
            return Err(RunError::Emptied { particles: fluid.len(), time: sim.time(), step: fluid.steps() });
        }
        // Work follows the integrated (awake) particles, not the bed.
        let awake = sim.system.fluid.awake();
        let n = awake as f64;
        let s = &mut self.stats;
        s.awake_min = s.awake_min.min(awake);
        s.awake_max = s.awake_max.max(awake);
        s.steps += u64::from(r.fluid_steps);
        s.particle_steps += n * f64::from(r.fluid_steps);
        s.pairs += r.pairs as f64 * f64::from(r.fluid_steps);
        s.last_speed = r.max_speed;
        s.dt_min = s.dt_min.min(r.dt_min);
        s.dt_max = s.dt_max.max(r.dt_max);
        s.max_speed_run = s.max_speed_run.max(r.max_speed);
        s.rarefied_max = s.rarefied_max.max(r.rarefied_max);
        for o in &mut self.observers {
            o.after_step(sim, &self.stats)?;
        }
        Ok(())
    }

    /// Publishes named quantities of the current exchange to every observer.
    pub fn publish(
        &mut self,
        sim: &Simulation<T>,
        topic: &str,
        title: &str,
        fields: &[(&str, f64)],
    ) -> Result<(), RunError> {
        for o in &mut self.observers {
            o.values(sim, topic, title, fields)?;
        }
        Ok(())
    }

    /// Tells every observer that the runs are over; the first error wins, but all are told.
    pub fn finish(&mut self) -> Result<(), RunError> {
        let mut first = Ok(());
        for o in &mut self.observers {
            let r = o.finish();
            if first.is_ok() {
                first = r;
            }
        }
        first
    }
}
