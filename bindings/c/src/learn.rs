//! Learning from repetition (`hystcomp_learn::Learner`): a real-time board runs the drive of a
//! trial, records the response, and between cycles asks the learner for the next trial's
//! drive.

use std::ffi::c_int;

use hystcomp_learn::{
    DEFAULT_DIVERGENCE_FACTOR, DEFAULT_FILTER_ORDER, DEFAULT_GAIN, Inverse, LearnError, Learner,
    LearningOptions, MAX_TRIAL_SAMPLES, Status,
};

use crate::HystcompStatus;
use crate::args::{clear_out, doubles, handle, put_handle, write_out};
use crate::boundary::{Failure, boundary};
use crate::model::{HystcompModel, model_arg};

/// The most samples one trial may have (5 000 000: 500 s at 10 kHz), checked before anything
/// is read or allocated. A learner holds about ten copies of a trial (records, reference,
/// drives, the filter's spectra): about 600 MB at the bound.
pub const HYSTCOMP_MAX_TRIAL_SAMPLES: usize = MAX_TRIAL_SAMPLES;

/// A learner of a repeated motion (opaque): the drive of the next trial from the measured
/// response of the last (see `hystcomp_learner_new`). Released by `hystcomp_learner_free`.
pub struct HystcompLearner {
    inner: Learner,
}

/// The learning law's options (`hystcomp_learn::LearningOptions`). Fill it with
/// `hystcomp_learning_options_default`, then change what you need. Zero in `gain`,
/// `bandwidth_hz`, `filter_order`, `divergence_factor` or `mhe_bins` means the default.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct HystcompLearningOptions {
    /// The records' sample rate, Hz (above 0, at most 1e7).
    pub sample_rate_hz: f64,
    /// Nonzero: each trial is one whole period of a periodic motion (filters wrap around);
    /// 0: a finite motion repeated from rest.
    pub periodic: c_int,
    /// The learning gain `gamma` (0 < gain <= 10; default 0.8; above 2 diverges even on a
    /// perfect model, and the divergence guard stops it).
    pub gain: f64,
    /// The cut-off of the zero-phase filter `Q`, Hz (at most half the sample rate); 0: a
    /// hundredth of the sample rate, a tenth for a model with a vibration link.
    pub bandwidth_hz: f64,
    /// The order of `Q` (1 to 8; 0: 4).
    pub filter_order: usize,
    /// The phase lead of the learning, samples (0 to 1000).
    pub lead_samples: usize,
    /// A trial whose e_rms exceeds this factor times the best trial's stops the learning (above
    /// 1, at most 100; 0: 1.5).
    pub divergence_factor: f64,
    /// The exact inverse the learned reference is fed to: 0 = IHC, 1 = WIHC.
    pub inverse: c_int,
    /// Nonzero: the drive limits are `v_min`, `v_max` (the model's voltage unit); 0: the range
    /// the model was identified on.
    pub use_limits: c_int,
    /// The lower drive limit (with `use_limits`).
    pub v_min: f64,
    /// The upper drive limit (with `use_limits`).
    pub v_max: f64,
    /// Bins of the desired range for e_mhe (at most a tenth of the trial's samples); 0: 100.
    pub mhe_bins: usize,
}

/// One trial's outcome, written by `hystcomp_learner_update`. Indices in % of the desired
/// range.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct HystcompLearningUpdate {
    /// The trial just measured (0: the first drive).
    pub trial: usize,
    /// Its RMS tracking error, (D2), %.
    pub e_rms_percent: f64,
    /// Its largest tracking error, (D1), %.
    pub e_m_percent: f64,
    /// Its maximum hysteresis error, eq. (12), %.
    pub e_mhe_percent: f64,
    /// Nonzero when the next trial's indices are predicted (not after the guard tripped).
    pub has_prediction: c_int,
    /// The next trial's RMS error predicted by the law's linear model, %.
    pub predicted_e_rms_percent: f64,
    /// The next trial's largest error predicted, %.
    pub predicted_e_m_percent: f64,
    /// The next trial's e_mhe predicted, %.
    pub predicted_e_mhe_percent: f64,
    /// Samples of the next reference clamped into the range the model reaches within the
    /// limits.
    pub clamped_samples: usize,
    /// Nonzero when the divergence guard stopped the learning on this trial.
    pub diverged: c_int,
    /// The best trial so far, whose drive is kept when the guard trips.
    pub best_trial: usize,
}

/// The learning law in force (`hystcomp_learner_law`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct HystcompLearningLaw {
    /// `gamma`.
    pub gain: f64,
    /// `m`, samples.
    pub lead_samples: usize,
    /// `Q`'s cut-off, Hz.
    pub bandwidth_hz: f64,
    /// `Q`'s order.
    pub filter_order: usize,
    /// Nonzero for periodic trials.
    pub periodic: c_int,
    /// The stationary variance of the learned reference's noise relative to the sensor's
    /// (bounded: noise is not amplified trial after trial); negative when the update does not
    /// contract somewhere (`gamma Q >= 2`).
    pub stationary_noise_ratio: f64,
    /// The divergence factor.
    pub divergence_factor: f64,
    /// The drive limits, the model's voltage unit.
    pub v_min: f64,
    /// The upper drive limit.
    pub v_max: f64,
}

/// Writes the defaults at `sample_rate_hz` to `*out` (periodic trials, gain 0.8, `Q` of order
/// 4 at its default cut-off, no lead, divergence factor 1.5, IHC, the model's range, 100
/// bins).
///
/// Fails with `NULL_POINTER`.
///
/// # Safety
/// `out` must be valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learning_options_default(
    sample_rate_hz: f64,
    out: *mut HystcompLearningOptions,
) -> c_int {
    boundary(|| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let d = LearningOptions::new(sample_rate_hz);
        let options = HystcompLearningOptions {
            sample_rate_hz,
            periodic: 1,
            gain: d.gain,
            bandwidth_hz: 0.0,
            filter_order: d.filter_order,
            lead_samples: d.lead_samples,
            divergence_factor: d.divergence_factor,
            inverse: 0,
            use_limits: 0,
            v_min: 0.0,
            v_max: 0.0,
            mhe_bins: d.mhe_bins,
        };
        // SAFETY: non-NULL and valid for a write (the caller's contract).
        unsafe { out.write(options) };
        Ok(())
    })
}

fn options_arg(o: &HystcompLearningOptions) -> Result<LearningOptions, Failure> {
    let inverse = match o.inverse {
        0 => Inverse::Ihc,
        1 => Inverse::Wihc,
        other => {
            return Err(Failure::invalid(format!(
                "inverse {other} is not known: give 0 (IHC) or 1 (WIHC)"
            )));
        }
    };
    let or = |value: f64, default: f64| if value == 0.0 { default } else { value };
    let options = LearningOptions {
        sample_rate_hz: o.sample_rate_hz,
        periodic: o.periodic != 0,
        gain: or(o.gain, DEFAULT_GAIN),
        bandwidth_hz: (o.bandwidth_hz != 0.0).then_some(o.bandwidth_hz),
        filter_order: if o.filter_order == 0 {
            DEFAULT_FILTER_ORDER
        } else {
            o.filter_order
        },
        lead_samples: o.lead_samples,
        divergence_factor: or(o.divergence_factor, DEFAULT_DIVERGENCE_FACTOR),
        inverse,
        limits: (o.use_limits != 0).then_some((o.v_min, o.v_max)),
        mhe_bins: if o.mhe_bins == 0 {
            hystcomp_indices::DEFAULT_MHE_BINS
        } else {
            o.mhe_bins
        },
        // The slew-projected learned drive is measured worse on the built-in stage (README):
        // not offered through the C ABI yet.
        max_drive_step: None,
        anti_windup: None,
    };
    options.validate().map_err(learn_failure)?;
    Ok(options)
}

fn learn_failure(e: LearnError) -> Failure {
    match e {
        LearnError::Compensator(c) => Failure::from(c),
        LearnError::Stopped { .. } => Failure::new(HystcompStatus::LearningStopped, e.to_string()),
        other => Failure::invalid(other.to_string()),
    }
}

/// `n` (2 ..= HYSTCOMP_MAX_TRIAL_SAMPLES), checked before anything is read.
fn trial_length(n: usize) -> Result<(), Failure> {
    if !(2..=HYSTCOMP_MAX_TRIAL_SAMPLES).contains(&n) {
        return Err(Failure::invalid(format!(
            "a trial of {n} samples cannot be learned: give 2 to {HYSTCOMP_MAX_TRIAL_SAMPLES}"
        )));
    }
    Ok(())
}

/// The `n` doubles at `ptr`, refused when NULL or when one is NaN or infinite (naming it).
///
/// # Safety
/// As `doubles`.
unsafe fn finite<'a>(ptr: *const f64, n: usize, what: &'static str) -> Result<&'a [f64], Failure> {
    // SAFETY: the caller's contract.
    let values = unsafe { doubles(ptr, n, what) }?;
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(Failure::new(
            HystcompStatus::NonFiniteInput,
            format!(
                "{what}[{i}] = {} is not finite; nothing was changed",
                values[i]
            ),
        ));
    }
    Ok(values)
}

/// Creates a learner for one trial of `desired` (`n` samples, the model's displacement unit)
/// with a **plant** model: trial 0 runs the exact inverse's own drive for it
/// (`hystcomp_learner_drive`). Learning: after each trial, `hystcomp_learner_update` with the
/// measured response gives the next drive, `r_k+1 = sat(r_k + Q[gamma z^m e_k])` on the
/// reference the exact inverse follows (Leang & Devasia 2006, doi:10.1016/j.mechatronics.2005.11.006;
/// the law is `hystcomp-learn`'s).
///
/// Allocates (a learner holds about ten copies of a trial): build it, and update it, between
/// cycles, not in the control interrupt. The model is copied; it may be freed afterwards.
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (n outside 2 ..=
/// `HYSTCOMP_MAX_TRIAL_SAMPLES`, an option, an inverse model), `NON_FINITE_INPUT` (a NaN
/// desired sample), `WRONG_DIRECTION` or `NOT_INVERTIBLE`.
///
/// # Safety
/// `model` a live model handle or NULL; `desired` `n` readable doubles or NULL; `options`
/// readable or NULL; `out` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learner_new(
    model: *const HystcompModel,
    desired: *const f64,
    n: usize,
    options: *const HystcompLearningOptions,
    out: *mut *mut HystcompLearner,
) -> c_int {
    // SAFETY: the same contract, without a drive.
    unsafe { learner(model, desired, std::ptr::null(), n, options, out) }
}

/// As `hystcomp_learner_new`, resuming from `drive` (`n` samples within the limits): the drive
/// of the trial about to be measured (any compensator's, or a learner's saved earlier). The
/// reference it follows is recovered by running the model over it.
///
/// # Safety
/// As `hystcomp_learner_new`; `drive` `n` readable doubles or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learner_resume(
    model: *const HystcompModel,
    desired: *const f64,
    drive: *const f64,
    n: usize,
    options: *const HystcompLearningOptions,
    out: *mut *mut HystcompLearner,
) -> c_int {
    if drive.is_null() {
        return boundary(|| {
            // SAFETY: `out` is valid or NULL (the caller's contract).
            unsafe { clear_out(out) }?;
            Err(Failure::null("drive"))
        });
    }
    // SAFETY: the same contract.
    unsafe { learner(model, desired, drive, n, options, out) }
}

/// # Safety
/// As `hystcomp_learner_resume`, `drive` NULL for a new learner.
unsafe fn learner(
    model: *const HystcompModel,
    desired: *const f64,
    drive: *const f64,
    n: usize,
    options: *const HystcompLearningOptions,
    out: *mut *mut HystcompLearner,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: a live handle or NULL.
        let model = unsafe { model_arg(model) }?;
        // SAFETY: readable or NULL.
        let options = unsafe { options.as_ref() }.ok_or_else(|| Failure::null("options"))?;
        let options = options_arg(options)?;
        trial_length(n)?;
        // SAFETY: `n` readable doubles or NULL.
        let desired = unsafe { finite(desired, n, "desired") }?;
        let inner = if drive.is_null() {
            Learner::new(&model.file, desired, options)
        } else {
            // SAFETY: `n` readable doubles (checked non-NULL by the caller).
            let drive = unsafe { finite(drive, n, "drive") }?;
            Learner::resume(&model.file, desired, drive, options)
        }
        .map_err(learn_failure)?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, HystcompLearner { inner }) };
        Ok(())
    })
}

/// Copies the drive of the next trial (`n` samples, the model's voltage unit: within the
/// limits, never NaN) into `drive_out`. Does not allocate.
///
/// Fails with `NULL_POINTER` or `INVALID_ARGUMENT` (`n` is not the trial's length).
///
/// # Safety
/// `h` a live handle or NULL; `drive_out` valid for `n` writes or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learner_drive(
    h: *const HystcompLearner,
    drive_out: *mut f64,
    n: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL.
        let learner = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("learner handle"))?;
        // SAFETY: valid for `n` writes or NULL.
        unsafe { copy_drive(&learner.inner, drive_out, n) }
    })
}

/// # Safety
/// `drive_out` valid for `n` writes or NULL.
unsafe fn copy_drive(learner: &Learner, drive_out: *mut f64, n: usize) -> Result<(), Failure> {
    let drive = learner.drive();
    if n != drive.len() {
        return Err(Failure::invalid(format!(
            "the drive has {} samples, not {n}: pass the trial's length",
            drive.len()
        )));
    }
    if drive_out.is_null() {
        return Err(Failure::null("drive_out"));
    }
    if !drive_out.is_aligned() {
        return Err(Failure::invalid("drive_out is not aligned for doubles"));
    }
    // SAFETY: `n` writes (the caller's contract), non-NULL and aligned (checked); `drive` is
    // the learner's own memory, which cannot overlap a caller's array.
    unsafe { std::ptr::copy_nonoverlapping(drive.as_ptr(), drive_out, n) };
    Ok(())
}

/// The trial's measured response (`n` samples, aligned with the desired trajectory and the
/// drive that was sent) in; the next trial's drive out, into `drive_out` (`n` samples), and
/// the trial's indices into `*update` (or NULL). Allocates: call it between cycles.
///
/// When the divergence guard trips on this trial (its e_rms above the factor times the best
/// trial's), `drive_out` receives the best trial's drive (the last good one), `update->diverged`
/// is set and the call returns `HYSTCOMP_STATUS_LEARNING_STOPPED`; every later update is
/// refused with the same status, the learner unchanged.
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (`n` is not the trial's length),
/// `NON_FINITE_INPUT` (a NaN measured sample: nothing changed) or `LEARNING_STOPPED`.
///
/// # Safety
/// `h` a live handle or NULL, not used elsewhere meanwhile; `measured` `n` readable doubles or
/// NULL; `drive_out` valid for `n` writes or NULL (it may be the same array as `measured`);
/// `update` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learner_update(
    h: *mut HystcompLearner,
    measured: *const f64,
    n: usize,
    drive_out: *mut f64,
    update: *mut HystcompLearningUpdate,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL.
        let learner = unsafe { handle(h, "learner handle") }?;
        let expected = learner.inner.desired().len();
        if n != expected {
            return Err(Failure::invalid(format!(
                "the measured record has {n} samples but the trial has {expected}"
            )));
        }
        if drive_out.is_null() {
            return Err(Failure::null("drive_out"));
        }
        // Every argument checked before the learner moves: a refused call changes nothing,
        // so that a caller may fix the argument and call again.
        crate::args::check_array(drive_out, n, "drive_out")?;
        // SAFETY: `n` readable doubles or NULL. Copied before the drive is written: the two
        // arrays may be one.
        let measured = unsafe { finite(measured, n, "measured") }?.to_vec();
        let result = learner.inner.update(&measured).map_err(learn_failure)?;
        // SAFETY: valid for `n` writes (the caller's contract).
        unsafe { copy_drive(&learner.inner, drive_out, n) }?;
        let mut out = HystcompLearningUpdate {
            trial: result.trial,
            e_rms_percent: result.indices.e_rms_percent,
            e_m_percent: result.indices.e_m_percent,
            e_mhe_percent: result.indices.e_mhe_percent,
            clamped_samples: result.clamped_samples,
            best_trial: learner.inner.best().map_or(0, |(t, _)| t),
            ..Default::default()
        };
        if let Some(p) = result.predicted {
            out.has_prediction = 1;
            out.predicted_e_rms_percent = p.e_rms_percent;
            out.predicted_e_m_percent = p.e_m_percent;
            out.predicted_e_mhe_percent = p.e_mhe_percent;
        }
        let stopped = match result.status {
            Status::Learning => None,
            Status::Diverged {
                e_rms_percent,
                best_trial,
                best_e_rms_percent,
                factor,
            } => {
                out.diverged = 1;
                out.best_trial = best_trial;
                Some(format!(
                    "the divergence guard stopped the learning at trial {}: its e_rms {:.4} % \
                     exceeds {factor} times the best trial's ({best_trial}: {:.4} %); drive_out \
                     holds trial {best_trial}'s drive, the last good one; start again with a \
                     lower gain or bandwidth",
                    result.trial, e_rms_percent, best_e_rms_percent
                ))
            }
        };
        if !update.is_null() {
            // SAFETY: non-NULL, valid for one write (the caller's contract).
            unsafe { update.write(out) };
        }
        match stopped {
            Some(message) => Err(Failure::new(HystcompStatus::LearningStopped, message)),
            None => Ok(()),
        }
    })
}

/// The trial's length in samples, into `*n`.
///
/// # Safety
/// `h` a live handle or NULL; `n` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learner_samples(
    h: *const HystcompLearner,
    n: *mut usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL.
        let learner = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("learner handle"))?;
        // SAFETY: valid for one write or NULL (checked by write_out).
        unsafe { write_out(n, learner.inner.desired().len(), "n") }
    })
}

/// The learning law in force, into `*out`.
///
/// # Safety
/// `h` a live handle or NULL; `out` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learner_law(
    h: *const HystcompLearner,
    out: *mut HystcompLearningLaw,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL.
        let learner = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("learner handle"))?;
        let law = learner.inner.law();
        let value = HystcompLearningLaw {
            gain: law.gain,
            lead_samples: law.lead_samples,
            bandwidth_hz: law.bandwidth_hz,
            filter_order: law.filter_order,
            periodic: c_int::from(law.periodic),
            stationary_noise_ratio: law.stationary_noise_ratio.unwrap_or(-1.0),
            divergence_factor: law.divergence_factor,
            v_min: law.limits.0,
            v_max: law.limits.1,
        };
        // SAFETY: valid for one write or NULL (checked by write_out).
        unsafe { write_out(out, value, "out") }
    })
}

/// Releases a learner. NULL is accepted (and ignored).
///
/// # Safety
/// `h` a handle from `hystcomp_learner_new` or `hystcomp_learner_resume`, not used afterwards,
/// or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_learner_free(h: *mut HystcompLearner) {
    if !h.is_null() {
        // SAFETY: a handle from a constructor, released once (the caller's contract). A panic
        // in a destructor is not expected; it is caught so that nothing unwinds into C.
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| unsafe {
            drop(Box::from_raw(h))
        }));
    }
}
