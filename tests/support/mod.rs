//! What the end-to-end tests of the `skinkit` binary share: running it, reading what it said, and
//! the repository's sample folders. Each test file takes it with
//! `#[path = "support/mod.rs"] mod support;` and uses what it needs.

// Every test file is its own crate, and none uses every helper.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The binary under test, as a command to add arguments to.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_skinkit"))
}

/// Runs the binary with `args` to the end.
pub fn skinkit(args: &[&str]) -> Output {
    bin().args(args).output().expect("skinkit runs")
}

/// What the run wrote on stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repository exists")
}

/// A sample mold's folder, `samples/molds/<region>`.
pub fn mold(region: &str) -> PathBuf {
    repo().join("samples/molds").join(region)
}

/// A path as a command-line argument (the tests' paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}
