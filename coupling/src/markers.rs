//! BCE markers of a body, in its body frame, generated from its shape.
//!
//! Markers fill `layers` layers at spacing d0 inward from the surface, the outermost layer on
//! the surface itself (`inset = 0`) or `inset` below it. A lattice point stands for a d0³
//! cell, so soil resting on markers meets the body half a spacing outside the outermost
//! layer: with markers on the surface the body acts half a spacing larger than its geometry
//! on every face, with `inset = d0/2` the contact lies on the geometry. A part thinner than
//! twice the inset keeps one layer on its mid-surface (it acts d0 thick). Curved surfaces are
//! sampled on rings and shells that follow them (a lattice would leave steps), flat faces on
//! regular grids (layer k at depth `inset + k·d0`):
//! - boxes: the surfaces of the box shrunk by that depth;
//! - spheres: shells of radius R less that depth;
//! - cylinders and wheels: coaxial shells and cap discs; grousers are boxes on the rim;
//! - cones: the cone offset inward by that depth along its normal, sampled on rings along the
//!   slant.
//!   The tip is truncated: the first ring sits at radius d0/2 with at least three markers, so
//!   the tip is never a single marker (a lone apex marker blows up under load in the anchor);
//! - triangle meshes: the triangles sampled at spacing d0 and moved `inset` inward along their
//!   normals, then lattice points inside the mesh within `inset + (layers − ½)·d0` of the
//!   surface; the mesh must be watertight (closed, consistently oriented), otherwise inside is
//!   undefined and the generation is an error; one wound inward is turned around;
//! - compounds: the union of their parts.
//!
//! Markers closer than d0/2 to one already placed are dropped, so overlapping parts and seams
//! do not double the wall.

use std::collections::HashMap;

use rapier3d::parry::math::Vector as PVector;
use rapier3d::parry::query::PointQuery;
use rapier3d::parry::shape::{TriMesh, TriMeshFlags};
use regolith_rigid::{Axis, Pose, ShapeDesc};

use crate::CouplingError;

/// Markers of a shape (body frame, m), the outermost layer `inset` (0 to d0/2) below its
/// surface.
pub fn shape_markers(shape: &ShapeDesc, d0: f64, layers: usize, inset: f64) -> Result<Vec<[f64; 3]>, CouplingError> {
    if !(d0 > 0.0 && d0.is_finite()) || layers == 0 {
        return Err(CouplingError::Invalid(format!("marker spacing {d0} m and layers {layers} must be positive")));
    }
    if !(0.0..=0.5 * d0).contains(&inset) {
        return Err(CouplingError::Invalid(format!("marker inset {inset} m must be in 0..=d0/2 = {} m", 0.5 * d0)));
    }
    let mut set = MarkerSet::new(d0);
    let layout = Layout { d0, layers, inset };
    add_shape(&mut set, shape, &Pose::default(), layout)?;
    if set.points.is_empty() {
        return Err(CouplingError::Invalid("the shape is smaller than the marker spacing: no marker fits".into()));
    }
    Ok(set.points)
}

/// Points with a minimum separation of d0/2 (spatial hash).
struct MarkerSet {
    points: Vec<[f64; 3]>,
    cells: HashMap<[i64; 3], Vec<usize>>,
    cell: f64,
    min2: f64,
}

impl MarkerSet {
    fn new(d0: f64) -> Self {
        Self { points: Vec::new(), cells: HashMap::new(), cell: 0.5 * d0, min2: 0.25 * d0 * d0 * (1.0 - 1e-9) }
    }
    fn key(&self, p: [f64; 3]) -> [i64; 3] {
        p.map(|x| (x / self.cell).floor() as i64)
    }
    fn push(&mut self, p: [f64; 3]) {
        let k = self.key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = self.cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &i in v {
                            let q = self.points[i];
                            let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                            if d2 < self.min2 {
                                return;
                            }
                        }
                    }
                }
            }
        }
        self.cells.entry(k).or_default().push(self.points.len());
        self.points.push(p);
    }
}

/// How a shape is filled: spacing, layers and the outermost layer's depth below the surface.
#[derive(Clone, Copy)]
struct Layout {
    d0: f64,
    layers: usize,
    inset: f64,
}

impl Layout {
    /// Depth of layer `k` below the surface.
    fn depth(&self, k: usize) -> f64 {
        self.inset + k as f64 * self.d0
    }
}

fn count(length: f64, d0: f64) -> usize {
    ((length / d0).round() as usize).max(1)
}

/// Points on a circle of radius `r` in the plane normal to z, at height z.
fn ring(r: f64, z: f64, d0: f64, min_points: usize, out: &mut Vec<[f64; 3]>) {
    let n = count(2.0 * std::f64::consts::PI * r, d0).max(min_points);
    for i in 0..n {
        let a = 2.0 * std::f64::consts::PI * (i as f64 + 0.5 * (z / d0).round().rem_euclid(2.0)) / n as f64;
        out.push([r * a.cos(), r * a.sin(), z]);
    }
}

/// A disc of radius `r` at height z: rings inward from the rim (rim excluded when `rim` is
/// false), and a centre point once the rings get below d0.
fn disc(r: f64, z: f64, d0: f64, rim: bool, out: &mut Vec<[f64; 3]>) {
    let mut m = if rim { 0 } else { 1 };
    loop {
        let rr = r - m as f64 * d0;
        if rr < 0.5 * d0 {
            out.push([0.0, 0.0, z]);
            break;
        }
        ring(rr, z, d0, 1, out);
        m += 1;
    }
}

fn add_points(set: &mut MarkerSet, pts: Vec<[f64; 3]>, at: &Pose) {
    for p in pts {
        set.push(at.apply(p));
    }
}

fn add_shape(set: &mut MarkerSet, shape: &ShapeDesc, at: &Pose, lay: Layout) -> Result<(), CouplingError> {
    let Layout { d0, layers, .. } = lay;
    match shape {
        ShapeDesc::Box { size } => {
            let mut pts = Vec::new();
            for k in 0..layers {
                let mut h = size.map(|s| 0.5 * s - lay.depth(k));
                if k == 0 {
                    // A box thinner than twice the inset keeps its mid-plane.
                    h = h.map(|x| x.max(0.0));
                }
                if h.iter().any(|&x| x < -1e-12) {
                    break;
                }
                let n = h.map(|x| if x <= 1e-12 { 0 } else { count(2.0 * x, d0) });
                for i in 0..=n[0] {
                    for j in 0..=n[1] {
                        for l in 0..=n[2] {
                            let on_surface = i == 0 || i == n[0] || j == 0 || j == n[1] || l == 0 || l == n[2];
                            if on_surface {
                                let c = |idx: usize, nn: usize, hh: f64| {
                                    if nn == 0 { 0.0 } else { -hh + 2.0 * hh * idx as f64 / nn as f64 }
                                };
                                pts.push([c(i, n[0], h[0]), c(j, n[1], h[1]), c(l, n[2], h[2])]);
                            }
                        }
                    }
                }
            }
            add_points(set, pts, at);
        }
        ShapeDesc::Sphere { radius } => {
            let mut pts = Vec::new();
            for k in 0..layers {
                let r = radius - lay.depth(k);
                if r < 0.5 * d0 {
                    pts.push([0.0; 3]);
                    break;
                }
                // Fibonacci sphere: N points spread evenly, N from the shell area.
                let n = ((4.0 * std::f64::consts::PI * r * r / (d0 * d0)).round() as usize).max(4);
                let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
                for i in 0..n {
                    let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                    let s = (1.0 - z * z).sqrt();
                    let a = golden * i as f64;
                    pts.push([r * s * a.cos(), r * s * a.sin(), r * z]);
                }
            }
            add_points(set, pts, at);
        }
        ShapeDesc::Cylinder { radius, length, axis } => {
            let pts = cylinder_points(*radius, *length, lay);
            add_points(set, pts, &at.compose(&z_onto(*axis)));
        }
        ShapeDesc::Wheel { radius, width, grousers } => {
            let pts = cylinder_points(*radius, *width, lay);
            add_points(set, pts, &at.compose(&z_onto(Axis::Y)));
            if let Some(g) = grousers {
                for p in g.plate_poses(*radius) {
                    let plate = ShapeDesc::Box { size: [g.thickness.max(d0), *width, g.height] };
                    add_shape(set, &plate, &at.compose(&p), Layout { layers: layers.min(2), ..lay })?;
                }
            }
        }
        ShapeDesc::Cone { radius, height } => {
            add_points(set, cone_points(*radius, *height, lay), at);
        }
        ShapeDesc::Mesh { vertices, indices } => {
            add_points(set, mesh_points(vertices, indices, lay)?, at);
        }
        ShapeDesc::Compound(parts) => {
            for (p, s) in parts {
                add_shape(set, s, &at.compose(p), lay)?;
            }
        }
    }
    Ok(())
}

/// Rotation taking the local z axis onto `axis`.
fn z_onto(axis: Axis) -> Pose {
    match axis {
        Axis::Z => Pose::default(),
        Axis::X => Pose::from_rpy_deg([0.0; 3], [0.0, 90.0, 0.0]),
        Axis::Y => Pose::from_rpy_deg([0.0; 3], [-90.0, 0.0, 0.0]),
    }
}

/// A solid cylinder along z: coaxial shells and cap discs, `layers` deep.
fn cylinder_points(radius: f64, length: f64, lay: Layout) -> Vec<[f64; 3]> {
    let Layout { d0, layers, .. } = lay;
    let mut pts = Vec::new();
    for k in 0..layers {
        let r = radius - lay.depth(k);
        let mut l = 0.5 * length - lay.depth(k);
        if k == 0 {
            // A disc thinner than twice the inset keeps its mid-plane.
            l = l.max(0.0);
        }
        if r < 0.5 * d0 || l < 0.0 {
            // The core: a line of points on the axis fills what is left.
            if l >= 0.0 {
                let n = count(2.0 * l, d0);
                for j in 0..=n {
                    pts.push([0.0, 0.0, if n == 0 { 0.0 } else { -l + 2.0 * l * j as f64 / n as f64 }]);
                }
            }
            break;
        }
        let nz = count(2.0 * l, d0);
        for j in 0..=nz {
            ring(r, -l + 2.0 * l * j as f64 / nz as f64, d0, 3, &mut pts);
        }
        disc(r, l, d0, false, &mut pts);
        disc(r, -l, d0, false, &mut pts);
    }
    pts
}

/// A solid cone, apex down at z = −h/2, base at z = +h/2, `layers` deep, tip truncated.
fn cone_points(radius: f64, height: f64, lay: Layout) -> Vec<[f64; 3]> {
    let Layout { d0, layers, .. } = lay;
    let mut pts = Vec::new();
    let slant = (radius * radius + height * height).sqrt();
    let (sin_a, cos_a) = (radius / slant, height / slant); // half-angle α: tan α = R/H
    for k in 0..layers {
        let delta = lay.depth(k);
        // The inner cone offset by δ along the inward normal: same half-angle, apex raised by
        // δ / sin α, base lowered by δ.
        let apex = -0.5 * height + delta / sin_a;
        let top = 0.5 * height - delta;
        let hk = top - apex;
        if hk <= 0.0 {
            break;
        }
        let rk = hk * radius / height;
        let sk = hk / cos_a;
        // Rings along the slant from radius d0/2 (the truncated tip) to the base rim.
        let s0 = (0.5 * d0 / sin_a).min(sk);
        let n = count(sk - s0, d0);
        for j in 0..=n {
            let s = s0 + (sk - s0) * j as f64 / n as f64;
            ring(s * sin_a, apex + s * cos_a, d0, 3, &mut pts);
        }
        disc(rk, top, d0, false, &mut pts);
    }
    pts
}

/// Checks that a mesh is closed and consistently oriented: every directed edge appears once
/// and its reverse once.
pub fn check_watertight(vertices: &[[f64; 3]], indices: &[[u32; 3]]) -> Result<(), CouplingError> {
    if indices.is_empty() {
        return Err(CouplingError::Mesh("the mesh has no triangles".into()));
    }
    if let Some(t) = indices.iter().find(|t| t.iter().any(|&i| i as usize >= vertices.len())) {
        return Err(CouplingError::Mesh(format!(
            "triangle {t:?} refers to a vertex beyond the {} given",
            vertices.len()
        )));
    }
    // Merge coincident vertices first: exporters often split vertices along seams.
    let mut canon: HashMap<[i64; 3], u32> = HashMap::new();
    let scale = vertices.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs())).max(1e-12);
    let key = |v: [f64; 3]| v.map(|x| (x / scale * 1e9).round() as i64);
    let ids: Vec<u32> = vertices
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let n = canon.len() as u32;
            let _ = i;
            *canon.entry(key(*v)).or_insert(n)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in indices {
        let v = t.map(|i| ids[i as usize]);
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            continue;
        }
        for (a, b) in [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])] {
            *edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        if n > 1 {
            return Err(CouplingError::Mesh(format!(
                "the mesh is not consistently oriented or not manifold: edge {a}→{b} is used by {n} triangles in the same direction"
            )));
        }
        if !edges.contains_key(&(b, a)) {
            return Err(CouplingError::Mesh(format!(
                "the mesh is not watertight: edge {a}–{b} borders only one triangle (a hole); markers fill a closed volume"
            )));
        }
    }
    Ok(())
}

fn mesh_points(vertices: &[[f64; 3]], indices: &[[u32; 3]], lay: Layout) -> Result<Vec<[f64; 3]>, CouplingError> {
    let Layout { d0, layers, inset } = lay;
    check_watertight(vertices, indices)?;
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let cross =
        |p: [f64; 3], q: [f64; 3]| [p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]];
    let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    // A closed, consistently oriented mesh winds outward when its signed volume is positive;
    // one wound inward is turned around, so that parry's inside test and the normals agree.
    let volume: f64 = indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            dot(a, cross(b, c))
        })
        .sum();
    let indices: Vec<[u32; 3]> =
        if volume >= 0.0 { indices.to_vec() } else { indices.iter().map(|t| [t[0], t[2], t[1]]).collect() };
    let verts: Vec<PVector> = vertices.iter().map(|v| PVector::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect();
    let mesh =
        TriMesh::with_flags(verts, indices.clone(), TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES)
            .map_err(|e| CouplingError::Mesh(format!("cannot build the mesh: {e:?}")))?;
    // Depth of a point below the surface (negative outside).
    let depth = |p: [f64; 3]| {
        let q = PVector::new(p[0] as f32, p[1] as f32, p[2] as f32);
        let proj = mesh.project_local_point(q, false);
        let d = f64::from((proj.point - q).length());
        if proj.is_inside { d } else { -d }
    };
    let mut pts = Vec::new();
    // Surface: each triangle on a barycentric grid with edges of at most d0, moved `inset`
    // inward along its normal. Near an edge or a corner a moved sample can still lie closer
    // than `inset` to a neighbouring face: it is dropped (the f32 projection allows 1e-6 m).
    for t in &indices {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let len = |p: [f64; 3], q: [f64; 3]| dot(sub(p, q), sub(p, q)).sqrt();
        let normal = cross(sub(b, a), sub(c, a));
        let area2 = dot(normal, normal).sqrt();
        if area2 <= 0.0 {
            continue;
        }
        let shift = normal.map(|x| -inset * x / area2);
        let n = (len(a, b).max(len(b, c)).max(len(c, a)) / d0).ceil().max(1.0) as usize;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let w = 1.0 - u - v;
                let p = [0, 1, 2].map(|k| w * a[k] + u * b[k] + v * c[k] + shift[k]);
                if inset == 0.0 || depth(p) >= inset - 1e-6 {
                    pts.push(p);
                }
            }
        }
    }
    if layers > 1 {
        let mut lo = [f64::MAX; 3];
        let mut hi = [f64::MIN; 3];
        for v in vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        let n = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / d0).floor() as i64);
        let depth_max = inset + (layers as f64 - 0.5) * d0;
        for i in 0..=n[0] {
            for j in 0..=n[1] {
                for l in 0..=n[2] {
                    let p =
                        [lo[0] + (i as f64 + 0.5) * d0, lo[1] + (j as f64 + 0.5) * d0, lo[2] + (l as f64 + 0.5) * d0];
                    let d = depth(p);
                    if d > inset + 0.5 * d0 && d <= depth_max {
                        pts.push(p);
                    }
                }
            }
        }
    }
    Ok(pts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use regolith_rigid::Grousers;

    fn min_dist(p: &[[f64; 3]]) -> f64 {
        let mut m = f64::MAX;
        for i in 0..p.len() {
            for j in 0..i {
                let d =
                    ((p[i][0] - p[j][0]).powi(2) + (p[i][1] - p[j][1]).powi(2) + (p[i][2] - p[j][2]).powi(2)).sqrt();
                m = m.min(d);
            }
        }
        m
    }

    #[test]
    fn box_markers_sit_on_nested_surfaces() {
        let d0 = 0.01;
        let m = shape_markers(&ShapeDesc::Box { size: [0.1, 0.06, 0.04] }, d0, 3, 0.0).expect("markers");
        // Outermost layer on the surface, inner ones one and two spacings in.
        let on = |p: &[f64; 3], k: f64| {
            let h = [0.05 - k * d0, 0.03 - k * d0, 0.02 - k * d0];
            let inside = (0..3).all(|a| p[a].abs() <= h[a] + 1e-12);
            let touch = (0..3).any(|a| (p[a].abs() - h[a]).abs() < 1e-12);
            inside && touch
        };
        assert!(m.iter().all(|p| on(p, 0.0) || on(p, 1.0) || on(p, 2.0)));
        assert!(m.iter().filter(|p| on(p, 0.0)).count() > 60);
        assert!(min_dist(&m) >= 0.5 * d0 - 1e-12);
    }

    #[test]
    fn cone_tip_is_truncated_into_a_ring() {
        let d0 = 0.002;
        let (r, h) = (0.0101, 0.0101 / (15f64).to_radians().tan()); // 30° cone, 323 mm² base
        let m = shape_markers(&ShapeDesc::Cone { radius: r, height: h }, d0, 3, 0.0).expect("markers");
        let zmin = m.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
        let tip: Vec<_> = m.iter().filter(|p| (p[2] - zmin).abs() < 1e-9).collect();
        assert!(tip.len() >= 3, "the lowest level holds {} markers: a single tip marker", tip.len());
        let tip_r = (tip[0][0].powi(2) + tip[0][1].powi(2)).sqrt();
        assert!((tip_r - 0.5 * d0).abs() < 1e-9);
        // All markers lie inside the cone.
        for p in &m {
            let s = (p[2] + 0.5 * h) * r / h;
            assert!((p[0].powi(2) + p[1].powi(2)).sqrt() <= s + 1e-9 && p[2] <= 0.5 * h + 1e-9);
        }
    }

    #[test]
    fn wheel_with_grousers_has_plates_on_the_rim() {
        let d0 = 0.01;
        let g = Grousers { count: 8, height: 0.02, thickness: 0.005 };
        let m = shape_markers(&ShapeDesc::Wheel { radius: 0.15, width: 0.1, grousers: Some(g) }, d0, 3, 0.0)
            .expect("markers");
        let beyond: Vec<_> = m.iter().filter(|p| (p[0].powi(2) + p[2].powi(2)).sqrt() > 0.15 + 0.5 * d0).collect();
        assert!(beyond.len() > 8 * 4, "grouser markers: {}", beyond.len());
        assert!(m.iter().all(|p| p[1].abs() <= 0.05 + 1e-9));
        assert!(min_dist(&m) >= 0.5 * d0 - 1e-9);
    }

    fn cube(open: bool) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let v = vec![
            [0.0, 0.0, 0.0],
            [0.1, 0.0, 0.0],
            [0.1, 0.1, 0.0],
            [0.0, 0.1, 0.0],
            [0.0, 0.0, 0.1],
            [0.1, 0.0, 0.1],
            [0.1, 0.1, 0.1],
            [0.0, 0.1, 0.1],
        ];
        let mut t = vec![
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
        ];
        if open {
            t.pop();
        }
        (v, t)
    }

    #[test]
    fn watertight_mesh_gets_volume_layers_and_an_open_one_is_an_error() {
        let (v, t) = cube(false);
        let d0 = 0.01;
        let m = shape_markers(&ShapeDesc::Mesh { vertices: v, indices: t }, d0, 3, 0.0).expect("markers");
        let inner = m.iter().filter(|p| p.iter().all(|&x| x > 0.005 && x < 0.095)).count();
        assert!(inner > 100, "inner layer markers: {inner}");
        assert!(m.iter().all(|p| p.iter().all(|&x| (-1e-9..=0.1 + 1e-9).contains(&x))));
        let (v, t) = cube(true);
        let e = shape_markers(&ShapeDesc::Mesh { vertices: v, indices: t }, d0, 3, 0.0).expect_err("open mesh");
        assert!(e.to_string().contains("not watertight"), "{e}");
    }

    #[test]
    fn spheres_and_cylinders_follow_their_surfaces() {
        let d0 = 0.01;
        let m = shape_markers(&ShapeDesc::Sphere { radius: 0.05 }, d0, 2, 0.0).expect("markers");
        assert!(m.iter().all(|p| {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            (r - 0.05).abs() < 1e-9 || (r - 0.04).abs() < 1e-9
        }));
        let m = shape_markers(&ShapeDesc::Cylinder { radius: 0.05, length: 0.02, axis: Axis::X }, d0, 3, 0.0)
            .expect("markers");
        assert!(m.iter().all(|p| p[0].abs() <= 0.01 + 1e-9 && (p[1] * p[1] + p[2] * p[2]).sqrt() <= 0.05 + 1e-9));
        assert!(m.iter().any(|p| ((p[1] * p[1] + p[2] * p[2]).sqrt() - 0.05).abs() < 1e-9));
    }

    #[test]
    fn inset_markers_lie_half_a_spacing_inside_every_shape() {
        let d0 = 0.01;
        let i = 0.5 * d0;
        // Box: nested surfaces shrunk by d0/2 + k d0.
        let m = shape_markers(&ShapeDesc::Box { size: [0.1, 0.06, 0.04] }, d0, 3, i).expect("markers");
        let on = |p: &[f64; 3], k: f64| {
            let h = [0.05, 0.03, 0.02].map(|x| x - i - k * d0);
            (0..3).all(|a| p[a].abs() <= h[a] + 1e-12) && (0..3).any(|a| (p[a].abs() - h[a]).abs() < 1e-12)
        };
        assert!(m.iter().all(|p| on(p, 0.0) || on(p, 1.0) || on(p, 2.0)));
        assert!(m.iter().any(|p| (p[0] - 0.045).abs() < 1e-12));
        // A plate thinner than d0 keeps one layer on its mid-plane.
        let m = shape_markers(&ShapeDesc::Box { size: [0.1, 0.1, 0.006] }, d0, 3, i).expect("markers");
        assert!(m.iter().all(|p| p[2].abs() < 1e-12), "a thin plate's markers leave its mid-plane");
        assert!(m.iter().any(|p| (p[0] - 0.045).abs() < 1e-12));
        // Sphere and cylinder shells at R − d0/2 − k d0.
        let m = shape_markers(&ShapeDesc::Sphere { radius: 0.05 }, d0, 2, i).expect("markers");
        assert!(m.iter().all(|p| {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            (r - 0.045).abs() < 1e-9 || (r - 0.035).abs() < 1e-9
        }));
        let m = shape_markers(&ShapeDesc::Cylinder { radius: 0.05, length: 0.02, axis: Axis::Z }, d0, 3, i)
            .expect("markers");
        let r_max = m.iter().map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt()).fold(0.0, f64::max);
        let z_max = m.iter().map(|p| p[2].abs()).fold(0.0, f64::max);
        assert!((r_max - 0.045).abs() < 1e-9 && (z_max - 0.005).abs() < 1e-9, "{r_max} {z_max}");
        // Cone: every marker at least d0/2 inside the slant and the base.
        let (r, h) = (0.02, 0.03);
        let m = shape_markers(&ShapeDesc::Cone { radius: r, height: h }, d0 / 4.0, 3, i / 4.0).expect("markers");
        let slant = (r * r + h * h).sqrt();
        for p in &m {
            let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
            // Distance inside the slanted face: (radius there − ρ) cos α.
            let inside_slant = ((p[2] + 0.5 * h) * r / h - rho) * h / slant;
            assert!(inside_slant >= i / 4.0 - 1e-9 && 0.5 * h - p[2] >= i / 4.0 - 1e-9, "{p:?}");
        }
        // A closed mesh (a cube, either winding): its surface samples move d0/2 inward, and
        // both windings give the same markers (an inward-wound mesh is turned around; it used
        // to lose its inner layers, parry reading its inside as outside).
        let mut counts = Vec::new();
        for flip in [false, true] {
            let (v, mut t) = cube(false);
            if flip {
                t.iter_mut().for_each(|tri| tri.swap(1, 2));
            }
            let m = shape_markers(&ShapeDesc::Mesh { vertices: v, indices: t }, d0, 2, i)
                .unwrap_or_else(|e| panic!("flip {flip}: {e}"));
            assert!(m.iter().all(|p| p.iter().all(|&x| (i - 2e-6..=0.1 - i + 2e-6).contains(&x))), "flip {flip}");
            assert!(m.iter().filter(|p| p.iter().any(|&x| (x - i).abs() < 1e-9)).count() > 100);
            let (v, mut t) = cube(false);
            if flip {
                t.iter_mut().for_each(|tri| tri.swap(1, 2));
            }
            counts.push((
                m.len(),
                shape_markers(&ShapeDesc::Mesh { vertices: v, indices: t }, d0, 3, 0.0).map(|m| m.len()).ok(),
            ));
        }
        assert_eq!(counts[0], counts[1]);
        assert!(shape_markers(&ShapeDesc::Sphere { radius: 0.05 }, d0, 2, 0.6 * d0).is_err());
    }
}
