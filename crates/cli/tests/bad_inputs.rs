//! Bad inputs through the built binary, one case per defect of issue 13 and per refusal the
//! command line already made: for each, the exit status (non-zero, or success for files that
//! are now accepted), a message on stderr naming the file, row or option, no panic or abort,
//! no output file left behind and no input file changed.

mod common;

use common::*;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The files most cases start from, in a fresh temporary folder.
struct Fixture {
    dir: tempfile::TempDir,
}

impl Fixture {
    fn new() -> Self {
        let fixture = Fixture {
            dir: tempfile::tempdir().unwrap(),
        };
        for name in ["table1-plant.json", "table2-inverse.json"] {
            std::fs::copy(models().join(name), fixture.path(name)).unwrap();
        }
        std::fs::copy(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../stage/stages/default.toml"),
            fixture.path("stage.toml"),
        )
        .unwrap();
        fixture.write("trajectory.csv", &trajectory_csv());
        fixture.write("volts.csv", &volts_csv(10_000.0, 400));
        fixture.write("record.csv", &record_csv());
        fixture
    }

    fn write_bytes(&self, name: &str, contents: &[u8]) -> String {
        std::fs::write(self.path(name), contents).unwrap();
        self.arg(name)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// The path as an argument.
    fn arg(&self, name: &str) -> String {
        self.path(name).to_str().unwrap().to_owned()
    }

    fn write(&self, name: &str, contents: &str) -> String {
        std::fs::write(self.path(name), contents).unwrap();
        self.arg(name)
    }
}

/// A reachable desired trajectory for the Table 1 plant (time_s, desired_um), 1000 samples.
fn trajectory_csv() -> String {
    let file = hystcomp_io::model_file::ModelFile::load(&models().join("table1-plant.json"))
        .expect("the example model loads");
    let mut plant = file.model().unwrap();
    let mut text = String::from("time_s,desired_um\n");
    for k in 0..1000 {
        let t = k as f64 * 1e-3;
        let v = 5.0 - 4.0 * (2.0 * std::f64::consts::PI * 5.0 * t).cos();
        let y = file.output_to_physical(plant.step(file.normalise_input(v)));
        text.push_str(&format!("{t},{y}\n"));
    }
    text
}

/// One period of a 5 Hz sine of 30 +- 10 um at the built-in stage's 10 kHz (time_s,
/// desired_um), 2000 samples: what `learn --simulate` plays.
fn desired_10khz_csv() -> String {
    let mut text = String::from("time_s,desired_um\n");
    for k in 0..2000 {
        let t = k as f64 * 1e-4;
        let y = 30.0 + 10.0 * (2.0 * std::f64::consts::PI * 5.0 * t).sin();
        text.push_str(&format!("{t},{y}\n"));
    }
    text
}

/// A command record (time_s, volts) at `rate_hz`.
fn volts_csv(rate_hz: f64, n: usize) -> String {
    let mut text = String::from("time_s,volts\n");
    for k in 0..n {
        let t = k as f64 / rate_hz;
        let v = 4.0 - 4.0 * (2.0 * std::f64::consts::PI * 2.0 * t).cos();
        text.push_str(&format!("{t},{v}\n"));
    }
    text
}

/// A measured record (time_s, voltage_v, displacement_um) through the Table 1 plant, with
/// nested reversals.
fn record_csv() -> String {
    let file = hystcomp_io::model_file::ModelFile::load(&models().join("table1-plant.json"))
        .expect("the example model loads");
    let mut plant = file.model().unwrap();
    let mut text = String::from("time_s,voltage_v,displacement_um\n");
    for k in 0..2000 {
        let t = k as f64 * 1e-3;
        let envelope = 1.0 - 0.8 * t / 2.0;
        let v = 5.0 - 4.5 * envelope * (2.0 * std::f64::consts::PI * 3.0 * t).cos();
        let y = file.output_to_physical(plant.step(file.normalise_input(v)));
        text.push_str(&format!("{t},{v},{y}\n"));
    }
    text
}

/// What a case expects.
enum Expect {
    /// Refused with this exit code and every fragment in the message.
    Refused(i32, Vec<String>),
    /// Accepted (exit 0), the output written.
    Accepted,
    /// The work done and the output written, but the drive clamped: exit 4 and every fragment
    /// in the message.
    Saturated(Vec<String>),
}

/// One bad input: a command line in a fixture, what it must do, and the files it must leave
/// alone.
struct Case {
    name: &'static str,
    args: Vec<String>,
    /// The command's output (file or directory): must not exist after a refusal.
    output: Option<PathBuf>,
    expect: Expect,
    /// A `--json` run: stdout must be one JSON document when the command succeeds, empty
    /// when it is refused.
    json: bool,
}

impl Case {
    fn refused<S: Into<String>>(
        name: &'static str,
        args: impl IntoIterator<Item = S>,
        code: i32,
        fragments: &[&str],
    ) -> Self {
        Case {
            name,
            args: args.into_iter().map(Into::into).collect(),
            output: None,
            expect: Expect::Refused(code, fragments.iter().map(|f| f.to_string()).collect()),
            json: false,
        }
    }

    fn saturated<S: Into<String>>(
        name: &'static str,
        args: impl IntoIterator<Item = S>,
        fragments: &[&str],
    ) -> Self {
        Case {
            name,
            args: args.into_iter().map(Into::into).collect(),
            output: None,
            expect: Expect::Saturated(fragments.iter().map(|f| f.to_string()).collect()),
            json: false,
        }
    }

    fn json(mut self) -> Self {
        self.json = true;
        self
    }

    fn accepted<S: Into<String>>(name: &'static str, args: impl IntoIterator<Item = S>) -> Self {
        Case {
            name,
            args: args.into_iter().map(Into::into).collect(),
            output: None,
            expect: Expect::Accepted,
            json: false,
        }
    }

    fn output(mut self, path: PathBuf) -> Self {
        self.output = Some(path);
        self
    }
}

/// Every file under `dir` with its bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                files.insert(path.clone(), std::fs::read(&path).unwrap());
            }
        }
    }
    files
}

/// Runs `case` in `fixture` and checks everything the issue asks; returns a description of
/// what went wrong, if anything.
fn check(fixture: &Fixture, case: &Case) -> Result<(), String> {
    let before = snapshot(fixture.dir.path());
    let out = Command::new(env!("CARGO_BIN_EXE_hystcomp"))
        .args(&case.args)
        .current_dir(fixture.dir.path())
        .output()
        .expect("the hystcomp binary runs");
    let message = stderr(&out);
    let code = out.status.code();
    let mut problems = Vec::new();
    if code.is_none() || code == Some(101) || code == Some(134) || message.contains("panicked") {
        problems.push(format!("crashed ({:?}): {message}", out.status));
    }
    let after = snapshot(fixture.dir.path());
    for (path, bytes) in &before {
        match after.get(path) {
            Some(now) if now == bytes => {}
            Some(_) => problems.push(format!("input {} changed", path.display())),
            None => problems.push(format!("input {} removed", path.display())),
        }
    }
    let created: Vec<&PathBuf> = after.keys().filter(|p| !before.contains_key(*p)).collect();
    if case.json {
        let text = stdout(&out);
        let parses = serde_json::from_str::<serde_json::Value>(&text).is_ok();
        match (code, parses, text.trim().is_empty()) {
            (Some(0) | Some(4), true, _) | (Some(1..=3), _, true) => {}
            _ => problems.push(format!("stdout of a --json run: {text:?}")),
        }
    }
    let stray_temporary = created.iter().find(|p| {
        p.file_name()
            .is_some_and(|n| n.to_string_lossy().ends_with(".tmp"))
    });
    if let Some(stray) = stray_temporary {
        problems.push(format!("temporary file left behind: {}", stray.display()));
    }
    match &case.expect {
        Expect::Refused(expected, fragments) => {
            if code != Some(*expected) {
                problems.push(format!("exit {code:?}, expected {expected}: {message}"));
            }
            for fragment in fragments {
                if !message.contains(fragment.as_str()) {
                    problems.push(format!("{fragment:?} not in the message: {message}"));
                }
            }
            if !created.is_empty() {
                problems.push(format!("files left behind: {created:?}"));
            }
            if let Some(output) = &case.output
                && !before.contains_key(output)
                && output.exists()
            {
                problems.push(format!("output {} left behind", output.display()));
            }
        }
        Expect::Accepted => {
            if code != Some(0) {
                problems.push(format!("exit {code:?}, expected success: {message}"));
            }
            if let Some(output) = &case.output
                && !output.exists()
            {
                problems.push(format!("output {} not written", output.display()));
            }
        }
        Expect::Saturated(fragments) => {
            if code != Some(4) {
                problems.push(format!("exit {code:?}, expected 4 (saturated): {message}"));
            }
            for fragment in fragments {
                if !message.contains(fragment.as_str()) {
                    problems.push(format!("{fragment:?} not in the message: {message}"));
                }
            }
            if let Some(output) = &case.output
                && !output.exists()
            {
                problems.push(format!("output {} not written", output.display()));
            }
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("\n    "))
    }
}

/// Runs every case, each in a fresh fixture, and reports all failures at once.
fn run_cases(cases: Vec<(Fixture, Case)>) -> usize {
    let count = cases.len();
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|(fixture, case)| {
            check(fixture, case)
                .err()
                .map(|e| format!("{}: {:?}\n    {e}", case.name, case.args))
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    count
}

/// Issue 13, "Inputs overwritten": every command that writes refuses an output naming one of
/// its inputs, by any spelling, before reading anything.
fn overwritten_inputs() -> Vec<(Fixture, Case)> {
    let mut cases = Vec::new();
    let mut add = |build: &dyn Fn(&Fixture) -> Case| {
        let fixture = Fixture::new();
        let case = build(&fixture);
        cases.push((fixture, case));
    };
    let compensate = |f: &Fixture, output: &str| -> Vec<String> {
        [
            "compensate",
            "--model",
            &f.arg("table1-plant.json"),
            "--method",
            "ihc",
            "--desired",
            &f.arg("trajectory.csv"),
            "-o",
            output,
        ]
        .map(str::to_owned)
        .to_vec()
    };
    add(&|f| {
        Case::refused(
            "compensate -o the trajectory",
            compensate(f, &f.arg("trajectory.csv")),
            1,
            &["--output", "same file as --desired", "trajectory.csv"],
        )
    });
    add(&|f| {
        Case::refused(
            "compensate -o the model",
            compensate(f, &f.arg("table1-plant.json")),
            1,
            &["same file as --model", "table1-plant.json"],
        )
    });
    add(&|f| {
        std::fs::create_dir(f.path("sub")).unwrap();
        Case::refused(
            "compensate -o the trajectory by a relative path through ..",
            compensate(f, "sub/../trajectory.csv"),
            1,
            &["same file as --desired"],
        )
    });
    #[cfg(unix)]
    add(&|f| {
        std::os::unix::fs::symlink(f.path("trajectory.csv"), f.path("link.csv")).unwrap();
        Case::refused(
            "compensate -o a symbolic link to the trajectory",
            compensate(f, &f.arg("link.csv")),
            1,
            &["same file as --desired"],
        )
    });
    #[cfg(unix)]
    add(&|f| {
        std::fs::hard_link(f.path("trajectory.csv"), f.path("hard.csv")).unwrap();
        Case::refused(
            "compensate -o a hard link to the trajectory",
            compensate(f, &f.arg("hard.csv")),
            1,
            &["same file as --desired"],
        )
    });
    let simulate = |f: &Fixture, output: &str| -> Vec<String> {
        [
            "simulate",
            "--stage",
            &f.arg("stage.toml"),
            "--drive",
            &f.arg("volts.csv"),
            "-o",
            output,
        ]
        .map(str::to_owned)
        .to_vec()
    };
    add(&|f| {
        Case::refused(
            "simulate -o the input record",
            simulate(f, &f.arg("volts.csv")),
            1,
            &["same file as --drive", "volts.csv"],
        )
    });
    add(&|f| {
        Case::refused(
            "simulate -o the stage file",
            simulate(f, &f.arg("stage.toml")),
            1,
            &["same file as --stage", "stage.toml"],
        )
    });
    add(&|f| {
        Case::refused(
            "identify -o the record",
            [
                "identify",
                "--data",
                &f.arg("record.csv"),
                "--voltage-column",
                "2",
                "--displacement-column",
                "3",
                "-o",
                &f.arg("record.csv"),
            ],
            1,
            &["same file as --data", "record.csv"],
        )
    });
    for (option, input) in [("--save-plant", "--train"), ("--save-inverse", "--test")] {
        add(&move |f| {
            f.write("test.csv", &record_csv());
            let target = if input == "--train" {
                "record.csv"
            } else {
                "test.csv"
            };
            Case::refused(
                "crossval saving a model over a record",
                [
                    "crossval",
                    "--train",
                    &f.arg("record.csv"),
                    "--test",
                    &f.arg("test.csv"),
                    "--voltage-column",
                    "2",
                    "--displacement-column",
                    "3",
                    option,
                    &f.arg(target),
                ],
                1,
                &[option, &format!("same file as {input}")],
            )
        });
    }
    add(&|f| {
        Case::refused(
            "crossval saving both models to one file",
            [
                "crossval",
                "--train",
                &f.arg("record.csv"),
                "--test",
                &f.arg("record.csv"),
                "--voltage-column",
                "2",
                "--displacement-column",
                "3",
                "--save-plant",
                &f.arg("models.json"),
                "--save-inverse",
                &f.arg("./models.json"),
            ],
            1,
            &["--save-plant", "--save-inverse", "same place"],
        )
        .output(f.path("models.json"))
    });
    add(&|f| {
        // The last trial's drive and response (any records of the trajectory's length).
        f.write("drive.csv", &trajectory_csv());
        f.write("measured.csv", &trajectory_csv());
        Case::refused(
            "learn -o the last trial's drive",
            [
                "learn",
                "--desired",
                &f.arg("trajectory.csv"),
                "--drive",
                &f.arg("drive.csv"),
                "--measured",
                &f.arg("measured.csv"),
                "--model",
                &f.arg("table1-plant.json"),
                "-o",
                &f.arg("drive.csv"),
            ],
            1,
            &["--output", "same file as --drive", "drive.csv"],
        )
    });
    add(&|f| {
        std::fs::create_dir(f.path("report")).unwrap();
        std::fs::copy(f.path("stage.toml"), f.path("report/stage.toml")).unwrap();
        Case::refused(
            "reproduce --out the folder holding the stage file",
            [
                "reproduce",
                "--stage",
                &f.arg("report/stage.toml"),
                "--output",
                &f.arg("report"),
            ],
            1,
            &["--output", "holds the input --stage"],
        )
    });
    cases
}

#[test]
fn no_command_overwrites_its_inputs() {
    let count = run_cases(overwritten_inputs());
    assert!(count >= 10);
}

#[test]
fn the_protected_commands_still_write_new_outputs() {
    let f = Fixture::new();
    let out = f.path("drive.csv");
    let case = Case::accepted(
        "compensate to a new file",
        [
            "compensate",
            "--model",
            &f.arg("table1-plant.json"),
            "--method",
            "ihc",
            "--desired",
            &f.arg("trajectory.csv"),
            "-o",
            "drive.csv",
        ],
    )
    .output(out);
    check(&f, &case).unwrap();
}

/// Issue 13, "Broken pipe": a reader that closes stdout before the command prints leaves
/// every command exiting with its usual status, without a panic or a message about the pipe.
#[test]
#[allow(clippy::incompatible_msrv)] // std::io::pipe, in a test only
fn a_closed_stdout_ends_every_command_quietly() {
    let f = Fixture::new();
    f.write("test.csv", &record_csv());
    f.write("desired.csv", &desired_10khz_csv());
    let commands: Vec<Vec<String>> = vec![
        vec![
            "--json",
            "evaluate",
            "--desired",
            "trajectory.csv",
            "--measured",
            "trajectory.csv",
        ],
        vec![
            "evaluate",
            "--desired",
            "trajectory.csv",
            "--measured",
            "trajectory.csv",
        ],
        vec![
            "crossval",
            "--train",
            "record.csv",
            "--test",
            "test.csv",
            "--voltage-column",
            "2",
            "--displacement-column",
            "3",
        ],
        vec![
            "--json",
            "crossval",
            "--train",
            "record.csv",
            "--test",
            "test.csv",
            "--voltage-column",
            "2",
            "--displacement-column",
            "3",
        ],
        vec![
            "identify",
            "--data",
            "record.csv",
            "--voltage-column",
            "2",
            "--displacement-column",
            "3",
            "-o",
            "model.json",
        ],
        vec![
            "compensate",
            "--model",
            "table1-plant.json",
            "--method",
            "ihc",
            "--desired",
            "trajectory.csv",
            "-o",
            "drive.csv",
        ],
        vec!["simulate", "--drive", "volts.csv", "-o", "response.csv"],
        vec!["bench", "--samples", "100", "--repeats", "1"],
        vec!["signal", "paper", "-o", "paper.csv"],
        vec![
            "learn",
            "--simulate",
            "--desired",
            "desired.csv",
            "--model",
            "table1-plant.json",
            "--trials",
            "1",
            "--periods",
            "1",
            "-o",
            "next.csv",
        ],
    ]
    .into_iter()
    .map(|args| args.into_iter().map(str::to_owned).collect())
    .collect();
    for args in commands {
        // What the command says about its work with stdout open (warm-up and start notes,
        // compensate's feasibility warning: the fixture's trajectory starts away from rest) ...
        let open = Command::new(env!("CARGO_BIN_EXE_hystcomp"))
            .args(&args)
            .current_dir(f.dir.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        assert_eq!(open.status.code(), Some(0), "{args:?}: {}", stderr(&open));
        // ... is all it may say with stdout closed: nothing about the pipe.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_hystcomp"))
            .args(&args)
            .current_dir(f.dir.path())
            .stdout(writer)
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {message}");
        assert_eq!(
            message,
            stderr(&open),
            "{args:?}: stdout closed, it said more than with stdout open"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Issue 13's matrix: one case per defect, the files it asks to accept, and the refusals the
// command line already made
// ---------------------------------------------------------------------------------------------

#[path = "../../io/tests/common/mat5.rs"]
mod mat5;

/// `text` with `;` between fields and decimal commas, as Excel writes CSV in European locales.
fn european(text: &str) -> String {
    text.replace(',', ";").replace('.', ",")
}

/// The Table 1 model file with `from` replaced by `to` (once).
fn edited_model(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(models().join("table1-plant.json")).unwrap();
    let edited = text.replacen(from, to, 1);
    assert_ne!(edited, text, "{from} is in the model file");
    edited
}

/// `identify` of `data` (voltage in column 2, displacement in column 3) into `model.json`.
fn identify(f: &Fixture, data: &str, extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = [
        "identify",
        "--data",
        data,
        "--voltage-column",
        "2",
        "--displacement-column",
        "3",
        "-o",
        &f.arg("model.json"),
    ]
    .map(str::to_owned)
    .to_vec();
    args.extend(extra.iter().map(|a| a.to_string()));
    args
}

/// `compensate` with the model `model` on the desired trajectory `desired` into `drive.csv`.
fn compensate(f: &Fixture, model: &str, desired: &str, extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = [
        "compensate",
        "--model",
        model,
        "--method",
        "ihc",
        "--desired",
        desired,
        "-o",
        &f.arg("drive.csv"),
    ]
    .map(str::to_owned)
    .to_vec();
    args.extend(extra.iter().map(|a| a.to_string()));
    args
}

/// `evaluate` of `measured` against the reachable trajectory.
fn evaluate(f: &Fixture, measured: &str) -> Vec<String> {
    [
        "evaluate",
        "--desired",
        &f.arg("trajectory.csv"),
        "--measured",
        measured,
    ]
    .map(str::to_owned)
    .to_vec()
}

/// A MAT-file of one int8 and one double record (int8 made the `matfile` crate print on
/// stdout), variables `volts` and `um`, through the Table 1 plant.
fn int8_record_mat() -> Vec<u8> {
    let file = hystcomp_io::model_file::ModelFile::load(&models().join("table1-plant.json"))
        .expect("the example model loads");
    let mut plant = file.model().unwrap();
    let volts: Vec<i8> = (0..1500)
        .map(|k| {
            let t = k as f64 / 200.0;
            (5.0 - 5.0 * (-t / 3.0).exp() * (2.0 * std::f64::consts::PI * t).cos()).round() as i8
        })
        .collect();
    let um: Vec<f64> = volts
        .iter()
        .map(|&v| file.output_to_physical(plant.step(file.normalise_input(f64::from(v)))))
        .collect();
    let n = volts.len() as i64;
    mat5::file(
        &[
            mat5::Variable {
                name: "volts",
                dims: &[n, 1],
                values: mat5::Values::Int8(&volts),
            },
            mat5::var("um", &[n, 1], &um),
        ],
        false,
        true,
    )
}

/// Every case of the matrix, each in its own fixture.
fn matrix() -> Vec<(Fixture, Case)> {
    let mut cases = Vec::new();
    let mut add = |build: &dyn Fn(&Fixture) -> Case| {
        let fixture = Fixture::new();
        let case = build(&fixture);
        cases.push((fixture, case));
    };
    let mat_identify = |f: &Fixture, mat: &str, extra: &[&str]| {
        let mut args: Vec<String> = [
            "identify",
            "--data",
            mat,
            "--voltage-column",
            "u",
            "--displacement-column",
            "y",
            "-o",
            &f.arg("model.json"),
        ]
        .map(str::to_owned)
        .to_vec();
        args.extend(extra.iter().map(|a| a.to_string()));
        args
    };

    // 2. Crafted MAT-files: negative dimensions, dimensions whose product overflows, a cut.
    add(&|f| {
        let mut bytes = mat5::file(
            &[
                mat5::var("u", &[-1, 1], &[1.0, 2.0]),
                mat5::var("y", &[2, 1], &[1.0, 2.0]),
            ],
            false,
            false,
        );
        bytes.extend_from_slice(&[0; 8]);
        f.write_bytes("negative.mat", &bytes);
        Case::refused(
            "MAT-file with a negative dimension",
            mat_identify(f, &f.arg("negative.mat"), &[]),
            1,
            &["negative.mat", "negative dimension"],
        )
    });
    add(&|f| {
        let bytes = mat5::file(
            &[mat5::var(
                "u",
                &[65_536, 65_536, 65_536, 65_536, 65_536],
                &[],
            )],
            true,
            true,
        );
        f.write_bytes("overflow.mat", &bytes);
        Case::refused(
            "MAT-file whose dimensions multiply beyond any size",
            mat_identify(f, &f.arg("overflow.mat"), &[]),
            1,
            &["overflow.mat", "multiply beyond"],
        )
    });
    add(&|f| {
        let bytes = mat5::file(
            &[
                mat5::var("u", &[3, 1], &[1.0, 2.0, 3.0]),
                mat5::var("y", &[3, 1], &[1.0, 2.0, 3.0]),
            ],
            false,
            false,
        );
        f.write_bytes("cut.mat", &bytes[..bytes.len() - 20]);
        Case::refused(
            "MAT-file cut short",
            mat_identify(f, &f.arg("cut.mat"), &[]),
            1,
            &["cut.mat", "truncated or damaged"],
        )
    });
    // 4. Nothing but the command's output on stdout: int8 variables read (the old reader
    // printed "Unsupported variable type: Int8"), damaged compressed data refused quietly.
    add(&|f| {
        f.write_bytes("int8.mat", &int8_record_mat());
        let mut args = vec!["--json".to_owned()];
        let mut identify = identify(f, &f.arg("int8.mat"), &[]);
        identify[4] = "volts".to_owned();
        identify[6] = "um".to_owned();
        identify.extend(["-n".to_owned(), "2".to_owned()]);
        args.extend(identify);
        Case::accepted("--json identify on int8 MAT data", args)
            .output(f.path("model.json"))
            .json()
    });
    add(&|f| {
        let mut bytes = int8_record_mat();
        let n = bytes.len();
        for b in &mut bytes[n - 40..n - 20] {
            *b ^= 0x5a;
        }
        f.write_bytes("damaged.mat", &bytes);
        let mut args = vec!["--json".to_owned()];
        args.extend(mat_identify(f, &f.arg("damaged.mat"), &[]));
        Case::refused(
            "--json identify on damaged compressed MAT data",
            args,
            1,
            &["damaged.mat", "compressed"],
        )
        .json()
    });
    add(&|f| {
        let mut bytes = vec![b' '; 116];
        bytes.extend_from_slice(b"MATLAB 7.3 MAT-file");
        let mut header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64".to_vec();
        header.resize(124, b' ');
        header.extend_from_slice(&0x0200u16.to_le_bytes());
        header.extend_from_slice(b"IM");
        header.resize(512, 0);
        header.extend_from_slice(b"\x89HDF\r\n\x1a\n");
        f.write_bytes("v73.mat", &header);
        Case::refused(
            "a MATLAB v7.3 file",
            mat_identify(f, &f.arg("v73.mat"), &[]),
            1,
            &["v73.mat", "v7.3", "-v7"],
        )
    });

    // 3. Sizes: every one bounded, named, refused before allocating.
    for (name, rate, fragment) in [
        ("stage sample_rate_hz = 1e300", "1e300", "sample_rate_hz"),
        ("stage sample_rate_hz = 1e7", "1e7", "at most 1e6 Hz"),
        ("study beyond 5e6 samples per run", "500000.0", "5000000"),
    ] {
        add(&move |f| {
            f.write(
                "fast.toml",
                &format!("sample_rate_hz = {rate}\n[mechanics]\nresonance_hz = 600.0\n"),
            );
            Case::refused(
                name,
                [
                    "reproduce",
                    "--stage",
                    &f.arg("fast.toml"),
                    "-o",
                    &f.arg("report"),
                ],
                1,
                &["fast.toml", fragment],
            )
            .output(f.path("report"))
        });
    }
    add(&|f| {
        f.write("fast.toml", "sample_rate_hz = 1e300\n");
        Case::refused(
            "simulate on a stage of 1e300 Hz",
            [
                "simulate",
                "--stage",
                &f.arg("fast.toml"),
                "--drive",
                &f.arg("volts.csv"),
                "-o",
                &f.arg("out.csv"),
            ],
            1,
            &["fast.toml", "sample_rate_hz"],
        )
        .output(f.path("out.csv"))
    });
    add(&|f| {
        f.write(
            "big-weight.json",
            &edited_model("\"weights\": [", "\"weights\": [1e300, "),
        );
        // One weight too many now: drop the last threshold's partner by adding a threshold.
        let text = std::fs::read_to_string(f.path("big-weight.json"))
            .unwrap()
            .replacen("\"thresholds\": [", "\"thresholds\": [0.0, ", 1);
        f.write("big-weight.json", &text);
        Case::refused(
            "a model weight of 1e300 (compensate once drove a flat 0 V)",
            compensate(f, &f.arg("big-weight.json"), &f.arg("trajectory.csv"), &[]),
            1,
            &["big-weight.json", "1e15"],
        )
        .output(f.path("drive.csv"))
    });
    add(&|f| {
        let stage = std::fs::read_to_string(f.path("stage.toml"))
            .unwrap()
            .replacen("stroke_um = 72.27", "stroke_um = 1e300", 1);
        f.write("far.toml", &stage);
        Case::refused(
            "a stage stroke of 1e300 um (simulate once wrote positions no reader takes)",
            [
                "simulate",
                "--stage",
                &f.arg("far.toml"),
                "--input",
                &f.arg("volts.csv"),
                "-o",
                &f.arg("out.csv"),
            ],
            1,
            &["far.toml", "stroke_um"],
        )
        .output(f.path("out.csv"))
    });
    add(&|f| {
        // The record's displacements scaled into the subnormal range: the errors in % of
        // their range overflow.
        let mut text = String::new();
        for (k, line) in record_csv().lines().enumerate() {
            let mut cells: Vec<String> = line.split(',').map(str::to_owned).collect();
            if k > 0 {
                cells[2] = format!("{:e}", cells[2].parse::<f64>().unwrap() * 1e-310);
            }
            text += &(cells.join(",") + "\n");
        }
        f.write("subnormal.csv", &text);
        Case::refused(
            "predict on a record of subnormal values (once reported an error of inf %)",
            [
                "predict",
                "--model",
                &f.arg("table1-plant.json"),
                "--data",
                &f.arg("subnormal.csv"),
                "--voltage-column",
                "2",
                "--displacement-column",
                "3",
                "-o",
                &f.arg("p.csv"),
            ],
            1,
            &["subnormal.csv", "too small a range"],
        )
        .output(f.path("p.csv"))
    });
    for decimation in ["0", "5"] {
        add(&move |f| {
            Case::refused(
                "identify --decimation without a chain (once accepted and ignored)",
                identify(f, &f.arg("record.csv"), &["--decimation", decimation]),
                1,
                &["--decimation"],
            )
            .output(f.path("model.json"))
        });
    }
    add(&|f| {
        // Said before the study's seconds of work (it once failed only when writing).
        f.write("not-a-folder", "a file\n");
        Case::refused(
            "reproduce --output onto a file",
            ["reproduce", "-o", &f.arg("not-a-folder")],
            3,
            &["not-a-folder", "cannot make the output folder"],
        )
    });
    add(&|_| {
        let counts = vec!["1"; 33].join(",");
        Case::refused(
            "bench --channels with 33 counts",
            ["bench", "--channels", counts.as_str()],
            1,
            &["--channels", "1 to 32"],
        )
    });
    add(&|_| {
        Case::refused(
            "bench --channels 65536 --repeats 1000 (hours of timing)",
            ["bench", "--channels", "65536", "--repeats", "1000"],
            1,
            &["channel-steps", "--repeats 1000"],
        )
    });
    add(&|_| {
        Case::refused(
            "bench --samples 1000000 --repeats 1000 (hours of timing)",
            ["bench", "--samples", "1000000", "--repeats", "1000"],
            1,
            &["--samples 1000000 x --repeats 1000"],
        )
    });
    for (name, args, fragment) in [
        (
            "bench --samples 1e12",
            ["bench", "--samples", "1000000000000"],
            "--samples 1000000000000: give 100 to 1000000",
        ),
        (
            "bench --repeats 0",
            ["bench", "--repeats", "0"],
            "--repeats 0: give 1 to 1000",
        ),
    ] {
        add(&move |_| Case::refused(name, args, 1, &[fragment]));
    }
    for (name, extra, fragment) in [
        (
            "identify --pso-particles 1e8",
            &["--method", "pso", "--pso-particles", "100000000"][..],
            "--pso-particles 100000000: give 2 to 1000",
        ),
        (
            "identify --pso-iterations 1e9",
            &["--method", "pso", "--pso-iterations", "1000000000"][..],
            "--pso-iterations 1000000000: give 1 to 100000",
        ),
        (
            "identify -n 5000",
            &["-n", "5000"][..],
            "-n/--operators 5000: give 1 to 1000",
        ),
        ("reproduce's --pso-particles beyond 1000", &[][..], ""),
    ] {
        if fragment.is_empty() {
            add(&|f| {
                Case::refused(
                    "reproduce --pso-particles 1e6",
                    [
                        "reproduce",
                        "--pso-particles",
                        "1000000",
                        "-o",
                        &f.arg("report"),
                    ],
                    1,
                    &["--pso-particles 1000000"],
                )
                .output(f.path("report"))
            });
            continue;
        }
        add(&move |f| {
            Case::refused(
                name,
                identify(f, &f.arg("record.csv"), extra),
                1,
                &[fragment],
            )
            .output(f.path("model.json"))
        });
    }
    add(&|f| {
        let many: Vec<String> = (0..2000)
            .map(|i| format!("{}", i as f64 / 2001.0))
            .collect();
        Case::refused(
            "identify with 2000 thresholds",
            identify(f, &f.arg("record.csv"), &["--thresholds", &many.join(",")]),
            1,
            &["--thresholds 2000: give 1 to 1000"],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let n = 10_001;
        let thresholds: Vec<String> = (0..n).map(|i| format!("{}", i as f64 / n as f64)).collect();
        let weights = vec!["1e-6"; n];
        let text = edited_model(
            "\"thresholds\": [",
            &format!("\"thresholds\": [{}, ", thresholds[..n - 10].join(", ")),
        )
        .replacen(
            "\"weights\": [",
            &format!("\"weights\": [{}, ", weights[..n - 10].join(", ")),
            1,
        );
        f.write("huge-model.json", &text);
        Case::refused(
            "a model file of 10001 operators",
            compensate(f, &f.arg("huge-model.json"), &f.arg("trajectory.csv"), &[]),
            1,
            &["huge-model.json", "10001 play operators"],
        )
        .output(f.path("drive.csv"))
    });
    add(&|f| {
        let file = std::fs::File::create(f.path("big.json")).unwrap();
        file.set_len(17 << 20).unwrap();
        Case::refused(
            "a 17 MiB model file",
            compensate(f, &f.arg("big.json"), &f.arg("trajectory.csv"), &[]),
            1,
            &["big.json", "16 MiB"],
        )
        .output(f.path("drive.csv"))
    });
    #[cfg(unix)]
    add(&|f| {
        Case::refused(
            "a record that never ends (/dev/zero)",
            identify(f, "/dev/zero", &[]),
            1,
            &["/dev/zero", "never ends"],
        )
        .output(f.path("model.json"))
    });
    #[cfg(unix)]
    add(&|f| {
        Case::refused(
            "a model file that never ends (/dev/zero)",
            compensate(f, "/dev/zero", &f.arg("trajectory.csv"), &[]),
            1,
            &["/dev/zero", "16 MiB"],
        )
        .output(f.path("drive.csv"))
    });

    // 5. Silent garbage: values beyond 1e15 refused when read, naming file, line and column;
    // model scales that lose every value refused when loaded.
    add(&|f| {
        let text = trajectory_csv()
            .replace(",", ",1e300*")
            .replace("1e300*", "");
        let scaled: String = text
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    format!("{l}\n")
                } else {
                    let (t, y) = l.split_once(',').unwrap();
                    format!("{t},{:e}\n", y.parse::<f64>().unwrap() * 1e300)
                }
            })
            .collect();
        f.write("huge.csv", &scaled);
        Case::refused(
            "evaluate on 1e300-scale data",
            evaluate(f, &f.arg("huge.csv")),
            1,
            &["huge.csv", "line 2", "row 1", "1e15"],
        )
    });
    add(&|f| {
        let mut lines: Vec<String> = trajectory_csv().lines().map(str::to_owned).collect();
        lines[500] = "0.499,1e308".to_owned();
        f.write("spike.csv", &(lines.join("\n") + "\n"));
        Case::refused(
            "evaluate with one 1e308 sample",
            evaluate(f, &f.arg("spike.csv")),
            1,
            &["spike.csv", "line 501", "row 500", "1e15"],
        )
    });
    add(&|f| {
        let scaled: String = record_csv()
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    format!("{l}\n")
                } else {
                    let fields: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                    format!("{},{},{:e}\n", fields[0], fields[1], fields[2] * 1e300)
                }
            })
            .collect();
        f.write("test.csv", &scaled);
        Case::refused(
            "crossval on a 1e300-scale test record",
            [
                "crossval",
                "--train",
                &f.arg("record.csv"),
                "--test",
                &f.arg("test.csv"),
                "--voltage-column",
                "2",
                "--displacement-column",
                "3",
            ],
            1,
            &["test.csv", "1e15"],
        )
    });
    add(&|f| {
        f.write(
            "half-scale.json",
            &edited_model("\"scale\": 75.0", "\"scale\": 0.5"),
        );
        f.write("far.csv", "time_s,desired_um\n0,1\n0.001,1e308\n0.002,1\n");
        Case::refused(
            "compensate with output scale 0.5 on a 1e308 sample",
            compensate(f, &f.arg("half-scale.json"), &f.arg("far.csv"), &[]),
            1,
            &["far.csv", "line 3", "1e15"],
        )
        .output(f.path("drive.csv"))
    });
    add(&|f| {
        f.write(
            "denormal.json",
            &edited_model("\"scale\": 75.0", "\"scale\": 5e-324"),
        );
        Case::refused(
            "compensate with a subnormal output scale",
            compensate(f, &f.arg("denormal.json"), &f.arg("trajectory.csv"), &[]),
            1,
            &["denormal.json", "output.scale must lie in [1e-12, 1e12]"],
        )
        .output(f.path("drive.csv"))
    });
    // 7. Every clamp counted: a delayed WIHC driven far beyond its reach clamps, counts and
    // says so with exit 4 (the drive file written).
    add(&|f| {
        f.write(
            "beyond.csv",
            "time_s,desired_um\n0,1\n0.001,1e14\n0.002,-1e14\n0.003,1\n",
        );
        // Table 1's delayed WIHC has loop gain 1.66: run it with the explicit override.
        let mut args = compensate(
            f,
            &f.arg("table1-plant.json"),
            &f.arg("beyond.csv"),
            &["--allow-unstable-delay"],
        );
        args[4] = "wihc-delayed".to_owned();
        Case::saturated(
            "delayed WIHC fed 1e14 um",
            args,
            &["2 of 4 desired positions lie outside", "--allow-saturation"],
        )
        .output(f.path("drive.csv"))
    });
    // 8. A bare NaN token (Python's json.dump) named as such.
    for (token, python) in [("NaN", "float('nan')"), ("Infinity", "float('inf')")] {
        add(&move |f| {
            f.write("nan.json", &edited_model("-0.1569", token));
            Case::refused(
                "a model file with a bare NaN or Infinity",
                compensate(f, &f.arg("nan.json"), &f.arg("trajectory.csv"), &[]),
                1,
                &["nan.json", &format!("bare {token}"), python],
            )
            .output(f.path("drive.csv"))
        });
    }

    // Valid files a user has: accepted now.
    add(&|f| {
        f.write("european.csv", &european(&record_csv()));
        Case::accepted(
            "decimal commas between semicolons",
            identify(f, &f.arg("european.csv"), &[]),
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let body = european(&record_csv()).replace('\n', "\r\n");
        let (header, rows) = body.split_once("\r\n").unwrap();
        f.write(
            "excel.csv",
            &format!("sep=;\r\n{header}\r\ns;V;um\r\n{rows};;\r\n;;\r\n;;\r\n"),
        );
        Case::accepted(
            "Excel's sep= line, units row and empty rows",
            identify(f, &f.arg("excel.csv"), &[]),
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let text = record_csv().replace(',', "\t");
        let mut bytes = vec![0xff, 0xfe];
        bytes.extend(text.encode_utf16().flat_map(u16::to_le_bytes));
        f.write_bytes("unicode.txt", &bytes);
        Case::accepted(
            "UTF-16 text from Excel or PowerShell",
            identify(f, &f.arg("unicode.txt"), &[]),
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        f.write("units.csv", &record_csv().replacen('\n', "\ns,V,um\n", 1));
        Case::accepted(
            "a units row under the header",
            identify(f, &f.arg("units.csv"), &[]),
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        f.write("desired-eu.csv", &european(&trajectory_csv()));
        Case::accepted(
            "a European desired trajectory",
            compensate(
                f,
                &f.arg("table1-plant.json"),
                &f.arg("desired-eu.csv"),
                &[],
            ),
        )
        .output(f.path("drive.csv"))
    });
    let ms_volts = || {
        volts_csv(10_000.0, 400)
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    "time_ms,volts\n".to_owned()
                } else {
                    let (t, v) = l.split_once(',').unwrap();
                    format!("{},{v}\n", t.parse::<f64>().unwrap() * 1000.0)
                }
            })
            .collect::<String>()
    };
    add(&|f| {
        f.write("ms.csv", &ms_volts());
        Case::refused(
            "a time column in milliseconds: the flag named",
            [
                "simulate",
                "--drive",
                &f.arg("ms.csv"),
                "-o",
                &f.arg("out.csv"),
            ],
            1,
            &["ms.csv", "--time-unit ms"],
        )
        .output(f.path("out.csv"))
    });
    add(&|f| {
        f.write("ms.csv", &ms_volts());
        Case::accepted(
            "a time column in milliseconds with --time-unit ms",
            [
                "simulate",
                "--drive",
                &f.arg("ms.csv"),
                "--time-unit",
                "ms",
                "-o",
                &f.arg("out.csv"),
            ],
        )
        .output(f.path("out.csv"))
    });

    // The refusals the command line already made.
    add(&|f| {
        Case::refused(
            "a missing model file",
            compensate(f, &f.arg("missing.json"), &f.arg("trajectory.csv"), &[]),
            1,
            &["missing.json"],
        )
        .output(f.path("drive.csv"))
    });
    add(&|f| {
        let mut args = compensate(
            f,
            &f.arg("table1-plant.json"),
            &f.arg("trajectory.csv"),
            &[],
        );
        args[4] = "newton".to_owned();
        Case::refused("an unknown method", args, 2, &["--method", "newton"])
            .output(f.path("drive.csv"))
    });
    add(&|f| {
        let mut args = compensate(
            f,
            &f.arg("table1-plant.json"),
            &f.arg("trajectory.csv"),
            &[],
        );
        args[4] = "dihc".to_owned();
        Case::refused(
            "DIHC with a plant model",
            args,
            1,
            &["table1-plant.json", "inverse"],
        )
        .output(f.path("drive.csv"))
    });
    add(&|f| {
        Case::refused(
            "limits the wrong way round",
            compensate(
                f,
                &f.arg("table1-plant.json"),
                &f.arg("trajectory.csv"),
                &["--limits", "10:0"],
            ),
            1,
            &["limits"],
        )
        .output(f.path("drive.csv"))
    });
    add(&|f| {
        f.write("ragged.csv", "t,v,y\n0,1,2\n1,2\n2,3,4\n");
        Case::refused(
            "a ragged record",
            identify(f, &f.arg("ragged.csv"), &[]),
            1,
            &["ragged.csv", "line 3"],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let mut lines: Vec<String> = record_csv().lines().map(str::to_owned).collect();
        lines[700] = "0.699,oops,12".to_owned();
        f.write("text.csv", &(lines.join("\n") + "\n"));
        Case::refused(
            "text in a selected column",
            identify(f, &f.arg("text.csv"), &[]),
            1,
            &["text.csv", "line 701", "\"oops\""],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let mut lines: Vec<String> = record_csv().lines().map(str::to_owned).collect();
        lines[900] = "0.899,NaN,12".to_owned();
        f.write("nan.csv", &(lines.join("\n") + "\n"));
        Case::refused(
            "a NaN in a selected column",
            identify(f, &f.arg("nan.csv"), &[]),
            1,
            &["nan.csv", "line 901", "row 900", "finite"],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let constant: String = record_csv()
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    format!("{l}\n")
                } else {
                    let fields: Vec<&str> = l.split(',').collect();
                    format!("{},5,{}\n", fields[0], fields[2])
                }
            })
            .collect();
        f.write("constant.csv", &constant);
        Case::refused(
            "a constant voltage",
            identify(f, &f.arg("constant.csv"), &[]),
            1,
            &["constant.csv", "constant"],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let mut args = identify(f, &f.arg("record.csv"), &[]);
        args[6] = "2".to_owned();
        Case::refused(
            "the same column twice",
            args,
            1,
            &["record.csv", "same column"],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        Case::refused(
            "a hold-out of 1.5",
            identify(f, &f.arg("record.csv"), &["--holdout", "1.5"]),
            1,
            &["holdout", "1.5"],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        Case::refused(
            "a voltage factor that overflows",
            identify(f, &f.arg("record.csv"), &["--voltage-factor", "1e306"]),
            1,
            &["--voltage-factor 1e306", "beyond 1e15"],
        )
        .output(f.path("model.json"))
    });
    add(&|f| {
        let text = trajectory_csv();
        let mut lines: Vec<&str> = text.lines().collect();
        lines.truncate(600);
        f.write("short.csv", &(lines.join("\n") + "\n"));
        Case::refused(
            "records of different lengths",
            evaluate(f, &f.arg("short.csv")),
            1,
            &["short.csv", "trajectory.csv"],
        )
    });
    add(&|f| {
        Case::refused(
            "signal with an amplitude no record may hold",
            [
                "signal",
                "paper",
                "--amplitude",
                "1e308",
                "--offset",
                "1e308",
                "-o",
                &f.arg("signal.csv"),
            ],
            1,
            &["--amplitude", "row 1", "1e15"],
        )
        .output(f.path("signal.csv"))
    });
    add(&|f| {
        Case::refused(
            "signal of 1e12 s",
            [
                "signal",
                "paper",
                "--duration",
                "1e12",
                "-o",
                &f.arg("signal.csv"),
            ],
            1,
            &["--duration", "samples"],
        )
        .output(f.path("signal.csv"))
    });
    // Huge and tiny values are echoed as written (1e308), not digit by digit.
    for (name, args, fragments) in [
        (
            "signal at 1e308 Hz",
            ["triangle", "--frequency", "1e308"],
            ["--frequency", "got 1e308"],
        ),
        (
            "signal of 1e308 s",
            ["paper", "--duration", "1e308"],
            ["--duration", "1e308 s at"],
        ),
        (
            "signal sampled at 1e-300 Hz",
            ["paper", "--sample-rate", "1e-300"],
            ["--duration", "at 1e-300 Hz"],
        ),
    ] {
        add(&|f| {
            let mut line = vec!["signal".to_owned()];
            line.extend(args.map(str::to_owned));
            line.extend(["-o".to_owned(), f.arg("signal.csv")]);
            Case::refused(name, line, 1, &fragments).output(f.path("signal.csv"))
        });
    }
    let learn = |f: &Fixture, extra: &[&str]| -> Vec<String> {
        let mut args: Vec<String> = [
            "learn",
            "--simulate",
            "--desired",
            &f.write("desired.csv", &desired_10khz_csv()),
            "--model",
            &f.arg("table1-plant.json"),
            "-o",
            &f.arg("next.csv"),
        ]
        .map(str::to_owned)
        .to_vec();
        args.extend(extra.iter().map(|a| a.to_string()));
        args
    };
    add(&|f| {
        Case::refused(
            "learn with a NaN gain",
            learn(f, &["--gain", "NaN"]),
            1,
            &["--gain", "NaN"],
        )
        .output(f.path("next.csv"))
    });
    add(&|f| {
        Case::refused(
            "learn with more e_mhe bins than the trial supports",
            learn(f, &["--bins", "1000"]),
            1,
            &["--bins: e_mhe bins = 1000", "at most 200 bins"],
        )
        .output(f.path("next.csv"))
    });
    add(&|f| {
        Case::refused(
            "learn with a gain of 1e308",
            learn(f, &["--gain", "1e308"]),
            1,
            &["--gain", "gain = 1e308 cannot"],
        )
        .output(f.path("next.csv"))
    });
    add(&|f| {
        // 1000 trials of 1000 periods of 2000 samples: twice the 1e9 one run simulates.
        let long: String = (0..1010)
            .map(|k| {
                let t = k as f64 * 1e-3;
                format!(
                    "{t},{}\n",
                    30.0 + 10.0 * (2.0 * std::f64::consts::PI * t).sin()
                )
            })
            .collect();
        f.write("long.csv", &format!("time_s,desired_um\n{long}"));
        let mut args = learn(f, &["--trials", "1000", "--periods", "1000"]);
        args[3] = f.arg("long.csv");
        Case::refused(
            "learn of more stage samples than one run simulates",
            learn(f, &["--trials", "1000", "--periods", "1000"]),
            1,
            &["--trials", "--periods", "1e9"],
        )
        .output(f.path("next.csv"))
    });
    add(&|f| {
        f.write("broken.toml", "sample_rate_hz = [1, 2\n");
        Case::refused(
            "a stage file that is not TOML",
            [
                "simulate",
                "--stage",
                &f.arg("broken.toml"),
                "--drive",
                &f.arg("volts.csv"),
                "-o",
                &f.arg("out.csv"),
            ],
            1,
            &["broken.toml"],
        )
        .output(f.path("out.csv"))
    });
    add(&|f| {
        Case::refused(
            "a missing test record",
            [
                "crossval",
                "--train",
                &f.arg("record.csv"),
                "--test",
                &f.arg("missing.csv"),
                "--voltage-column",
                "2",
                "--displacement-column",
                "3",
            ],
            1,
            &["missing.csv"],
        )
    });
    add(&|f| {
        let mut args = identify(f, &f.arg("record.csv"), &[]);
        let target = f.path("no-such-folder/model.json");
        args[8] = target.to_str().unwrap().to_owned();
        Case::refused(
            "a model into a folder that does not exist",
            args,
            3,
            &["no-such-folder", "does not exist"],
        )
        .output(target)
    });
    add(&|f| {
        std::fs::create_dir(f.path("folder")).unwrap();
        let mut args = compensate(
            f,
            &f.arg("table1-plant.json"),
            &f.arg("trajectory.csv"),
            &[],
        );
        args[8] = f.arg("folder");
        Case::refused(
            "a drive file onto a folder",
            args,
            3,
            &["folder", "directory"],
        )
    });
    add(&|f| {
        f.write_bytes("binary.dat", &[0u8, 1, 2, 3, 255, 254, 0, 7, 9, 0]);
        Case::refused(
            "a binary file as a record",
            identify(f, &f.arg("binary.dat"), &[]),
            1,
            &["binary.dat", "binary"],
        )
        .output(f.path("model.json"))
    });
    cases
}

/// Issue 13's acceptance: at least 40 bad inputs through the command line, each with its
/// exit status, a message naming the file, row or option, no panic or abort, no output file
/// left behind and no input file changed (the overwrite cases above count too).
#[test]
fn every_bad_input_of_issue_13_is_handled() {
    let count = run_cases(matrix());
    let overwrites = overwritten_inputs().len();
    eprintln!("{count} cases of the matrix, {overwrites} of overwritten inputs");
    assert!(count + overwrites >= 40, "{count} + {overwrites} cases");
}
