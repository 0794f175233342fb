//! A triangle mesh (m) and the error of a mesh file that cannot be used: what every mesh
//! reader returns (`mesh_io.rs` for STL and OBJ, `dae.rs` for COLLADA).

use std::path::{Path, PathBuf};

/// A mesh file could not be used.
#[derive(Debug, thiserror::Error)]
#[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct MeshError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line, for text formats.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

/// A triangle mesh (m).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertices.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles.
    pub indices: Vec<[u32; 3]>,
}

/// A [`MeshError`] for `path` (at `line`, for text formats).
pub(crate) fn err(path: &Path, line: Option<usize>, message: impl Into<String>) -> MeshError {
    MeshError { path: path.to_path_buf(), line, message: message.into() }
}
