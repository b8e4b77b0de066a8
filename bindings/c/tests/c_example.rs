//! The C example `examples/c/round_trip.c`, compiled with gcc against the committed header and
//! the static library, linked and run against the paper's Table 1 model: the round trip
//! `P[C[y_d]] = y_d` holds, every voltage stays within the limits, and bad input gives a status
//! and a message.
//!
//! The static library is built by a nested cargo in the outer build's target directory (it is
//! usually fresh already: `cargo test` builds the library's every crate type); the examples are
//! compiled into `<target>/c-examples`.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;
use std::sync::{Arc, Mutex, OnceLock, PoisonError, RwLock};

use hystcomp_testkit::{available, c_static_library, run, target_dir, workspace_root};

/// Compiles `examples/c/{name}.c` against the committed header and the static library, with
/// every warning an error; the path of the executable.
fn compile_example(name: &str) -> PathBuf {
    compile(&format!("examples/c/{name}.c"), name)
}

/// The C programs, by name: each compiled once per test run ([`compile`]).
static PROGRAMS: Mutex<BTreeMap<String, Arc<OnceLock<PathBuf>>>> = Mutex::new(BTreeMap::new());

/// Read while gcc links a program against the static library, written while `make` may rebuild
/// that library (`makefile_builds_and_runs_both_examples`).
static LIBRARY: RwLock<()> = RwLock::new(());

/// Compiles the C source `source` (relative to the workspace root) into the executable `name`
/// in `<target>/c-examples`, as [`compile_example`], once per test run: the tests run in
/// parallel and several run the same program (the learner, the models program), and a second
/// gcc writing the executable while another test ran it failed that test with "Permission
/// denied". A test asking for a program being compiled waits for it; different programs
/// compile side by side.
fn compile(source: &str, name: &str) -> PathBuf {
    let slot = Arc::clone(
        PROGRAMS
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .entry(name.to_owned())
            .or_default(),
    );
    // A test that panicked while compiling left the slot empty: the next one compiles.
    slot.get_or_init(|| compile_now(source, name)).clone()
}

/// [`compile`]'s gcc run.
fn compile_now(source: &str, name: &str) -> PathBuf {
    let root = workspace_root();
    let library = c_static_library();
    assert!(
        available("gcc"),
        "gcc is needed to compile examples/c (apt-get install gcc)"
    );
    let examples = target_dir().join("c-examples");
    std::fs::create_dir_all(&examples).expect("the examples' directory can be created");
    let program = examples.join(name);
    let _library = LIBRARY.read().unwrap_or_else(PoisonError::into_inner);
    run(
        Command::new("gcc")
            .current_dir(&root)
            .args([
                "-std=c99",
                "-O2",
                "-Wall",
                "-Wextra",
                "-Werror",
                "-pedantic",
            ])
            .args(["-I", "bindings/c/include"])
            .arg(source)
            .arg(library)
            .args(["-lpthread", "-ldl", "-lm", "-o"])
            .arg(&program),
        &format!("{source} must compile without warnings against the committed header"),
    );
    program
}

fn round_trip_program() -> PathBuf {
    compile_example("round_trip")
}

#[test]
fn readme_c_example_is_examples_c_minimal_and_runs() {
    let root = workspace_root();
    let snippets = std::fs::read_to_string(root.join("README.md")).expect("README.md exists");
    let block = snippets
        .split("```c\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("the README has a ```c block");
    let minimal = std::fs::read_to_string(root.join("examples/c/minimal.c")).unwrap();
    assert_eq!(
        block, minimal,
        "the C block of README.md must be examples/c/minimal.c verbatim"
    );
    let output = run(
        Command::new(compile_example("minimal")).current_dir(&root),
        "the minimal C example must run",
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.starts_with("40 um -> "), "{stdout}");
    assert!(
        stdout.trim_end().ends_with(" V -> 40.000000 um"),
        "{stdout}"
    );
}

#[test]
fn c_round_trip_through_table1_model_is_exact() {
    let root = workspace_root();
    let output = run(
        Command::new(round_trip_program())
            .current_dir(&root)
            .arg("models/table1-plant.json"),
        "the C example must pass its own checks",
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("round trip OK"), "{stdout}");
    assert!(stdout.contains("drive limits [0, 10] V"), "{stdout}");
    // Both round trips (step and in-place process) report their worst error; parse them back.
    let errors: Vec<f64> = stdout
        .lines()
        .filter_map(|l| l.split("y_d| = ").nth(1))
        .map(|e| e.trim_end_matches(" um").parse().expect("a number"))
        .collect();
    assert_eq!(errors.len(), 2, "{stdout}");
    assert!(errors.iter().all(|e| *e < 1e-9), "{errors:?}");
    assert!(
        stdout.contains(
            "missing file: file could not be read: cannot read no-such-model.json: No such file"
        ),
        "{stdout}"
    );
    assert!(
        stdout.contains("NULL handle: null pointer: compensator handle is NULL"),
        "{stdout}"
    );
}

#[test]
fn c_program_identifies_saves_loads_compensates_and_scores() {
    let program = compile("bindings/c/tests/c/models.c", "models");
    let dir = tempfile::tempdir().expect("a temporary directory");
    let output = run(
        Command::new(program).arg(dir.path()),
        "bindings/c/tests/c/models.c must pass its own checks",
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.starts_with("models OK: fit "), "{stdout}");
    assert!(dir.path().join("identified.json").is_file());
}

/// Issue 10 in C: `for_delayed` (the bound, its cost, the delayed WIHC then built),
/// `operators_auto` (the choice in the report) and `hystcomp_predict` (per-sample prediction and
/// error, the summary, refusals that write nothing).
#[test]
fn c_program_identifies_for_delayed_with_auto_order_and_predicts() {
    let program = compile(
        "bindings/c/tests/c/delayed_auto_predict.c",
        "delayed_auto_predict",
    );
    let output = run(
        &mut Command::new(program),
        "bindings/c/tests/c/delayed_auto_predict.c must pass its own checks",
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.starts_with("delayed_auto_predict OK: "), "{stdout}");
}

#[test]
fn c_program_learns_between_trials_and_is_stopped_by_the_guard() {
    let program = compile("bindings/c/tests/c/learner.c", "learner");
    let output = run(
        Command::new(program)
            .current_dir(workspace_root())
            .arg("models/table1-plant.json"),
        "bindings/c/tests/c/learner.c must pass its own checks",
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.starts_with("learner OK: e_rms "), "{stdout}");
}

#[test]
fn c_example_refuses_an_inverse_model_with_the_reason() {
    let output = Command::new(round_trip_program())
        .current_dir(workspace_root())
        .arg("models/table2-inverse.json")
        .output()
        .expect("the example runs");
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr
            .contains("hystcomp_compensator_from_model_file failed: model of the wrong direction")
            && stderr.contains("ihc needs a plant model"),
        "{stderr}"
    );
}

#[test]
fn c_example_without_arguments_prints_its_usage() {
    let output = Command::new(round_trip_program())
        .output()
        .expect("the example runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("usage:"));
}

/// The ```sh block of the README's "### C" subsection, one command per line.
fn readme_c_commands() -> Vec<String> {
    let readme = std::fs::read_to_string(workspace_root().join("README.md")).unwrap();
    let section = readme
        .split("\n### C\n")
        .nth(1)
        .and_then(|rest| rest.split("\n### ").next())
        .expect("the README has a ### C subsection");
    section
        .split("```sh\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("the C subsection has a ```sh block")
        .lines()
        .map(str::to_owned)
        .collect()
}

#[test]
fn readme_c_build_commands_work_from_the_repository_root() {
    let commands = readme_c_commands();
    assert_eq!(commands[0], "cargo build --release -p hystcomp-c");
    assert_eq!(commands.len(), 3, "{commands:?}");
    // The gcc line as written, with the library of this (debug) build instead of the release
    // one and the executable in the target directory; every other path is the README's,
    // relative to the repository's root.
    let release = "target/release/libhystcomp.a";
    let gcc: Vec<&str> = commands[1].split_whitespace().collect();
    assert_eq!(gcc[0], "gcc");
    assert!(
        gcc.contains(&release) && gcc.contains(&"examples/c/minimal.c"),
        "{gcc:?}"
    );
    let output_at = gcc.iter().position(|a| *a == "-o").expect("gcc -o NAME");
    assert_eq!(commands[2], format!("./{}", gcc[output_at + 1]));
    let program = target_dir().join("c-examples").join("readme-minimal");
    std::fs::create_dir_all(program.parent().unwrap()).unwrap();
    let library = c_static_library();
    let args: Vec<std::ffi::OsString> = gcc[1..]
        .iter()
        .enumerate()
        .map(|(i, a)| match *a {
            a if a == release => library.clone().into_os_string(),
            _ if i == output_at => program.clone().into_os_string(),
            a => a.into(),
        })
        .collect();
    run(
        Command::new("gcc")
            .current_dir(workspace_root())
            .args(&args),
        "the README's gcc line must work from the repository's root",
    );
    let output = run(
        Command::new(&program).current_dir(workspace_root()),
        "the README's C example must run from the repository's root",
    );
    assert!(String::from_utf8_lossy(&output.stdout).ends_with(" V -> 40.000000 um\n"));
}

/// The gcc line of the README's C build commands, split into words.
fn readme_gcc_line() -> Vec<String> {
    readme_c_commands()[1]
        .split_whitespace()
        .map(str::to_owned)
        .collect()
}

#[test]
fn makefile_links_the_library_the_readme_builds() {
    assert!(available("make"), "make is needed (apt-get install make)");
    // What `make -C examples/c` would do, without doing it (a release build takes minutes).
    let output = run(
        Command::new("make")
            .args(["-n", "-C", "examples/c", "all"])
            .env_remove("CARGO_TARGET_DIR")
            .env_remove("PROFILE")
            .current_dir(workspace_root()),
        "make -n -C examples/c must print its commands",
    );
    let plan = String::from_utf8_lossy(&output.stdout);
    let cargo_line = readme_c_commands()[0].clone();
    assert!(plan.contains(&cargo_line), "{cargo_line:?} not in:\n{plan}");
    let library = readme_gcc_line()
        .into_iter()
        .find(|w| w.ends_with("libhystcomp.a"))
        .expect("the README's gcc line links libhystcomp.a");
    let linked = workspace_root().join(&library);
    assert!(
        plan.contains(&linked.display().to_string()),
        "the Makefile must link {library} as the README does:\n{plan}"
    );
}

#[test]
fn what_the_readme_c_steps_build_is_ignored_by_git() {
    let gcc = readme_gcc_line();
    let output_at = gcc.iter().position(|a| a == "-o").expect("gcc -o NAME");
    // The README's executable (at the root) and the Makefile's (in examples/c).
    let built = [
        gcc[output_at + 1].clone(),
        "examples/c/minimal".to_owned(),
        "examples/c/round_trip".to_owned(),
    ];
    for path in built {
        let ignored = Command::new("git")
            .current_dir(workspace_root())
            .args(["check-ignore", "-q", "--no-index", &path])
            .status()
            .expect("git runs");
        if ignored.code() == Some(128) {
            hystcomp_testkit::skip("not a git checkout: .gitignore not checked");
            return;
        }
        assert!(ignored.success(), "{path} is not in .gitignore");
    }
}

#[test]
fn makefile_builds_and_runs_both_examples() {
    assert!(available("make"), "make is needed (apt-get install make)");
    c_static_library();
    let out = target_dir().join("c-examples").join("make");
    let _ = std::fs::remove_dir_all(&out);
    // The Makefile runs cargo, which rewrites the static library if it is not fresh: not while
    // another test's gcc reads it.
    let _library = LIBRARY.write().unwrap_or_else(PoisonError::into_inner);
    let output = run(
        Command::new("make")
            .args(["-C", "examples/c", "run", "PROFILE=debug"])
            .arg(format!("OUT={}", out.display()))
            // The build `workspace_libraries` made (the default `-p hystcomp-c` resolves other
            // features and rebuilt the crates under it, two minutes in CI).
            .arg("CARGO_PACKAGES=--workspace --lib --tests")
            .env("CARGO_TARGET_DIR", target_dir())
            .current_dir(workspace_root()),
        "make -C examples/c run must build and run both examples",
    );
    assert!(out.join("minimal").is_file() && out.join("round_trip").is_file());
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains(" V -> 40.000000 um"), "{stdout}");
    assert!(stdout.contains("round trip OK"), "{stdout}");
}

fn bank_program() -> PathBuf {
    compile("bindings/c/tests/c/bank.c", "bank")
}

/// The arguments of `bindings/c/tests/c/bank.c`: the three-axis set, Table 1's plant model and
/// Table 2's inverse model.
const BANK_ARGS: [&str; 3] = [
    "models/table1-xyz-set.json",
    "models/table1-plant.json",
    "models/table2-inverse.json",
];

/// The bank from C (issue 16): a bank from a model set and from models in memory, stepped and
/// processed (also in place), every channel bit for bit its own compensator for IHC, WIHC and
/// their guarded loops; per-channel limits and diagnostics (a NaN counted on its channel
/// only, saturation where the position is beyond reach); refused channels named by index.
#[test]
fn c_bank_program_steps_every_channel_as_its_own_compensator() {
    let output = run(
        Command::new(bank_program())
            .current_dir(workspace_root())
            .args(BANK_ARGS),
        "the C bank program must pass its own checks",
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(stdout.trim_end(), "bank OK");
}

/// The C programs run under valgrind's memcheck: no invalid read or write, no use of an
/// uninitialised value, no definite leak through the C ABI, on success (the round trip, the
/// identify-save-load-compensate program, the learner, the bank) and on refusals (an inverse
/// model, no arguments).
#[test]
fn c_programs_run_clean_under_valgrind() {
    if !hystcomp_testkit::require_tool(
        "valgrind",
        available("valgrind"),
        "apt-get install valgrind",
    ) {
        return;
    }
    let dir = tempfile::tempdir().expect("a temporary directory");
    let models = compile("bindings/c/tests/c/models.c", "models");
    let learner = compile("bindings/c/tests/c/learner.c", "learner");
    let delayed_auto_predict = compile(
        "bindings/c/tests/c/delayed_auto_predict.c",
        "delayed_auto_predict",
    );
    let runs: Vec<(PathBuf, Vec<std::ffi::OsString>, i32)> = vec![
        (
            round_trip_program(),
            vec!["models/table1-plant.json".into()],
            0,
        ),
        (
            round_trip_program(),
            vec!["models/table2-inverse.json".into()],
            1,
        ),
        (round_trip_program(), vec![], 2),
        (models, vec![dir.path().into()], 0),
        (learner, vec!["models/table1-plant.json".into()], 0),
        (delayed_auto_predict, vec![], 0),
        (
            bank_program(),
            BANK_ARGS.iter().map(Into::into).collect(),
            0,
        ),
        (bank_program(), vec![], 2),
    ];
    for (program, args, code) in runs {
        let output = Command::new("valgrind")
            .args([
                "--error-exitcode=99",
                "--leak-check=full",
                "--show-leak-kinds=definite",
                "--errors-for-leak-kinds=definite",
                "-q",
            ])
            .arg(&program)
            .args(&args)
            .current_dir(workspace_root())
            .output()
            .expect("valgrind runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(
            output.status.code(),
            Some(code),
            "{} {args:?} under valgrind:\n{stderr}",
            program.display()
        );
        assert!(
            !stderr.contains("=="),
            "{} {args:?}: valgrind reported\n{stderr}",
            program.display()
        );
    }
}
