//! Fit reports: errors in physical units and in % of a range, sample counts, solver details.

use hystcomp_io::model_file::Direction;
use serde::{Deserialize, Serialize};

use crate::{OutputOffset, PsoOptions};

/// Errors of a prediction over a span of samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    /// Number of samples.
    pub samples: usize,
    /// Root mean square error, in the signal's unit.
    pub rms: f64,
    /// Largest absolute error, in the signal's unit.
    pub max: f64,
    /// Mean error (prediction minus measurement), in the signal's unit: a bias or offset drift.
    pub mean: f64,
    /// The range the percentages refer to, in the signal's unit.
    pub range: f64,
    /// `rms / range * 100`.
    pub rms_percent: f64,
    /// `max / range * 100`.
    pub max_percent: f64,
    /// The RMS of the error minus its mean (what an offset correction cannot remove), in % of
    /// the range.
    pub std_percent: f64,
}

impl ErrorStats {
    /// Statistics of `predicted - measured`, in % of `range`. `None` for no samples.
    pub fn new(predicted: &[f64], measured: &[f64], range: f64) -> Option<Self> {
        let samples = predicted.len().min(measured.len());
        if samples == 0 {
            return None;
        }
        let (mut sum, mut sum_sq, mut max) = (0.0, 0.0, 0.0_f64);
        for (p, m) in predicted.iter().zip(measured) {
            let e = p - m;
            sum += e;
            sum_sq += e * e;
            max = max.max(e.abs());
        }
        let n = samples as f64;
        let rms = (sum_sq / n).sqrt();
        let mean = sum / n;
        let std = (sum_sq / n - mean * mean).max(0.0).sqrt();
        Some(ErrorStats {
            samples,
            rms,
            max,
            mean,
            range,
            rms_percent: 100.0 * rms / range,
            max_percent: 100.0 * max / range,
            std_percent: 100.0 * std / range,
        })
    }
}

/// The worst-case gains of the two one-sample-delayed loops a plant model gives (see
/// `hystcomp_core::Mpim::delayed_ihc_loop_gain` and `delayed_wihc_loop_gain`), over a drive
/// range. Below 1 the delayed loop settles after any jump in the desired position; at or above
/// 1 it can ring between the limits, and `hystcomp compensate` refuses it unless
/// `--allow-unstable-delay` is given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DelayedGains {
    /// The delayed IHC's: `max |g'(x) - a2| / (a2 + b_1 + ... + b_k)`.
    pub ihc: f64,
    /// The delayed WIHC's: `max |g'(x) - a2 + b_1 + ... + b_k| / a2`.
    pub wihc: f64,
}

impl DelayedGains {
    /// Both gains of `plant` over the normalised drive range `[lo, hi]` (NaN where the core
    /// cannot compute one: a model that is not invertible there).
    pub fn of(plant: &hystcomp_core::Mpim<f64, Vec<f64>>, lo: f64, hi: f64) -> Self {
        DelayedGains {
            ihc: plant
                .delayed_ihc_loop_gain(lo, hi)
                .map_or(f64::NAN, |g| g.gain),
            wihc: plant
                .delayed_wihc_loop_gain(lo, hi)
                .map_or(f64::NAN, |g| g.gain),
        }
    }
}

/// What constraining both delayed loops' gains cost ([`crate::IdentifyOptions::delayed_loop_bound`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DelayedConstraint {
    /// The bound both delayed loops' gains were held to.
    pub bound: f64,
    /// The RMS fit error, in % of the fitted output range, of the least-squares optimum of the
    /// same problem without the delayed-loop rows: the fit's cost of the constraint is
    /// [`FitReport::fit`]'s `rms_percent` minus this.
    pub unconstrained_fit_rms_percent: f64,
    /// Both gains of that unconstrained optimum (what the constraint brought down).
    pub unconstrained_gains: DelayedGains,
}

/// The physical range of one signal of a record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SignalRange {
    /// `voltage` or `displacement`.
    pub quantity: String,
    /// Its unit.
    pub unit: String,
    /// Smallest value over the fitted samples (warm-up and hold-out excluded).
    pub min: f64,
    /// Largest value over the fitted samples.
    pub max: f64,
}

/// How the samples of a record were used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SampleCounts {
    /// Samples in the record (the operators run over all of them).
    pub total: usize,
    /// Samples at the start excluded as warm-up.
    pub warmup: usize,
    /// Samples the error was minimised over.
    pub fit: usize,
    /// Samples at the end held out of the fit.
    pub holdout: usize,
}

/// Which samples were fitted and where the operators' memory at the start came from
/// ([`crate::Warmup`], [`crate::warmup`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WarmupReport {
    /// The warm-up asked for.
    pub mode: crate::Warmup,
    /// The first fitted sample (0-based; the warm-up's length).
    pub first_fitted: usize,
    /// The first sample (0-based) where the voltage reaches the record's minimum or maximum:
    /// from there on the operators' memory is fixed by the record whatever came before.
    pub memory_known_from: usize,
    /// With [`crate::Warmup::Estimate`]: the virtual history run before the first sample (model
    /// input, physical units: an end of the range, the other end, the turning point `v0`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history: Option<Vec<f64>>,
    /// With [`crate::Warmup::Estimate`]: each operator's memory before the first sample,
    /// normalised (fractions of the fitted input range).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_memory: Option<Vec<f64>>,
    /// Why these samples, in a sentence for people.
    pub reason: String,
}

/// What [`crate::identify`] did and how well the model fits. Serialisable: the command line
/// prints it with `--json` and writes it into the model file's `identification` field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    /// What the model maps.
    pub direction: Direction,
    /// `ls` or `pso`.
    pub solver: String,
    /// How the solver reached its answer.
    pub detail: String,
    /// The thresholds `r_i` (normalised).
    pub thresholds: Vec<f64>,
    /// Sample counts.
    pub samples: SampleCounts,
    /// Which samples were fitted and why; where the operators' memory came from. Reports
    /// written before this field existed read as `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warmup: Option<WarmupReport>,
    /// The model input's physical range (normalised to `[0, 1]`).
    pub input: SignalRange,
    /// The model output's physical range (its width is the output scale).
    pub output: SignalRange,
    /// How the output offset was handled.
    pub offset_mode: OutputOffset,
    /// The model file's `output.offset`: the physical output at normalised output 0.
    pub output_offset: f64,
    /// Errors over the fitting span, in the output's unit and % of the output range.
    pub fit: ErrorStats,
    /// Errors over the held-out span, if any, in % of **the held-out span's own** output range
    /// (its `range`; the test span's range, as `crossval` normalises: the model runs on from
    /// the fitted samples into the held-out ones, so that the figure is the one `crossval`
    /// gives for the same split of the record). Reports written before issue 10 used the
    /// fitted output range.
    pub holdout: Option<ErrorStats>,
    /// Condition number of the column-scaled regressor matrix.
    pub condition_number: f64,
    /// Number of linear constraints.
    pub constraints: usize,
    /// Number of constraints active at the final parameters: holding with equality within
    /// [`ACTIVE_TOLERANCE`](crate::problem::ACTIVE_TOLERANCE) (normalised slope units).
    pub active_constraints: usize,
    /// Number of constraints violated at the final parameters by more than
    /// [`ACTIVE_TOLERANCE`](crate::problem::ACTIVE_TOLERANCE): 0 whenever the solver's answer
    /// is feasible to that tolerance, as the least-squares optimum is (a swarm's best particle
    /// may leave some violated; the model is still checked invertible before it is returned).
    /// Reports written before this field existed read as 0.
    #[serde(default)]
    pub violated_constraints: usize,
    /// The slope margin every constraint demands (normalised).
    pub margin: f64,
    /// The smallest branch slope of the model over its input range (the core's check).
    pub min_branch_slope: f64,
    /// Plant models: the gains of the delayed IHC and WIHC over the fitted voltage range
    /// (below 1: both delayed loops settle after any jump). `None` for inverse models.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delayed_loop_gains: Option<DelayedGains>,
    /// When both delayed loops were constrained (`--for-delayed`): the bound and what it cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delayed_constraint: Option<DelayedConstraint>,
    /// The swarm's settings, when the solver was `pso`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pso: Option<PsoOptions>,
    /// Wall-clock time of the identification, in seconds.
    pub elapsed_s: f64,
}
