//! Compensators: desired position in, drive voltage out (IHC, WIHC, DIHC).

use std::ffi::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

use hystcomp_io::compensator::{Method, ScaledCompensator, UnstableDelay};
use hystcomp_io::model_file::{Direction, ModelFile, ModelFileError};

use crate::args::{
    clear_out, handle, non_finite_failure, normalised_scale, parameters, path_arg, put_handle,
    run_signal, str_arg, write_out,
};
use crate::boundary::{Failure, boundary};
use crate::{HYSTCOMP_ALLOW_UNSTABLE_DELAY, HystcompStatus};

/// A feedforward compensator: desired position in, drive voltage out (opaque).
///
/// Created by `hystcomp_compensator_from_model_file` or `hystcomp_compensator_from_model`
/// (physical units of the model) or `hystcomp_compensator_from_parameters` (normalised units),
/// released by `hystcomp_compensator_free`.
pub struct HystcompCompensator {
    pub(crate) inner: ScaledCompensator,
}

/// Creates a compensator from a model file, in the file's physical units: desired position in
/// (e.g. um), drive voltage out (e.g. V).
///
/// - `path`: the JSON model file (e.g. `models/table1-plant.json`).
/// - `method`: `"ihc"`, `"ihc-delayed"`, `"wihc"`, `"wihc-delayed"`, `"ihc-guarded"`,
///   `"wihc-guarded"` (plant models) or `"dihc"` (inverse models), case-insensitive.
/// - `v_min`, `v_max`, `use_limits`: with `use_limits != 0`, the drive limits in the model's
///   voltage unit (finite, `v_min < v_max`); with `use_limits == 0` they are ignored and the
///   range the model was identified on is used.
/// - `out`: receives the handle (NULL on failure). Free it with `hystcomp_compensator_free`.
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (unknown method, limits), `IO` (missing
/// file), `INVALID_MODEL_FILE`, `WRONG_DIRECTION`, `NOT_INVERTIBLE` (over the limits) or
/// `UNSTABLE_DELAY` (a plain delayed method whose loop can oscillate; see
/// `hystcomp_compensator_from_model_file_with`).
///
/// # Safety
/// `path` and `method` must be NUL-terminated strings or NULL; `out` must be valid for one
/// write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_from_model_file(
    path: *const c_char,
    method: *const c_char,
    v_min: f64,
    v_max: f64,
    use_limits: c_int,
    out: *mut *mut HystcompCompensator,
) -> c_int {
    // SAFETY: the same contract.
    unsafe {
        hystcomp_compensator_from_model_file_with(path, method, v_min, v_max, use_limits, 0, out)
    }
}

/// As `hystcomp_compensator_from_model_file`, with `flags`: 0, or
/// `HYSTCOMP_ALLOW_UNSTABLE_DELAY` to build a plain delayed method (`ihc-delayed`,
/// `wihc-delayed`) even when its loop gain over the limits is 1 or more (the explicit
/// override: the drive still never leaves the limits, but may ring between them after a jump
/// in the desired position). Other flag bits are refused with `INVALID_ARGUMENT`.
///
/// # Safety
/// As `hystcomp_compensator_from_model_file`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_from_model_file_with(
    path: *const c_char,
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
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let path = unsafe { path_arg(path, "path") }?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let method = unsafe { method_arg(method) }?;
        let file = ModelFile::load(&path)?;
        let inner = scaled(&file, method, v_min, v_max, use_limits, unstable)?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, HystcompCompensator { inner }) };
        Ok(())
    })
}

/// The method named by the NUL-terminated string `method` (`"ihc"`, `"wihc-guarded"`, ...).
///
/// # Safety
/// `method` must be a NUL-terminated string or NULL.
pub(crate) unsafe fn method_arg(method: *const c_char) -> Result<Method, Failure> {
    // SAFETY: NUL-terminated or NULL (the caller's contract).
    Ok(unsafe { str_arg(method, "method") }?.parse()?)
}

/// The compensator `method` of `file` within `[v_min, v_max]` when `use_limits != 0`,
/// otherwise the range the model was identified on: the one construction behind the file and
/// in-memory constructors and `hystcomp_compensate`.
pub(crate) fn scaled(
    file: &ModelFile,
    method: Method,
    v_min: f64,
    v_max: f64,
    use_limits: c_int,
    unstable: UnstableDelay,
) -> Result<ScaledCompensator, Failure> {
    let limits = (use_limits != 0).then_some((v_min, v_max));
    Ok(ScaledCompensator::with_unstable_delay(
        file, method, limits, unstable,
    )?)
}

/// The override the flags ask for.
pub(crate) fn unstable_delay(flags: c_int) -> Result<UnstableDelay, Failure> {
    match flags {
        0 => Ok(UnstableDelay::Refuse),
        HYSTCOMP_ALLOW_UNSTABLE_DELAY => Ok(UnstableDelay::Allow),
        other => Err(Failure::invalid(format!(
            "flags {other} are not known; give 0 or HYSTCOMP_ALLOW_UNSTABLE_DELAY (1)"
        ))),
    }
}

/// Creates a compensator from MPIM parameters in **normalised** units (eq. (4), eq. (11)):
/// desired position in and control out are both normalised.
///
/// - `thresholds`, `weights`: `n >= 1` values each (thresholds `>= 0`, increasing; all finite).
/// - `a1`, `a2`: the polynomial input function `g(x) = a1 x^3 + a2 x`.
/// - `method`: a `HystcompMethod`. IHC and WIHC take a plant model (normalised voltage in,
///   displacement out, e.g. Table 1); DIHC takes an inverse model (desired position in, voltage
///   out, e.g. Table 2) valid for desired positions in `[0, 1]` (clamped into it).
/// - `v_min`, `v_max`: the output limits (normalised; e.g. 0 and 1), finite, `v_min < v_max`.
///   IHC and WIHC check invertibility over them.
/// - `out`: receives the handle (NULL on failure).
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (n = 0 or above 10000, NaN, unsorted thresholds, limits,
/// unknown method) or `NOT_INVERTIBLE`.
///
/// # Safety
/// `thresholds` and `weights` must point to `n` doubles each or be NULL; `out` must be valid
/// for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_from_parameters(
    thresholds: *const f64,
    weights: *const f64,
    n: usize,
    a1: f64,
    a2: f64,
    method: c_int,
    v_min: f64,
    v_max: f64,
    out: *mut *mut HystcompCompensator,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: `n` doubles each or NULL (the caller's contract).
        let (thresholds, weights) = unsafe { parameters(thresholds, weights, n) }?;
        let method = usize::try_from(method)
            .ok()
            .and_then(|m| Method::ALL.get(m).copied())
            .ok_or_else(|| {
                Failure::invalid(format!(
                    "method {method} is not a HystcompMethod (0 = IHC, 1 = IHC delayed, \
                     2 = WIHC, 3 = WIHC delayed, 4 = DIHC, 5 = IHC guarded, 6 = WIHC guarded)"
                ))
            })?;
        let (input, output) = match method.needs() {
            Direction::Plant => ("normalised voltage", "normalised displacement"),
            Direction::Inverse => ("normalised displacement", "normalised voltage"),
        };
        let file = ModelFile::new(
            method.needs(),
            normalised_scale(input),
            normalised_scale(output),
            [0.0, 1.0],
            thresholds.to_vec(),
            weights.to_vec(),
            a1,
            a2,
        )
        .map_err(|e| match e {
            // The parameters themselves, not a file: report them as arguments.
            ModelFileError::Model(core) => Failure::from(core),
            other => Failure::from(other),
        })?;
        let inner = ScaledCompensator::new(&file, method, Some((v_min, v_max)))?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, HystcompCompensator { inner }) };
        Ok(())
    })
}

/// One sample: writes to `*v_out` the drive for the desired position `y_d`.
///
/// `*v_out` always lies within the compensator's limits and is never NaN. A NaN or infinite
/// `y_d` (or one so large that it overflows when normalised by the model's scale) holds the
/// previous output, writes it to `*v_out` and returns
/// `HYSTCOMP_STATUS_NON_FINITE_INPUT`. Never allocates on success.
///
/// # Safety
/// `h` must be a live handle or NULL; `v_out` must be valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_step(
    h: *mut HystcompCompensator,
    y_d: f64,
    v_out: *mut f64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let c = unsafe { handle(h, "compensator handle") }?;
        if v_out.is_null() {
            return Err(Failure::null("v_out"));
        }
        let (v, held) = c.inner.step_held(y_d);
        // SAFETY: non-NULL (checked above, before the state moves), valid for a write (the
        // caller's contract).
        unsafe { v_out.write(v) };
        if held {
            Err(Failure::new(
                HystcompStatus::NonFiniteInput,
                "the desired position is NaN or infinite (or too large to normalise by the \
                 model's scale, or for its creep or vibration links to follow); the previous \
                 output was held",
            ))
        } else {
            Ok(())
        }
    })
}

/// A whole signal: `v[k]` is the drive for `y_d[k]`, `k = 0 .. len - 1`, as `len` calls of
/// `hystcomp_compensator_step`. `y_d` and `v` may be the same array (in place). With `len == 0`
/// nothing is done and the arrays may be NULL.
///
/// Non-finite samples (and samples too large to normalise) hold the previous output; the
/// whole signal is still processed and `HYSTCOMP_STATUS_NON_FINITE_INPUT` is returned, with
/// their count and first index in the message.
///
/// # Safety
/// `h` must be a live handle or NULL; `y_d` must point to `len` readable doubles and `v` to
/// `len` writable doubles (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_process(
    h: *mut HystcompCompensator,
    y_d: *const f64,
    v: *mut f64,
    len: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let c = unsafe { handle(h, "compensator handle") }?;
        // SAFETY: `len` elements each, or NULL (the caller's contract).
        let (count, first) = unsafe { run_signal(y_d, v, len, |x| c.inner.step_held(x)) }?;
        if count == 0 {
            Ok(())
        } else {
            Err(non_finite_failure(count, first, "desired position"))
        }
    })
}

/// Back to the initial state: the operators' memory zero (eq. (1)), the previous output 0
/// clamped into the limits, the diagnostics cleared.
///
/// # Safety
/// `h` must be a live handle or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_reset(h: *mut HystcompCompensator) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        unsafe { handle(h, "compensator handle") }?.inner.reset();
        Ok(())
    })
}

/// Writes the output limits `[*v_min, *v_max]` (the model's voltage unit, or normalised for a
/// compensator made from parameters).
///
/// # Safety
/// `h` must be a live handle or NULL; `v_min` and `v_max` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_limits(
    h: *const HystcompCompensator,
    v_min: *mut f64,
    v_max: *mut f64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let c = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("compensator handle"))?;
        if v_min.is_null() || v_max.is_null() {
            return Err(Failure::null(if v_min.is_null() {
                "v_min"
            } else {
                "v_max"
            }));
        }
        let (lo, hi) = c.inner.limits();
        // SAFETY: non-NULL, valid for a write (the caller's contract).
        unsafe { write_out(v_min, lo, "v_min") }?;
        // SAFETY: as above.
        unsafe { write_out(v_max, hi, "v_max") }
    })
}

/// Writes the counters since the last reset: samples whose desired position could not be
/// reached within the limits (`*saturated`; a delayed loop's clamp of a reachable position is
/// counted by `hystcomp_compensator_loop_saturated` instead) and NaN or infinite samples
/// (`*non_finite`).
/// Either pointer may be NULL when that counter is not wanted.
///
/// # Safety
/// `h` must be a live handle or NULL; `saturated` and `non_finite` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_diagnostics(
    h: *const HystcompCompensator,
    saturated: *mut u64,
    non_finite: *mut u64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let c = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("compensator handle"))?;
        let d = c.inner.diagnostics();
        if !saturated.is_null() {
            // SAFETY: non-NULL, valid for a write (the caller's contract).
            unsafe { saturated.write(d.saturated) };
        }
        if !non_finite.is_null() {
            // SAFETY: as above.
            unsafe { non_finite.write(d.non_finite) };
        }
        Ok(())
    })
}

/// Writes the number of samples, since the last reset, that a delayed loop (`ihc-delayed`,
/// `wihc-delayed`) drove to a drive limit although the desired position was reachable within
/// the limits: the loop lagged or rang after a jump (always 0 for the exact methods and DIHC).
/// Those samples are not counted in `hystcomp_compensator_diagnostics`'s `*saturated`.
///
/// # Safety
/// `h` must be a live handle or NULL; `loop_saturated` valid for one write (NULL is refused).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_loop_saturated(
    h: *const HystcompCompensator,
    loop_saturated: *mut u64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let c = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("compensator handle"))?;
        let count = c.inner.diagnostics().loop_saturated;
        // SAFETY: non-NULL checked by write_out, valid for a write (the caller's contract).
        unsafe { write_out(loop_saturated, count, "loop_saturated") }
    })
}

/// Writes the worst-case gain of the one-sample-delayed loop of the compensator's family over
/// the drive limits, whatever its own mode: for the IHC methods
/// `max |3 a1 x^2| / (a2 + b_1 + ... + b_k)` (eq. (5) with `v(t - Ts)`; Table 1 of the paper:
/// 0.68), for the WIHC methods `max |3 a1 x^2 + b_1 + ... + b_k| / a2` (eq. (9) with
/// `H[v](t - Ts)`; Table 1: 1.66). At or above 1 the plain delayed loop can ring between the
/// limits after a jump in the desired position (and is refused unless allowed); the exact and
/// guarded methods do not. DIHC: `HYSTCOMP_STATUS_INVALID_ARGUMENT`.
///
/// # Safety
/// `h` must be a live handle or NULL; `gain` valid for one write (NULL is refused).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_delayed_loop_gain(
    h: *const HystcompCompensator,
    gain: *mut f64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let c = unsafe { h.as_ref() }.ok_or_else(|| Failure::null("compensator handle"))?;
        let value = c.inner.delayed_loop_gain().ok_or_else(|| {
            Failure::new(
                HystcompStatus::InvalidArgument,
                format!(
                    "{} has no delayed loop; the loop gain exists for the IHC and WIHC methods",
                    c.inner.method()
                ),
            )
        })?;
        // SAFETY: non-NULL checked by write_out, valid for a write (the caller's contract).
        unsafe { write_out(gain, value, "gain") }
    })
}

/// Releases a compensator. NULL is accepted (and ignored); a handle must not be used after,
/// nor freed twice.
///
/// # Safety
/// `h` must be a live handle from this library or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_compensator_free(h: *mut HystcompCompensator) {
    if h.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a live handle made by `Box::into_raw` in this library, freed once (the
        // caller's contract).
        drop(unsafe { Box::from_raw(h) });
    }));
}
