//! Tests of the report's HTML: Table 3, the checks, escaping by the engine, the parameter
//! tables, refusals and the atomic write.
use super::view::{param, pct};
use super::*;

fn indices(e_mhe: f64, e_m: f64, e_rms: f64) -> TrackingIndices {
    TrackingIndices {
        e_mhe_percent: e_mhe,
        e_m_percent: e_m,
        e_rms_percent: e_rms,
        mhe_bins: 100,
    }
}

fn model(unit_in: &str, unit_out: &str) -> ModelParameters {
    ModelParameters {
        thresholds: (0..10).map(|i| i as f64 / 10.0).collect(),
        weights: vec![
            0.25, 0.3, 0.01, 0.07, 0.06, 0.02, 0.004, 0.009, 0.026, -0.00002,
        ],
        a1: -0.15,
        a2: 0.47,
        input_scale: 120.0,
        input_unit: unit_in.to_string(),
        output_scale: 69.3,
        output_unit: unit_out.to_string(),
        fit: vec![Fact::new("fit RMS error", "0.21 µm")],
    }
}

fn data() -> ReportData {
    ReportData {
        title: "Study <one>".to_string(),
        generated_at: "2026-04-01T09:30:00Z".to_string(),
        git_description: Some("v0.1.0-3-gabcdef".to_string()),
        command_line: Some("hystcomp reproduce --out report".to_string()),
        run_time_s: Some(42.5),
        seeds: vec![Seed {
            name: "stage noise".to_string(),
            value: 7,
        }],
        run_facts: vec![Fact::new("sample rate", "10 kHz")],
        uncompensated: Some(indices(12.34, 11.0, 4.0)),
        pipelines: vec![
            PipelineResult {
                name: "paper".to_string(),
                description: "PSO identification, delayed IHC & WIHC".to_string(),
                ihc: Some(indices(3.21, 2.71, 0.81)),
                wihc: Some(indices(3.05, 2.95, 0.79)),
                dihc: None,
                forward_model: Some(model("V", "µm")),
                inverse_model: None,
                notes: vec!["DIHC model refused: not invertible".to_string()],
            },
            PipelineResult {
                name: "exact".to_string(),
                description: "least squares, exact inverses".to_string(),
                ihc: Some(indices(1.11, 1.22, 0.33)),
                wihc: Some(indices(1.12, 1.23, 0.34)),
                dihc: Some(indices(1.13, 1.24, 0.35)),
                forward_model: Some(model("V", "µm")),
                inverse_model: Some(model("µm", "V")),
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
            AcceptanceBound {
                pipeline: Some("paper".to_string()),
                compensator: Some(Compensator::Dihc),
                index: IndexName::ERms,
                min_percent: None,
                max_percent: Some(0.75),
                source: "the paper's e_rms".to_string(),
                informational: false,
            },
            AcceptanceBound {
                pipeline: None,
                compensator: None,
                index: IndexName::EMhe,
                min_percent: Some(10.0),
                max_percent: Some(16.0),
                source: "near the paper's 13 %".to_string(),
                informational: false,
            },
        ],
        figures: vec![],
        sections: vec![TextSection::new(
            "Why <b>pipelines</b> differ",
            vec!["<script>alert('x')</script> & more".to_string()],
        )],
        stage_config_toml: "[amplifier]\ngain = 15.0 # <V/V>\n".to_string(),
    }
}

fn html() -> String {
    let dir = tempfile::tempdir().unwrap();
    render_html(dir.path(), &data()).unwrap()
}

/// The text of the Table 3 element.
fn table3_of(html: &str) -> &str {
    let start = html
        .find("<table class=\"results\"")
        .expect("Table 3 is there");
    let end = start + html[start..].find("</table>").unwrap();
    &html[start..end]
}

#[test]
fn table3_holds_the_papers_numbers_beside_ours() {
    let html = html();
    let t = table3_of(&html);
    for printed in [
        ">13<", ">3<", ">2.5<", ">2.66<", ">2.87<", ">2.06<", ">0.75<", ">0.76<", ">0.78<",
    ] {
        assert!(t.contains(printed), "paper number {printed} missing");
    }
    for ours in [
        "data-pipeline=\"paper\" data-compensator=\"wihc\" data-index=\"e_m\">2.95<",
        "data-pipeline=\"exact\" data-compensator=\"dihc\" data-index=\"e_rms\"",
        "data-pipeline=\"uncompensated\" data-compensator=\"none\" data-index=\"e_mhe\"",
    ] {
        assert!(t.contains(ours), "{ours} missing");
    }
    assert!(t.contains(">12.34<"));
    assert!(t.contains(">1.13<"));
    // The paper pipeline's DIHC did not run.
    assert!(t.contains("data-compensator=\"dihc\" data-index=\"e_mhe\">not run<"));
    // Column headers name both pipelines under every compensator.
    assert_eq!(t.matches("<code>paper</code>").count(), 3);
    assert_eq!(t.matches("<code>exact</code>").count(), 3);
    assert!(html.contains("over 100 equal bins"));
}

#[test]
fn misses_are_marked_in_the_table_and_in_words() {
    let html = html();
    let t = table3_of(&html);
    // paper IHC e_mhe 3.21 > 3: a miss; exact e_mhe all <= 3: passes.
    assert!(t.contains(
        "class=\"ours miss\" data-pipeline=\"paper\" data-compensator=\"ihc\" data-index=\"e_mhe\""
    ));
    assert!(t.contains(
        "class=\"ours pass\" data-pipeline=\"exact\" data-compensator=\"wihc\" data-index=\"e_mhe\""
    ));
    // Unbounded numbers are neither.
    assert!(t.contains(
        "class=\"ours\" data-pipeline=\"paper\" data-compensator=\"wihc\" data-index=\"e_mhe\""
    ));
    // DIHC of the paper pipeline did not run: its bound is missed.
    assert!(t.contains(
        "class=\"ours miss\" data-pipeline=\"paper\" data-compensator=\"dihc\" data-index=\"e_rms\""
    ));
    assert!(html.contains("2 of 6 checks against acceptance bounds miss"));
    assert!(html.contains(
        "✗ <code>paper</code> pipeline, IHC: e_mhe = 3.21 % misses the bound e_mhe ≤ 3 %"
    ));
    assert!(
        html.contains("✓ uncompensated run: e_mhe = 12.34 % meets the bound 10 % ≤ e_mhe ≤ 16 %")
    );
}

#[test]
fn every_caller_string_is_escaped() {
    let html = html();
    assert!(!html.contains("<script>"));
    // The engine escapes & < > " ' (and /): whatever its entities, no markup survives.
    assert!(html.contains("&lt;script&gt;alert(&#x27;x&#x27;)&lt;&#x2f;script&gt; &amp; more"));
    assert!(html.contains("<title>Study &lt;one&gt;</title>"));
    assert!(html.contains("Why &lt;b&gt;pipelines&lt;&#x2f;b&gt; differ"));
    assert!(html.contains("gain = 15.0 # &lt;V&#x2f;V&gt;"));
    assert!(html.contains("delayed IHC &amp; WIHC"));
    assert!(html.contains("Study &lt;one&gt;</h1>"));
}

#[test]
fn parameters_are_laid_out_like_tables_1_and_2() {
    let html = html();
    let start = html.find("id=\"table1\"").unwrap();
    let t1 = &html[start..start + html[start..].find("</table>").unwrap()];
    // Row 1: paper r=0, b=0.2313, a1=-0.1569; ours r=0, b=0.25, a1=-0.15.
    assert!(t1.contains(
        "<tr><th scope=\"row\">1</th><td class=\"paper\">0</td><td class=\"paper\">0.2313</td><td class=\"paper\">-0.1569</td><td class=\"ours\">0</td><td class=\"ours\">0.25</td><td class=\"ours\">-0.15</td>"
    ));
    // Row 3 has no a_i.
    assert!(t1.contains("<tr><th scope=\"row\">3</th><td class=\"paper\">0.2</td><td class=\"paper\">0.0155</td><td class=\"paper\"></td>"));
    assert!(t1.contains("input 1 = 120 V<br>output 1 = 69.3 µm"));
    let start = html.find("id=\"table2\"").unwrap();
    let t2 = &html[start..start + html[start..].find("</table>").unwrap()];
    // Only the exact pipeline has a DIHC model.
    assert!(t2.contains("<code>exact</code>") && !t2.contains("<code>paper</code>"));
    assert!(t2.contains(">-0.47999<") && t2.contains(">-0.00002<"));
    assert!(html.contains("DIHC model refused: not invertible"));
}

#[test]
fn parameters_are_printed_with_trimmed_decimals() {
    assert_eq!(param(0.1), "0.1");
    assert_eq!(param(-0.00002), "-0.00002");
    assert_eq!(param(0.000001), "0");
    assert_eq!(param(-0.000001), "0");
    assert_eq!(param(1.25886), "1.25886");
    assert_eq!(param(f64::NAN), "not finite");
    assert_eq!(pct(2.666), "2.67");
}

#[test]
fn bad_data_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut d = data();
    d.pipelines[1].name = "paper".to_string();
    assert!(matches!(
        render_html(dir.path(), &d),
        Err(ReportError::BadPipelineName(_))
    ));
    let mut d = data();
    d.acceptance[0].pipeline = Some("nope".to_string());
    assert!(matches!(
        render_html(dir.path(), &d),
        Err(ReportError::UnknownPipeline(_))
    ));
    let mut d = data();
    d.acceptance[0].max_percent = None;
    assert!(matches!(
        render_html(dir.path(), &d),
        Err(ReportError::BadBound(_))
    ));
    let mut d = data();
    d.acceptance[0].max_percent = Some(f64::NAN);
    assert!(matches!(
        render_html(dir.path(), &d),
        Err(ReportError::BadBound(_))
    ));
    let figure = |png: &str| FigureEntry {
        png_file: png.to_string(),
        svg_file: None,
        paper_figure: "Fig. 7".to_string(),
        caption: "c".to_string(),
    };
    let mut d = data();
    d.figures = vec![figure("../x.png")];
    assert!(matches!(
        render_html(dir.path(), &d),
        Err(ReportError::BadFileName(_))
    ));
    d.figures = vec![figure("absent.png")];
    let err = render_html(dir.path(), &d).unwrap_err();
    assert!(matches!(err, ReportError::MissingFigure(_)), "{err}");
    std::fs::write(dir.path().join("fake.png"), "not a png").unwrap();
    d.figures = vec![figure("fake.png")];
    assert!(matches!(
        render_html(dir.path(), &d),
        Err(ReportError::BadFigure { .. })
    ));
    // Nothing was written.
    assert!(!dir.path().join("index.html").exists());
}

#[test]
fn report_data_round_trips_through_json() {
    let d = data();
    let json = serde_json::to_string(&d).unwrap();
    assert!(json.contains("\"index\":\"e_mhe\"") && json.contains("\"compensator\":\"ihc\""));
    let back: ReportData = serde_json::from_str(&json).unwrap();
    assert_eq!(back, d);
}

#[test]
fn the_report_is_written_atomically_and_replaces_an_old_one() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("index.html"), "old").unwrap();
    let path = write_report(dir.path(), &data()).unwrap();
    assert_eq!(path, dir.path().join("index.html"));
    let written = std::fs::read_to_string(&path).unwrap();
    assert!(written.starts_with("<!DOCTYPE html>") && written.trim_end().ends_with("</html>"));
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        vec!["index.html".to_string()],
        "temporary files left behind"
    );
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&path).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o644);
    }
    // A directory that cannot be created gives an error, not a panic.
    let blocked = dir.path().join("index.html").join("sub");
    assert!(matches!(
        write_report(&blocked, &data()),
        Err(ReportError::Io { .. })
    ));
}

#[test]
fn the_page_needs_nothing_from_outside() {
    let html = html();
    for outside in ["<script", "<link", "http://", "https://", "@import", "url("] {
        assert!(!html.contains(outside), "{outside} found");
    }
}

fn study_section() -> TextSection {
    TextSection {
        id: "duration-study".to_string(),
        tables: vec![Table {
            id: "duration-table".to_string(),
            caption: "Error <against> duration".to_string(),
            columns: vec!["duration".into(), "e_rms (%)".into()],
            rows: vec![
                TableRow::new("20 s", vec!["0.33".into()]),
                TableRow::new("200 s", vec!["0.92 & more".into()]),
            ],
            note: "µm and % throughout".to_string(),
        }],
        ..TextSection::new("A study", vec!["Measured.".to_string()])
    }
}

#[test]
fn a_study_section_shows_its_tables_escaped_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let mut d = data();
    d.sections.push(study_section());
    let html = render_html(dir.path(), &d).unwrap();
    let start = html
        .find("<section class=\"text\" id=\"duration-study\">")
        .unwrap();
    let section = &html[start..start + html[start..].find("</section>").unwrap()];
    assert!(
        section.contains("<h2>A study</h2>\n<p>Measured.</p>"),
        "{section}"
    );
    assert!(section.contains("<h3>Error &lt;against&gt; duration</h3>"));
    assert!(section.contains("<table class=\"data\" id=\"duration-table\">"));
    assert!(section.contains("<tr><th>duration</th><th>e_rms (%)</th></tr>"));
    assert!(section.contains("<tr><th scope=\"row\">200 s</th><td>0.92 &amp; more</td></tr>"));
    assert!(section.contains("µm and % throughout"));
    // After Table 3, before the figures and parameters.
    assert!(html.find("id=\"table3\"").unwrap() < start);
    assert!(start < html.find("id=\"parameters\"").unwrap());
}

#[test]
fn a_bad_study_section_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let refused = |section: TextSection| {
        let mut d = data();
        d.sections.push(section);
        let err = render_html(dir.path(), &d).unwrap_err();
        assert!(matches!(err, ReportError::BadSection(_)), "{err}");
        err.to_string()
    };
    let mut s = study_section();
    s.tables[0].rows[0].cells.push("extra".into());
    assert!(refused(s).contains("has 2 cells for 1 columns"));
    let mut s = study_section();
    s.id = "a b".into();
    assert!(refused(s).contains("id"));
    let mut s = study_section();
    s.template = Some("no-such-study".into());
    assert!(refused(s).contains("templates/studies"));
}
