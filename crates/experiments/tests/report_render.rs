//! The report as a person sees it: written from synthetic data with real figures, rendered by
//! headless Chromium, and checked on the screenshot (not blank, the Table 3 colours and text
//! where the table is) and on the rendered DOM (Table 3 holds the expected numbers).
//!
//! Needs Debian's `chromium` (`apt-get install -y chromium`); `HYSTCOMP_CHROMIUM` names another
//! binary. Without a browser the test fails, unless `HYSTCOMP_SKIP_BROWSER_TESTS=1`.
//! Set `HYSTCOMP_KEEP_REPORT=<dir>` to keep the report and the screenshot in `<dir>`.

use std::path::{Path, PathBuf};

use hystcomp_experiments::figures::{self, LABEL_POSITION, LABEL_TRACKING_ERROR, Panel};
use hystcomp_experiments::report::{
    AcceptanceBound, Compensator, Fact, FigureEntry, IndexName, ModelParameters, PipelineResult,
    ReportData, Seed, TextSection, write_report,
};
use hystcomp_experiments::{Reference, TrackingIndices};

mod common;

use common::*;

fn indices(e_mhe: f64, e_m: f64, e_rms: f64) -> TrackingIndices {
    TrackingIndices {
        e_mhe_percent: e_mhe,
        e_m_percent: e_m,
        e_rms_percent: e_rms,
        mhe_bins: 100,
    }
}

fn model(input_unit: &str, output_unit: &str, sign: f64) -> ModelParameters {
    ModelParameters {
        thresholds: (0..10).map(|i| f64::from(i) / 10.0).collect(),
        weights: (0..10).map(|i| sign * 0.3 / f64::from(i + 1)).collect(),
        a1: -0.1523 * sign,
        a2: 0.4712,
        input_scale: 120.0,
        input_unit: input_unit.to_string(),
        output_scale: 69.31,
        output_unit: output_unit.to_string(),
        fit: vec![Fact::new("fit RMS error", "0.18 µm")],
    }
}

/// Draws the figures of a synthetic run into `dir` and returns their entries.
fn draw_figures(dir: &Path) -> Vec<FigureEntry> {
    let reference = Reference::paper();
    let (t, yd) = reference.trajectory().sample(1000.0, 20_000);
    let top = yd.iter().copied().fold(0.0, f64::max);
    // A crude hysteresis: a play operator of width 0.1 (normalised) mixed with the input.
    let mut w = 0.0_f64;
    let uncomp: Vec<f64> = yd
        .iter()
        .map(|y| {
            let v = y / top;
            w = w.max(v - 0.1).min(v);
            (0.5 * v + 0.5 * w) * top
        })
        .collect();
    let comp: Vec<f64> = t
        .iter()
        .zip(&yd)
        .map(|(t, y)| y + 0.5 * (2.0 * std::f64::consts::PI * t).sin())
        .collect();
    let err: Vec<f64> = comp.iter().zip(&yd).map(|(y, d)| y - d).collect();

    let fig7 = Panel::map("Without compensation", true).with_series("measured y", &yd, &uncomp);
    figures::write_panel_figure(dir, "fig07", &fig7).unwrap();
    let map = Panel::map("(a) desired versus actual", true).with_series("IHC", &yd, &comp);
    let response = Panel::time_series("(b) response", LABEL_POSITION)
        .with_series("desired y_d", &t, &yd)
        .with_series("actual y", &t, &comp);
    let error = Panel::time_series("(c) tracking error", LABEL_TRACKING_ERROR).with_series(
        "y − y_d",
        &t,
        &err,
    );
    figures::write_approach_figure(dir, "fig08", "IHC", &map, &response, &error).unwrap();
    vec![
        FigureEntry {
            png_file: "fig07.png".to_string(),
            svg_file: Some("fig07.svg".to_string()),
            paper_figure: "Fig. 7".to_string(),
            caption: "Actual against desired position with the linear feedforward gain only."
                .to_string(),
        },
        FigureEntry {
            png_file: "fig08.png".to_string(),
            svg_file: Some("fig08.svg".to_string()),
            paper_figure: "Fig. 8".to_string(),
            caption: "IHC of the exact pipeline: map, response and error.".to_string(),
        },
    ]
}

fn report_data(figures: Vec<FigureEntry>) -> ReportData {
    ReportData {
        title: "hystcomp reproduce: synthetic report for the rendering test".to_string(),
        generated_at: "2026-04-01T09:30:00Z".to_string(),
        git_description: Some("v0.1.0-test".to_string()),
        command_line: Some("cargo test --test report_render".to_string()),
        run_time_s: Some(12.3),
        seeds: vec![
            Seed {
                name: "stage noise".to_string(),
                value: 20140917,
            },
            Seed {
                name: "PSO".to_string(),
                value: 7,
            },
        ],
        run_facts: vec![
            Fact::new("sample rate", "10 kHz"),
            Fact::new("evaluation window", "last 10 s period (10 s to 20 s)"),
        ],
        uncompensated: Some(indices(12.87, 10.52, 4.33)),
        pipelines: vec![
            PipelineResult {
                name: "paper".to_string(),
                description: "PSO identification, delayed IHC and WIHC".to_string(),
                ihc: Some(indices(3.41, 2.93, 0.88)),
                wihc: Some(indices(3.37, 3.02, 0.91)),
                dihc: Some(indices(2.64, 2.21, 0.83)),
                forward_model: Some(model("V", "µm", 1.0)),
                inverse_model: Some(model("µm", "V", -1.0)),
                notes: vec![],
            },
            PipelineResult {
                name: "exact".to_string(),
                description: "least-squares identification, exact inverses".to_string(),
                ihc: Some(indices(1.46, 1.18, 0.36)),
                wihc: Some(indices(1.47, 1.19, 0.37)),
                dihc: Some(indices(1.95, 1.57, 0.52)),
                forward_model: Some(model("V", "µm", 1.0)),
                inverse_model: Some(model("µm", "V", -1.0)),
                notes: vec![],
            },
        ],
        table3_notes: vec!["Calibrated <by> construction.".to_string()],
        acceptance: vec![
            AcceptanceBound {
                pipeline: Some("exact".to_string()),
                compensator: None,
                index: IndexName::EMhe,
                min_percent: None,
                max_percent: Some(3.0),
                source: "the paper's e_mhe".to_string(),
                informational: false,
            },
            AcceptanceBound {
                pipeline: Some("paper".to_string()),
                compensator: Some(Compensator::Ihc),
                index: IndexName::EMhe,
                min_percent: None,
                max_percent: Some(3.0),
                source: "the paper's e_mhe".to_string(),
                informational: false,
            },
        ],
        figures,
        sections: vec![TextSection {
            heading: "Why the pipelines differ".to_string(),
            paragraphs: vec![
                "Synthetic text. <script>document.body.innerHTML = 'owned'</script>".to_string(),
            ],
            ..Default::default()
        }],
        stage_config_toml: "[amplifier]\ngain = 15.0\nrange_v = [0.0, 150.0]\n".to_string(),
    }
}

#[test]
fn chromium_renders_the_report_with_its_table() {
    let Some(browser) = chromium() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let dir = match std::env::var_os("HYSTCOMP_KEEP_REPORT") {
        Some(d) => PathBuf::from(d),
        None => tmp.path().join("report"),
    };
    std::fs::create_dir_all(&dir).unwrap();
    let dir = dir.canonicalize().unwrap();
    let figures = draw_figures(&dir);
    let page = write_report(&dir, &report_data(figures)).unwrap();

    // The rendered DOM holds Table 3 with our numbers and the paper's, and no injected script.
    let dom_file = dir.join("dom.html");
    run_chromium(&browser, &["--dump-dom".to_string()], &page, &dom_file);
    let dom = std::fs::read_to_string(&dom_file).unwrap();
    let start = dom
        .find("id=\"table3-table\"")
        .expect("Table 3 in the rendered DOM");
    let table = &dom[start..start + dom[start..].find("</table>").unwrap()];
    for number in [
        "12.87", "3.41", "2.93", "0.88", "1.46", "0.52", "2.66", "2.06", "0.78", ">13<",
    ] {
        assert!(table.contains(number), "Table 3 lacks {number}");
    }
    // Had the free text run as a script, the body would be the word "owned" alone.
    assert!(!dom.contains("<script"), "a script element reached the DOM");
    assert!(dom.contains("&lt;script&gt;document.body.innerHTML = "));

    // The screenshot.
    let (w, h, pixels) = screenshot(&browser, &page, &dir);
    assert_shows_table(w, h, &pixels);
    let red = pixels.iter().filter(|p| near(**p, MISS_RED)).count();
    let green = pixels.iter().filter(|p| near(**p, PASS_GREEN)).count();
    assert!(red > 1_000, "the missed cell is not painted ({red} px)");
    assert!(green > 2_000, "the met cells are not painted ({green} px)");

    if let Some(keep) = std::env::var_os("HYSTCOMP_KEEP_REPORT") {
        eprintln!(
            "report and screenshot kept in {}",
            PathBuf::from(keep).display()
        );
    }
}
