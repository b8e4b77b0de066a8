//! `hystcomp signal`: every kind writes `time_s` and its column at the sample rate, the values
//! those of the library's generators (the command only wraps them), scaled, sped up and cut as
//! asked; bad values are refused with exit code 1 and the option named.

mod common;

use common::{assert_fails, hystcomp, s, stderr, stdout};
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_experiments::signals::{PaperTrajectory, Raster, Shape, Signal, Steps};
use hystcomp_io::data::{Column, ReadOptions, read_columns};

/// Runs `hystcomp signal ARGS -o FILE` in `dir`; the file's header and columns.
fn signal(dir: &std::path::Path, args: &[&str]) -> (Vec<String>, Vec<Vec<f64>>) {
    let path = dir.join("signal.csv");
    let mut all = vec!["signal"];
    all.extend(args);
    all.extend(["-o", s(&path)]);
    let out = hystcomp(&all);
    assert!(out.status.success(), "{all:?}: {}", stderr(&out));
    let text = std::fs::read_to_string(&path).unwrap();
    let header: Vec<String> = text
        .lines()
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let columns = read_columns(
        &path,
        &[Column::Index(1), Column::Index(2)],
        &ReadOptions::default(),
    )
    .unwrap();
    (header, columns.values)
}

#[test]
fn every_kind_is_the_librarys_generator_scaled_sped_up_and_sampled() {
    let dir = tempfile::tempdir().unwrap();
    let rate = 2000.0;
    let cases: Vec<(Vec<&str>, Signal)> = vec![
        (
            vec!["paper", "--speed", "10", "--duration", "2"],
            Signal::paper(10.0, 2.0, rate),
        ),
        (
            vec![
                "triangle",
                "--frequency",
                "5",
                "--rounding",
                "0.1",
                "--amplitude",
                "3",
                "--offset",
                "-1",
            ],
            Signal {
                shape: Shape::Raster(Raster::triangle(5.0, 0.1)),
                amplitude: 3.0,
                offset: -1.0,
                duration_s: 10.0,
                speed: 1.0,
                sample_rate_hz: rate,
            },
        ),
        (
            vec![
                "steps",
                "--levels=-1,0.5,0",
                "--hold",
                "0.2",
                "--transition",
                "0.05",
                "--duration",
                "1",
            ],
            Signal {
                shape: Shape::Steps(Steps {
                    levels: vec![-1.0, 0.5, 0.0],
                    hold_s: 0.2,
                    transition_s: 0.05,
                }),
                amplitude: 10.0,
                offset: 20.0,
                duration_s: 1.0,
                speed: 1.0,
                sample_rate_hz: rate,
            },
        ),
    ];
    for (args, expected) in cases {
        let mut all = args.clone();
        all.extend(["--sample-rate", "2000"]);
        let (header, values) = signal(dir.path(), &all);
        assert_eq!(header, ["time_s", "desired_um"], "{args:?}");
        let want = expected.sample().unwrap();
        assert_eq!(values[1].len(), want.len(), "{args:?}");
        for (k, (got, want)) in values[1].iter().zip(&want).enumerate() {
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "{args:?} at {k}"
            );
            assert!((values[0][k] - k as f64 / rate).abs() < 1e-12);
        }
    }
    // The paper's trajectory by default: two periods of 10 s, its range.
    let (_, values) = signal(dir.path(), &["paper", "--sample-rate", "1000"]);
    assert_eq!(values[1].len(), 20_000);
    let paper = PaperTrajectory::new();
    let (lo, hi) = (
        paper.mid_range_um() - paper.half_range_um(),
        paper.mid_range_um() + paper.half_range_um(),
    );
    assert!(
        values[1]
            .iter()
            .all(|v| (lo - 1e-9..=hi + 1e-9).contains(v))
    );
    // The other generators run and stay in their range.
    for kind in ["sawtooth", "multisine", "chirp"] {
        let (_, values) = signal(
            dir.path(),
            &[kind, "--sample-rate", "1000", "--duration", "3"],
        );
        assert_eq!(values[1].len(), 3000, "{kind}");
        assert!(
            values[1]
                .iter()
                .all(|v| (10.0 - 1e-9..=30.0 + 1e-9).contains(v)),
            "{kind}"
        );
    }
}

#[test]
fn the_identification_excitation_is_the_studys_from_rest() {
    let dir = tempfile::tempdir().unwrap();
    let (header, values) = signal(dir.path(), &["identification", "--sample-rate", "1000"]);
    assert_eq!(header, ["time_s", "command_v"]);
    let study = IdentificationExcitation::default().command_v(1000.0);
    assert_eq!(values[1].len(), study.len());
    for (got, want) in values[1].iter().zip(&study) {
        assert!((got - want).abs() < 1e-12);
    }
    assert!(values[1][0].abs() < 1e-3, "from rest");
    // Sped up twice and scaled to 1 .. 3 V: half as long, the same shape.
    let (_, fast) = signal(
        dir.path(),
        &[
            "identification",
            "--sample-rate",
            "1000",
            "--speed",
            "2",
            "--amplitude",
            "1",
            "--offset",
            "2",
        ],
    );
    assert!(
        fast[1].len().abs_diff(study.len() / 2) <= 10,
        "{}",
        fast[1].len()
    );
    // (Its raised-cosine moves are sampled on a grid twice as coarse: equal to within one
    // nominal millisecond's move, at most 16 V/s x 1 ms, scaled by 1/5.)
    for (k, v) in fast[1].iter().enumerate().take(study.len() / 2) {
        let want = 2.0 + (study[2 * k] / 5.0 - 1.0);
        assert!((v - want).abs() < 0.004, "{k}: {v} against {want}");
    }
    // Longer than the excitation: held at its last value.
    let (_, long) = signal(
        dir.path(),
        &["identification", "--sample-rate", "100", "--duration", "60"],
    );
    assert_eq!(long[1].len(), 6000);
    assert_eq!(long[1][5999], long[1][5000]);
}

#[test]
fn bad_values_are_refused_naming_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.csv");
    let o = s(&out);
    assert_fails(&["signal", "paper", "--speed", "0", "-o", o], &["--speed"]);
    assert_fails(
        &["signal", "paper", "--sample-rate", "1e9", "-o", o],
        &["--sample-rate"],
    );
    assert_fails(
        &["signal", "paper", "--duration", "1e9", "-o", o],
        &["samples"],
    );
    assert_fails(
        &["signal", "multisine", "--tones", "100000", "-o", o],
        &["--tones"],
    );
    assert_fails(
        &["signal", "identification", "--duration=-1", "-o", o],
        &["--duration"],
    );
    // One second is few samples, but the excitation is built whole at the asked rate before
    // it is cut: that is bounded too (it allocated gigabytes, or aborted).
    assert_fails(
        &[
            "signal",
            "identification",
            "--sample-rate",
            "1e6",
            "--duration",
            "1",
            "-o",
            o,
        ],
        &["before it is cut", "--speed"],
    );
    assert_fails(
        &["signal", "triangle", "--rounding", "0.9", "-o", o],
        &["--rounding"],
    );
    assert_fails(
        &["signal", "sawtooth", "--rise-fraction", "1", "-o", o],
        &["--rise-fraction"],
    );
    assert_fails(&["signal", "steps", "--hold", "0", "-o", o], &["--hold"]);
    // Values no record could hold are refused, naming the row (counted from 1) and the scale.
    assert_fails(
        &["signal", "triangle", "--amplitude", "1e300", "-o", o],
        &["row ", "beyond the 1e15", "--amplitude"],
    );
    assert!(!out.exists(), "nothing written on a refusal");
    let usage = hystcomp(&["signal", "nonsense", "-o", o]);
    assert_eq!(usage.status.code(), Some(2));
    let json = hystcomp(&["--json", "signal", "steps", "--duration", "1", "-o", o]);
    let report: serde_json::Value = serde_json::from_str(&stdout(&json)).unwrap();
    assert_eq!(report["samples"], 10_000);
}

#[test]
fn evaluate_scores_the_last_period_of_signals_made_here() {
    let dir = tempfile::tempdir().unwrap();
    let desired = dir.path().join("desired.csv");
    let out = hystcomp(&[
        "signal",
        "paper",
        "--sample-rate",
        "1000",
        "-o",
        s(&desired),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = |args: &[&str]| {
        let mut all = vec![
            "evaluate",
            "--desired",
            s(&desired),
            "--measured",
            s(&desired),
        ];
        all.extend(args);
        let out = hystcomp(&all);
        assert!(out.status.success(), "{}", stderr(&out));
        stdout(&out)
    };
    let last = text(&["--time-column", "time_s", "--period", "10"]);
    assert!(last.starts_with("10000 samples, t = 10 .. 20 s"), "{last}");
    let whole = text(&["--time-column", "time_s"]);
    assert!(whole.starts_with("20000 samples, t = 0 .. 20 s"), "{whole}");
    assert_fails(
        &[
            "evaluate",
            "--desired",
            s(&desired),
            "--measured",
            s(&desired),
            "--period",
            "10",
        ],
        &["--period needs --time-column"],
    );
    assert_fails(
        &[
            "evaluate",
            "--desired",
            s(&desired),
            "--measured",
            s(&desired),
            "--time-column",
            "time_s",
            "--period",
            "30",
        ],
        &["longer than the record"],
    );
}
