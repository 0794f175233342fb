//! `regolith inspect recording.mcap`: topics, schemas, message counts and time range.

use std::path::Path;

use super::Failure;
use crate::input::InputError;
use crate::output::record::topics;

pub(super) fn run(path: &Path) -> Result<(), Failure> {
    let bytes = std::fs::read(path).map_err(|e| InputError::file(path, format!("cannot read: {e}")))?;
    let not_mcap = |m: String| InputError::file(path, format!("not a readable MCAP recording: {m}"));
    let summary = mcap::Summary::read(&bytes).map_err(|e| not_mcap(e.to_string()))?;
    let list = topics(&bytes).map_err(not_mcap)?;
    let total: u64 = list.iter().map(|t| t.messages).sum();
    let start = list.iter().filter_map(|t| t.range.map(|r| r.0)).reduce(f64::min);
    let end = list.iter().filter_map(|t| t.range.map(|r| r.1)).reduce(f64::max);
    println!("{}", path.display());
    match (start, end) {
        (Some(a), Some(b)) => println!("  {total} messages, t = {a:.4} .. {b:.4} s ({:.4} s)", b - a),
        _ => println!("  no messages"),
    }
    println!(
        "  {}",
        if summary.is_some() { "summary section: present" } else { "summary section: missing (unfinished file?)" }
    );
    let width = list.iter().map(|t| t.topic.len()).max().unwrap_or(5).max(5);
    println!("  {:width$}  {:>8}  {:>10}  {:>10}  schema", "topic", "messages", "first (s)", "last (s)");
    for t in &list {
        let (a, b) = t.range.unwrap_or((0.0, 0.0));
        println!("  {:width$}  {:>8}  {:>10.4}  {:>10.4}  {} ({})", t.topic, t.messages, a, b, t.schema, t.encoding);
    }
    Ok(())
}
