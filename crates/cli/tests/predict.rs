//! `hystcomp predict` and `crossval --predictions` through the binary: the written
//! predictions against the model run independently, the errors against the report's, and
//! refusals (units that disagree, an output naming an input).

mod common;

use common::*;

use std::path::Path;

use hystcomp_io::model_file::ModelFile;
use serde_json::Value;

/// A record of Table 1 from its reset state: time, volts (0..10 V with reversals) and um.
fn table1_record(dir: &Path) -> (std::path::PathBuf, Vec<f64>, Vec<f64>) {
    let file = ModelFile::load(&models().join("table1-plant.json")).unwrap();
    let mut plant = file.model().unwrap();
    let mut text = String::from("time_s,volts,um\n");
    let (mut volts, mut um) = (Vec::new(), Vec::new());
    for k in 0..1500 {
        let t = k as f64 * 1e-3;
        let v = 5.0 - 5.0 * (-t).exp() * (2.0 * std::f64::consts::PI * 3.0 * t).cos();
        let y = file.output_to_physical(plant.step(file.normalise_input(v)));
        text.push_str(&format!("{t:?},{v:?},{y:?}\n"));
        volts.push(v);
        um.push(y);
    }
    let path = dir.join("record.csv");
    std::fs::write(&path, text).unwrap();
    (path, volts, um)
}

#[test]
fn predict_writes_the_models_output_beside_the_measurement() {
    let dir = tempfile::tempdir().unwrap();
    let (record, volts, um) = table1_record(dir.path());
    let out = dir.path().join("predicted.csv");
    let model = models().join("table1-plant.json");
    let o = hystcomp(&[
        "--json",
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&record),
        "--voltage-column",
        "volts",
        "--displacement-column",
        "um",
        "--time-column",
        "time_s",
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["samples"], 1500);
    assert_eq!(report["direction"], "plant");
    assert!(
        report["error"]["rms_percent"].as_f64().unwrap() < 1e-9,
        "{report}"
    );
    let (header, columns) = read_csv(&out);
    assert_eq!(
        header,
        [
            "time_s",
            "drive_v",
            "measured_um",
            "predicted_um",
            "error_um"
        ]
    );
    for k in 0..volts.len() {
        assert_eq!(columns[1][k], volts[k]);
        assert_eq!(columns[2][k], um[k]);
        assert!((columns[3][k] - um[k]).abs() < 1e-9, "row {k}");
        assert_eq!(columns[4][k], columns[3][k] - columns[2][k]);
    }
    // An inverse model maps the displacement to the voltage.
    let inverse_out = dir.path().join("inverse.csv");
    let o = hystcomp(&[
        "predict",
        "--model",
        s(&models().join("table2-inverse.json")),
        "--data",
        s(&record),
        "--voltage-column",
        "volts",
        "--displacement-column",
        "um",
        "-o",
        s(&inverse_out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, columns) = read_csv(&inverse_out);
    assert_eq!(
        header,
        ["sample", "measured_um", "drive_v", "predicted_v", "error_v"]
    );
    assert_eq!(columns[0][0], 1.0);
    // Units that disagree are refused, naming the options; the output may not be the input.
    assert_fails(
        &[
            "predict",
            "--model",
            s(&model),
            "--data",
            s(&record),
            "--voltage-column",
            "volts",
            "--displacement-column",
            "um",
            "--displacement-unit",
            "nm",
            "-o",
            s(&dir.path().join("x.csv")),
        ],
        &["table1-plant.json", "um", "nm", "--displacement-unit"],
    );
    assert!(!dir.path().join("x.csv").exists());
    let before = std::fs::read(&record).unwrap();
    let o = hystcomp(&[
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&record),
        "--voltage-column",
        "volts",
        "--displacement-column",
        "um",
        "-o",
        s(&record),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(std::fs::read(&record).unwrap(), before);
}

#[test]
fn crossval_predictions_are_the_validations_own() {
    let dir = tempfile::tempdir().unwrap();
    let (record, _, _) = table1_record(dir.path());
    let out = dir.path().join("predictions.csv");
    let o = hystcomp(&[
        "--json",
        "crossval",
        "--train",
        s(&record),
        "--test",
        s(&record),
        "--voltage-column",
        "volts",
        "--displacement-column",
        "um",
        "--time-column",
        "time_s",
        "--predictions",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: Value = serde_json::from_slice(&o.stdout).unwrap();
    let test = &doc["report"]["test"];
    let (header, columns) = read_csv(&out);
    assert_eq!(
        header,
        [
            "time_s",
            "drive_v",
            "measured_um",
            "predicted_um",
            "error_um",
            "predicted_drive_v",
            "drive_error_v",
            "scored"
        ]
    );
    let warmup = test["warmup"].as_u64().unwrap() as usize;
    assert_eq!(
        columns[7].iter().filter(|v| **v == 0.0).count(),
        warmup,
        "{test}"
    );
    let scored: Vec<f64> = (0..columns[0].len())
        .filter(|&k| columns[7][k] == 1.0)
        .map(|k| columns[4][k])
        .collect();
    let rms = (scored.iter().map(|e| e * e).sum::<f64>() / scored.len() as f64).sqrt();
    let reported = test["forward"]["rms"].as_f64().unwrap();
    assert!(
        (rms - reported).abs() <= 1e-6 * reported.max(1e-12),
        "{rms} against {reported}"
    );
}
