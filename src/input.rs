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

/// One line of a TOML file as the locator sees it.
struct Line {
    /// 1-based line number.
    number: usize,
    /// Dotted path of the table the line belongs to (`materials[1]`), after any header on it.
    table: String,
    /// `Some(key)` for a `key = value` line.
    key: Option<String>,
    /// True for a table header line.
    header: bool,
}

/// Walks the lines of a TOML source, tracking the current table (array-of-tables entries are
/// indexed in order of appearance).
fn lines(source: &str) -> impl Iterator<Item = Line> + '_ {
    let mut table = String::new();
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    source.lines().enumerate().map(move |(i, raw)| {
        let l = raw.trim();
        if let Some(h) = header(l) {
            table = h.name.clone();
            if h.array {
                let n = counts.entry(h.name.clone()).or_insert(0);
                table = format!("{}[{}]", h.name, *n);
                *n += 1;
            }
            return Line { number: i + 1, table: table.clone(), key: None, header: true };
        }
        let key = if l.starts_with('#') || !l.contains('=') {
            None
        } else {
            l.split('=').next().map(|k| k.trim().trim_matches('"').to_string()).filter(|k| !k.is_empty())
        };
        Line { number: i + 1, table: table.clone(), key, header: false }
    })
}

fn join(table: &str, key: &str) -> String {
    if table.is_empty() { key.to_string() } else { format!("{table}.{key}") }
}

/// The dotted key defined on a 1-based line (`table.key`), if the line is `key = value` or a
/// table header.
fn key_at_line(source: &str, line: usize) -> Option<String> {
    let l = lines(source).find(|l| l.number == line)?;
    if l.header {
        return Some(l.table);
    }
    l.key.map(|k| join(&l.table, &k))
}

struct Header {
    name: String,
    array: bool,
}

fn header(l: &str) -> Option<Header> {
    if let Some(rest) = l.strip_prefix("[[") {
        let end = rest.find("]]")?;
        return Some(Header { name: rest[..end].trim().to_string(), array: true });
    }
    if let Some(rest) = l.strip_prefix('[') {
        let end = rest.find(']')?;
        return Some(Header { name: rest[..end].trim().to_string(), array: false });
    }
    None
}

/// The 1-based line where a dotted key (`sph.spacing`, `materials[1].density`, `bodies[0]`) is
/// written: the key's own line, else the line of the nearest enclosing key (a key inside an
/// inline table, `bodies[0].shape.radius`, resolves to the line of `bodies[0].shape`), else the
/// header of its table.
pub fn locate_key(source: &str, key: &str) -> Option<usize> {
    if let Some(line) = locate_exact(source, key) {
        return Some(line);
    }
    let mut k = key;
    while let Some((parent, _)) = k.rsplit_once('.') {
        if let Some(line) = locate_exact(source, parent).filter(|_| key_is_written(source, parent)) {
            return Some(line);
        }
        k = parent;
    }
    table_header_line(source, key)
}

fn key_is_written(source: &str, key: &str) -> bool {
    lines(source).any(|l| l.key.as_ref().is_some_and(|k| join(&l.table, k) == key) || (l.header && l.table == key))
}

fn table_header_line(source: &str, key: &str) -> Option<usize> {
    let table_of_key = key.rsplit_once('.').map(|(t, _)| t).unwrap_or("");
    lines(source)
        .find(|l| l.header && (l.table == table_of_key || table_of_key.starts_with(&format!("{}.", l.table))))
        .map(|l| l.number)
}

fn locate_exact(source: &str, key: &str) -> Option<usize> {
    let table_of_key = key.rsplit_once('.').map(|(t, _)| t).unwrap_or("");
    let mut header_line = None;
    for l in lines(source) {
        if l.header && l.table == key {
            return Some(l.number);
        }
        if l.header && l.table == table_of_key {
            header_line = Some(l.number);
        }
        if let Some(k) = &l.key
            && join(&l.table, k) == key
        {
            return Some(l.number);
        }
    }
    header_line
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
