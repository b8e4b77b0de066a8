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

/// A command record (time_s, volts) at `rate_hz`.
fn volts_csv(rate_hz: f64, n: usize) -> String {
    let mut text = String::from("time_s,volts\n");
    for k in 0..n {
        let t = k as f64 / rate_hz;
        let v = 5.0 + 4.0 * (2.0 * std::f64::consts::PI * 20.0 * t).sin();
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
}

/// One bad input: a command line in a fixture, what it must do, and the files it must leave
/// alone.
struct Case {
    name: &'static str,
    args: Vec<String>,
    /// The command's output (file or directory): must not exist after a refusal.
    output: Option<PathBuf>,
    expect: Expect,
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
        }
    }

    fn accepted<S: Into<String>>(name: &'static str, args: impl IntoIterator<Item = S>) -> Self {
        Case {
            name,
            args: args.into_iter().map(Into::into).collect(),
            output: None,
            expect: Expect::Accepted,
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
            if let Some(stray) = created.iter().find(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().ends_with(".tmp"))
            }) {
                problems.push(format!("temporary file left behind: {}", stray.display()));
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
/// every command exiting with its usual status, without a panic or a message.
#[test]
#[allow(clippy::incompatible_msrv)] // std::io::pipe, in a test only
fn a_closed_stdout_ends_every_command_quietly() {
    let f = Fixture::new();
    f.write("test.csv", &record_csv());
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
    ]
    .into_iter()
    .map(|args| args.into_iter().map(str::to_owned).collect())
    .collect();
    for args in commands {
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
        assert!(message.is_empty(), "{args:?} said: {message}");
    }
}
