//! The command line with creep and vibration: `identify` and `crossval` with
//! `--model-structure full`, `compensate` inverting the chain with the amplifier checked, on a
//! record simulated at 2 kHz (a stage file; small enough for a quick test), and the shared real
//! record (the acceptance of issue 11: the full model's prediction no worse than the
//! hysteresis-only model's).

mod common;

use std::path::{Path, PathBuf};

use common::*;
use hystcomp_experiments::chain_excitation::ChainExcitation;
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_experiments::signals::Signal;
use hystcomp_io::model_file::ModelFile;
use hystcomp_stage::{StageConfig, simulate};

const RATE: f64 = 2_000.0;

fn stage_file(dir: &Path) -> (PathBuf, StageConfig) {
    let path = dir.join("stage.toml");
    std::fs::write(&path, "sample_rate_hz = 2000.0\n").unwrap();
    (path.clone(), StageConfig::from_toml_file(&path).unwrap())
}

/// Writes `desired` (um) sampled at `rate_hz` as a `time_s,desired_um` trajectory file.
fn write_desired(path: &Path, desired: &[f64], rate_hz: f64) {
    let mut text = String::from("time_s,desired_um\n");
    for (k, y) in desired.iter().enumerate() {
        text.push_str(&format!("{},{y}\n", k as f64 / rate_hz));
    }
    std::fs::write(path, text).unwrap();
}

fn write_record(path: &Path, command: &[f64], measured: &[f64]) {
    let mut text = String::from("time_s,command_v,measured_um\n");
    for (k, (v, y)) in command.iter().zip(measured).enumerate() {
        text.push_str(&format!("{},{v},{y}\n", k as f64 / RATE));
    }
    std::fs::write(path, text).unwrap();
}

/// A shortened study excitation on the 2 kHz stage: the record and where the vibration
/// segment lies, s.
fn record(dir: &Path, config: &StageConfig) -> (PathBuf, f64, f64) {
    let hysteresis = IdentificationExcitation {
        segment_s: 0.5,
        multisine_s: 8.0,
        ..IdentificationExcitation::default()
    };
    let mut command = hysteresis.command_v(RATE);
    let chain = ChainExcitation {
        rate_s: 5.0,
        hold_s: 15.0,
        second_hold_s: 5.0,
        vibration_band_hz: [20.0, 900.0],
        ..ChainExcitation::default()
    };
    let start = command.len();
    let (part, segments) = chain
        .command_v(10.0, RATE, *command.last().unwrap())
        .unwrap();
    command.extend(part);
    let measured = simulate(config, 1, &command).unwrap().measured_position_um;
    let path = dir.join("record.csv");
    write_record(&path, &command, &measured);
    (
        path,
        (start + segments.vibration.start) as f64 / RATE,
        (start + segments.vibration.end) as f64 / RATE,
    )
}

fn identify_args<'a>(data: &'a Path, out: &'a Path, from: &'a str, to: &'a str) -> Vec<&'a str> {
    vec![
        "--json",
        "identify",
        "--data",
        s(data),
        "--voltage-column",
        "command_v",
        "--displacement-column",
        "measured_um",
        "--time-column",
        "time_s",
        "--model-structure",
        "full",
        "--dynamics-from",
        from,
        "--dynamics-to",
        to,
        "--decimation",
        "2",
        "--holdout",
        "0",
        "--warmup",
        "0",
        "-o",
        s(out),
    ]
}

#[test]
fn identify_fits_the_creep_on_the_record_holds_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let (_, config) = stage_file(dir.path());
    let (data, from, to) = record(dir.path(), &config);
    let (from, to) = (from.to_string(), to.to_string());
    let plant = dir.path().join("plant.json");
    let mut args = identify_args(&data, &plant, &from, &to);
    args.extend(["--creep-fit", "holds"]);
    let out = hystcomp(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let report = &json["report"];
    // The record's rest and two holds; every default candidate scored, one chosen.
    assert!(
        report["hysteresis"]["detail"]
            .as_str()
            .unwrap()
            .contains("on 3 holds"),
        "{report}"
    );
    let candidates = report["creep"]["smoothness_candidates"].as_array().unwrap();
    assert_eq!(
        candidates.len(),
        hystcomp_identify::creep_holds::DEFAULT_SMOOTHNESS_CANDIDATES.len()
    );
    let chosen = report["creep"]["smoothness"].as_f64().unwrap();
    assert!(candidates.iter().any(|c| c[0].as_f64() == Some(chosen)));
    // Creep still helps the fit.
    let rms: Vec<f64> = report["contributions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["rms_percent"].as_f64().unwrap())
        .collect();
    assert!(rms[1] < 0.6 * rms[0], "{rms:?}");
    let model = ModelFile::load(&plant).unwrap();
    assert!(model.creep.unwrap().weights.iter().all(|w| *w >= 0.0));

    // A record without holds is refused, saying why, and writes nothing.
    let moving = dir.path().join("moving.csv");
    let command: Vec<f64> = (0..20_000)
        .map(|k| 5.0 + 4.0 * (k as f64 / RATE).sin())
        .collect();
    let measured = simulate(&config, 1, &command).unwrap().measured_position_um;
    write_record(&moving, &command, &measured);
    let refused = dir.path().join("refused.json");
    let out = hystcomp(&[
        "identify",
        "--data",
        s(&moving),
        "--voltage-column",
        "command_v",
        "--displacement-column",
        "measured_um",
        "--time-column",
        "time_s",
        "--creep",
        "--creep-fit",
        "holds",
        "-o",
        s(&refused),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("holds its voltage nowhere"),
        "{}",
        stderr(&out)
    );
    assert!(!refused.exists());
}

#[test]
fn identify_compensate_and_crossval_take_the_full_model() {
    let dir = tempfile::tempdir().unwrap();
    let (stage, config) = stage_file(dir.path());
    let (data, from, to) = record(dir.path(), &config);
    let (from, to) = (from.to_string(), to.to_string());
    // identify: a format-version-2 file with both links, each helping.
    let plant = dir.path().join("plant.json");
    let out = hystcomp(&identify_args(&data, &plant, &from, &to));
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rms: Vec<f64> = json["report"]["contributions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["segment_rms_percent"].as_f64().unwrap())
        .collect();
    assert_eq!(rms.len(), 3);
    assert!(
        rms[2] < 0.5 * rms[1],
        "the vibration link on its segment: {rms:?}"
    );
    let model = ModelFile::load(&plant).unwrap();
    assert!(model.creep.is_some() && model.vibration.is_some());
    assert_eq!(model.sample_rate_hz, Some(RATE));
    assert!(
        std::fs::read_to_string(&plant)
            .unwrap()
            .contains("\"format_version\": 2")
    );
    // For people: the links and their contributions.
    let text = hystcomp(&identify_args(&data, &plant, &from, &to)[1..]);
    assert!(stdout(&text).contains("+ vibration"), "{}", stdout(&text));
    // Which samples the hysteresis and creep were fitted on (every second, up to the
    // vibration segment when it lies in the record's second half).
    let record_samples = std::fs::read_to_string(&data).unwrap().lines().count() - 1;
    assert!(
        stdout(&text).contains(&format!(
            "chain: the record has {record_samples} samples; the hysteresis and creep fitted \
             on samples 1 .. "
        )),
        "{}",
        stdout(&text)
    );
    assert!(
        stdout(&text).contains("(every 2 samples;"),
        "{}",
        stdout(&text)
    );
    // --creep --dynamics add both links: the same model as --model-structure full.
    let flagged = dir.path().join("flagged.json");
    let mut args = identify_args(&data, &flagged, &from, &to);
    let at = args.iter().position(|a| *a == "--model-structure").unwrap();
    args.splice(at..at + 2, ["--creep", "--dynamics"]);
    let out = hystcomp(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let flagged = ModelFile::load(&flagged).unwrap();
    assert_eq!(flagged.creep, model.creep);
    assert_eq!(flagged.vibration, model.vibration);
    // --dynamics alone (as --model-structure vibration): the vibration link, no creep link.
    for structure in [&["--dynamics"][..], &["--model-structure", "vibration"][..]] {
        let alone = dir.path().join("vibration-only.json");
        let mut args = identify_args(&data, &alone, &from, &to);
        let at = args.iter().position(|a| *a == "--model-structure").unwrap();
        args.splice(at..at + 2, structure.iter().copied());
        let out = hystcomp(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let alone = ModelFile::load(&alone).unwrap();
        assert!(alone.creep.is_none(), "{structure:?}");
        assert!(alone.vibration.is_some(), "{structure:?}");
        assert_eq!(alone.sample_rate_hz, Some(RATE));
    }

    // compensate: the paper's trajectory at the model's rate, checked against the amplifier.
    let desired = dir.path().join("desired.csv");
    let trajectory = Signal::paper(1.0, 20.0, RATE).sample().unwrap();
    write_desired(&desired, &trajectory, RATE);
    // The drive (IHC, limits 0-10 V, `extra` options), its report, and its e_rms on the stage
    // over the second half of the trajectory.
    let compensate = |name: &str, extra: &[&str]| {
        let drive = dir.path().join(name);
        let mut args = vec![
            "--json",
            "compensate",
            "--model",
            s(&plant),
            "--method",
            "ihc",
            "--desired",
            s(&desired),
            "--stage",
            s(&stage),
            "--limits",
            "0:10",
            "-o",
            s(&drive),
        ];
        args.extend_from_slice(extra);
        let out = hystcomp(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let drive_v = drive_column(&drive);
        assert_eq!(drive_v.len(), trajectory.len());
        assert!(drive_v.iter().all(|v| (0.0..=10.0).contains(v)));
        let measured = simulate(&config, 2, &drive_v).unwrap().measured_position_um;
        let last = trajectory.len() / 2..trajectory.len();
        let indices = hystcomp_experiments::TrackingIndices::compute(
            &trajectory[last.clone()],
            &measured[last],
            100,
        )
        .unwrap();
        (drive_v, report, indices.e_rms_percent)
    };
    let (drive_v, report, e_rms) = compensate("drive.csv", &[]);
    // Only the start from rest to the trajectory's first 60 um is slew-limited.
    let limited = report["feasibility"]["slew_limited"].as_u64().unwrap();
    assert!(limited < 40, "{report}");
    assert!(e_rms < 0.6, "{e_rms}");
    // A shorter preview than the default: still one drive row per desired sample, within the
    // limits, tracking (the vibration inverse cut shorter).
    let (short_v, report, short_e_rms) = compensate("short.csv", &["--preview", "8"]);
    assert_eq!(report["preview"], 8, "{report}");
    assert_ne!(short_v, drive_v);
    assert!(short_e_rms < 1.0, "{short_e_rms}");
    // A trajectory at another rate is refused: the vibration link is discrete.
    let wrong = dir.path().join("wrong.csv");
    write_desired(&wrong, &trajectory[..1000], 1000.0);
    assert_fails(
        &[
            "compensate",
            "--model",
            s(&plant),
            "--method",
            "ihc",
            "--desired",
            s(&wrong),
            "-o",
            s(&dir.path().join("w.csv")),
        ],
        &["resample", "2000 Hz"],
    );
    // A fast trajectory: the amplifier cannot slew it, and compensate says so before driving.
    let fast = dir.path().join("fast.csv");
    let trajectory = Signal::paper(100.0, 0.2, RATE).sample().unwrap();
    write_desired(&fast, &trajectory, RATE);
    let out = hystcomp(&[
        "compensate",
        "--model",
        s(&plant),
        "--method",
        "ihc",
        "--desired",
        s(&fast),
        "--stage",
        s(&stage),
        "--limits",
        "0:10",
        "--allow-saturation",
        "-o",
        s(&dir.path().join("f.csv")),
    ]);
    assert!(
        stderr(&out).contains("cannot deliver this drive"),
        "{}",
        stderr(&out)
    );
    band_limited_inversion(dir.path(), &plant, &fast, &stage);
    slew_constrained_drive(dir.path(), &plant, &fast, &stage, &config);

    // bench: the model file's own chain timed beside its hysteresis compensators, for a
    // plant (around IHC) and an inverse model (around DIHC).
    let timed = |model: &Path| -> Vec<String> {
        bench_model_figures(model)
            .iter()
            .map(|f| f["what"].as_str().unwrap().to_owned())
            .collect()
    };
    let mine = timed(&plant);
    assert!(
        mine.iter().any(|w| w == "chain-ihc") && mine.iter().any(|w| w == "ihc"),
        "{mine:?}"
    );
    let inverse = dir.path().join("inverse.json");
    let mut args = identify_args(&data, &inverse, &from, &to);
    args.extend(["--direction", "inverse"]);
    let out = hystcomp(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let mine = timed(&inverse);
    assert!(
        mine.iter().any(|w| w == "chain-dihc") && mine.iter().any(|w| w == "dihc"),
        "{mine:?}"
    );

    // crossval: the chains' reports beside the usual one.
    let crossval = |test: &Path| -> Vec<String> {
        [
            "crossval",
            "--train",
            s(&data),
            "--test",
            s(test),
            "--voltage-column",
            "command_v",
            "--displacement-column",
            "measured_um",
            "--time-column",
            "time_s",
            "--model-structure",
            "full",
            "--dynamics-from",
            &from,
            "--dynamics-to",
            &to,
        ]
        .map(str::to_owned)
        .to_vec()
    };
    let mut args = vec!["--json".to_owned()];
    args.extend(crossval(&data));
    args.extend(["--decimation".to_owned(), "2".to_owned()]);
    let out = hystcomp(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        json["plant_chain"]["contributions"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    assert!(
        json["report"]["test"]["forward"]["rms_percent"]
            .as_f64()
            .unwrap()
            < 0.5
    );
    // A test record at another rate than the training record's is refused before any work.
    let slow = dir.path().join("slow.csv");
    let mut text = String::from("time_s,command_v,measured_um\n");
    for k in 0..200 {
        let v = 5.0 + 4.0 * (k as f64 * 0.05).sin();
        text.push_str(&format!("{},{v},{}\n", k as f64 / (RATE / 2.0), 7.5 * v));
    }
    std::fs::write(&slow, text).unwrap();
    assert_fails(
        &crossval(&slow)
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
        &["sampled at 1000 Hz, the training record at 2000 Hz; creep and vibration"],
    );
    // predict: a model with creep and vibration links runs only at its own rate.
    let predict = |record: &Path, out: &str| {
        vec![
            "predict".to_owned(),
            "--model".to_owned(),
            s(&plant).to_owned(),
            "--data".to_owned(),
            s(record).to_owned(),
            "--voltage-column".to_owned(),
            "command_v".to_owned(),
            "--displacement-column".to_owned(),
            "measured_um".to_owned(),
            "--time-column".to_owned(),
            "time_s".to_owned(),
            "-o".to_owned(),
            s(&dir.path().join(out)).to_owned(),
        ]
    };
    let args = predict(&slow, "slow-prediction.csv");
    assert_fails(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &["the record is sampled at 1000 Hz", "identified at 2000 Hz"],
    );
    assert!(!dir.path().join("slow-prediction.csv").exists());
    let args = predict(&data, "prediction.csv");
    let out = hystcomp(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(out.status.success(), "{}", stderr(&out));
    // Creep and vibration need the sample rate.
    assert_fails(
        &[
            "identify",
            "--data",
            s(&data),
            "--voltage-column",
            "command_v",
            "--displacement-column",
            "measured_um",
            "--creep",
            "-o",
            s(&dir.path().join("x.json")),
        ],
        &["sample rate", "--time-column"],
    );
}

/// The drive column (second) of a drive file.
fn drive_column(path: &Path) -> Vec<f64> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect()
}

/// The largest step between neighbouring samples.
fn peak_step(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0, f64::max)
}

/// `compensate --inverse-band-hz`: the drive is the library's band-limited offline inversion
/// (`ScaledCompensator::with_inverse_band`), asks less slew than the whole inverse, and bad
/// bands or a model without a vibration link are refused with the option named.
fn band_limited_inversion(dir: &Path, plant: &Path, fast: &Path, stage: &Path) {
    use hystcomp_io::compensator::{Method, ScaledCompensator};
    let run = |band: Option<&str>, out: &Path| {
        let mut args = vec![
            "--json",
            "compensate",
            "--model",
            s(plant),
            "--method",
            "ihc",
            "--desired",
            s(fast),
            "--stage",
            s(stage),
            "--limits",
            "0:10",
            "--allow-saturation",
            "-o",
            s(out),
        ];
        if let Some(band) = band {
            args.extend(["--inverse-band-hz", band]);
        }
        let out = hystcomp(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let whole_path = dir.join("whole.csv");
    let banded_path = dir.join("banded.csv");
    let whole_report = run(None, &whole_path);
    let report = run(Some("60"), &banded_path);
    assert!(whole_report["inverse_band_hz"].is_null(), "{whole_report}");
    assert_eq!(report["inverse_band_hz"].as_f64(), Some(60.0), "{report}");
    let (whole, banded) = (drive_column(&whole_path), drive_column(&banded_path));
    // The library's offline inversion of the same trajectory with the same band.
    let model = ModelFile::load(plant).unwrap();
    let desired: Vec<f64> = std::fs::read_to_string(fast)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let mut reference = ScaledCompensator::new(&model, Method::Ihc, Some((0.0, 10.0)))
        .unwrap()
        .with_inverse_band(Some(60.0))
        .unwrap();
    let mut expected = vec![0.0; desired.len()];
    reference.process(&desired, &mut expected).unwrap();
    assert_eq!(banded.len(), expected.len());
    for (k, (a, b)) in banded.iter().zip(&expected).enumerate() {
        assert!(
            (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
            "sample {k}: {a} vs {b}"
        );
    }
    // Band-limited, the drive asks less of the amplifier than the whole inverse (after the
    // start from rest, a jump to the trajectory's first position either way).
    let (b, w) = (peak_step(&banded[50..]), peak_step(&whole[50..]));
    assert!(b < 0.8 * w, "{b} vs {w}");
    let slew = |r: &serde_json::Value| r["feasibility"]["slew_limited"].as_u64().unwrap();
    assert!(slew(&report) <= slew(&whole_report), "{report}");
    // The drive file's desired column is the trajectory as given, not the low-passed one.
    let written: Vec<f64> = std::fs::read_to_string(&banded_path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    assert_eq!(written, desired);
    // Bad bands: at or beyond the model's Nyquist frequency (1 kHz), zero, not a number.
    for bad in ["1000", "0", "1e9", "NaN"] {
        assert_fails(
            &[
                "compensate",
                "--model",
                s(plant),
                "--method",
                "ihc",
                "--desired",
                s(fast),
                "--inverse-band-hz",
                bad,
                "-o",
                s(&dir.join("bad.csv")),
            ],
            &["--inverse-band-hz", "Nyquist"],
        );
    }
    assert!(!dir.join("bad.csv").exists());
    // Without a vibration link there is nothing to band-limit.
    let table1 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/table1-plant.json");
    assert_fails(
        &[
            "compensate",
            "--model",
            s(&table1),
            "--method",
            "ihc",
            "--desired",
            s(fast),
            "--inverse-band-hz",
            "200",
            "-o",
            s(&dir.join("none.csv")),
        ],
        &["--inverse-band-hz", "no vibration link"],
    );
}

/// `compensate --within-slew`: every drive step within the share of the amplifier's slew
/// rate, the model tracking closer than the faithful drive clamped step by step; bad shares,
/// methods and models refused with the option named.
fn slew_constrained_drive(
    dir: &Path,
    plant: &Path,
    fast: &Path,
    stage: &Path,
    config: &StageConfig,
) {
    let base = |out: &Path| {
        vec![
            "--json".to_owned(),
            "compensate".to_owned(),
            "--model".to_owned(),
            s(plant).to_owned(),
            "--method".to_owned(),
            "ihc".to_owned(),
            "--desired".to_owned(),
            s(fast).to_owned(),
            "--stage".to_owned(),
            s(stage).to_owned(),
            "--limits".to_owned(),
            "0:10".to_owned(),
            "--allow-saturation".to_owned(),
            "-o".to_owned(),
            s(out).to_owned(),
        ]
    };
    let run = |args: Vec<String>| {
        let out = hystcomp(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(out.status.success(), "{}", stderr(&out));
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let whole_path = dir.join("faithful.csv");
    let slewed_path = dir.join("slewed.csv");
    let whole_report = run(base(&whole_path));
    assert!(whole_report["slew_constrained"].is_null(), "{whole_report}");
    let mut args = base(&slewed_path);
    args.extend(["--within-slew".to_owned(), "0.9".to_owned()]);
    let report = run(args);
    assert_eq!(report["slew_constrained"].as_bool(), Some(true), "{report}");
    let (faithful, slewed) = (drive_column(&whole_path), drive_column(&slewed_path));
    let max_step = 0.9 * config.amplifier.slew_rate_v_per_s() / config.amplifier.gain / RATE;
    assert!(peak_step(&faithful) > max_step);
    for (k, w) in slewed.windows(2).enumerate() {
        assert!(
            (w[1] - w[0]).abs() <= max_step * (1.0 + 1e-9),
            "sample {k}: {} > {max_step}",
            w[1] - w[0]
        );
    }
    assert!(slewed.iter().all(|v| (0.0..=10.0).contains(v)));
    let slew = |r: &serde_json::Value| r["feasibility"]["slew_limited"].as_u64().unwrap();
    assert!(slew(&report) < slew(&whole_report), "{report}");
    // Closer, through the model, than the faithful drive clamped step by step.
    let model = ModelFile::load(plant).unwrap();
    let desired: Vec<f64> = std::fs::read_to_string(fast)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let mut clamped = faithful.clone();
    for k in 1..clamped.len() {
        clamped[k] = clamped[k - 1] + (faithful[k] - clamped[k - 1]).clamp(-max_step, max_step);
    }
    let rms = |drive: &[f64]| {
        let y = model.predict(drive).unwrap();
        (y.iter()
            .zip(&desired)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / y.len() as f64)
            .sqrt()
    };
    assert!(
        rms(&slewed) < rms(&clamped),
        "{} vs {}",
        rms(&slewed),
        rms(&clamped)
    );
    // Refused: shares out of (0, 1], a loop method, a model without a vibration link, with
    // --preview.
    let table1 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/table1-plant.json");
    let refused = dir.join("refused.csv");
    for (extra, model, fragment) in [
        (vec!["--within-slew", "0"], plant, "between 0"),
        (vec!["--within-slew", "1.5"], plant, "between 0"),
        (vec!["--within-slew", "NaN"], plant, "between 0"),
        (
            vec!["--within-slew", "0.9", "--method", "ihc-guarded"],
            plant,
            "ihc or wihc",
        ),
        (
            vec!["--within-slew", "0.9"],
            table1.as_path(),
            "no vibration link",
        ),
        (
            vec!["--within-slew", "0.9", "--preview", "40"],
            plant,
            "drop --preview",
        ),
    ] {
        let mut args = vec![
            "compensate",
            "--model",
            s(model),
            "--desired",
            s(fast),
            "-o",
            s(&refused),
        ];
        if !extra.contains(&"--method") {
            args.extend(["--method", "ihc"]);
        }
        args.extend(extra);
        assert_fails(&args, &["--within-slew", fragment]);
    }
    assert!(!refused.exists());
}

#[test]
fn on_the_real_record_the_full_model_predicts_no_worse_than_hysteresis_alone() {
    let Some((train, test)) = dbo_records() else {
        return;
    };
    let run = |structure: &str| {
        let out = dbo_crossval(
            &train,
            &test,
            &["--sample-rate", "200", "--model-structure", structure],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let hysteresis = run("hysteresis");
    let full = run("full");
    let forward =
        |j: &serde_json::Value, key: &str| j["report"]["test"]["forward"][key].as_f64().unwrap();
    // The prediction of the other record: no worse, with the sensor's offset drift between
    // the records (0.9 um) and without it.
    assert!(
        forward(&full, "rms_percent") <= forward(&hysteresis, "rms_percent"),
        "{} vs {}",
        forward(&full, "rms_percent"),
        forward(&hysteresis, "rms_percent")
    );
    assert!(forward(&full, "std_percent") < forward(&hysteresis, "std_percent"));
    // What each link contributed on the training record: the delay (vibration link) found,
    // creep and hysteresis fitted jointly.
    let contributions = full["plant_chain"]["contributions"].as_array().unwrap();
    assert_eq!(contributions.len(), 3);
    assert!(
        full["plant_chain"]["dynamics"]["part"]["delay_samples"]
            .as_u64()
            .unwrap()
            >= 2
    );
    // The inverse chain's rows, link by link: with the record's delay of several samples, the
    // creep row is judged on a model fitted without the delay taken back (it was 5.5 % against
    // 0.47 % for hysteresis alone when it reused the delay-aligned MPIM), and the whole chain
    // fits better than hysteresis alone.
    let rows: Vec<f64> = full["inverse_chain"]["contributions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["rms_percent"].as_f64().unwrap())
        .collect();
    assert_eq!(rows.len(), 3);
    assert!(rows[1] < 1.1 * rows[0], "{rows:?}");
    assert!(rows[2] < rows[0], "{rows:?}");
    // Test samples outside the training ranges: for the chain, against the measured
    // displacement (its inverse model's own input is the creep-free displacement, against
    // which 3 080 of the 14 155 samples were once counted).
    let outside = |j: &serde_json::Value| {
        j["report"]["test"]["displacement_outside_model_range"]
            .as_u64()
            .unwrap()
    };
    assert!(outside(&hysteresis) < 50, "{}", outside(&hysteresis));
    assert!(outside(&full) < 50, "{}", outside(&full));
    // The offline inverse replay of every compensator is computed for both (the full model's
    // is worse on this record, 2.46 against 1.79 % for IHC: README, real data).
    for j in [&hysteresis, &full] {
        let replay = j["report"]["test"]["replay"].as_array().unwrap();
        assert_eq!(replay.len(), 7);
        let ihc = replay[0]["error"]["rms_percent"].as_f64().unwrap();
        assert!(ihc.is_finite() && ihc < 5.0, "{ihc}");
    }

    // compensate with the plant identified with the record's delay (--model-structure
    // vibration): the first test samples lie below the training range, and the inverse of
    // the delay asks for them while its preview fills, before the first drive sample: the
    // warning names t = 0 for them, not a time it does not have.
    let dir = tempfile::tempdir().unwrap();
    let plant = dir.path().join("plant.json");
    let out = hystcomp(&[
        "identify",
        "--data",
        s(&train),
        "--voltage-column",
        "1",
        "--displacement-column",
        "5",
        "--sample-rate",
        "200",
        "--model-structure",
        "vibration",
        "-o",
        s(&plant),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let measured: Vec<f64> = std::fs::read_to_string(&test)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_whitespace().nth(4).map(|y| y.parse().unwrap()))
        .collect();
    let desired = dir.path().join("desired.csv");
    write_desired(&desired, &measured, 200.0);
    let out = hystcomp(&[
        "compensate",
        "--model",
        s(&plant),
        "--method",
        "ihc",
        "--desired",
        s(&desired),
        "--allow-saturation",
        "-o",
        s(&dir.path().join("drive.csv")),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("lie outside what the model can reach"),
        "{}",
        stderr(&out)
    );
    assert!(
        stderr(&out).contains("(first at t = 0 s)"),
        "{}",
        stderr(&out)
    );
    assert!(!stderr(&out).contains("NaN"), "{}", stderr(&out));
}

/// A sample rate so low that the default creep bank's shortest time constant (two decimated
/// periods) passes its longest (1000 s): refused with the reason and the way out, for
/// `identify` and `crossval` alike, never a panic (it was `f64::clamp` with its bounds
/// crossed).
#[test]
fn a_sample_rate_too_low_for_the_default_creep_bank_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("slow.csv");
    let mut text = String::from("voltage_v,displacement_um\n");
    for k in 0..400 {
        let v = 5.0 + 4.0 * (k as f64 * 0.05).sin();
        text.push_str(&format!(
            "{v},{}\n",
            7.0 * v + 0.3 * (k as f64 * 0.05).cos()
        ));
    }
    std::fs::write(&data, text).unwrap();
    let out = dir.path().join("model.json");
    for (rate, decimation) in [("0.001", "1"), ("1", "1000")] {
        for command in ["identify", "crossval"] {
            let mut args = vec![command];
            match command {
                "identify" => args.extend(["--data", s(&data)]),
                _ => args.extend(["--train", s(&data), "--test", s(&data)]),
            }
            args.extend([
                "--voltage-column",
                "1",
                "--displacement-column",
                "2",
                "--sample-rate",
                rate,
                "--decimation",
                decimation,
                "--creep",
            ]);
            if command == "identify" {
                args.extend(["-o", s(&out)]);
            }
            let output = hystcomp(&args);
            assert_eq!(
                output.status.code(),
                Some(1),
                "{args:?}: {}",
                stderr(&output)
            );
            assert!(
                stderr(&output).contains("beyond the longest")
                    && stderr(&output).contains("--creep-time-constants"),
                "{args:?}: {}",
                stderr(&output)
            );
            assert!(!out.exists());
        }
    }
}
