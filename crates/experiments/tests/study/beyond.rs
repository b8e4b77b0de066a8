//! Issue 11 on the default stage, from the study's own run (called by the default study's
//! test in `study.rs`, so that the study runs once): the `full` pipeline, the duration and
//! speed studies, and the figures against the bounds where they are met, against the
//! measured values (with room for the noise) where they are not. The report and `--json`
//! state each miss; these assertions keep the measured numbers honest.

use hystcomp_experiments::study::Study;
use hystcomp_experiments::study_report::StudySummary;

fn close_to(value: f64, measured: f64, tolerance: f64, what: &str) {
    assert!(
        (value - measured).abs() <= tolerance,
        "{what}: {value} (measured when written: {measured} +- {tolerance})"
    );
}

pub fn the_full_pipeline_and_the_duration_and_speed_studies_measure_what_they_claim(
    study: &Study,
    summary: &StudySummary,
) {
    let exact = study.pipeline("exact").unwrap();
    let full = &study.full;
    assert_eq!(full.runs.len(), 3);
    // The chain: creep and vibration identified, each helping the fit where it should.
    let plant = &full.plant.report;
    let rms: Vec<f64> = plant.contributions.iter().map(|c| c.rms_percent).collect();
    assert_eq!(rms.len(), 3, "{:?}", plant.contributions);
    assert!(rms[1] < 0.5 * rms[0], "creep: {rms:?}");
    let segment: Vec<f64> = plant
        .contributions
        .iter()
        .map(|c| c.segment_rms_percent.unwrap())
        .collect();
    // On the vibration segment the vibration link removes two thirds of the error (measured
    // 0.470 -> 0.152 %; 0.458 -> 0.108 % before the creep weights were smoothed, when the
    // 10 ms creep element sat at its floor).
    assert!(segment[2] < 0.4 * segment[1], "vibration: {segment:?}");
    let dynamics = plant.dynamics.as_ref().unwrap();
    assert!(
        dynamics
            .modes
            .iter()
            .any(|m| (m.frequency_hz - 800.0).abs() < 20.0),
        "the stage's 800 Hz resonance: {:?}",
        dynamics.modes
    );
    // The creep bank: ending at 1000 s, chosen among 100, 1000 and 10 000 s by the
    // leave-one-hold-out error (measured 0.0289, 0.0069 and 0.0069 %: the 100 s bank cannot
    // follow the holds; the sensor noise alone is 0.007 % of the range).
    let grid = &full.creep_grid;
    assert_eq!(grid.len(), 3, "{grid:?}");
    let best = grid.iter().map(|g| g.1).fold(f64::INFINITY, f64::min);
    assert_eq!(
        grid.iter().find(|g| g.1 == best).unwrap().0,
        1000.0,
        "{grid:?}"
    );
    assert!(grid[0].1 > 3.0 * best, "{grid:?}");
    // The weights fitted on the record's holds, the smoothness chosen by leaving each hold
    // out among the candidates (every one scored), none at its floor.
    let creep = plant.creep.as_ref().unwrap();
    let weights = &creep.part.weights;
    assert_eq!(weights.len(), 11, "{weights:?}");
    let largest = weights.iter().copied().fold(0.0, f64::max);
    assert!(weights.iter().all(|w| *w > 0.5 * largest), "{weights:?}");
    assert_eq!(
        creep.smoothness_candidates.len(),
        hystcomp_experiments::full::HOLD_SMOOTHNESS_CANDIDATES.len()
    );
    assert!(
        plant.hysteresis.detail.contains("on 3 holds"),
        "{}",
        plant.hysteresis.detail
    );
    // 20 s: every approach within the 0.25 % target. Measured 0.063 % (IHC, WIHC) and 0.088 %
    // (DIHC) with 12 operators at p = 1.75 (full::OPERATORS, full::THRESHOLD_EXPONENT); 0.084
    // and 0.188 % with ten uniform ones; with the output map of degree 3
    // (full::OUTPUT_MAP_DEGREE); 0.275 and 0.444 %
    // with the MPIM alone, whose mismatch with the stage's asymmetric loops left 0.255-0.29 %
    // even on a creep-, dynamics- and noise-free copy of the stage (examples/full_diag.rs).
    let full_ihc = full.runs[0].indices.e_rms_percent;
    assert!(full_ihc < exact.runs[0].indices.e_rms_percent);
    for run in &full.runs {
        assert!(run.indices.e_rms_percent <= 0.25, "{}", run.label);
    }
    close_to(full_ihc, 0.063, 0.02, "full / ihc e_rms over 20 s");
    close_to(
        full.runs[2].indices.e_rms_percent,
        0.088,
        0.03,
        "full / dihc e_rms over 20 s",
    );
    // 200 s: the exact IHC drifts away, the full one holds (issue 11: <= 0.30 %).
    let series = |label: &str| {
        study
            .duration
            .series
            .iter()
            .find(|s| s.label == label)
            .unwrap_or_else(|| panic!("no duration series {label}"))
    };
    let long = |label: &str| series(label).at(200.0).unwrap().e_rms_percent;
    assert!(long("exact / ihc") > 0.7, "{}", long("exact / ihc"));
    assert!(long("full / ihc") <= 0.30, "{}", long("full / ihc"));
    assert!(long("full / wihc") <= 0.30, "{}", long("full / wihc"));
    assert!(long("full / dihc") <= 0.30, "{}", long("full / dihc"));
    assert_eq!(series("full / ihc").indices.len(), 20);
    // The held step: with the creep fitted on the record's holds, the drift is within the
    // target (0.1 um; measured 0.011 um IHC and 0.020 um DIHC with 12 operators at p = 1.75,
    // 0.040 / 0.084 um with ten uniform ones, 0.023 um both without the output map; 0.179 /
    // 0.135 um with the creep fitted jointly).
    let hold = |label: &str| {
        study
            .duration
            .hold
            .iter()
            .find(|h| h.label == label)
            .unwrap()
            .drift_um
    };
    assert!(hold("exact / ihc") > 1.0, "{}", hold("exact / ihc"));
    assert!(hold("full / ihc") < 0.3 * hold("exact / ihc"));
    assert!(hold("full / ihc") <= 0.1, "{}", hold("full / ihc"));
    assert!(hold("full / wihc") <= 0.1, "{}", hold("full / wihc"));
    assert!(hold("full / dihc") <= 0.1, "{}", hold("full / dihc"));
    close_to(hold("full / ihc"), 0.011, 0.03, "full / ihc drift");
    close_to(hold("full / dihc"), 0.020, 0.016, "full / dihc drift");
    // Speed: the paper's trajectory at 10x (issue 11: <= 0.35 %), better than exact's.
    let paper10 = study
        .speed
        .paper
        .iter()
        .find(|p| p.rate_hz == 10.0)
        .unwrap();
    assert_eq!(paper10.amplitude_scale, 1.0);
    let at10 = paper10.run("full / ihc").unwrap().indices.e_rms_percent;
    assert!(at10 <= 0.35, "{at10}");
    assert!(at10 < paper10.run("exact / ihc").unwrap().indices.e_rms_percent);
    // The fastest trajectories are scaled down to what the amplifier can slew.
    let fastest = study.speed.paper.last().unwrap();
    assert!(fastest.amplitude_scale < 0.5, "{}", fastest.amplitude_scale);
    // The 100 Hz raster: full better than exact; within the 0.5 % target on the built-in
    // amplifier (slew-constrained drive), short of it with ten times the slew (faithful drive).
    let raster = |points: &[hystcomp_experiments::speed::SpeedPoint], label: &str| {
        points
            .iter()
            .find(|p| p.rate_hz == 100.0)
            .unwrap()
            .run(label)
            .unwrap()
            .indices
            .e_rms_percent
    };
    let r_full = raster(&study.speed.raster_strong_amplifier, "full / ihc");
    assert!(r_full < 0.5 * raster(&study.speed.raster_strong_amplifier, "exact / ihc"));
    // Measured 0.555 % (strong amplifier) with 12 operators at p = 1.75; 0.854 % with ten
    // uniform ones, 0.766 % without the output map.
    close_to(
        r_full,
        0.555,
        0.1,
        "full raster at 100 Hz, strong amplifier",
    );
    // On the built-in amplifier the faithful drive asks three times its slew rate at the
    // corners: the slew-constrained drive keeps within it and meets issue 11's 0.5 % (measured
    // 0.444 %; 0.774 % with ten uniform operators, where it tracked as the 10x-slew amplifier's
    // faithful drive did).
    let built_in = raster(&study.speed.raster, "full / ihc");
    assert!(built_in <= 0.5, "{built_in}");
    close_to(
        built_in,
        0.444,
        0.05,
        "full raster at 100 Hz, built-in amplifier",
    );
    assert!(built_in < r_full + 0.05, "{built_in} vs {r_full}");
    let run_at = |points: &[hystcomp_experiments::speed::SpeedPoint], label: &str| {
        points
            .iter()
            .find(|p| p.rate_hz == 100.0)
            .unwrap()
            .run(label)
            .unwrap()
            .clone()
    };
    let constrained = run_at(&study.speed.raster, "full / ihc");
    assert!(constrained.slew_constrained && constrained.limited_share == 0.0);
    assert!(!run_at(&study.speed.raster_strong_amplifier, "full / ihc").slew_constrained);
    assert!(!run_at(&study.speed.raster, "exact / ihc").slew_constrained);
    // Every figure of the issue is in the summary, met or not.
    let checks = &summary.beyond.checks;
    // 20 s, 200 s and the hold for IHC, WIHC and DIHC, two rasters, the paper's at 10x.
    assert_eq!(checks.len(), 12, "{checks:?}");
    assert_eq!(checks.iter().filter(|c| c.passed).count(), 11, "{checks:?}");
    // The exact WIHC solves IHC's equation: the same long-run figures.
    let value = |what: &str| checks.iter().find(|c| c.what == what).unwrap().value;
    for what in [
        "e_rms over 200 s (last period)",
        "drift over a 60 s hold after a 50 um step",
    ] {
        let (ihc, wihc) = (
            value(&format!("full / ihc: {what}")),
            value(&format!("full / wihc: {what}")),
        );
        assert!(
            (ihc - wihc).abs() <= 1e-9 * ihc.abs().max(1.0),
            "{what}: {ihc} {wihc}"
        );
    }
}
