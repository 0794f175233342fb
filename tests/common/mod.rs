//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::collections::BTreeMap;
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

/// Messages of a recording, by topic: (log time s, JSON value), each validated against the
/// JSON schema its channel carries in the file.
pub fn read_validated(path: &Path) -> BTreeMap<String, Vec<(f64, serde_json::Value)>> {
    let bytes = std::fs::read(path).expect("recording exists");
    assert!(mcap::Summary::read(&bytes).expect("summary parses").is_some(), "the summary section is written");
    let mut validators: BTreeMap<u16, jsonschema::Validator> = BTreeMap::new();
    let mut out: BTreeMap<String, Vec<(f64, serde_json::Value)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).expect("stream") {
        let m = m.expect("message parses");
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m.channel.schema.as_ref().expect("every channel has a schema");
        assert_eq!(schema.encoding, "jsonschema");
        let v = validators.entry(m.channel.id).or_insert_with(|| {
            let s: serde_json::Value = serde_json::from_slice(&schema.data).expect("schema is JSON");
            jsonschema::validator_for(&s).expect("schema compiles")
        });
        let msg: serde_json::Value = serde_json::from_slice(&m.data).expect("message is JSON");
        if let Err(e) = v.validate(&msg) {
            panic!("{} message at {} ns does not match {}: {e}", m.channel.topic, m.log_time, schema.name);
        }
        out.entry(m.channel.topic.clone()).or_default().push((m.log_time as f64 * 1e-9, msg));
    }
    out
}
