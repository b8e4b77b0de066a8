//! `hystcomp learn`: the hardware loop one trial at a time (here `simulate` stands in for the
//! stage: the drive played for two periods from rest, the second recorded), the state carried
//! by the drive files, the divergence guard's exit status and kept drive, `--simulate`, and
//! refusals. Short records (the paper's trajectory ten times faster, 1 s at 10 kHz).

mod common;

use std::path::Path;

use common::{assert_fails, hystcomp, models, s, stderr, stdout};
use hystcomp_io::data::{Column, ReadOptions, read_columns};
use hystcomp_io::model_file::{CreepPart, ModelFile};

fn column(path: &Path, name: &str) -> Vec<f64> {
    read_columns(path, &[Column::Name(name.into())], &ReadOptions::default())
        .unwrap()
        .values
        .remove(0)
}

/// A JSON file (a learn state file) as a value.
fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Plays `drive` (its `drive_v`) twice on the built-in stage from rest and writes the second
/// period's measurement to `measured` (time_s, measured_um).
fn run_on_stage(dir: &Path, drive: &Path, measured: &Path, seed: u64) {
    let v = column(drive, "drive_v");
    let n = v.len();
    let play = dir.join("play.csv");
    let mut text = String::from("time_s,drive_v\n");
    for k in 0..2 * n {
        text.push_str(&format!("{},{}\n", k as f64 * 1e-4, v[k % n]));
    }
    std::fs::write(&play, text).unwrap();
    let out_path = dir.join("stage.csv");
    let seed = seed.to_string();
    let out = hystcomp(&[
        "simulate",
        "--drive",
        s(&play),
        "--seed",
        &seed,
        "-o",
        s(&out_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let y = column(&out_path, "measured_um");
    let mut text = String::from("time_s,measured_um\n");
    for k in 0..n {
        text.push_str(&format!("{},{}\n", k as f64 * 1e-4, y[n + k]));
    }
    std::fs::write(measured, text).unwrap();
}

/// The paper's trajectory ten times faster, `duration` s at 10 kHz, written to `path`.
fn paper_signal(path: &Path, duration: &str) {
    let out = hystcomp(&[
        "signal",
        "paper",
        "--speed",
        "10",
        "--duration",
        duration,
        "-o",
        s(path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// desired.csv (one period of the paper's trajectory, 1 s) and drive_0.csv (Table 1's IHC).
fn setup(dir: &Path) {
    let desired = dir.join("desired.csv");
    paper_signal(&desired, "1");
    let model = models().join("table1-plant.json");
    let drive = dir.join("drive_0.csv");
    let out = hystcomp(&[
        "compensate",
        "--model",
        s(&model),
        "--method",
        "ihc",
        "--desired",
        s(&desired),
        "-o",
        s(&drive),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// `learn` for one trial on hardware: `dir`'s desired.csv, `drive` and `measured`, `model`,
/// `-o output`.
fn trial_args<'a>(
    dir: &Path,
    drive: &'a Path,
    measured: &'a Path,
    model: &'a Path,
    output: &'a Path,
) -> [&'a str; 11] {
    [
        "learn",
        "--desired",
        s(&dir.join("desired.csv")).to_owned().leak(),
        "--drive",
        s(drive),
        "--measured",
        s(measured),
        "--model",
        s(model),
        "-o",
        s(output),
    ]
}

fn learn(dir: &Path, k: usize, extra: &[&str]) -> std::process::Output {
    let model = models().join("table1-plant.json");
    let (drive, measured, next) = (
        dir.join(format!("drive_{k}.csv")),
        dir.join(format!("meas_{k}.csv")),
        dir.join(format!("drive_{}.csv", k + 1)),
    );
    let mut args = vec!["--json"];
    args.extend(trial_args(dir, &drive, &measured, &model, &next));
    args.extend(extra);
    hystcomp(&args)
}

#[test]
fn the_hardware_loop_learns_trial_after_trial_from_the_files_alone() {
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let mut e_rms = Vec::new();
    for k in 0..4 {
        run_on_stage(
            dir.path(),
            &dir.path().join(format!("drive_{k}.csv")),
            &dir.path().join(format!("meas_{k}.csv")),
            10 + k as u64,
        );
        let out = learn(dir.path(), k, &[]);
        assert!(out.status.success(), "trial {k}: {}", stderr(&out));
        let report: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(report["trial"], k);
        assert!(
            report["predicted"]["e_rms_percent"].as_f64().unwrap()
                < report["indices"]["e_rms_percent"].as_f64().unwrap()
        );
        e_rms.push(report["indices"]["e_rms_percent"].as_f64().unwrap());
        let state = read_json(&dir.path().join(format!("drive_{}.learn.json", k + 1)));
        assert_eq!(
            state["history"].as_array().unwrap().len(),
            k + 1,
            "the state carries every trial"
        );
        let next = column(&dir.path().join(format!("drive_{}.csv", k + 1)), "drive_v");
        assert!(next.iter().all(|v| (0.0..=10.0).contains(v)));
    }
    assert!(e_rms[3] < 0.2 * e_rms[0], "{e_rms:?}");
    // Text output: the trial's indices, the prediction and the law.
    run_on_stage(
        dir.path(),
        &dir.path().join("drive_4.csv"),
        &dir.path().join("meas_4.csv"),
        20,
    );
    let model = models().join("table1-plant.json");
    let d = dir.path();
    let out = hystcomp(&trial_args(
        d,
        &d.join("drive_4.csv"),
        &d.join("meas_4.csv"),
        &model,
        &d.join("drive_5.csv"),
    ));
    let text = stdout(&out);
    for fragment in [
        "trial 4: e_rms = ",
        "predicted trial 5: e_rms = ",
        "learning law: gain 0.8",
        "Q cut-off 100 Hz",
    ] {
        assert!(text.contains(fragment), "{fragment:?} in {text}");
    }
}

/// The state file names its drive by a checksum of the drive's values: a drive changed after
/// its state was written (or a state left from another run) is refused, nothing written; a
/// state file from before the checksum was kept is taken on trust.
#[test]
fn a_state_file_beside_another_drive_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    setup(d);
    run_on_stage(d, &d.join("drive_0.csv"), &d.join("meas_0.csv"), 3);
    let out = learn(d, 0, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let state_path = d.join("drive_1.learn.json");
    let state = read_json(&state_path);
    assert!(state["drive_crc32"].is_u64(), "{state}");
    run_on_stage(d, &d.join("drive_1.csv"), &d.join("meas_1.csv"), 4);

    // One drive value changed by one part in a million: refused, naming both files.
    let drive = d.join("drive_1.csv");
    let original = std::fs::read_to_string(&drive).unwrap();
    let mut lines: Vec<String> = original.lines().map(str::to_owned).collect();
    let mut fields: Vec<String> = lines[5].split(',').map(str::to_owned).collect();
    let v: f64 = fields[1].parse().unwrap();
    fields[1] = format!("{:?}", v * (1.0 + 1e-6));
    lines[5] = fields.join(",");
    std::fs::write(&drive, lines.join("\n") + "\n").unwrap();
    let before = std::fs::read(&state_path).unwrap();
    let out = learn(d, 1, &[]);
    assert!(!out.status.success());
    let message = stderr(&out);
    assert!(
        message.contains("belongs to another drive") && message.contains("drive_1.csv"),
        "{message}"
    );
    assert!(!d.join("drive_2.csv").exists() && !d.join("drive_2.learn.json").exists());
    assert_eq!(
        std::fs::read(&state_path).unwrap(),
        before,
        "the state is kept"
    );

    // The drive as written: accepted.
    std::fs::write(&drive, &original).unwrap();
    let out = learn(d, 1, &[]);
    assert!(out.status.success(), "{}", stderr(&out));

    // A state left from another run beside this run's drive (as a learn cut off between its
    // two writes leaves it): trial 1 learned again from another measurement gives another
    // drive_2.csv; with the first run's state beside it, trial 2 is refused.
    let first_state = std::fs::read(d.join("drive_2.learn.json")).unwrap();
    run_on_stage(d, &drive, &d.join("meas_1.csv"), 5);
    let out = learn(d, 1, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_ne!(
        std::fs::read(d.join("drive_2.learn.json")).unwrap(),
        first_state
    );
    std::fs::write(d.join("drive_2.learn.json"), &first_state).unwrap();
    run_on_stage(d, &d.join("drive_2.csv"), &d.join("meas_2.csv"), 6);
    let out = learn(d, 2, &[]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("belongs to another drive") && stderr(&out).contains("Re-run"),
        "{}",
        stderr(&out)
    );
    assert!(!d.join("drive_3.csv").exists() && !d.join("drive_3.learn.json").exists());

    // A state file without the checksum (written before it was kept): taken on trust.
    let mut old: serde_json::Value = state.clone();
    old.as_object_mut().unwrap().remove("drive_crc32");
    std::fs::write(&state_path, serde_json::to_string(&old).unwrap()).unwrap();
    std::fs::write(&drive, lines.join("\n") + "\n").unwrap();
    for stale in ["drive_2.csv", "drive_2.learn.json"] {
        std::fs::remove_file(d.join(stale)).unwrap();
    }
    let out = learn(d, 1, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let next = read_json(&d.join("drive_2.learn.json"));
    assert_eq!(next["history"].as_array().unwrap().len(), 2, "{next}");
}

/// A drive file that would be refused (here a column name with a line break, from a model's
/// unit) is refused before the state file is written: no state without its drive.
#[test]
fn a_drive_refused_before_it_is_written_leaves_no_state_behind() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    setup(d);
    run_on_stage(d, &d.join("drive_0.csv"), &d.join("meas_0.csv"), 3);
    let mut model = ModelFile::load(&models().join("table1-plant.json")).unwrap();
    model.input.unit = "V\nper stack".into();
    let model_path = d.join("plant-odd-unit.json");
    model.save(&model_path).unwrap();
    let out = hystcomp(&trial_args(
        d,
        &d.join("drive_0.csv"),
        &d.join("meas_0.csv"),
        &model_path,
        &d.join("drive_1.csv"),
    ));
    assert!(!out.status.success());
    assert!(stderr(&out).contains("line break"), "{}", stderr(&out));
    for never in ["drive_1.csv", "drive_1.learn.json"] {
        assert!(!d.join(never).exists(), "{never} was written");
    }
}

#[test]
fn a_gain_too_high_is_stopped_with_exit_6_and_the_last_good_drive_kept() {
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let drive_0 = column(&dir.path().join("drive_0.csv"), "drive_v");
    let mut stopped = None;
    for k in 0..4 {
        run_on_stage(
            dir.path(),
            &dir.path().join(format!("drive_{k}.csv")),
            &dir.path().join(format!("meas_{k}.csv")),
            30 + k as u64,
        );
        let out = learn(dir.path(), k, &["--gain", "5"]);
        if out.status.code() == Some(6) {
            stopped = Some((k, stderr(&out)));
            break;
        }
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let (k, message) = stopped.expect("the guard trips");
    assert!(
        message.contains("divergence guard stopped the learning")
            && message.contains("last good drive")
            && message.contains("--gain"),
        "{message}"
    );
    let kept = column(&dir.path().join(format!("drive_{}.csv", k + 1)), "drive_v");
    let best = column(
        &dir.path().join(format!("drive_{}.csv", k + 1)),
        "best_drive_v",
    );
    assert_eq!(kept, best);
    if k == 1 {
        for (a, b) in kept.iter().zip(&drive_0) {
            assert!((a - b).abs() < 1e-9);
        }
    }
    // A stopped learning refuses to go on from that drive until its state file is removed.
    run_on_stage(
        dir.path(),
        &dir.path().join(format!("drive_{}.csv", k + 1)),
        &dir.path().join(format!("meas_{}.csv", k + 1)),
        40,
    );
    let out = learn(dir.path(), k + 1, &[]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("remove"), "{}", stderr(&out));
}

#[test]
fn simulate_runs_the_loop_on_the_stage() {
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let model = models().join("table1-plant.json");
    let out_path = dir.path().join("learned.csv");
    let out = hystcomp(&[
        "--json",
        "learn",
        "--simulate",
        "--desired",
        s(&dir.path().join("desired.csv")),
        "--model",
        s(&model),
        "--trials",
        "4",
        "-o",
        s(&out_path),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let trials = report["trials"].as_array().unwrap();
    assert_eq!(trials.len(), 4);
    let e = |t: &serde_json::Value| t["update"]["indices"]["e_rms_percent"].as_f64().unwrap();
    assert!(e(&trials[3]) < 0.2 * e(&trials[0]));
    assert!(out_path.exists() && dir.path().join("learned.learn.json").exists());
}

#[test]
fn bad_learning_inputs_are_refused_with_the_option_named() {
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    run_on_stage(
        dir.path(),
        &dir.path().join("drive_0.csv"),
        &dir.path().join("meas_0.csv"),
        3,
    );
    let d = dir.path();
    let model = models().join("table1-plant.json");
    let base = |extra: &[&str], output: &Path| {
        let mut a: Vec<String> = trial_args(
            d,
            &d.join("drive_0.csv"),
            &d.join("meas_0.csv"),
            &model,
            output,
        )
        .iter()
        .map(|x| x.to_string())
        .collect();
        a.extend(extra.iter().map(|x| x.to_string()));
        a
    };
    let check = |extra: &[&str], output: &Path, fragments: &[&str]| {
        let a = base(extra, output);
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        assert_fails(&refs, fragments);
    };
    let out = d.join("next.csv");
    check(&["--gain", "0"], &out, &["--gain", "above 0"]);
    check(&["--gain", "11"], &out, &["--gain", "at most 10"]);
    check(
        &["--bandwidth", "6000"],
        &out,
        &["--bandwidth", "half the sample rate"],
    );
    check(
        &["--divergence-factor", "1"],
        &out,
        &["--divergence-factor"],
    );
    check(&[], &d.join("drive_0.csv"), &["--output"]);
    // A measured record of another length.
    let text = std::fs::read_to_string(d.join("meas_0.csv")).unwrap();
    let short: String = text.lines().take(500).map(|l| format!("{l}\n")).collect();
    std::fs::write(d.join("short.csv"), short).unwrap();
    let a: Vec<String> = trial_args(
        d,
        &d.join("drive_0.csv"),
        &d.join("short.csv"),
        &model,
        &out,
    )
    .iter()
    .map(|x| x.to_string())
    .collect();
    let refs: Vec<&str> = a.iter().map(String::as_str).collect();
    assert_fails(&refs, &["499 samples", "aligned sample by sample"]);
    assert!(!out.exists(), "nothing written on refusal");
    // The output's state file may not be an input either (here: the drive's own state file),
    // nor the output itself (it was compared with the named inputs only).
    std::fs::write(d.join("drive_0.learn.json"), "{}").unwrap();
    check(&[], &d.join("drive_0.out"), &["state file"]);
    check(
        &[],
        &d.join("drive_0.learn.json"),
        &["--output", "--drive's state file"],
    );
    assert_eq!(
        std::fs::read_to_string(d.join("drive_0.learn.json")).unwrap(),
        "{}"
    );
    std::fs::remove_file(d.join("drive_0.learn.json")).unwrap();
    // --simulate: a stage file is an input the output's state file may not replace, and a
    // model with links identified at another rate than the trajectory's is refused.
    let stage = d.join("st.learn.json");
    std::fs::write(&stage, "sample_rate_hz = 10000\n").unwrap();
    let desired = d.join("desired.csv");
    let simulate = |model: &Path, stage: Option<&Path>, output: &Path, fragments: &[&str]| {
        let mut a = vec![
            "learn",
            "--simulate",
            "--desired",
            s(&desired),
            "--model",
            s(model),
            "-o",
            s(output),
        ];
        if let Some(stage) = stage {
            a.extend(["--stage", s(stage)]);
        }
        assert_fails(&a, fragments);
        assert!(!output.exists());
    };
    simulate(&model, Some(&stage), &d.join("st.csv"), &["--stage"]);
    assert_eq!(
        std::fs::read_to_string(&stage).unwrap(),
        "sample_rate_hz = 10000\n"
    );
    let mut linked = ModelFile::load(&model).unwrap();
    linked.format_version = 2;
    linked.sample_rate_hz = Some(5000.0);
    linked.creep = Some(CreepPart {
        origin: 0.0,
        time_constants_s: vec![1.0],
        weights: vec![0.05],
    });
    let linked_path = d.join("linked.json");
    linked.save(&linked_path).unwrap();
    simulate(
        &linked_path,
        None,
        &d.join("linked.csv"),
        &["identified at 5000 Hz"],
    );
    // One trial's periods are bounded in memory (its drive and responses), not only the whole
    // run in time: 600 periods of 20 000 samples are refused before anything runs.
    let long = d.join("long.csv");
    paper_signal(&long, "2");
    assert_fails(
        &[
            "learn",
            "--simulate",
            "--desired",
            s(&long),
            "--model",
            s(&model),
            "--trials",
            "1",
            "--periods",
            "600",
            "-o",
            s(&d.join("long_out.csv")),
        ],
        &["per trial", "--periods"],
    );
}

/// A model whose voltage unit is not V: the drive file's best drive is `best_drive_mv`, and
/// the next trial reads it back under that name (it looked for `best_drive_v` and failed).
#[test]
fn a_model_in_millivolts_learns_trial_after_trial() {
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path());
    let d = dir.path();
    run_on_stage(d, &d.join("drive_0.csv"), &d.join("meas_0.csv"), 5);
    let mut model = ModelFile::load(&models().join("table1-plant.json")).unwrap();
    model.input.unit = "mV".into();
    model.input.scale *= 1000.0;
    model.input.offset *= 1000.0;
    let model_path = d.join("plant-mv.json");
    model.save(&model_path).unwrap();
    let out = hystcomp(&[
        "compensate",
        "--model",
        s(&model_path),
        "--method",
        "ihc",
        "--desired",
        s(&d.join("desired.csv")),
        "-o",
        s(&d.join("mv_0.csv")),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    for k in 0..2 {
        let out = hystcomp(&trial_args(
            d,
            &d.join(format!("mv_{k}.csv")),
            &d.join("meas_0.csv"),
            &model_path,
            &d.join(format!("mv_{}.csv", k + 1)),
        ));
        assert!(out.status.success(), "trial {k}: {}", stderr(&out));
        let state = read_json(&d.join(format!("mv_{}.learn.json", k + 1)));
        assert!(state["best_trial"].is_u64(), "{state}");
        assert_eq!(
            column(&d.join(format!("mv_{}.csv", k + 1)), "best_drive_mv").len(),
            10_000
        );
    }
}
