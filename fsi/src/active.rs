//! Active domains: integrate only the soil near the bodies.
//!
//! Each FSI body owns a box in its own frame (its markers' bounding box grown by a margin).
//! At a *classification* every soil particle inside the domain gets one of three roles:
//! - **awake**: inside some body's box grown by the travel allowance, or moving faster than the
//!   sleep speed; integrated every step;
//! - **extended**: not awake, but in a neighbour-grid cell within the kernel support (2h) plus
//!   one cell of a cell holding an awake particle; a neighbour of awake particles, its state
//!   frozen;
//! - **asleep**: everything else; not sorted, searched or integrated, its state kept exactly.
//!
//! A classification stays valid while (a) every box's corners have moved less than the travel
//! allowance since it was made (a rigid motion moves no point of a box farther than its
//! farthest-moving corner, so each box then still lies inside the awake region), and (b) every
//! awake particle is within one cell of a cell that held an awake particle (so its neighbours
//! are awake or extended). The solver checks both every step and classifies again when either
//! fails: the neighbours of every awake particle are then exactly those of the full-domain
//! run, and the only difference from it is that extended and sleeping soil does not move. A sleeping
//! particle wakes with the state it fell asleep with: no jump in stress or velocity.

use regolith_body::BodyState;

/// How the active region is kept (`[sph.active]` of a scene).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveSettings {
    /// Distance (m) a box's corners may move before the particles are classified again; the
    /// awake region is each box grown by it.
    pub travel: f64,
    /// A particle faster than this (m/s) at a classification stays awake wherever it is.
    pub sleep_speed: f64,
    /// Until this time (s) the whole domain is awake (the bed settles).
    pub free_flow_time: f64,
}

impl ActiveSettings {
    /// Checks the settings: a positive finite travel, a non-negative sleep speed and free-flow
    /// time. Returns the offending field's name and what is allowed.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if !(self.travel.is_finite() && self.travel > 0.0) {
            return Err(("travel", format!("must be > 0 m (got {})", self.travel)));
        }
        if !(self.sleep_speed.is_finite() && self.sleep_speed >= 0.0) {
            return Err(("sleep_speed", format!("must be >= 0 m/s (got {})", self.sleep_speed)));
        }
        if !(self.free_flow_time.is_finite() && self.free_flow_time >= 0.0) {
            return Err(("free_flow_time", format!("must be >= 0 s (got {})", self.free_flow_time)));
        }
        Ok(())
    }
}

/// A box fixed in a body's frame: centre and half-extents along the body's axes (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyBox {
    /// Centre, body frame (m).
    pub center: [f64; 3],
    /// Half-extents along the body's x, y, z (m).
    pub half: [f64; 3],
}

impl BodyBox {
    /// The bounding box of body-frame points (a point box at the body origin for none).
    pub fn around(points: &[[f64; 3]]) -> Self {
        let Some(first) = points.first() else { return Self { center: [0.0; 3], half: [0.0; 3] } };
        let (mut lo, mut hi) = (*first, *first);
        for p in points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Self { center: [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])), half: [0, 1, 2].map(|k| 0.5 * (hi[k] - lo[k])) }
    }

    /// The box grown by `margin` (m) on every side.
    pub fn grown(&self, margin: f64) -> Self {
        Self { center: self.center, half: self.half.map(|h| h + margin) }
    }

    /// Where the box is for a body in state `s`.
    pub fn place(&self, s: &BodyState) -> WorldBox {
        let c = s.to_world(self.center);
        let axes = [0, 1, 2].map(|k| {
            let mut e = self.center;
            e[k] += 1.0;
            let p = s.to_world(e);
            [p[0] - c[0], p[1] - c[1], p[2] - c[2]]
        });
        WorldBox { center: c, axes, half: self.half }
    }
}

/// A box placed in the world: centre, unit axes and half-extents (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldBox {
    /// Centre (m).
    pub center: [f64; 3],
    /// Unit axes (the body's x, y, z in the world frame).
    pub axes: [[f64; 3]; 3],
    /// Half-extents along the axes (m).
    pub half: [f64; 3],
}

impl WorldBox {
    /// True when `p` lies in the box grown by `grow` (m) along each axis.
    #[inline]
    pub fn contains(&self, p: [f64; 3], grow: f64) -> bool {
        let d = [p[0] - self.center[0], p[1] - self.center[1], p[2] - self.center[2]];
        (0..3).all(|k| {
            let a = self.axes[k];
            (d[0] * a[0] + d[1] * a[1] + d[2] * a[2]).abs() <= self.half[k] + grow
        })
    }

    /// The eight corners (m).
    pub fn corners(&self) -> [[f64; 3]; 8] {
        std::array::from_fn(|i| {
            let s = [0, 1, 2].map(|k| if i >> k & 1 == 1 { 1.0 } else { -1.0 });
            [0, 1, 2].map(|j| self.center[j] + (0..3).map(|k| s[k] * self.half[k] * self.axes[k][j]).sum::<f64>())
        })
    }

    /// The farthest any corner has moved from `earlier` (m): under a rigid motion, the
    /// farthest any point of the box has moved.
    pub fn drift_from(&self, earlier: &WorldBox) -> f64 {
        self.corners()
            .iter()
            .zip(earlier.corners())
            .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt())
            .fold(0.0, f64::max)
    }
}

/// What a solver needs to keep an active region: the settings and one box per FSI body, in
/// the order of the bodies passed to [`crate::SphSolver::place_bodies`].
#[derive(Clone, Debug, PartialEq)]
pub struct ActiveDomain {
    /// Settings.
    pub settings: ActiveSettings,
    /// One box per FSI body.
    pub boxes: Vec<BodyBox>,
}

/// Role of a particle at a classification.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub enum Role {
    /// Integrated.
    Awake = 0,
    /// Neighbour only, frozen.
    Extended = 1,
    /// Excluded, state kept.
    Asleep = 2,
    /// Outside the neighbour grid (escaped).
    Outside = 3,
}

/// Counts of each role.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RoleCounts {
    /// Awake particles.
    pub awake: usize,
    /// Extended particles.
    pub extended: usize,
    /// Sleeping particles.
    pub asleep: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(origin: [f64; 3], angle_y: f64) -> BodyState {
        let h = 0.5 * angle_y;
        BodyState {
            origin,
            com: origin,
            rotation: [0.0, h.sin(), 0.0, h.cos()],
            linvel: [0.0; 3],
            angvel: [0.0; 3],
            linacc: [0.0; 3],
            angacc: [0.0; 3],
        }
    }

    #[test]
    fn a_box_follows_its_body_and_its_drift_bounds_every_point() {
        let b = BodyBox::around(&[[-0.1, -0.05, -0.1], [0.1, 0.05, 0.1]]).grown(0.02);
        assert_eq!(BodyBox::around(&[]).grown(0.1).half, [0.1; 3]);
        for (h, want) in b.half.iter().zip([0.12, 0.07, 0.12]) {
            assert!((h - want).abs() < 1e-15);
        }
        let w0 = b.place(&state([1.0, 0.0, 0.5], 0.0));
        assert!(w0.contains([1.1199, 0.0, 0.5], 0.0));
        assert!(!w0.contains([1.13, 0.0, 0.5], 0.0));
        assert!(w0.contains([1.13, 0.0, 0.5], 0.011));
        // Rotated by 45° about y: the corner direction (1, 0, 1)/√2 now points along +x.
        let w1 = b.place(&state([1.0, 0.0, 0.5], std::f64::consts::FRAC_PI_4));
        let r = 0.12 * 2f64.sqrt();
        assert!(w1.contains([1.0 + r - 1e-9, 0.0, 0.5], 0.0));
        assert!(!w0.contains([1.0 + r - 1e-9, 0.0, 0.5], 0.0));
        // Every point of the rotated box lies in the old box grown by the drift.
        let d = w1.drift_from(&w0);
        for i in 0..=10 {
            for j in 0..=10 {
                let (u, v) = (i as f64 / 5.0 - 1.0, j as f64 / 5.0 - 1.0);
                let p =
                    [0, 1, 2].map(|k| w1.center[k] + u * w1.half[0] * w1.axes[0][k] + v * w1.half[2] * w1.axes[2][k]);
                assert!(w1.contains(p, 1e-12));
                assert!(w0.contains(p, d + 1e-12), "point {p:?} outside the old box grown by {d}");
            }
        }
        // A pure translation drifts by its length.
        let w2 = b.place(&state([1.3, 0.0, 0.5], 0.0));
        assert!((w2.drift_from(&w0) - 0.3).abs() < 1e-12);
    }

    #[test]
    fn settings_name_what_is_wrong() {
        let ok = ActiveSettings { travel: 0.02, sleep_speed: 0.01, free_flow_time: 0.0 };
        assert!(ok.validate().is_ok());
        assert_eq!(ActiveSettings { travel: 0.0, ..ok }.validate().unwrap_err().0, "travel");
        assert_eq!(ActiveSettings { sleep_speed: f64::NAN, ..ok }.validate().unwrap_err().0, "sleep_speed");
        assert_eq!(ActiveSettings { free_flow_time: -1.0, ..ok }.validate().unwrap_err().0, "free_flow_time");
    }
}
