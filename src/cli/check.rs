//! `regolith check`.

use std::path::Path;

use super::Failure;
use crate::scene::{describe, load_scene};

pub(super) fn run(path: &Path, sets: &[(String, toml::Value)]) -> Result<(), Failure> {
    let scene = load_scene(path, sets)?;
    print!("{}", describe(&scene));
    println!("ok: the scene is valid");
    Ok(())
}
