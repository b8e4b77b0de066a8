//! One vocabulary across commands (the brief's Part 3): the help shows only the current
//! spellings, the old ones still parse (hidden aliases for one release), the exit codes are in
//! every --help and in the README, and `reproduce` exits 5 when an acceptance check fails.

mod common;

use common::{hystcomp, s, stderr, stdout};

/// The subcommands, from the top-level help.
fn subcommands() -> Vec<String> {
    let help = stdout(&hystcomp(&["--help"]));
    help.split("Commands:")
        .nth(1)
        .unwrap()
        .split("Options:")
        .next()
        .unwrap()
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_owned)
        .collect()
}

/// Spellings renamed in 0.2: old, new (command-line options).
const RENAMED: [(&str, &str); 5] = [
    ("--input", "--drive"),
    ("--trajectory", "--desired"),
    ("--out", "--output"),
    ("--iterations", "--pso-iterations"),
    ("--particles", "--pso-particles"),
];

#[test]
fn help_shows_the_current_spellings_and_the_exit_codes() {
    let commands = subcommands();
    assert!(commands.len() >= 8, "{commands:?}");
    for command in &commands {
        let help = stdout(&hystcomp(&[command, "--help"]));
        for (old, _) in RENAMED {
            let shown = help
                .split_whitespace()
                .any(|w| w.trim_end_matches(',') == old);
            assert!(!shown, "{command} --help shows the old {old}");
        }
        assert!(help.contains("Exit status:"), "{command} --help");
        for code in [
            "  0  success",
            "  1  bad input",
            "  3  an output",
            "  5  an acceptance",
        ] {
            assert!(help.contains(code), "{command} --help lacks {code:?}");
        }
        // Output files are -o/--output everywhere (the option itself, a whole word: not
        // `--output-map-degree`, which names the hysteresis link's output map).
        let has_output = help
            .split_whitespace()
            .any(|w| w.trim_end_matches(',') == "--output");
        if has_output {
            assert!(help.contains("-o, --output"), "{command}");
        }
    }
}

#[test]
fn old_spellings_still_parse() {
    // An unknown option is a usage error (2); an old spelling reaches the command, which then
    // refuses the missing file as bad input (1).
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.csv");
    let out = dir.path().join("out.csv");
    let (m, o) = (s(&missing), s(&out));
    let cases: [&[&str]; 5] = [
        &["simulate", "--input", m, "-o", o],
        &[
            "compensate",
            "--model",
            m,
            "--method",
            "ihc",
            "--trajectory",
            m,
            "-o",
            o,
        ],
        &[
            "identify",
            "--data",
            m,
            "--voltage-column",
            "1",
            "--displacement-column",
            "2",
            "--iterations",
            "5",
            "--particles",
            "4",
            "-o",
            o,
        ],
        &["reproduce", "--stage", m, "--out", s(dir.path())],
        &["evaluate", "--desired", m, "--measured", m],
    ];
    for args in cases {
        let run = hystcomp(args);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {}", stderr(&run));
    }
    let bogus = hystcomp(&["simulate", "--no-such-option", m, "-o", o]);
    assert_eq!(bogus.status.code(), Some(2));
}

#[test]
fn the_readme_lists_the_exit_codes_of_the_help() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let help = stdout(&hystcomp(&["--help"]));
    let list = help
        .split("Exit status:\n")
        .nth(1)
        .expect("exit codes in --help");
    for line in list.lines().filter(|l| !l.trim().is_empty()) {
        let line = line.trim();
        let (code, meaning) = line.split_once("  ").unwrap();
        let row = format!("| {code} | {} |", meaning.trim());
        assert!(readme.contains(&row), "the README lacks the row {row:?}");
    }
}

#[test]
fn reproduce_exits_5_when_an_acceptance_check_fails_unless_no_check() {
    // A stage with little hysteresis: its uncompensated e_mhe misses the calibration bound
    // (13 % +- 1.5), an acceptance check.
    let dir = tempfile::tempdir().unwrap();
    let stage = dir.path().join("stage.toml");
    std::fs::write(
        &stage,
        "[hysteresis.preisach]\nreversible_fraction = 0.95\n",
    )
    .unwrap();
    let out = dir.path().join("report");
    let args = [
        "reproduce",
        "--stage",
        s(&stage),
        "-o",
        s(&out),
        "--pso-iterations",
        "5",
    ];
    let run = hystcomp(&args);
    assert_eq!(run.status.code(), Some(5), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("acceptance checks failed"),
        "{}",
        stderr(&run)
    );
    assert!(stderr(&run).contains("uncompensated"), "{}", stderr(&run));
    assert!(
        out.join("index.html").is_file(),
        "the report is written all the same"
    );
    let mut no_check = args.to_vec();
    no_check.push("--no-check");
    let run = hystcomp(&no_check);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    assert!(stdout(&run).contains("MISS"), "{}", stdout(&run));
}
