//! The root crate's modules form a one-way flow: each imports only modules before it in
//! [`LAYERS`] (the order of `ARCHITECTURE.md`), so there is no import cycle among them. This
//! test reads the sources and fails on any import that points the other way, and on any cycle.
//! Below the top level, every crate of the workspace is checked file by file: no two source
//! files (modules) import each other, directly or through others.

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

/// The workspace's crates: the root crate and each member, by their `src` folders.
const CRATE_SOURCES: [&str; 9] =
    ["src", "body/src", "coupling/src", "fsi/src", "gpu/src", "python/src", "rigid/src", "terrain/src", "vehicles/src"];

/// The module path of a source file relative to its crate's `src` (`cpu/rates.rs` →
/// `cpu::rates`, `cpu/mod.rs` → `cpu`, `lib.rs` → the root, an empty path).
fn module_path(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    if let Some(last) = parts.pop() {
        let stem = last.trim_end_matches(".rs").to_string();
        if !matches!(stem.as_str(), "mod" | "lib" | "main") {
            parts.push(stem);
        }
    }
    parts
}

/// Every path a file names through `crate::`, `super::` or `self::` (in code or doc comments;
/// plain `//` comments are skipped), as the module path it starts from (`crate` = empty,
/// `super`/`self` relative to `here`) followed by its segments. A `{…}` group gives one path
/// per member (its first segment).
fn file_refs(text: &str, here: &[String]) -> Vec<Vec<String>> {
    let ident = |s: &str| -> String { s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect() };
    let mut out = Vec::new();
    for line in text.lines() {
        let t = line.trim_start();
        let code = if t.starts_with("///") || t.starts_with("//!") { t } else { line.split("//").next().unwrap_or("") };
        let bytes = code.as_bytes();
        for head in ["crate::", "super::", "self::"] {
            let mut from = 0;
            while let Some(i) = code[from..].find(head).map(|i| i + from) {
                from = i + head.len();
                // A path's first segment only (not `my_crate::` or the second `super::`).
                if i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b':') {
                    continue;
                }
                let mut base: Vec<String> = if head == "crate::" { Vec::new() } else { here.to_vec() };
                if head == "super::" {
                    base.pop();
                }
                let mut rest = &code[from..];
                loop {
                    let name = ident(rest);
                    if name.is_empty() {
                        break;
                    }
                    if name == "super" {
                        base.pop();
                    } else {
                        base.push(name.clone());
                    }
                    rest = &rest[name.len()..];
                    match rest.strip_prefix("::") {
                        Some(r) => rest = r,
                        None => break,
                    }
                }
                match rest.strip_prefix('{') {
                    Some(group) => {
                        let group = group.split('}').next().unwrap_or("");
                        for member in group.split(',') {
                            let name = ident(member.trim());
                            let mut p = base.clone();
                            if !name.is_empty() && name != "self" {
                                p.push(name);
                            }
                            out.push(p);
                        }
                    }
                    None => out.push(base),
                }
            }
        }
    }
    out
}

/// The file-level import graph of the crate under `src`: each module (file) and the modules
/// it names, each reference resolved to the longest prefix of its path that is a module of
/// the crate. A module naming its own ancestor (`super::X`, usually an item a `mod.rs`
/// re-exports) or descendant (a `mod.rs` using its children) is no edge: that is the
/// declaration tree, not an import between files.
fn file_graph(src: &Path) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeMap<Vec<String>, PathBuf> =
        files.iter().map(|f| (module_path(f.strip_prefix(src).expect("under src")), f.clone())).collect();
    let mut g = BTreeMap::new();
    for (m, f) in &modules {
        let text = std::fs::read_to_string(f).expect("source readable");
        let mut to = BTreeSet::new();
        for full in file_refs(&text, m) {
            let Some(k) = (0..=full.len()).rev().find(|&k| modules.contains_key(&full[..k])) else { continue };
            let target = full[..k].to_vec();
            let related = target.starts_with(m) || m.starts_with(&target);
            if !related {
                to.insert(target);
            }
        }
        g.insert(m.clone(), to);
    }
    g
}

/// A cycle of `g`, if it has one, as the modules along it (first repeated at the end).
fn find_cycle(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Option<Vec<String>> {
    fn visit(
        m: &Vec<String>,
        g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        path: &mut Vec<Vec<String>>,
        done: &mut BTreeSet<Vec<String>>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| p == m) {
            let mut cycle: Vec<String> = path[i..].iter().map(|p| p.join("::")).collect();
            cycle.push(m.join("::"));
            return Some(cycle);
        }
        if done.contains(m) {
            return None;
        }
        path.push(m.clone());
        for r in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(r, g, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(m.clone());
        None
    }
    let mut done = BTreeSet::new();
    g.keys().find_map(|m| visit(m, g, &mut Vec::new(), &mut done))
}

#[test]
fn no_import_cycle_among_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cycles = Vec::new();
    for src in CRATE_SOURCES {
        let g = file_graph(&root.join(src));
        assert!(!g.is_empty(), "{src}: no source files found");
        if let Some(c) = find_cycle(&g) {
            cycles.push(format!("{src}: {}", c.join(" → ")));
        }
    }
    assert!(cycles.is_empty(), "import cycles between files (move what both use into a file of its own): {cycles:?}");
}

#[test]
fn the_file_scanner_resolves_paths_and_finds_cycles() {
    // Guard against a scanner that resolves nothing (the check above would pass vacuously).
    let here: Vec<String> = ["cpu", "lanes"].iter().map(|s| s.to_string()).collect();
    let refs = file_refs(
        "use super::pair::{Packed, PairSums};\nuse super::super::math::Vec3; // crate::x\n/// [`crate::a::B`]\nlet n = self::inner::f(); my_crate::z();",
        &here,
    );
    let s = |p: &[&str]| p.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    assert_eq!(
        refs,
        vec![
            s(&["cpu", "pair", "Packed"]),
            s(&["cpu", "pair", "PairSums"]),
            s(&["math", "Vec3"]),
            s(&["a", "B"]),
            s(&["cpu", "lanes", "inner", "f"]),
        ]
    );
    assert_eq!(module_path(Path::new("cpu/mod.rs")), s(&["cpu"]));
    assert_eq!(module_path(Path::new("cpu/rates.rs")), s(&["cpu", "rates"]));
    assert!(module_path(Path::new("lib.rs")).is_empty());
    // The fsi crate's graph has the edge the pair loop's files make, and a two-file loop is found.
    let g = file_graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fsi/src"));
    assert!(g[&s(&["cpu", "lanes"])].contains(&s(&["cpu", "pair"])), "{g:?}");
    let mut looped = g.clone();
    looped.get_mut(&s(&["cpu", "pair"])).expect("pair.rs").insert(s(&["cpu", "lanes"]));
    let c = find_cycle(&looped).expect("a cycle");
    assert!(c.contains(&"cpu::pair".to_string()) && c.contains(&"cpu::lanes".to_string()), "{c:?}");
    assert!(find_cycle(&g).is_none());
}
