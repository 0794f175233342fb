//! User-input errors and TOML helpers shared by material files, scene files and the CLI.
//!
//! Every wrong input becomes one [`InputError`]: a single line naming the file (and line when
//! it can be found), the key, and what is allowed. The binary prints it and exits with code 2.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// A wrong user input: file, line, key, and what is allowed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputError {
    /// The file, if the input came from one.
    pub file: Option<PathBuf>,
    /// 1-based line in that file, when known.
    pub line: Option<usize>,
    /// Dotted key path (`sph.spacing`, `materials[1].mcc_kappa`) or CLI flag (`--p0`).
    pub key: Option<String>,
    /// What was wrong and what is allowed.
    pub message: String,
}

impl InputError {
    /// An error about a key of a file.
    pub fn key(file: &Path, key: impl Into<String>, message: impl Into<String>) -> Self {
        Self { file: Some(file.to_path_buf()), line: None, key: Some(key.into()), message: message.into() }
    }
    /// An error about a whole file.
    pub fn file(file: &Path, message: impl Into<String>) -> Self {
        Self { file: Some(file.to_path_buf()), line: None, key: None, message: message.into() }
    }
    /// An error about a command-line flag.
    pub fn flag(flag: &str, message: impl Into<String>) -> Self {
        Self { file: None, line: None, key: Some(flag.to_string()), message: message.into() }
    }
    /// Fills in the line from the file's source by looking the key up (best effort).
    pub fn located(mut self, source: &str) -> Self {
        if self.line.is_none()
            && let Some(k) = &self.key
        {
            self.line = locate_key(source, k);
        }
        self
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}", file.display())?;
            if let Some(line) = self.line {
                write!(f, ":{line}")?;
            }
            write!(f, ": ")?;
        }
        if let Some(k) = &self.key {
            if k.starts_with('-') {
                write!(f, "{k}: ")?;
            } else {
                write!(f, "key `{k}`: ")?;
            }
        }
        // One line, whatever the message: fold newlines that upstream messages may carry.
        let msg: String = self.message.split_whitespace().collect::<Vec<_>>().join(" ");
        write!(f, "{msg}")
    }
}

impl std::error::Error for InputError {}

/// Reads a file to a string, as an input error naming the file.
pub fn read_text(path: &Path) -> Result<String, InputError> {
    std::fs::read_to_string(path).map_err(|e| InputError::file(path, format!("cannot read: {e}")))
}

/// Parses TOML into `T` (which should use `deny_unknown_fields`), turning a syntax or schema
/// error into one line with the file, line and key.
pub fn parse_toml<T: DeserializeOwned>(path: &Path, source: &str) -> Result<T, InputError> {
    toml::from_str(source).map_err(|e| {
        let line = e.span().map(|s| 1 + source[..s.start.min(source.len())].matches('\n').count());
        let key = line.and_then(|l| key_at_line(source, l));
        let mut message = e.message().trim().to_string();
        if message.starts_with("unknown field") {
            message = format!("{message} (unknown keys are errors so that nothing is silently ignored)");
        }
        InputError { file: Some(path.to_path_buf()), line, key, message }
    })
}

/// Every key of a TOML document with where it is written: dotted paths (`sph.spacing`,
/// `materials[1].density`, `bodies[0].shape.radius`; an array element is `name[i]`) and the
/// byte span of the key (of the element, for array elements), as toml's spanned parser gives
/// them. A document with syntax errors yields what the parser recovered.
fn key_spans(source: &str) -> Vec<(String, std::ops::Range<usize>)> {
    use toml::de::{DeTable, DeValue};
    fn walk(prefix: &str, t: &DeTable<'_>, out: &mut Vec<(String, std::ops::Range<usize>)>) {
        for (k, v) in t.iter() {
            let path = if prefix.is_empty() { k.get_ref().to_string() } else { format!("{prefix}.{}", k.get_ref()) };
            out.push((path.clone(), k.span()));
            value(&path, v.get_ref(), out);
        }
    }
    fn value(path: &str, v: &DeValue<'_>, out: &mut Vec<(String, std::ops::Range<usize>)>) {
        match v {
            DeValue::Table(t) => walk(path, t, out),
            DeValue::Array(a) => {
                for (i, el) in a.iter().enumerate() {
                    let p = format!("{path}[{i}]");
                    out.push((p.clone(), el.span()));
                    value(&p, el.get_ref(), out);
                }
            }
            _ => {}
        }
    }
    let (doc, _errors) = DeTable::parse_recoverable(source);
    let mut out = Vec::new();
    walk("", doc.get_ref(), &mut out);
    out
}

/// 1-based line of a byte offset.
fn line_of(source: &str, offset: usize) -> usize {
    1 + source[..offset.min(source.len())].matches('\n').count()
}

/// The dotted key written first on a 1-based line (a table header's table, or the key of a
/// `key = value` line).
fn key_at_line(source: &str, line: usize) -> Option<String> {
    key_spans(source)
        .into_iter()
        .filter(|(_, span)| line_of(source, span.start) == line)
        .min_by_key(|(path, span)| (span.start, std::cmp::Reverse(path.len())))
        .map(|(path, _)| path)
}

/// The parent of a dotted key: `a.b[2].c` → `a.b[2]` → `a.b` → `a`.
fn parent_key(key: &str) -> Option<&str> {
    if let Some(stripped) = key.strip_suffix(']') {
        return stripped.rfind('[').map(|i| &key[..i]);
    }
    key.rfind(['.', '[']).map(|i| &key[..i])
}

/// The 1-based line where a dotted key (`sph.spacing`, `materials[1].density`, `bodies[0]`) is
/// written: the key's own line, else the line of the nearest enclosing key that is written (a
/// key missing from `[[materials]]` entry 1 resolves to that entry's header; one inside an
/// inline table, `bodies[0].shape.radius`, to the line of `bodies[0].shape`).
pub fn locate_key(source: &str, key: &str) -> Option<usize> {
    let spans = key_spans(source);
    let mut k = Some(key);
    while let Some(cur) = k {
        if let Some((_, span)) = spans.iter().find(|(p, _)| p == cur) {
            return Some(line_of(source, span.start));
        }
        k = parent_key(cur);
    }
    None
}

/// Any error and its chain of causes on one line, joined by `: ` (what every command prints;
/// the facade error's `report` is this).
pub fn report(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut cur = e.source();
    while let Some(s) = cur {
        let text = s.to_string();
        // Errors that already print their cause (`{source}` in their message) would repeat it.
        if !out.ends_with(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
        cur = s.source();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRC: &str =
        "# c\n[simulation]\nend_time = 1.0\n\n[[materials]]\nname = \"a\"\n[[materials]]\nname = \"b\"\ndensity = 3\n";

    #[test]
    fn locates_keys_in_tables_and_arrays() {
        assert_eq!(locate_key(SRC, "simulation.end_time"), Some(3));
        assert_eq!(locate_key(SRC, "materials[1].density"), Some(9));
        assert_eq!(locate_key(SRC, "materials[1]"), Some(7));
        assert_eq!(locate_key(SRC, "materials[0].density"), Some(5));
        assert_eq!(key_at_line(SRC, 9).as_deref(), Some("materials[1].density"));
    }

    #[test]
    fn parents_of_keys() {
        assert_eq!(parent_key("a.b[2].c"), Some("a.b[2]"));
        assert_eq!(parent_key("a.b[2]"), Some("a.b"));
        assert_eq!(parent_key("a.b"), Some("a"));
        assert_eq!(parent_key("a"), None);
    }

    #[test]
    fn display_is_one_line() {
        let e = InputError {
            file: Some("a.toml".into()),
            line: Some(3),
            key: Some("sph.spacing".into()),
            message: "must be\n > 0".into(),
        };
        assert_eq!(e.to_string(), "a.toml:3: key `sph.spacing`: must be > 0");
        assert_eq!(InputError::flag("--p0", "must be > 0 Pa").to_string(), "--p0: must be > 0 Pa");
    }
}
