//! COLLADA (`.dae`) triangle geometry, as URDF packages ship it.
//!
//! Reads every `<mesh>` of `<library_geometries>`: the `POSITION` source behind `<vertices>`,
//! and `<triangles>`, `<polylist>` (fanned) and `<polygons>` (fanned) index lists with any
//! number of interleaved inputs; `<asset><unit meter="…">` scales the result to metres. The
//! scene graph (`<node>` transforms) is not applied: a node with a transform other than the
//! identity is an error naming it, so a mesh is never placed wrongly in silence. Export with
//! transforms applied ("bake") to use such a file.

use std::collections::HashMap;
use std::path::Path;

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

use crate::mesh::{MeshError, TriangleMesh, err};

#[derive(Default)]
struct Primitive {
    /// Offset of the VERTEX input and the number of interleaved inputs.
    vertex_offset: usize,
    stride: usize,
    vertices_id: String,
    /// Polygon sizes (`<vcount>` of a polylist; empty = triangles).
    vcount: Vec<usize>,
    /// `<p>` lists (one for triangles/polylist, one per polygon for `<polygons>`).
    p: Vec<Vec<usize>>,
    kind: String,
}

fn attr(e: &BytesStart<'_>, name: &str) -> Option<String> {
    e.try_get_attribute(name).ok().flatten().and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
}

fn numbers<T: std::str::FromStr>(path: &Path, text: &str, what: &str) -> Result<Vec<T>, MeshError> {
    text.split_whitespace()
        .map(|w| w.parse::<T>().map_err(|_| err(path, None, format!("{what}: `{w}` is not a number"))))
        .collect()
}

/// Reads the triangles of a `.dae` file (m).
pub fn read(path: &Path, bytes: &[u8]) -> Result<TriangleMesh, MeshError> {
    let text = std::str::from_utf8(bytes).map_err(|_| err(path, None, "not UTF-8 text (COLLADA is XML)"))?;
    let mut reader = Reader::from_str(text);
    let mut stack: Vec<String> = Vec::new();
    let mut unit = 1.0;
    let mut source_id = String::new();
    let mut float_arrays: HashMap<String, Vec<f64>> = HashMap::new();
    let mut vertices_id = String::new();
    let mut position_of: HashMap<String, String> = HashMap::new();
    let mut prims: Vec<Primitive> = Vec::new();
    let mut node = String::new();
    let xml = |e: quick_xml::Error, pos: u64| err(path, None, format!("malformed XML at byte {pos}: {e}"));
    loop {
        let ev = reader.read_event().map_err(|e| xml(e, reader.buffer_position()))?;
        let (start, empty) = match &ev {
            Event::Start(e) => (Some(e.clone()), false),
            Event::Empty(e) => (Some(e.clone()), true),
            _ => (None, false),
        };
        if let Some(e) = start {
            let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
            match name.as_str() {
                "unit" => {
                    if let Some(m) = attr(&e, "meter") {
                        unit = m.parse::<f64>().ok().filter(|u| *u > 0.0 && u.is_finite()).ok_or_else(|| {
                            err(path, None, format!("<unit meter=\"{m}\"> must be a positive number"))
                        })?;
                    }
                }
                "source" => source_id = attr(&e, "id").unwrap_or_default(),
                "vertices" => vertices_id = attr(&e, "id").unwrap_or_default(),
                "node" => node = attr(&e, "name").or_else(|| attr(&e, "id")).unwrap_or_else(|| "(unnamed)".into()),
                "triangles" | "polylist" | "polygons" => {
                    prims.push(Primitive { kind: name.clone(), ..Default::default() });
                }
                "input" => {
                    let semantic = attr(&e, "semantic").unwrap_or_default();
                    let src = attr(&e, "source").unwrap_or_default().trim_start_matches('#').to_string();
                    let parent = stack.last().map(String::as_str).unwrap_or("");
                    if parent == "vertices" && semantic == "POSITION" {
                        position_of.insert(vertices_id.clone(), src);
                    } else if matches!(parent, "triangles" | "polylist" | "polygons")
                        && let Some(p) = prims.last_mut()
                    {
                        let offset: usize = attr(&e, "offset").and_then(|o| o.parse().ok()).unwrap_or(0);
                        p.stride = p.stride.max(offset + 1);
                        if semantic == "VERTEX" {
                            p.vertex_offset = offset;
                            p.vertices_id = src;
                        }
                    }
                }
                _ => {}
            }
            if !empty {
                stack.push(name);
            }
            continue;
        }
        match ev {
            Event::Text(t) => {
                let Some(top) = stack.last() else { continue };
                let s = t.decode().map_err(|e| err(path, None, format!("text encoding: {e}")))?;
                let parent = stack.len().checked_sub(2).map(|i| stack[i].as_str()).unwrap_or("");
                match top.as_str() {
                    "float_array" => {
                        let v = numbers::<f64>(path, &s, &format!("float_array of source `{source_id}`"))?;
                        float_arrays.entry(source_id.clone()).or_default().extend(v);
                    }
                    "vcount" => {
                        if let Some(p) = prims.last_mut() {
                            p.vcount.extend(numbers::<usize>(path, &s, "vcount")?);
                        }
                    }
                    "p" if matches!(parent, "triangles" | "polylist" | "polygons") => {
                        if let Some(p) = prims.last_mut() {
                            let list = numbers::<usize>(path, &s, "<p> index list")?;
                            if p.kind == "polygons" || p.p.is_empty() {
                                p.p.push(list);
                            } else {
                                p.p[0].extend(list);
                            }
                        }
                    }
                    "matrix" | "translate" | "rotate" | "scale" if parent == "node" => {
                        let v = numbers::<f64>(path, &s, &format!("<{top}> of node `{node}`"))?;
                        let identity = match top.as_str() {
                            "matrix" => {
                                v.len() == 16
                                    && v.iter()
                                        .enumerate()
                                        .all(|(i, x)| (x - if i % 5 == 0 { 1.0 } else { 0.0 }).abs() < 1e-9)
                            }
                            "translate" => v.iter().all(|x| x.abs() < 1e-12),
                            "rotate" => v.len() == 4 && v[3].abs() < 1e-12,
                            _ => v.iter().all(|x| (x - 1.0).abs() < 1e-12),
                        };
                        if !identity {
                            return Err(err(
                                path,
                                None,
                                format!(
                                    "node `{node}` has a <{top}> transform; node transforms are not applied: export the mesh with transforms baked into the geometry"
                                ),
                            ));
                        }
                    }
                    _ => {}
                }
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Eof => break,
            _ => {}
        }
    }
    let mut mesh = TriangleMesh::default();
    for p in &prims {
        let src = position_of.get(&p.vertices_id).ok_or_else(|| {
            err(path, None, format!("<{}> refers to vertices `{}` with no POSITION", p.kind, p.vertices_id))
        })?;
        let floats = float_arrays
            .get(src)
            .ok_or_else(|| err(path, None, format!("POSITION source `{src}` has no float_array")))?;
        if floats.len() % 3 != 0 {
            return Err(err(
                path,
                None,
                format!("POSITION source `{src}` holds {} numbers, not a multiple of 3", floats.len()),
            ));
        }
        let base = mesh.vertices.len() as u32;
        let n = floats.len() / 3;
        mesh.vertices.extend(floats.chunks(3).map(|c| [c[0] * unit, c[1] * unit, c[2] * unit]));
        let stride = p.stride.max(1);
        let vertex = |list: &[usize], k: usize| -> Result<u32, MeshError> {
            let i = *list
                .get(k * stride + p.vertex_offset)
                .ok_or_else(|| err(path, None, format!("<{}> index list is shorter than its polygons", p.kind)))?;
            if i >= n {
                return Err(err(
                    path,
                    None,
                    format!("<{}> vertex index {i} is out of range (source `{src}` has {n})", p.kind),
                ));
            }
            Ok(base + i as u32)
        };
        let mut fan = |list: &[usize], first: usize, count: usize| -> Result<(), MeshError> {
            for k in 1..count.saturating_sub(1) {
                mesh.indices.push([vertex(list, first)?, vertex(list, first + k)?, vertex(list, first + k + 1)?]);
            }
            Ok(())
        };
        match p.kind.as_str() {
            "triangles" => {
                let list = p.p.first().map(Vec::as_slice).unwrap_or(&[]);
                for t in 0..list.len() / (3 * stride) {
                    fan(list, 3 * t, 3)?;
                }
            }
            "polylist" => {
                let list = p.p.first().map(Vec::as_slice).unwrap_or(&[]);
                let mut first = 0;
                for &c in &p.vcount {
                    fan(list, first, c)?;
                    first += c;
                }
            }
            _ => {
                for list in &p.p {
                    fan(list, 0, list.len() / stride)?;
                }
            }
        }
    }
    Ok(mesh)
}
