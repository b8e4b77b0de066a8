//! Issue 12's learning study on the default stage, from the study's own run (called by the
//! default study's test in `study.rs`, so that the study runs once): every series ran its
//! trials, the paper's trajectory from the exact pipeline meets the figure, and the
//! misses are the measured ones (the report and `--json` state them).

use hystcomp_experiments::learning_study::{
    PAPER, PAPER_TRIALS, RASTER, RASTER_TRIALS, learning_checks,
};
use hystcomp_experiments::study::Study;
use hystcomp_experiments::study_report::StudySummary;

pub fn the_learning_study_measures_what_it_claims(study: &Study, summary: &StudySummary) {
    let learning = &study.learning;
    assert_eq!(learning.series.len(), 4);
    for s in &learning.series {
        let full_length = if s.trajectory == PAPER {
            PAPER_TRIALS
        } else {
            RASTER_TRIALS
        };
        // A series ends early only when the divergence guard stopped it.
        assert_eq!(
            s.trials.len() == full_length,
            !s.stopped,
            "{}: {} trials, stopped {}",
            s.label(),
            s.trials.len(),
            s.stopped
        );
        for (k, p) in s.trials.iter().enumerate() {
            assert_eq!(p.trial, k);
            assert!(p.noise_floor_percent > 0.0 && p.indices.e_rms_percent > 0.0);
            assert!((0.0..=1.0).contains(&p.limited_share));
        }
        // Learning helps: the best trial beats the compensator's own drive.
        let best = s.best_within(s.trials.len()).unwrap();
        assert!(
            best.indices.e_rms_percent < 0.5 * s.trials[0].indices.e_rms_percent,
            "{}",
            s.label()
        );
    }
    // Trial 0 of the paper's trajectory from the exact pipeline is its IHC (in the periodic
    // state rather than from rest): within 10 % of the study's exact / ihc run.
    let exact = learning.series(PAPER, "exact / ihc").unwrap();
    let study_ihc = study.pipeline("exact").unwrap().runs[0]
        .indices
        .e_rms_percent;
    let trial0 = exact.trials[0].indices.e_rms_percent;
    assert!(
        (trial0 - study_ihc).abs() <= 0.1 * study_ihc,
        "{trial0} vs {study_ihc}"
    );
    // Issue 12's figure on the paper's trajectory from the exact pipeline: met, and the last
    // trial sits on the noise floor.
    assert!(exact.first_meeting(10, 0.03, 0.3).is_some(), "{exact:?}");
    let last = exact.trials.last().unwrap();
    assert!(last.indices.e_rms_percent < 1.5 * last.noise_floor_percent);
    // The raster from the exact pipeline: Q's default cut-off (a hundredth of the sample
    // rate, 100 Hz) keeps the learning below the triangle's harmonics; it improves about 2.7
    // times and stays there (measured 4.29 -> 1.58 %), missing the 0.1 %.
    let raster = learning.series(RASTER, "exact / ihc").unwrap();
    assert!(!raster.stopped);
    let e_last = raster.trials.last().unwrap().indices.e_rms_percent;
    assert!((1.0..2.2).contains(&e_last), "{e_last}");
    // Issue 12's raster figure from the full pipeline (its vibration link lets Q reach the
    // triangle's harmonics): e_rms <= 0.1 % within 20 trials (measured 0.080 %, met at trial
    // 6). Its faithful drive asks more than the amplifier's slew at the corners, so the series
    // starts from the slew-constrained drive (StudyOptions::feasible_learning_start): trial 0
    // has no sample at the amplifier's limits and tracks as the speed study's 100 Hz raster
    // (measured 0.419 %; 2.9-3.1 % from the faithful drive, best of 20 then 0.135 %).
    let full_raster = learning.series(RASTER, "full / ihc").unwrap();
    let best = full_raster.best_within(20).unwrap();
    assert!(best.indices.e_rms_percent <= 0.1, "{full_raster:?}");
    for s in &learning.series {
        assert_eq!(
            s.slew_constrained_start,
            s.trajectory == RASTER && s.start == "full / ihc",
            "{}",
            s.label()
        );
    }
    let start = &full_raster.trials[0];
    assert_eq!(start.limited_share, 0.0, "{start:?}");
    assert!(start.indices.e_rms_percent < 0.6, "{start:?}");
    // The paper's trajectory from the full pipeline meets the figure too.
    let full_paper = learning.series(PAPER, "full / ihc").unwrap();
    assert!(
        full_paper.first_meeting(10, 0.03, 0.3).is_some(),
        "{full_paper:?}"
    );
    // The checks are the summary's and the study's, one per series.
    assert_eq!(summary.learning.checks.len(), 4);
    assert_eq!(
        learning_checks(&learning.series).len(),
        learning.checks.len()
    );
    assert!(
        summary.learning.checks[0].passed,
        "{:?}",
        summary.learning.checks[0]
    );
    let text = summary.to_string();
    assert!(text.contains("issue 12 targets"), "{text}");
}
