//! Runs the Python tests (pytest, `bindings/python/tests/test_*.py`) against the extension
//! module, so that `cargo test --workspace` tests the Python package too.
//!
//! 1. Finds or creates the virtual environment `target/python-venv` (`python3 -m venv`, then
//!    `pip install maturin numpy pytest` from the package index) unless it already has them.
//! 2. `maturin develop` builds `bindings/python` and installs it into that environment, in the
//!    outer build's target directory, so that it reuses what `cargo test` compiled (cargo
//!    holds its lock while it builds, not while the test binaries run).
//! 3. `python -m pytest bindings/python/tests -q -rs`; a failure shows pytest's output, and
//!    every test pytest skipped is recorded with its reason by `hystcomp_testkit::skip`, so
//!    that CI lists it (cargo would count this one test as passed).
//!
//! `HYSTCOMP_PYTHON` names another interpreter than `python3` for creating the environment.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the workspace root exists")
}

/// The target directory of the outer `cargo test` (`CARGO_TARGET_DIR`, or `target/`).
fn target_dir(root: &Path) -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from) {
        Some(dir) if dir.is_absolute() => dir,
        Some(dir) => root.join(dir),
        None => root.join("target"),
    }
}

fn describe(output: &Output) -> String {
    format!(
        "--- stdout\n{}\n--- stderr\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// Runs `command`; its output, or a panic with `what` and the output.
fn run(command: &mut Command, what: &str) -> Output {
    let shown = format!("{command:?}");
    let output = command
        .output()
        .unwrap_or_else(|e| panic!("{what}: could not run {shown}: {e}"));
    if !output.status.success() {
        panic!(
            "{what}: {shown} failed ({}):\n{}",
            output.status,
            describe(&output)
        );
    }
    output
}

/// `true` when `program args...` runs and succeeds.
fn succeeds(program: &Path, args: &[&str]) -> bool {
    Command::new(program)
        .args(args)
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The environment's interpreter, creating the environment and installing maturin, numpy and
/// pytest when they are missing.
fn virtual_environment(venv: &Path) -> PathBuf {
    let python = venv.join("bin/python");
    if !python.exists() {
        let system_python = std::env::var_os("HYSTCOMP_PYTHON").unwrap_or_else(|| "python3".into());
        let works = Command::new(&system_python)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success());
        assert!(
            works,
            "the Python tests need {:?} (Python 3.9 or newer with the venv module): install it, \
             e.g. `apt-get install python3 python3-venv`, or name another interpreter in \
             HYSTCOMP_PYTHON",
            system_python
        );
        run(
            Command::new(&system_python).arg("-m").arg("venv").arg(venv),
            "creating the virtual environment for the Python tests (is python3-venv installed?)",
        );
    }
    let ready = succeeds(&python, &["-c", "import numpy, pytest"])
        && succeeds(&venv.join("bin/maturin"), &["--version"]);
    if !ready {
        run(
            Command::new(&python).args([
                "-m", "pip", "install", "--quiet", "maturin", "numpy", "pytest",
            ]),
            "installing maturin, numpy and pytest into target/python-venv (needs the package index)",
        );
    }
    python
}

#[test]
fn python_package_passes_pytest() {
    let root = workspace_root();
    let venv = root.join("target/python-venv");
    let python = virtual_environment(&venv);

    // maturin and the pip it calls are found through the environment's bin directory.
    let mut path = OsString::from(venv.join("bin"));
    if let Some(system_path) = std::env::var_os("PATH") {
        path.push(":");
        path.push(system_path);
    }
    let started = std::time::Instant::now();
    run(
        Command::new(venv.join("bin/maturin"))
            .current_dir(&root)
            .args([
                "develop",
                "--quiet",
                "--manifest-path",
                "bindings/python/Cargo.toml",
            ])
            .env("VIRTUAL_ENV", &venv)
            .env("PATH", &path)
            .env("CARGO_TARGET_DIR", target_dir(&root))
            .env_remove("CARGO_BUILD_TARGET")
            .env_remove("PYTHONHOME"),
        "building and installing the Python package (maturin develop)",
    );
    eprintln!("maturin develop: {:.1} s", started.elapsed().as_secs_f64());

    let output = Command::new(&python)
        .current_dir(&root)
        .args([
            "-m",
            "pytest",
            "bindings/python/tests",
            "-q",
            "-rs",
            "-p",
            "no:cacheprovider",
        ])
        .env("VIRTUAL_ENV", &venv)
        .env("PATH", &path)
        .env_remove("PYTHONHOME")
        .env_remove("PYTHONPATH")
        .output()
        .expect("pytest runs");
    let report = describe(&output);
    // Shown with `cargo test -- --nocapture`, and in full when a test fails.
    println!("{report}");
    assert!(
        output.status.success(),
        "pytest failed ({}):\n{report}",
        output.status
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains(" passed") && !stdout.contains(" failed"),
        "pytest ran no test:\n{report}"
    );
    for reason in skipped_tests(&stdout) {
        hystcomp_testkit::skip(format!("pytest: {reason}"));
    }
}

/// The skips pytest's `-rs` summary lists (`SKIPPED [1] tests/test_x.py:12: reason`), each as
/// `tests/test_x.py:12: reason`.
fn skipped_tests(stdout: &str) -> Vec<String> {
    stdout
        .lines()
        .filter_map(|line| line.strip_prefix("SKIPPED ["))
        .filter_map(|rest| rest.split_once("] "))
        .map(|(_, what)| what.trim().to_owned())
        .collect()
}

#[test]
fn pytest_skips_are_read_from_its_summary() {
    let summary = "..s.\n=== short test summary info ===\n\
        SKIPPED [1] bindings/python/tests/test_identify.py:103: the DBO data are not present\n\
        SKIPPED [2] bindings/python/tests/test_x.py:7: no data\n\
        40 passed, 3 skipped in 2.1s\n";
    assert_eq!(
        skipped_tests(summary),
        [
            "bindings/python/tests/test_identify.py:103: the DBO data are not present",
            "bindings/python/tests/test_x.py:7: no data",
        ]
    );
    assert!(skipped_tests("40 passed in 2.1s\n").is_empty());
}
