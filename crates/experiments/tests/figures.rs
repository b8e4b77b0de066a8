//! Figures drawn from synthetic records: the files are valid PNG and SVG that show what they
//! should, decimation keeps each run's extremes, and bad data gives errors, not panics.
//!
//! Set `HYSTCOMP_KEEP_FIGURES=<dir>` to keep the figures in `<dir>` for looking at them.

mod common;

use std::path::{Path, PathBuf};
use std::time::Instant;

use common::{decode_png, png_colour_type};

use hystcomp_experiments::Reference;
use hystcomp_experiments::figures::{
    self, FigureError, LABEL_DESIRED_POSITION, LABEL_POSITION, LABEL_TIME, LABEL_TRACKING_ERROR,
    Panel, decimate_min_max, decimate_min_max_indices,
};
use proptest::prelude::*;

/// A synthetic run of the paper's trajectory: 20 s at 10 kHz.
struct Run {
    time_s: Vec<f64>,
    desired_um: Vec<f64>,
    /// A hysteretic stage with a linear feedforward gain (like fig. 7).
    uncompensated_um: Vec<f64>,
    /// Three compensated runs: small smooth errors plus deterministic "noise".
    compensated_um: [Vec<f64>; 3],
}

/// A plain one-sided play operator (eq. (1)-(2)), for a synthetic hysteresis loop.
fn play(input: &[f64], r: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(input.len());
    let mut w = 0.0_f64;
    for &v in input {
        w = w.max(v - r).min(v);
        out.push(w);
    }
    out
}

fn synthetic_run() -> Run {
    let reference = Reference::paper();
    let (time_s, desired_um) = reference.trajectory().sample(10_000.0, 200_000);
    let top = desired_um.iter().copied().fold(0.0, f64::max);
    let v: Vec<f64> = desired_um.iter().map(|y| y / top).collect();
    let thresholds = [0.0, 0.1, 0.2, 0.3];
    let weights = [0.55, 0.25, 0.12, 0.08];
    let mut hyst = vec![0.0; v.len()];
    for (r, b) in thresholds.iter().zip(weights) {
        for (h, p) in hyst.iter_mut().zip(play(&v, *r)) {
            *h += b * p;
        }
    }
    let uncompensated_um = hyst.iter().map(|h| h * top).collect();
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut noise = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let compensated_um = [(0.6, 1.0), (0.9, -1.0), (0.5, 0.0)].map(|(gain, bias)| {
        time_s
            .iter()
            .zip(&desired_um)
            .map(|(t, d)| d + bias + gain * (2.0 * std::f64::consts::PI * t).sin() + 0.1 * noise())
            .collect()
    });
    Run {
        time_s,
        desired_um,
        uncompensated_um,
        compensated_um,
    }
}

fn out_dir() -> (Option<tempfile::TempDir>, PathBuf) {
    match std::env::var_os("HYSTCOMP_KEEP_FIGURES") {
        Some(dir) => (None, PathBuf::from(dir)),
        None => {
            let tmp = tempfile::tempdir().expect("a temporary directory");
            let path = tmp.path().to_path_buf();
            (Some(tmp), path)
        }
    }
}

/// Asserts the image is a drawn figure: not blank, several colours, dark text, and pixels
/// close to each `colours` (the series colours).
fn assert_drawn(path: &Path, size: (u32, u32), colours: &[[u8; 3]]) {
    assert_eq!(
        png_colour_type(path),
        png::ColorType::Rgb,
        "{}",
        path.display()
    );
    let (w, h, pixels) = decode_png(path);
    assert_eq!((w, h), size, "{}", path.display());
    let distinct: std::collections::HashSet<[u8; 3]> = pixels.iter().copied().collect();
    assert!(
        distinct.len() >= 8,
        "{}: {} colours",
        path.display(),
        distinct.len()
    );
    let dark = pixels.iter().filter(|p| p.iter().all(|&c| c < 80)).count();
    assert!(
        dark > 1_000,
        "{}: only {dark} dark (text) pixels",
        path.display()
    );
    let white = pixels.iter().filter(|p| **p == [255, 255, 255]).count();
    assert!(
        white > pixels.len() / 3,
        "{}: background is not white",
        path.display()
    );
    for colour in colours {
        let near = pixels
            .iter()
            .filter(|p| p.iter().zip(colour).all(|(&a, &b)| a.abs_diff(b) <= 12))
            .count();
        assert!(
            near > 300,
            "{}: only {near} pixels of series colour {colour:?}",
            path.display()
        );
    }
}

fn assert_svg(path: &Path, texts: &[&str]) {
    let svg = std::fs::read_to_string(path).expect("the SVG exists");
    assert!(svg.starts_with("<svg"), "{}", path.display());
    assert!(svg.trim_end().ends_with("</svg>"), "{}", path.display());
    assert!(
        svg.len() < 2_000_000,
        "{}: {} bytes",
        path.display(),
        svg.len()
    );
    for text in texts {
        assert!(svg.contains(text), "{} lacks {text:?}", path.display());
    }
    assert_well_formed(&svg, path);
}

/// A small XML well-formedness check: every element closes in order, attributes are quoted,
/// and text holds no raw `<` or stray `&`.
fn assert_well_formed(svg: &str, path: &Path) {
    let mut open: Vec<&str> = Vec::new();
    let mut rest = svg;
    while let Some(start) = rest.find('<') {
        let text = &rest[..start];
        assert!(
            text.split('&')
                .skip(1)
                .all(|t| ["lt;", "gt;", "amp;", "quot;", "apos;", "#"]
                    .iter()
                    .any(|e| t.starts_with(e))),
            "{}: stray '&' in {text:?}",
            path.display()
        );
        let end = start + rest[start..].find('>').expect("tag closes");
        let tag = &rest[start + 1..end];
        assert!(
            !tag.contains('<'),
            "{}: '<' inside a tag: {tag:?}",
            path.display()
        );
        assert_eq!(
            tag.matches('"').count() % 2,
            0,
            "{}: unbalanced quotes",
            path.display()
        );
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                open.pop(),
                Some(name.trim()),
                "{}: bad nesting",
                path.display()
            );
        } else if !tag.ends_with('/') && !tag.starts_with('?') && !tag.starts_with('!') {
            open.push(tag.split_whitespace().next().unwrap_or(""));
        }
        rest = &rest[end + 1..];
    }
    assert!(
        open.is_empty(),
        "{}: unclosed elements {open:?}",
        path.display()
    );
}

const BLUE: [u8; 3] = [0, 114, 178];
const VERMILION: [u8; 3] = [213, 94, 0];
const GREEN: [u8; 3] = [0, 158, 115];

#[test]
fn figures_of_a_synthetic_run_are_valid_png_and_svg_showing_their_labels() {
    let run = synthetic_run();
    let (_keep, dir) = out_dir();
    let errors: Vec<Vec<f64>> = run
        .compensated_um
        .iter()
        .map(|y| y.iter().zip(&run.desired_um).map(|(y, d)| y - d).collect())
        .collect();

    // Fig. 7: the uncompensated map.
    let fig7 = Panel::map("Hysteresis without compensation (linear gain)", true)
        .with_series("measured y", &run.desired_um, &run.uncompensated_um)
        .with_note("e_mhe = 13.0 % (100 bins)");
    // Its time is printed, not asserted (a test build on a shared machine): speed is the
    // benches' to measure.
    let started = Instant::now();
    let files = figures::write_panel_figure(&dir, "fig07_uncompensated", &fig7).unwrap();
    let elapsed = started.elapsed();
    eprintln!("fig07 (200 000 samples) drawn and written in {elapsed:?}");
    assert_eq!(files.png, dir.join("fig07_uncompensated.png"));
    assert_drawn(&files.png, figures::PANEL_FIGURE_SIZE, &[BLUE]);
    assert_svg(
        &files.svg,
        &[
            "desired position y_d (µm)",
            "actual position y (µm)",
            "measured y",
            "ideal: y = y_d",
            "e_mhe = 13.0 % (100 bins)",
        ],
    );

    // Fig. 8 (b): response, desired first (blue solid) and actual (vermilion dashed).
    let response = Panel::time_series("IHC: tracking response", LABEL_POSITION)
        .with_series("desired y_d", &run.time_s, &run.desired_um)
        .with_series("actual y", &run.time_s, &run.compensated_um[0]);
    let files = figures::write_panel_figure(&dir, "fig08b_ihc_response", &response).unwrap();
    assert_drawn(&files.png, figures::PANEL_FIGURE_SIZE, &[BLUE, VERMILION]);
    assert_svg(
        &files.svg,
        &[LABEL_TIME, LABEL_POSITION, "desired y_d", "actual y"],
    );

    // Fig. 11: the three errors overlaid.
    let fig11 = Panel::time_series(
        "Tracking errors of the three approaches",
        LABEL_TRACKING_ERROR,
    )
    .with_series("IHC", &run.time_s, &errors[0])
    .with_series("WIHC", &run.time_s, &errors[1])
    .with_series("DIHC", &run.time_s, &errors[2])
    .with_note("e_rms: IHC 0.75 %, WIHC 0.76 %, DIHC 0.78 %");
    let files = figures::write_panel_figure(&dir, "fig11_errors", &fig11).unwrap();
    assert_drawn(
        &files.png,
        figures::PANEL_FIGURE_SIZE,
        &[BLUE, VERMILION, GREEN],
    );
    assert_svg(
        &files.svg,
        &["tracking error y − y_d (µm)", "IHC", "WIHC", "DIHC"],
    );

    // Fig. 12: the three maps overlaid.
    let fig12 = Panel::map("Resulting hysteresis of the three approaches", true)
        .with_series("IHC", &run.desired_um, &run.compensated_um[0])
        .with_series("WIHC", &run.desired_um, &run.compensated_um[1])
        .with_series("DIHC", &run.desired_um, &run.compensated_um[2]);
    let files = figures::write_panel_figure(&dir, "fig12_maps", &fig12).unwrap();
    assert_drawn(
        &files.png,
        figures::PANEL_FIGURE_SIZE,
        &[BLUE, VERMILION, GREEN],
    );
    assert_svg(&files.svg, &[LABEL_DESIRED_POSITION, "IHC", "WIHC", "DIHC"]);

    // Figs. 8-10 as one composite per approach.
    let map = Panel::map("(a) desired versus actual position", true)
        .with_series("IHC", &run.desired_um, &run.compensated_um[0])
        .with_note("e_mhe = 2.9 % (100 bins)");
    let error = Panel::time_series("(c) tracking error", LABEL_TRACKING_ERROR).with_series(
        "y − y_d",
        &run.time_s,
        &errors[0],
    );
    let mut response = response.clone();
    response.title = "(b) tracking response";
    let files = figures::write_approach_figure(
        &dir,
        "fig08_ihc",
        "IHC: inverse hysteresis compensation",
        &map,
        &response,
        &error,
    )
    .unwrap();
    assert_drawn(
        &files.png,
        figures::APPROACH_FIGURE_SIZE,
        &[BLUE, VERMILION],
    );
    assert_svg(
        &files.svg,
        &[
            "IHC: inverse hysteresis compensation",
            "(a) desired versus actual position",
            "(b) tracking response",
            "(c) tracking error",
        ],
    );

    // Nothing but the figures is left in the directory (no temporary files).
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("fig"))
        .collect();
    names.sort();
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    assert_eq!(names.len(), 10, "{names:?}");
}

#[test]
fn rewriting_a_figure_replaces_it_whole() {
    let dir = tempfile::tempdir().unwrap();
    let x: Vec<f64> = (0..50).map(f64::from).collect();
    let first = Panel::time_series("first", LABEL_POSITION).with_series("first series", &x, &x);
    let second = Panel::time_series("second", LABEL_POSITION).with_series("second series", &x, &x);
    std::fs::write(dir.path().join("f.svg"), "stale").unwrap();
    figures::write_panel_figure(dir.path(), "f", &first).unwrap();
    let files = figures::write_panel_figure(dir.path(), "f", &second).unwrap();
    let svg = std::fs::read_to_string(&files.svg).unwrap();
    assert!(svg.contains("second series") && !svg.contains("first series"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn markup_in_labels_is_escaped_in_the_svg() {
    let dir = tempfile::tempdir().unwrap();
    let x: Vec<f64> = (0..100).map(f64::from).collect();
    let panel = Panel::time_series("a <b> & \"c\"", LABEL_POSITION)
        .with_series("y < y_d & more", &x, &x)
        .with_note("<script>alert(1)</script>");
    let files = figures::write_panel_figure(dir.path(), "markup", &panel).unwrap();
    let svg = std::fs::read_to_string(&files.svg).unwrap();
    assert!(!svg.contains("<script>") && !svg.contains("<b>"));
    assert!(svg.contains("y &lt; y_d &amp; more"));
    assert_well_formed(&svg, &files.svg);
}

#[test]
fn constant_and_single_sample_series_are_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let x = [1.0];
    let y = [2.0];
    let single = Panel::map("one sample", true).with_series("one", &x, &y);
    figures::write_panel_figure(dir.path(), "single", &single).unwrap();
    let t = [0.0, 1.0, 2.0];
    let c = [5.0, 5.0, 5.0];
    let flat = Panel::time_series("flat", LABEL_POSITION).with_series("flat", &t, &c);
    figures::write_panel_figure(dir.path(), "flat", &flat).unwrap();
}

#[test]
fn a_logarithmic_axis_spans_decades_with_round_ticks() {
    let dir = tempfile::tempdir().unwrap();
    let t: Vec<f64> = (1..=1000).map(|i| i as f64).collect();
    let y: Vec<f64> = t.iter().map(|i| 100.0 / i).collect();
    let panel = Panel::time_series("decay", "error (%)")
        .with_log_y()
        .with_series("1/t", &t, &y);
    let files = figures::write_panel_figure(dir.path(), "log", &panel).unwrap();
    let svg = std::fs::read_to_string(&files.svg).unwrap();
    let texts: Vec<&str> = svg.lines().map(str::trim).collect();
    // Ticks at the decades between 0.1 and 100: a linear axis from 0.1 to 100 would not
    // label 0.1, 1 and 10 all three.
    for tick in ["0.1", "1", "10", "100"] {
        assert!(texts.contains(&tick), "no tick {tick} in the SVG");
    }
}

#[test]
fn bad_data_gives_errors_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let good = [0.0, 1.0, 2.0];
    let nan = [0.0, f64::NAN, 2.0];
    let inf = [0.0, 1.0, f64::INFINITY];
    let short = [0.0, 1.0];
    let empty: [f64; 0] = [];

    let cases: Vec<(&str, Panel<'_>)> = vec![
        ("no series", Panel::map("nothing", true)),
        (
            "empty",
            Panel::map("empty", true).with_series("e", &empty, &empty),
        ),
        (
            "nan",
            Panel::map("nan", false).with_series("n", &good, &nan),
        ),
        (
            "inf x",
            Panel::time_series("inf", LABEL_POSITION).with_series("i", &inf, &good),
        ),
        (
            "mismatch",
            Panel::time_series("m", LABEL_POSITION).with_series("m", &good, &short),
        ),
        (
            "too wide",
            Panel::map("wide", false).with_series("w", &[-f64::MAX, f64::MAX], &good[..2]),
        ),
        (
            "log of zero",
            Panel::time_series("log", LABEL_POSITION)
                .with_log_y()
                .with_series("z", &good, &good),
        ),
    ];
    for (what, panel) in &cases {
        let err = figures::write_panel_figure(dir.path(), "bad", panel).unwrap_err();
        assert!(!err.to_string().is_empty());
        match (*what, &err) {
            ("no series", FigureError::NoSeries { .. })
            | ("empty", FigureError::EmptySeries { .. })
            | (
                "nan",
                FigureError::NonFinite {
                    axis: "y",
                    index: 1,
                    ..
                },
            )
            | (
                "inf x",
                FigureError::NonFinite {
                    axis: "x",
                    index: 2,
                    ..
                },
            )
            | (
                "mismatch",
                FigureError::LengthMismatch {
                    x_len: 3, y_len: 2, ..
                },
            )
            | ("too wide", FigureError::RangeTooWide { .. })
            | ("log of zero", FigureError::NotPositive { index: 0, .. }) => {}
            _ => panic!("{what}: unexpected error {err:?}"),
        }
    }
    let ok = Panel::map("ok", true).with_series("ok", &good, &good);
    assert!(matches!(
        figures::write_panel_figure(dir.path(), "../escape", &ok),
        Err(FigureError::BadStem(_))
    ));
    let bad = Panel::map("nan", false).with_series("n", &good, &nan);
    assert!(figures::write_approach_figure(dir.path(), "composite", "t", &ok, &ok, &bad).is_err());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "files written on error"
    );

    assert!(matches!(
        decimate_min_max(&good, &short, 10),
        Err(FigureError::LengthMismatch { .. })
    ));
    assert!(matches!(
        decimate_min_max(&good, &nan, 10),
        Err(FigureError::NonFinite { .. })
    ));
    assert!(matches!(
        decimate_min_max(&good, &good, 1),
        Err(FigureError::TooFewPoints(1))
    ));
    assert!(matches!(
        decimate_min_max(&empty, &empty, 10),
        Err(FigureError::EmptySeries { .. })
    ));
}

/// The plain definition: run `b` of `n` samples in `bins` runs is `b*n/bins .. (b+1)*n/bins`;
/// its extremes are found by sorting.
fn reference_extremes(y: &[f64], bins: usize) -> Vec<(std::ops::Range<usize>, f64, f64)> {
    let n = y.len();
    (0..bins)
        .map(|b| {
            let range = b * n / bins..(b + 1) * n / bins;
            let mut values = y[range.clone()].to_vec();
            values.sort_by(|a, b| a.partial_cmp(b).unwrap());
            (range, values[0], values[values.len() - 1])
        })
        .collect()
}

proptest! {
    #[test]
    fn decimation_keeps_the_extremes_of_every_run(
        y in prop::collection::vec(-1.0e6..1.0e6_f64, 0..3000),
        max_points in 2usize..400,
    ) {
        let kept = decimate_min_max_indices(&y, max_points).unwrap();
        prop_assert!(kept.windows(2).all(|w| w[0] < w[1]), "indices not increasing");
        prop_assert!(kept.iter().all(|&i| i < y.len()));
        if y.len() <= max_points {
            prop_assert_eq!(kept, (0..y.len()).collect::<Vec<_>>());
        } else {
            prop_assert!(kept.len() <= max_points);
            for (range, lo, hi) in reference_extremes(&y, max_points / 2) {
                let inside: Vec<f64> = kept.iter().filter(|i| range.contains(i)).map(|&i| y[i]).collect();
                prop_assert!(!inside.is_empty() && inside.len() <= 2);
                prop_assert!(inside.contains(&lo), "min {} of {:?} lost", lo, range);
                prop_assert!(inside.contains(&hi), "max {} of {:?} lost", hi, range);
            }
        }
    }

    #[test]
    fn decimated_points_are_samples_of_the_record(
        y in prop::collection::vec(-10.0..10.0_f64, 1..2000),
        max_points in 2usize..100,
    ) {
        let x: Vec<f64> = (0..y.len()).map(|i| i as f64 * 0.5).collect();
        let points = decimate_min_max(&x, &y, max_points).unwrap();
        for (px, py) in points {
            let i = (px / 0.5) as usize;
            prop_assert_eq!(y[i], py);
        }
    }
}
