//! The duration study (issue 11): does compensation hold over time?
//!
//! - **The paper's trajectory for [`DURATION_S`] (200 s)** with each approach, its indices on
//!   every period (10 s): e_rms against time. The study's own tracking runs are the first two
//!   periods of these; creep that a rate-independent model does not know makes the error grow
//!   with time.
//! - **A held step**: from rest, a step of [`HOLD_STEP_UM`] (50 um; a raised cosine of 0.1 s
//!   after 1 s) held [`HOLD_S`] (60 s). The drift is the largest distance of the measured
//!   position (averaged over 0.1 s windows, to see through the sensor noise) from its value
//!   1 s after the step, over the rest of the hold.
//!
//! Every run starts a fresh stage with the study's tracking noise seed; the runs are
//! independent and run in parallel.

use hystcomp_stage::{StageConfig, feasibility};
use rayon::prelude::*;
use serde::Serialize;

use crate::indices::TrackingIndices;
use crate::signals::{Signal, Steps};
use crate::study::{Approach, StudyError, evaluate, track};

/// Length of the long runs, s (20 periods of the paper's trajectory).
pub const DURATION_S: f64 = 200.0;
/// The held step, um.
pub const HOLD_STEP_UM: f64 = 50.0;
/// How long the step is held, s.
pub const HOLD_S: f64 = 60.0;
/// Rest before the step, s.
const HOLD_REST_S: f64 = 1.0;
/// The step's raised-cosine transition, s.
const HOLD_TRANSITION_S: f64 = 0.1;
/// From the end of the step to the reference value of the drift, s.
const HOLD_REFERENCE_AFTER_S: f64 = 1.0;
/// The averaging window of the drift, s.
const HOLD_WINDOW_S: f64 = 0.1;

/// One approach over the long run.
#[derive(Debug, Clone, Serialize)]
pub struct DurationSeries {
    /// The approach, e.g. `full / ihc`.
    pub label: String,
    /// The end of each period, s.
    pub period_end_s: Vec<f64>,
    /// The indices of each period, % of the `y_d` range.
    pub indices: Vec<TrackingIndices>,
    /// Samples the compensator clamped.
    pub saturated: u64,
    /// Share of the samples at the amplifier's slew or rail limit.
    pub limited_share: f64,
}

impl DurationSeries {
    /// The indices of the period that ends at `end_s` (20 or 200).
    pub fn at(&self, end_s: f64) -> Option<&TrackingIndices> {
        self.period_end_s
            .iter()
            .position(|t| (t - end_s).abs() < 1e-6)
            .map(|k| &self.indices[k])
    }
}

/// One approach holding a step.
#[derive(Debug, Clone, Serialize)]
pub struct HoldRun {
    /// The approach.
    pub label: String,
    /// The position 1 s after the step minus the target, um (0.1 s average).
    pub error_at_reference_um: f64,
    /// The largest distance from that position over the rest of the hold, um.
    pub drift_um: f64,
    /// Positions (0.1 s averages) every second from the reference on, um.
    pub positions_um: Vec<f64>,
}

/// Everything the duration study measured.
#[derive(Debug, Clone, Serialize)]
pub struct DurationStudy {
    /// Length of the long runs, s.
    pub duration_s: f64,
    /// The trajectory's period, s.
    pub period_s: f64,
    /// One per approach.
    pub series: Vec<DurationSeries>,
    /// The held step, um.
    pub hold_step_um: f64,
    /// How long it is held, s.
    pub hold_s: f64,
    /// One per approach.
    pub hold: Vec<HoldRun>,
}

enum Task<'a> {
    Long(&'a Approach<'a>),
    Hold(&'a Approach<'a>),
}

enum Outcome {
    Long(DurationSeries),
    Hold(HoldRun),
}

/// Runs the duration study for `approaches` (see the [module documentation](self)).
pub(crate) fn run_duration(
    stage: &StageConfig,
    seed: u64,
    approaches: &[Approach<'_>],
    full_scale: f64,
    bins: usize,
) -> Result<DurationStudy, StudyError> {
    let fs = stage.sample_rate_hz;
    let option = |e: crate::signals::SignalError| StudyError::Option(e.to_string());
    let desired = Signal::paper(1.0, DURATION_S, fs)
        .sample()
        .map_err(option)?;
    let period_s = 10.0;
    let per_period = (period_s * fs).round() as usize;
    let hold_duration = HOLD_REST_S + HOLD_TRANSITION_S + HOLD_S + HOLD_REFERENCE_AFTER_S;
    let step = Signal {
        shape: crate::signals::Shape::Steps(Steps::step(-1.0, 1.0, HOLD_REST_S, HOLD_TRANSITION_S)),
        amplitude: HOLD_STEP_UM / 2.0,
        offset: HOLD_STEP_UM / 2.0,
        duration_s: hold_duration,
        speed: 1.0,
        sample_rate_hz: fs,
    }
    .sample()
    .map_err(option)?;
    let tasks: Vec<Task> = approaches
        .iter()
        .map(Task::Long)
        .chain(approaches.iter().map(Task::Hold))
        .collect();
    let outcomes: Vec<Outcome> = tasks
        .into_par_iter()
        .map(|task| -> Result<Outcome, StudyError> {
            match task {
                Task::Long(approach) => {
                    let (command, saturated) = approach.command(&desired, full_scale)?;
                    let limited_share = feasibility(stage, &command)?.limited_share();
                    let measured = track(stage, seed, &command)?;
                    let mut series = DurationSeries {
                        label: approach.label.clone(),
                        period_end_s: Vec::new(),
                        indices: Vec::new(),
                        saturated,
                        limited_share,
                    };
                    for end in (per_period..=desired.len()).step_by(per_period) {
                        let indices = evaluate(
                            &desired[..end],
                            &measured[..end],
                            end - per_period,
                            bins,
                            &approach.label,
                        )?;
                        series.period_end_s.push(end as f64 / fs);
                        series.indices.push(indices);
                    }
                    Ok(Outcome::Long(series))
                }
                Task::Hold(approach) => {
                    let (command, _) = approach.command(&step, full_scale)?;
                    let measured = track(stage, seed, &command)?;
                    let window = (HOLD_WINDOW_S * fs).round() as usize;
                    let average = |start: usize| {
                        measured[start..start + window].iter().sum::<f64>() / window as f64
                    };
                    let reference = ((HOLD_REST_S + HOLD_TRANSITION_S + HOLD_REFERENCE_AFTER_S)
                        * fs)
                        .round() as usize;
                    let at_reference = average(reference);
                    let last = measured.len() - window;
                    let drift_um = (reference..=last)
                        .step_by(window)
                        .map(|k| (average(k) - at_reference).abs())
                        .fold(0.0, f64::max);
                    let positions_um = (reference..=last)
                        .step_by(fs.round() as usize)
                        .map(average)
                        .collect();
                    Ok(Outcome::Hold(HoldRun {
                        label: approach.label.clone(),
                        error_at_reference_um: at_reference - HOLD_STEP_UM,
                        drift_um,
                        positions_um,
                    }))
                }
            }
        })
        .collect::<Result<_, _>>()?;
    let mut study = DurationStudy {
        duration_s: DURATION_S,
        period_s,
        series: Vec::new(),
        hold_step_um: HOLD_STEP_UM,
        hold_s: HOLD_S,
        hold: Vec::new(),
    };
    for outcome in outcomes {
        match outcome {
            Outcome::Long(s) => study.series.push(s),
            Outcome::Hold(h) => study.hold.push(h),
        }
    }
    Ok(study)
}
