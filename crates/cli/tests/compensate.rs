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
        ("ihc-guarded", "table1-plant.json"),
        ("wihc", "table1-plant.json"),
        ("wihc-delayed", "table1-plant.json"),
        ("wihc-guarded", "table1-plant.json"),
        ("dihc", "table2-inverse.json"),
    ] {
        let out = dir.path().join(format!("{method}.csv"));
        let model = models().join(model);
        let mut args = vec![
            "compensate",
            "--model",
            s(&model),
            "--method",
            method,
            "--desired",
            s(&trajectory),
            "-o",
            s(&out),
        ];
        // Table 1's delayed WIHC can ring (loop gain 1.66): it runs only when allowed.
        if method == "wihc-delayed" {
            args.push("--allow-unstable-delay");
        }
        let o = hystcomp(&args);
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
        "--desired",
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
            "--desired",
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

/// `y_d = 35 + 20 sin(2 pi t)` um at 10 kHz for one second, starting at 35 um (a jump from rest).
fn sine_from_rest(dir: &Path) -> PathBuf {
    let time: Vec<f64> = (0..10_000).map(|k| k as f64 * 1e-4).collect();
    let desired: Vec<f64> = time
        .iter()
        .map(|t| 35.0 + 20.0 * (2.0 * std::f64::consts::PI * t).sin())
        .collect();
    let path = dir.join("sine.csv");
    hystcomp_io::data::write_csv(&path, &["time_s", "desired_um"], &[&time, &desired]).unwrap();
    path
}

#[test]
fn delayed_wihc_ringing_is_reported_as_such_not_as_unreachable_positions() {
    let dir = tempfile::tempdir().unwrap();
    let trajectory = sine_from_rest(dir.path());
    let model = models().join("table1-plant.json");
    let out = dir.path().join("drive.csv");
    let run_with = |method: &str, extra: &[&str]| {
        let mut args = vec![
            "compensate",
            "--model",
            s(&model),
            "--method",
            method,
            "--desired",
            s(&trajectory),
            "-o",
            s(&out),
            "--json",
        ];
        args.extend_from_slice(extra);
        hystcomp(&args)
    };
    let run = |method: &str| run_with(method, &[]);
    // The exact WIHC reaches every sample: nothing clamped, exit 0.
    let o = run("wihc");
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["unreachable"], 0, "{report}");
    assert_eq!(report["loop_saturated"], 0, "{report}");
    assert_eq!(report["saturated"], 0, "{report}");
    let gain = report["delayed_loop_gain"].as_f64().unwrap();
    assert!(gain >= 1.0, "Table 1's delayed loop gain {gain}");
    // The plain delayed WIHC is refused, naming the flag, the exact and the guarded methods;
    // no drive file is written.
    std::fs::remove_file(&out).unwrap();
    let o = run("wihc-delayed");
    let message = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{message}");
    for part in [
        "delayed WIHC can oscillate",
        &format!("{gain:.4}"),
        "--allow-unstable-delay",
        "--method wihc-guarded",
        "--method wihc ",
    ] {
        assert!(message.contains(part), "{part}: {message}");
    }
    assert!(!out.exists());
    // The guarded loop follows without ringing.
    let o = run("wihc-guarded");
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["saturated"], 0, "{report}");
    let relaxation = report["guard_relaxation"].as_f64().unwrap();
    // The guarded WIHC delays only the cubic, as the delayed IHC does: Table 1's a1 < 0 needs
    // no under-relaxation.
    assert_eq!(relaxation, 1.0, "{report}");
    // Allowed explicitly, the delayed WIHC rings between 0 and 10 V after the jump: a loop
    // saturation.
    let o = run_with("wihc-delayed", &["--allow-unstable-delay"]);
    let message = stderr(&o);
    assert_eq!(o.status.code(), Some(4), "{message}");
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["unreachable"], 0, "{report}");
    let looped = report["loop_saturated"].as_u64().unwrap();
    assert!(looped > 10, "{report}");
    assert_eq!(report["saturated"].as_u64().unwrap(), looped, "{report}");
    assert!(report["first_loop_saturated_time_s"].as_f64().unwrap() < 0.01);
    assert!(report["first_unreachable_time_s"].is_null(), "{report}");
    assert!(
        !message.contains("outside what the model can reach"),
        "{message}"
    );
    assert!(
        message.contains("warning: --allow-unstable-delay: the wihc-delayed loop gain"),
        "{message}"
    );
    assert!(message.contains("--method wihc"), "{message}");
    assert!(message.contains("within reach"), "{message}");
    assert!(message.contains(&format!("{gain:.3} >= 1")), "{message}");
    // The ringing stays within the limits, and the drive file is written.
    let drive = &read(&out)[1];
    assert!(drive.iter().all(|v| (0.0..=10.0).contains(v)));
    assert!(
        drive[..40].iter().filter(|v| **v == 10.0).count() > 5,
        "rings"
    );
}

#[test]
fn dihc_says_its_desired_positions_were_clamped_into_the_models_range() {
    let dir = tempfile::tempdir().unwrap();
    let time: Vec<f64> = (0..400).map(|k| k as f64 * 1e-3).collect();
    // Table 2's inverse model accepts 0 .. 75 um.
    let desired: Vec<f64> = time.iter().map(|t| 40.0 + 50.0 * (9.0 * t).sin()).collect();
    let traj = dir.path().join("wide.csv");
    hystcomp_io::data::write_csv(&traj, &["t", "y"], &[&time, &desired]).unwrap();
    let out = dir.path().join("out.csv");
    let o = hystcomp(&[
        "compensate",
        "--model",
        s(&models().join("table2-inverse.json")),
        "--method",
        "dihc",
        "--desired",
        s(&traj),
        "-o",
        s(&out),
        "--json",
    ]);
    let message = stderr(&o);
    assert_eq!(o.status.code(), Some(4), "{message}");
    let outside = desired.iter().filter(|d| **d < 0.0 || **d > 75.0).count();
    assert!(outside > 0);
    assert!(
        message.contains(&format!(
            "{outside} of 400 desired positions lie outside the range 0.0000 .. 75.0000 um"
        )),
        "{message}"
    );
    assert!(message.contains("DIHC clamped them into it"), "{message}");
    assert!(!message.contains("the drive was clamped"), "{message}");
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["unreachable"].as_u64().unwrap(), outside as u64);
    assert_eq!(report["loop_saturated"], 0);
    assert_eq!(report["desired_range"], serde_json::json!([0.0, 75.0]));
}

#[test]
fn unreadable_models_and_infinite_positions_are_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let (trajectory, _) = reachable_trajectory(dir.path());
    let out = dir.path().join("o.csv");
    // A directory where the model file should be.
    let o = hystcomp(&[
        "compensate",
        "--model",
        s(dir.path()),
        "--method",
        "ihc",
        "--desired",
        s(&trajectory),
        "-o",
        s(&out),
    ]);
    let message = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{message}");
    assert!(message.contains(s(dir.path())), "{message}");
    assert!(message.contains("directory"), "{message}");
    assert!(!message.contains("panicked"), "{message}");
    // An infinite desired position.
    let inf = dir.path().join("inf.csv");
    std::fs::write(&inf, "t,y\n0,10\n0.001,inf\n0.002,11\n").unwrap();
    let o = hystcomp(&[
        "compensate",
        "--model",
        s(&models().join("table1-plant.json")),
        "--method",
        "ihc",
        "--desired",
        s(&inf),
        "-o",
        s(&out),
    ]);
    let message = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{message}");
    assert!(message.to_lowercase().contains("inf"), "{message}");
    assert!(message.contains(s(&inf)), "{message}");
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
        "mpim-chained",
        "ihc",
        "ihc-delayed",
        "ihc-guarded",
        "wihc",
        "wihc-delayed",
        "wihc-guarded",
        "dihc",
        "creep-inverse",
        "vibration-inverse",
        "chain-ihc",
    ] {
        for n in [10, 100] {
            for precision in ["f64", "f32"] {
                let f = figures
                    .iter()
                    .find(|f| {
                        f["what"] == what && f["operators"] == n && f["precision"] == precision
                    })
                    .unwrap_or_else(|| panic!("no figure for {what} n = {n} {precision}"));
                let ns = f["median_ns_per_sample"].as_f64().unwrap();
                let min = f["min_ns_per_sample"].as_f64().unwrap();
                assert!(ns > 0.0 && ns.is_finite(), "{what} {n} {precision}: {ns}");
                assert!(
                    min > 0.0 && min <= ns,
                    "{what} {n} {precision}: {min} > {ns}"
                );
            }
        }
    }
    // Exactly those: 12 kinds x 2 sizes x 2 precisions, no figure twice.
    assert_eq!(figures.len(), 12 * 2 * 2, "{report}");
    assert_eq!(report["samples"], 2000);
    assert_eq!(report["repeats"], 3);
    let o = hystcomp(&["bench", "--samples", "10"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--samples 10: give 100 to 1000000"));
}

#[test]
fn bench_times_a_model_file_too() {
    let plant = models().join("table1-plant.json");
    let inverse = models().join("table2-inverse.json");
    let figures_for = |model: &Path| {
        bench_model_figures(model)
            .iter()
            .map(|f| {
                assert_eq!(f["operators"], 10);
                f["what"].as_str().unwrap().to_string()
            })
            .collect::<Vec<_>>()
    };
    let mut plant_figures = figures_for(&plant);
    plant_figures.sort();
    assert_eq!(
        plant_figures,
        [
            "ihc",
            "ihc-delayed",
            "ihc-guarded",
            "mpim-chained",
            "mpim-forward",
            "wihc",
            "wihc-delayed",
            "wihc-guarded"
        ]
    );
    assert_eq!(figures_for(&inverse), ["dihc"]);
    // A missing model file is refused with its path.
    assert_fails(
        &["bench", "--model", "/no/such/model.json"],
        &["/no/such/model.json"],
    );
}
