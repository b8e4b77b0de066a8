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
//!
//! # Other tools
//! Tests that drive other tools (cargo, gcc, octave) share [`target_dir`], [`cargo`] (a nested
//! cargo on the same target directory), [`run`] (a command whose failure shows its output),
//! [`available`], [`workspace_libraries`] (every library of the workspace, built once per test
//! binary with the outer build's features) and [`c_static_library`] (the C ABI's static
//! library among them).

use std::fmt::Display;
use std::fs::OpenOptions;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

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

/// The target directory of the outer `cargo test` (`CARGO_TARGET_DIR`, or `target/` in the
/// workspace). A nested `cargo build` may share it: cargo holds its lock while it builds, not
/// while the test binaries run, and builds of other feature sets get other artifact hashes.
/// Sharing it means the nested build reuses what `cargo test` already compiled.
pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map(|dir| {
            if dir.is_absolute() {
                dir
            } else {
                workspace_root().join(dir)
            }
        })
        .unwrap_or_else(|| workspace_root().join("target"))
}

/// The skip log: `$CARGO_TARGET_DIR/test-skips.log`, or `target/test-skips.log` in the
/// workspace.
pub fn skip_log() -> PathBuf {
    target_dir().join(SKIP_LOG)
}

/// The cargo that runs these tests (or `cargo` from the PATH), for a nested build on the same
/// target directory (see [`target_dir`]), without the outer build's target triple or flags.
pub fn cargo() -> Command {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut command = Command::new(cargo);
    command
        .env("CARGO_TARGET_DIR", target_dir())
        .env_remove("CARGO_BUILD_TARGET")
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTFLAGS");
    command
}

/// Runs `command`, panicking with its output (and `hint`) when it cannot start or fails.
pub fn run(command: &mut Command, hint: &str) -> Output {
    let shown = format!("{command:?}");
    let output = command
        .output()
        .unwrap_or_else(|e| panic!("could not run {shown}: {e}. {hint}"));
    if !output.status.success() {
        panic!(
            "{shown} failed ({}):\n--- stdout\n{}\n--- stderr\n{}\n{hint}",
            output.status,
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    output
}

/// `true` when `program --version` runs.
pub fn available(program: &str) -> bool {
    Command::new(program)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The workspace's libraries of every crate type, debug profile, built by one nested
/// `cargo build --workspace --lib --tests` once per test binary; the directory that holds
/// them (`target/debug`). Its `--workspace --tests` resolves the features as `cargo test
/// --workspace` does (every member, dev-dependencies included), so under that command the
/// nested build reuses what it compiled and builds only the crate types `cargo test` leaves
/// out (the Python extension's `cdylib`). A nested build of one package (`-p hystcomp-c`)
/// resolves other features and rebuilt the stack under it: about two minutes on the project's
/// 2-core machine, once for the C library and once for the Python extension. Under a narrower
/// outer command (`cargo test -p hystcomp-python`, `--release`) it builds what the whole
/// workspace's tests need once, then stays fresh. The outer build's `RUSTFLAGS` are kept (they
/// do not change artifact names: without them the nested build would rebuild every library in
/// place, and the next outer build again).
pub fn workspace_libraries() -> &'static PathBuf {
    static LIBRARIES: OnceLock<PathBuf> = OnceLock::new();
    LIBRARIES.get_or_init(|| {
        let mut command = cargo();
        for flags in ["RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS"] {
            if let Some(value) = std::env::var_os(flags) {
                command.env(flags, value);
            }
        }
        run(
            command.current_dir(workspace_root()).args([
                "build",
                "--quiet",
                "--workspace",
                "--lib",
                "--tests",
            ]),
            "the workspace's libraries must build",
        );
        target_dir().join("debug")
    })
}

/// The C ABI's static library (`libhystcomp.a` of `bindings/c`, debug profile), from
/// [`workspace_libraries`].
pub fn c_static_library() -> &'static PathBuf {
    static LIBRARY: OnceLock<PathBuf> = OnceLock::new();
    LIBRARY.get_or_init(|| {
        let library = workspace_libraries().join("libhystcomp.a");
        assert!(library.is_file(), "{} was not built", library.display());
        library
    })
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
