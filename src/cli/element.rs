//! `regolith element`.

use std::path::PathBuf;

use anyhow::Context;
use regolith_fsi::Real;

use super::{Failure, Precision, TestArg};
use crate::element::{Control, ElementError, ElementSpec, ElementTest, run_element};
use crate::input::InputError;
use crate::material::{build_material, load_material_file};
use crate::output::element_plot::element_figure;
use crate::output::write_figure;

pub(super) struct Args {
    pub material: PathBuf,
    pub test: TestArg,
    pub p0: f64,
    pub ocr: Option<f64>,
    pub axial_strain: Option<f64>,
    pub p_end: Option<f64>,
    pub p_unload: Option<f64>,
    pub steps: usize,
    pub precision: Precision,
    pub out: PathBuf,
}

pub(super) fn run(a: Args) -> Result<(), Failure> {
    let test = match a.test {
        TestArg::Isotropic => ElementTest::Isotropic,
        TestArg::DrainedTriaxial => ElementTest::DrainedTriaxial,
        TestArg::UndrainedTriaxial => ElementTest::UndrainedTriaxial,
        TestArg::Oedometer => ElementTest::Oedometer,
    };
    let control = match (a.axial_strain, a.p_end) {
        (Some(e), None) => Control::AxialStrain(e),
        (None, Some(end)) => Control::Pressure { end, unload: a.p_unload },
        _ => {
            let need = if test == ElementTest::Isotropic { "--p-end" } else { "--axial-strain" };
            return Err(InputError::flag(need, format!("is required for a {} test", test.name())).into());
        }
    };
    let spec = ElementSpec { test, p0: a.p0, ocr: a.ocr, control, steps: a.steps };
    let params = load_material_file(&a.material)?;
    match a.precision {
        Precision::F64 => go::<f64>(&a, &params, &spec),
        Precision::F32 => go::<f32>(&a, &params, &spec),
    }
}

fn go<T: Real>(a: &Args, params: &regolith_fsi::rheology::MaterialParams, spec: &ElementSpec) -> Result<(), Failure> {
    let material = build_material::<T>(params, &a.material, "", "")?;
    let path = run_element(&material, spec).map_err(|e| match e {
        ElementError::Spec { flag, message } => Failure::Input(InputError::flag(flag, message)),
        other => Failure::Run(anyhow::Error::new(other).context("element test failed")),
    })?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("cannot create {}", a.out.display()))?;
    let json = a.out.join("element.json");
    let text = serde_json::to_string_pretty(&path).context("serialising element.json")?;
    std::fs::write(&json, text).with_context(|| format!("cannot write {}", json.display()))?;
    let plots = write_figure(&element_figure(&path, &material), &a.out, "element").map_err(anyhow::Error::new)?;
    let f = &path.final_state;
    println!(
        "{} on {} ({}): final p = {:.4e} Pa, q = {:.4e} Pa{}, v = {:.5}, eps_axial = {:.4}, eps_vol = {:.4}",
        path.test,
        path.model,
        path.precision,
        f.p,
        f.q,
        f.pc.map(|pc| format!(", pc = {pc:.4e} Pa")).unwrap_or_default(),
        f.v,
        f.eps_axial,
        f.eps_vol
    );
    if let (Some(p), Some(q)) = (path.expected.critical_state_p, path.expected.critical_state_q) {
        println!("  critical state (closed form): p = {p:.4e} Pa, q = {q:.4e} Pa");
    }
    if let Some(q) = path.expected.failure_q {
        println!("  Mohr–Coulomb failure (closed form): q = {q:.4e} Pa");
    }
    println!(
        "  wrote {}, {}",
        json.display(),
        plots.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}
