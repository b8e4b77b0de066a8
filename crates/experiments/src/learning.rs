//! Learning from repetition on the simulated stage: the trial loop ([`run_trials`]) that
//! `hystcomp learn --simulate`, the learning study of `hystcomp reproduce` and the acceptance
//! tests share. The learning law itself is `hystcomp-learn`'s; this module only plays drives
//! on the stage and hands the measurements back.
//!
//! A trial starts from rest (a fresh stage: relaxed, at 0 V), as iterative learning control
//! assumes (every trial from the same state; Bristow, Tharayil & Alleyne 2006,
//! doi:10.1109/MCS.2006.1636313). A periodic learner's drive (one period) is played
//! `periods` times and the last period is measured, so that the start from rest is over and
//! the creep since it is the same in every trial; a finite one is played once. Each trial has
//! its own sensor-noise seed (`seed + trial`): noise does not repeat, and learning must not
//! learn it.

use hystcomp_learn::{LearnError, Learner, Update};
use hystcomp_stage::{ClampCounts, Stage, StageConfig, StageError, feasibility};
use serde::Serialize;

/// The most periods one simulated trial plays.
pub const MAX_PERIODS_PER_TRIAL: usize = 1000;
/// The most trials one simulated run makes.
pub const MAX_TRIALS: usize = 1000;
/// The most stage samples one simulated run may play in all (1e9: about two minutes of
/// simulation on this project's machine).
pub const MAX_SIMULATED_SAMPLES: f64 = 1e9;
/// The most stage samples one simulated trial may play (its periods together): 1e7. A trial
/// keeps its drive and five response signals of that length in memory (about 480 MB at the
/// bound), so the bound is on memory, beside [`MAX_SIMULATED_SAMPLES`] on time.
pub const MAX_TRIAL_SAMPLES: f64 = 1e7;

/// Why the simulated loop stopped early.
#[derive(Debug)]
pub enum TrialError {
    /// The stage.
    Stage(StageError),
    /// The learner.
    Learn(LearnError),
    /// An option out of range.
    Option(String),
}

impl std::fmt::Display for TrialError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TrialError::Stage(e) => write!(f, "stage: {e}"),
            TrialError::Learn(e) => write!(f, "{e}"),
            TrialError::Option(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for TrialError {}

impl From<StageError> for TrialError {
    fn from(e: StageError) -> Self {
        TrialError::Stage(e)
    }
}

impl From<LearnError> for TrialError {
    fn from(e: LearnError) -> Self {
        TrialError::Learn(e)
    }
}

/// One simulated trial.
#[derive(Debug, Clone, Serialize)]
pub struct SimulatedTrial {
    /// The learner's report of it.
    pub update: Update,
    /// RMS of the sensor noise alone over the measured period (measured minus true position),
    /// % of the desired range: the floor no learning goes below.
    pub noise_floor_percent: f64,
    /// What the stage clamped or slewed in this trial.
    #[serde(skip)]
    pub clamps: ClampCounts,
    /// Samples during which the amplifier slewed at its current limit (the whole trial).
    pub slew_limited: u64,
    /// Share of the measured period's samples in which the amplifier was at its slew or rail
    /// limit (`hystcomp_stage::feasibility` over the trial's drive): where it is large, the
    /// amplifier, not the learning, limits the error.
    pub limited_share: f64,
}

/// Checks `trials` and `periods` against the bounds before anything runs.
pub fn check_trials(trials: usize, periods: usize, samples: usize) -> Result<(), TrialError> {
    if !(1..=MAX_TRIALS).contains(&trials) {
        return Err(TrialError::Option(format!(
            "--trials {trials}: give 1 to {MAX_TRIALS}"
        )));
    }
    if !(1..=MAX_PERIODS_PER_TRIAL).contains(&periods) {
        return Err(TrialError::Option(format!(
            "--periods {periods}: give 1 to {MAX_PERIODS_PER_TRIAL}"
        )));
    }
    let per_trial = periods as f64 * samples as f64;
    if per_trial > MAX_TRIAL_SAMPLES {
        return Err(TrialError::Option(format!(
            "{periods} periods of {samples} samples are {per_trial:.3e} stage samples per \
             trial, more than the {MAX_TRIAL_SAMPLES:.0e} one trial holds in memory; lower \
             --periods (or give a shorter period)"
        )));
    }
    let total = trials as f64 * per_trial;
    if total > MAX_SIMULATED_SAMPLES {
        return Err(TrialError::Option(format!(
            "{trials} trials of {periods} periods of {samples} samples are {total:.3e} stage \
             samples, more than the {MAX_SIMULATED_SAMPLES:.0e} one run simulates; lower \
             --trials or --periods"
        )));
    }
    Ok(())
}

/// Runs `trials` trials of `learner` on `stage` (see the [module documentation](self));
/// `watch` sees each trial as it ends. Stops early, without error, when the divergence guard
/// trips (the last trial's status says so; the learner's drive is then the last good one).
pub fn run_trials(
    stage: &StageConfig,
    seed: u64,
    learner: &mut Learner,
    trials: usize,
    periods: usize,
    watch: &mut dyn FnMut(&SimulatedTrial),
) -> Result<Vec<SimulatedTrial>, TrialError> {
    let n = learner.desired().len();
    let periodic = learner.options().periodic;
    let periods = if periodic { periods } else { 1 };
    check_trials(trials, periods, n)?;
    let (lo, hi) = learner
        .desired()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    let mut out = Vec::with_capacity(trials);
    for trial in 0..trials {
        let drive: Vec<f64> = (0..periods)
            .flat_map(|_| learner.drive().iter().copied())
            .collect();
        let response = Stage::new(stage, seed.wrapping_add(trial as u64))?.run(&drive);
        let start = drive.len() - n;
        let limited = feasibility(stage, &drive)?.limited_samples()
            - feasibility(stage, &drive[..start])?.limited_samples();
        let measured = &response.measured_position_um[start..];
        let truth = &response.true_position_um[start..];
        let noise = (measured
            .iter()
            .zip(truth)
            .map(|(m, t)| (m - t).powi(2))
            .sum::<f64>()
            / n as f64)
            .sqrt();
        let update = learner.update(measured)?;
        let record = SimulatedTrial {
            update,
            noise_floor_percent: noise / (hi - lo) * 100.0,
            clamps: response.clamps,
            slew_limited: response.clamps.slew_limited,
            limited_share: limited as f64 / n as f64,
        };
        watch(&record);
        let stopped = learner.is_stopped();
        out.push(record);
        if stopped {
            break;
        }
    }
    Ok(out)
}

/// The study's `exact` plant model on `stage`: the identification excitation from rest
/// (sensor-noise seed `seed`), every tenth sample, constrained least squares with `operators`
/// play operators (as `hystcomp reproduce` identifies it).
pub fn exact_plant_model(
    stage: &StageConfig,
    seed: u64,
    operators: usize,
) -> Result<hystcomp_io::model_file::ModelFile, TrialError> {
    use hystcomp_identify::{IdentifyOptions, Method, Thresholds, Warmup, identify};
    let excitation = crate::excitation::IdentificationExcitation {
        full_scale_v: stage.full_scale_command_v(),
        ..Default::default()
    };
    let command = excitation.command_v(stage.sample_rate_hz);
    let response = Stage::new(stage, seed)?.run(&command);
    let v: Vec<f64> = command.iter().step_by(10).copied().collect();
    let y: Vec<f64> = response
        .measured_position_um
        .iter()
        .step_by(10)
        .copied()
        .collect();
    let options = IdentifyOptions {
        thresholds: Thresholds::Uniform(operators),
        warmup: Warmup::Samples(0),
        max_fit_rms_percent: None,
        method: Method::LeastSquares,
        ..IdentifyOptions::default()
    };
    identify(&v, &y, &options)
        .map(|id| id.model)
        .map_err(|e| TrialError::Option(format!("identifying the stage's plant model: {e}")))
}
