//! Material files: TOML with the keys of [`MaterialParams`], SI units, angles in degrees.
//!
//! ```toml
//! model = "mcc"
//! density = 1700.0          # kg/m³
//! youngs_modulus = 2.0e7    # Pa
//! poisson_ratio = 0.3
//! mcc_m = 1.2               # or friction_angle = 30.0
//! mcc_kappa = 0.02          # or mcc_cr (κ = Cr / ln 10)
//! mcc_lambda = 0.10         # or mcc_cc (λ = Cc / ln 10)
//! mcc_v_lambda = 2.2        # specific volume on the NCL at 1 kPa
//! ocr = 2.0
//! ```

use std::path::Path;

use regolith_fsi::Real;
use regolith_fsi::rheology::{Material, MaterialParams};

use crate::input::{InputError, parse_toml, read_text};

/// Reads and checks a material file.
pub fn load_material_file(path: &Path) -> Result<MaterialParams, InputError> {
    let source = read_text(path)?;
    let params: MaterialParams = parse_toml(path, &source)?;
    if params.file.is_some() {
        return Err(InputError::key(path, "file", "is only allowed in a scene's [[materials]] entry").located(&source));
    }
    build_material::<f64>(&params, path, "", &source)?;
    Ok(params)
}

/// Builds a material, reporting a broken rule against `file` with the key prefixed by
/// `prefix` (e.g. `materials[2].`).
pub fn build_material<T: Real>(
    params: &MaterialParams,
    file: &Path,
    prefix: &str,
    source: &str,
) -> Result<Material<T>, InputError> {
    params.build::<T>().map_err(|e| InputError::key(file, format!("{prefix}{}", e.key), e.message).located(source))
}
