//! # regolith-body
//!
//! The one interface between the soil and the rigid-body solver, as Chrono's `FsiBodyState` /
//! `FsiBodyForce`: a body's [`BodyState`] goes to the soil (to place its BCE markers), a
//! [`Wrench`] comes back. Both are plain `f64` world-frame values, so the soil crates
//! (`regolith-fsi`, `regolith-wgpu`), the coupling and the rapier side (`regolith-rigid`)
//! share them without depending on each other. Quaternions are `[x, y, z, w]`.

/// A rigid body's state in the world frame (SI). Velocities and accelerations are those of
/// the centre of mass.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyState {
    /// Body-frame origin (m).
    pub origin: [f64; 3],
    /// Centre of mass (m).
    pub com: [f64; 3],
    /// Orientation, unit quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
    /// Linear velocity of the centre of mass (m/s).
    pub linvel: [f64; 3],
    /// Angular velocity (rad/s).
    pub angvel: [f64; 3],
    /// Linear acceleration of the centre of mass (m/s²).
    pub linacc: [f64; 3],
    /// Angular acceleration (rad/s²).
    pub angacc: [f64; 3],
}

impl BodyState {
    /// Body-frame point to world (m).
    pub fn to_world(&self, local: [f64; 3]) -> [f64; 3] {
        add(self.origin, quat_rotate(self.rotation, local))
    }
    /// Velocity of a world point moving with the body (m/s).
    pub fn velocity_at(&self, p: [f64; 3]) -> [f64; 3] {
        add(self.linvel, cross(self.angvel, sub(p, self.com)))
    }
    /// Acceleration of a world point moving with the body (m/s²), rigid-body kinematics.
    pub fn acceleration_at(&self, p: [f64; 3]) -> [f64; 3] {
        let r = sub(p, self.com);
        add(add(self.linacc, cross(self.angacc, r)), cross(self.angvel, cross(self.angvel, r)))
    }
    /// A body-frame point's world position, velocity and acceleration.
    pub fn point(&self, local: [f64; 3]) -> [[f64; 3]; 3] {
        let x = self.to_world(local);
        [x, self.velocity_at(x), self.acceleration_at(x)]
    }
    /// The state advanced by `tau` (s) at constant linear and angular velocity.
    pub fn extrapolate(&self, tau: f64) -> BodyState {
        let w = self.angvel;
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        let rotation = if n * tau > 0.0 {
            let half = 0.5 * n * tau;
            let k = half.sin() / n;
            let dq = [w[0] * k, w[1] * k, w[2] * k, half.cos()];
            quat_mul(dq, self.rotation)
        } else {
            self.rotation
        };
        let com = add(self.com, scale(self.linvel, tau));
        // The origin keeps its body-frame offset from the centre of mass.
        let offset_local = quat_rotate(quat_conj(self.rotation), sub(self.origin, self.com));
        let origin = add(com, quat_rotate(rotation, offset_local));
        BodyState { origin, com, rotation, ..*self }
    }
}

/// A force (N) and a torque about the centre of mass (N m), world frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrench {
    /// Force (N).
    pub force: [f64; 3],
    /// Torque about the centre of mass (N m).
    pub torque: [f64; 3],
}

impl Wrench {
    /// `self + s · other`.
    pub fn add_scaled(&self, other: &Wrench, s: f64) -> Wrench {
        Wrench { force: add(self.force, scale(other.force, s)), torque: add(self.torque, scale(other.torque, s)) }
    }
    /// `s · self`.
    pub fn scaled(&self, s: f64) -> Wrench {
        Wrench { force: scale(self.force, s), torque: scale(self.torque, s) }
    }
}

/// Rotates `v` by the unit quaternion `q = [x, y, z, w]`.
pub fn quat_rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [x, y, z, w] = q;
    // t = 2 q_v × v; v' = v + w t + q_v × t
    let t = [2.0 * (y * v[2] - z * v[1]), 2.0 * (z * v[0] - x * v[2]), 2.0 * (x * v[1] - y * v[0])];
    [
        v[0] + w * t[0] + (y * t[2] - z * t[1]),
        v[1] + w * t[1] + (z * t[0] - x * t[2]),
        v[2] + w * t[2] + (x * t[1] - y * t[0]),
    ]
}

/// Hamilton product `a b`.
pub fn quat_mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// The conjugate (the inverse of a unit quaternion).
pub fn quat_conj(q: [f64; 4]) -> [f64; 4] {
    [-q[0], -q[1], -q[2], q[3]]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spinning() -> BodyState {
        let h = 0.3_f64;
        BodyState {
            origin: [1.0, 2.0, 3.0],
            com: [1.1, 2.0, 2.9],
            rotation: [0.0, 0.0, h.sin(), h.cos()],
            linvel: [0.5, 0.0, -0.1],
            angvel: [0.0, 0.0, 2.0],
            linacc: [0.0, 0.0, -9.81],
            angacc: [0.0, 1.0, 0.0],
        }
    }

    #[test]
    fn a_point_moves_rigidly() {
        let s = spinning();
        let l = [0.2, -0.1, 0.05];
        let [x, v, a] = s.point(l);
        // Velocity: ω × r with ω along z; acceleration includes the centripetal −ω² r⊥.
        let r = [x[0] - s.com[0], x[1] - s.com[1], x[2] - s.com[2]];
        let want_v = [0.5 - 2.0 * r[1], 2.0 * r[0], -0.1];
        let want_a = [r[2] - 4.0 * r[0], -4.0 * r[1], -9.81 - r[0]];
        for k in 0..3 {
            assert!((v[k] - want_v[k]).abs() < 1e-12, "{v:?} {want_v:?}");
            assert!((a[k] - want_a[k]).abs() < 1e-12, "{a:?} {want_a:?}");
        }
        // The rotation keeps the point's distance from the origin.
        let n = |p: [f64; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!((n(sub(x, s.origin)) - n(l)).abs() < 1e-12);
    }

    #[test]
    fn extrapolation_keeps_the_origin_offset_and_turns_by_omega_tau() {
        let s = spinning();
        let e = s.extrapolate(0.25);
        let before = quat_rotate(quat_conj(s.rotation), sub(s.origin, s.com));
        let after = quat_rotate(quat_conj(e.rotation), sub(e.origin, e.com));
        for k in 0..3 {
            assert!((before[k] - after[k]).abs() < 1e-12);
        }
        // Yaw grew by ω τ = 0.5 rad: the quaternion's half angle went from 0.3 to 0.55.
        assert!((e.rotation[3] - 0.55_f64.cos()).abs() < 1e-12);
        assert!((e.com[0] - (1.1 + 0.125)).abs() < 1e-12);
        assert_eq!(s.extrapolate(0.0), s);
    }

    #[test]
    fn wrench_arithmetic() {
        let a = Wrench { force: [1.0, 2.0, 3.0], torque: [0.0, -1.0, 0.5] };
        let b = a.add_scaled(&a, 2.0).scaled(0.5);
        assert_eq!(b, Wrench { force: [1.5, 3.0, 4.5], torque: [0.0, -1.5, 0.75] });
    }
}
