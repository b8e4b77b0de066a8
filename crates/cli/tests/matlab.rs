//! The MATLAB/Octave binding (`bindings/matlab`) under GNU Octave: `build.m` compiles the MEX
//! gateway with `mkoctfile --mex` against the C ABI's static library, then
//! `bindings/matlab/tests/test_hystcomp.m` runs its assertions (Table 1 round trips, the
//! identification of the shared DBO record against this command line's, every bad argument
//! refused with an identifier, freed handles, the Simulink S-function), and the example script
//! runs and draws its figure.
//!
//! It lives among the command line's tests because it compares the binding's identification
//! with the `hystcomp` binary's (`CARGO_BIN_EXE_hystcomp`): a nested build of the binary from
//! another crate's tests would rebuild its dependencies with other features (minutes).
//!
//! Octave is a prerequisite `.ci/run` installs (`octave`, `liboctave-dev`, `gnuplot-nox`,
//! `fonts-freefont-otf`, `ghostscript`): the test fails without it under CI and records a skip
//! elsewhere.

use std::path::Path;
use std::process::Command;

use hystcomp_testkit::{
    c_static_library, dbo_record, on_path, require_tool, run, target_dir, workspace_root,
};

/// Whether Octave and mkoctfile are here (a skip is logged when not; under CI a failure).
fn octave_here() -> bool {
    require_tool(
        "octave",
        on_path("octave-cli") && on_path("mkoctfile"),
        "apt-get install octave liboctave-dev gnuplot-nox fonts-freefont-otf ghostscript",
    )
}

/// An Octave string literal of a path.
fn quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', "''"))
}

/// Runs `script` in a fresh Octave (no init files, no history: nothing of the user's), from
/// the workspace root; its stdout, after asserting a zero exit status.
fn octave(script: &str) -> String {
    let output = run(
        Command::new("octave-cli")
            .args([
                "--no-init-file",
                "--no-history",
                "--quiet",
                "--eval",
                script,
            ])
            .current_dir(workspace_root()),
        "Octave must run the script without error",
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// `hystcomp identify` on the DBO record with the command line's defaults, into `output`.
fn identify_with_the_cli(record: &Path, direction: &str, output: &Path) {
    run(
        Command::new(env!("CARGO_BIN_EXE_hystcomp")).args([
            "identify",
            "--data",
            record.to_str().unwrap(),
            "--voltage-column",
            "1",
            "--displacement-column",
            "5",
            "--direction",
            direction,
            "-o",
            output.to_str().unwrap(),
        ]),
        "hystcomp identify must identify the DBO record",
    );
}

#[test]
fn octave_builds_the_mex_file_and_passes_the_binding_tests() {
    if !octave_here() {
        return;
    }
    let root = workspace_root();
    let library = c_static_library();
    let mexdir = target_dir().join("matlab");
    let scratch = tempfile::tempdir().expect("a temporary directory");
    let dbo = dbo_record("Model_Vi_Do.dat");
    let (record, plant, inverse) = match &dbo {
        Some(record) => {
            let plant = scratch.path().join("cli-plant.json");
            let inverse = scratch.path().join("cli-inverse.json");
            identify_with_the_cli(record, "plant", &plant);
            identify_with_the_cli(record, "inverse", &inverse);
            (quoted(record), quoted(&plant), quoted(&inverse))
        }
        // The Octave test says it skipped that part; the skip is logged by dbo_record.
        None => ("''".into(), "''".into(), "''".into()),
    };
    let matlab = root.join("bindings/matlab");
    let stdout = octave(&format!(
        "addpath({matlab}); \
         build('library', {library}, 'output', {mexdir}); \
         addpath(fullfile({matlab}, 'tests')); \
         test_hystcomp({mexdir}, {library}, {root}, {record}, {plant}, {inverse});",
        matlab = quoted(&matlab),
        library = quoted(library),
        mexdir = quoted(&mexdir),
        root = quoted(&root),
    ));
    println!("{stdout}");
    assert!(stdout.trim_end().ends_with("ALL PASSED"), "{stdout}");
    for test in [
        "round_trip_table1",
        "identification_matches_the_cli",
        "models_round_trip_through_files_and_structs",
        "models_with_creep_and_vibration_run_their_chain",
        "indices_match_a_plain_reference",
        "every_bad_argument_raises_an_error_with_an_identifier",
        "freed_and_forged_handles_are_refused",
        "simulink_s_function_steps_the_compensator",
    ] {
        assert!(
            stdout.contains(&format!("PASS {test}")),
            "{test} did not pass:\n{stdout}"
        );
    }
    if dbo.is_some() {
        assert!(
            !stdout.contains("identification_matches_the_cli (SKIPPED"),
            "{stdout}"
        );
    }
}

/// The first fenced block of `language` after `heading` in the Markdown file `path`.
fn block(path: &Path, heading: &str, language: &str) -> String {
    let text = std::fs::read_to_string(path).expect("the README exists");
    text.split(heading)
        .nth(1)
        .and_then(|rest| rest.split(&format!("```{language}\n")).nth(1))
        .and_then(|rest| rest.split("```").next())
        .unwrap_or_else(|| {
            panic!(
                "{} has a ```{language} block after {heading:?}",
                path.display()
            )
        })
        .to_owned()
}

#[test]
fn the_readme_blocks_and_the_example_run() {
    if !octave_here() {
        return;
    }
    let root = workspace_root();
    // Its own MEX directory: the other test builds into target/matlab at the same time.
    let mexdir = target_dir().join("matlab-readme");
    octave(&format!(
        "addpath(fullfile({root}, 'bindings', 'matlab')); \
         build('library', {library}, 'output', {mexdir});",
        root = quoted(&root),
        library = quoted(c_static_library()),
        mexdir = quoted(&mexdir),
    ));

    // The README's build lines, and its MATLAB block as written, from the repository's root.
    let readme = root.join("README.md");
    let build: Vec<String> = block(&readme, "\n### MATLAB and Octave\n", "sh")
        .lines()
        .map(str::to_owned)
        .collect();
    assert_eq!(build[0], "cargo build --release -p hystcomp-c");
    assert_eq!(build[1], "octave-cli --eval \"cd bindings/matlab; build\"");
    let example = block(&readme, "\n### MATLAB and Octave\n", "matlab");
    octave(&format!("addpath({}); {example}", quoted(&mexdir)));

    let Some(record) = dbo_record("Model_Vi_Do.dat") else {
        return;
    };
    // bindings/matlab/README.md's usage block, the shared record where it says, in a scratch
    // directory (it writes plant.json).
    let scratch = tempfile::tempdir().expect("a temporary directory");
    let usage = block(
        &root.join("bindings/matlab/README.md"),
        "\n## Use\n",
        "matlab",
    );
    let relative = "'../shared/data/dbo-micromanipulator/Model_Vi_Do.dat'";
    assert!(usage.contains(relative), "{usage}");
    let usage = usage.replace(relative, &quoted(&record));
    let stdout = octave(&format!(
        "addpath(fullfile({root}, 'bindings', 'matlab')); addpath({mexdir}); cd({scratch}); \
         {usage}",
        root = quoted(&root),
        mexdir = quoted(&mexdir),
        scratch = quoted(scratch.path()),
    ));
    assert!(scratch.path().join("plant.json").is_file(), "{stdout}");

    // The example script: the figures it prints and the figure it draws.
    let figure = scratch.path().join("example.png");
    let stdout = octave(&format!(
        "cd(fullfile({root}, 'bindings', 'matlab')); addpath(pwd); addpath({mexdir}); \
         record = {record}; figure_file = {figure}; \
         run(fullfile('examples', 'identify_and_compensate.m'));",
        root = quoted(&root),
        mexdir = quoted(&mexdir),
        record = quoted(&record),
        figure = quoted(&figure),
    ));
    assert!(
        stdout.contains("plant model:   fit 0.679 % RMS"),
        "{stdout}"
    );
    let ihc = stdout
        .lines()
        .find(|l| l.starts_with("IHC "))
        .expect("an IHC line");
    let indices: Vec<f64> = ihc
        .split_whitespace()
        .skip(1)
        .map(|x| x.parse().expect("a number"))
        .collect();
    // IHC inverts the plant model exactly: no tracking error on it, e_mhe the bins' slope.
    assert!(
        indices[0] < 1e-6 && indices[1] < 1e-6 && indices[2] < 1.1,
        "{ihc}"
    );
    let png = std::fs::read(&figure).expect("the example wrote its figure");
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 5000,
        "{} bytes",
        png.len()
    );
}
