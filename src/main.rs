//! The `regolith` command-line tool.
fn main() {}
