//! Shared by the command-line tests: running the built binary and reading what it said.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `hystcomp` with `args`.
pub fn hystcomp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hystcomp"))
        .args(args)
        .output()
        .expect("the hystcomp binary runs")
}

/// What the run printed on stderr.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// What the run printed on stdout.
pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A path as an argument.
pub fn s(path: &Path) -> &str {
    path.to_str().expect("test paths are UTF-8")
}

/// The repository's example model files.
pub fn models() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

/// Runs `hystcomp` with `args`, asserts a non-zero exit and every fragment in the message.
pub fn assert_fails(args: &[&str], fragments: &[&str]) {
    let out = hystcomp(args);
    assert!(!out.status.success(), "succeeded: {args:?}");
    assert_ne!(out.status.code(), Some(0));
    let message = stderr(&out);
    for fragment in fragments {
        assert!(message.contains(fragment), "{fragment:?} not in: {message}");
    }
}
