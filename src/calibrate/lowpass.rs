//! Zero-phase low-pass filters, and the failure point of a triaxial test picked on the
//! filtered vertical stress (AGX's rule: the first local maximum).
//!
//! Two filters, with the same cutoff convention (the frequency, as a fraction of Nyquist, at
//! which a sine keeps half its amplitude):
//! - **Gaussian**: convolution with a normalised Gaussian kernel. Its kernel is positive, so
//!   it cannot raise a concave stretch of a curve above the curve (Jensen): the kink where an
//!   elastic–perfectly plastic sample yields comes out rounded, never overshooting.
//! - **Butterworth** of order n (AGX's filter): the bilinear transform with a pre-warped
//!   cutoff, as cascaded second-order sections (and one first-order section for an odd
//!   order), run forward then backward (squared magnitude response). Its kernel has negative
//!   lobes: at such a kink it overshoots by about 1.6 % of (slope jump × filter wavelength)
//!   for order 4, the same amount whatever the stress level, which the first-peak rule turns
//!   into an apparent cohesion (unit test below).
//!
//! Both take out the signal's end-to-end straight line and extend the rest at both ends by
//! odd reflection, so a straight line passes unchanged and the ends carry no transient.

use serde::{Deserialize, Serialize};

/// One section in transposed direct form II: `b` over `a` with `a0 = 1`.
#[derive(Clone, Copy, Debug)]
struct Section {
    b: [f64; 3],
    a: [f64; 3],
}

impl Section {
    /// Runs the section over `x` in place, starting from the steady state of a constant
    /// input equal to `x[0]` (every section has unit gain at zero frequency).
    fn run(&self, x: &mut [f64]) {
        let Some(&u0) = x.first() else { return };
        let [b0, b1, b2] = self.b;
        let [_, a1, a2] = self.a;
        let (mut z1, mut z2) = ((1.0 - b0) * u0, (b2 - a2) * u0);
        for v in x.iter_mut() {
            let u = *v;
            let y = b0 * u + z1;
            z1 = b1 * u - a1 * y + z2;
            z2 = b2 * u - a2 * y;
            *v = y;
        }
    }
}

/// A digital Butterworth low-pass of order `order` with its cutoff at `cutoff` times the
/// Nyquist frequency.
#[derive(Clone, Debug)]
pub struct Butterworth {
    sections: Vec<Section>,
    cutoff: f64,
}

/// Why a filter cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FilterError {
    /// Order 0.
    #[error("filter order must be at least 1")]
    Order,
    /// Cutoff outside (0, 1).
    #[error("the cutoff must lie strictly between 0 and the Nyquist frequency (got {0} of it)")]
    Cutoff(f64),
}

impl Butterworth {
    /// Designs the filter (bilinear transform, cutoff pre-warped so that the digital response
    /// is −3 dB at `cutoff` × Nyquist).
    pub fn new(order: usize, cutoff: f64) -> Result<Self, FilterError> {
        if order == 0 {
            return Err(FilterError::Order);
        }
        if !(cutoff > 0.0 && cutoff < 1.0) {
            return Err(FilterError::Cutoff(cutoff));
        }
        let k = (std::f64::consts::FRAC_PI_2 * cutoff).tan();
        let k2 = k * k;
        let mut sections = Vec::new();
        // Pole pairs of the analogue prototype: s² + 2 sin((2j+1)π/(2n)) s + 1.
        for j in 0..order / 2 {
            let b = 2.0 * ((2 * j + 1) as f64 * std::f64::consts::PI / (2 * order) as f64).sin();
            let a0 = 1.0 + b * k + k2;
            sections.push(Section {
                b: [k2 / a0, 2.0 * k2 / a0, k2 / a0],
                a: [1.0, 2.0 * (k2 - 1.0) / a0, (1.0 - b * k + k2) / a0],
            });
        }
        if order % 2 == 1 {
            // The real pole: 1 / (s + 1).
            let a0 = 1.0 + k;
            sections.push(Section { b: [k / a0, k / a0, 0.0], a: [1.0, (k - 1.0) / a0, 0.0] });
        }
        Ok(Self { sections, cutoff })
    }

    /// Runs the filter forward and backward over `x` (zero phase), the end-to-end line taken
    /// out and the rest extended by odd reflection (see the module's notes).
    pub fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        zero_phase(x, (6.0 / self.cutoff).ceil() as usize, |y| {
            for s in &self.sections {
                s.run(y);
            }
            y.reverse();
            for s in &self.sections {
                s.run(y);
            }
            y.reverse();
        })
    }
}

/// Runs `filter` on `x` less the straight line through its first and last samples, extended
/// at both ends by odd reflection over `pad` samples (or the whole signal, if shorter), and
/// puts the line back: a line passes exactly and the ends carry no start-up transient.
fn zero_phase(x: &[f64], pad: usize, filter: impl FnOnce(&mut Vec<f64>)) -> Vec<f64> {
    let n = x.len();
    if n < 2 {
        return x.to_vec();
    }
    let slope = (x[n - 1] - x[0]) / (n - 1) as f64;
    let line = |i: usize| x[0] + slope * i as f64;
    let r: Vec<f64> = x.iter().enumerate().map(|(i, v)| v - line(i)).collect();
    let pad = pad.min(n - 1);
    // The residual is zero at both ends, so its odd reflection is minus its mirror image.
    let mut y = Vec::with_capacity(n + 2 * pad);
    y.extend((1..=pad).rev().map(|i| -r[i]));
    y.extend_from_slice(&r);
    y.extend((1..=pad).map(|i| -r[n - 1 - i]));
    filter(&mut y);
    y[pad..pad + n].iter().enumerate().map(|(i, v)| v + line(i)).collect()
}

/// A Gaussian low-pass: convolution with a normalised Gaussian kernel (zero phase, positive).
#[derive(Clone, Debug)]
pub struct Gaussian {
    kernel: Vec<f64>,
}

impl Gaussian {
    /// The kernel whose response `exp(−2π² σ² f²)` is 1/2 at `cutoff` × Nyquist (a sine there
    /// keeps half its amplitude, as through the Butterworth filtfilt), truncated at ±4σ.
    pub fn new(cutoff: f64) -> Result<Self, FilterError> {
        if !(cutoff > 0.0 && cutoff < 1.0) {
            return Err(FilterError::Cutoff(cutoff));
        }
        let f = 0.5 * cutoff;
        let sigma = (std::f64::consts::LN_2 / 2.0).sqrt() / (std::f64::consts::PI * f);
        let half = (4.0 * sigma).ceil() as i64;
        let w: Vec<f64> = (-half..=half).map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp()).collect();
        let total: f64 = w.iter().sum();
        Ok(Self { kernel: w.into_iter().map(|v| v / total).collect() })
    }

    /// Filters `x` (zero phase), the end-to-end line taken out and the rest extended by odd
    /// reflection (see the module's notes).
    pub fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        let half = self.kernel.len() / 2;
        zero_phase(x, half, |y| {
            let src = y.clone();
            for (i, v) in y.iter_mut().enumerate() {
                let mut acc = 0.0;
                let mut norm = 0.0;
                for (k, w) in self.kernel.iter().enumerate() {
                    // Samples past the padded ends drop out and the weights are renormalised.
                    if let Some(u) = (i + k).checked_sub(half).and_then(|j| src.get(j)) {
                        acc += w * u;
                        norm += w;
                    }
                }
                *v = acc / norm;
            }
        })
    }
}

/// Which low-pass filter smooths a record before the failure pick.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FilterKind {
    /// A Gaussian kernel: no overshoot at a yield kink (the default).
    Gaussian,
    /// AGX's Butterworth of the given order, run forward and backward.
    Butterworth,
}

/// A designed zero-phase low-pass of either kind.
#[derive(Clone, Debug)]
pub enum LowPass {
    /// See [`Gaussian`].
    Gaussian(Gaussian),
    /// See [`Butterworth`].
    Butterworth(Butterworth),
}

impl LowPass {
    /// Designs the filter; `order` is the Butterworth's (a Gaussian has none).
    pub fn new(kind: FilterKind, order: usize, cutoff: f64) -> Result<Self, FilterError> {
        Ok(match kind {
            FilterKind::Gaussian => Self::Gaussian(Gaussian::new(cutoff)?),
            FilterKind::Butterworth => Self::Butterworth(Butterworth::new(order, cutoff)?),
        })
    }

    /// Filters `x` with zero phase.
    pub fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        match self {
            Self::Gaussian(g) => g.filtfilt(x),
            Self::Butterworth(b) => b.filtfilt(x),
        }
    }
}

/// How a test's failure point was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// The first local maximum of the filtered vertical stress (AGX's rule).
    Peak,
    /// The mean of the filtered vertical stress over the last part of the test: the critical
    /// state (asked for, or no peak was found before the end).
    Plateau,
}

/// A picked failure point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Failure {
    /// How it was found.
    pub kind: FailureKind,
    /// Sample index (for a plateau: the first sample of the averaged tail).
    pub index: usize,
    /// The filtered vertical stress there (Pa; for a plateau, the tail's mean).
    pub value: f64,
}

/// The first local maximum of `y` over a window of `half` samples on each side (the maximum
/// of `y[i − half ..= i + half]`, with the window complete after it) at which `y ≥ floor`.
pub fn first_peak(y: &[f64], half: usize, floor: f64) -> Option<usize> {
    let half = half.max(1);
    (0..y.len()).find(|&i| {
        if i + half >= y.len() || y[i] < floor {
            return false;
        }
        let lo = i.saturating_sub(half);
        y[lo..=i + half].iter().all(|&v| v <= y[i]) && y[i + half] < y[i]
    })
}

/// The mean of `y` over its last `fraction` (at least one sample), and where that tail starts.
pub fn plateau(y: &[f64], fraction: f64) -> Option<(usize, f64)> {
    if y.is_empty() {
        return None;
    }
    let k = ((y.len() as f64 * fraction).ceil() as usize).clamp(1, y.len());
    let start = y.len() - k;
    Some((start, y[start..].iter().sum::<f64>() / k as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(n: usize, cycles_per_sample: f64, amp: f64) -> Vec<f64> {
        (0..n).map(|i| amp * (std::f64::consts::TAU * cycles_per_sample * i as f64).sin()).collect()
    }

    #[test]
    fn a_straight_line_passes_unchanged() {
        let f = Butterworth::new(4, 0.1).expect("design");
        let x: Vec<f64> = (0..200).map(|i| 3.0 + 0.25 * i as f64).collect();
        let y = f.filtfilt(&x);
        for (a, b) in x.iter().zip(&y) {
            assert!((a - b).abs() < 1e-9 * (1.0 + a.abs()), "{a} became {b}");
        }
    }

    /// The squared Butterworth magnitude |H|² = 1 / (1 + (ω/ωc)^(2n)), applied twice: at the
    /// cutoff a filtfilt halves a sine's amplitude; an octave below it passes, a decade above
    /// it is gone.
    #[test]
    fn the_response_is_the_butterworth_magnitude_squared() {
        for order in [2, 3, 4] {
            let wn = 0.1;
            let f = Butterworth::new(order, wn).expect("design");
            let amp_at = |ratio: f64| {
                let x = sine(4000, 0.5 * wn * ratio, 1.0);
                let y = f.filtfilt(&x);
                // The middle, away from the ends.
                y[1000..3000].iter().fold(0.0f64, |m, v| m.max(v.abs()))
            };
            assert!((amp_at(1.0) - 0.5).abs() < 0.02, "order {order}: {} at the cutoff", amp_at(1.0));
            let below = 1.0 / (1.0 + 0.5f64.powi(2 * order as i32));
            assert!((amp_at(0.5) - below).abs() < 0.02, "order {order}: {} an octave below", amp_at(0.5));
            assert!(amp_at(8.0) < 1e-3, "order {order}: {} three octaves above", amp_at(8.0));
        }
    }

    #[test]
    fn zero_phase_keeps_a_bump_where_it_was() {
        let f = Butterworth::new(4, 0.05).expect("design");
        let x: Vec<f64> = (0..400).map(|i| (-((i as f64 - 170.0) / 25.0).powi(2)).exp()).collect();
        let y = f.filtfilt(&x);
        let at = y.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| i);
        assert_eq!(at, Some(170));
    }

    /// An elastic–perfectly plastic record (σ1 rising at E per unit strain from σ3 to 3 σ3,
    /// then flat) at three confining stresses, sampled as the triaxial test samples it
    /// (2e-4 strain apart, wavelength 1 % strain). The Butterworth's first peak stands a
    /// constant 1.6 % of E × wavelength above the plateau at every stress (an apparent
    /// cohesion of that over 2√Kp); the Gaussian's filtered record never rises above the
    /// plateau, so whatever it picks is the plateau stress.
    #[test]
    fn a_butterworth_overshoots_a_yield_kink_by_a_constant_and_a_gaussian_does_not() {
        let (e, de, wavelength): (f64, f64, f64) = (2e6, 2e-4, 0.01);
        let cutoff = 2.0 * de / wavelength;
        let half = (wavelength / de).round() as usize;
        let butterworth = LowPass::new(FilterKind::Butterworth, 4, cutoff).expect("design");
        let gaussian = LowPass::new(FilterKind::Gaussian, 0, cutoff).expect("design");
        for s3 in [10e3, 20e3, 30e3] {
            let x: Vec<f64> = (0..300).map(|i| (s3 + e * de * i as f64).min(3.0 * s3)).collect();
            let yb = butterworth.filtfilt(&x);
            let i = first_peak(&yb, half, 1.25 * s3).expect("the Butterworth rings into a peak");
            let over = (yb[i] - 3.0 * s3) / (e * wavelength);
            assert!((over - 0.0159).abs() < 0.0005, "σ3 = {s3}: overshoot {over} of E λ");
            let yg = gaussian.filtfilt(&x);
            assert!(yg.iter().zip(&x).all(|(g, v)| *g <= v + 1e-9 * s3), "σ3 = {s3}: Gaussian above the record");
            // On the flat tail round-off may make a "peak"; it cannot stand above the plateau.
            if let Some(i) = first_peak(&yg, half, 1.25 * s3) {
                assert!(yg[i] <= 3.0 * s3 * (1.0 + 1e-9), "σ3 = {s3}: Gaussian peak {} above 3 σ3", yg[i]);
            }
            let (_, p) = plateau(&yg, 0.2).expect("a tail");
            assert!((p / (3.0 * s3) - 1.0).abs() < 1e-9, "σ3 = {s3}: plateau {p}");
        }
    }

    #[test]
    fn a_gaussian_has_the_same_half_amplitude_cutoff_and_passes_a_line() {
        let wn = 0.1;
        let g = Gaussian::new(wn).expect("design");
        let amp_at = |ratio: f64| {
            let y = g.filtfilt(&sine(4000, 0.5 * wn * ratio, 1.0));
            y[1000..3000].iter().fold(0.0f64, |m, v| m.max(v.abs()))
        };
        assert!((amp_at(1.0) - 0.5).abs() < 0.01, "{} at the cutoff", amp_at(1.0));
        assert!(amp_at(4.0) < 1e-3, "{} two octaves above", amp_at(4.0));
        let x: Vec<f64> = (0..200).map(|i| 3.0 + 0.25 * i as f64).collect();
        for (a, b) in x.iter().zip(g.filtfilt(&x)) {
            assert!((a - b).abs() < 1e-9 * (1.0 + a.abs()), "{a} became {b}");
        }
    }

    #[test]
    fn bad_designs_are_errors() {
        assert_eq!(Gaussian::new(1.0).err(), Some(FilterError::Cutoff(1.0)));
        assert_eq!(Butterworth::new(0, 0.1).err(), Some(FilterError::Order));
        assert_eq!(Butterworth::new(4, 1.0).err(), Some(FilterError::Cutoff(1.0)));
        assert_eq!(Butterworth::new(4, 0.0).err(), Some(FilterError::Cutoff(0.0)));
    }

    #[test]
    fn the_first_peak_is_found_on_a_noisy_softening_curve() {
        // Rise to a peak at sample 300, soften to 80 % by 500, then flat, plus noise.
        let n = 800;
        let clean: Vec<f64> = (0..n)
            .map(|i| {
                let i = i as f64;
                if i < 300.0 {
                    100.0 * (i / 300.0) * (2.0 - i / 300.0)
                } else if i < 500.0 {
                    100.0 - 20.0 * (i - 300.0) / 200.0
                } else {
                    80.0
                }
            })
            .collect();
        let noisy: Vec<f64> = clean.iter().zip(sine(n, 0.23, 3.0)).map(|(a, b)| a + b).collect();
        let y = Butterworth::new(4, 0.04).expect("design").filtfilt(&noisy);
        let i = first_peak(&y, 25, 50.0).expect("a peak");
        assert!((i as i64 - 300).abs() <= 15, "peak at {i}");
        assert!((y[i] - 100.0).abs() < 2.0, "peak value {}", y[i]);
        // A monotonic rise has no peak; its plateau is its tail.
        let rise: Vec<f64> = (0..100).map(|i| i as f64).collect();
        assert_eq!(first_peak(&rise, 5, 0.0), None);
        assert_eq!(plateau(&rise, 0.1), Some((90, 94.5)));
        // Below the floor nothing counts.
        assert_eq!(first_peak(&y, 25, 150.0), None);
    }
}
