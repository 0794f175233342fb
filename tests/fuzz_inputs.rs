//! Mutated inputs never panic: scene, material and URDF files, each the shipped examples with
//! random edits (lines deleted, duplicated, swapped or inserted, values replaced by wrong
//! types and extreme numbers, text truncated or a byte changed). Every file is either accepted
//! or rejected with one line naming the file; the CLI turns those into exit code 2 (tested in
//! tests/cli_errors.rs). 12 000 + 4 000 + 4 000 cases (about 10 s).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use proptest::prelude::*;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn texts(dir: &str) -> Vec<(PathBuf, String)> {
    let mut out: Vec<(PathBuf, String)> = std::fs::read_dir(root().join(dir))
        .expect("dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| {
            let t = std::fs::read_to_string(&p).expect("read");
            (p, t)
        })
        .collect();
    out.sort();
    out
}

fn scenes() -> &'static [(PathBuf, String)] {
    static S: OnceLock<Vec<(PathBuf, String)>> = OnceLock::new();
    S.get_or_init(|| [texts("examples/scenes"), texts("examples/hard")].concat())
}

fn materials() -> &'static [(PathBuf, String)] {
    static S: OnceLock<Vec<(PathBuf, String)>> = OnceLock::new();
    S.get_or_init(|| texts("examples/materials"))
}

const VALUES: [&str; 16] = [
    "-1",
    "0",
    "-0.0",
    "1e300",
    "-1e300",
    "nan",
    "inf",
    "1e-300",
    "4294967296",
    "2.5",
    "\"x\"",
    "[1, 2]",
    "[]",
    "true",
    "{ type = \"box\" }",
    "\"\"",
];
const LINES: [&str; 10] = [
    "[simulation]",
    "x = 1",
    "[[bodies]]",
    "name = \"sand\"",
    "[[expect]]",
    "[[soil_blocks]]",
    "shape = { type = \"wheel\", radius = 0.0, width = -1 }",
    "\u{0}\u{7f}\u{ff}",
    "[sph.active]",
    "<robot name=\"r\"><link name=\"l\"/></robot>",
];

#[derive(Clone, Debug)]
enum Edit {
    Delete(usize),
    Duplicate(usize),
    Swap(usize, usize),
    Insert(usize, usize),
    Value(usize, usize),
    Truncate(usize),
    Byte(usize, char),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        any::<usize>().prop_map(Edit::Delete),
        any::<usize>().prop_map(Edit::Duplicate),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::Swap(a, b)),
        (any::<usize>(), 0..LINES.len()).prop_map(|(a, b)| Edit::Insert(a, b)),
        (any::<usize>(), 0..VALUES.len()).prop_map(|(a, b)| Edit::Value(a, b)),
        (any::<usize>(), 0..VALUES.len()).prop_map(|(a, b)| Edit::Value(a, b)),
        any::<usize>().prop_map(Edit::Truncate),
        (any::<usize>(), prop::char::any()).prop_map(|(a, c)| Edit::Byte(a, c)),
    ]
}

/// `text` with `edits` applied, line by line.
fn mutate(text: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for e in edits {
        let n = lines.len().max(1);
        match *e {
            Edit::Delete(i) if !lines.is_empty() => {
                lines.remove(i % n);
            }
            Edit::Duplicate(i) if !lines.is_empty() => {
                let l = lines[i % n].clone();
                lines.insert(i % n, l);
            }
            Edit::Swap(a, b) if !lines.is_empty() => lines.swap(a % n, b % n),
            Edit::Insert(i, l) => lines.insert(i % (lines.len() + 1), LINES[l].to_string()),
            Edit::Value(i, v) => {
                // Replace the value of a `key = value` line (or an XML attribute's value).
                let i = i % n;
                if let Some(line) = lines.get_mut(i)
                    && let Some((k, _)) = line.split_once('=')
                {
                    let quoted = k.trim_end().ends_with('"') || line.contains("=\"");
                    *line = if quoted && line.contains('<') {
                        let at = line.find("=\"").map_or(0, |p| p + 2);
                        let end = line[at..].find('"').map_or(line.len(), |q| at + q);
                        format!("{}{}{}", &line[..at], VALUES[v].trim_matches('"'), &line[end..])
                    } else {
                        format!("{k}= {}", VALUES[v])
                    };
                }
            }
            Edit::Truncate(p) => {
                let joined = lines.join("\n");
                let mut cut = p % (joined.len() + 1);
                while !joined.is_char_boundary(cut) {
                    cut -= 1;
                }
                lines = joined[..cut].lines().map(str::to_string).collect();
            }
            Edit::Byte(p, c) if !lines.is_empty() => {
                let l = &mut lines[p % n];
                let chars: Vec<char> = l.chars().collect();
                if !chars.is_empty() {
                    let k = (p / n) % chars.len();
                    *l = chars.iter().enumerate().map(|(j, x)| if j == k { c } else { *x }).collect();
                }
            }
            _ => {}
        }
    }
    lines.join("\n")
}

/// A rejection is one line naming one of `files`, or a file next to one (a URDF, mesh or
/// heightmap the file refers to, which the message names with the key that refers to it).
fn one_line(e: impl std::fmt::Display, files: &[&Path]) -> Result<(), TestCaseError> {
    let m = e.to_string();
    prop_assert_eq!(m.lines().count(), 1, "not one line: {}", m);
    let names = |f: &&Path| {
        m.contains(&f.display().to_string()) || f.parent().is_some_and(|d| m.contains(&d.display().to_string()))
    };
    prop_assert!(files.iter().any(names), "does not name {:?}: {}", files, m);
    Ok(())
}

/// A fixed seed, so that CI runs the same cases every time (`FUZZ_SEED=n` explores others).
fn seed(default: u64) -> proptest::test_runner::RngSeed {
    let s = std::env::var("FUZZ_SEED").ok().and_then(|s| s.parse::<u64>().ok()).map_or(default, |s| s * 7919 + default);
    proptest::test_runner::RngSeed::Fixed(s)
}

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz_inputs");
    std::fs::create_dir_all(&d).expect("tmp");
    d.join(name)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12000, rng_seed: seed(1), failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn mutated_scenes_are_accepted_or_refused_in_one_line(
        which in any::<usize>(),
        edits in prop::collection::vec(edit(), 1..4),
    ) {
        let (path, text) = &scenes()[which % scenes().len()];
        let text = mutate(text, &edits);
        if std::env::var_os("FUZZ_TRACE").is_some() {
            std::fs::write(tmp("last_scene.toml"), format!("# {}\n{text}", path.display())).expect("trace");
        }
        // Parsed from memory, named (and resolving relative files) as the original.
        match regolith::scene::load_scene_source(path, &text, &[]) {
            Ok(scene) => {
                // What `regolith check` prints must not panic either.
                let _ = regolith::scene::describe(&scene);
            }
            Err(e) => one_line(e, &[path])?,
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, rng_seed: seed(2), failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn mutated_material_files_are_accepted_or_refused_in_one_line(
        which in any::<usize>(),
        edits in prop::collection::vec(edit(), 1..4),
    ) {
        let (_, text) = &materials()[which % materials().len()];
        let path = tmp("material.toml");
        std::fs::write(&path, mutate(text, &edits)).expect("write");
        match regolith::material::load_material_file(&path) {
            Ok(m) => {
                // A material that loads also builds in both precisions, or says why.
                let _ = m.build::<f32>();
                let _ = m.build::<f64>();
            }
            Err(e) => one_line(e, &[&path])?,
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, rng_seed: seed(3), failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn mutated_urdfs_are_accepted_or_refused_in_one_line(edits in prop::collection::vec(edit(), 1..4)) {
        static URDF: OnceLock<String> = OnceLock::new();
        let urdf = URDF.get_or_init(|| {
            std::fs::read_to_string(root().join("examples/rover_description/urdf/rover.urdf")).expect("urdf")
        });
        let path = tmp("rover.urdf");
        std::fs::write(&path, mutate(urdf, &edits)).expect("write");
        if std::env::var_os("FUZZ_TRACE").is_some() {
            std::fs::copy(&path, tmp("last.urdf")).expect("trace");
        }
        let examples = root().join("examples");
        let scene = format!(
            "[simulation]\nend_time = 0.1\n\n[sph]\nspacing = 0.02\n\n[[materials]]\nname = \"s\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
             [container]\nmin = [0.0, 0.0, 0.0]\nmax = [1.2, 0.7, 0.3]\n\n[terrain]\nmaterial = \"s\"\ndepth = 0.1\n\n\
             [[vehicles]]\nname = \"rover\"\nurdf = {:?}\npackage_path = [{:?}]\nposition = [0.3, 0.35]\n",
            path.display().to_string(),
            examples.display().to_string()
        );
        let scene_path = tmp("urdf_scene.toml");
        match regolith::scene::load_scene_source(&scene_path, &scene, &[]) {
            Ok(s) => {
                let _ = regolith::scene::describe(&s);
            }
            Err(e) => one_line(e, &[&scene_path, &path])?,
        }
    }
}
