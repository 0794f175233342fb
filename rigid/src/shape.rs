//! Body shapes, in the body frame (m). The same description builds the rapier collider and,
//! in `regolith-coupling`, the body's BCE markers.

pub use regolith_body::{quat_mul, quat_rotate};

/// A body-frame axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// x.
    X,
    /// y.
    Y,
    /// z.
    Z,
}

impl Axis {
    /// Unit vector.
    pub fn unit(self) -> [f64; 3] {
        match self {
            Self::X => [1.0, 0.0, 0.0],
            Self::Y => [0.0, 1.0, 0.0],
            Self::Z => [0.0, 0.0, 1.0],
        }
    }
}

/// A rigid transform: translation (m) and rotation as a unit quaternion `[x, y, z, w]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Translation (m).
    pub translation: [f64; 3],
    /// Unit quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
}

impl Default for Pose {
    fn default() -> Self {
        Self { translation: [0.0; 3], rotation: [0.0, 0.0, 0.0, 1.0] }
    }
}

impl Pose {
    /// A pure translation.
    pub fn translation(t: [f64; 3]) -> Self {
        Self { translation: t, ..Default::default() }
    }
    /// From a translation and roll, pitch, yaw (degrees, applied as R = Rz(yaw) Ry(pitch) Rx(roll)).
    pub fn from_rpy_deg(t: [f64; 3], rpy_deg: [f64; 3]) -> Self {
        let [r, p, y] = rpy_deg.map(|a| a.to_radians() * 0.5);
        let (sr, cr) = r.sin_cos();
        let (sp, cp) = p.sin_cos();
        let (sy, cy) = y.sin_cos();
        let q = [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ];
        Self { translation: t, rotation: q }
    }
    /// Rotates a vector.
    pub fn rotate(&self, v: [f64; 3]) -> [f64; 3] {
        quat_rotate(self.rotation, v)
    }
    /// Transforms a point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rotate(p);
        [r[0] + self.translation[0], r[1] + self.translation[1], r[2] + self.translation[2]]
    }
    /// `self ∘ other` (apply `other` first).
    pub fn compose(&self, other: &Pose) -> Pose {
        Pose { translation: self.apply(other.translation), rotation: quat_mul(self.rotation, other.rotation) }
    }
    /// The point `p` (world) in this pose's frame: the inverse of [`Pose::apply`].
    pub fn to_local(&self, p: [f64; 3]) -> [f64; 3] {
        let [x, y, z, w] = self.rotation;
        quat_rotate([-x, -y, -z, w], [0, 1, 2].map(|k| p[k] - self.translation[k]))
    }
}

/// A grouser layout on a wheel: plates running across the tread.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grousers {
    /// Number of plates, evenly spaced around the rim.
    pub count: u32,
    /// Radial height above the rim (m).
    pub height: f64,
    /// Thickness in the rolling direction (m).
    pub thickness: f64,
}

impl Grousers {
    /// Pose (wheel frame, axle along y) of the centre of each plate on a rim of radius
    /// `radius`: plates evenly spaced in angle, centred at `radius + height/2`, their local z
    /// radial and local x along the tread.
    pub fn plate_poses(&self, radius: f64) -> impl Iterator<Item = Pose> + '_ {
        (0..self.count).map(move |k| {
            let rot = Pose::from_rpy_deg([0.0; 3], [0.0, 360.0 * k as f64 / self.count as f64, 0.0]);
            Pose { translation: rot.rotate([0.0, 0.0, radius + 0.5 * self.height]), rotation: rot.rotation }
        })
    }
}

/// A body shape in its body frame (origin at the shape's centre).
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeDesc {
    /// A box of full sizes `size` (m).
    Box {
        /// Full edge lengths (m).
        size: [f64; 3],
    },
    /// A ball.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A solid cylinder centred at the origin.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length along the axis (m).
        length: f64,
        /// Axis.
        axis: Axis,
    },
    /// A solid cone with its axis along z, apex pointing down (−z), centred at half height:
    /// apex at z = −height/2, base at z = +height/2. A penetrometer tip.
    Cone {
        /// Base radius (m).
        radius: f64,
        /// Height (m).
        height: f64,
    },
    /// A closed triangle mesh (m, body frame).
    Mesh {
        /// Vertices.
        vertices: Vec<[f64; 3]>,
        /// Triangles (counter-clockwise seen from outside).
        indices: Vec<[u32; 3]>,
    },
    /// A wheel: a cylinder along y with optional grousers.
    Wheel {
        /// Rim radius (m).
        radius: f64,
        /// Width along y (m).
        width: f64,
        /// Grousers, if any.
        grousers: Option<Grousers>,
    },
    /// Several shapes, each at a pose in the body frame.
    Compound(Vec<(Pose, ShapeDesc)>),
}

impl ShapeDesc {
    /// Volume (m³), for density-specified bodies and reports. Mesh volume by the divergence
    /// theorem; compounds sum their parts (overlaps counted twice).
    pub fn volume(&self) -> f64 {
        use std::f64::consts::PI;
        match self {
            Self::Box { size } => size[0] * size[1] * size[2],
            Self::Sphere { radius } => 4.0 / 3.0 * PI * radius.powi(3),
            Self::Cylinder { radius, length, .. } => PI * radius * radius * length,
            Self::Cone { radius, height } => PI * radius * radius * height / 3.0,
            Self::Mesh { vertices, indices } => {
                let mut v = 0.0;
                for t in indices {
                    let [a, b, c] = t.map(|i| vertices[i as usize]);
                    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                        + a[2] * (b[0] * c[1] - b[1] * c[0]);
                }
                (v / 6.0).abs()
            }
            Self::Wheel { radius, width, grousers } => {
                let rim = PI * radius * radius * width;
                rim + grousers.map_or(0.0, |g| g.count as f64 * g.height * g.thickness * width)
            }
            Self::Compound(parts) => parts.iter().map(|(_, s)| s.volume()).sum(),
        }
    }

    /// Radius of a sphere about the body origin that contains the shape (m).
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Self::Box { size } => 0.5 * (size[0] * size[0] + size[1] * size[1] + size[2] * size[2]).sqrt(),
            Self::Sphere { radius } => *radius,
            Self::Cylinder { radius, length, .. } => (radius * radius + 0.25 * length * length).sqrt(),
            Self::Cone { radius, height } => (radius * radius + 0.25 * height * height).sqrt(),
            Self::Mesh { vertices, .. } => {
                vertices.iter().map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()).fold(0.0, f64::max)
            }
            Self::Wheel { radius, width, grousers } => {
                let r = radius + grousers.map_or(0.0, |g| g.height);
                (r * r + 0.25 * width * width).sqrt()
            }
            Self::Compound(parts) => parts
                .iter()
                .map(|(p, s)| {
                    let t = p.translation;
                    (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt() + s.bounding_radius()
                })
                .fold(0.0, f64::max),
        }
    }

    /// Lowest world z of the shape at `pose` (m); `+∞` for an empty compound.
    pub fn lowest_z(&self, pose: &Pose) -> f64 {
        let z = pose.translation[2];
        // World z component of a body-frame direction.
        let up = |v: [f64; 3]| pose.rotate(v)[2];
        // A disc of radius r about a body axis reaches down r·sqrt(1 − a_z²).
        let disc = |axis: [f64; 3], r: f64| {
            let a = up(axis);
            r * (1.0 - a * a).max(0.0).sqrt()
        };
        match self {
            Self::Box { size } => {
                z - 0.5
                    * (size[0] * up([1.0, 0.0, 0.0]).abs()
                        + size[1] * up([0.0, 1.0, 0.0]).abs()
                        + size[2] * up([0.0, 0.0, 1.0]).abs())
            }
            Self::Sphere { radius } => z - radius,
            Self::Cylinder { radius, length, axis } => {
                z - 0.5 * length * up(axis.unit()).abs() - disc(axis.unit(), *radius)
            }
            Self::Cone { radius, height } => {
                let a = up([0.0, 0.0, 1.0]);
                // Apex at −h/2 along the axis, base disc at +h/2.
                (z - 0.5 * height * a).min(z + 0.5 * height * a - disc([0.0, 0.0, 1.0], *radius))
            }
            Self::Mesh { vertices, .. } => vertices.iter().map(|v| pose.apply(*v)[2]).fold(f64::INFINITY, f64::min),
            Self::Wheel { radius, width, grousers } => {
                let r = radius + grousers.map_or(0.0, |g| g.height);
                z - 0.5 * width * up([0.0, 1.0, 0.0]).abs() - disc([0.0, 1.0, 0.0], r)
            }
            Self::Compound(parts) => {
                parts.iter().map(|(p, s)| s.lowest_z(&pose.compose(p))).fold(f64::INFINITY, f64::min)
            }
        }
    }
}

impl ShapeDesc {
    /// Which of the body-frame points lie inside the shape grown by `margin` (m). Meshes use
    /// a parity test on a ray along +x plus the distance to the surface.
    pub fn contains_points(&self, points: &[[f64; 3]], margin: f64) -> Vec<bool> {
        let mut inside = vec![false; points.len()];
        self.mark_inside(&Pose::default(), points, margin, &mut inside);
        inside
    }

    fn mark_inside(&self, at: &Pose, points: &[[f64; 3]], m: f64, inside: &mut [bool]) {
        let inv_r = [-at.rotation[0], -at.rotation[1], -at.rotation[2], at.rotation[3]];
        let local = |p: [f64; 3]| {
            quat_rotate(inv_r, [p[0] - at.translation[0], p[1] - at.translation[1], p[2] - at.translation[2]])
        };
        let along = |p: [f64; 3], axis: Axis| match axis {
            Axis::X => (p[0], (p[1] * p[1] + p[2] * p[2]).sqrt()),
            Axis::Y => (p[1], (p[0] * p[0] + p[2] * p[2]).sqrt()),
            Axis::Z => (p[2], (p[0] * p[0] + p[1] * p[1]).sqrt()),
        };
        match self {
            Self::Compound(parts) => {
                for (p, s) in parts {
                    s.mark_inside(&at.compose(p), points, m, inside);
                }
                return;
            }
            Self::Wheel { radius, width, grousers } => {
                Self::Cylinder { radius: *radius, length: *width, axis: Axis::Y }.mark_inside(at, points, m, inside);
                if let Some(g) = grousers {
                    for p in g.plate_poses(*radius) {
                        let plate = Self::Box { size: [g.thickness, *width, g.height] };
                        plate.mark_inside(&at.compose(&p), points, m, inside);
                    }
                }
                return;
            }
            Self::Mesh { vertices, indices } => {
                for (flag, p) in inside.iter_mut().zip(points) {
                    if !*flag {
                        let q = local(*p);
                        *flag = mesh_contains(vertices, indices, q) || mesh_distance(vertices, indices, q) <= m;
                    }
                }
                return;
            }
            _ => {}
        }
        for (flag, p) in inside.iter_mut().zip(points) {
            if *flag {
                continue;
            }
            let q = local(*p);
            *flag = match self {
                Self::Box { size } => (0..3).all(|k| q[k].abs() <= 0.5 * size[k] + m),
                Self::Sphere { radius } => q[0] * q[0] + q[1] * q[1] + q[2] * q[2] <= (radius + m).powi(2),
                Self::Cylinder { radius, length, axis } => {
                    let (a, r) = along(q, *axis);
                    a.abs() <= 0.5 * length + m && r <= radius + m
                }
                Self::Cone { radius, height } => {
                    let z = q[2] + 0.5 * height; // from the apex
                    let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
                    let slant = (radius * radius + height * height).sqrt();
                    z >= -m && z <= height + m && r <= z.max(0.0) * radius / height + m * slant / height
                }
                _ => false,
            };
        }
    }
}

/// Parity of crossings of a ray from `p` along +x with the mesh's triangles.
fn mesh_contains(v: &[[f64; 3]], t: &[[u32; 3]], p: [f64; 3]) -> bool {
    let mut crossings = 0;
    for tri in t {
        let [a, b, c] = tri.map(|i| v[i as usize]);
        // Möller–Trumbore with direction (1, 0, 0); a slight tilt avoids edge-on hits.
        let d = [1.0, 1.234e-7, 2.345e-7];
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let h = [d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]];
        let det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
        if det.abs() < 1e-18 {
            continue;
        }
        let f = 1.0 / det;
        let s = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
        let u = f * (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]);
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let q = [s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]];
        let w = f * (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]);
        if w < 0.0 || u + w > 1.0 {
            continue;
        }
        if f * (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) > 0.0 {
            crossings += 1;
        }
    }
    crossings % 2 == 1
}

/// Distance from `p` to the nearest triangle of the mesh (m).
fn mesh_distance(v: &[[f64; 3]], t: &[[u32; 3]], p: [f64; 3]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let mut best = f64::INFINITY;
    for tri in t {
        let [a, b, c] = tri.map(|i| v[i as usize]);
        // Closest point on a triangle (Ericson, Real-Time Collision Detection, 5.1.5).
        let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
        let (d1, d2) = (dot(ab, ap), dot(ac, ap));
        let q = if d1 <= 0.0 && d2 <= 0.0 {
            a
        } else {
            let bp = sub(p, b);
            let (d3, d4) = (dot(ab, bp), dot(ac, bp));
            let cp = sub(p, c);
            let (d5, d6) = (dot(ab, cp), dot(ac, cp));
            let vc = d1 * d4 - d3 * d2;
            let vb = d5 * d2 - d1 * d6;
            let va = d3 * d6 - d5 * d4;
            if d3 >= 0.0 && d4 <= d3 {
                b
            } else if d6 >= 0.0 && d5 <= d6 {
                c
            } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
                let s = d1 / (d1 - d3);
                [a[0] + s * ab[0], a[1] + s * ab[1], a[2] + s * ab[2]]
            } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
                let s = d2 / (d2 - d6);
                [a[0] + s * ac[0], a[1] + s * ac[1], a[2] + s * ac[2]]
            } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
                let s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
                [b[0] + s * (c[0] - b[0]), b[1] + s * (c[1] - b[1]), b[2] + s * (c[2] - b[2])]
            } else {
                let den = 1.0 / (va + vb + vc);
                let (s, u) = (vb * den, vc * den);
                [a[0] + ab[0] * s + ac[0] * u, a[1] + ab[1] * s + ac[1] * u, a[2] + ab[2] * s + ac[2] * u]
            }
        };
        let d = sub(p, q);
        best = best.min(dot(d, d).sqrt());
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn containment_of_primitives_and_meshes() {
        let pts = [[0.0, 0.0, 0.0], [0.049, 0.0, 0.0], [0.06, 0.0, 0.0], [0.0, 0.0, -0.024]];
        assert_eq!(ShapeDesc::Sphere { radius: 0.05 }.contains_points(&pts, 0.0), vec![true, true, false, true]);
        assert_eq!(ShapeDesc::Sphere { radius: 0.05 }.contains_points(&pts, 0.011), vec![true, true, true, true]);
        let cone = ShapeDesc::Cone { radius: 0.02, height: 0.05 };
        // apex at z = −0.025: a point just above the apex on the axis is inside, one beside it not.
        assert_eq!(
            cone.contains_points(&[[0.0, 0.0, -0.024], [0.01, 0.0, -0.024], [0.0, 0.0, 0.03]], 0.0),
            vec![true, false, false]
        );
        let cube = unit_cube();
        assert_eq!(
            cube.contains_points(&[[0.5, 0.5, 0.5], [1.5, 0.5, 0.5], [1.05, 0.5, 0.5], [0.5, 0.5, -0.2]], 0.1),
            vec![true, false, true, false]
        );
        let wheel = ShapeDesc::Wheel {
            radius: 0.1,
            width: 0.05,
            grousers: Some(Grousers { count: 4, height: 0.02, thickness: 0.01 }),
        };
        assert_eq!(
            wheel.contains_points(&[[0.0, 0.0, 0.11], [0.0, 0.0, -0.11], [0.08, 0.0, 0.08], [0.0, 0.03, 0.0]], 0.0),
            vec![true, true, false, false]
        );
    }

    /// The unit cube [0, 1]³ as a closed, outward-facing triangle mesh.
    fn unit_cube() -> ShapeDesc {
        ShapeDesc::Mesh {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
                [0.0, 1.0, 1.0],
            ],
            indices: vec![
                [0, 2, 1],
                [0, 3, 2],
                [4, 5, 6],
                [4, 6, 7],
                [0, 1, 5],
                [0, 5, 4],
                [1, 2, 6],
                [1, 6, 5],
                [2, 3, 7],
                [2, 7, 6],
                [3, 0, 4],
                [3, 4, 7],
            ],
        }
    }

    #[test]
    fn lowest_points_match_closed_forms() {
        // A box of 0.2 × 0.1 × 0.04 m rolled 90° about x: its 0.1 m side stands vertical.
        let b = ShapeDesc::Box { size: [0.2, 0.1, 0.04] };
        let p = Pose::from_rpy_deg([0.0, 0.0, 1.0], [90.0, 0.0, 0.0]);
        assert!((b.lowest_z(&p) - (1.0 - 0.05)).abs() < 1e-12);
        // A z-axis cylinder tilted by θ about x reaches down h/2 cos θ + r sin θ.
        let c = ShapeDesc::Cylinder { radius: 0.1, length: 0.4, axis: Axis::Z };
        let th = 30.0_f64;
        let p = Pose::from_rpy_deg([0.0; 3], [th, 0.0, 0.0]);
        let want = -(0.2 * th.to_radians().cos() + 0.1 * th.to_radians().sin());
        assert!((c.lowest_z(&p) - want).abs() < 1e-12);
        // A wheel upright (axle along y) touches at radius + grouser height.
        let w = ShapeDesc::Wheel {
            radius: 0.1,
            width: 0.05,
            grousers: Some(Grousers { count: 4, height: 0.02, thickness: 0.01 }),
        };
        assert!((w.lowest_z(&Pose::default()) + 0.12).abs() < 1e-12);
        assert!((unit_cube().lowest_z(&Pose::translation([0.0, 0.0, 2.0])) - 2.0).abs() < 1e-12);
        assert_eq!(ShapeDesc::Compound(Vec::new()).lowest_z(&Pose::default()), f64::INFINITY);
    }

    #[test]
    fn rpy_rotates_as_documented() {
        let p = Pose::from_rpy_deg([0.0; 3], [0.0, 0.0, 90.0]);
        let v = p.rotate([1.0, 0.0, 0.0]);
        assert!((v[0]).abs() < 1e-12 && (v[1] - 1.0).abs() < 1e-12);
        let p = Pose::from_rpy_deg([0.0; 3], [90.0, 0.0, 0.0]);
        let v = p.rotate([0.0, 1.0, 0.0]);
        assert!((v[2] - 1.0).abs() < 1e-12);
        let p = Pose::from_rpy_deg([0.0; 3], [0.0, 90.0, 0.0]);
        let v = p.rotate([0.0, 0.0, 1.0]);
        assert!((v[0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn volumes() {
        let cube = unit_cube();
        assert!((cube.volume() - 1.0).abs() < 1e-12);
        assert!((ShapeDesc::Box { size: [1.0, 2.0, 3.0] }.volume() - 6.0).abs() < 1e-12);
    }

    #[test]
    fn to_local_undoes_apply() {
        let p = Pose::from_rpy_deg([0.3, -0.2, 1.0], [10.0, 20.0, 30.0]);
        let x = [0.1, 0.2, 0.3];
        let back = p.to_local(p.apply(x));
        for k in 0..3 {
            assert!((back[k] - x[k]).abs() < 1e-12, "{back:?}");
        }
    }
}
