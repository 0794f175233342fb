//! JSON files (`summary.json`, reports).

use std::path::Path;

use serde::Serialize;

use crate::driver::RunError;

/// Writes any serialisable value as pretty JSON.
pub fn write_json<S: Serialize>(path: &Path, value: &S) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| RunError::output(path, e))?;
    std::fs::write(path, text).map_err(|e| RunError::output(path, e))
}
