//! Compensators from a model in memory, and the one-shot compensation of a whole trajectory.

use std::ffi::{c_char, c_int};

use hystcomp_io::compensator::{ScaledCompensator, UnstableDelay};

use crate::HystcompCompensator;
use crate::args::{check_array, clear_out, non_finite_failure, put_handle, write_out};
use crate::boundary::{Failure, boundary};
use crate::compensator::{method_arg, scaled, unstable_delay};
use crate::model::{HystcompModel, model_arg};

/// What a compensator did to a signal (`hystcomp_compensate`), counted over the signal, and the
/// limits it used.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HystcompDiagnostics {
    /// Samples whose desired position could not be reached within the limits (clamped).
    pub saturated: u64,
    /// Samples a delayed loop (`ihc-delayed`, `wihc-delayed`) drove to a limit although the
    /// desired position was reachable: the loop lagged or rang after a jump (0 for the exact
    /// methods and DIHC).
    pub loop_saturated: u64,
    /// NaN or infinite desired positions, or too large to normalise or for the model's creep
    /// or vibration links to follow (the previous output was held).
    pub non_finite: u64,
    /// The lower drive limit used, in the model's voltage unit.
    pub v_min: f64,
    /// The upper drive limit used, in the model's voltage unit.
    pub v_max: f64,
}

/// The compensator `method` (a name) of `model` within the limits (or the model's range).
///
/// # Safety
/// `method` must be a NUL-terminated string or NULL.
unsafe fn build(
    model: &HystcompModel,
    method: *const c_char,
    v_min: f64,
    v_max: f64,
    use_limits: c_int,
    unstable: UnstableDelay,
) -> Result<ScaledCompensator, Failure> {
    // SAFETY: NUL-terminated or NULL (the caller's contract).
    let method = unsafe { method_arg(method) }?;
    scaled(&model.file, method, v_min, v_max, use_limits, unstable)
}

/// Creates a compensator from a model in memory, in its physical units: desired position in,
/// drive voltage out. As `hystcomp_compensator_from_model_file`, without the file: `method` is
/// `"ihc"`, `"ihc-delayed"`, `"wihc"`, `"wihc-delayed"` (plant models) or `"dihc"` (inverse
/// models); with `use_limits != 0` the drive limits are `[v_min, v_max]` (the model's voltage
/// unit), otherwise the range the model was identified on. The model may be freed after.
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (unknown method, limits), `WRONG_DIRECTION`
/// or `NOT_INVERTIBLE` (over the limits).
///
/// # Safety
/// `m` must be a live model handle or NULL; `method` a NUL-terminated string or NULL; `out`
/// valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_from_model(
    m: *const HystcompModel,
    method: *const c_char,
    v_min: f64,
    v_max: f64,
    use_limits: c_int,
    out: *mut *mut HystcompCompensator,
) -> c_int {
    // SAFETY: the same contract.
    unsafe { hystcomp_compensator_from_model_with(m, method, v_min, v_max, use_limits, 0, out) }
}

/// As `hystcomp_compensator_from_model`, with `flags`: 0, or `HYSTCOMP_ALLOW_UNSTABLE_DELAY`
/// to build a plain delayed method (`ihc-delayed`, `wihc-delayed`) even when its loop gain
/// over the limits is 1 or more (as `hystcomp_compensator_from_model_file_with`). Other flag
/// bits are refused with `INVALID_ARGUMENT`.
///
/// # Safety
/// As `hystcomp_compensator_from_model`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_from_model_with(
    m: *const HystcompModel,
    method: *const c_char,
    v_min: f64,
    v_max: f64,
    use_limits: c_int,
    flags: c_int,
    out: *mut *mut HystcompCompensator,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        let unstable = unstable_delay(flags)?;
        // SAFETY: a live handle or NULL (the caller's contract).
        let model = unsafe { model_arg(m) }?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let inner = unsafe { build(model, method, v_min, v_max, use_limits, unstable) }?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, HystcompCompensator { inner }) };
        Ok(())
    })
}

/// One-shot compensation: the drive `v[k]` for every desired position `y_d[k]` of a whole
/// known trajectory, from the initial state (zero operator memory, eq. (1)), as a compensator
/// made by `hystcomp_compensator_from_model` and run by `hystcomp_compensator_process` would
/// give; for a model with a vibration link the drive is aligned with the trajectory (`v[k]` for
/// `y_d[k]`: the preview's lag removed, the trajectory held at its last value after its end).
/// `y_d` and `v` may be the same array (in place). Every `v[k]` lies within the limits and is
/// never NaN.
///
/// - `y_d_len` and `v_len` must be equal and not 0.
/// - `diagnostics`: receives the counts over the signal and the limits used (also when the
///   status is `NON_FINITE_INPUT`), or NULL when not wanted.
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (lengths differ or 0, unknown method, limits),
/// `WRONG_DIRECTION` or `NOT_INVERTIBLE` (then `v` is not written), or `NON_FINITE_INPUT` (the
/// whole signal was processed, NaN or infinite samples holding the previous output; the message
/// gives their count and the first index).
///
/// # Safety
/// `m` must be a live model handle or NULL; `method` a NUL-terminated string or NULL; `y_d`
/// must point to `y_d_len` readable doubles and `v` to `v_len` writable doubles (or be NULL);
/// `diagnostics` valid for one write or NULL.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn hystcomp_compensate(
    m: *const HystcompModel,
    method: *const c_char,
    v_min: f64,
    v_max: f64,
    use_limits: c_int,
    y_d: *const f64,
    y_d_len: usize,
    v: *mut f64,
    v_len: usize,
    diagnostics: *mut HystcompDiagnostics,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let model = unsafe { model_arg(m) }?;
        if y_d.is_null() {
            return Err(Failure::null("y_d"));
        }
        if v.is_null() {
            return Err(Failure::null("v"));
        }
        if y_d_len == 0 {
            return Err(Failure::invalid(
                "y_d is empty (length 0); give at least one desired position",
            ));
        }
        if v_len != y_d_len {
            return Err(Failure::invalid(format!(
                "y_d has {y_d_len} samples but v has room for {v_len}; give arrays of equal length"
            )));
        }
        check_array(y_d, y_d_len, "y_d")?;
        check_array(v, v_len, "v")?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let mut compensator = unsafe {
            build(
                model,
                method,
                v_min,
                v_max,
                use_limits,
                UnstableDelay::Refuse,
            )
        }?;
        // SAFETY: `y_d_len` readable doubles (the caller's contract), non-NULL and aligned
        // (checked); copied before `v` is written, so the two may be the same array.
        let desired = unsafe { std::slice::from_raw_parts(y_d, y_d_len) }.to_vec();
        let mut drive = vec![0.0; y_d_len];
        // The samples held: not finite, or too large for the model's scale or its links.
        let (count, first) = compensator.process_held(&desired, &mut drive)?;
        let first = first.unwrap_or(0);
        // SAFETY: `v` is valid for `v_len == drive.len()` writes (the caller's contract),
        // non-NULL and aligned (checked); `desired` is a copy.
        unsafe { std::ptr::copy_nonoverlapping(drive.as_ptr(), v, drive.len()) };
        if !diagnostics.is_null() {
            let d = compensator.diagnostics();
            let (lo, hi) = compensator.limits();
            // SAFETY: non-NULL, valid for a write (the caller's contract).
            unsafe {
                diagnostics.write(HystcompDiagnostics {
                    saturated: d.saturated,
                    loop_saturated: d.loop_saturated,
                    non_finite: d.non_finite,
                    v_min: lo,
                    v_max: hi,
                })
            };
        }
        if count == 0 {
            Ok(())
        } else {
            Err(non_finite_failure(count, first, "desired position"))
        }
    })
}

/// Writes the vibration inverse's preview, in samples, to `*samples`: 0 for a model without a
/// vibration link. Streaming (`hystcomp_compensator_step`, `hystcomp_compensator_process`),
/// the drive returned lags the desired position fed by this many samples;
/// `hystcomp_compensate` removes the lag for a whole known trajectory.
///
/// Fails with `NULL_POINTER`.
///
/// # Safety
/// `h` must be a live handle or NULL; `samples` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_preview(
    h: *const HystcompCompensator,
    samples: *mut usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let c = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("compensator handle"))?;
        // SAFETY: valid for a write or NULL (checked by write_out).
        unsafe { write_out(samples, c.inner.preview(), "samples") }
    })
}
