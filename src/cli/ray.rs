//! Starting the Python package's Ray runners (`regolith.sweep` for `regolith sweep`,
//! `regolith.batch` for the studies and calibrations whose runs are independent): the
//! interpreter, the flags both refuse, and the process they run in.

use std::process::ExitStatus;

use super::Failure;
use crate::input::InputError;

/// The Python interpreter the Ray runners are started with: `REGOLITH_PYTHON`, else `python3`.
pub const PYTHON_ENV: &str = "REGOLITH_PYTHON";

/// Refuses `--jobs` on the Ray runner and CPU / GPU counts that are not numbers > 0 (≥ 0 GPUs).
pub(super) fn check_ray_flags(
    jobs: Option<usize>,
    num_cpus: Option<f64>,
    num_gpus: Option<f64>,
) -> Result<(), Failure> {
    if jobs.is_some() {
        return Err(InputError::flag("--jobs", "applies to --runner threads only (Ray takes --num-cpus)").into());
    }
    for (flag, v) in [("--num-cpus", num_cpus), ("--num-gpus", num_gpus)] {
        if v.is_some_and(|x| !(x.is_finite() && x >= 0.0) || (flag == "--num-cpus" && x == 0.0)) {
            return Err(InputError::flag(flag, "must be a number > 0 (--num-gpus: >= 0)").into());
        }
    }
    Ok(())
}

/// Runs `main(args)` of the Python module `regolith.<module>` in the interpreter of
/// [`PYTHON_ENV`] and waits for it. A missing package or Ray is the module's one-line error
/// (exit 2); an interpreter that cannot start is a `--runner` error here. Returns the
/// interpreter's name (for messages) and its exit status.
pub(super) fn run_module(module: &str, args: &[String]) -> Result<(String, ExitStatus), Failure> {
    let python = std::env::var(PYTHON_ENV).unwrap_or_else(|_| "python3".into());
    let hint = "install the Python package and Ray: pip install ./python ray; or pass --runner threads";
    let script = [
        "import sys".to_string(),
        "try:".into(),
        format!("    import regolith.{module} as m"),
        "except ImportError as e:".into(),
        format!("    print('error: --runner ray: ' + str(e) + ' ({hint})', file=sys.stderr)"),
        "    sys.exit(2)".into(),
        "sys.exit(m.main(sys.argv[1:]))".into(),
    ]
    .join("\n");
    let status = std::process::Command::new(&python).arg("-c").arg(script).args(args).status().map_err(|e| {
        InputError::flag(
            "--runner",
            format!("ray: cannot start {python} ({e}); set {PYTHON_ENV} to a Python with the regolith package and ray, or pass --runner threads"),
        )
    })?;
    Ok((python, status))
}
