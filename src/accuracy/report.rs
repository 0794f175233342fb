//! The study's tables and plots: `accuracy.csv` (one row per point), `accuracy.json`,
//! `accuracy.md` (per case the order, the Pareto front and the cheapest point within 10, 5 and
//! 2 %, then a recommendation table) and per case a convergence plot and an error-against-time
//! plot with the Pareto front.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::analysis::{CaseResult, Row, TOLERANCES};
use crate::output::plot::{Figure, Panel, Series};
use crate::output::write_figure;
use crate::study::StudyError;

/// The columns of `accuracy.csv`.
pub const CSV_COLUMNS: [&str; 14] = [
    "case",
    "knob",
    "setting",
    "measured",
    "reference",
    "reference_kind",
    "error",
    "rel_error",
    "wall_s",
    "particle_steps",
    "steps",
    "peak_mem_bytes",
    "machine",
    "command",
];

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

/// `accuracy.csv`.
pub fn csv(results: &[CaseResult]) -> String {
    let mut t = CSV_COLUMNS.join(",");
    t.push('\n');
    for r in results.iter().flat_map(|c| &c.rows) {
        let cells = [
            r.case.clone(),
            r.knob.clone(),
            r.setting.clone(),
            r.measured.to_string(),
            r.reference.to_string(),
            r.reference_kind.clone(),
            r.error.to_string(),
            r.rel_error.to_string(),
            r.wall_s.to_string(),
            r.particle_steps.to_string(),
            r.steps.to_string(),
            r.peak_mem_bytes.map(|b| b.to_string()).unwrap_or_default(),
            r.machine.clone(),
            r.command.clone(),
        ];
        t.push_str(&cells.iter().map(|c| quote(c)).collect::<Vec<_>>().join(","));
        t.push('\n');
    }
    t
}

fn pct(x: f64) -> String {
    if x.is_finite() { format!("{:+.2} %", 100.0 * x) } else { "–".into() }
}

fn g(x: f64) -> String {
    if !x.is_finite() {
        "–".into()
    } else if x != 0.0 && (x.abs() >= 1e5 || x.abs() < 1e-3) {
        format!("{x:.3e}")
    } else {
        format!("{x:.4}")
    }
}

fn mib(b: Option<u64>) -> String {
    b.map_or("–".into(), |b| format!("{:.0}", b as f64 / (1024.0 * 1024.0)))
}

fn setting(r: &Row) -> String {
    if r.knob == "d0" { format!("d0 = {}", r.setting) } else { format!("{} = {} (d0 = {})", r.knob, r.setting, r.d0) }
}

/// `accuracy.md`.
pub fn markdown(results: &[CaseResult], budget: &str, machine: &str, command: &str) -> String {
    let mut m = String::new();
    let _ = writeln!(m, "# Accuracy and its cost\n");
    let _ = writeln!(m, "Budget `{budget}`, measured on {machine}. Reproduce with `{command}`.\n");
    let _ = writeln!(
        m,
        "Each case is a scene of `examples/study/` run over a resolution ladder (d0) and, at the \
         baseline d0, with one knob turned at a time. The error is measured − reference; the \
         relative error divides by |reference|. Wall time is the whole point (loading and writing \
         included), on the machine above. The order is the least-squares slope of ln|error| on \
         ln d0 against an external reference, or Richardson's observed order for a \
         self-convergence case (whose reference is the extrapolated limit). Each row's command \
         in `accuracy.csv` runs that point by hand.\n"
    );
    let _ = writeln!(m, "## Recommendations\n");
    let _ = writeln!(m, "| case | quantity | reference | order | 10 % | 5 % | 2 % |");
    let _ = writeln!(m, "|---|---|---|---|---|---|---|");
    for c in results {
        let cell = |t: f64| -> String {
            match c.cheapest.iter().find(|(x, _)| *x == t).and_then(|(_, i)| *i) {
                Some(i) => {
                    let r = &c.rows[i];
                    format!("{} ({} s per simulated s)", setting(r), g(r.cost_per_sim_s()))
                }
                None => "not reached".into(),
            }
        };
        let _ = writeln!(
            m,
            "| {} | {} | {} | {} | {} | {} | {} |",
            c.case,
            c.quantity,
            c.reference_kind,
            g(c.order.order),
            cell(TOLERANCES[0]),
            cell(TOLERANCES[1]),
            cell(TOLERANCES[2])
        );
    }
    let _ = writeln!(
        m,
        "\nA cell names the cheapest point of the case whose |relative error| is within the \
         tolerance, and what it costs per simulated second here. \"not reached\": no point of \
         this budget got there (a finer ladder, or a model that cannot, see the case).\n"
    );
    for c in results {
        let _ = writeln!(m, "## {}\n", c.case);
        let _ = writeln!(m, "- Quantity: {}", c.quantity);
        let _ = writeln!(m, "- Reference ({}): {}", c.reference_kind, c.source);
        let _ = writeln!(m, "- Ladder over `{}`; knobs turned at d0 = {}", c.resolution, c.baseline);
        let _ = write!(
            m,
            "- Observed order ({}): {} (consecutive levels {} to {})",
            c.order.method,
            g(c.order.order),
            g(c.order.range.0),
            g(c.order.range.1)
        );
        if let Some(n) = &c.order.note {
            let _ = write!(m, "; {n}");
        }
        let _ = writeln!(m);
        if let Some(f) = &c.richardson {
            let _ = writeln!(m, "- Richardson limit {} (GCI band ±{})", g(f.limit), g(f.gci));
        }
        let front: Vec<String> = c.pareto.iter().map(|&i| setting(&c.rows[i])).collect();
        let _ = writeln!(
            m,
            "- Pareto front (cheapest first): {}",
            if front.is_empty() { "none".into() } else { front.join("; ") }
        );
        let _ = writeln!(m, "- Plots: `{0}_convergence.png`, `{0}_cost.png` (and .svg)\n", c.case);
        let _ = writeln!(
            m,
            "| knob | setting | d0 (m) | measured | reference | error | rel. error | wall (s) | s per sim. s | particle-steps | steps | peak MiB | Pareto |"
        );
        let _ = writeln!(m, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for (i, r) in c.rows.iter().enumerate() {
            let measured = match &r.failure {
                Some(f) => format!("FAILED: {f}"),
                None => g(r.measured),
            };
            let _ = writeln!(
                m,
                "| {} | {} | {} | {} | {} | {} | {} | {:.1} | {} | {:.3e} | {} | {} | {} |",
                r.knob,
                r.setting,
                r.d0,
                measured,
                g(r.reference),
                g(r.error),
                pct(r.rel_error),
                r.wall_s,
                g(r.cost_per_sim_s()),
                r.particle_steps,
                r.steps,
                mib(r.peak_mem_bytes),
                if c.pareto.contains(&i) { "●" } else { "" }
            );
        }
        let _ = writeln!(m);
    }
    m
}

/// The convergence plot (|relative error| against d0, log–log, with the fitted order) and the
/// cost plot (|relative error| against wall time, log–log, Pareto front joined) of a case.
pub fn write_plots(c: &CaseResult, dir: &Path) -> Result<Vec<PathBuf>, StudyError> {
    let ladder: Vec<(f64, f64)> = c
        .rows
        .iter()
        .filter(|r| r.knob == "d0" && r.usable() && r.rel_error != 0.0)
        .map(|r| (r.d0, r.rel_error.abs()))
        .collect();
    let mut conv = Panel {
        title: format!("{}: convergence", c.case),
        x_label: "d0 (m)".into(),
        y_label: "|relative error|".into(),
        x_log: true,
        y_log: true,
        series: vec![Series::points("ladder", ladder.clone())],
        ..Default::default()
    };
    if c.order.order.is_finite() && c.order.method == "error-slope" && !ladder.is_empty() {
        // The fitted line through the geometric mean of the points.
        let n = ladder.len() as f64;
        let (mx, my) =
            (ladder.iter().map(|p| p.0.ln()).sum::<f64>() / n, ladder.iter().map(|p| p.1.ln()).sum::<f64>() / n);
        let line = ladder.iter().map(|p| (p.0, (my + c.order.order * (p.0.ln() - mx)).exp())).collect();
        conv.series.push(Series::line(format!("fit: order {:.2}", c.order.order), line));
    }
    let all: Vec<(f64, f64)> =
        c.rows.iter().filter(|r| r.usable() && r.rel_error != 0.0).map(|r| (r.wall_s, r.rel_error.abs())).collect();
    let front: Vec<(f64, f64)> = c
        .pareto
        .iter()
        .map(|&i| &c.rows[i])
        .filter(|r| r.rel_error != 0.0)
        .map(|r| (r.wall_s, r.rel_error.abs()))
        .collect();
    let cost = Panel {
        title: format!("{}: error against cost", c.case),
        x_label: "wall time (s)".into(),
        y_label: "|relative error|".into(),
        x_log: true,
        y_log: true,
        series: vec![Series::points("points", all), Series::line("Pareto front", front)],
        ..Default::default()
    };
    let mut files = Vec::new();
    for (stem, fig) in [(format!("{}_convergence", c.case), conv), (format!("{}_cost", c.case), cost)]
        .map(|(s, p)| (s, Figure { panels: vec![p] }))
    {
        files.extend(write_figure(&fig, dir, &stem).map_err(|e| StudyError::output(&e.path.clone(), e))?);
    }
    Ok(files)
}
