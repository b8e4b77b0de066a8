//! Acceptance of issue 10: on records of the built-in stage started mid-range (the study's
//! identification excitation with its first 1, 2 and 5 s left unrecorded) the identified
//! model's held-out RMS is within 10 % of the one from the full record.
//!
//! The stage is driven by the whole excitation from rest, as the study drives it; a record
//! "started mid-range" is that response with its first seconds cut off, so the stage has a
//! history the record does not show (the operators' memory at its first sample is unknown, as
//! on a real record). Every record is decimated to 1 kHz as in the study, and every model is
//! judged on the same held-out span: the last 25 % of the excitation (the multisine), in um.
//!
//! The bound is one-sided: the records started later fit *better* on the held-out span
//! (-4 %, -10 % and -23 % for 1, 2 and 5 s with the default warm-up): which samples are fitted
//! moves the held-out figure, not the unknown memory (the records that start later hold fewer
//! of the nested reversals and relatively more of the multisine the held-out span continues).
//! The full record fitted over exactly the samples the shorter record fits (its history
//! known) is therefore checked too, two-sided: within 10 % (measured: at most 0.03 %), it is
//! what not knowing the history costs.

use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_identify::{FitReport, IdentifyOptions, Warmup, identify};
use hystcomp_stage::{Stage, StageConfig};

/// Keep every 10th sample, as the study does.
const DECIMATION: usize = 10;

/// Identifies on `v`, `y` with `warmup`, holding out exactly the last `held_out` samples.
fn fit(v: &[f64], y: &[f64], warmup: Warmup, held_out: usize) -> FitReport {
    let options = |holdout: f64| IdentifyOptions {
        warmup,
        holdout,
        ..IdentifyOptions::default()
    };
    // The hold-out is a fraction of the samples after the warm-up: learn the warm-up first.
    let first = identify(v, y, &options(0.0)).expect("identifies").report;
    let after = v.len() - first.samples.warmup;
    let fraction = (held_out as f64 + 0.5) / after as f64;
    let report = identify(v, y, &options(fraction))
        .expect("identifies")
        .report;
    assert_eq!(report.samples.holdout, held_out);
    report
}

#[test]
fn records_started_mid_range_identify_as_well_as_the_full_record() {
    let config = StageConfig::default();
    let fs = config.sample_rate_hz;
    let excitation = IdentificationExcitation {
        full_scale_v: config.full_scale_command_v(),
        ..IdentificationExcitation::default()
    };
    let command = excitation.command_v(fs);
    let response = Stage::new(&config, 1)
        .expect("the built-in stage")
        .run(&command);
    let v: Vec<f64> = command.iter().step_by(DECIMATION).copied().collect();
    let y: Vec<f64> = response
        .measured_position_um
        .iter()
        .step_by(DECIMATION)
        .copied()
        .collect();
    let rate = fs / DECIMATION as f64;
    let held_out = v.len() / 4;

    for warmup in [Warmup::Auto, Warmup::Estimate] {
        let full = fit(&v, &y, warmup, held_out);
        let reference = full.holdout.as_ref().unwrap().rms;
        eprintln!(
            "{warmup:?}: full record: fitted samples {}..{} of {}, held-out RMS {reference:.4} um \
             ({:.4} %)",
            full.samples.warmup + 1,
            full.samples.warmup + full.samples.fit,
            full.samples.total,
            full.holdout.as_ref().unwrap().rms_percent
        );
        for dropped_s in [1.0, 2.0, 5.0] {
            let start = (dropped_s * rate).round() as usize;
            let r = fit(&v[start..], &y[start..], warmup, held_out);
            let rms = r.holdout.as_ref().unwrap().rms;
            let w = r.warmup.as_ref().unwrap();
            eprintln!(
                "{warmup:?}: first {dropped_s} s dropped (starts at {:.3} V): fitted samples \
                 {}..{} of {}, held-out RMS {rms:.4} um ({:+.1} % of the full record's): {}",
                v[start],
                r.samples.warmup + 1,
                r.samples.warmup + r.samples.fit,
                r.samples.total,
                100.0 * (rms / reference - 1.0),
                w.reason
            );
            // The same fitted samples of the full record, whose history is known (the stage
            // from rest): what not knowing the history costs.
            let same = fit(&v, &y, Warmup::Samples(start + r.samples.warmup), held_out);
            let known = same.holdout.as_ref().unwrap().rms;
            eprintln!(
                "    the full record fitted over the same samples (history known): held-out RMS \
                 {known:.4} um; the record started mid-range is {:+.2} % from it",
                100.0 * (rms / known - 1.0)
            );
            assert!(
                (rms / known - 1.0).abs() <= 0.1,
                "{warmup:?}, first {dropped_s} s dropped: held-out RMS {rms} um, against {known} \
                 um fitted on the same samples of the full record"
            );
            assert!(
                rms <= 1.1 * reference,
                "{warmup:?}, first {dropped_s} s dropped: held-out RMS {rms} um, more than 10 % \
                 above the full record's {reference} um"
            );
        }
    }
}
