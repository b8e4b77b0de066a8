//! The between-trials update (see the [crate documentation](crate) for the law).

use hystcomp_indices::TrackingIndices;
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::{Direction, ModelFile};
use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::amplifier::{
    AntiWindup, AntiWindupLaw, amplifier_output, delivered_drive, slew_feasible_drive,
};
use crate::filter::LearningFilter;
use crate::options::{Inverse, LearningOptions, MAX_TRIAL_SAMPLES};
use crate::slew::project_slew;

/// Periods a periodic record is run for to reach the hysteresis' periodic state: the drive
/// and the recovered reference are taken from the middle one (the play operators' memory is
/// periodic after one period; the middle period also keeps a vibration inverse's preview
/// inside the signal).
const PERIODIC_PASSES: usize = 3;

/// How the learning law is set, as reported with every update.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearningLaw {
    /// `gamma` in `L = gamma z^m`.
    pub gain: f64,
    /// `m`, samples.
    pub lead_samples: usize,
    /// `Q`'s cut-off, Hz.
    pub bandwidth_hz: f64,
    /// `Q`'s order `n`.
    pub filter_order: usize,
    /// Whether the records are periodic (circular filtering).
    pub periodic: bool,
    /// Zeros padded on each side of a finite record.
    pub padding_samples: usize,
    /// `mean (gamma Q)^2`: the share of white sensor noise's variance one update passes into
    /// the learned reference.
    pub noise_gain: f64,
    /// The stationary variance of the learned reference's noise, relative to the sensor
    /// noise's, for white noise and a model whose slope is right: `sum over f of (gamma Q)^2 /
    /// (1 - (1 - gamma Q)^2)`, averaged over the band (bounded: the noise does not grow trial
    /// after trial; see the crate documentation). `None` when `gamma Q` reaches 2 somewhere:
    /// there the update does not contract, and the noise (like the error) grows.
    pub stationary_noise_ratio: Option<f64>,
    /// The divergence factor.
    pub divergence_factor: f64,
    /// The exact inverse the reference is fed to.
    pub inverse: Inverse,
    /// The drive limits, model voltage unit.
    pub limits: (f64, f64),
    /// Whether the model has a vibration link (the compensator then inverts the stage's
    /// dynamics and the learning may reach higher).
    pub model_has_vibration: bool,
    /// The largest drive step per sample the drive is projected within
    /// ([`LearningOptions::max_drive_step`]); `None`: not projected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_drive_step: Option<f64>,
    /// The anti-windup against the amplifier's slew limit ([`LearningOptions::anti_windup`]);
    /// `None`: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anti_windup: Option<AntiWindup>,
}

/// What stopped the learning, if anything.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum Status {
    /// Learning goes on.
    Learning,
    /// The divergence guard tripped on this trial: its e_rms exceeded the factor times the
    /// best trial's; the drive is the best trial's and further updates are refused.
    Diverged {
        /// The trial's e_rms, %.
        e_rms_percent: f64,
        /// The best trial so far.
        best_trial: usize,
        /// Its e_rms, %.
        best_e_rms_percent: f64,
        /// The factor.
        factor: f64,
    },
}

/// One trial's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Update {
    /// The trial just measured (0: the starting drive).
    pub trial: usize,
    /// Its indices (% of the desired range) over the whole record.
    pub indices: TrackingIndices,
    /// The indices predicted for the next trial by the learning law's linear model
    /// (`e_next = e - z^-m [r_next - r]`: the stage follows a change of reference after the
    /// lead), noise of this trial included. `None` when the guard stopped the learning.
    pub predicted: Option<TrackingIndices>,
    /// Samples of the next reference clamped into the range the model reaches within the
    /// drive limits (anti-windup).
    pub clamped_samples: usize,
    /// Whether learning goes on.
    pub status: Status,
}

/// The iterative learning update between trials of a repeated motion (see the
/// [crate documentation](crate)).
#[derive(Debug, Clone)]
pub struct Learner {
    model: ModelFile,
    options: LearningOptions,
    law: LearningLaw,
    desired: Vec<f64>,
    reference: Vec<f64>,
    drive: Vec<f64>,
    best: Option<(usize, f64, Vec<f64>)>,
    history: Vec<TrackingIndices>,
    reachable: (f64, f64),
    filter: LearningFilter,
    correction: Vec<f64>,
    stopped: Option<(usize, usize)>,
}

fn check_finite(what: &'static str, values: &[f64]) -> Result<(), LearnError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(LearnError::NonFinite { what, index }),
        None => Ok(()),
    }
}

fn check_length(what: &'static str, expected: usize, values: &[f64]) -> Result<(), LearnError> {
    if values.len() == expected {
        Ok(())
    } else {
        Err(LearnError::Length {
            what,
            expected,
            found: values.len(),
        })
    }
}

impl Learner {
    /// A learner for `desired` (the model's displacement unit) starting from the compensator's
    /// own drive for it (trial 0 runs `C[y_d]`).
    pub fn new(
        model: &ModelFile,
        desired: &[f64],
        options: LearningOptions,
    ) -> Result<Learner, LearnError> {
        Self::build(model, desired, None, options)
    }

    /// A learner resuming from `drive`, the drive of the trial about to be measured (any
    /// compensator's, or a previous learner's output): the reference it follows is recovered
    /// by running the model forward over it (exact for IHC and WIHC, whose drive the model maps
    /// back onto the reference, `P[C[r]] = r`).
    pub fn resume(
        model: &ModelFile,
        desired: &[f64],
        drive: &[f64],
        options: LearningOptions,
    ) -> Result<Learner, LearnError> {
        Self::build(model, desired, Some(drive), options)
    }

    fn build(
        model: &ModelFile,
        desired: &[f64],
        drive: Option<&[f64]>,
        options: LearningOptions,
    ) -> Result<Learner, LearnError> {
        options.validate()?;
        if model.direction != Direction::Plant {
            return Err(LearnError::Model(
                "learning needs a plant model (voltage -> displacement): the model run forward \
                 over a drive recovers the reference it followed; identify one with \
                 `hystcomp identify --direction plant` (a DIHC drive can still be the starting \
                 drive)"
                    .into(),
            ));
        }
        if desired.len() < 2 || desired.len() > MAX_TRIAL_SAMPLES {
            return Err(LearnError::Option {
                option: "desired trajectory",
                value: format!("{} samples", desired.len()),
                reason: format!("a trial has 2 to {MAX_TRIAL_SAMPLES} samples"),
            });
        }
        check_finite("desired", desired)?;
        let n = desired.len();
        let most_bins = (n / 10).max(1);
        if options.mhe_bins > most_bins {
            return Err(LearnError::Option {
                option: "e_mhe bins",
                value: options.mhe_bins.to_string(),
                reason: format!(
                    "a trial of {n} samples supports at most {most_bins} bins (10 samples per \
                     bin on average; with fewer, e_mhe underestimates the loop)"
                ),
            });
        }
        if options.lead_samples >= n {
            return Err(LearnError::Option {
                option: "lead",
                value: options.lead_samples.to_string(),
                reason: format!("give fewer samples than the trial's {n}"),
            });
        }
        let compensator = Self::compensator(model, &options)?;
        let limits = compensator.limits();
        let has_vibration = model.vibration.is_some();
        let bandwidth_hz = options.resolved_bandwidth_hz(has_vibration);
        let filter = LearningFilter::new(
            n,
            options.periodic,
            options.sample_rate_hz,
            options.gain,
            bandwidth_hz,
            options.filter_order,
            options.lead_samples,
        );
        let reachable = reachable_range(model, limits)?;
        let law = LearningLaw {
            gain: options.gain,
            lead_samples: options.lead_samples,
            bandwidth_hz,
            filter_order: options.filter_order,
            periodic: options.periodic,
            padding_samples: filter.padding(),
            noise_gain: filter.noise_gain(),
            stationary_noise_ratio: stationary_noise_ratio(&options, bandwidth_hz),
            divergence_factor: options.divergence_factor,
            inverse: options.inverse,
            limits,
            model_has_vibration: has_vibration,
            max_drive_step: options.max_drive_step,
            anti_windup: options.anti_windup,
        };
        let mut learner = Learner {
            model: model.clone(),
            options,
            law,
            desired: desired.to_vec(),
            reference: Vec::new(),
            drive: Vec::new(),
            best: None,
            history: Vec::new(),
            reachable,
            filter,
            correction: vec![0.0; n],
            stopped: None,
        };
        match drive {
            Some(drive) => {
                check_length("drive", n, drive)?;
                check_finite("drive", drive)?;
                let (lo, hi) = limits;
                if let Some(index) = drive.iter().position(|v| *v < lo || *v > hi) {
                    return Err(LearnError::Option {
                        option: "drive",
                        value: format!("{} at sample {index}", drive[index]),
                        reason: format!(
                            "the drive leaves the limits {lo} .. {hi}; give the limits it was \
                             made with"
                        ),
                    });
                }
                learner.reference = learner.state_of(drive)?;
                learner.drive = drive.to_vec();
            }
            None => {
                learner.reference = desired
                    .iter()
                    .map(|y| y.clamp(reachable.0, reachable.1))
                    .collect();
                learner.drive = learner.inverse(&learner.reference)?;
                if learner.resets_state() {
                    learner.reference = learner.state_of(&learner.drive)?;
                }
            }
        }
        Ok(learner)
    }

    fn compensator(
        model: &ModelFile,
        options: &LearningOptions,
    ) -> Result<ScaledCompensator, LearnError> {
        let method = match options.inverse {
            Inverse::Ihc => Method::Ihc,
            Inverse::Wihc => Method::Wihc,
        };
        Ok(ScaledCompensator::new(model, method, options.limits)?)
    }

    fn passes(&self) -> usize {
        if self.options.periodic {
            PERIODIC_PASSES
        } else {
            1
        }
    }

    /// `C[r]`: the drive for a reference, from the middle period of a periodic record.
    fn inverse(&self, reference: &[f64]) -> Result<Vec<f64>, LearnError> {
        let n = reference.len();
        let passes = self.passes();
        let input: Vec<f64> = (0..passes)
            .flat_map(|_| reference.iter().copied())
            .collect();
        let mut out = vec![0.0; input.len()];
        let mut c = Self::compensator(&self.model, &self.options)?;
        c.process(&input, &mut out)?;
        let start = (passes / 2) * n;
        let (lo, hi) = self.law.limits;
        let drive: Vec<f64> = out[start..start + n]
            .iter()
            .map(|v| v.clamp(lo, hi))
            .collect();
        let drive = match self.options.max_drive_step {
            Some(r) => project_slew(&drive, r, (lo, hi), self.options.periodic).drive,
            None => drive,
        };
        Ok(match self.options.anti_windup {
            Some(AntiWindup {
                amplifier,
                law: AntiWindupLaw::Projected { margin },
            }) => slew_feasible_drive(
                &amplifier,
                self.options.sample_rate_hz,
                &drive,
                (lo, hi),
                self.options.periodic,
                margin,
            ),
            _ => drive,
        })
    }

    /// `P[v]`: the reference a drive follows, from the middle period of a periodic record.
    fn forward(&self, drive: &[f64]) -> Result<Vec<f64>, LearnError> {
        let n = drive.len();
        let passes = self.passes();
        let input: Vec<f64> = (0..passes).flat_map(|_| drive.iter().copied()).collect();
        let out = self.model.predict(&input)?;
        let start = (passes / 2) * n;
        Ok(out[start..start + n].to_vec())
    }

    /// Whether the learner's state is the reference of a drive other than `C[r]` itself (the
    /// slew-projected one, or what the amplifier delivers of it).
    fn resets_state(&self) -> bool {
        self.options.max_drive_step.is_some()
            || self.options.anti_windup.is_some_and(|aw| aw.resets_state())
    }

    /// The learner's state for a drive: the reference the model follows for it (`P[v]`), or
    /// with a resetting [`LearningOptions::anti_windup`] for what the amplifier delivers of it
    /// (`P[A^-1[A[v]]]`).
    fn state_of(&self, drive: &[f64]) -> Result<Vec<f64>, LearnError> {
        match &self.options.anti_windup {
            Some(aw) if aw.resets_state() => self.forward(&delivered_drive(
                &aw.amplifier,
                self.options.sample_rate_hz,
                drive,
                self.options.periodic,
            )),
            _ => self.forward(drive),
        }
    }

    /// Restores what earlier trials measured, for a learner resumed from files
    /// ([`Learner::resume`]): their indices (the next update is trial `history.len()`) and the
    /// best of them with its drive (the last good drive, which the divergence guard falls back
    /// to). Refuses a best trial beyond the history, a drive of another length, outside the
    /// limits or not finite.
    pub fn restore_history(
        &mut self,
        history: &[TrackingIndices],
        best: Option<(usize, &[f64])>,
    ) -> Result<(), LearnError> {
        if let Some((trial, drive)) = best {
            if trial >= history.len() {
                return Err(LearnError::Option {
                    option: "best trial",
                    value: trial.to_string(),
                    reason: format!("the history holds {} trials", history.len()),
                });
            }
            check_length("best drive", self.desired.len(), drive)?;
            check_finite("best drive", drive)?;
            let (lo, hi) = self.law.limits;
            if drive.iter().any(|v| *v < lo || *v > hi) {
                return Err(LearnError::Option {
                    option: "best drive",
                    value: "a sample".into(),
                    reason: format!("it leaves the limits {lo} .. {hi}"),
                });
            }
            self.best = Some((trial, history[trial].e_rms_percent, drive.to_vec()));
        } else {
            self.best = None;
        }
        self.history = history.to_vec();
        Ok(())
    }

    /// The drive of the next trial (model voltage unit): within the limits, never NaN. After
    /// the divergence guard tripped, the best trial's drive.
    pub fn drive(&self) -> &[f64] {
        &self.drive
    }

    /// The reference the compensator follows in the next trial (model displacement unit).
    pub fn reference(&self) -> &[f64] {
        &self.reference
    }

    /// The desired trajectory.
    pub fn desired(&self) -> &[f64] {
        &self.desired
    }

    /// The best trial measured so far and its drive (the last good drive), if any.
    pub fn best(&self) -> Option<(usize, &[f64])> {
        self.best.as_ref().map(|(t, _, d)| (*t, d.as_slice()))
    }

    /// The indices of every trial measured so far.
    pub fn history(&self) -> &[TrackingIndices] {
        &self.history
    }

    /// The learning law in force.
    pub fn law(&self) -> &LearningLaw {
        &self.law
    }

    /// The options.
    pub fn options(&self) -> &LearningOptions {
        &self.options
    }

    /// Whether the divergence guard stopped the learning.
    pub fn is_stopped(&self) -> bool {
        self.stopped.is_some()
    }

    /// The trial's measured response (aligned with the desired trajectory and the drive) in;
    /// the next drive is then [`Learner::drive`]. Refuses records of another length or with a
    /// non-finite sample, and every update after the divergence guard stopped the learning.
    pub fn update(&mut self, measured: &[f64]) -> Result<Update, LearnError> {
        if let Some((trial, best_trial)) = self.stopped {
            return Err(LearnError::Stopped { trial, best_trial });
        }
        let n = self.desired.len();
        check_length("measured", n, measured)?;
        check_finite("measured", measured)?;
        let indices = TrackingIndices::compute(&self.desired, measured, self.options.mhe_bins)?;
        let trial = self.history.len();
        self.history.push(indices);
        let e_rms = indices.e_rms_percent;
        if let Some((best_trial, best_e_rms, best_drive)) = &self.best
            && e_rms > self.options.divergence_factor * best_e_rms
        {
            let status = Status::Diverged {
                e_rms_percent: e_rms,
                best_trial: *best_trial,
                best_e_rms_percent: *best_e_rms,
                factor: self.options.divergence_factor,
            };
            self.drive = best_drive.clone();
            self.reference = self.state_of(&self.drive)?;
            self.stopped = Some((trial, *best_trial));
            return Ok(Update {
                trial,
                indices,
                predicted: None,
                clamped_samples: 0,
                status,
            });
        }
        if self.best.as_ref().is_none_or(|(_, b, _)| e_rms <= *b) {
            self.best = Some((trial, e_rms, self.drive.clone()));
        }
        let error: Vec<f64> = self
            .desired
            .iter()
            .zip(measured)
            .map(|(d, y)| d - y)
            .collect();
        let mut error = error;
        if let Some(AntiWindup {
            amplifier,
            law: AntiWindupLaw::Conditional,
        }) = &self.options.anti_windup
        {
            let fs = self.options.sample_rate_hz;
            let u = amplifier_output(amplifier, fs, &self.drive, self.options.periodic);
            let full = amplifier.slew_rate_per_s / fs * (1.0 - 1e-9);
            for k in 0..n {
                let before = match k {
                    0 if self.options.periodic => u[n - 1],
                    0 => 0.0,
                    _ => u[k - 1],
                };
                let step = u[k] - before;
                if step.abs() >= full && error[k] * step > 0.0 {
                    error[k] = 0.0;
                }
            }
        }
        self.filter.apply(&error, &mut self.correction);
        let (lo, hi) = self.reachable;
        let mut clamped_samples = 0;
        let next: Vec<f64> = self
            .reference
            .iter()
            .zip(&self.correction)
            .map(|(r, c)| {
                let value = r + c;
                if value < lo || value > hi {
                    clamped_samples += 1;
                }
                value.clamp(lo, hi)
            })
            .collect();
        // e_next = e - z^-m (r_next - r): the change arrives `m` samples later.
        let m = self.options.lead_samples;
        // Constrained: the drive is the slew-feasible projection of `C[next]` and the reference
        // the model's response to it, what the next trial actually follows (crate::slew).
        // With the amplifier's specification, the reference of what it delivers of that drive
        // (crate::amplifier: the undeliverable correction dropped, not accumulated).
        let drive = self.inverse(&next)?;
        let next = if self.resets_state() {
            self.state_of(&drive)?
        } else {
            next
        };
        let predicted_measured: Vec<f64> = (0..n)
            .map(|k| {
                let change = if k >= m {
                    next[k - m] - self.reference[k - m]
                } else if self.options.periodic {
                    next[k + n - m] - self.reference[k + n - m]
                } else {
                    0.0
                };
                measured[k] + change
            })
            .collect();
        let predicted =
            TrackingIndices::compute(&self.desired, &predicted_measured, self.options.mhe_bins)?;
        self.drive = drive;
        self.reference = next;
        Ok(Update {
            trial,
            indices,
            predicted: Some(predicted),
            clamped_samples,
            status: Status::Learning,
        })
    }
}

/// The displacements the model reaches within the drive limits: from zero memory, the lower
/// limit, then the upper (the ascending branch from the bottom).
fn reachable_range(model: &ModelFile, limits: (f64, f64)) -> Result<(f64, f64), LearnError> {
    let mut mpim = model.model()?;
    let map = model
        .core_output_map()
        .map_err(hystcomp_io::model_file::ModelFileError::from)?;
    let lo = model.hysteresis_output_to_physical(&map, mpim.step(model.normalise_input(limits.0)));
    let hi = model.hysteresis_output_to_physical(&map, mpim.step(model.normalise_input(limits.1)));
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(LearnError::Model(format!(
            "the model's displacement at the drive limits ({lo} .. {hi}) is not an increasing \
             range; check the model and the limits"
        )));
    }
    Ok((lo, hi))
}

/// `mean over f of v(f)` with `v = (gamma Q)^2 / (1 - (1 - gamma Q)^2)` where the update
/// contracts (`0 < gamma Q < 2`), the stationary variance of the reference's noise per unit
/// of white sensor-noise variance (scalar recursion `d_k+1 = (1 - g) d_k + g n_k`); 0 where
/// `Q` vanishes. Evaluated on a fine grid up to half the sample rate.
fn stationary_noise_ratio(options: &LearningOptions, bandwidth_hz: f64) -> Option<f64> {
    const GRID: usize = 4096;
    let nyquist = options.sample_rate_hz / 2.0;
    let mut sum = 0.0;
    for i in 0..GRID {
        let f = (i as f64 + 0.5) / GRID as f64 * nyquist;
        let g = options.gain * crate::filter::q_response(f, bandwidth_hz, options.filter_order);
        sum += if g <= 0.0 {
            0.0
        } else if g < 2.0 {
            g / (2.0 - g)
        } else {
            f64::INFINITY
        };
    }
    let ratio = sum / GRID as f64;
    ratio.is_finite().then_some(ratio)
}
