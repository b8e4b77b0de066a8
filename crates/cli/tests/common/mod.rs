//! Shared by the command-line tests: running the built binary and reading what it said.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `hystcomp` with `args`.
pub fn hystcomp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hystcomp"))
        .args(args)
        .output()
        .expect("the hystcomp binary runs")
}

/// What the run printed on stderr.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// What the run printed on stdout.
pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A path as an argument.
pub fn s(path: &Path) -> &str {
    path.to_str().expect("test paths are UTF-8")
}

/// The repository's example model files.
pub fn models() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

/// Runs `hystcomp` with `args`, asserts a non-zero exit and every fragment in the message.
pub fn assert_fails(args: &[&str], fragments: &[&str]) {
    let out = hystcomp(args);
    assert!(!out.status.success(), "succeeded: {args:?}");
    assert_ne!(out.status.code(), Some(0));
    let message = stderr(&out);
    for fragment in fragments {
        assert!(message.contains(fragment), "{fragment:?} not in: {message}");
    }
}

/// The two records of the shared DBO data, to train on (`Model_Vi_Do.dat`) and to test on
/// (`Test_Vi_Do_Di.dat`); `None`, the skip said, without the shared data.
pub fn dbo_records() -> Option<(PathBuf, PathBuf)> {
    match (
        hystcomp_testkit::dbo_record("Model_Vi_Do.dat"),
        hystcomp_testkit::dbo_record("Test_Vi_Do_Di.dat"),
    ) {
        (Some(train), Some(test)) => Some((train, test)),
        _ => None,
    }
}

/// Runs `hystcomp --json crossval` trained on `train` and tested on `test`, the DBO records'
/// columns (voltage 1, displacement 5), then `extra`.
pub fn dbo_crossval(train: &Path, test: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "--json",
        "crossval",
        "--train",
        s(train),
        "--test",
        s(test),
        "--voltage-column",
        "1",
        "--displacement-column",
        "5",
    ];
    args.extend(extra);
    hystcomp(&args)
}

/// `hystcomp --json bench --samples 500 --repeats 1 --model <model>`: the figures timed for
/// that model file (each with a positive median), after asserting success.
pub fn bench_model_figures(model: &Path) -> Vec<serde_json::Value> {
    let out = hystcomp(&[
        "--json",
        "bench",
        "--samples",
        "500",
        "--repeats",
        "1",
        "--model",
        s(model),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let figures: Vec<serde_json::Value> = json["figures"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["model"] == s(model))
        .cloned()
        .collect();
    for f in &figures {
        assert!(f["median_ns_per_sample"].as_f64().unwrap() > 0.0, "{f}");
    }
    figures
}

/// Reads a CSV of numbers written by the binary: the header and the columns.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let mut columns = vec![Vec::new(); header.len()];
    for line in lines {
        for (c, v) in line.split(',').enumerate() {
            columns[c].push(v.parse::<f64>().unwrap());
        }
    }
    (header, columns)
}
