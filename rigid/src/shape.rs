//! Body shapes, in the body frame (m). The same description builds the rapier collider and,
//! in `regolith-coupling`, the body's BCE markers.

use rapier3d::parry::bounding_volume::BoundingVolume;
use rapier3d::parry::math::Vector as PVector;
use rapier3d::parry::query::PointQuery;
use rapier3d::parry::shape::{TriMesh, TriMeshFlags};
use rayon::prelude::*;
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

    /// The shape's world extent at `pose` along x and y (m): `[[min x, max x], [min y, max y]]`,
    /// each the lowest point of the shape turned so that that direction points down
    /// ([`Self::lowest_z`] of the pose turned a quarter turn about y or x); `±∞` for an empty
    /// compound.
    pub fn horizontal_extent(&self, pose: &Pose) -> [[f64; 2]; 2] {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        // A quarter turn about y by ∓90° takes ±x to −z; about x by ±90°, ±y to −z.
        let lowest = |q: [f64; 4]| {
            self.lowest_z(&Pose { translation: quat_rotate(q, pose.translation), rotation: quat_mul(q, pose.rotation) })
        };
        [[lowest([0.0, -s, 0.0, s]), -lowest([0.0, s, 0.0, s])], [lowest([s, 0.0, 0.0, s]), -lowest([-s, 0.0, 0.0, s])]]
    }
}

impl ShapeDesc {
    /// A closed, outward-oriented triangle mesh of a torus about the z axis: tube centre circle
    /// of radius `major`, tube radius `minor` (m), `around` segments along the big circle and
    /// `across` around the tube, so `2 · around · across` triangles. A non-convex test and
    /// benchmark body (see `examples/carve_bench.rs`); `around` and `across` are at least 3.
    pub fn torus_mesh(major: f64, minor: f64, around: u32, across: u32) -> Self {
        use std::f64::consts::TAU;
        let (n, k) = (around.max(3), across.max(3));
        let mut vertices = Vec::with_capacity((n * k) as usize);
        for i in 0..n {
            let (su, cu) = (TAU * f64::from(i) / f64::from(n)).sin_cos();
            for j in 0..k {
                let (sv, cv) = (TAU * f64::from(j) / f64::from(k)).sin_cos();
                let r = major + minor * cv;
                vertices.push([r * cu, r * su, minor * sv]);
            }
        }
        let id = |i: u32, j: u32| (i % n) * k + j % k;
        let mut indices = Vec::with_capacity((2 * n * k) as usize);
        for i in 0..n {
            for j in 0..k {
                // ∂p/∂u × ∂p/∂v points outward, so (i, j) → (i+1, j) → (i+1, j+1) is
                // counter-clockwise seen from outside.
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                indices.push([a, b, c]);
                indices.push([a, c, d]);
            }
        }
        Self::Mesh { vertices, indices }
    }

    /// Which of the body-frame points lie inside the shape grown by `margin` (m). A mesh (which
    /// must be closed and outward-oriented, as `regolith_coupling::check_watertight` demands)
    /// becomes a parry [`TriMesh`] (with its BVH) once per call; a point is inside when it lies
    /// behind the angle-weighted pseudo-normal of the mesh feature nearest to it, or within
    /// `margin` of the surface. Points far from the surface mostly take their answer from a
    /// nearby point's distance instead of their own search. The mesh queries run in `f32`
    /// (parry's precision), on all cores: a point within that precision of the grown surface
    /// (e.g. a lattice point exactly `margin` from a face) counts as inside. A margin below
    /// zero does not shrink a mesh.
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
                mark_inside_mesh(vertices, indices, &local, points, m, inside);
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

/// Marks the points (given in the frame of the shape that holds the mesh; `local` takes them
/// into the mesh's frame) inside the closed mesh `vertices`/`indices` or within `m` of it.
///
/// Each point's nearest surface point comes from parry's BVH; with `ORIENTED`, parry decides
/// inside or outside from the angle-weighted pseudo-normal of the feature (face, edge or
/// vertex) that point lies on. A point close to the surface is cheap to project (the search
/// is bounded); an unbounded projection of a point deep inside or far outside visits every
/// triangle near its distance, many of them. But a point `c` at distance `d` from the surface
/// certifies the open ball of radius `d` about it: no surface crosses it, so every point `p`
/// in it lies on `c`'s side, and farther than `m` from the surface when `|p − c| < d − m`.
/// The points are therefore taken in Morton order and each reuses the balls of the last few
/// points projected before it; only points that no ball covers are projected.
fn mark_inside_mesh(
    vertices: &[[f64; 3]],
    indices: &[[u32; 3]],
    local: &(impl Fn([f64; 3]) -> [f64; 3] + Sync),
    points: &[[f64; 3]],
    m: f64,
    inside: &mut [bool],
) {
    /// Balls remembered per run of points.
    const BALLS: usize = 32;
    let Some(mesh) = oriented_trimesh(vertices, indices) else {
        return; // no triangles: nothing is inside
    };
    let m_grow = m.max(0.0) as f32;
    let m = m as f32;
    let bounds = mesh.local_aabb();
    // The f32 rounding of coordinates and projections, as a length: a point within `tie` of
    // the grown surface counts as inside, so points exactly `m` from it (a lattice aligned
    // with a face, points on the surface for m = 0) are all in rather than in or out by
    // rounding. Sixteen times as much is taken off each certified radius, to be safe.
    let tie = 4.0 * f32::EPSILON * (bounds.mins.abs().max(bounds.maxs.abs()).max_element() + m_grow);
    let slack = 16.0 * tie;
    // A point farther than m from the mesh's box is farther than m from the mesh, and outside.
    let reach = bounds.loosened(m_grow + 2.0 * tie);
    // Projections are searched first within this distance, which decides most points near
    // the surface without a long search.
    let near = m_grow + (bounds.maxs - bounds.mins).length() / 128.0;
    let extent = (reach.maxs - reach.mins).max(PVector::splat(f32::MIN_POSITIVE));

    let mut todo: Vec<(u64, usize, PVector)> = inside
        .par_iter()
        .zip(points.par_iter())
        .enumerate()
        .with_min_len(1024)
        .filter_map(|(i, (flag, p))| {
            if *flag {
                return None;
            }
            let q = local(*p);
            let q = PVector::new(q[0] as f32, q[1] as f32, q[2] as f32);
            reach.contains_local_point(q).then(|| (morton((q - reach.mins) / extent), i, q))
        })
        .collect();
    todo.par_sort_unstable_by_key(|t| t.0);

    let mesh = &mesh;
    let hits: Vec<usize> = todo
        .par_chunks(4096)
        .flat_map_iter(|run| {
            let mut balls: Vec<(PVector, f32, bool)> = Vec::with_capacity(BALLS);
            let mut next = 0;
            run.iter().filter_map(move |&(_, i, q)| {
                let covered = balls.iter().find(|(c, r, _)| (q - *c).length() < r - m_grow).map(|b| b.2);
                let is_in = covered.unwrap_or_else(|| {
                    let proj = mesh
                        .project_local_point_with_max_dist(q, false, near)
                        .unwrap_or_else(|| mesh.project_local_point(q, false));
                    let d = (proj.point - q).length();
                    let ball = (q, d * (1.0 - 1e-5) - slack, proj.is_inside);
                    if balls.len() < BALLS {
                        balls.push(ball);
                    } else {
                        balls[next] = ball;
                        next = (next + 1) % BALLS;
                    }
                    proj.is_inside || d <= m + tie
                });
                is_in.then_some(i)
            })
        })
        .collect();
    for i in hits {
        inside[i] = true;
    }
}

/// Morton (Z-order) code of a point of the unit cube, 10 bits per axis: points near each
/// other in space get codes near each other.
fn morton(rel: PVector) -> u64 {
    let spread = |x: f32| {
        let mut v = (x.clamp(0.0, 1.0) * 1023.0) as u64;
        v = (v | (v << 16)) & 0x0300_00FF;
        v = (v | (v << 8)) & 0x0300_F00F;
        v = (v | (v << 4)) & 0x030C_30C3;
        (v | (v << 2)) & 0x0924_9249
    };
    spread(rel.x) | (spread(rel.y) << 1) | (spread(rel.z) << 2)
}

/// A parry mesh with outward pseudo-normals, coincident vertices merged (STL files repeat
/// them per triangle) and the triangles this collapses removed; `None` without triangles.
fn oriented_trimesh(vertices: &[[f64; 3]], indices: &[[u32; 3]]) -> Option<TriMesh> {
    let verts = vertices.iter().map(|v| PVector::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect();
    let flags =
        TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES | TriMeshFlags::DELETE_DEGENERATE_TRIANGLES;
    TriMesh::with_flags(verts, indices.to_vec(), flags).ok().filter(|t| t.num_triangles() > 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horizontal_extent_of_a_turned_box_and_a_wheel() {
        // A 0.4 × 0.2 × 0.1 box at (1, 2, 3) turned 30° about z: its half-extents along x and y
        // are ½(a cos θ + b sin θ) and ½(a sin θ + b cos θ).
        let b = ShapeDesc::Box { size: [0.4, 0.2, 0.1] };
        let pose = Pose::from_rpy_deg([1.0, 2.0, 3.0], [0.0, 0.0, 30.0]);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let (hx, hy) = (0.5 * (0.4 * c + 0.2 * s), 0.5 * (0.4 * s + 0.2 * c));
        let e = b.horizontal_extent(&pose);
        for (got, want) in e.iter().flatten().zip([1.0 - hx, 1.0 + hx, 2.0 - hy, 2.0 + hy]) {
            assert!((got - want).abs() < 1e-12, "{e:?}");
        }
        // A wheel (axle along y) reaches its radius along x and half its width along y.
        let w = ShapeDesc::Wheel { radius: 0.1, width: 0.04, grousers: None };
        let e = w.horizontal_extent(&Pose::translation([0.0, 0.5, 0.2]));
        for (got, want) in e.iter().flatten().zip([-0.1, 0.1, 0.48, 0.52]) {
            assert!((got - want).abs() < 1e-12, "{e:?}");
        }
    }

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

    // The brute-force mesh queries `contains_points` used before parry (O(points × triangles)),
    // kept verbatim as the test oracle.

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

    /// The old answer: inside by ray parity, or within `m` of a triangle.
    fn brute_inside(shape: &ShapeDesc, p: [f64; 3], m: f64) -> bool {
        let ShapeDesc::Mesh { vertices, indices } = shape else { unreachable!("a mesh") };
        mesh_contains(vertices, indices, p) || mesh_distance(vertices, indices, p) <= m
    }

    /// splitmix64: reproducible uniform numbers in [0, 1) without a dependency.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// An L-shaped prism 2 × 2 × 1 (the square [1, 2]² cut out of [0, 2]², extruded along z),
    /// closed and outward-oriented: a reflex edge, and saddle vertices at its ends.
    fn l_prism() -> ShapeDesc {
        let outline = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]];
        let mut vertices: Vec<[f64; 3]> = outline.iter().map(|p| [p[0], p[1], 0.0]).collect();
        vertices.extend(outline.iter().map(|p| [p[0], p[1], 1.0]));
        let mut indices = Vec::new();
        // Caps: a fan from (0, 0), which sees every corner; bottom reversed to face −z.
        for k in 1..5u32 {
            indices.push([0, k + 1, k]);
            indices.push([6, 6 + k, 6 + k + 1]);
        }
        for k in 0..6u32 {
            let k1 = (k + 1) % 6;
            indices.push([k, k1, 6 + k1]);
            indices.push([k, 6 + k1, 6 + k]);
        }
        ShapeDesc::Mesh { vertices, indices }
    }

    /// The mesh with three vertices of its own per triangle, as STL files store it.
    fn unshared(shape: &ShapeDesc) -> ShapeDesc {
        let ShapeDesc::Mesh { vertices, indices } = shape else { unreachable!("a mesh") };
        ShapeDesc::Mesh {
            vertices: indices.iter().flat_map(|t| t.map(|i| vertices[i as usize])).collect(),
            indices: (0..indices.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
        }
    }

    fn rover_chassis() -> ShapeDesc {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/rover_description/meshes/chassis.stl");
        let mesh = crate::load_mesh(&path, [1.0; 3]).expect("chassis.stl");
        ShapeDesc::Mesh { vertices: mesh.vertices, indices: mesh.indices }
    }

    /// `n` random points in the mesh's bounding box grown by `pad` on every side.
    fn random_points(shape: &ShapeDesc, n: usize, pad: f64, rng: &mut Rng) -> Vec<[f64; 3]> {
        let ShapeDesc::Mesh { vertices, .. } = shape else { unreachable!("a mesh") };
        let lo = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MAX, f64::min) - pad);
        let hi = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MIN, f64::max) + pad);
        (0..n).map(|_| [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * rng.next())).collect()
    }

    /// About `n` lattice points (cell centres, spacing returned) filling the mesh's bounding box
    /// grown by `pad`: neighbours in space, as soil particles are, which the ball reuse of
    /// `mark_inside_mesh` relies on.
    fn lattice_around(shape: &ShapeDesc, n: f64, pad: f64) -> (Vec<[f64; 3]>, f64) {
        let ShapeDesc::Mesh { vertices, .. } = shape else { unreachable!("a mesh") };
        let lo = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MAX, f64::min) - pad);
        let hi = [0, 1, 2].map(|k| vertices.iter().map(|v| v[k]).fold(f64::MIN, f64::max) + pad);
        let d = ((hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) / n).cbrt();
        let c = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / d).round() as usize);
        let mut pts = Vec::with_capacity(c[0] * c[1] * c[2]);
        for i in 0..c[0] {
            for j in 0..c[1] {
                for l in 0..c[2] {
                    let f = [i, j, l].map(|x| x as f64 + 0.5);
                    pts.push([lo[0] + f[0] * d, lo[1] + f[1] * d, lo[2] + f[2] * d]);
                }
            }
        }
        (pts, d)
    }

    #[test]
    fn parry_mesh_containment_matches_the_brute_force_oracle_on_a_lattice() {
        for (name, mesh) in [("L prism", l_prism()), ("torus", ShapeDesc::torus_mesh(0.3, 0.1, 32, 12))] {
            let (pts, d0) = lattice_around(&mesh, 12_000.0, 0.0137);
            for margin in [0.0, 0.5 * d0, 2.0 * d0] {
                let got = mesh.contains_points(&pts, margin);
                let n_in = got.iter().filter(|x| **x).count();
                for (p, g) in pts.iter().zip(&got) {
                    assert_eq!(*g, brute_inside(&mesh, *p, margin), "{name}, margin {margin}: point {p:?}");
                }
                assert!(n_in > 1000 && n_in < pts.len() - 1000, "{name}, margin {margin}: {n_in} inside");
            }
        }
    }

    /// Lattice points exactly `margin` from a face of the rover chassis (cell centres at
    /// (i + ½)·d0 against faces at multiples of d0), or on a face for margin 0, are ties that
    /// the old f64 brute force decided by rounding, differently from face to face; they are
    /// all inside now. Every other point gets the old answer.
    #[test]
    fn points_exactly_at_the_margin_are_inside() {
        let chassis = rover_chassis();
        let ShapeDesc::Mesh { vertices, indices } = &chassis else { unreachable!("a mesh") };
        let d0 = 0.01;
        let mut pts = Vec::new();
        for i in -25..25 {
            for j in -18..18 {
                for k in -8..8 {
                    pts.push([i, j, k].map(|x| (f64::from(x) + 0.5) * d0));
                }
            }
        }
        for margin in [0.5 * d0, 0.0] {
            let got = chassis.contains_points(&pts, margin);
            let mut ties = 0;
            for (p, g) in pts.iter().zip(got) {
                if (mesh_distance(vertices, indices, *p) - margin).abs() < 1e-12 {
                    ties += 1;
                    assert!(g, "margin {margin}: point {p:?} at the margin is outside");
                } else {
                    assert_eq!(g, brute_inside(&chassis, *p, margin), "margin {margin}: point {p:?}");
                }
            }
            assert!(ties > 100, "margin {margin}: only {ties} ties");
        }
    }

    #[test]
    fn parry_mesh_containment_matches_the_brute_force_oracle() {
        let mut rng = Rng(7);
        let meshes = [
            ("L prism", l_prism(), 1.0),
            ("L prism, vertices unshared", unshared(&l_prism()), 1.0),
            ("torus", ShapeDesc::torus_mesh(0.3, 0.1, 24, 12), 0.1),
            ("torus, vertices unshared", unshared(&ShapeDesc::torus_mesh(0.3, 0.1, 24, 12)), 0.1),
            ("rover chassis", rover_chassis(), 0.05),
        ];
        for (name, mesh, size) in meshes {
            for margin in [0.0, 0.05 * size, 0.3 * size] {
                let pts = random_points(&mesh, 4000, 0.5 * size, &mut rng);
                let got = mesh.contains_points(&pts, margin);
                let want: Vec<bool> = pts.iter().map(|p| brute_inside(&mesh, *p, margin)).collect();
                let differ: Vec<_> = pts.iter().zip(got.iter().zip(&want)).filter(|(_, (g, w))| g != w).collect();
                assert!(
                    differ.is_empty(),
                    "{name}, margin {margin}: {} of 4000 differ, e.g. {:?}",
                    differ.len(),
                    differ[0]
                );
                let n_in = want.iter().filter(|x| **x).count();
                assert!(n_in > 200 && n_in < 3800, "{name}, margin {margin}: {n_in} inside, too few of either kind");
            }
            // The same mesh as a rotated, shifted compound part: points go through the pose.
            let pose = Pose::from_rpy_deg([0.1, -0.2, 0.3], [20.0, -35.0, 50.0]);
            let part = ShapeDesc::Compound(vec![(pose, mesh.clone())]);
            let inv = [-pose.rotation[0], -pose.rotation[1], -pose.rotation[2], pose.rotation[3]];
            let local = random_points(&mesh, 2000, 0.5 * size, &mut rng);
            let pts: Vec<[f64; 3]> = local.iter().map(|p| pose.apply(*p)).collect();
            let got = part.contains_points(&pts, 0.05 * size);
            for (p, g) in pts.iter().zip(got) {
                let q = quat_rotate(inv, [0, 1, 2].map(|k| p[k] - pose.translation[k]));
                assert_eq!(g, brute_inside(&mesh, q, 0.05 * size), "{name} posed, point {p:?}");
            }
        }
        // The torus's hole is outside: the old and new answers agree there too.
        let torus = ShapeDesc::torus_mesh(0.3, 0.1, 24, 12);
        assert_eq!(
            torus.contains_points(&[[0.0; 3], [0.3, 0.0, 0.0], [0.0, 0.3, 0.05]], 0.05),
            vec![false, true, true]
        );
        let empty = ShapeDesc::Mesh { vertices: Vec::new(), indices: Vec::new() };
        assert_eq!(empty.contains_points(&[[0.0; 3]], 1.0), vec![false]);
    }

    #[test]
    fn torus_mesh_is_closed_outward_and_close_to_the_torus() {
        use std::collections::HashSet;
        let (major, minor) = (0.3, 0.1);
        let torus = ShapeDesc::torus_mesh(major, minor, 96, 48);
        let ShapeDesc::Mesh { vertices, indices } = &torus else { unreachable!("a mesh") };
        assert_eq!(indices.len(), 2 * 96 * 48);
        // Every directed edge once, and its reverse once.
        let edges: HashSet<(u32, u32)> =
            indices.iter().flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]).collect();
        assert_eq!(edges.len(), 3 * indices.len());
        assert!(edges.iter().all(|&(a, b)| edges.contains(&(b, a))));
        // Outward: the signed volume is positive and close to 2π² R r² (inscribed: a bit less).
        let signed: f64 = indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0])
            })
            .sum::<f64>()
            / 6.0;
        let exact = 2.0 * std::f64::consts::PI.powi(2) * major * minor * minor;
        assert!(signed > 0.0 && (signed / exact - 1.0).abs() < 0.01, "volume {signed} vs {exact}");
        // Away from the surface (farther than the chords' sagitta), the mesh agrees with the torus.
        let mut rng = Rng(11);
        let pts = random_points(&torus, 5000, 0.05, &mut rng);
        let got = torus.contains_points(&pts, 0.0);
        let sagitta = (major + minor) * (1.0 - (std::f64::consts::PI / 48.0).cos()) * 4.0;
        for (p, g) in pts.iter().zip(got) {
            let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
            let d = ((rho - major).powi(2) + p[2] * p[2]).sqrt() - minor;
            if d.abs() > sagitta {
                assert_eq!(g, d < 0.0, "point {p:?} at {d} m from the torus");
            }
        }
    }

    /// Before/after timing of a carve on a small case (the brute force is too slow for the big
    /// one): `cargo test --release -p regolith-rigid -- --ignored --nocapture carve_timing`.
    /// Also the before/after timing of BENCHMARKS.md (run with `--nocapture`).
    #[test]
    fn carve_timing_brute_force_vs_parry() {
        // The case of `cargo run --release -p regolith-rigid --example carve_bench -- 1000 100000`.
        let torus = ShapeDesc::torus_mesh(0.3, 0.1, 38, 13);
        let ShapeDesc::Mesh { indices, .. } = &torus else { unreachable!("a mesh") };
        let (pts, d0) = lattice_around(&torus, 100_000.0, 0.01);
        let margin = 0.5 * d0;
        let t = std::time::Instant::now();
        let want: Vec<bool> = pts.iter().map(|p| brute_inside(&torus, *p, margin)).collect();
        let brute = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let got = torus.contains_points(&pts, margin);
        let parry = t.elapsed().as_secs_f64();
        assert_eq!(got, want);
        let removed = got.iter().filter(|x| **x).count();
        let pairs = (pts.len() * indices.len()) as f64;
        eprintln!(
            "{} triangles × {} points, margin {:.3} mm, {removed} inside: brute force {brute:.3} s \
             ({:.2} ns per point-triangle pair), parry {parry:.4} s ({} threads)",
            indices.len(),
            pts.len(),
            1e3 * margin,
            1e9 * brute / pairs,
            rayon::current_num_threads()
        );
    }

    /// The benchmark case of `carve_bench` (100 000 triangles, 1 M lattice points): parry's
    /// answers checked against the brute force on a random sample of the points (all of them
    /// would take the brute force half an hour).
    #[test]
    fn carve_of_the_benchmark_case_agrees_with_brute_force_on_a_sample() {
        let torus = ShapeDesc::torus_mesh(0.3, 0.1, 388, 129);
        let (pts, d0) = lattice_around(&torus, 1e6, 0.01);
        let got = torus.contains_points(&pts, 0.5 * d0);
        let mut rng = Rng(5);
        for _ in 0..2000 {
            let i = (rng.next() * pts.len() as f64) as usize;
            assert_eq!(got[i], brute_inside(&torus, pts[i], 0.5 * d0), "point {:?}", pts[i]);
        }
        assert_eq!(got.iter().filter(|x| **x).count(), 421_739, "the count carve_bench prints");
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
