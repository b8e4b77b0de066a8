//! The comparative study on the default stage: the acceptance bounds of the issue, determinism,
//! measured explanations, every output written, and the real report rendered in Chromium.

mod common;

use common::*;
use hystcomp_experiments::study::Silent;
use hystcomp_experiments::{RunMeta, StudyOptions, run_study, summarize, write_outputs};
use hystcomp_io::model_file::ModelFile;

fn meta() -> RunMeta {
    RunMeta {
        generated_at: "2026-11-22T00:00:00Z".into(),
        git_description: None,
        command_line: Some("cargo test --test study".into()),
    }
}

#[test]
fn default_study_meets_the_acceptance_bounds_and_writes_a_report_chromium_shows() {
    let study = run_study(&StudyOptions::default(), &mut Silent).unwrap();
    let summary = summarize(&study);
    // Acceptance on the default stage: the exact pipeline cuts e_mhe from about 13 % to <= 3 %
    // with e_rms <= 0.75 %.
    let exact = study.pipeline("exact").unwrap();
    for run in &exact.runs {
        assert!(
            run.indices.e_mhe_percent <= 3.0,
            "{}: {:?}",
            run.label,
            run.indices
        );
        assert!(
            run.indices.e_rms_percent <= 0.75,
            "{}: {:?}",
            run.label,
            run.indices
        );
        assert_eq!(run.saturated, 0, "{}", run.label);
    }
    let un = study.uncompensated.indices.e_mhe_percent;
    assert!((11.5..=14.5).contains(&un), "uncompensated e_mhe {un}");
    for check in &summary.acceptance {
        assert!(check.passed, "{check:?}");
    }
    // Both pipelines ran every approach, and compensation helps in each.
    for pipeline in &study.pipelines {
        assert_eq!(pipeline.runs.len(), 3);
        for run in &pipeline.runs {
            assert!(run.indices.e_rms_percent < study.uncompensated.indices.e_rms_percent);
        }
    }
    // Least squares is the global optimum of the same problem the swarm solves.
    let paper = study.pipeline("paper").unwrap();
    assert!(exact.plant.report.fit.rms_percent <= paper.plant.report.fit.rms_percent + 1e-9);
    assert!(exact.inverse.report.fit.rms_percent <= paper.inverse.report.fit.rms_percent + 1e-9);

    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let files = write_outputs(&study, &out, &meta(), &mut Silent).unwrap();
    assert_eq!(files.figures.len(), 2 * 13);
    for f in &files.figures {
        assert!(
            std::fs::metadata(f).unwrap().len() > 1000,
            "{}",
            f.display()
        );
    }
    for m in &files.models {
        let model = ModelFile::load(m).unwrap();
        model.model().unwrap().check_invertible(0.0, 1.0).unwrap();
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files.summary).unwrap()).unwrap();
    assert_eq!(json["pipelines"].as_array().unwrap().len(), 2);
    let html = std::fs::read_to_string(&files.report).unwrap();
    // The explanations quote the measured numbers.
    let exact_ihc = format!("{:.3} %", exact.runs[0].indices.e_rms_percent);
    assert!(
        html.contains(&exact_ihc),
        "the report should quote {exact_ihc}"
    );

    let Some(browser) = chromium() else {
        return;
    };
    let page = files.report.canonicalize().unwrap();
    let dom_file = out.join("dom.html");
    run_chromium(&browser, &["--dump-dom".to_string()], &page, &dom_file);
    let dom = std::fs::read_to_string(&dom_file).unwrap();
    let start = dom
        .find("id=\"table3-table\"")
        .expect("Table 3 in the rendered DOM");
    let table = &dom[start..start + dom[start..].find("</table>").unwrap()];
    for run in exact.runs.iter().chain(&paper.runs) {
        let number = format!("{:.2}", run.indices.e_rms_percent);
        assert!(
            table.contains(&number),
            "Table 3 lacks {number} ({})",
            run.label
        );
    }
    let shot = out.join("screenshot.png");
    run_chromium(
        &browser,
        &[format!("--screenshot={}", shot.display())],
        &page,
        &out.join("shot.out"),
    );
    let (w, h, pixels) = decode_png(&shot);
    assert_shows_table(w, h, &pixels);
}

#[test]
fn the_study_is_deterministic_per_seed() {
    let quick = |seed: u64| {
        let mut options = StudyOptions {
            seed,
            pso_seed: seed,
            ..StudyOptions::default()
        };
        options.pso.iterations = 20;
        summarize(&run_study(&options, &mut Silent).unwrap())
    };
    let a = quick(5);
    let b = quick(5);
    let c = quick(6);
    let numbers = |s: &hystcomp_experiments::StudySummary| -> Vec<f64> {
        s.pipelines
            .iter()
            .flat_map(|p| p.runs.iter())
            .chain(&s.cross_runs)
            .map(|r| r.indices.e_rms_percent)
            .chain([s.uncompensated.e_mhe_percent])
            .collect()
    };
    assert_eq!(numbers(&a), numbers(&b));
    assert_ne!(numbers(&a), numbers(&c));
}

#[test]
fn bad_options_are_refused_with_the_reason() {
    let err = |options: StudyOptions| run_study(&options, &mut Silent).unwrap_err().to_string();
    assert!(
        err(StudyOptions {
            periods: 1,
            ..StudyOptions::default()
        })
        .contains("at least 2 periods")
    );
    assert!(
        err(StudyOptions {
            decimation: 0,
            ..StudyOptions::default()
        })
        .contains("decimation")
    );
    let mut options = StudyOptions::default();
    options.stage.mechanics.damping_ratio = -0.1;
    assert!(err(options).contains("damping_ratio"));
    assert!(
        err(StudyOptions {
            operators: 0,
            ..StudyOptions::default()
        })
        .contains("operators")
    );
}
