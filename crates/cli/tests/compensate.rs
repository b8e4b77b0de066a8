//! `hystcomp compensate` and `hystcomp bench` through the built binary.

mod common;

use common::*;

use std::path::{Path, PathBuf};
use std::process::Output;

/// A trajectory (time s, desired um) produced by a voltage sweep through the Table 1 plant,
/// so that it is reachable; returns the sweep too.
fn reachable_trajectory(dir: &Path) -> (PathBuf, Vec<f64>) {
    let file =
        hystcomp_io::model_file::ModelFile::load(&models().join("table1-plant.json")).unwrap();
    let mut plant = file.model().unwrap();
    let n = 2000;
    let time: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let volts: Vec<f64> = time
        .iter()
        .map(|t| {
            4.8 - 4.0 * (2.0 * std::f64::consts::PI * t).cos() * (1.0 - 0.15 * (9.0 * t).sin())
        })
        .collect();
    let desired: Vec<f64> = volts
        .iter()
        .map(|&v| file.output_to_physical(plant.step(file.normalise_input(v))))
        .collect();
    let path = dir.join("trajectory.csv");
    hystcomp_io::data::write_csv(&path, &["time_s", "desired_um"], &[&time, &desired]).unwrap();
    (path, volts)
}

fn read(path: &Path) -> Vec<Vec<f64>> {
    use hystcomp_io::data::{Column, ReadOptions, read_columns};
    read_columns(
        path,
        &[Column::Index(1), Column::Index(2), Column::Index(3)],
        &ReadOptions::default(),
    )
    .unwrap()
    .values
}

#[test]
fn every_method_writes_the_drive_and_exact_ones_recover_the_voltage() {
    let dir = tempfile::tempdir().unwrap();
    let (trajectory, volts) = reachable_trajectory(dir.path());
    for (method, model) in [
        ("ihc", "table1-plant.json"),
        ("ihc-delayed", "table1-plant.json"),
        ("wihc", "table1-plant.json"),
        ("wihc-delayed", "table1-plant.json"),
        ("dihc", "table2-inverse.json"),
    ] {
        let out = dir.path().join(format!("{method}.csv"));
        let o = hystcomp(&[
            "compensate",
            "--model",
            s(&models().join(model)),
            "--method",
            method,
            "--trajectory",
            s(&trajectory),
            "-o",
            s(&out),
        ]);
        assert!(o.status.success(), "{method}: {}", stderr(&o));
        let cols = read(&out);
        assert_eq!(cols[0].len(), 2000);
        assert_eq!(cols[0][1999], 1.999, "time column kept");
        for &v in &cols[1] {
            assert!(
                (0.0..=10.0).contains(&v),
                "{method}: drive {v} V outside 0..10 V"
            );
        }
        if method == "ihc" || method == "wihc" {
            for (v, v_true) in cols[1].iter().zip(&volts) {
                assert!((v - v_true).abs() < 1e-7, "{method}: {v} vs {v_true}");
            }
        }
    }
}

#[test]
fn json_report_and_saturation_exit_codes() {
    let dir = tempfile::tempdir().unwrap();
    // A trajectory that runs past the stage's reach (the plant gives at most ~70 um at 10 V).
    let time: Vec<f64> = (0..500).map(|k| k as f64 * 1e-3).collect();
    let desired: Vec<f64> = time.iter().map(|t| 40.0 + 60.0 * (6.0 * t).sin()).collect();
    let traj = dir.path().join("far.csv");
    hystcomp_io::data::write_csv(&traj, &["t", "y"], &[&time, &desired]).unwrap();
    let out = dir.path().join("out.csv");
    let model = models().join("table1-plant.json");
    let args = [
        "compensate",
        "--model",
        s(&model),
        "--method",
        "ihc",
        "--trajectory",
        s(&traj),
        "-o",
        s(&out),
        "--json",
    ];
    let o = hystcomp(&args);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("outside what the model can reach"),
        "{}",
        stderr(&o)
    );
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let saturated = report["saturated"].as_u64().unwrap();
    assert!(saturated > 0 && saturated < 500, "{report}");
    // The clamped output is written all the same, within the limits.
    for v in &read(&out)[1] {
        assert!((0.0..=10.0).contains(v));
    }
    let mut allowed = args.to_vec();
    allowed.push("--allow-saturation");
    let o = hystcomp(&allowed);
    assert!(o.status.success(), "{}", stderr(&o));
    // Narrower limits are honoured.
    let mut narrow = args.to_vec();
    narrow.extend(["--limits", "1:6", "--allow-saturation"]);
    assert!(hystcomp(&narrow).status.success());
    for v in &read(&out)[1] {
        assert!((1.0..=6.0).contains(v), "{v}");
    }
}

#[test]
fn bad_inputs_give_clear_messages_and_non_zero_exits() {
    let dir = tempfile::tempdir().unwrap();
    let (trajectory, _) = reachable_trajectory(dir.path());
    let plant = models().join("table1-plant.json");
    let out = dir.path().join("o.csv");
    let run = |model: &Path, method: &str, traj: &Path, extra: &[&str]| {
        let mut a = vec![
            "compensate",
            "--model",
            s(model),
            "--method",
            method,
            "--trajectory",
            s(traj),
            "-o",
            s(&out),
        ];
        a.extend(extra);
        hystcomp(&a)
    };
    let fails = |o: Output, needle: &str| {
        assert!(!o.status.success(), "should fail with {needle:?}");
        assert!(
            stderr(&o).contains(needle),
            "expected {needle:?} in: {}",
            stderr(&o)
        );
    };
    fails(
        run(Path::new("/no/such/model.json"), "ihc", &trajectory, &[]),
        "/no/such/model.json",
    );
    fails(
        run(&plant, "ihc", Path::new("/no/such/traj.csv"), &[]),
        "/no/such/traj.csv",
    );
    fails(
        run(&plant, "dihc", &trajectory, &[]),
        "dihc needs an inverse model",
    );
    fails(run(&plant, "magic", &trajectory, &[]), "choose one of");
    fails(
        run(&plant, "ihc", &trajectory, &["--desired-column", "height"]),
        "no column named \"height\"",
    );
    fails(
        run(&plant, "ihc", &trajectory, &["--limits", "5:1"]),
        "limits",
    );
    // Unknown format version.
    let text = std::fs::read_to_string(&plant)
        .unwrap()
        .replace("\"format_version\": 1", "\"format_version\": 9");
    let future = dir.path().join("future.json");
    std::fs::write(&future, text).unwrap();
    fails(run(&future, "ihc", &trajectory, &[]), "format_version 9");
    // A model that is not invertible (Table 1 with b1 = 0 and a1 = -0.3).
    let text = std::fs::read_to_string(&plant)
        .unwrap()
        .replace("0.2313", "0.0")
        .replace("-0.1569", "-0.3");
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, text).unwrap();
    fails(run(&bad, "wihc", &trajectory, &[]), "not invertible");
    // NaN in the trajectory, and time going backwards.
    let nan = dir.path().join("nan.csv");
    std::fs::write(&nan, "t,y\n0,10\n0.001,NaN\n0.002,11\n").unwrap();
    fails(run(&plant, "ihc", &nan, &[]), "NaN");
    let back = dir.path().join("back.csv");
    std::fs::write(&back, "t,y\n0,10\n0.002,11\n0.001,12\n").unwrap();
    fails(run(&plant, "ihc", &back, &[]), "not increasing");
    // Nothing was written by the failed runs.
    assert!(!out.exists());
}

#[test]
fn bench_reports_every_compensator_for_10_and_100_operators() {
    let o = hystcomp(&["bench", "--samples", "2000", "--repeats", "3", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let figures = report["figures"].as_array().unwrap();
    for what in [
        "mpim-forward",
        "ihc",
        "ihc-delayed",
        "wihc",
        "wihc-delayed",
        "dihc",
    ] {
        for n in [10, 100] {
            let f = figures
                .iter()
                .find(|f| f["what"] == what && f["operators"] == n && f["precision"] == "f64")
                .unwrap_or_else(|| panic!("no figure for {what} n = {n}"));
            let ns = f["median_ns_per_sample"].as_f64().unwrap();
            assert!(ns > 0.0 && ns.is_finite(), "{what} {n}: {ns}");
        }
    }
    let o = hystcomp(&["bench", "--samples", "10"]);
    assert!(!o.status.success());
}
