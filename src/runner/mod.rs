//! The runner every batch of independent runs shares — a sweep's points, the accuracy study's
//! points, the stability suite's cases, a triaxial envelope's tests, a plate calibration's
//! sizes: [`Task`]s run on threads ([`run_tasks`]) or, through the Python package, as Ray
//! tasks; one [`Record`] per finished run in the batch's `results.jsonl`, so a
//! batch resumes and records a failed run while the others go on. It comes before the
//! studies and calibrations that use it, and knows nothing of scenes.

mod records;
mod task;

pub use records::{Record, Shard, append, read_all, results_file};
pub use task::{Outcome, Task, eta_text, fnv_id, forget, pending, run_tasks};

/// A TOML value as JSON.
pub fn toml_to_json(v: &toml::Value) -> serde_json::Value {
    match v {
        toml::Value::String(s) => s.clone().into(),
        toml::Value::Integer(i) => (*i).into(),
        toml::Value::Float(f) => serde_json::Number::from_f64(*f).map_or(serde_json::Value::Null, Into::into),
        toml::Value::Boolean(b) => (*b).into(),
        toml::Value::Datetime(d) => d.to_string().into(),
        toml::Value::Array(a) => a.iter().map(toml_to_json).collect::<Vec<_>>().into(),
        toml::Value::Table(t) => {
            t.iter().map(|(k, v)| (k.clone(), toml_to_json(v))).collect::<serde_json::Map<_, _>>().into()
        }
    }
}
