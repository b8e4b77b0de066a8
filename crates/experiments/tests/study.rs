//! The comparative study on the default stage: the acceptance bounds of the issue, determinism,
//! measured explanations, every output written, and the real report rendered in Chromium.

mod common;

use common::*;
use hystcomp_experiments::study::Silent;
use hystcomp_experiments::{RunMeta, StudyOptions, run_study, summarize, write_outputs};

#[path = "study/beyond.rs"]
mod beyond;
#[path = "study/learning.rs"]
mod learning;
use hystcomp_io::model_file::ModelFile;

/// The HTML of the table with the given id.
fn table_of<'a>(html: &'a str, id: &str) -> &'a str {
    let start = html
        .find(&format!("id=\"{id}\""))
        .unwrap_or_else(|| panic!("no table {id}"));
    &html[start..start + html[start..].find("</table>").unwrap()]
}

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
    beyond::the_full_pipeline_and_the_duration_and_speed_studies_measure_what_they_claim(
        &study, &summary,
    );
    learning::the_learning_study_measures_what_it_claims(&study, &summary);
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
    // Fifteen figures of the paper's study, six beyond it (the full pipeline, the duration
    // and speed studies) and two of the learning study, each a PNG and an SVG.
    assert_eq!(files.figures.len(), 2 * (15 + 6 + 2));
    // Every figure of a pipeline names it in its title; fig. 12 has a readable twin.
    for pipeline in ["exact", "paper"] {
        for stem in [
            format!("fig08_{pipeline}_ihc"),
            format!("fig11_{pipeline}_errors"),
            format!("fig12_{pipeline}_hysteresis"),
            format!("fig12_{pipeline}_hysteresis_error"),
        ] {
            let svg = std::fs::read_to_string(out.join(format!("{stem}.svg"))).unwrap();
            assert!(svg.contains(&format!("{pipeline} pipeline")), "{stem}");
        }
    }
    let fig11 = std::fs::read_to_string(out.join("fig11_exact_errors.svg")).unwrap();
    assert!(
        fig11.contains("IHC = WIHC") || fig11.contains("IHC and WIHC differ by at most"),
        "fig. 11 must not hide IHC under WIHC silently"
    );
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
    // The text as a reader sees it: the template engine writes ' and / as entities.
    let html = std::fs::read_to_string(&files.report)
        .unwrap()
        .replace("&#x2f;", "/")
        .replace("&#x27;", "'");
    // The explanations quote the measured numbers.
    let exact_ihc = format!("{:.3} %", exact.runs[0].indices.e_rms_percent);
    assert!(
        html.contains(&exact_ihc),
        "the report should quote {exact_ihc}"
    );
    // The noise floor comes from runs with other noise seeds: they differ, but little.
    let floor = &study.noise_floor;
    assert_eq!(floor.seeds.len(), 5);
    assert_eq!(floor.exact_ihc.len(), 5);
    assert_eq!(floor.exact_ihc[0], exact.runs[0].indices);
    assert!(floor.e_rms_spread_percent > 0.0 && floor.e_rms_spread_percent < 0.01);
    assert!(floor.e_mhe_spread_percent > 0.0 && floor.e_mhe_spread_percent < 0.2);
    assert!(html.contains(&format!("{:.4} points", floor.e_rms_spread_percent)));
    // The count of stage runs the periods' cap speaks of is the study's own: the tracking
    // runs, two replays per extra noise seed, the ablations beyond the baseline.
    assert_eq!(
        hystcomp_experiments::study::TRACKING_RUNS,
        1 + study.pipelines.iter().map(|p| p.runs.len()).sum::<usize>()
            + study.full.runs.len()
            + study.cross_runs.len()
            + 2 * (floor.seeds.len() - 1)
            + study.ablations.len()
            - 1
    );
    // The ablations come from runs: switching creep off changes the result (creep is
    // configured), switching everything off leaves less error than the baseline, and each
    // row's numbers are in the report and in study.json.
    let ablation = |label: &str| {
        study
            .ablations
            .iter()
            .find(|a| a.label == label)
            .unwrap_or_else(|| panic!("no ablation {label}"))
    };
    let base = ablation("baseline");
    assert_eq!(base.ihc, exact.runs[0].indices);
    let creep_off = ablation("creep off");
    assert!(creep_off.changed);
    assert_ne!(creep_off.ihc, base.ihc);
    assert!(creep_off.plant_fit_rms_percent < base.plant_fit_rms_percent);
    let all_off = ablation("creep, noise and dynamics off");
    assert!(all_off.ihc.e_rms_percent < base.ihc.e_rms_percent);
    assert!(ablation("sensor noise off").changed && ablation("dynamics off").changed);
    // The ablation is a table, a row per stage with its numbers.
    let ablation_table = table_of(&html, "ablation");
    for a in &study.ablations {
        let row = format!("<tr><th scope=\"row\">{}", a.label);
        assert!(
            ablation_table.contains(&row),
            "the report lacks the ablation row {row}"
        );
        assert!(
            ablation_table.contains(&format!("<td>{:.3}</td>", a.ihc.e_rms_percent)),
            "{}",
            a.label
        );
    }
    // So is the comparison of the pipelines: both families, the four e_rms of each.
    let comparison = table_of(&html, "pipeline-comparison");
    for family in ["IHC", "WIHC"] {
        assert!(comparison.contains(&format!("<th scope=\"row\">{family}</th>")));
    }
    assert!(comparison.contains(&format!(
        "<td>{:.3}</td>",
        exact.runs[0].indices.e_rms_percent
    )));
    assert!(comparison.contains("(`paper` pipeline)") && comparison.contains("(`exact` pipeline)"));
    // The uncompensated number is said to match by calibration; µm, never "um".
    assert!(html.contains("because the built-in stage is calibrated to it"));
    // (The stage file's TOML, shown verbatim, keeps its own key names.)
    let prose = &html[..html.find("<pre class=\"config\">").unwrap()];
    for um in [" um ", " um)", " um.", " um,", "V/um"] {
        assert!(!prose.contains(um), "µm everywhere, not {um:?}");
    }
    // Figures carry the paper's numbers; the others are supplementary.
    assert!(html.contains("<b>Fig. 7</b>") && html.contains("<b>Fig. S1</b>"));
    assert!(html.contains("<b>Fig. 8 (a)-(c)</b>") && html.contains("<b>Fig. 12, redrawn</b>"));
    // One colour per approach in every figure and pipeline (from the SVG files).
    use hystcomp_experiments::figures::SeriesStyle;
    let svg = |stem: &str| std::fs::read_to_string(out.join(format!("{stem}.svg"))).unwrap();
    let colours = [
        ("ihc", SeriesStyle::IHC),
        ("wihc", SeriesStyle::WIHC),
        ("dihc", SeriesStyle::DIHC),
    ];
    for pipeline in ["exact", "paper"] {
        for (k, (family, style)) in colours.iter().enumerate() {
            let own = svg(&format!("fig{:02}_{pipeline}_{family}", 8 + k));
            assert!(
                own.contains(&style.colour.hex()),
                "fig. {} {pipeline}",
                8 + k
            );
            for (other, other_style) in &colours {
                if other != family {
                    assert!(
                        !own.contains(&other_style.colour.hex()),
                        "{family} has {other}'s colour"
                    );
                }
            }
        }
        let errors = svg(&format!("fig11_{pipeline}_errors"));
        assert!(errors.contains(&SeriesStyle::DIHC.colour.hex()));
        assert!(errors.contains(&SeriesStyle::IHC.colour.hex()));
    }
    // Panels (c) of figs. 8-10 share one scale, stated in each and the same everywhere.
    let scale_note = |stem: &str| {
        let text = svg(stem);
        let at = text
            .find("same scale in every fig. 8-10")
            .expect("the shared scale's note");
        text[at..at + text[at..].find('<').unwrap()].to_string()
    };
    let first = scale_note("fig08_exact_ihc");
    for stem in [
        "fig09_exact_wihc",
        "fig10_exact_dihc",
        "fig08_paper_ihc",
        "fig10_paper_dihc",
    ] {
        assert_eq!(scale_note(stem), first, "{stem}");
    }
    // Fig. 12 redrawn: faint raw loops under the envelope, labelled as such.
    let fig12 = svg("fig12_exact_hysteresis_error");
    assert!(fig12.contains("min and max per bin"));
    assert!(fig12.contains("opacity=\"0.3"), "faint raw loops");
    // Every series the figures show is in CSV beside study.json, with units in the names.
    let series = json["series"]
        .as_array()
        .expect("study.json lists the series files");
    let tracking = series
        .iter()
        .find(|s| s["file"] == "series/tracking.csv")
        .expect("tracking.csv");
    let columns: Vec<&str> = tracking["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert_eq!(
        &columns[..3],
        ["time_s", "desired_um", "uncompensated_measured_um"]
    );
    assert!(
        columns.contains(&"exact_ihc_measured_um")
            && columns.contains(&"paper_ihc_delayed_measured_um"),
        "{columns:?}"
    );
    let csv = std::fs::read_to_string(out.join("series/tracking.csv")).unwrap();
    assert_eq!(csv.lines().count(), study.desired_um.len() + 1);
    assert_eq!(csv.lines().next().unwrap(), columns.join(","));
    for name in [
        "identification.csv",
        "pso_convergence.csv",
        "fig12_exact_envelope.csv",
    ] {
        assert!(out.join("series").join(name).is_file(), "{name}");
    }
    assert_eq!(
        json["ablations"].as_array().unwrap().len(),
        study.ablations.len()
    );
    assert_eq!(
        json["ablations"][1]["ihc"]["e_rms_percent"]
            .as_f64()
            .unwrap(),
        creep_off.ihc.e_rms_percent
    );
    // The text names the configured hysteresis model.
    assert!(html.contains("Preisach hysteresis (a smooth"));
    assert!(!html.contains("Bouc-Wen hysteresis"));
    // DIHC's sentence quotes the two fits.
    assert!(html.contains(&format!(
        "{:.3} % of the voltage range against {:.3} % of the position range",
        exact.inverse.report.fit.rms_percent, exact.plant.report.fit.rms_percent
    )));
    // The paper pipeline's checks are shown but not counted; each matches its number.
    assert_eq!(summary.informational.len(), 6);
    let paper_dihc = paper.run("dihc").unwrap().indices.e_mhe_percent;
    let check = summary
        .informational
        .iter()
        .find(|c| c.what == "paper / dihc: e_mhe")
        .unwrap();
    assert_eq!(check.passed, paper_dihc <= 3.0);
    // A miss is said in a sentence of the report.
    if !check.passed {
        assert!(html.contains(&format!("paper / dihc: e_mhe = {paper_dihc:.2} %")));
        assert!(html.contains("misses one"));
    }
    assert!(html.contains("informational"));
    assert!(!html.contains("the paper's (none"));
    assert!(html.contains("no equivalent in the paper"));

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
    let (w, h, pixels) = screenshot(&browser, &page, &out);
    assert_shows_table(w, h, &pixels);
}

/// Records the names of the steps the study announces.
#[derive(Default)]
struct Steps(Vec<String>);

impl hystcomp_experiments::study::StudyObserver for Steps {
    fn begin(&mut self, step: &str, _total: u64) {
        self.0.push(step.to_string());
    }
    fn advance(&mut self, _done: u64) {}
    fn end(&mut self) {}
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
        let mut steps = Steps::default();
        let summary = summarize(&run_study(&options, &mut steps).unwrap());
        // The command line's progress labels are 12 characters wide.
        assert!(steps.0.len() >= 8, "{:?}", steps.0);
        for step in &steps.0 {
            assert!(step.chars().count() <= 12, "step label {step:?} too wide");
        }
        summary
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
            periods: 21,
            ..StudyOptions::default()
        })
        .contains("at most 20 periods")
    );
    assert!(
        err(StudyOptions {
            mhe_bins: 10_001,
            ..StudyOptions::default()
        })
        .contains("use at most 10000 bins")
    );
    // The full pipeline's threshold spacing is checked before any run.
    for p in [0.1, 5.0, f64::NAN] {
        let mut options = StudyOptions::default();
        options.full.threshold_exponent = p;
        let message = err(options);
        assert!(
            message.contains("threshold exponent is 0.25 to 4"),
            "{message}"
        );
    }
    let mut options = StudyOptions::default();
    options.stage.hysteresis.preisach.stroke_um = 30.0;
    let message = err(options);
    assert!(message.contains("cannot reach the trajectory"), "{message}");
    assert!(message.contains("150.0 V at the amplifier"), "{message}");
    // A x5 amplifier from a 10 V DAC tops out at 50 V: the gain or the DAC is what to change.
    let mut options = StudyOptions::default();
    options.stage.amplifier.gain = 5.0;
    let message = err(options);
    assert!(message.contains("50.0 V at the amplifier"), "{message}");
    assert!(message.contains("amplifier.gain or dac.max_v"), "{message}");
    let mut options = StudyOptions::default();
    options.stage.sensor.sensitivity_v_per_um = 0.2;
    assert!(err(options).contains("sensor.sensitivity_v_per_um = 10 / 0.2"));
    assert!(
        err(StudyOptions {
            operators: 0,
            ..StudyOptions::default()
        })
        .contains("operators")
    );
}

#[test]
fn ablations_follow_the_stage_configuration() {
    // A Bouc-Wen stage without creep: "creep off" changes nothing and must reproduce the
    // baseline exactly; the report names Bouc-Wen, not Preisach.
    let mut options = StudyOptions::default();
    options.pso.iterations = 20;
    options.stage.hysteresis.model = hystcomp_stage::HysteresisModel::BoucWen;
    options.stage.creep.percent_per_decade = 0.0;
    let study = run_study(&options, &mut Silent).unwrap();
    let creep_off = &study.ablations[1];
    assert_eq!(creep_off.label, "creep off");
    assert!(!creep_off.changed);
    assert_eq!(creep_off.ihc, study.ablations[0].ihc);
    let sections = hystcomp_experiments::study_report::explanations(&study);
    let text: String = sections
        .iter()
        .flat_map(|s| s.paragraphs.clone())
        .collect::<Vec<_>>()
        .join("\n");
    let ablation = sections
        .iter()
        .flat_map(|s| &s.tables)
        .find(|t| t.id == "ablation")
        .expect("the ablation table");
    assert_eq!(ablation.rows[1].header, "creep off (already so)");
    assert!(
        text.contains("asymmetric Bouc-Wen hysteresis (A = 0.40648"),
        "{text}"
    );
    assert!(!text.contains("Preisach"), "{text}");
}
