//! The README's command-line block runs as written, line by line, in a fresh directory that
//! holds the three input files it names.

mod common;

use std::path::Path;
use std::process::Command;

use common::{s, stderr, stdout};
use hystcomp_experiments::Reference;
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_io::data::write_csv;

const SAMPLE_RATE_HZ: f64 = 10_000.0;

/// The commands of the ```sh block under "## The command line", comments removed.
fn readme_commands() -> Vec<Vec<String>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md exists");
    let section = readme
        .split("## The command line")
        .nth(1)
        .expect("the README has a command-line section");
    let block = section
        .split("```sh\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("the command-line section has a ```sh block");
    block
        .lines()
        .map(|line| line.split('#').next().unwrap_or("").trim())
        .filter(|line| !line.is_empty())
        .map(|line| line.split_whitespace().map(str::to_owned).collect())
        .collect()
}

/// A record's command voltage at the stage's rate, as `time_s, command_v`.
fn write_volts(path: &Path, excitation: &IdentificationExcitation) {
    let command = excitation.command_v(SAMPLE_RATE_HZ);
    let time: Vec<f64> = (0..command.len())
        .map(|k| k as f64 / SAMPLE_RATE_HZ)
        .collect();
    write_csv(path, &["time_s", "command_v"], &[&time, &command]).unwrap();
}

#[test]
fn the_readme_command_line_block_runs_as_written() {
    let commands = readme_commands();
    assert!(commands.len() >= 8, "too few commands: {commands:?}");
    let dir = tempfile::tempdir().unwrap();
    let here = dir.path();

    // The inputs the README names: an excitation, a second record, a desired trajectory.
    let short = IdentificationExcitation {
        multisine_s: 6.0,
        ..IdentificationExcitation::default()
    };
    write_volts(&here.join("volts.csv"), &short);
    let other = IdentificationExcitation {
        segment_s: 0.5,
        multisine_s: 4.0,
        ..IdentificationExcitation::default()
    };
    write_volts(&here.join("check-volts.csv"), &other);
    let check = Command::new(env!("CARGO_BIN_EXE_hystcomp"))
        .current_dir(here)
        .args(["simulate", "--input", "check-volts.csv", "-o", "check.csv"])
        .args(["--seed", "9"])
        .output()
        .unwrap();
    assert!(check.status.success(), "{}", stderr(&check));
    let (time, desired) = Reference::paper()
        .trajectory()
        .sample(SAMPLE_RATE_HZ, 30_000);
    write_csv(
        &here.join("desired.csv"),
        &["time_s", "desired_um"],
        &[&time, &desired],
    )
    .unwrap();

    for command in &commands {
        assert_eq!(
            command[0], "hystcomp",
            "not a hystcomp command: {command:?}"
        );
        let out = Command::new(env!("CARGO_BIN_EXE_hystcomp"))
            .current_dir(here)
            .args(&command[1..])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{command:?} failed: {}{}",
            stdout(&out),
            stderr(&out)
        );
        // Every file a command says it writes is there.
        if let Some(k) = command.iter().position(|a| a == "-o") {
            let written = here.join(&command[k + 1]);
            assert!(written.is_file(), "{command:?} wrote no {}", s(&written));
        }
        if command[1] == "evaluate" {
            assert!(stdout(&out).contains("e_mhe"), "{}", stdout(&out));
        }
    }
    assert!(here.join("report/index.html").is_file());
}
