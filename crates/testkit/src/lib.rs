//! Test support shared by hystcomp's test suites (a dev-dependency only).
//!
//! # Skips that CI shows
//! `cargo test` counts a test that returns early as passed. A test that cannot do its work on
//! this machine therefore calls [`skip`] (or [`require_tool`], [`shared_data`]) before it
//! returns: the reason goes to stderr and, one line per skip, to `test-skips.log` in the
//! target directory, which `.ci/run` empties before the tests and prints after them.
//!
//! A prerequisite that `.ci/run` installs (a tool such as `chromium`, `gcc` or `octave`) is
//! never skipped under CI: with `HYSTCOMP_CI=1` in the environment (set by `.ci/run`),
//! [`require_tool`] fails the test instead.
//!
//! # The shared real data
//! The real records live beside the repository, in `../shared/data` (see the README); they are
//! not copied into it. [`shared_data`] finds one (or `$HYSTCOMP_SHARED_DATA` instead of
//! `../shared/data`) and records a skip when it is absent.

use std::fmt::Display;
use std::fs::OpenOptions;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The environment variable `.ci/run` sets to `1`: prerequisites it installs must be present.
pub const CI_VARIABLE: &str = "HYSTCOMP_CI";

/// The environment variable that points at a directory to use instead of `../shared/data`.
pub const SHARED_DATA_VARIABLE: &str = "HYSTCOMP_SHARED_DATA";

/// The name of the skip log in the target directory.
pub const SKIP_LOG: &str = "test-skips.log";

/// The workspace's root directory (this crate lives in `crates/testkit`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap_or_else(|_| Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
}

/// The skip log: `$CARGO_TARGET_DIR/test-skips.log`, or `target/test-skips.log` in the
/// workspace.
pub fn skip_log() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map(|t| {
            if t.is_absolute() {
                t
            } else {
                workspace_root().join(t)
            }
        })
        .unwrap_or_else(|| workspace_root().join("target"));
    target.join(SKIP_LOG)
}

/// `true` under CI (`HYSTCOMP_CI=1`).
pub fn under_ci() -> bool {
    std::env::var(CI_VARIABLE).as_deref() == Ok("1")
}

/// Records that the calling test skips (all or part of) its work, and why: on stderr and as one
/// line `test name<TAB>reason` in the [`skip_log`]. The test should return (or leave out the
/// part) after calling it.
pub fn skip(reason: impl Display) {
    record_skip(&skip_log(), &reason.to_string());
}

/// [`skip`] into a given log.
fn record_skip(log: &Path, reason: &str) {
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("a test");
    let reason = reason.replace(['\n', '\t'], " ");
    eprintln!("SKIPPED {test}: {reason}");
    if let Some(dir) = log.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    // One write of one line with O_APPEND: lines from tests running in parallel do not mix.
    if let Ok(mut file) = OpenOptions::new().create(true).append(true).open(log) {
        let _ = file.write_all(format!("{test}\t{reason}\n").as_bytes());
    }
}

/// Whether a tool the test needs (and `.ci/run` installs) is `available`. When it is not:
/// under CI the test fails with `install_hint`; elsewhere the skip is recorded ([`skip`]) and
/// `false` returned, so that the test returns early.
pub fn require_tool(tool: &str, available: bool, install_hint: &str) -> bool {
    if available {
        return true;
    }
    if under_ci() {
        panic!(
            "{tool} is needed by this test and .ci/run installs it, but it is missing: {install_hint}"
        );
    }
    skip(format!("{tool} is not installed ({install_hint})"));
    false
}

/// `true` when an executable named `program` is on `PATH`.
pub fn on_path(program: &str) -> bool {
    find_on_path(program).is_some()
}

/// The executable named `program` on `PATH`, if any.
pub fn find_on_path(program: &str) -> Option<PathBuf> {
    let paths = std::env::var_os("PATH")?;
    std::env::split_paths(&paths)
        .map(|dir| dir.join(program))
        .find(|p| p.is_file())
}

/// The directory of the shared real data: `$HYSTCOMP_SHARED_DATA`, or `../shared/data` beside
/// the repository. `None` (no skip recorded) when it does not exist.
pub fn shared_data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os(SHARED_DATA_VARIABLE)
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("../shared/data"));
    dir.is_dir().then_some(dir)
}

/// A file of the shared real data, by its path inside `../shared/data` (e.g.
/// `"dbo-micromanipulator/Model_Vi_Do.dat"`), or `None` after recording a skip when it is absent.
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    find_shared_data(relative).map_err(skip).ok()
}

/// The file of the shared data, or why it is absent.
fn find_shared_data(relative: &str) -> Result<PathBuf, String> {
    shared_data_dir()
        .map(|dir| dir.join(relative))
        .filter(|p| p.is_file())
        .ok_or_else(|| {
            format!(
                "the shared real data {relative} is absent (looked in ${SHARED_DATA_VARIABLE} \
                 or ../shared/data beside the repository)"
            )
        })
}

/// The two records of the DBO piezo micromanipulator (Aye & Ang 2018) in `../shared/data`:
/// `"Model_Vi_Do.dat"` or `"Test_Vi_Do_Di.dat"`. See [`shared_data`].
pub fn dbo_record(name: &str) -> Option<PathBuf> {
    shared_data(&format!("dbo-micromanipulator/{name}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_skip_is_logged_with_the_test_name_and_reason() {
        let log = std::env::temp_dir().join(format!("hystcomp-testkit-{}.log", std::process::id()));
        let _ = std::fs::remove_file(&log);
        record_skip(&log, "first\twith a tab\nand a newline");
        record_skip(&log, "second");
        let text = std::fs::read_to_string(&log).expect("the skip log");
        let _ = std::fs::remove_file(&log);
        let name = "tests::a_skip_is_logged_with_the_test_name_and_reason";
        assert_eq!(
            text,
            format!("{name}\tfirst with a tab and a newline\n{name}\tsecond\n")
        );
    }

    #[test]
    fn a_missing_shared_record_says_where_it_looked() {
        let why = find_shared_data("no-such-folder/no-such-file.dat").expect_err("absent");
        assert!(why.contains("no-such-folder/no-such-file.dat"), "{why}");
        assert!(why.contains("../shared/data"), "{why}");
    }

    #[test]
    fn the_workspace_root_holds_the_workspace_manifest() {
        let manifest = std::fs::read_to_string(workspace_root().join("Cargo.toml")).unwrap();
        assert!(manifest.contains("[workspace]"));
    }
}
