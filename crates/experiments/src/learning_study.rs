//! The learning study of `hystcomp reproduce` (issue 12): e_rms against trial number when a
//! motion repeats and `hystcomp-learn` learns from each trial.
//!
//! Two motions, each learned from two starting points, the `exact` pipeline's IHC (the MPIM
//! alone, least squares) and the `full` pipeline's IHC (hysteresis, creep and vibration):
//!
//! - **the paper's trajectory**, one 10 s period per trial played [`PAPER_PERIODS_PER_TRIAL`]
//!   times from rest and measured on the last (the study's own protocol), [`PAPER_TRIALS`]
//!   trials (trial 0 is the compensator's own drive), e_mhe over [`PAPER_MHE_BINS`] bins (with
//!   the study's 100, a perfect tracker reads 1 %: the map's slope across one bin);
//! - **a 20 um triangle raster at 100 Hz** with corners rounded over 5 % of its period (the
//!   speed study's, [`crate::speed::RASTER_UM`] about the trajectory's mid-range), one period
//!   per trial played [`RASTER_PERIODS_PER_TRIAL`] times from rest, [`RASTER_TRIALS`] trials.
//!
//! The learning law is `hystcomp-learn`'s with its defaults (gain 0.8, `Q` of order 4 with its
//! cut-off at a hundredth of the sample rate for a model without a vibration link, a tenth
//! with one); nothing is tuned per motion. Every trial starts from a fresh stage at rest with
//! its own sensor-noise seed (`seed + trial`), so noise does not repeat ([`run_trials`]).
//! Besides the indices, each trial records the sensor noise's own RMS over the measured period
//! (the floor) and the share of that period's samples in which the amplifier was at its slew
//! or rail limit (`hystcomp_stage::feasibility`), which tells the amplifier's limit from the
//! law's.

use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::{Learner, LearningLaw, LearningOptions};
use hystcomp_stage::StageConfig;
use rayon::prelude::*;
use serde::Serialize;

use crate::TrackingIndices;
use crate::learning::run_trials;
use crate::signals::{PaperTrajectory, Raster, Shape, Signal};
use crate::speed::{RASTER_ROUNDING, RASTER_UM};
use crate::study::{EXACT_IHC_LABEL, FULL_IHC_LABEL, StudyError};
use crate::study_report::{AcceptanceCheck, write_targets};

/// Trials of the paper's trajectory: trial 0 and ten learned ones.
pub const PAPER_TRIALS: usize = 11;
/// Periods of the paper's trajectory each trial plays from rest (the last is measured).
pub const PAPER_PERIODS_PER_TRIAL: usize = 2;
/// Bins of e_mhe on the paper's trajectory.
pub const PAPER_MHE_BINS: usize = 1000;
/// Trials of the raster: trial 0 and twenty learned ones.
pub const RASTER_TRIALS: usize = 21;
/// The raster's scan rate, Hz.
pub const RASTER_RATE_HZ: f64 = 100.0;
/// Periods of the raster each trial plays from rest (the last is measured).
pub const RASTER_PERIODS_PER_TRIAL: usize = 20;
/// Bins of e_mhe on the raster (one period at 10 kHz holds 100 samples).
pub const RASTER_MHE_BINS: usize = 10;

/// The name of the paper's trajectory in the series.
pub const PAPER: &str = "paper trajectory";
/// The name of the raster in the series.
pub const RASTER: &str = "raster 100 Hz";

/// One trial of a series.
#[derive(Debug, Clone, Serialize)]
pub struct LearningPoint {
    /// The trial (0: the compensator's own drive, or the slew-constrained one).
    pub trial: usize,
    /// Its indices over the measured period, % of the desired range.
    pub indices: TrackingIndices,
    /// RMS of the sensor noise alone over the measured period, % of the desired range.
    pub noise_floor_percent: f64,
    /// Share of the measured period's samples at the amplifier's slew or rail limit.
    pub limited_share: f64,
}

/// One motion learned from one starting compensator.
#[derive(Debug, Clone, Serialize)]
pub struct LearningSeries {
    /// [`PAPER`] or [`RASTER`].
    pub trajectory: String,
    /// The starting compensator, `exact / ihc` or `full / ihc`.
    pub start: String,
    /// The law in force.
    pub law: LearningLaw,
    /// Every trial run.
    pub trials: Vec<LearningPoint>,
    /// Whether the divergence guard stopped the learning.
    pub stopped: bool,
    /// Whether trial 0 is the slew-constrained drive ([`feasible_start`]) rather than the
    /// compensator's own.
    pub slew_constrained_start: bool,
}

impl LearningSeries {
    /// `trajectory from start`.
    pub fn label(&self) -> String {
        format!("{} from {}", self.trajectory, self.start)
    }

    /// The first trial within `within` whose e_rms is at most `e_rms` and e_mhe at most
    /// `e_mhe` (percent).
    pub fn first_meeting(&self, within: usize, e_rms: f64, e_mhe: f64) -> Option<usize> {
        self.trials
            .iter()
            .take(within + 1)
            .find(|p| p.indices.e_rms_percent <= e_rms && p.indices.e_mhe_percent <= e_mhe)
            .map(|p| p.trial)
    }

    /// The lowest e_rms of trials `0..=within`, and its trial.
    pub fn best_within(&self, within: usize) -> Option<&LearningPoint> {
        self.trials
            .iter()
            .take(within + 1)
            .min_by(|a, b| a.indices.e_rms_percent.total_cmp(&b.indices.e_rms_percent))
    }
}

/// Everything the learning study measured.
#[derive(Debug, Clone, Serialize)]
pub struct LearningStudy {
    /// The paper's trajectory from `exact` and from `full`, then the raster from each.
    pub series: Vec<LearningSeries>,
    /// The raster's scan rate, Hz.
    pub raster_rate_hz: f64,
    /// Its peak-to-peak amplitude, um.
    pub raster_um: f64,
    /// The share of its period over which each corner is rounded.
    pub raster_rounding: f64,
    /// Periods per trial: the paper's trajectory, the raster.
    pub periods_per_trial: (usize, usize),
    /// Issue 12's acceptance figures (reported, not counted in the exit status).
    pub checks: Vec<AcceptanceCheck>,
}

impl LearningStudy {
    /// The series of `trajectory` from `start`.
    pub fn series(&self, trajectory: &str, start: &str) -> Option<&LearningSeries> {
        self.series
            .iter()
            .find(|s| s.trajectory == trajectory && s.start == start)
    }
}

/// One period of the raster (20 um about the paper trajectory's mid-range).
pub fn raster_period(sample_rate_hz: f64) -> Result<Vec<f64>, StudyError> {
    Signal {
        shape: Shape::Raster(Raster::triangle(RASTER_RATE_HZ, RASTER_ROUNDING)),
        amplitude: RASTER_UM / 2.0,
        offset: PaperTrajectory::new().mid_range_um(),
        duration_s: 1.0 / RASTER_RATE_HZ,
        speed: 1.0,
        sample_rate_hz,
    }
    .sample()
    .map_err(|e| StudyError::Option(format!("the learning study's raster: {e}")))
}

/// The slew-constrained starting drive of a series (one period, model voltage unit), or `None`
/// where the learner's own start is kept: the speed study's drive ([`crate::slew_drive`],
/// every step within `max_step`) for `periods` repetitions of `desired` as a trial plays them
/// from rest, used only where the speed study would use it (a model with a vibration link whose
/// faithful drive over those periods has a step beyond `max_step`). The drive is the record's
/// last period (the one a trial measures), made slew-feasible around the period's wrap as well
/// (`hystcomp_learn::slew::project_slew`, periodic), within `limits`.
pub fn feasible_start(
    model: &ModelFile,
    desired: &[f64],
    periods: usize,
    limits: (f64, f64),
    max_step: f64,
) -> Result<Option<Vec<f64>>, String> {
    if model.vibration.is_none() {
        return Ok(None);
    }
    let n = desired.len();
    let repeated: Vec<f64> = (0..periods.max(1))
        .flat_map(|_| desired.iter().copied())
        .collect();
    let drive = crate::slew_drive::slew_constrained_drive(
        model,
        hystcomp_io::compensator::Method::Ihc,
        limits,
        &repeated,
        max_step,
    )?;
    if !drive.constrained {
        return Ok(None);
    }
    let last = &drive.drive[drive.drive.len() - n..];
    Ok(Some(
        hystcomp_learn::slew::project_slew(last, max_step, limits, true).drive,
    ))
}

fn learn(
    stage: &StageConfig,
    seed: u64,
    trajectory: &str,
    (label, model): (&str, &ModelFile),
    desired: &[f64],
    max_drive_step: Option<f64>,
    start_step: Option<f64>,
) -> Result<LearningSeries, StudyError> {
    let (trials, periods, bins) = if trajectory == PAPER {
        (PAPER_TRIALS, PAPER_PERIODS_PER_TRIAL, PAPER_MHE_BINS)
    } else {
        (RASTER_TRIALS, RASTER_PERIODS_PER_TRIAL, RASTER_MHE_BINS)
    };
    let failed = |e: &dyn std::fmt::Display| {
        StudyError::Option(format!("learning the {trajectory} from {label}: {e}"))
    };
    let mut options = LearningOptions::new(stage.sample_rate_hz);
    options.mhe_bins = bins;
    options.max_drive_step = max_drive_step;
    let mut learner = Learner::new(model, desired, options.clone()).map_err(|e| failed(&e))?;
    let mut slew_constrained_start = false;
    // A programme the solver could not finish (or a start the learner refuses) leaves the
    // learner's own start, as the speed study keeps the faithful drive: the series then
    // reports no slew-constrained start.
    if let Some(step) = start_step
        && let Ok(Some(start)) = feasible_start(model, desired, periods, learner.law().limits, step)
        && let Ok(resumed) = Learner::resume(model, desired, &start, options)
    {
        learner = resumed;
        slew_constrained_start = true;
    }
    let played = run_trials(stage, seed, &mut learner, trials, periods, &mut |_| {})
        .map_err(|e| failed(&e))?;
    Ok(LearningSeries {
        trajectory: trajectory.into(),
        start: label.into(),
        law: learner.law().clone(),
        stopped: learner.is_stopped(),
        slew_constrained_start,
        trials: played
            .iter()
            .map(|t| LearningPoint {
                trial: t.update.trial,
                indices: t.update.indices,
                noise_floor_percent: t.noise_floor_percent,
                limited_share: t.limited_share,
            })
            .collect(),
    })
}

fn check(what: String, value: f64, bound: &str, passed: bool) -> AcceptanceCheck {
    AcceptanceCheck {
        what,
        value,
        bound: bound.into(),
        passed,
    }
}

/// Issue 12's acceptance figures on the study's series: the paper's trajectory (e_rms <=
/// 0.03 % and e_mhe <= 0.3 % within 10 trials) and the raster (e_rms <= 0.1 % within 20
/// trials), from each starting compensator. The value is the best e_rms within the trials.
pub fn learning_checks(series: &[LearningSeries]) -> Vec<AcceptanceCheck> {
    let mut checks = Vec::new();
    for s in series {
        if s.trajectory == PAPER {
            let within = PAPER_TRIALS - 1;
            let met = s.first_meeting(within, 0.03, 0.3);
            if let Some(best) = s.best_within(within) {
                checks.push(check(
                    format!(
                        "{}: best e_rms within {within} trials (trial {}; e_mhe {:.3} % over \
                         {PAPER_MHE_BINS} bins){}",
                        s.label(),
                        best.trial,
                        best.indices.e_mhe_percent,
                        met.map_or(String::new(), |t| format!("; both met at trial {t}"))
                    ),
                    best.indices.e_rms_percent,
                    "e_rms <= 0.03 % and e_mhe <= 0.3 %",
                    met.is_some(),
                ));
            }
        } else {
            let within = RASTER_TRIALS - 1;
            let met = s.first_meeting(within, 0.1, f64::INFINITY);
            if let Some(best) = s.best_within(within) {
                checks.push(check(
                    format!(
                        "{}: best e_rms within {within} trials (trial {}){}",
                        s.label(),
                        best.trial,
                        met.map_or(String::new(), |t| format!("; met at trial {t}"))
                    ),
                    best.indices.e_rms_percent,
                    "e_rms <= 0.1 %",
                    met.is_some(),
                ));
            }
        }
    }
    checks
}

/// Runs the learning study on `stage` (see the [module documentation](self)): the paper's
/// trajectory and the raster, each learned from the `exact` and the `full` plant model's IHC,
/// the four series in parallel; with `max_drive_step` (command volts per sample) every
/// trial's drive is kept within it (`hystcomp_learn::slew`); with `start_step` (command volts
/// per sample) a series whose faithful drive asks a larger step starts from the
/// slew-constrained drive instead ([`feasible_start`]).
pub(crate) fn run_learning(
    stage: &StageConfig,
    seed: u64,
    exact: &ModelFile,
    full: &ModelFile,
    max_drive_step: Option<f64>,
    start_step: Option<f64>,
) -> Result<LearningStudy, StudyError> {
    let fs = stage.sample_rate_hz;
    let paper = Signal::paper(1.0, crate::Reference::paper().trajectory.period_s, fs)
        .sample()
        .map_err(|e| StudyError::Option(format!("the learning study's trajectory: {e}")))?;
    let raster = raster_period(fs)?;
    let jobs = [
        (PAPER, (EXACT_IHC_LABEL, exact), &paper),
        (PAPER, (FULL_IHC_LABEL, full), &paper),
        (RASTER, (EXACT_IHC_LABEL, exact), &raster),
        (RASTER, (FULL_IHC_LABEL, full), &raster),
    ];
    let series: Vec<LearningSeries> = jobs
        .par_iter()
        .map(|(trajectory, start, desired)| {
            learn(
                stage,
                seed,
                trajectory,
                *start,
                desired,
                max_drive_step,
                start_step,
            )
        })
        .collect::<Result<_, _>>()?;
    Ok(LearningStudy {
        checks: learning_checks(&series),
        series,
        raster_rate_hz: RASTER_RATE_HZ,
        raster_um: RASTER_UM,
        raster_rounding: RASTER_ROUNDING,
        periods_per_trial: (PAPER_PERIODS_PER_TRIAL, RASTER_PERIODS_PER_TRIAL),
    })
}

impl std::fmt::Display for LearningStudy {
    /// e_rms against trial number for each series, and issue 12's checks, as text.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "learning from repetition: e_rms % by trial (trial 0: the compensator's own drive, \
             or the slew-constrained one where marked; \
             last: the noise floor, % at the amplifier's limits):"
        )?;
        for s in &self.series {
            write!(f, "  {:<36}", s.label())?;
            for p in &s.trials {
                write!(f, " {:.4}", p.indices.e_rms_percent)?;
            }
            if let Some(last) = s.trials.last() {
                write!(
                    f,
                    "  (floor {:.4}; {:.0} % limited)",
                    last.noise_floor_percent,
                    100.0 * last.limited_share
                )?;
            }
            if s.stopped {
                write!(f, "  STOPPED by the divergence guard")?;
            }
            if s.slew_constrained_start {
                write!(f, "  (slew-constrained start)")?;
            }
            writeln!(f)?;
        }
        write_targets(f, 12, &self.checks, |v| format!("{v:.4} %"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(trajectory: &str, e: &[(f64, f64)]) -> LearningSeries {
        LearningSeries {
            trajectory: trajectory.into(),
            start: EXACT_IHC_LABEL.into(),
            law: hystcomp_learn::Learner::new(
                &hystcomp_io::model_file::ModelFile::load(std::path::Path::new(
                    "../../models/table1-plant.json",
                ))
                .unwrap(),
                &[30.0, 40.0],
                {
                    let mut o = LearningOptions::new(10.0);
                    o.mhe_bins = 1;
                    o
                },
            )
            .unwrap()
            .law()
            .clone(),
            trials: e
                .iter()
                .enumerate()
                .map(|(k, &(e_rms, e_mhe))| LearningPoint {
                    trial: k,
                    indices: TrackingIndices {
                        e_mhe_percent: e_mhe,
                        e_m_percent: 3.0 * e_rms,
                        e_rms_percent: e_rms,
                        mhe_bins: 10,
                    },
                    noise_floor_percent: 0.01,
                    limited_share: 0.0,
                })
                .collect(),
            stopped: false,
            slew_constrained_start: false,
        }
    }

    /// One period of a rounded triangle raster (`rate` Hz at 10 kHz).
    fn raster_at(rate: f64, amplitude: f64, offset: f64) -> Vec<f64> {
        Signal {
            shape: Shape::Raster(Raster::triangle(rate, 0.05)),
            amplitude,
            offset,
            duration_s: 1.0 / rate,
            speed: 1.0,
            sample_rate_hz: 10_000.0,
        }
        .sample()
        .unwrap()
    }

    /// The largest step of the faithful IHC drive over `periods` repetitions from rest.
    fn faithful_peak_step(model: &ModelFile, desired: &[f64], periods: usize) -> f64 {
        let repeated: Vec<f64> = (0..periods).flat_map(|_| desired.iter().copied()).collect();
        let mut c = hystcomp_io::compensator::ScaledCompensator::new(
            model,
            hystcomp_io::compensator::Method::Ihc,
            Some((0.0, 10.0)),
        )
        .unwrap();
        let mut v = vec![0.0; repeated.len()];
        c.process(&repeated, &mut v).unwrap();
        v.windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn a_feasible_start_is_kept_only_where_the_faithful_drive_is_infeasible() {
        let model = crate::slew_drive::tests::chain();
        let limits = (0.0, 10.0);
        let mut options = LearningOptions::new(10_000.0);
        options.mhe_bins = 5;
        options.limits = Some(limits);
        for (rate, amplitude, offset, periods) in [
            (100.0, 10.0, 37.5, 4),
            (130.0, 6.0, 30.0, 3),
            (80.0, 12.0, 40.0, 2),
        ] {
            let desired = raster_at(rate, amplitude, offset);
            let n = desired.len();
            let peak = faithful_peak_step(&model, &desired, periods);
            // Feasible faithful drive, or no vibration link: the learner's own start.
            assert_eq!(
                feasible_start(&model, &desired, periods, limits, 1.5 * peak).unwrap(),
                None
            );
            let plain =
                ModelFile::load(std::path::Path::new("../../models/table1-plant.json")).unwrap();
            assert_eq!(
                feasible_start(&plain, &desired, periods, limits, 0.5 * peak).unwrap(),
                None
            );
            // Infeasible: a period whose every step, the wrap included, is within the bound.
            let step = 0.6 * peak;
            let start = feasible_start(&model, &desired, periods, limits, step)
                .unwrap()
                .expect("the faithful drive is infeasible");
            assert_eq!(start.len(), n);
            assert!(
                start
                    .iter()
                    .all(|v| v.is_finite() && (0.0..=10.0).contains(v))
            );
            for k in 0..n {
                let d = start[(k + 1) % n] - start[k];
                assert!(
                    d.abs() <= step * (1.0 + 1e-9),
                    "{rate} Hz, sample {k}: {d} > {step}"
                );
            }
            // The learner resumed from it plays it as trial 0, and its reference is the model's
            // response to it.
            let learner = Learner::resume(&model, &desired, &start, options.clone()).unwrap();
            assert_eq!(learner.drive(), &start[..]);
            assert!(learner.reference().iter().all(|r| r.is_finite()));
        }
    }

    #[test]
    fn checks_need_both_indices_within_the_trials_and_quote_the_best() {
        // Paper: e_rms met at trial 2 but e_mhe only at trial 3.
        let paper = series(PAPER, &[(0.3, 2.0), (0.05, 0.5), (0.02, 0.4), (0.025, 0.2)]);
        assert_eq!(paper.first_meeting(10, 0.03, 0.3), Some(3));
        assert_eq!(paper.first_meeting(2, 0.03, 0.3), None);
        assert_eq!(paper.best_within(10).unwrap().trial, 2);
        // Raster: never below 0.1 % within 20 trials; a later trial does not count.
        let mut e: Vec<(f64, f64)> = (0..21)
            .map(|k| (0.5 + 1.0 / (k as f64 + 1.0), 5.0))
            .collect();
        e.push((0.01, 5.0));
        let raster = series(RASTER, &e);
        let checks = learning_checks(&[paper, raster]);
        assert_eq!(checks.len(), 2);
        assert!(checks[0].passed && checks[0].what.contains("met at trial 3"));
        assert_eq!(checks[0].value, 0.02);
        assert!(!checks[1].passed);
        assert!(
            (checks[1].value - (0.5 + 1.0 / 21.0)).abs() < 1e-12,
            "{:?}",
            checks[1]
        );
    }
}
