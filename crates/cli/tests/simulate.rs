//! `hystcomp simulate` end to end: the built binary on files in a temporary folder.

mod common;

use common::*;

use std::path::Path;

/// A command record at `rate_hz`: a slow sine around 5 V, `n` samples, with a header.
fn write_input(path: &Path, rate_hz: f64, n: usize) {
    let mut text = String::from("time_s,volts\n");
    for k in 0..n {
        let t = k as f64 / rate_hz;
        let v = 5.0 + 4.0 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
        text.push_str(&format!("{t},{v}\n"));
    }
    std::fs::write(path, text).unwrap();
}

/// `simulate --stage STAGE --drive DRIVE -o OUTPUT`.
fn on_stage<'a>(stage: &'a Path, drive: &'a Path, output: &'a Path) -> [&'a str; 7] {
    [
        "simulate",
        "--stage",
        s(stage),
        "--drive",
        s(drive),
        "-o",
        s(output),
    ]
}

fn read_output(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn good_run_writes_every_column_and_a_json_summary() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    let output = dir.path().join("out.csv");
    write_input(&input, 10_000.0, 5_000);
    let out = hystcomp(&[
        "--json",
        "simulate",
        "--drive",
        s(&input),
        "-o",
        s(&output),
        "--seed",
        "3",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (header, rows) = read_output(&output);
    assert_eq!(
        header,
        [
            "time_s",
            "command_v",
            "amplifier_v",
            "true_position_um",
            "measured_um"
        ]
    );
    assert_eq!(rows.len(), 5_000);
    // The amplifier multiplies by 15 (after its lag) and the stage moves tens of micrometres.
    let top = rows.iter().map(|r| r[2]).fold(0.0, f64::max);
    assert!((top - 135.0).abs() < 2.0, "{top}");
    let far = rows.iter().map(|r| r[3]).fold(0.0, f64::max);
    assert!(far > 40.0 && far < 80.0, "{far}");
    for r in &rows {
        assert!(
            (r[4] - r[3]).abs() < 0.05,
            "measured {} vs true {}",
            r[4],
            r[3]
        );
    }

    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["samples"], 5_000);
    assert_eq!(summary["seed"], 3);
    assert_eq!(summary["hysteresis_model"], "preisach");
    assert!((summary["duration_s"].as_f64().unwrap() - 0.5).abs() < 1e-12);
    assert_eq!(summary["clamped"]["dac"], 0);
    assert_eq!(summary["clamped"]["amplifier"], 0);
    let max_true = summary["columns"]["true_position_um"]["max"]
        .as_f64()
        .unwrap();
    assert_eq!(max_true, far);

    // Same seed, same file; another seed, other noise.
    let again = dir.path().join("again.csv");
    let other = dir.path().join("other.csv");
    for (path, seed) in [(&again, "3"), (&other, "4")] {
        let out = hystcomp(&[
            "simulate",
            "--drive",
            s(&input),
            "-o",
            s(path),
            "--seed",
            seed,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    assert_eq!(
        std::fs::read(&output).unwrap(),
        std::fs::read(&again).unwrap()
    );
    assert_ne!(
        std::fs::read(&output).unwrap(),
        std::fs::read(&other).unwrap()
    );
}

#[test]
fn stage_file_and_named_columns_are_used() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    let output = dir.path().join("out.csv");
    let stage = dir.path().join("stage.toml");
    // Columns swapped, a 5 kHz stage, and clamped commands counted: 10 beyond the DAC's
    // +-10 V span, 5 within it but below the amplifier's 0 V rail once amplified.
    let mut text = String::from("volts;time\n");
    for k in 0..1000 {
        let volts = match k {
            0..10 => 12.0,
            10..15 => -1.0,
            _ => 2.0,
        };
        text.push_str(&format!("{volts};{}\n", k as f64 / 5e3));
    }
    std::fs::write(&input, text).unwrap();
    std::fs::write(
        &stage,
        "sample_rate_hz = 5000.0\n[hysteresis]\nmodel = \"bouc-wen\"\n",
    )
    .unwrap();
    let out = hystcomp(&[
        "--json",
        "simulate",
        "--stage",
        s(&stage),
        "--drive",
        s(&input),
        "--time-column",
        "time",
        "--voltage-column",
        "1",
        "-o",
        s(&output),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["hysteresis_model"], "bouc-wen");
    assert_eq!(summary["sample_rate_hz"], 5000.0);
    assert_eq!(summary["clamped"]["dac"], 10);
    assert_eq!(summary["clamped"]["amplifier"], 5);
    assert_eq!(summary["clamped"]["adc"], 0);
}

#[test]
fn adc_saturation_is_counted_and_warned() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    let output = dir.path().join("out.csv");
    let stage = dir.path().join("stage.toml");
    // The sine reaches 9 V (about 67 um); an ADC span of 0..3 V at 0.1 V/um reads 30 um at most.
    write_input(&input, 1e4, 5000);
    std::fs::write(
        &stage,
        "[adc]
min_v = -3.0
max_v = 3.0
",
    )
    .unwrap();
    let args = on_stage(&stage, &input, &output);
    let out = hystcomp(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("outside the ADC's span") && stderr(&out).contains("adc.max_v"),
        "{}",
        stderr(&out)
    );
    let (_, rows) = read_output(&output);
    let saturated = rows.iter().filter(|r| r[3] * 0.1 > 3.0).count() as u64;
    assert!(saturated > 100, "{saturated}");
    let mut json_args = vec!["--json"];
    json_args.extend(args);
    let out = hystcomp(&json_args);
    assert!(out.status.success(), "{}", stderr(&out));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // Noise can push a reading near the top across the edge either way: within a few samples.
    let counted = summary["clamped"]["adc"].as_u64().unwrap();
    assert!(
        counted.abs_diff(saturated) <= 20,
        "{counted} vs {saturated}"
    );
    let top = rows.iter().map(|r| r[4]).fold(f64::MIN, f64::max);
    assert!(top < 30.0, "measured {top}");
}

#[test]
fn bad_stage_file_is_refused_with_the_field_named() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    write_input(&input, 10_000.0, 100);
    let output = dir.path().join("out.csv");
    for (content, fragments) in [
        (
            "[mechanics]\ndamping_ratio = -0.05\n",
            &["stage.toml", "mechanics.damping_ratio must be"][..],
        ),
        ("[amplifier]\nbandwith_hz = 2000.0\n", &["bandwith_hz"][..]),
        (
            "[amplifier]\noutput_min_v = 150.0\noutput_max_v = 0.0\n",
            &["amplifier.output_min_v..amplifier.output_max_v"][..],
        ),
        // Each field valid, together overflowing: said before anything is written, naming the
        // row (the writer blamed the output file's column).
        (
            "[adc]\nmin_v = 0.0\nmax_v = 1e308\n",
            &["stage.toml", "non-finite", "row 1", "check them"][..],
        ),
    ] {
        let stage = dir.path().join("stage.toml");
        std::fs::write(&stage, content).unwrap();
        assert_fails(&on_stage(&stage, &input, &output), fragments);
        assert!(!output.exists());
    }
}

#[test]
fn missing_input_is_refused_with_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("nowhere.csv");
    let output = dir.path().join("out.csv");
    assert_fails(
        &["simulate", "--drive", s(&input), "-o", s(&output)],
        &["nowhere.csv"],
    );
    assert!(!output.exists());
}

#[test]
fn nan_in_the_input_is_refused_with_its_row() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    let output = dir.path().join("out.csv");
    std::fs::write(&input, "time_s,volts\n0,1\n0.0001,NaN\n0.0002,1\n").unwrap();
    assert_fails(
        &["simulate", "--drive", s(&input), "-o", s(&output)],
        &["volts.csv", "row 2", "volts"],
    );
    assert!(!output.exists());
}

#[test]
fn wrong_column_is_refused_with_the_column_named() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    let output = dir.path().join("out.csv");
    write_input(&input, 10_000.0, 100);
    assert_fails(
        &[
            "simulate",
            "--drive",
            s(&input),
            "--voltage-column",
            "command",
            "-o",
            s(&output),
        ],
        &["command"],
    );
    assert_fails(
        &[
            "simulate",
            "--drive",
            s(&input),
            "--voltage-column",
            "7",
            "-o",
            s(&output),
        ],
        &["7"],
    );
    assert!(!output.exists());
}

#[test]
fn time_step_other_than_the_stage_period_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    let output = dir.path().join("out.csv");
    write_input(&input, 1_000.0, 100);
    assert_fails(
        &["simulate", "--drive", s(&input), "-o", s(&output)],
        &["time step", "10000 Hz", "sample_rate_hz = 1000"],
    );
    assert!(!output.exists());
}

#[test]
fn simulate_reports_the_share_of_samples_at_the_slew_or_rail_limit() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, frequency_hz: f64| {
        let path = dir.path().join(name);
        let mut text = String::from("time_s,volts\n");
        for k in 0..5_000 {
            let t = k as f64 / 10_000.0;
            // From rest to 5 V over 0.1 s, then the tone.
            let rise = 0.5 - 0.5 * (std::f64::consts::PI * (t / 0.1).min(1.0)).cos();
            let v = rise * (5.0 + 4.0 * (2.0 * std::f64::consts::PI * frequency_hz * t).sin());
            text.push_str(&format!("{t},{v}\n"));
        }
        std::fs::write(&path, text).unwrap();
        path
    };
    let run = |input: &Path| {
        let output = dir.path().join("out.csv");
        let out = hystcomp(&["--json", "simulate", "--input", s(input), "-o", s(&output)]);
        assert!(out.status.success(), "{}", stderr(&out));
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    // 4 V at 2 Hz asks 750 V/s of a 14 300 V/s amplifier; at 100 Hz, 37 700 V/s.
    let slow = run(&write("slow.csv", 2.0));
    assert_eq!(slow["clamped"]["slew_limited"], 0);
    assert_eq!(slow["limited_share"], 0.0);
    let fast = run(&write("fast.csv", 100.0));
    let share = fast["limited_share"].as_f64().unwrap();
    assert!(share > 0.3 && share < 1.0, "{share}");
    assert!(fast["clamped"]["slew_limited"].as_u64().unwrap() > 1_000);
    // For people, on stderr.
    let output = dir.path().join("out.csv");
    let text = hystcomp(&[
        "simulate",
        "--input",
        s(&write("fast2.csv", 100.0)),
        "-o",
        s(&output),
    ]);
    assert!(stderr(&text).contains("slew limit"), "{}", stderr(&text));
}

#[test]
fn the_stage_files_seed_sets_the_noise_and_seed_on_the_command_line_overrides_it() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("volts.csv");
    write_input(&input, 10_000.0, 2_000);
    let seeded = dir.path().join("seeded.toml");
    std::fs::write(&seeded, "seed = 5\n").unwrap();
    let run = |name: &str, extra: &[&str]| {
        let output = dir.path().join(name);
        let mut args = vec!["--json", "simulate", "--drive", s(&input), "-o", s(&output)];
        args.extend_from_slice(extra);
        let out = hystcomp(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let measured: Vec<f64> = read_output(&output).1.iter().map(|r| r[4]).collect();
        (summary["seed"].as_u64().unwrap(), measured)
    };
    let (file_seed, from_file) = run("file.csv", &["--stage", s(&seeded)]);
    let (flag_seed, from_flag) = run("flag.csv", &["--seed", "5"]);
    let (default_seed, from_default) = run("default.csv", &[]);
    let (override_seed, overridden) = run("override.csv", &["--stage", s(&seeded), "--seed", "1"]);
    assert_eq!(
        (file_seed, flag_seed, default_seed, override_seed),
        (5, 5, 1, 1)
    );
    // The same noise from the file's seed as from --seed; another from the default seed.
    assert_eq!(from_file, from_flag);
    assert_ne!(from_file, from_default);
    assert_eq!(overridden, from_default);
}

/// The model file a stage file names (`hysteresis.mpim.model_file`) is an input of
/// `simulate`: an output there is refused and the model is left as it was (it was replaced by
/// the CSV).
#[test]
fn the_stage_files_model_file_is_not_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.json");
    std::fs::copy(models().join("table1-plant.json"), &model).unwrap();
    let stage = dir.path().join("stage.toml");
    std::fs::write(
        &stage,
        "[hysteresis]\nmodel = \"mpim\"\n[hysteresis.mpim]\nmodel_file = \"m.json\"\n",
    )
    .unwrap();
    let input = dir.path().join("in.csv");
    write_input(&input, 10_000.0, 100);
    let before = std::fs::read(&model).unwrap();
    assert_fails(
        &on_stage(&stage, &input, &model),
        &["hysteresis.mpim.model_file"],
    );
    assert_eq!(std::fs::read(&model).unwrap(), before);
}
