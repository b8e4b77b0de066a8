//! What the learning update is asked to do, every value bounded before anything is allocated.

use hystcomp_core::Shown;
use hystcomp_indices::DEFAULT_MHE_BINS;
use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::amplifier::{AntiWindup, AntiWindupLaw};

/// The most samples one trial may have (5 000 000: 500 s at 10 kHz). The update holds about
/// ten copies of a trial in memory (the records, the learned reference, the drive, the best
/// drive and the filter's complex spectra): about 600 MB at the bound.
pub const MAX_TRIAL_SAMPLES: usize = 5_000_000;
/// The largest learning gain accepted. Above 2 the update diverges even on a perfect model
/// (`|1 - gain| > 1`); such gains are accepted so that the divergence guard can be seen
/// working, and it stops them.
pub const MAX_GAIN: f64 = 10.0;
/// The highest order of the robustness filter `Q`.
pub const MAX_FILTER_ORDER: usize = 8;
/// The longest phase lead, samples.
pub const MAX_LEAD_SAMPLES: usize = 1000;
/// The largest divergence factor accepted.
pub const MAX_DIVERGENCE_FACTOR: f64 = 100.0;
/// The default learning gain `gamma`.
pub const DEFAULT_GAIN: f64 = 0.8;
/// The default order of `Q`.
pub const DEFAULT_FILTER_ORDER: usize = 4;
/// The default divergence factor: a trial whose RMS error exceeds this times the best trial's
/// stops the learning.
pub const DEFAULT_DIVERGENCE_FACTOR: f64 = 1.5;

/// The compensator the learned reference is fed to (an exact inverse of a plant model, so that
/// the model run forward over a drive recovers the reference that produced it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Inverse {
    /// The exact IHC (eqs. (5)-(8)).
    Ihc,
    /// The exact WIHC (eq. (9)).
    Wihc,
}

/// The learning law's parameters (see the [crate documentation](crate)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearningOptions {
    /// The records' sample rate, Hz.
    pub sample_rate_hz: f64,
    /// `true`: the records are whole periods of a periodic motion, and the filters wrap around
    /// (the error at the end of the record continues at its start); `false`: a finite motion
    /// repeated from rest, filtered with zeros beyond its ends.
    pub periodic: bool,
    /// The learning gain `gamma` in `L = gamma z^m`, in (0, [`MAX_GAIN`]].
    pub gain: f64,
    /// The cut-off of the zero-phase robustness filter `Q`, Hz: learning acts below it.
    /// `None`: a hundredth of the sample rate for a model without a vibration link (below any
    /// stage resonance the model does not invert), a tenth with one (the vibration link is
    /// known only over the band it was identified on, well below the Nyquist frequency: the
    /// study's ends at 1.5 kHz at 10 kHz; a quarter diverged on the built-in stage, see the
    /// crate documentation).
    pub bandwidth_hz: Option<f64>,
    /// The order `n` of `Q(f) = 1 / (1 + (f / f_c)^(2n))`, 1 to [`MAX_FILTER_ORDER`].
    pub filter_order: usize,
    /// The phase lead `m` of `L`, samples (0 to [`MAX_LEAD_SAMPLES`]): the stage's delay
    /// between drive and measurement, if any.
    pub lead_samples: usize,
    /// A trial whose e_rms exceeds this factor times the best trial's stops the learning and
    /// keeps the best trial's drive; greater than 1, at most [`MAX_DIVERGENCE_FACTOR`].
    pub divergence_factor: f64,
    /// The exact inverse the learned reference is fed to.
    pub inverse: Inverse,
    /// The drive limits, in the model's voltage unit; `None`: the voltage range the model was
    /// identified on.
    pub limits: Option<(f64, f64)>,
    /// Bins of the `y_d` range for e_mhe.
    pub mhe_bins: usize,
    /// The largest drive step per sample the amplifier follows linearly (its slew rate over
    /// the sample rate, with a margin), in the model's voltage unit; `Some`: every trial's
    /// drive is projected onto the slew-feasible drives and the reference learned from the
    /// projected one (constrained ILC, see [`crate::slew`]); `None` (the default): the exact
    /// inverse's drive, whatever slew it asks.
    #[serde(default)]
    pub max_drive_step: Option<f64>,
    /// Anti-windup against the amplifier's slew limit ([`crate::amplifier`]); `None` (the
    /// default): the learner knows nothing of the amplifier. Measured on the learning study's
    /// 100 Hz raster, every law destabilises the learning (README, learning from repetition):
    /// not for use yet.
    #[serde(default)]
    pub anti_windup: Option<AntiWindup>,
}

impl LearningOptions {
    /// The defaults at `sample_rate_hz`.
    pub fn new(sample_rate_hz: f64) -> LearningOptions {
        LearningOptions {
            sample_rate_hz,
            periodic: true,
            gain: DEFAULT_GAIN,
            bandwidth_hz: None,
            filter_order: DEFAULT_FILTER_ORDER,
            lead_samples: 0,
            divergence_factor: DEFAULT_DIVERGENCE_FACTOR,
            inverse: Inverse::Ihc,
            limits: None,
            mhe_bins: DEFAULT_MHE_BINS,
            max_drive_step: None,
            anti_windup: None,
        }
    }

    /// Checks every value; the error names the option.
    pub fn validate(&self) -> Result<(), LearnError> {
        let bad = |option: &'static str, value: String, reason: String| {
            Err(LearnError::Option {
                option,
                value,
                reason,
            })
        };
        let fs = self.sample_rate_hz;
        if !(fs.is_finite() && fs > 0.0 && fs <= 1e7) {
            return bad(
                "sample rate",
                Shown(fs).to_string(),
                "give the records' sample rate in Hz, above 0 and at most 1e7".into(),
            );
        }
        if !(self.gain.is_finite() && self.gain > 0.0 && self.gain <= MAX_GAIN) {
            return bad(
                "gain",
                Shown(self.gain).to_string(),
                format!(
                    "give a learning gain above 0 and at most {MAX_GAIN} (default {DEFAULT_GAIN})"
                ),
            );
        }
        if let Some(fc) = self.bandwidth_hz
            && !(fc.is_finite() && fc > 0.0 && fc <= fs / 2.0)
        {
            return bad(
                "bandwidth",
                Shown(fc).to_string(),
                format!(
                    "give a cut-off in Hz above 0 and at most half the sample rate ({})",
                    fs / 2.0
                ),
            );
        }
        if !(1..=MAX_FILTER_ORDER).contains(&self.filter_order) {
            return bad(
                "filter order",
                self.filter_order.to_string(),
                format!("give 1 to {MAX_FILTER_ORDER}"),
            );
        }
        if self.lead_samples > MAX_LEAD_SAMPLES {
            return bad(
                "lead",
                self.lead_samples.to_string(),
                format!("give 0 to {MAX_LEAD_SAMPLES} samples"),
            );
        }
        let d = self.divergence_factor;
        if !(d.is_finite() && d > 1.0 && d <= MAX_DIVERGENCE_FACTOR) {
            return bad(
                "divergence factor",
                Shown(d).to_string(),
                format!(
                    "give a factor above 1 and at most {MAX_DIVERGENCE_FACTOR} (default {DEFAULT_DIVERGENCE_FACTOR})"
                ),
            );
        }
        if let Some((lo, hi)) = self.limits
            && !(lo.is_finite() && hi.is_finite() && lo < hi)
        {
            return bad(
                "drive limits",
                format!("{lo} .. {hi}"),
                "both must be finite and the lower below the upper".into(),
            );
        }
        if let Some(r) = self.max_drive_step
            && !(r.is_finite() && r > 0.0)
        {
            return bad(
                "largest drive step",
                Shown(r).to_string(),
                "give the largest drive step per sample, above 0 and finite".into(),
            );
        }
        if let Some(aw) = &self.anti_windup {
            let a = aw.amplifier;
            if !a.is_valid() {
                return bad(
                    "amplifier",
                    format!(
                        "bandwidth {} Hz, slew rate {} /s",
                        Shown(a.bandwidth_hz),
                        Shown(a.slew_rate_per_s)
                    ),
                    "give the amplifier's bandwidth and slew rate, both above 0 and finite".into(),
                );
            }
            if let AntiWindupLaw::Projected { margin } = aw.law
                && !(margin.is_finite() && margin > 0.0 && margin <= 1.0)
            {
                return bad(
                    "anti-windup margin",
                    Shown(margin).to_string(),
                    "give a share of the slew rate above 0 and at most 1".into(),
                );
            }
        }
        if self.mhe_bins == 0 {
            return bad("e_mhe bins", "0".into(), "give at least 1".into());
        }
        Ok(())
    }

    /// The cut-off of `Q` actually used, Hz, for a model with or without a vibration link.
    pub fn resolved_bandwidth_hz(&self, has_vibration: bool) -> f64 {
        self.bandwidth_hz.unwrap_or(if has_vibration {
            self.sample_rate_hz / 10.0
        } else {
            self.sample_rate_hz / 100.0
        })
    }
}
