//! The root crate's modules form a one-way flow: each imports only modules before it in
//! [`LAYERS`] (the order of `ARCHITECTURE.md`), so there is no import cycle among them. This
//! test reads the sources and fails on any import that points the other way, and on any cycle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The root crate's top-level modules, in the order the data flows.
/// `error`, the facade's error type, gathers the stages' own error types, so it comes after them.
const LAYERS: [&str; 18] = [
    "input",
    "material",
    "element",
    "scene",
    "build",
    "sim",
    "driver",
    "output",
    "rig",
    "run",
    "runner",
    "study",
    "error",
    "sweep",
    "calibrate",
    "accuracy",
    "bench",
    "cli",
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("src readable") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a source file belongs to (`None` for lib.rs and main.rs).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).expect("under src");
    let first = rel.components().next()?.as_os_str().to_string_lossy().into_owned();
    let name = first.trim_end_matches(".rs").to_string();
    (name != "lib" && name != "main").then_some(name)
}

/// Every `crate::<module>` named in code or in doc comments (a doc link to a later module is a
/// dependency a reader follows too); plain `//` comments are skipped.
fn crate_refs(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in text.lines() {
        let t = line.trim_start();
        let code = if t.starts_with("///") || t.starts_with("//!") { t } else { line.split("//").next().unwrap_or("") };
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            let after = &rest[i + "crate::".len()..];
            let name: String = after.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if !name.is_empty() {
                out.insert(name);
            }
            rest = after;
        }
    }
    out
}

fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let Some(m) = module_of(&src, &f) else { continue };
        let text = std::fs::read_to_string(&f).expect("source readable");
        let refs = crate_refs(&text);
        g.entry(m.clone()).or_default().extend(refs.into_iter().filter(|r| *r != m));
    }
    g
}

#[test]
fn every_module_is_in_a_layer() {
    for m in graph().keys() {
        assert!(LAYERS.contains(&m.as_str()), "module `{m}` is not in LAYERS: place it in the data flow");
    }
}

#[test]
fn no_module_imports_a_later_one() {
    let rank = |m: &str| LAYERS.iter().position(|l| *l == m);
    let mut wrong = Vec::new();
    for (m, refs) in graph() {
        let Some(rm) = rank(&m) else { continue };
        for r in refs {
            let Some(rr) = rank(&r) else { continue };
            if rr >= rm {
                wrong.push(format!("{m} → {r}"));
            }
        }
    }
    assert!(wrong.is_empty(), "imports against the data flow: {wrong:?}");
}

#[test]
fn no_import_cycle_among_modules() {
    let g = graph();
    fn visit<'a>(
        m: &'a str,
        g: &'a BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<&'a str>,
        done: &mut BTreeSet<&'a str>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| *p == m) {
            let mut cycle: Vec<String> = path[i..].iter().map(|s| s.to_string()).collect();
            cycle.push(m.to_string());
            return Some(cycle);
        }
        if done.contains(m) {
            return None;
        }
        path.push(m);
        for r in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(r, g, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(m);
        None
    }
    let mut done = BTreeSet::new();
    for m in g.keys() {
        let mut path = Vec::new();
        if let Some(c) = visit(m, &g, &mut path, &mut done) {
            panic!("import cycle: {}", c.join(" → "));
        }
    }
}

#[test]
fn the_scanner_sees_imports() {
    // Guard against a scanner that finds nothing (the checks above would then pass vacuously).
    let g = graph();
    assert!(g["run"].contains("driver") && g["sim"].contains("build") && g["cli"].contains("run"), "{g:?}");
    let refs = crate_refs("use crate::a::b; // crate::c\n/// [`crate::d::X`]\n// crate::g\nlet x = crate::e::f();");
    let want: BTreeSet<String> = ["a", "d", "e"].iter().map(|s| s.to_string()).collect();
    assert_eq!(refs, want);
}
