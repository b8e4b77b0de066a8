//! `hystcomp crossval` through the binary: synthetic records with a known answer, per-file
//! column options, the real DBO records (skipped when absent), and bad input.

mod common;

use common::*;

use std::path::{Path, PathBuf};

use hystcomp_core::Mpim;
use hystcomp_io::model_file::{Direction, ModelFile};
use serde_json::Value;

/// Table 1 driven by `voltage` (0..10 V), in um with an offset of 5 um.
fn displacement(voltage: &[f64]) -> Vec<f64> {
    let thresholds = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
    let weights = [
        0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ];
    let mut plant: Mpim<f64, Vec<f64>> = Mpim::new(&thresholds, &weights, -0.1569, 0.4603).unwrap();
    voltage
        .iter()
        .map(|v| 5.0 + 75.0 * plant.step(v / 10.0))
        .collect()
}

/// Voltage and displacement samples of one record.
type Pair = (Vec<f64>, Vec<f64>);

/// A decaying 1 Hz cycle from 0 to 10 V (training) and, for testing, the paper's three-tone
/// trajectory shape mapped into 1..9 V after a ramp up from 0 V.
fn records() -> (Pair, Pair) {
    let train: Vec<f64> = (0..4000)
        .map(|k| {
            let t = k as f64 / 200.0;
            // Exactly 0 to 10 V in the first cycle (the thresholds of Table 1), then decaying.
            let envelope = (-(t - 0.5).max(0.0) / 12.0).exp();
            5.0 - 5.0 * envelope * (2.0 * std::f64::consts::PI * t).cos()
        })
        .collect();
    let mut test: Vec<f64> = (0..100).map(|k| k as f64 / 100.0 * 5.0).collect();
    test.extend((0..2000).map(|k| {
        let t = k as f64 / 200.0;
        let pi = std::f64::consts::PI;
        let s = 10.5 * (pi * t + 2.6).sin()
            + 10.5 * (1.6 * pi * t + 3.0).sin()
            + 15.75 * (2.0 * pi * t + 1.5).sin();
        5.0 + 4.0 * s / 36.75
    }));
    let (y_train, y_test) = (displacement(&train), displacement(&test));
    ((train, y_train), (test, y_test))
}

fn write_csv(path: &Path, names: &[&str], columns: &[&[f64]]) {
    let mut text = names.join(",") + "\n";
    for r in 0..columns[0].len() {
        let row: Vec<String> = columns.iter().map(|c| format!("{:?}", c[r])).collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

fn files(dir: &Path) -> (PathBuf, PathBuf) {
    let ((v, y), (tv, ty)) = records();
    let train = dir.join("train.csv");
    let test = dir.join("test.csv");
    write_csv(&train, &["volts", "um"], &[&v, &y]);
    // The test file has its columns the other way round, and one more.
    let zeros = vec![0.0; tv.len()];
    write_csv(&test, &["um", "volts", "spare"], &[&ty, &tv, &zeros]);
    (train, test)
}

/// `crossval` of `train` against `test` on the columns named `volts` and `um`, then `extra`.
fn crossval<'a>(train: &'a Path, test: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "crossval",
        "--train",
        s(train),
        "--test",
        s(test),
        "--voltage-column",
        "volts",
        "--displacement-column",
        "um",
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn exact_compensators_replay_a_noise_free_test_record_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let (train, test) = files(dir.path());
    let plant_path = dir.path().join("plant.json");
    let inverse_path = dir.path().join("inverse.json");
    let args = crossval(
        &train,
        &test,
        &[
            "--test-warmup",
            "0",
            "--save-plant",
            s(&plant_path),
            "--save-inverse",
            s(&inverse_path),
        ],
    );
    let out = hystcomp(&[&["--json"], &args[..]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    let test_report = &doc["report"]["test"];
    assert_eq!(test_report["samples"], 2100);
    assert_eq!(test_report["warmup"], 0);
    assert!(test_report["forward"]["rms_percent"].as_f64().unwrap() < 1e-6);
    let replay = test_report["replay"].as_array().unwrap();
    let names: Vec<&str> = replay
        .iter()
        .map(|r| r["compensator"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "ihc",
            "ihc-delayed",
            "wihc",
            "wihc-delayed",
            "dihc",
            "ihc-guarded",
            "wihc-guarded"
        ]
    );
    // Table 1's delayed WIHC can ring (gain 1.68 on the identified model): not built, with
    // the reason; the report gives both delayed loops' gains.
    let gains = &test_report["delayed_loop_gains"];
    assert!(gains["wihc"].as_f64().unwrap() > 1.0, "{gains}");
    assert!(gains["ihc"].as_f64().unwrap() < 1.0, "{gains}");
    for r in replay {
        if r["compensator"] == "wihc-delayed" {
            assert!(r["error"].is_null(), "{r}");
            let failure = r["failure"].as_str().unwrap();
            assert!(failure.contains("delayed WIHC can oscillate"), "{r}");
            continue;
        }
        let rms = r["error"]["rms_percent"].as_f64().unwrap();
        let max = r["error"]["max_percent"].as_f64().unwrap();
        match r["compensator"].as_str().unwrap() {
            // The identified plant model is exact: its exact inverses return the voltage.
            "ihc" | "wihc" => assert!(max < 1e-6, "{r}"),
            _ => assert!(rms > 1e-6 && rms < 10.0, "{r}"),
        }
        // The first test sample sits exactly on the lower voltage limit: rounding may clamp it.
        // (The delayed WIHC may ring at the start, while several operators move.)
        if r["compensator"] != "wihc-delayed" {
            assert!(r["saturated"].as_u64().unwrap() <= 1, "{r}");
        }
    }
    let plant = ModelFile::load(&plant_path).unwrap();
    let inverse = ModelFile::load(&inverse_path).unwrap();
    assert_eq!(plant.direction, Direction::Plant);
    assert_eq!(inverse.direction, Direction::Inverse);
    assert_eq!(doc["plant_model"]["a1"].as_f64().unwrap(), plant.a1);
}

#[test]
fn text_report_lists_every_compensator() {
    let dir = tempfile::tempdir().unwrap();
    let (train, test) = files(dir.path());
    let out = hystcomp(&[
        "crossval",
        "--train",
        s(&train),
        "--test",
        s(&test),
        "--voltage-column",
        "1",
        "--displacement-column",
        "2",
        "--test-voltage-column",
        "2",
        "--test-displacement-column",
        "1",
        "--method",
        "pso",
        "--pso-iterations",
        "50",
        "--polish",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    for name in [
        "ihc",
        "ihc-delayed",
        "wihc",
        "wihc-delayed",
        "dihc",
        "forward prediction",
    ] {
        assert!(text.contains(name), "{name} missing from:\n{text}");
    }
}

/// A test record that starts away from rest makes the desired position jump at its first
/// sample; the identified Table 1 model's delayed WIHC (full loop gain 1.66) rings there. Its
/// clamps of reachable positions show as `loop_saturated` in the JSON and `loop-sat.` in the
/// text, apart from `saturated`; the exact compensators have none.
#[test]
fn a_ringing_delayed_wihc_shows_in_the_loop_saturated_count() {
    let dir = tempfile::tempdir().unwrap();
    let ((v, y), (tv, ty)) = records();
    let train = dir.path().join("train.csv");
    let test = dir.path().join("jump.csv");
    write_csv(&train, &["volts", "um"], &[&v, &y]);
    // The three-tone part only, without the ramp up from 0 V.
    write_csv(&test, &["volts", "um"], &[&tv[100..], &ty[100..]]);
    // Its loop gain is above 1: replayed only when allowed explicitly.
    let args = crossval(
        &train,
        &test,
        &["--test-warmup", "0", "--allow-unstable-delay"],
    );
    let out = hystcomp(&[&["--json"], &args[..]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    for r in doc["report"]["test"]["replay"].as_array().unwrap() {
        let looped = r["loop_saturated"]
            .as_u64()
            .expect("a loop_saturated count");
        match r["compensator"].as_str().unwrap() {
            "wihc-delayed" => assert!(looped > 0, "{r}"),
            // The exact and the guarded loops never ring.
            "ihc" | "wihc" | "ihc-guarded" | "wihc-guarded" => assert_eq!(looped, 0, "{r}"),
            _ => {}
        }
    }
    let out = hystcomp(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("loop-sat."), "{text}");
    assert!(text.contains("rang after a jump"), "{text}");
    assert!(
        text.contains("replayed anyway (--allow-unstable-delay)"),
        "{text}"
    );
}

#[test]
fn bad_test_files_are_refused_with_a_message_to_act_on() {
    let dir = tempfile::tempdir().unwrap();
    let (train, test) = files(dir.path());
    let run = |extra: &[&str]| {
        let out = hystcomp(&crossval(&train, &test, extra));
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        assert!(out.stdout.is_empty());
        stderr(&out)
    };
    let message = run(&["--test-voltage-column", "volt"]);
    assert!(message.contains("\"volt\""), "{message}");
    assert!(message.contains("\"spare\""), "{message}");
    let message = run(&["--test-displacement-column", "spare"]);
    assert!(message.contains("constant"), "{message}");
    let message = run(&["--test-warmup", "99999"]);
    assert!(message.contains("warm-up"), "{message}");
    let message = run(&["--test-warmup", "soon"]);
    assert!(message.contains("--test-warmup"), "{message}");
    // Too few test samples after the test warm-up: the number needed (10 operators, r_1 = 0,
    // offset fitted: 12 parameters, 3 samples each, as identification counts), and what to
    // change.
    let message = run(&["--test-rows", "1..2"]);
    assert!(message.contains("at least 36"), "{message}");
    assert!(message.contains("--test-warmup"), "{message}");
    let message = run(&["--test-rows", "1..37", "--test-warmup", "2"]);
    assert!(message.contains("at least 36"), "{message}");
    let message = run(&["--holdout", "-0.1"]);
    assert!(
        message.contains("holdout") && message.contains("-0.1"),
        "{message}"
    );
    // Missing and empty files.
    let missing = dir.path().join("missing.csv");
    let empty = dir.path().join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    for (train, test, fragments) in [
        (&train, &missing, ["missing.csv", "check the path"]),
        (&empty, &test, ["empty.csv", "no rows"]),
    ] {
        assert_fails(&crossval(train, test, &[]), &fragments);
    }
    // The same column for both (in the training file).
    assert_fails(
        &[
            "crossval",
            "--train",
            s(&train),
            "--test",
            s(&test),
            "--voltage-column",
            "volts",
            "--displacement-column",
            "volts",
        ],
        &["train.csv", "column \"volts\"", "exact linear function"],
    );
}

/// Output paths that are an input or each other are refused before anything is written.
#[test]
fn saved_models_never_overwrite_a_record_or_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let (train, test) = files(dir.path());
    let before = (
        std::fs::read(&train).unwrap(),
        std::fs::read(&test).unwrap(),
    );
    let model = dir.path().join("model.json");
    let base = crossval(&train, &test, &[]);
    for (extra, fragment) in [
        (
            vec!["--save-plant", s(&model), "--save-inverse", s(&model)],
            "--save-plant and --save-inverse",
        ),
        (vec!["--save-plant", s(&train)], "same file as --train"),
        (vec!["--save-inverse", s(&test)], "same file as --test"),
    ] {
        let out = hystcomp(&[&base[..], &extra[..]].concat());
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        assert!(stderr(&out).contains(fragment), "{}", stderr(&out));
        assert!(!model.exists());
        assert_eq!(
            (
                std::fs::read(&train).unwrap(),
                std::fs::read(&test).unwrap()
            ),
            before
        );
    }
    // Two different paths: both written, each with its direction.
    let inverse = dir.path().join("inverse.json");
    let out = hystcomp(
        &[
            &base[..],
            &["--save-plant", s(&model), "--save-inverse", s(&inverse)],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(ModelFile::load(&model).unwrap().direction, Direction::Plant);
    assert_eq!(
        ModelFile::load(&inverse).unwrap().direction,
        Direction::Inverse
    );
}

#[test]
fn dbo_records_cross_validate_within_sane_bounds() {
    let Some((train, test)) = dbo_records() else {
        return;
    };
    let out = dbo_crossval(&train, &test, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let report = &doc["report"];
    for model in ["plant", "inverse"] {
        let fit = &report[model]["fit"];
        eprintln!(
            "DBO crossval (cli): {model} fit RMS {:.3} % max {:.3} %",
            fit["rms_percent"].as_f64().unwrap(),
            fit["max_percent"].as_f64().unwrap()
        );
        // About 1.5 times the measured figures (plant 0.681 / 2.511 %, inverse 0.470 /
        // 1.826 %; the ranges are those of the fitted samples, warm-up excluded).
        let (rms, max) = if model == "plant" {
            (0.681, 2.511)
        } else {
            (0.470, 1.826)
        };
        assert!(fit["rms_percent"].as_f64().unwrap() < 1.5 * rms, "{fit}");
        assert!(fit["max_percent"].as_f64().unwrap() < 1.5 * max, "{fit}");
    }
    let forward = &report["test"]["forward"];
    eprintln!(
        "DBO crossval (cli): forward RMS {:.3} % max {:.3} %",
        forward["rms_percent"].as_f64().unwrap(),
        forward["max_percent"].as_f64().unwrap()
    );
    assert!(
        forward["rms_percent"].as_f64().unwrap() < 1.5 * 2.627,
        "{forward}"
    );
    assert!(
        forward["max_percent"].as_f64().unwrap() < 1.5 * 7.515,
        "{forward}"
    );
    // Measured replay (RMS, max) %: ihc 1.801 / 5.933, ihc-delayed 1.789 / 5.985, wihc 1.801 /
    // 5.933, wihc-delayed not built (loop gain 3.15), dihc 1.672 / 6.020, ihc-guarded 1.789 /
    // 5.985, wihc-guarded 1.782 / 5.977 (2.219 / 6.598 before it delayed only the cubic).
    let measured = [
        [1.801, 5.933],
        [1.789, 5.985],
        [1.801, 5.933],
        [f64::NAN, f64::NAN],
        [1.672, 6.020],
        [1.789, 5.985],
        [1.782, 5.977],
    ];
    assert_eq!(report["test"]["replay"].as_array().unwrap().len(), 7);
    for (r, [m_rms, m_max]) in report["test"]["replay"]
        .as_array()
        .unwrap()
        .iter()
        .zip(measured)
    {
        if m_rms.is_nan() {
            assert!(
                r["failure"].as_str().unwrap().contains("can oscillate"),
                "{r}"
            );
            continue;
        }
        let rms = r["error"]["rms_percent"].as_f64().unwrap();
        let max = r["error"]["max_percent"].as_f64().unwrap();
        eprintln!(
            "DBO crossval (cli): replay {} RMS {rms:.3} % max {max:.3} %",
            r["compensator"]
        );
        assert!(rms < 1.5 * m_rms && max < 1.5 * m_max, "{r}");
    }
}

/// Issue 10's acceptance on the shared DBO record: with `-n auto` the best compensator's
/// offline inverse replay is within 1.2 % of the test voltage range; the choice is said on
/// stderr and is one of the candidates.
#[test]
fn dbo_crossval_with_n_auto_replays_the_best_compensator_within_1_2_percent() {
    let Some((train, test)) = dbo_records() else {
        return;
    };
    let out = dbo_crossval(&train, &test, &["-n", "auto"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let said = stderr(&out);
    assert!(
        said.contains("-n auto") && said.contains("chose n = "),
        "{said}"
    );
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let n = doc["report"]["plant"]["thresholds"]
        .as_array()
        .unwrap()
        .len();
    assert!(
        hystcomp_identify::AUTO_OPERATOR_CANDIDATES.contains(&n),
        "{n}"
    );
    let best = doc["report"]["test"]["replay"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|r| r["error"]["rms_percent"].as_f64())
        .fold(f64::INFINITY, f64::min);
    eprintln!("DBO crossval -n auto: n = {n}, best replay RMS {best:.3} %");
    assert!(best <= 1.2, "best replay {best} % with n = {n}");
}

/// One record in one file, with measurement noise: the training cycle, then the test shape.
fn one_record(dir: &Path) -> (PathBuf, usize) {
    let ((v, y), (tv, ty)) = records();
    let voltage = [v, tv].concat();
    let displacement: Vec<f64> = [y, ty]
        .concat()
        .iter()
        .enumerate()
        .map(|(k, y)| y + 0.2 * (1.7 * k as f64).sin())
        .collect();
    let path = dir.join("record.csv");
    write_csv(&path, &["volts", "um"], &[&voltage, &displacement]);
    (path, voltage.len())
}

/// Consecutive row ranges of one file: crossval carries the operators' memory from the end of
/// the training rows into the test rows (said on stderr and in --json), and its figure is
/// `identify --holdout`'s for the same split, both in % of the test span's own displacement
/// range (its denominator in both reports). From rest (`--test-start rest`) the start is said
/// too, and the first test samples are another prediction.
#[test]
fn consecutive_spans_carry_memory_and_match_identify_holdout() {
    let dir = tempfile::tempdir().unwrap();
    let (record, rows) = one_record(dir.path());
    let columns = ["--voltage-column", "volts", "--displacement-column", "um"];
    let model = dir.path().join("model.json");
    let out = hystcomp(
        &[
            &["--json", "identify", "--data", s(&record)][..],
            &columns,
            &["--warmup", "0", "--holdout", "0.3", "-o", s(&model)],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let holdout = &doc["report"]["holdout"];
    let fitted = doc["report"]["samples"]["fit"].as_u64().unwrap() as usize;
    assert_eq!(doc["report"]["samples"]["warmup"], 0);
    let train_rows = format!("1..{fitted}");
    let test_rows = format!("{}..{rows}", fitted + 1);
    let predictions = dir.path().join("predictions.csv");
    let run = |test_rows: &str, extra: &[&str]| {
        let args = [
            &[
                "--json",
                "crossval",
                "--train",
                s(&record),
                "--test",
                s(&record),
            ][..],
            &columns,
            &[
                "--train-rows",
                &train_rows,
                "--test-rows",
                test_rows,
                "--warmup",
                "0",
            ],
            extra,
        ]
        .concat();
        let out = hystcomp(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
        (doc["report"]["test"].clone(), stderr(&out))
    };
    let (carried, note) = run(&test_rows, &["--predictions", s(&predictions)]);
    assert_eq!(carried["start"], "continue_training");
    assert_eq!(carried["preceding_samples"], fitted);
    assert_eq!(carried["warmup"], 0);
    assert!(
        note.contains("continued from the end of the training record")
            && note.contains("consecutive row ranges"),
        "{note}"
    );
    let figure = |v: &Value| v["rms_percent"].as_f64().unwrap();
    let (a, b) = (figure(holdout), figure(&carried["forward"]));
    assert!(
        (a - b).abs() <= 1e-9 * a,
        "identify --holdout {a} % vs crossval {b} %"
    );
    // The same denominator, written in both reports: the test span's displacement range.
    let range = holdout["range"].as_f64().unwrap();
    assert!((range - carried["ranges"]["displacement"].as_f64().unwrap()).abs() <= 1e-9 * range);
    assert!((range - carried["forward"]["range"].as_f64().unwrap()).abs() <= 1e-9 * range);
    // --predictions runs the models as the validation does: its RMS is the report's.
    let (header, columns_read) = read_csv(&predictions);
    let error = header.iter().position(|h| h == "error_um").unwrap();
    let rms = (columns_read[error].iter().map(|e| e * e).sum::<f64>()
        / columns_read[error].len() as f64)
        .sqrt();
    assert!(
        (100.0 * rms / range - b).abs() <= 1e-6 * b,
        "{rms} vs {b} %"
    );

    let (rest, note) = run(&test_rows, &["--test-start", "rest", "--test-warmup", "0"]);
    assert_eq!(rest["start"], "rest");
    assert_eq!(rest["preceding_samples"], 0);
    assert!(
        note.contains("at rest at the test record's first sample"),
        "{note}"
    );
    assert!(
        (figure(&rest["forward"]) - b).abs() > 1e-6 * b,
        "starting from rest should change the prediction of the first test samples"
    );
    // Separate files (or non-consecutive rows) start at rest by default, and say how to carry.
    let (separate, note) = run("1..2000", &[]);
    assert_eq!(separate["start"], "rest");
    assert!(note.contains("--test-start continue"), "{note}");
}

/// Issue 10's acceptance on the shared DBO record: `crossval` with defaults, n = 10, 20, 30
/// and 50: every compensator built replays the applied voltage within 1.9 % RMS of the voltage
/// range; the only one not built is the plain delayed WIHC, refused because its loop gain
/// (3.15-37) says it can oscillate. The guarded WIHC, which delays only the cubic since issue
/// 10's fix, replays as the delayed IHC does (before: 2.22 / 2.32 / 2.17 / 2.45 %).
#[test]
fn dbo_crossval_replays_every_compensator_within_1_9_percent_for_n_10_to_50() {
    let Some((train, test)) = dbo_records() else {
        return;
    };
    for n in ["10", "20", "30", "50"] {
        let out = dbo_crossval(&train, &test, &["-n", n]);
        assert!(out.status.success(), "n = {n}: {}", stderr(&out));
        let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
        for r in doc["report"]["test"]["replay"].as_array().unwrap() {
            let name = r["compensator"].as_str().unwrap();
            let Some(rms) = r["error"]["rms_percent"].as_f64() else {
                assert_eq!(name, "wihc-delayed", "n = {n}: {r}");
                assert!(
                    r["failure"].as_str().unwrap().contains("can oscillate"),
                    "{r}"
                );
                continue;
            };
            eprintln!("DBO crossval n = {n}: replay {name} RMS {rms:.3} %");
            assert!(rms <= 1.9, "n = {n}: {name} replays to {rms} %");
        }
    }
}
