//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use regolith::scene::{Scene, load_scene, load_scene_source, parse_set};

/// A scene from TOML text (relative files resolve against the crate root).
pub fn scene(text: &str) -> Scene {
    load_scene_source(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("inline.toml"), text, &[])
        .unwrap_or_else(|e| panic!("{e}"))
}

/// An example scene with `--set` overrides.
pub fn example(name: &str, sets: &[&str]) -> Scene {
    let sets: Vec<_> = sets.iter().map(|s| parse_set(s).expect("set")).collect();
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes").join(name);
    load_scene(&p, &sets).unwrap_or_else(|e| panic!("{e}"))
}

/// A fresh output directory under the test target dir.
pub fn out_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("out dir");
    d
}
