//! `hystcomp identify` through the binary: files in every supported shape, JSON output,
//! reproducible swarms, and every bad input with a non-zero exit and a message to act on.

mod common;

use common::*;

use std::path::{Path, PathBuf};
use std::process::Output;

use hystcomp_core::Mpim;
use hystcomp_io::model_file::{Direction, ModelFile};
use serde_json::Value;

/// A synthetic record at 200 Hz from Table 1 of the paper: a decaying 1 Hz cycle between
/// 0 and 10 V, starting at 0 V; displacement in um with a sensor offset of -40 um.
fn record(samples: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let thresholds = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
    let weights = [
        0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ];
    let mut plant: Mpim<f64, Vec<f64>> = Mpim::new(&thresholds, &weights, -0.1569, 0.4603).unwrap();
    let time: Vec<f64> = (0..samples).map(|k| k as f64 / 200.0).collect();
    let voltage: Vec<f64> = time
        .iter()
        .map(|t| {
            // Full range (exactly 0 and 10 V) in the first cycle, so that the normalised
            // thresholds are those of Table 1; then decaying.
            let envelope = (-(t - 0.5).max(0.0) / 15.0).exp();
            5.0 - 5.0 * envelope * (2.0 * std::f64::consts::PI * t).cos()
        })
        .collect();
    let displacement = voltage
        .iter()
        .map(|v| -40.0 + 75.0 * plant.step(v / 10.0))
        .collect();
    (time, voltage, displacement)
}

/// Writes rows of numbers (and an optional header) with `delimiter`.
fn write_table(path: &Path, header: Option<&[&str]>, columns: &[&[f64]], delimiter: &str) {
    let mut text = String::new();
    if let Some(names) = header {
        text.push_str(&names.join(delimiter));
        text.push('\n');
    }
    for r in 0..columns[0].len() {
        let row: Vec<String> = columns.iter().map(|c| format!("{:?}", c[r])).collect();
        text.push_str(&row.join(delimiter));
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

fn csv_record(dir: &Path, samples: usize) -> PathBuf {
    let (t, v, y) = record(samples);
    let path = dir.join("record.csv");
    write_table(
        &path,
        Some(&["time_s", "voltage_V", "position_um"]),
        &[&t, &v, &y],
        ",",
    );
    path
}

#[test]
fn identifies_a_csv_with_a_header_by_column_names() {
    let dir = tempfile::tempdir().unwrap();
    let data = csv_record(dir.path(), 4000);
    let model_path = dir.path().join("plant.json");
    let out = hystcomp(&[
        "identify",
        "--data",
        s(&data),
        "--voltage-column",
        "voltage_V",
        "--displacement-column",
        "position_um",
        "--time-column",
        "time_s",
        "-o",
        s(&model_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("fit:"), "{}", stdout(&out));
    let model = ModelFile::load(&model_path).unwrap();
    assert_eq!(model.direction, Direction::Plant);
    assert_eq!(model.input.unit, "V");
    assert_eq!(model.output.unit, "um");
    let mpim = model.model().unwrap();
    assert!(mpim.check_invertible(0.0, 1.0).is_ok());
    // Noise-free data from Table 1: the prediction reproduces the record.
    let (_, v, y) = record(4000);
    let mut m = mpim.clone();
    for (v, y) in v.iter().zip(&y) {
        let predicted = model.output_to_physical(m.step(model.normalise_input(*v)));
        assert!((predicted - y).abs() < 1e-6, "{predicted} vs {y}");
    }
    let identification = model.identification.expect("the fit report is kept");
    assert_eq!(identification["solver"], "ls");
    assert!(
        identification["data"]
            .as_str()
            .unwrap()
            .ends_with("record.csv")
    );
}

#[test]
fn json_output_is_one_document_with_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let (t, v, y) = record(3000);
    // Tab-separated without a header, columns by index, as the DBO files.
    let data = dir.path().join("record.dat");
    write_table(&data, None, &[&v, &t, &y], "\t");
    let model_path = dir.path().join("inverse.json");
    let out = hystcomp(&[
        "--json",
        "identify",
        "--data",
        s(&data),
        "--voltage-column",
        "1",
        "--displacement-column",
        "3",
        "--direction",
        "inverse",
        "--holdout",
        "0.25",
        "-o",
        s(&model_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: Value = serde_json::from_str(&stdout(&out)).expect("stdout is one JSON document");
    let report = &doc["report"];
    assert_eq!(report["direction"], "inverse");
    assert_eq!(report["input"]["quantity"], "displacement");
    let samples = &report["samples"];
    let total = samples["total"].as_u64().unwrap();
    assert_eq!(total, 3000);
    assert_eq!(
        samples["warmup"].as_u64().unwrap()
            + samples["fit"].as_u64().unwrap()
            + samples["holdout"].as_u64().unwrap(),
        total
    );
    assert!(report["fit"]["rms_percent"].as_f64().unwrap() < 2.0);
    assert!(report["holdout"]["rms_percent"].as_f64().unwrap() < 2.0);
    assert!(report["elapsed_s"].as_f64().unwrap() > 0.0);
    let model = ModelFile::load(&model_path).unwrap();
    assert_eq!(model.direction, Direction::Inverse);
    assert_eq!(doc["model"]["a1"].as_f64().unwrap(), model.a1);
    assert!(model.model().unwrap().check_invertible(0.0, 1.0).is_ok());
}

#[test]
fn whitespace_files_row_ranges_and_warmup_seconds() {
    let dir = tempfile::tempdir().unwrap();
    let (t, v, y) = record(3000);
    let data = dir.path().join("record.txt");
    write_table(&data, Some(&["t", "u", "y"]), &[&t, &v, &y], "   ");
    let model_path = dir.path().join("m.json");
    let out = hystcomp(&[
        "--json",
        "identify",
        "--data",
        s(&data),
        "--voltage-column",
        "u",
        "--displacement-column",
        "y",
        "--time-column",
        "t",
        "--rows",
        "101:2600",
        "--warmup-seconds",
        "0.5",
        "--holdout",
        "0",
        "-n",
        "6",
        "-o",
        s(&model_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(doc["report"]["samples"]["total"], 2500);
    assert_eq!(doc["report"]["samples"]["warmup"], 100); // 0.5 s at 200 Hz
    assert_eq!(doc["report"]["thresholds"].as_array().unwrap().len(), 6);
    assert!(doc["report"]["holdout"].is_null());
}

/// A MAT-file with real hysteresis, written by scipy (see the fixtures' README: Table 1 of the
/// paper driven by a decaying 1 Hz cycle, 600 samples at 200 Hz, compressed): identified
/// through the binary, the paper's parameters come back.
#[test]
fn identifies_table1_from_a_scipy_matlab_file() {
    let dir = tempfile::tempdir().unwrap();
    let fixture = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../io/tests/fixtures/scipy_hysteresis.mat"
    );
    let model_path = dir.path().join("m.json");
    let out = hystcomp(&[
        "--json",
        "identify",
        "--data",
        fixture,
        "--time-column",
        "t",
        "--voltage-column",
        "volts",
        "--displacement-column",
        "um",
        "-o",
        s(&model_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: Value = serde_json::from_slice(&out.stdout).expect("one JSON document");
    assert_eq!(doc["report"]["samples"]["total"], 600);
    assert!(
        doc["report"]["fit"]["rms_percent"].as_f64().unwrap() < 1e-6,
        "{doc}"
    );
    let model = ModelFile::load(&model_path).unwrap();
    assert_eq!(model.direction, Direction::Plant);
    assert_eq!((model.input.offset, model.input.scale), (0.0, 10.0));
    // Normalised by the record's displacement range instead of 75 um: rescale to compare.
    let k = model.output.scale / 75.0;
    assert!((k * model.a1 - -0.1569).abs() < 1e-6, "{}", k * model.a1);
    assert!((k * (model.a2 + model.weights[0]) - (0.4603 + 0.2313)).abs() < 1e-6);
    for (i, b) in [
        0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ]
    .iter()
    .enumerate()
    {
        assert!((k * model.weights[i + 1] - b).abs() < 1e-6, "b{}", i + 2);
    }
    // The sensor offset of -40 um is the physical output at normalised 0.
    assert!(
        (model.output.offset - -40.0).abs() < 1e-6,
        "{}",
        model.output.offset
    );
}

#[test]
fn reads_a_matlab_level5_file_and_explains_v73() {
    let dir = tempfile::tempdir().unwrap();
    let fixture = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../io/tests/fixtures/scipy_record.mat"
    );
    let model_path = dir.path().join("m.json");
    let out = hystcomp(&[
        "identify",
        "--data",
        fixture,
        "--voltage-column",
        "u",
        "--displacement-column",
        "y",
        "-n",
        "1",
        "--holdout",
        "0",
        "-o",
        s(&model_path),
    ]);
    // The fixture's variables are exact linear functions of one counter (u = k/4 - 1,
    // y = k/2 - 100): read, then refused as no hysteresis record (correlation 1).
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("exact linear function"),
        "{}",
        stderr(&out)
    );
    assert!(!model_path.exists());

    // A MATLAB v7.3 file is HDF5: a 512-byte text header, then the HDF5 signature.
    let v73 = dir.path().join("record.mat");
    let mut bytes = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 .".to_vec();
    bytes.resize(512, b' ');
    bytes.extend_from_slice(b"\x89HDF\r\n\x1a\n");
    bytes.resize(2048, 0);
    std::fs::write(&v73, bytes).unwrap();
    let out = hystcomp(&[
        "identify",
        "--data",
        v73.to_str().unwrap(),
        "--voltage-column",
        "u",
        "--displacement-column",
        "y",
        "-o",
        s(&model_path),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("-v7"), "{}", stderr(&out));
}

#[test]
fn the_swarm_is_reproducible_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let data = csv_record(dir.path(), 2000);
    let run = |name: &str, seed: &str| {
        let path = dir.path().join(name);
        let out = hystcomp(&[
            "identify",
            "--data",
            s(&data),
            "--voltage-column",
            "2",
            "--displacement-column",
            "3",
            "--method",
            "pso",
            "--seed",
            seed,
            "--pso-iterations",
            "60",
            "-o",
            s(&path),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        ModelFile::load(&path).unwrap()
    };
    let a = run("a.json", "7");
    let b = run("b.json", "7");
    let c = run("c.json", "8");
    assert_eq!((a.a1, a.a2, &a.weights), (b.a1, b.a2, &b.weights));
    assert_ne!((a.a1, &a.weights), (c.a1, &c.weights));
    assert_eq!(a.identification.unwrap()["pso"]["seed"], 7);
}

/// Runs identify on `contents` (written to a file) and returns the failed output.
fn refused(contents: &str, extra: &[&str]) -> Output {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("bad.csv");
    std::fs::write(&data, contents).unwrap();
    let model_path = dir.path().join("m.json");
    let mut args = vec![
        "identify",
        "--data",
        s(&data),
        "--voltage-column",
        "v",
        "--displacement-column",
        "y",
        "-o",
        s(&model_path),
    ];
    args.extend_from_slice(extra);
    let out = hystcomp(&args);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(!model_path.exists(), "no model file is written");
    assert!(stdout(&out).is_empty());
    out
}

/// A good record as CSV text with columns t, v, y, with `edit` applied to its lines.
fn csv_text(samples: usize, edit: impl Fn(usize, String) -> String) -> String {
    let (t, v, y) = record(samples);
    let mut text = "t,v,y\n".to_owned();
    for k in 0..samples {
        text.push_str(&edit(k, format!("{:?},{:?},{:?}", t[k], v[k], y[k])));
        text.push('\n');
    }
    text
}

#[test]
fn bad_inputs_are_refused_with_a_message_to_act_on() {
    // Ragged rows.
    let out = refused(
        &csv_text(
            500,
            |k, line| {
                if k == 40 { format!("{line},9") } else { line }
            },
        ),
        &[],
    );
    assert!(stderr(&out).contains("line 42"), "{}", stderr(&out));
    assert!(stderr(&out).contains("same number of fields"));

    // NaN and infinite values.
    let out = refused(
        &csv_text(500, |k, line| {
            if k == 10 {
                "0.05,NaN,1.0".to_owned()
            } else {
                line
            }
        }),
        &[],
    );
    assert!(
        stderr(&out).contains("not a finite number"),
        "{}",
        stderr(&out)
    );
    let out = refused(
        &csv_text(500, |k, line| {
            if k == 10 {
                "0.05,1.0,inf".to_owned()
            } else {
                line
            }
        }),
        &[],
    );
    assert!(
        stderr(&out).contains("not a finite number"),
        "{}",
        stderr(&out)
    );

    // Non-increasing time.
    let out = refused(
        &csv_text(500, |k, line| {
            if k == 20 {
                line.replacen("0.1,", "0.09,", 1)
            } else {
                line
            }
        }),
        &["--time-column", "t"],
    );
    assert!(
        stderr(&out).contains("time is not increasing"),
        "{}",
        stderr(&out)
    );

    // Constant input, constant output.
    let flat_v = csv_text(500, |k, _| format!("{},2.5,{}", k as f64 / 200.0, k % 7));
    let out = refused(&flat_v, &[]);
    assert!(stderr(&out).contains("voltage"), "{}", stderr(&out));
    assert!(stderr(&out).contains("constant"));
    let flat_y = csv_text(500, |k, _| format!("{},{},-3", k as f64 / 200.0, k % 7));
    let out = refused(&flat_y, &[]);
    assert!(stderr(&out).contains("displacement"), "{}", stderr(&out));
    assert!(stderr(&out).contains("constant"));

    // Too few samples: says how many are needed.
    let out = refused(&csv_text(20, |_, line| line), &[]);
    assert!(
        stderr(&out).contains("at least 36 needed"),
        "{}",
        stderr(&out)
    );

    // A column that does not exist: names the ones that do.
    let out = refused(
        &csv_text(500, |_, line| line),
        &["--time-column", "seconds"],
    );
    let message = stderr(&out);
    assert!(message.contains("\"seconds\""), "{message}");
    assert!(message.contains("\"t\"") && message.contains("\"v\"") && message.contains("\"y\""));

    // Options that cannot be used.
    let out = refused(&csv_text(500, |_, line| line), &["--holdout", "1.5"]);
    assert!(stderr(&out).contains("holdout"), "{}", stderr(&out));
    let out = refused(
        &csv_text(500, |_, line| line),
        &["--thresholds", "0,0.5,0.4"],
    );
    assert!(
        stderr(&out).contains("increase strictly"),
        "{}",
        stderr(&out)
    );
    let out = refused(&csv_text(500, |_, line| line), &["--warmup-seconds", "1"]);
    assert!(stderr(&out).contains("--sample-rate"), "{}", stderr(&out));
}

#[test]
fn an_unwritable_model_path_is_an_output_error() {
    let dir = tempfile::tempdir().unwrap();
    let data = csv_record(dir.path(), 1000);
    let model_path = dir.path().join("no such folder").join("m.json");
    let out = hystcomp(&[
        "identify",
        "--data",
        s(&data),
        "--voltage-column",
        "2",
        "--displacement-column",
        "3",
        "-o",
        s(&model_path),
    ]);
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    assert!(stderr(&out).contains("m.json"));
}

/// Runs identify with `args` after `identify`, asserting exit status 1, no model written, and
/// every fragment in the message; returns the message.
fn refuses(model_path: &Path, args: &[&str], fragments: &[&str]) -> String {
    let mut all = vec!["identify"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["-o", s(model_path)]);
    let out = hystcomp(&all);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {}", stderr(&out));
    assert!(!model_path.exists(), "{args:?}: no model file is written");
    let message = stderr(&out);
    for fragment in fragments {
        assert!(
            message.contains(fragment),
            "{args:?}: {fragment:?} not in: {message}"
        );
    }
    assert!(!message.contains("panicked"), "{message}");
    message
}

/// A headerless tab-separated record like the DBO files: time, voltage, displacement, a
/// nearly constant column (a constant plus 1e-6 noise).
fn tab_record(dir: &Path) -> PathBuf {
    let (t, v, y) = record(3000);
    let noise: Vec<f64> = (0..t.len())
        .map(|k| 4.2 + 1e-6 * ((k * 7919) % 101) as f64 / 101.0)
        .collect();
    let path = dir.join("record.dat");
    write_table(&path, None, &[&t, &v, &y, &noise], "\t");
    path
}

/// Inputs whose fit cannot describe a piezo: the same column twice, a sign-flipped or
/// nearly constant displacement, an output offset far off the data (unless accepted).
#[test]
fn fits_that_cannot_describe_a_piezo_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = tab_record(dir.path());
    let d = s(&data);
    let m = dir.path().join("m.json");
    let cols = |v: &'static str, y: &'static str| {
        [
            "--data",
            d,
            "--voltage-column",
            v,
            "--displacement-column",
            y,
        ]
    };

    let mut args = cols("2", "2").to_vec();
    // The library's refusal, with the file and the two columns given.
    refuses(
        &m,
        &args,
        &[
            "exact linear function",
            "voltage column 2, displacement column 2",
            "--displacement-column",
        ],
    );
    args.extend(["--displacement-factor", "15"]);
    refuses(&m, &args, &["exact linear function", "same column"]);
    let mut args = cols("2", "3").to_vec();
    args.extend(["--voltage-factor", "-1"]);
    let message = refuses(
        &m,
        &args,
        &["does not rise", "correlation", "sign", "factors"],
    );
    assert!(message.contains("-0.9"), "{message}");
    refuses(
        &m,
        &cols("2", "4"),
        &["does not rise", "correlation", "columns"],
    );
    let mut args = cols("2", "3").to_vec();
    args.extend(["--offset", "-500"]);
    refuses(&m, &args, &["RMS error", "--accept-poor-fit"]);
    args.push("--accept-poor-fit");
    let out = hystcomp(&[&["identify"], &args[..], &["-o", s(&m)]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let model = ModelFile::load(&m).unwrap();
    let rms = model.identification.unwrap()["fit"]["rms_percent"]
        .as_f64()
        .unwrap();
    assert!(rms > 10.0, "{rms}");
}

/// Output paths that are an input file are refused, and the record is left as it was.
#[test]
fn the_model_never_overwrites_the_record() {
    let dir = tempfile::tempdir().unwrap();
    let data = tab_record(dir.path());
    let before = std::fs::read(&data).unwrap();
    let args = [
        "--data",
        s(&data),
        "--voltage-column",
        "2",
        "--displacement-column",
        "3",
    ];
    for output in [data.clone(), dir.path().join(".").join("record.dat")] {
        let out = hystcomp(&[&["identify"], &args[..], &["-o", s(&output)]].concat());
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        assert!(
            stderr(&out).contains("same file as --data"),
            "{}",
            stderr(&out)
        );
        assert_eq!(
            std::fs::read(&data).unwrap(),
            before,
            "the record is intact"
        );
    }
}

/// Bad files and columns: a missing column by index, a name in a headerless file, an empty
/// file, a missing file, a repeated time value, a wrong delimiter, a truncated MAT-file.
#[test]
fn bad_files_and_columns_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = tab_record(dir.path());
    let d = s(&data);
    let m = dir.path().join("m.json");
    refuses(
        &m,
        &[
            "--data",
            d,
            "--voltage-column",
            "2",
            "--displacement-column",
            "9",
        ],
        &["no column 9", "4 columns"],
    );
    refuses(
        &m,
        &[
            "--data",
            d,
            "--voltage-column",
            "voltage",
            "--displacement-column",
            "3",
        ],
        &["\"voltage\"", "no header", "by number"],
    );
    let message = refuses(
        &m,
        &[
            "--data",
            d,
            "--voltage-column",
            "2",
            "--displacement-column",
            "3",
            "--delimiter",
            "comma",
        ],
        &["1 column", "--delimiter"],
    );
    assert!(message.contains("record.dat"), "{message}");
    let empty = dir.path().join("empty.dat");
    std::fs::write(&empty, "").unwrap();
    refuses(
        &m,
        &[
            "--data",
            s(&empty),
            "--voltage-column",
            "1",
            "--displacement-column",
            "2",
        ],
        &["empty.dat", "no rows"],
    );
    let missing = dir.path().join("missing.dat");
    refuses(
        &m,
        &[
            "--data",
            s(&missing),
            "--voltage-column",
            "1",
            "--displacement-column",
            "2",
        ],
        &["missing.dat", "check the path"],
    );
    // A repeated time value in a headerless file: "time column 1", said once.
    let (t, v, y) = record(600);
    let mut t2 = t.clone();
    t2[100] = t2[99];
    let repeated = dir.path().join("repeated.dat");
    write_table(&repeated, None, &[&t2, &v, &y], "\t");
    let message = refuses(
        &m,
        &[
            "--data",
            s(&repeated),
            "--voltage-column",
            "2",
            "--displacement-column",
            "3",
            "--time-column",
            "1",
        ],
        &["time column 1", "not increasing"],
    );
    assert!(!message.contains("column column"), "{message}");
    // A Level-5 MAT-file cut short.
    let fixture = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../io/tests/fixtures/scipy_record.mat"
    );
    let bytes = std::fs::read(fixture).unwrap();
    let cut = dir.path().join("cut.mat");
    std::fs::write(&cut, &bytes[..300]).unwrap();
    refuses(
        &m,
        &[
            "--data",
            s(&cut),
            "--voltage-column",
            "u",
            "--displacement-column",
            "y",
        ],
        &["cut.mat", "truncated"],
    );
}

/// Options checked by the program, not by the argument parser, each named in its message.
#[test]
fn option_values_are_named_in_their_messages() {
    let dir = tempfile::tempdir().unwrap();
    let data = tab_record(dir.path());
    let m = dir.path().join("m.json");
    let base = [
        "--data",
        s(&data),
        "--voltage-column",
        "2",
        "--displacement-column",
        "3",
    ];
    let with = |extra: &[&'static str]| [&base[..], extra].concat();
    refuses(
        &m,
        &with(&["--holdout", "-0.1"]),
        &["holdout", "-0.1", "[0, 1)"],
    );
    refuses(
        &m,
        &with(&["--voltage-factor", "1e308"]),
        &["--voltage-factor", "beyond 1e15"],
    );
    refuses(&m, &with(&["--max-condition", "1.5"]), &["limit 1.5)"]);
    refuses(
        &m,
        &with(&["--method", "pso", "--bound", "0"]),
        &["--bound 0", "positive"],
    );
    refuses(
        &m,
        &with(&["--method", "pso", "--offset-bound", "-1"]),
        &["--offset-bound"],
    );
}

/// `--thresholds` sets the model's thresholds (here r_i = (i - 0.5)/n, none at 0), and the
/// text report counts the operators in good English.
#[test]
fn given_thresholds_are_used() {
    let dir = tempfile::tempdir().unwrap();
    let data = tab_record(dir.path());
    let m = dir.path().join("m.json");
    let base = [
        "identify",
        "--data",
        s(&data),
        "--voltage-column",
        "2",
        "--displacement-column",
        "3",
    ];
    let out = hystcomp(
        &[
            &base[..],
            &["--thresholds", "0.125,0.375,0.625,0.875", "-o", s(&m)],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let model = ModelFile::load(&m).unwrap();
    assert_eq!(model.thresholds, [0.125, 0.375, 0.625, 0.875]);
    assert!(
        stdout(&out).contains("4 play operators"),
        "{}",
        stdout(&out)
    );
    let report = model.identification.unwrap();
    assert!(report["fit"]["rms_percent"].as_f64().unwrap() < 5.0);
    let out = hystcomp(&[&base[..], &["--thresholds", "0.5", "-o", s(&m)]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("1 play operator,"),
        "{}",
        stdout(&out)
    );
}

/// `identify --for-delayed` on the real DBO record: both delayed gains below the bound in the
/// report and the model file, the cost in fit RMS said, and `compensate` runs the plain delayed
/// WIHC it refuses on the model fitted without the flag (loop gain 3.15), naming the flag.
#[test]
fn for_delayed_fits_a_model_compensate_runs_with_the_delayed_loops() {
    let Some(record) = hystcomp_testkit::dbo_record("Model_Vi_Do.dat") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let free = dir.path().join("free.json");
    let bounded = dir.path().join("bounded.json");
    let base = [
        "identify",
        "--data",
        s(&record),
        "--voltage-column",
        "1",
        "--displacement-column",
        "5",
    ];
    let out = hystcomp(&[&base[..], &["-o", s(&free)]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("identify with --for-delayed"),
        "{}",
        stdout(&out)
    );
    let out = hystcomp(
        &[
            &["--json"],
            &base[..],
            &["--for-delayed", "-o", s(&bounded)],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    let report = if report.get("report").is_some() {
        &report["report"]
    } else {
        &report
    };
    let gains = &report["delayed_loop_gains"];
    for which in ["ihc", "wihc"] {
        let g = gains[which].as_f64().unwrap();
        assert!(g <= 0.9 + 1e-9, "{which} {g}: {report}");
    }
    let c = &report["delayed_constraint"];
    assert_eq!(c["bound"].as_f64(), Some(0.9), "{report}");
    let free_rms = c["unconstrained_fit_rms_percent"].as_f64().unwrap();
    let rms = report["fit"]["rms_percent"].as_f64().unwrap();
    eprintln!("DBO --for-delayed: fit RMS {rms:.4} % against {free_rms:.4} % without the bound");
    assert!(rms >= free_rms - 1e-9 && rms < 3.0 * free_rms, "{report}");
    assert!(
        c["unconstrained_gains"]["wihc"].as_f64().unwrap() > 1.0,
        "{report}"
    );
    // The model file carries the same report.
    let text = std::fs::read_to_string(&bounded).unwrap();
    assert!(text.contains("delayed_constraint"), "{text}");

    let trajectory = dir.path().join("trajectory.csv");
    let mut csv = String::from("time_s,desired_um\n");
    for k in 0..400 {
        let t = k as f64 * 1e-3;
        let y = -96.0 + 15.0 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
        csv.push_str(&format!("{t},{y}\n"));
    }
    std::fs::write(&trajectory, csv).unwrap();
    let drive = dir.path().join("drive.csv");
    let compensate = |model: &Path| {
        hystcomp(&[
            "compensate",
            "--model",
            s(model),
            "--method",
            "wihc-delayed",
            "--desired",
            s(&trajectory),
            "-o",
            s(&drive),
        ])
    };
    let refused = compensate(&free);
    assert_eq!(refused.status.code(), Some(1), "{}", stderr(&refused));
    assert!(
        stderr(&refused).contains("--allow-unstable-delay"),
        "{}",
        stderr(&refused)
    );
    let out = compensate(&bounded);
    assert!(
        out.status.code() == Some(0) || out.status.code() == Some(4),
        "{}",
        stderr(&out)
    );
    assert!(drive.exists());
}

/// Issue 10: which samples were fitted and why, on stderr and in `--json`; `--warmup
/// estimate`; `--input-degree` (a degree-7 model file that `compensate` runs), and the
/// degrees and solvers it refuses. On the shared DBO record, which starts mid-range.
#[test]
fn warmup_reasons_and_input_degree_on_the_dbo_record() {
    let Some(data) = hystcomp_testkit::dbo_record("Model_Vi_Do.dat") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("d7.json");
    let base = [
        "--json",
        "identify",
        "--data",
        s(&data),
        "--voltage-column",
        "1",
        "--displacement-column",
        "5",
        "-o",
        s(&model),
    ];
    let run = |extra: &[&str]| {
        let mut args = base.to_vec();
        args.extend(extra);
        let out = hystcomp(&args);
        assert!(out.status.success(), "{extra:?}: {}", stderr(&out));
        let doc: Value = serde_json::from_str(&stdout(&out)).unwrap();
        (doc, stderr(&out))
    };
    let (auto, message) = run(&[]);
    let w = &auto["report"]["warmup"];
    assert_eq!(w["mode"], "auto");
    assert_eq!(w["first_fitted"], 44);
    assert_eq!(auto["report"]["samples"]["warmup"], 44);
    assert!(
        message.contains("fitted samples 45..6431 of 8027"),
        "{message}"
    );
    assert!(message.contains("wiping-out"), "{message}");
    assert!(w["reason"].as_str().unwrap().contains("sample 45"), "{w}");

    let (estimate, message) = run(&["--warmup", "estimate"]);
    let w = &estimate["report"]["warmup"];
    assert_eq!(w["mode"], "estimate");
    assert_eq!(w["first_fitted"], 0);
    assert_eq!(w["history"].as_array().unwrap().len(), 3);
    assert_eq!(w["initial_memory"].as_array().unwrap().len(), 10);
    assert!(
        message.contains("estimated with the parameters"),
        "{message}"
    );

    let (seventh, _) = run(&["--input-degree", "7"]);
    let cubic = auto["report"]["fit"]["rms_percent"].as_f64().unwrap();
    let d7 = seventh["report"]["fit"]["rms_percent"].as_f64().unwrap();
    assert!(
        d7 <= cubic * (1.0 + 1e-9),
        "degree 7 {d7} % against the cubic's {cubic} %"
    );
    let file = ModelFile::load(&model).unwrap();
    assert_eq!(file.input_polynomial.as_ref().unwrap().len(), 7);
    // The degree-7 model compensates (exact IHC) within its limits.
    let desired = dir.path().join("desired.csv");
    let mut text = String::from("time_s,desired_um\n");
    for k in 0..400 {
        let t = k as f64 / 200.0;
        text.push_str(&format!(
            "{t},{}\n",
            -96.0 + 18.0 * (2.0 * std::f64::consts::PI * t).sin()
        ));
    }
    std::fs::write(&desired, text).unwrap();
    let drive = dir.path().join("drive.csv");
    let out = hystcomp(&[
        "compensate",
        "--model",
        s(&model),
        "--desired",
        s(&desired),
        "--method",
        "ihc",
        "--allow-saturation",
        "-o",
        s(&drive),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let written = std::fs::read_to_string(&drive).unwrap();
    let (lo, hi) = (file.input.offset, file.input.offset + file.input.scale);
    let mut rows = 0;
    for line in written.lines().skip(1) {
        let v: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        assert!(v.is_finite() && v >= lo - 1e-9 && v <= hi + 1e-9, "{line}");
        rows += 1;
    }
    assert_eq!(rows, 400);

    for (extra, fragment) in [
        (&["--input-degree", "4"][..], "--input-degree 4"),
        (&["--input-degree", "11"][..], "--input-degree 11"),
        (
            &["--input-degree", "7", "--method", "pso"][..],
            "needs --method ls",
        ),
        (&["--warmup", "later"][..], "auto, estimate"),
    ] {
        let mut args = base.to_vec();
        args.extend(extra);
        assert_fails(&args, &[fragment]);
    }
}
