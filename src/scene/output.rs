//! `[output]`: where and how often a run records.

use super::*;

pub(super) fn resolve_output(
    o: OutputFile,
    end_time: f64,
    exchange: f64,
    e: &dyn Fn(&str, String) -> InputError,
) -> Result<OutputSpec, InputError> {
    let dir = match o.dir {
        Some(d) if d.trim().is_empty() => return Err(e("output.dir", "must not be empty".into())),
        d => d.map(PathBuf::from),
    };
    // 100 frames by default, never closer than one exchange interval.
    let every = o.every.unwrap_or((end_time / 100.0).max(exchange));
    if !(every.is_finite() && every > 0.0) {
        return Err(e("output.every", format!("must be > 0 s (got {every})")));
    }
    if every < exchange * (1.0 - 1e-9) {
        return Err(e(
            "output.every",
            format!(
                "must be at least simulation.exchange_interval = {exchange} s: frames are taken between exchanges (got {every})"
            ),
        ));
    }
    let decimate = o.decimate.unwrap_or(1);
    if decimate < 1 {
        return Err(e(
            "output.decimate",
            format!("must be an integer ≥ 1: record every n-th particle (got {decimate})"),
        ));
    }
    let roi = match (o.roi_min, o.roi_max) {
        (None, None) => None,
        (Some(lo), Some(hi)) => {
            if lo.iter().chain(&hi).any(|v| !v.is_finite()) || (0..3).any(|k| lo[k] >= hi[k]) {
                return Err(e(
                    "output.roi_max",
                    format!("must be finite and above roi_min on every axis (got {lo:?} .. {hi:?})"),
                ));
            }
            Some((lo, hi))
        }
        (Some(_), None) => {
            return Err(e("output.roi_max", "is required with roi_min (the region of interest is a box)".into()));
        }
        (None, Some(_)) => {
            return Err(e("output.roi_min", "is required with roi_max (the region of interest is a box)".into()));
        }
    };
    let mcap = o.mcap.unwrap_or(cfg!(feature = "mcap"));
    if mcap && !cfg!(feature = "mcap") {
        return Err(e("output.mcap", "this build of regolith has no `mcap` feature: set it to false".into()));
    }
    if !mcap && (o.particles.is_some() || o.decimate.is_some() || roi.is_some()) {
        return Err(e(
            "output.mcap",
            "is false but particles, decimate or roi are set; they configure the recording".into(),
        ));
    }
    Ok(OutputSpec { dir, every, mcap, particles: o.particles.unwrap_or(true), decimate: decimate as usize, roi })
}
