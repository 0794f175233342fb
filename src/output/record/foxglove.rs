//! Foxglove's well-known message types in their JSON encoding, and the JSON schemas that go
//! into the recording with them.
//!
//! The schemas follow the field names and types of Foxglove's published `foxglove.*` schemas
//! (timestamps as `{sec, nsec}`, `bytes` as base64 strings, enums as integers), so that
//! Foxglove shows the topics with its built-in panels. Every field we write is `required`, so
//! that validating a message against the embedded schema catches a missing field.

use base64::Engine as _;
use regolith_rigid::{Axis, Pose, ShapeDesc};
use serde_json::{Value, json};

/// `foxglove.PackedElementField` numeric type `FLOAT32`.
pub const FLOAT32: u32 = 7;
/// `foxglove.PackedElementField` numeric type `UINT32`.
pub const UINT32: u32 = 5;

/// The point-cloud fields: name and numeric type, packed in this order, 4 bytes each.
pub const POINT_FIELDS: [(&str, u32); 9] = [
    ("x", FLOAT32),
    ("y", FLOAT32),
    ("z", FLOAT32),
    ("p", FLOAT32),
    ("q", FLOAT32),
    ("pc", FLOAT32),
    ("speed", FLOAT32),
    ("material", UINT32),
    ("phase", UINT32),
];

/// Bytes per point.
pub const POINT_STRIDE: usize = 4 * POINT_FIELDS.len();

fn time_schema() -> Value {
    json!({
        "type": "object",
        "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}
        },
        "required": ["sec", "nsec"]
    })
}

fn xyz_schema() -> Value {
    json!({
        "type": "object",
        "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}},
        "required": ["x", "y", "z"]
    })
}

fn quat_schema() -> Value {
    json!({
        "type": "object",
        "properties": {
            "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}
        },
        "required": ["x", "y", "z", "w"]
    })
}

fn pose_schema() -> Value {
    json!({
        "type": "object",
        "properties": {"position": xyz_schema(), "orientation": quat_schema()},
        "required": ["position", "orientation"]
    })
}

fn color_schema() -> Value {
    let c = json!({"type": "number", "minimum": 0, "maximum": 1});
    json!({
        "type": "object",
        "properties": {"r": c, "g": c, "b": c, "a": c},
        "required": ["r", "g", "b", "a"]
    })
}

/// JSON schema of `foxglove.PointCloud`.
pub fn point_cloud_schema() -> Value {
    json!({
        "title": "foxglove.PointCloud",
        "description": "A collection of N-dimensional points, which may contain additional fields with information like normals, intensity, etc.",
        "type": "object",
        "properties": {
            "timestamp": time_schema(),
            "frame_id": {"type": "string"},
            "pose": pose_schema(),
            "point_stride": {"type": "integer", "minimum": 0},
            "fields": {
                "type": "array",
                "items": {
                    "title": "foxglove.PackedElementField",
                    "type": "object",
                    "properties": {
                        "name": {"type": "string"},
                        "offset": {"type": "integer", "minimum": 0},
                        "type": {"type": "integer", "enum": [0, 1, 2, 3, 4, 5, 6, 7, 8]}
                    },
                    "required": ["name", "offset", "type"]
                }
            },
            "data": {"type": "string", "contentEncoding": "base64"}
        },
        "required": ["timestamp", "frame_id", "pose", "point_stride", "fields", "data"]
    })
}

/// JSON schema of `foxglove.FrameTransforms`.
pub fn frame_transforms_schema() -> Value {
    json!({
        "title": "foxglove.FrameTransforms",
        "description": "An array of FrameTransform messages",
        "type": "object",
        "properties": {
            "transforms": {
                "type": "array",
                "items": {
                    "title": "foxglove.FrameTransform",
                    "type": "object",
                    "properties": {
                        "timestamp": time_schema(),
                        "parent_frame_id": {"type": "string"},
                        "child_frame_id": {"type": "string"},
                        "translation": xyz_schema(),
                        "rotation": quat_schema()
                    },
                    "required": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"]
                }
            }
        },
        "required": ["transforms"]
    })
}

/// JSON schema of `foxglove.SceneUpdate`, with the primitives Regolith writes (cubes, spheres,
/// cylinders and cones, triangle lists) spelled out; the other primitive lists are present
/// and empty.
pub fn scene_update_schema() -> Value {
    let sized = |title: &str| {
        json!({
            "title": title,
            "type": "object",
            "properties": {"pose": pose_schema(), "size": xyz_schema(), "color": color_schema()},
            "required": ["pose", "size", "color"]
        })
    };
    let cylinder = json!({
        "title": "foxglove.CylinderPrimitive",
        "type": "object",
        "properties": {
            "pose": pose_schema(),
            "size": xyz_schema(),
            "bottom_scale": {"type": "number"},
            "top_scale": {"type": "number"},
            "color": color_schema()
        },
        "required": ["pose", "size", "bottom_scale", "top_scale", "color"]
    });
    let triangles = json!({
        "title": "foxglove.TriangleListPrimitive",
        "type": "object",
        "properties": {
            "pose": pose_schema(),
            "points": {"type": "array", "items": xyz_schema()},
            "color": color_schema(),
            "colors": {"type": "array", "items": color_schema()},
            "indices": {"type": "array", "items": {"type": "integer", "minimum": 0}}
        },
        "required": ["pose", "points", "color", "colors", "indices"]
    });
    let empty = json!({"type": "array", "maxItems": 0});
    json!({
        "title": "foxglove.SceneUpdate",
        "description": "An update to the entities displayed in a 3D scene",
        "type": "object",
        "properties": {
            "deletions": {
                "type": "array",
                "items": {
                    "title": "foxglove.SceneEntityDeletion",
                    "type": "object",
                    "properties": {
                        "timestamp": time_schema(),
                        "type": {"type": "integer", "enum": [0, 1]},
                        "id": {"type": "string"}
                    },
                    "required": ["timestamp", "type", "id"]
                }
            },
            "entities": {
                "type": "array",
                "items": {
                    "title": "foxglove.SceneEntity",
                    "type": "object",
                    "properties": {
                        "timestamp": time_schema(),
                        "frame_id": {"type": "string"},
                        "id": {"type": "string"},
                        "lifetime": {
                            "type": "object",
                            "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer", "minimum": 0}},
                            "required": ["sec", "nsec"]
                        },
                        "frame_locked": {"type": "boolean"},
                        "metadata": {
                            "type": "array",
                            "items": {
                                "type": "object",
                                "properties": {"key": {"type": "string"}, "value": {"type": "string"}},
                                "required": ["key", "value"]
                            }
                        },
                        "arrows": empty,
                        "cubes": {"type": "array", "items": sized("foxglove.CubePrimitive")},
                        "spheres": {"type": "array", "items": sized("foxglove.SpherePrimitive")},
                        "cylinders": {"type": "array", "items": cylinder},
                        "lines": empty,
                        "triangles": {"type": "array", "items": triangles},
                        "texts": empty,
                        "models": empty
                    },
                    "required": [
                        "timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata", "arrows", "cubes",
                        "spheres", "cylinders", "lines", "triangles", "texts", "models"
                    ]
                }
            }
        },
        "required": ["deletions", "entities"]
    })
}

/// JSON schema of `/bodies/wrench` (Regolith's own): the soil's force and torque on each body.
pub fn wrench_schema() -> Value {
    json!({
        "title": "regolith.BodyWrenches",
        "description": "Soil force (N) and torque about the centre of mass (N m) on each FSI body, world frame, averaged over the last exchange interval",
        "type": "object",
        "properties": {
            "timestamp": time_schema(),
            "bodies": {
                "type": "array",
                "items": {
                    "type": "object",
                    "properties": {"name": {"type": "string"}, "force": xyz_schema(), "torque": xyz_schema()},
                    "required": ["name", "force", "torque"]
                }
            }
        },
        "required": ["timestamp", "bodies"]
    })
}

/// JSON schema of a topic of named numbers (`/rig/<type>`, `/vehicles/<name>`): a timestamp,
/// the run label (a wheel's slip, a plate's width; null for a single run) and one number per
/// quantity (null where undefined, e.g. the slip of a wheel that does not turn).
pub fn values_schema(title: &str, fields: &[&str]) -> Value {
    let mut props = serde_json::Map::new();
    props.insert("timestamp".into(), time_schema());
    props.insert("run".into(), json!({"type": ["number", "null"]}));
    for f in fields {
        props.insert((*f).into(), json!({"type": ["number", "null"]}));
    }
    let mut required = vec!["timestamp".to_string(), "run".to_string()];
    required.extend(fields.iter().map(|f| f.to_string()));
    json!({
        "title": title,
        "description": "Named quantities in SI units (angles in degrees), one message per recorded frame",
        "type": "object",
        "properties": props,
        "required": required
    })
}

/// `{sec, nsec}` of a time in seconds (≥ 0).
pub fn time(t: f64) -> Value {
    let ns = nanos(t);
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

/// A time in seconds as whole nanoseconds (MCAP log time).
pub fn nanos(t: f64) -> u64 {
    (t.max(0.0) * 1e9).round() as u64
}

/// `{x, y, z}`.
pub fn xyz(v: [f64; 3]) -> Value {
    json!({"x": v[0], "y": v[1], "z": v[2]})
}

fn pose(p: &Pose) -> Value {
    let q = p.rotation;
    json!({"position": xyz(p.translation), "orientation": {"x": q[0], "y": q[1], "z": q[2], "w": q[3]}})
}

/// A `foxglove.PointCloud` in `frame_id` (world) from packed point data.
pub fn point_cloud(t: f64, frame_id: &str, data: &[u8]) -> Value {
    let fields: Vec<Value> = POINT_FIELDS
        .iter()
        .enumerate()
        .map(|(k, (name, ty))| json!({"name": name, "offset": 4 * k, "type": ty}))
        .collect();
    json!({
        "timestamp": time(t),
        "frame_id": frame_id,
        "pose": pose(&Pose::default()),
        "point_stride": POINT_STRIDE,
        "fields": fields,
        "data": base64::engine::general_purpose::STANDARD.encode(data),
    })
}

/// A `foxglove.FrameTransforms` with each `(child, pose)` under `world`, and each
/// `(parent, child, pose)` of `under` under its parent frame (a URDF link lumped into the body
/// that carries it).
pub fn frame_transforms(t: f64, frames: &[(String, Pose)], under: &[(String, String, Pose)]) -> Value {
    let transform = |parent: &str, child: &str, p: &Pose| {
        let q = p.rotation;
        json!({
            "timestamp": time(t),
            "parent_frame_id": parent,
            "child_frame_id": child,
            "translation": xyz(p.translation),
            "rotation": {"x": q[0], "y": q[1], "z": q[2], "w": q[3]},
        })
    };
    let transforms: Vec<Value> = frames
        .iter()
        .map(|(child, p)| transform("world", child, p))
        .chain(under.iter().map(|(parent, child, p)| transform(parent, child, p)))
        .collect();
    json!({ "transforms": transforms })
}

#[derive(Default)]
struct Primitives {
    cubes: Vec<Value>,
    spheres: Vec<Value>,
    cylinders: Vec<Value>,
    triangles: Vec<Value>,
}

const BODY_COLOR: [f64; 4] = [0.72, 0.74, 0.78, 1.0];

fn color() -> Value {
    let [r, g, b, a] = BODY_COLOR;
    json!({"r": r, "g": g, "b": b, "a": a})
}

/// Rotation taking the cylinder primitive's z axis onto `axis`.
fn axis_pose(at: &Pose, axis: Axis) -> Pose {
    let local = match axis {
        Axis::X => Pose::from_rpy_deg([0.0; 3], [0.0, 90.0, 0.0]),
        Axis::Y => Pose::from_rpy_deg([0.0; 3], [-90.0, 0.0, 0.0]),
        Axis::Z => Pose::default(),
    };
    at.compose(&local)
}

fn add_shape(out: &mut Primitives, at: &Pose, shape: &ShapeDesc) {
    let cylinder = |at: &Pose, d: f64, len: f64, bottom: f64, top: f64| {
        json!({
            "pose": pose(at), "size": xyz([d, d, len]), "bottom_scale": bottom, "top_scale": top, "color": color()
        })
    };
    match shape {
        ShapeDesc::Box { size } => out.cubes.push(json!({"pose": pose(at), "size": xyz(*size), "color": color()})),
        ShapeDesc::Sphere { radius } => {
            let d = 2.0 * radius;
            out.spheres.push(json!({"pose": pose(at), "size": xyz([d, d, d]), "color": color()}));
        }
        ShapeDesc::Cylinder { radius, length, axis } => {
            out.cylinders.push(cylinder(&axis_pose(at, *axis), 2.0 * radius, *length, 1.0, 1.0))
        }
        // Apex down: the bottom face shrinks to a point.
        ShapeDesc::Cone { radius, height } => out.cylinders.push(cylinder(at, 2.0 * radius, *height, 0.0, 1.0)),
        ShapeDesc::Wheel { radius, width, grousers } => {
            out.cylinders.push(cylinder(&axis_pose(at, Axis::Y), 2.0 * radius, *width, 1.0, 1.0));
            if let Some(g) = grousers {
                for p in g.plate_poses(*radius) {
                    let size = [g.thickness, *width, g.height];
                    out.cubes.push(json!({"pose": pose(&at.compose(&p)), "size": xyz(size), "color": color()}));
                }
            }
        }
        ShapeDesc::Mesh { vertices, indices } => out.triangles.push(json!({
            "pose": pose(at),
            "points": vertices.iter().map(|v| xyz(*v)).collect::<Vec<_>>(),
            "color": color(),
            "colors": [],
            "indices": indices.iter().flatten().collect::<Vec<_>>(),
        })),
        ShapeDesc::Compound(parts) => {
            for (p, s) in parts {
                add_shape(out, &at.compose(p), s);
            }
        }
    }
}

/// A `foxglove.SceneUpdate` with one entity per `(frame, shape)`, drawn in that frame
/// (frame-locked, so it follows the frame's transforms), never expiring.
pub fn scene_update(t: f64, shapes: &[(String, ShapeDesc)]) -> Value {
    let entities: Vec<Value> = shapes
        .iter()
        .map(|(frame, shape)| {
            let mut prims = Primitives::default();
            add_shape(&mut prims, &Pose::default(), shape);
            json!({
                "timestamp": time(t),
                "frame_id": frame,
                "id": frame,
                "lifetime": {"sec": 0, "nsec": 0},
                "frame_locked": true,
                "metadata": [],
                "arrows": [],
                "cubes": prims.cubes,
                "spheres": prims.spheres,
                "cylinders": prims.cylinders,
                "lines": [],
                "triangles": prims.triangles,
                "texts": [],
                "models": [],
            })
        })
        .collect();
    json!({"deletions": [], "entities": entities})
}
