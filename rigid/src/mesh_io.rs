//! Triangle meshes from files: STL (ASCII or binary), Wavefront OBJ (`v` and `f` records;
//! polygons are fanned into triangles) and COLLADA `.dae` (see [`crate::dae`]). Errors name the file and, for text formats, the line.

use std::path::Path;

use crate::mesh::{MeshError, TriangleMesh, err};

/// Loads `.stl`, `.obj` or `.dae`, scaling every coordinate by `scale` (per axis).
pub fn load_mesh(path: &Path, scale: [f64; 3]) -> Result<TriangleMesh, MeshError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let bytes = std::fs::read(path).map_err(|e| err(path, None, format!("cannot read: {e}")))?;
    let mut mesh = match ext.as_deref() {
        Some("stl") => stl(path, &bytes)?,
        Some("obj") => obj(path, &bytes)?,
        Some("dae") => crate::dae::read(path, &bytes)?,
        _ => return Err(err(path, None, "unsupported mesh format: use .stl, .obj or .dae")),
    };
    if mesh.indices.is_empty() {
        return Err(err(path, None, "the mesh has no triangles"));
    }
    for v in &mut mesh.vertices {
        for k in 0..3 {
            v[k] *= scale[k];
        }
    }
    if mesh.vertices.iter().flatten().any(|x| !x.is_finite()) {
        return Err(err(path, None, "a vertex coordinate is not finite"));
    }
    Ok(mesh)
}

fn stl(path: &Path, b: &[u8]) -> Result<TriangleMesh, MeshError> {
    // Binary STL: 80-byte header, u32 count, 50 bytes per triangle. ASCII files start with
    // "solid" but some binary files do too, so decide by the size.
    if b.len() >= 84 {
        let n = u32::from_le_bytes([b[80], b[81], b[82], b[83]]) as usize;
        if b.len() == 84 + 50 * n {
            let mut m = TriangleMesh::default();
            for t in 0..n {
                let o = 84 + 50 * t + 12;
                let mut tri = [0u32; 3];
                for (k, slot) in tri.iter_mut().enumerate() {
                    let p = o + 12 * k;
                    let f = |i: usize| {
                        f64::from(f32::from_le_bytes([
                            b[p + 4 * i],
                            b[p + 4 * i + 1],
                            b[p + 4 * i + 2],
                            b[p + 4 * i + 3],
                        ]))
                    };
                    m.vertices.push([f(0), f(1), f(2)]);
                    *slot = (m.vertices.len() - 1) as u32;
                }
                m.indices.push(tri);
            }
            return Ok(m);
        }
    }
    let text = std::str::from_utf8(b).map_err(|_| {
        err(path, None, "not a valid binary STL (size does not match its triangle count) nor ASCII STL")
    })?;
    let mut m = TriangleMesh::default();
    let mut pending: Vec<u32> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("vertex") => {
                let c: Result<Vec<f64>, _> = w.map(str::parse).collect();
                let c = c.map_err(|e| err(path, Some(i + 1), format!("bad vertex: {e}")))?;
                if c.len() != 3 {
                    return Err(err(path, Some(i + 1), "a vertex needs three coordinates"));
                }
                m.vertices.push([c[0], c[1], c[2]]);
                pending.push((m.vertices.len() - 1) as u32);
            }
            Some("endfacet") => {
                if pending.len() != 3 {
                    return Err(err(path, Some(i + 1), format!("a facet has {} vertices, not 3", pending.len())));
                }
                m.indices.push([pending[0], pending[1], pending[2]]);
                pending.clear();
            }
            _ => {}
        }
    }
    Ok(m)
}

fn obj(path: &Path, b: &[u8]) -> Result<TriangleMesh, MeshError> {
    let text = String::from_utf8_lossy(b);
    let mut m = TriangleMesh::default();
    for (i, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Result<Vec<f64>, _> = w.take(3).map(str::parse).collect();
                let c = c.map_err(|e| err(path, Some(i + 1), format!("bad vertex: {e}")))?;
                if c.len() != 3 {
                    return Err(err(path, Some(i + 1), "a vertex needs three coordinates"));
                }
                m.vertices.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let mut idx = Vec::new();
                for tok in w {
                    let first = tok.split('/').next().unwrap_or("");
                    let k: i64 =
                        first.parse().map_err(|_| err(path, Some(i + 1), format!("bad face index `{tok}`")))?;
                    let n = m.vertices.len() as i64;
                    let j = if k < 0 { n + k } else { k - 1 };
                    if !(0..n).contains(&j) {
                        return Err(err(
                            path,
                            Some(i + 1),
                            format!("face index {k} refers to none of the {n} vertices read so far"),
                        ));
                    }
                    idx.push(j as u32);
                }
                if idx.len() < 3 {
                    return Err(err(path, Some(i + 1), "a face needs at least 3 vertices"));
                }
                for k in 1..idx.len() - 1 {
                    m.indices.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    fn tmp(name: &str, bytes: &[u8]) -> PathBuf {
        let d = std::env::temp_dir().join(format!("regolith-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("tmp");
        let p = d.join(name);
        std::fs::write(&p, bytes).expect("write");
        p
    }

    #[test]
    fn reads_obj_ascii_and_binary_stl() {
        let p = tmp("q.obj", b"# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 4/4\n");
        let m = load_mesh(&p, [2.0, 2.0, 2.0]).expect("obj");
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.vertices[2], [2.0, 2.0, 0.0]);
        let p = tmp("t.stl", b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n");
        assert_eq!(load_mesh(&p, [1.0; 3]).expect("ascii stl").indices.len(), 1);
        let mut b = vec![0u8; 80];
        b.extend(1u32.to_le_bytes());
        b.extend([0u8; 12]);
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for c in v {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
        let p = tmp("b.stl", &b);
        let m = load_mesh(&p, [1.0; 3]).expect("binary stl");
        assert_eq!(m.vertices[1], [1.0, 0.0, 0.0]);
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let p = tmp("bad.obj", b"v 0 0 0\nv 1 0\n");
        let e = load_mesh(&p, [1.0; 3]).expect_err("bad").to_string();
        assert!(e.ends_with("bad.obj:2: a vertex needs three coordinates"), "{e}");
        let p = tmp("bad2.obj", b"v 0 0 0\nf 1 2 3\n");
        assert!(
            load_mesh(&p, [1.0; 3])
                .expect_err("bad")
                .to_string()
                .contains(":2: face index 2 refers to none of the 1 vertices")
        );
        let p = tmp("x.ply", b"");
        assert!(load_mesh(&p, [1.0; 3]).expect_err("format").to_string().contains("unsupported mesh format"));
    }
}
