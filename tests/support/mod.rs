//! What the end-to-end tests of the `skinkit` binary share: running it, reading what it said, and
//! the repository's sample folders. Declared once, by the test binary's root `tests/cli.rs`; each
//! module takes what it needs with `use crate::support::...`.

// Some helpers serve only tests that are compiled on Unix (the FIFO and hang checks).
#![allow(dead_code)]

pub mod browser;
pub mod sessions;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

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

/// Runs the binary with `args` (from `dir` when given, stdin closed) and fails the test when it
/// has not ended after `seconds`: what a hang (a FIFO read, a file read whole) looks like.
pub fn run_within(seconds: u64, dir: Option<&Path>, args: &[&str]) -> Output {
    let mut command = bin();
    if let Some(dir) = dir {
        command.current_dir(dir);
    }
    let mut child = command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("skinkit runs");
    let start = Instant::now();
    while child.try_wait().expect("the child can be waited on").is_none() {
        if start.elapsed() > Duration::from_secs(seconds) {
            child.kill().ok();
            panic!("skinkit {} still running after {seconds} s", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("its output")
}

/// Makes a FIFO (named pipe) at `path`.
pub fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

/// Waits (up to 5 s) until process `pid` catches signal number `signo`: its handlers are installed
/// a few ms after the start, later on a loaded machine (this binary's other tests run beside),
/// and a signal before then would kill it with the default action. Returns at once when the
/// process ignores the signal (inherited ignored, as in a script's background job, and kept so by
/// the binary) or has exited. Linux only (`/proc/<pid>/status`); elsewhere it returns at once.
pub fn wait_for_signal_handler(pid: u32, signo: u32) {
    let bit = 1u64 << (signo - 1);
    let mask = |status: &str, field: &str| {
        let hex = status.lines().find_map(|l| l.strip_prefix(field)).map(str::trim);
        hex.and_then(|m| u64::from_str_radix(m, 16).ok())
    };
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(5) {
        let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else { return };
        // Already exited (a zombie until waited for): nothing left to catch.
        if status.lines().any(|l| l.starts_with("State:") && l.contains('Z')) {
            return;
        }
        let (Some(caught), Some(ignored)) = (mask(&status, "SigCgt:"), mask(&status, "SigIgn:")) else { return };
        if (caught | ignored) & bit != 0 {
            return;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}
