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

/// What the parse has gathered so far.
#[derive(Default)]
struct Collada {
    /// `<unit meter>`: metres per file unit.
    unit: f64,
    /// The `<source>` and `<vertices>` being read, and the `<node>` (for its transforms).
    source_id: String,
    vertices_id: String,
    node: String,
    float_arrays: HashMap<String, Vec<f64>>,
    /// The POSITION source of each `<vertices>`.
    position_of: HashMap<String, String>,
    prims: Vec<Primitive>,
}

/// Reads the triangles of a `.dae` file (m).
pub fn read(path: &Path, bytes: &[u8]) -> Result<TriangleMesh, MeshError> {
    let text = std::str::from_utf8(bytes).map_err(|_| err(path, None, "not UTF-8 text (COLLADA is XML)"))?;
    let mut reader = Reader::from_str(text);
    let mut stack: Vec<String> = Vec::new();
    let mut c = Collada { unit: 1.0, ..Default::default() };
    let xml = |e: quick_xml::Error, pos: u64| err(path, None, format!("malformed XML at byte {pos}: {e}"));
    loop {
        let ev = reader.read_event().map_err(|e| xml(e, reader.buffer_position()))?;
        match &ev {
            Event::Start(e) | Event::Empty(e) => {
                let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                c.start(path, e, &name, stack.last().map(String::as_str).unwrap_or(""))?;
                if matches!(ev, Event::Start(_)) {
                    stack.push(name);
                }
            }
            Event::Text(t) => {
                let Some(top) = stack.last() else { continue };
                let s = t.decode().map_err(|e| err(path, None, format!("text encoding: {e}")))?;
                let parent = stack.len().checked_sub(2).map(|i| stack[i].as_str()).unwrap_or("");
                c.text(path, top, parent, &s)?;
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Eof => break,
            _ => {}
        }
    }
    let mut mesh = TriangleMesh::default();
    for p in &c.prims {
        c.append(path, p, &mut mesh)?;
    }
    Ok(mesh)
}

impl Collada {
    /// An opening (or empty) element `name` inside `parent`.
    fn start(&mut self, path: &Path, e: &BytesStart<'_>, name: &str, parent: &str) -> Result<(), MeshError> {
        match name {
            "unit" => {
                if let Some(m) = attr(e, "meter") {
                    self.unit =
                        m.parse::<f64>().ok().filter(|u| *u > 0.0 && u.is_finite()).ok_or_else(|| {
                            err(path, None, format!("<unit meter=\"{m}\"> must be a positive number"))
                        })?;
                }
            }
            "source" => self.source_id = attr(e, "id").unwrap_or_default(),
            "vertices" => self.vertices_id = attr(e, "id").unwrap_or_default(),
            "node" => self.node = attr(e, "name").or_else(|| attr(e, "id")).unwrap_or_else(|| "(unnamed)".into()),
            "triangles" | "polylist" | "polygons" => {
                self.prims.push(Primitive { kind: name.to_string(), ..Default::default() });
            }
            "input" => {
                let semantic = attr(e, "semantic").unwrap_or_default();
                let src = attr(e, "source").unwrap_or_default().trim_start_matches('#').to_string();
                if parent == "vertices" && semantic == "POSITION" {
                    self.position_of.insert(self.vertices_id.clone(), src);
                } else if matches!(parent, "triangles" | "polylist" | "polygons")
                    && let Some(p) = self.prims.last_mut()
                {
                    let offset: usize = attr(e, "offset").and_then(|o| o.parse().ok()).unwrap_or(0);
                    p.stride = p.stride.max(offset + 1);
                    if semantic == "VERTEX" {
                        p.vertex_offset = offset;
                        p.vertices_id = src;
                    }
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The text `s` of element `top` inside `parent`: numbers, index lists, node transforms.
    fn text(&mut self, path: &Path, top: &str, parent: &str, s: &str) -> Result<(), MeshError> {
        match top {
            "float_array" => {
                let v = numbers::<f64>(path, s, &format!("float_array of source `{}`", self.source_id))?;
                self.float_arrays.entry(self.source_id.clone()).or_default().extend(v);
            }
            "vcount" => {
                if let Some(p) = self.prims.last_mut() {
                    p.vcount.extend(numbers::<usize>(path, s, "vcount")?);
                }
            }
            "p" if matches!(parent, "triangles" | "polylist" | "polygons") => {
                if let Some(p) = self.prims.last_mut() {
                    let list = numbers::<usize>(path, s, "<p> index list")?;
                    if p.kind == "polygons" || p.p.is_empty() {
                        p.p.push(list);
                    } else {
                        p.p[0].extend(list);
                    }
                }
            }
            "matrix" | "translate" | "rotate" | "scale" if parent == "node" => {
                let node = &self.node;
                let v = numbers::<f64>(path, s, &format!("<{top}> of node `{node}`"))?;
                let identity = match top {
                    "matrix" => {
                        v.len() == 16
                            && v.iter().enumerate().all(|(i, x)| (x - if i % 5 == 0 { 1.0 } else { 0.0 }).abs() < 1e-9)
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
        Ok(())
    }

    /// Appends primitive `p`'s vertices (scaled to metres) and its triangles (polygons fanned).
    fn append(&self, path: &Path, p: &Primitive, mesh: &mut TriangleMesh) -> Result<(), MeshError> {
        let src = self.position_of.get(&p.vertices_id).ok_or_else(|| {
            err(path, None, format!("<{}> refers to vertices `{}` with no POSITION", p.kind, p.vertices_id))
        })?;
        let floats = self
            .float_arrays
            .get(src)
            .ok_or_else(|| err(path, None, format!("POSITION source `{src}` has no float_array")))?;
        if floats.len() % 3 != 0 {
            return Err(err(
                path,
                None,
                format!("POSITION source `{src}` holds {} numbers, not a multiple of 3", floats.len()),
            ));
        }
        let unit = self.unit;
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
        Ok(())
    }
}
