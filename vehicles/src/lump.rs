//! Mass properties of links joined by fixed joints, combined into one body (what Gazebo and
//! Isaac call lumping): masses add, the centre of mass is the mass-weighted mean, and each
//! part's inertia is rotated into the body frame and moved to the common centre of mass by the
//! parallel-axis theorem.

use regolith_rigid::Pose;

/// A mass (kg), its centre of mass (m) and its inertia about the centre of mass
/// (`[ixx, iyy, izz, ixy, ixz, iyz]`, kg m²), both in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MassProperties {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass (m).
    pub com: [f64; 3],
    /// Inertia about the centre of mass, `[ixx, iyy, izz, ixy, ixz, iyz]` (kg m²).
    pub inertia: [f64; 6],
}

/// `R I Rᵀ` for a symmetric tensor given as `[ixx, iyy, izz, ixy, ixz, iyz]`: the tensor of a
/// frame rotated by `rot`, seen in the outer frame.
pub fn rotate_inertia(rot: &Pose, i: [f64; 6]) -> [f64; 6] {
    let [xx, yy, zz, xy, xz, yz] = i;
    let m = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
    let cols = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| rot.rotate(e));
    // r[a][b] = R_ab: column b of R is the image of e_b.
    let r = |a: usize, b: usize| cols[b][a];
    let mut out = [[0.0; 3]; 3];
    for (a, row) in out.iter_mut().enumerate() {
        for (b, o) in row.iter_mut().enumerate() {
            *o = m
                .iter()
                .enumerate()
                .flat_map(|(k, mk)| mk.iter().enumerate().map(move |(l, mkl)| (k, l, *mkl)))
                .map(|(k, l, mkl)| r(a, k) * mkl * r(b, l))
                .sum();
        }
    }
    [out[0][0], out[1][1], out[2][2], out[0][1], out[0][2], out[1][2]]
}

/// The parts, each given in its own frame at `pose` in the body frame, as one body (body frame).
/// Massless parts add nothing; with no mass at all the result is all zeros.
pub fn combine_mass(parts: &[(Pose, MassProperties)]) -> MassProperties {
    let mass: f64 = parts.iter().map(|(_, p)| p.mass).sum();
    if mass <= 0.0 {
        return MassProperties::default();
    }
    let placed: Vec<(f64, [f64; 3], [f64; 6])> = parts
        .iter()
        .filter(|(_, p)| p.mass > 0.0)
        .map(|(at, p)| (p.mass, at.apply(p.com), rotate_inertia(at, p.inertia)))
        .collect();
    let com = [0, 1, 2].map(|k| placed.iter().map(|(m, c, _)| m * c[k]).sum::<f64>() / mass);
    let mut inertia = [0.0; 6];
    for (m, c, i) in &placed {
        let d = [0, 1, 2].map(|k| c[k] - com[k]);
        // Parallel axis: I + m (|d|² E − d dᵀ).
        let shift = [
            d[1] * d[1] + d[2] * d[2],
            d[0] * d[0] + d[2] * d[2],
            d[0] * d[0] + d[1] * d[1],
            -d[0] * d[1],
            -d[0] * d[2],
            -d[1] * d[2],
        ];
        for k in 0..6 {
            inertia[k] += i[k] + m * shift[k];
        }
    }
    MassProperties { mass, com, inertia }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 6], b: [f64; 6]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn two_point_masses_make_a_dumbbell() {
        // 1 kg at x = ±0.5 m: com at 0, Iyy = Izz = 2 × 1 × 0.25, Ixx = 0.
        let point = MassProperties { mass: 1.0, ..Default::default() };
        let b =
            combine_mass(&[(Pose::translation([0.5, 0.0, 0.0]), point), (Pose::translation([-0.5, 0.0, 0.0]), point)]);
        assert_eq!(b.mass, 2.0);
        assert_eq!(b.com, [0.0; 3]);
        assert!(close(b.inertia, [0.0, 0.5, 0.5, 0.0, 0.0, 0.0]), "{:?}", b.inertia);
    }

    #[test]
    fn an_offset_rotated_rod_gets_products_of_inertia_and_massless_parts_add_nothing() {
        // A 2 kg rod along its own x (I = [0, a, a]), turned 90° about z and placed at (1, 1, 0)
        // beside a 2 kg point at the origin: com (0.5, 0.5, 0); the rod lies along y.
        let a = 2.0 * 0.4 * 0.4 / 12.0;
        let rod = MassProperties { mass: 2.0, com: [0.0; 3], inertia: [0.0, a, a, 0.0, 0.0, 0.0] };
        let at = Pose::from_rpy_deg([1.0, 1.0, 0.0], [0.0, 0.0, 90.0]);
        let point = MassProperties { mass: 2.0, ..Default::default() };
        let frame = MassProperties { mass: 0.0, com: [9.0; 3], inertia: [5.0; 6] };
        let b = combine_mass(&[(at, rod), (Pose::default(), point), (Pose::translation([3.0; 3]), frame)]);
        assert_eq!(b.mass, 4.0);
        assert!((b.com[0] - 0.5).abs() < 1e-12 && (b.com[1] - 0.5).abs() < 1e-12);
        // Each mass is 0.5 m from the com in x and y: m (d_y²) = 0.5 per part for Ixx, and so on.
        let want = [a + 1.0, 1.0, a + 2.0, -2.0 * 2.0 * 0.25, 0.0, 0.0];
        assert!(close(b.inertia, want), "{:?} vs {want:?}", b.inertia);
        assert_eq!(combine_mass(&[(Pose::default(), frame)]), MassProperties::default());
    }
}
