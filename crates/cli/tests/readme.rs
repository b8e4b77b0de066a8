//! The README's command-line block runs as written, line by line, in an empty directory (it
//! makes its inputs with `hystcomp signal`), and its last `evaluate` prints figures within the
//! band the README states.

mod common;

use std::path::Path;
use std::process::Command;

use common::{s, stderr, stdout};

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

/// `name = value %` from evaluate's text output.
fn percent(text: &str, name: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.starts_with(name))
        .unwrap_or_else(|| panic!("no {name} in {text}"));
    line.split('=')
        .nth(1)
        .unwrap()
        .split('%')
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

#[test]
fn the_readme_command_line_block_runs_as_written_and_scores_within_its_band() {
    let commands = readme_commands();
    assert!(commands.len() >= 12, "too few commands: {commands:?}");
    // An empty directory: the block makes every input it uses itself.
    let dir = tempfile::tempdir().unwrap();
    let here = dir.path();
    let mut evaluated = false;
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
            // The band the README states for the last period of the session's IHC.
            let text = stdout(&out);
            let (e_mhe, e_m, e_rms) = (
                percent(&text, "e_mhe"),
                percent(&text, "e_m "),
                percent(&text, "e_rms"),
            );
            assert!((1.5..=3.5).contains(&e_mhe), "e_mhe {e_mhe}: {text}");
            assert!((0.5..=2.0).contains(&e_m), "e_m {e_m}: {text}");
            assert!((0.2..=0.6).contains(&e_rms), "e_rms {e_rms}: {text}");
            assert!(text.contains("t = 10 .. 20 s"), "{text}");
            evaluated = true;
        }
    }
    assert!(evaluated, "the block ends with an evaluate");
    assert!(here.join("report/index.html").is_file());
}

#[test]
fn the_readme_shows_what_evaluate_prints() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let section = readme.split("## The command line").nth(1).unwrap();
    let shown = section
        .split("```text\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("the printed indices in a ```text block");
    for name in ["e_mhe", "e_m ", "e_rms"] {
        let value = percent(shown, name);
        assert!(value > 0.0, "{name}");
    }
    assert!((1.5..=3.5).contains(&percent(shown, "e_mhe")));
}
