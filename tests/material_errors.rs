//! Every material rule has a test asserting the exact one-line error (file, line, key, what is
//! allowed).

use std::path::PathBuf;

use regolith::material::load_material_file;

const MCC: &str = "model = \"mcc\"
density = 1700.0
youngs_modulus = 2.0e7
poisson_ratio = 0.3
mcc_m = 1.2
mcc_kappa = 0.02
mcc_lambda = 0.1
mcc_v_lambda = 2.2
ocr = 2.0
";

const DP: &str = "model = \"drucker-prager\"
density = 1600.0
youngs_modulus = 2.0e7
poisson_ratio = 0.3
friction_angle = 32.0
cohesion = 500.0
";

fn write(name: &str, text: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("material_errors");
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).expect("write");
    p
}

/// Applies edits `(key, Some(new line))` (replace in place, or append when absent) and
/// `(key, None)` (delete), then returns the file and its error text.
fn error_with(base: &str, name: &str, edits: &[(&str, Option<&str>)]) -> (PathBuf, String) {
    let mut out: Vec<String> = base.lines().map(str::to_string).collect();
    for (key, line) in edits {
        let pos = out.iter().position(|l| l.split('=').next().map(str::trim) == Some(*key));
        match (pos, line) {
            (Some(i), Some(new)) => out[i] = new.to_string(),
            (Some(i), None) => {
                out.remove(i);
            }
            (None, Some(new)) => out.push(new.to_string()),
            (None, None) => {}
        }
    }
    let p = write(name, &(out.join("\n") + "\n"));
    let e = load_material_file(&p).expect_err("must be rejected").to_string();
    (p, e)
}

macro_rules! case {
    ($name:ident, $base:expr, $edits:expr, $expected:expr) => {
        #[test]
        fn $name() {
            let (p, e) = error_with($base, stringify!($name), &$edits);
            assert_eq!(e, format!($expected, p.display()));
        }
    };
}

#[test]
fn valid_files_load() {
    load_material_file(&write("ok_mcc", MCC)).expect("mcc ok");
    load_material_file(&write("ok_dp", DP)).expect("dp ok");
    load_material_file(&write(
        "ok_elastic",
        "model = \"elastic\"\ndensity = 2000.0\nyoungs_modulus = 1e7\npoisson_ratio = 0.25\n",
    ))
    .expect("elastic ok");
}

#[test]
fn missing_file() {
    let p = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("does-not-exist.toml");
    let e = load_material_file(&p).expect_err("missing").to_string();
    assert!(e.starts_with(&format!("{}: cannot read:", p.display())), "{e}");
}

case!(
    malformed_toml,
    MCC,
    [("density", Some("density = 1700.0.0"))],
    "{}:2: key `density`: invalid float, expected nothing"
);
case!(
    wrong_type,
    MCC,
    [("density", Some("density = \"heavy\""))],
    "{}:2: key `density`: invalid type: string \"heavy\", expected f64"
);
case!(
    unknown_key,
    MCC,
    [("densty", Some("densty = 1700.0"))],
    "{}:10: key `densty`: unknown field `densty`, expected one of `name`, `file`, `model`, `density`, `youngs_modulus`, `poisson_ratio`, `friction_angle`, `cohesion`, `mu_i_friction_angle`, `mu_i_i0`, `grain_diameter`, `grain_density`, `permeability`, `sound_speed`, `viscosity`, `mcc_m`, `mcc_kappa`, `mcc_lambda`, `mcc_cr`, `mcc_cc`, `mcc_v_lambda`, `ocr`, `mcc_clamp_moduli`, `mcc_pc_floor` (unknown keys are errors so that nothing is silently ignored)"
);
case!(
    unknown_model,
    MCC,
    [("model", Some("model = \"cam-clay\""))],
    "{}:1: key `model`: unknown variant `cam-clay`, expected one of `elastic`, `drucker-prager`, `mcc`, `water`"
);
case!(
    missing_model,
    MCC,
    [("model", None)],
    "{}: key `model`: is required: one of \"elastic\", \"drucker-prager\", \"mcc\", \"water\""
);
case!(
    density_not_positive,
    MCC,
    [("density", Some("density = 0.0"))],
    "{}:2: key `density`: must be > 0 kg/m³ (got 0)"
);
case!(density_missing, MCC, [("density", None)], "{}: key `density`: is required for model \"mcc\"");
case!(
    young_not_positive,
    MCC,
    [("youngs_modulus", Some("youngs_modulus = -1.0"))],
    "{}:3: key `youngs_modulus`: must be > 0 Pa (got -1)"
);
case!(
    poisson_half,
    MCC,
    [("poisson_ratio", Some("poisson_ratio = 0.5"))],
    "{}:4: key `poisson_ratio`: must satisfy 0 < ν < 0.5 (got 0.5)"
);
case!(
    poisson_zero,
    MCC,
    [("poisson_ratio", Some("poisson_ratio = 0.0"))],
    "{}:4: key `poisson_ratio`: must satisfy 0 < ν < 0.5 (got 0)"
);
case!(kappa_not_positive, MCC, [("mcc_kappa", Some("mcc_kappa = 0.0"))], "{}:6: key `mcc_kappa`: must be > 0 (got 0)");
case!(
    kappa_lambda_swapped,
    MCC,
    [("mcc_kappa", Some("mcc_kappa = 0.1")), ("mcc_lambda", Some("mcc_lambda = 0.02"))],
    "{}:7: key `mcc_lambda`: λ = 0.02 is smaller than κ = 0.1: they look swapped. κ (mcc_kappa) is the swelling slope, λ (mcc_lambda) the steeper normal compression slope; MCC needs λ > κ"
);
case!(
    lambda_equal_kappa,
    MCC,
    [("mcc_lambda", Some("mcc_lambda = 0.02"))],
    "{}:7: key `mcc_lambda`: must be greater than κ (both are 0.02): the hardening law divides by λ − κ"
);
case!(m_not_positive, MCC, [("mcc_m", Some("mcc_m = 0.0"))], "{}:5: key `mcc_m`: must satisfy 0 < M < 3 (got 0)");
case!(m_missing, MCC, [("mcc_m", None)], "{}: key `mcc_m`: is required for model \"mcc\" (or give friction_angle)");
case!(
    m_and_angle,
    MCC,
    [("friction_angle", Some("friction_angle = 30.0"))],
    "{}:5: key `mcc_m`: and friction_angle are both given: give one (M = 6 sinφ / (3 − sinφ))"
);
case!(
    kappa_and_cr,
    MCC,
    [("mcc_cr", Some("mcc_cr = 0.05"))],
    "{}:6: key `mcc_kappa`: and mcc_cr are both given: give one (κ = Cr / ln 10)"
);
case!(
    v_lambda_not_above_one,
    MCC,
    [("mcc_v_lambda", Some("mcc_v_lambda = 1.0"))],
    "{}:8: key `mcc_v_lambda`: must be > 1: it is a specific volume 1 + e (got 1)"
);
case!(
    ocr_below_one,
    MCC,
    [("ocr", Some("ocr = 0.5"))],
    "{}:9: key `ocr`: must be ≥ 1 (got 0.5); OCR < 1 puts the start outside the yield surface"
);
case!(
    pc_floor_negative,
    MCC,
    [("mcc_pc_floor", Some("mcc_pc_floor = -5.0"))],
    "{}:10: key `mcc_pc_floor`: must be ≥ 0 Pa (got -5); 0 turns the floor off"
);
case!(
    cohesion_on_mcc,
    MCC,
    [("cohesion", Some("cohesion = 10.0"))],
    "{}:10: key `cohesion`: does not apply to model \"mcc\" (Modified Cam Clay is cohesionless here)"
);
case!(
    angle_out_of_range,
    DP,
    [("friction_angle", Some("friction_angle = 95.0"))],
    "{}:5: key `friction_angle`: must be in [0, 90) degrees (got 95)"
);
case!(
    dp_without_angle,
    DP,
    [("friction_angle", None)],
    "{}: key `friction_angle`: is required for model \"drucker-prager\""
);
case!(
    dp_without_strength,
    DP,
    [("friction_angle", Some("friction_angle = 0.0")), ("cohesion", Some("cohesion = 0.0"))],
    "{}:5: key `friction_angle`: and cohesion are both zero: the soil would have no strength; give φ > 0 or c > 0"
);
case!(cohesion_negative, DP, [("cohesion", Some("cohesion = -1.0"))], "{}:6: key `cohesion`: must be ≥ 0 Pa (got -1)");
case!(
    mcc_key_on_dp,
    DP,
    [("mcc_kappa", Some("mcc_kappa = 0.02"))],
    "{}:7: key `mcc_kappa`: does not apply to model \"drucker-prager\" (it is a Modified Cam Clay key; set model = \"mcc\")"
);
case!(
    mu_i_incomplete,
    DP,
    [("mu_i_friction_angle", Some("mu_i_friction_angle = 40.0"))],
    "{}: key `mu_i_i0`: is required when any μ(I) key is given (mu_i_friction_angle, mu_i_i0, grain_diameter, grain_density)"
);
case!(
    mu_i_below_static,
    DP,
    [
        ("mu_i_friction_angle", Some("mu_i_friction_angle = 20.0")),
        ("mu_i_i0", Some("mu_i_i0 = 0.3")),
        ("grain_diameter", Some("grain_diameter = 0.001")),
        ("grain_density", Some("grain_density = 2600.0"))
    ],
    "{}:7: key `mu_i_friction_angle`: must be in [friction_angle = 32, 90) degrees (got 20)"
);
case!(
    file_key_in_material_file,
    DP,
    [("file", Some("file = \"other.toml\""))],
    "{}:7: key `file`: is only allowed in a scene's [[materials]] entry"
);

const WATER: &str = "model = \"water\"
density = 1000.0
sound_speed = 50.0
viscosity = 1e-3
";

#[test]
fn water_and_wet_soils_load() {
    load_material_file(&write("ok_water", WATER)).expect("water ok");
    load_material_file(&write("ok_wet", &format!("{DP}permeability = 1e-4\ngrain_density = 2650.0\n")))
        .expect("wet soil ok");
}

case!(
    water_soil_key,
    WATER,
    [("youngs_modulus", Some("youngs_modulus = 1e7"))],
    "{}:5: key `youngs_modulus`: does not apply to model \"water\" (it is a soil key; give it to the soil the water flows through)"
);
case!(
    water_sound_speed_missing,
    WATER,
    [("sound_speed", None)],
    "{}: key `sound_speed`: is required for model \"water\""
);
case!(
    water_viscosity_negative,
    WATER,
    [("viscosity", Some("viscosity = -1.0"))],
    "{}:4: key `viscosity`: must be ≥ 0 Pa s (water at 20 °C: 1.0e-3; got -1)"
);
case!(
    soil_sound_speed,
    DP,
    [("sound_speed", Some("sound_speed = 50.0"))],
    "{}:7: key `sound_speed`: does not apply to model \"drucker-prager\" (it is a water key; set model = \"water\")"
);
case!(
    permeability_without_grain_density,
    DP,
    [("permeability", Some("permeability = 1e-4"))],
    "{}: key `grain_density`: is required with permeability: the porosity is 1 − density / grain_density (quartz sand: 2650 kg/m³)"
);
case!(
    grain_density_below_bulk,
    DP,
    [("permeability", Some("permeability = 1e-4")), ("grain_density", Some("grain_density = 1500.0"))],
    "{}:8: key `grain_density`: must exceed the bulk density 1600 kg/m³ (porosity 1 − density / grain_density > 0; got 1500)"
);
case!(
    permeability_zero,
    DP,
    [("permeability", Some("permeability = 0.0")), ("grain_density", Some("grain_density = 2650.0"))],
    "{}:7: key `permeability`: must be > 0 m/s (got 0)"
);
case!(
    grain_density_alone,
    DP,
    [("grain_density", Some("grain_density = 2650.0"))],
    "{}:7: key `grain_density`: applies with permeability (a soil water flows through) or with the μ(I) keys; give one or drop it"
);
