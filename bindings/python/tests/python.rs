//! Runs the Python tests (pytest, `bindings/python/tests/test_*.py`) against the extension
//! module, so that `cargo test --workspace` tests the Python package too.
//!
//! 1. Finds or creates the virtual environment `target/python-venv` (`python3 -m venv`, then
//!    `pip install numpy pytest` from the package index) unless it already has them.
//! 2. Builds the extension module with the workspace's libraries
//!    (`hystcomp_testkit::workspace_libraries`: the outer `cargo test`'s features, so only the
//!    `cdylib` itself is new) and installs it as `maturin develop` does: the library as
//!    `python/hystcomp/_hystcomp.abi3.so` beside the package's Python files, and a `.pth` file
//!    in the environment naming `bindings/python/python`. (`maturin develop` resolved the
//!    extension's features alone and rebuilt the workspace's crates under it, two to three
//!    minutes of CI; `pip install ./bindings/python`, the README's way, builds through maturin
//!    as before.)
//! 3. `python -m pytest bindings/python/tests -q -rs`; a failure shows pytest's output, and
//!    every test pytest skipped is recorded with its reason by `hystcomp_testkit::skip`, so
//!    that CI lists it (cargo would count this one test as passed).
//!
//! `HYSTCOMP_PYTHON` names another interpreter than `python3` for creating the environment.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use hystcomp_testkit::{run, workspace_root};

fn describe(output: &Output) -> String {
    format!(
        "--- stdout\n{}\n--- stderr\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// `true` when `program args...` runs and succeeds.
fn succeeds(program: &Path, args: &[&str]) -> bool {
    Command::new(program)
        .args(args)
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The environment's interpreter, creating the environment and installing numpy and pytest
/// when they are missing.
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
    if !succeeds(&python, &["-c", "import numpy, pytest"]) {
        run(
            Command::new(&python).args(["-m", "pip", "install", "--quiet", "numpy", "pytest"]),
            "installing numpy and pytest into target/python-venv (needs the package index)",
        );
    }
    python
}

/// Installs the extension module built with the workspace's libraries into `venv` as
/// `maturin develop` installs it (see the module documentation).
fn install_extension(root: &Path, python: &Path) {
    let built = hystcomp_testkit::workspace_libraries().join("lib_hystcomp.so");
    assert!(built.is_file(), "{} was not built", built.display());
    let package = root.join("bindings/python/python");
    let module = package.join("hystcomp/_hystcomp.abi3.so");
    // Copied beside and renamed over the old one: a reader never sees half a library.
    let partial = package.join("hystcomp/_hystcomp.abi3.so.partial");
    std::fs::copy(&built, &partial)
        .unwrap_or_else(|e| panic!("copying {} to {}: {e}", built.display(), partial.display()));
    std::fs::rename(&partial, &module).unwrap_or_else(|e| {
        panic!(
            "renaming {} to {}: {e}",
            partial.display(),
            module.display()
        )
    });
    let output = run(
        Command::new(python).args([
            "-c",
            "import sysconfig; print(sysconfig.get_paths()['purelib'])",
        ]),
        "asking the environment's Python for its site-packages",
    );
    let site = PathBuf::from(String::from_utf8_lossy(&output.stdout).trim());
    std::fs::write(
        site.join("hystcomp.pth"),
        format!("{}\n", package.display()),
    )
    .unwrap_or_else(|e| panic!("writing hystcomp.pth in {}: {e}", site.display()));
}

#[test]
fn python_package_passes_pytest() {
    let root = workspace_root();
    let venv = root.join("target/python-venv");
    let python = virtual_environment(&venv);

    // Scripts the tests start find the environment's interpreter first.
    let mut path = OsString::from(venv.join("bin"));
    if let Some(system_path) = std::env::var_os("PATH") {
        path.push(":");
        path.push(system_path);
    }
    let started = std::time::Instant::now();
    install_extension(&root, &python);
    eprintln!(
        "building and installing the extension: {:.1} s",
        started.elapsed().as_secs_f64()
    );

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

/// What `python_package_passes_pytest` installs by hand is what `pip install ./bindings/python`
/// (maturin) builds: `pyproject.toml`'s module name is the crate's `cdylib` and `#[pymodule]`,
/// in the package under `python/` (the `.pth` file's directory).
#[test]
fn pyproject_names_the_module_the_test_installs() {
    let here = workspace_root().join("bindings/python");
    let read = |file: &str| {
        std::fs::read_to_string(here.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
    };
    let pyproject = read("pyproject.toml");
    assert!(
        pyproject.contains("module-name = \"hystcomp._hystcomp\"")
            && pyproject.contains("python-source = \"python\""),
        "{pyproject}"
    );
    let manifest = read("Cargo.toml");
    assert!(
        manifest.contains("name = \"_hystcomp\"") && manifest.contains("crate-type = [\"cdylib\"]"),
        "{manifest}"
    );
    assert!(read("src/lib.rs").contains("#[pymodule]\nfn _hystcomp("));
    assert!(here.join("python/hystcomp/__init__.py").is_file());
}
