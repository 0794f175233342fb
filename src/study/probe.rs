//! The figures a stability check reads, measured while a scene runs: a [`Probe`] observes
//! every run (each slip or plate of a rig) and every exchange.

use regolith_fsi::Real;
use regolith_rigid::{Pose, ShapeDesc};

use crate::driver::{Observer, RunError, RunStats};
use crate::sim::{Body, Simulation};

/// One run's figures.
#[derive(Clone, Debug, Default)]
struct RunFigures {
    /// Initial position of each particle, by original index.
    start: Vec<[f64; 3]>,
    /// Simulated time and soil kinetic energy after each exchange.
    ke: Vec<(f64, f64)>,
    t0: f64,
    /// Total particle mass and count when the run began, and after the last exchange.
    mass0: (f64, usize),
    mass_end: (f64, usize),
    inside_max: usize,
    final_speed: f64,
    rms_final: f64,
    max_displacement: f64,
    leaked: usize,
    /// Per scene body: final origin height, speed, depth below the initial surface, and the
    /// mean speed over the last quarter of the run.
    bodies: Vec<[f64; 4]>,
    /// Simulated time and every body's origin after each exchange (for the mean speed).
    track: Vec<(f64, Vec<[f64; 3]>)>,
}

/// Where and when the soil was fastest: what a failed speed bound needs to be traced.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fastest {
    /// Its speed (m/s).
    pub speed: f64,
    /// Simulated time at the end of the exchange it was measured after (s).
    pub time: f64,
    /// The particle's original index.
    pub particle: u32,
    /// Its position then (m).
    pub position: [f64; 3],
}

/// Measures a scene's runs for the stability study (`stability.rs`).
#[derive(Clone, Debug, Default)]
pub struct Probe {
    runs: Vec<RunFigures>,
    max_speed: f64,
    fastest: Option<Fastest>,
    /// Body names, in scene order.
    names: Vec<String>,
    /// Per body: shape, its initial velocity, mass (for the impact law).
    shapes: Vec<(ShapeDesc, [f64; 3], f64)>,
}

/// The figures of all runs of a case.
#[derive(Clone, Debug, PartialEq)]
pub struct Figures {
    /// Largest particle speed of any run (m/s).
    pub max_soil_speed: f64,
    /// Which particle had it, when and where.
    pub fastest: Option<Fastest>,
    /// Largest particle speed at the end of the last run (m/s).
    pub final_soil_speed: f64,
    /// Largest count of particles deep inside a body, any run.
    pub inside_bodies: usize,
    /// Largest kinetic-energy growth of any run (second half's peak over the first half's).
    pub ke_growth: f64,
    /// RMS soil speed at the end of the last run (m/s).
    pub rms_speed_final: f64,
    /// Largest displacement at the end of any run (m).
    pub max_displacement: f64,
    /// Largest count of particles through a wall at the end of any run.
    pub leaked: usize,
    /// Per body (by name): final origin height (m), speed (m/s), depth below the initial
    /// surface (m), and mean speed over the last quarter of the run (m/s: the net
    /// displacement of its origin over that time, divided by the time; blind to oscillation).
    pub bodies: Vec<(String, [f64; 4])>,
    /// Per body: shape, initial velocity (m/s) and mass (kg).
    pub shapes: Vec<(String, ShapeDesc, [f64; 3], f64)>,
}

impl Probe {
    /// Largest relative change, over the runs, of the total particle mass (in the domain plus
    /// escaped) from the start to the last exchange; 1 when particles were lost or gained.
    /// `None`: no run began.
    pub fn mass_error(&self) -> Option<f64> {
        self.runs
            .iter()
            .map(|r| {
                if r.mass0.1 != r.mass_end.1 {
                    1.0
                } else {
                    (r.mass_end.0 - r.mass0.0).abs() / r.mass0.0.max(f64::MIN_POSITIVE)
                }
            })
            .reduce(f64::max)
    }

    /// What was measured (`None`: no run began).
    pub fn figures(&self) -> Option<Figures> {
        let last = self.runs.last()?;
        let ke_growth = self.runs.iter().map(ke_growth).fold(0.0, f64::max);
        Some(Figures {
            max_soil_speed: self.max_speed,
            fastest: self.fastest,
            final_soil_speed: last.final_speed,
            inside_bodies: self.runs.iter().map(|r| r.inside_max).max().unwrap_or(0),
            ke_growth,
            rms_speed_final: last.rms_final,
            max_displacement: self.runs.iter().map(|r| r.max_displacement).fold(0.0, f64::max),
            leaked: self.runs.iter().map(|r| r.leaked).max().unwrap_or(0),
            bodies: self.names.iter().cloned().zip(last.bodies.iter().copied()).collect(),
            shapes: self.names.iter().cloned().zip(&self.shapes).map(|(n, s)| (n, s.0.clone(), s.1, s.2)).collect(),
        })
    }
}

/// The second half's peak kinetic energy over the first half's (0 when the soil never moved).
fn ke_growth(r: &RunFigures) -> f64 {
    let Some(&(t_end, _)) = r.ke.last() else {
        return 0.0;
    };
    let mid = 0.5 * (r.t0 + t_end);
    let peak = |early: bool| r.ke.iter().filter(|(t, _)| (*t <= mid) == early).map(|x| x.1).fold(0.0, f64::max);
    let (first, second) = (peak(true), peak(false));
    if first > 0.0 {
        second / first
    } else if second > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// Per body, the net displacement of its origin over the last quarter of the run so far,
/// over that time (m/s): the sample nearest the three-quarter time to the last one. NaN
/// until two samples span it.
fn mean_speeds(t0: f64, track: &[(f64, Vec<[f64; 3]>)]) -> Vec<f64> {
    let Some((t_end, last)) = track.last() else {
        return Vec::new();
    };
    let t_from = t0 + 0.75 * (t_end - t0);
    let k = track.partition_point(|(t, _)| *t < t_from).min(track.len() - 1);
    let (t_a, first) = &track[k];
    let dt = t_end - t_a;
    last.iter()
        .zip(first)
        .map(|(b, a)| if dt > 0.0 { (0..3).map(|i| (b[i] - a[i]).powi(2)).sum::<f64>().sqrt() / dt } else { f64::NAN })
        .collect()
}

/// Soil particle centres deeper than `depth` inside body `b`'s shape.
fn count_inside<T: Real>(sim: &Simulation<T>, b: Body, depth: f64) -> usize {
    let spec = &sim.scene.bodies[b.index()];
    if !spec.fsi {
        return 0;
    }
    let st = sim.body_state(b);
    let pose = Pose { translation: st.origin, rotation: st.rotation };
    let r = spec.desc.shape.bounding_radius();
    let f = &sim.system.fluid;
    let near: Vec<[f64; 3]> = f.positions()[..f.active()]
        .iter()
        .map(|p| p.as_f64())
        .filter(|p| (0..3).map(|k| (p[k] - st.origin[k]).powi(2)).sum::<f64>() <= r * r)
        .map(|p| pose.to_local(p))
        .collect();
    spec.desc.shape.contains_points(&near, -depth).iter().filter(|x| **x).count()
}

impl<T: Real> Observer<T> for Probe {
    fn begin(&mut self, sim: &Simulation<T>, _label: Option<f64>) -> Result<(), RunError> {
        let f = &sim.system.fluid;
        let mut start = vec![[f64::NAN; 3]; f.len()];
        for (p, id) in f.positions().iter().zip(f.ids()) {
            if let Some(s) = start.get_mut(*id as usize) {
                *s = p.as_f64();
            }
        }
        self.names = sim.scene.bodies.iter().map(|b| b.desc.name.clone()).collect();
        self.shapes = sim
            .bodies()
            .map(|b| {
                let spec = &sim.scene.bodies[b.index()];
                let mass = spec.desc.mass.mass_of(&spec.desc.shape);
                (spec.desc.shape.clone(), spec.initial_velocity.unwrap_or([0.0; 3]), mass)
            })
            .collect();
        let mass0 = (f.total_mass(), f.len());
        self.runs.push(RunFigures { start, t0: sim.time(), mass0, mass_end: mass0, ..RunFigures::default() });
        Ok(())
    }

    fn after_step(&mut self, sim: &Simulation<T>, stats: &RunStats) -> Result<(), RunError> {
        if stats.last_speed > self.max_speed {
            // A new maximum (rare after the first exchanges): find its particle.
            let f = &sim.system.fluid;
            let n = f.active();
            let best = f.velocities()[..n]
                .iter()
                .map(|v| v.as_f64())
                .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((k, speed)) = best {
                self.fastest = Some(Fastest {
                    speed,
                    time: sim.time(),
                    particle: f.ids()[k],
                    position: f.positions()[k].as_f64(),
                });
            }
        }
        self.max_speed = self.max_speed.max(stats.last_speed);
        let Some(run) = self.runs.last_mut() else {
            return Ok(());
        };
        let d0 = sim.scene.solver.spacing;
        let f = &sim.system.fluid;
        let ke = sim.soil_kinetic_energy();
        run.ke.push((sim.time(), ke));
        run.mass_end = (f.total_mass(), f.len());
        run.final_speed = stats.last_speed;
        let mass = f.active_mass();
        run.rms_final = if mass > 0.0 { (2.0 * ke / mass).sqrt() } else { 0.0 };
        let inside: usize = sim.bodies().map(|b| count_inside(sim, b, 0.5 * d0)).sum();
        run.inside_max = run.inside_max.max(inside);
        let n = f.active();
        run.max_displacement = f.positions()[..n]
            .iter()
            .zip(&f.ids()[..n])
            .filter_map(|(p, id)| {
                let s = run.start.get(*id as usize)?;
                let p = p.as_f64();
                Some((0..3).map(|k| (p[k] - s[k]).powi(2)).sum::<f64>().sqrt())
            })
            .fold(0.0, f64::max);
        run.leaked = match sim.scene.container {
            Some(c) => {
                let tol = 0.5 * d0;
                f.positions()
                    .iter()
                    .map(|p| p.as_f64())
                    .filter(|p| {
                        let below_top = p[2] < c.max[2];
                        let side = (0..2).any(|k| p[k] < c.min[k] - tol || p[k] > c.max[k] + tol);
                        (side && below_top) || p[2] < c.min[2] - tol
                    })
                    .count()
            }
            None => 0,
        };
        let origins: Vec<[f64; 3]> = sim.bodies().map(|b| sim.body_state(b).origin).collect();
        run.track.push((sim.time(), origins));
        let means = mean_speeds(run.t0, &run.track);
        run.bodies = sim
            .bodies()
            .zip(means)
            .map(|(b, mean)| {
                let st = sim.body_state(b);
                let shape = &sim.scene.bodies[b.index()].desc.shape;
                let lowest = shape.lowest_z(&Pose { translation: st.origin, rotation: st.rotation });
                let surface = sim.initial_surface_height(st.origin[0], st.origin[1], 0.5 * d0).unwrap_or(f64::NAN);
                let speed = st.linvel.iter().map(|v| v * v).sum::<f64>().sqrt();
                [st.origin[2], speed, surface - lowest, mean]
            })
            .collect();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::mean_speeds;

    /// A body moving at constant velocity has that speed as its mean; one rocking in place
    /// over whole periods of the window has a mean of zero (to round-off), whatever its peaks.
    #[test]
    fn mean_speed_is_the_net_rate_over_the_last_quarter() {
        let dt = 1e-3;
        let track = |f: &dyn Fn(f64) -> [f64; 3]| -> Vec<(f64, Vec<[f64; 3]>)> {
            (0..=1000).map(|i| i as f64 * dt).map(|t| (t, vec![f(t)])).collect()
        };
        let steady = track(&|t| [0.3 * t, 0.0, -0.4 * t]);
        assert!((mean_speeds(0.0, &steady)[0] - 0.5).abs() < 1e-12);
        // 0.25 s window = 5 periods of 20 Hz; peak speed 2π·20·0.01 = 1.26 m/s.
        let rocking = track(&|t| [0.0, 0.0, 0.01 * (2.0 * std::f64::consts::PI * 20.0 * t).sin()]);
        assert!(mean_speeds(0.0, &rocking)[0] < 1e-9);
        // A single sample spans no time: not measurable.
        assert!(mean_speeds(0.0, &steady[..1])[0].is_nan());
    }
}
