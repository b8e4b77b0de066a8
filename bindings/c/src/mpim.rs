//! Forward models: the MPIM of eq. (4), model input in, model output out.

use std::ffi::{c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

use hystcomp_core::{CoreError, Mpim};
use hystcomp_io::model_file::{ModelFile, Scale};

use crate::HystcompStatus;
use crate::args::{
    clear_out, handle, non_finite_failure, parameters, path_arg, put_handle, run_signal, write_out,
};
use crate::boundary::{Failure, boundary};

/// A forward MPIM, eq. (4): model input in, model output out (opaque). Useful to check a
/// compensator (`P[C[y_d]] = y_d`) or to predict a plant's displacement.
///
/// Created by `hystcomp_mpim_from_model_file` or `hystcomp_mpim_from_model` (physical units of
/// the model) or `hystcomp_mpim_from_parameters` (normalised units), released by
/// `hystcomp_mpim_free`.
pub struct HystcompMpim {
    pub(crate) model: Mpim<f64, Vec<f64>>,
    /// Physical meaning of the input and the output; `None` for normalised units.
    pub(crate) scales: Option<(Scale, Scale)>,
}

impl HystcompMpim {
    /// The hysteresis of a model file in its physical units; a model with creep or vibration
    /// links is refused, since this handle would silently leave them out.
    pub(crate) fn of_file(file: &ModelFile) -> Result<Self, Failure> {
        if file.creep.is_some() || file.vibration.is_some() {
            return Err(Failure::invalid(
                "the model has creep or vibration links, which a forward MPIM handle would \
                 leave out; run the whole chain with hystcomp_model_predict (a file: \
                 hystcomp_model_load first)",
            ));
        }
        if file.output_map.is_some() {
            return Err(Failure::invalid(
                "the model has an output_map (its hysteresis link is psi^-1 of the MPIM), which \
                 a forward MPIM handle would leave out; run it with hystcomp_model_predict (a \
                 file: hystcomp_model_load first)",
            ));
        }
        Ok(Self {
            model: file.model()?,
            scales: Some((file.input.clone(), file.output.clone())),
        })
    }
}

/// Creates the forward model of a model file, in its physical units: for a plant model, drive
/// voltage in and displacement out (the inverse model of a DIHC file maps desired displacement
/// to voltage). The memory starts at zero (eq. (1)). A model with creep or vibration links is
/// refused, as by `hystcomp_mpim_from_model`: this handle runs the hysteresis alone; load the
/// file with `hystcomp_model_load` and run the whole chain with `hystcomp_model_predict`.
///
/// Fails with `NULL_POINTER`, `IO` (missing file), `INVALID_MODEL_FILE` or `INVALID_ARGUMENT`
/// (a model with links).
///
/// # Safety
/// `path` must be a NUL-terminated string or NULL; `out` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_from_model_file(
    path: *const c_char,
    out: *mut *mut HystcompMpim,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let path = unsafe { path_arg(path, "path") }?;
        let mpim = HystcompMpim::of_file(&ModelFile::load(&path)?)?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, mpim) };
        Ok(())
    })
}

/// Creates a forward model from its parameters, in normalised units (eq. (4)):
/// `y = a1 x^3 + a2 x + sum b_i F_{r_i}[x]`. `1 <= n <= 10000` thresholds (`>= 0`,
/// increasing) and weights, all finite.
///
/// Fails with `NULL_POINTER` or `INVALID_ARGUMENT`.
///
/// # Safety
/// `thresholds` and `weights` must point to `n` doubles each or be NULL; `out` valid for one
/// write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_from_parameters(
    thresholds: *const f64,
    weights: *const f64,
    n: usize,
    a1: f64,
    a2: f64,
    out: *mut *mut HystcompMpim,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: `n` doubles each or NULL (the caller's contract).
        let (thresholds, weights) = unsafe { parameters(thresholds, weights, n) }?;
        let model = Mpim::new(thresholds, weights, a1, a2)?;
        let boxed = Box::into_raw(Box::new(HystcompMpim {
            model,
            scales: None,
        }));
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { out.write(boxed) };
        Ok(())
    })
}

impl HystcompMpim {
    fn step(&mut self, x: f64) -> f64 {
        match &self.scales {
            Some((input, output)) => output.to_physical(self.model.step(input.normalise(x))),
            None => self.model.step(x),
        }
    }
}

/// One sample: writes the model output for input `x` to `*y_out` and updates the memory.
/// A NaN or infinite `x` writes NaN, leaves the memory as it was and returns
/// `HYSTCOMP_STATUS_NON_FINITE_INPUT`.
///
/// # Safety
/// `m` must be a live handle or NULL; `y_out` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_step(
    m: *mut HystcompMpim,
    x: f64,
    y_out: *mut f64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let m = unsafe { handle(m, "model handle") }?;
        if y_out.is_null() {
            return Err(Failure::null("y_out"));
        }
        let y = if x.is_finite() { m.step(x) } else { f64::NAN };
        // SAFETY: non-NULL, valid for a write (the caller's contract).
        unsafe { write_out(y_out, y, "y_out") }?;
        if x.is_finite() {
            Ok(())
        } else {
            Err(Failure::new(
                HystcompStatus::NonFiniteInput,
                "the model input is NaN or infinite; the output is NaN and the memory unchanged",
            ))
        }
    })
}

/// A whole signal: `y[k]` for `x[k]`, `k = 0 .. len - 1`; `x` and `y` may be the same array.
/// With `len == 0` nothing is done. Non-finite inputs give NaN outputs (the memory skips them)
/// and `HYSTCOMP_STATUS_NON_FINITE_INPUT` after the whole signal.
///
/// # Safety
/// `m` must be a live handle or NULL; `x` must point to `len` readable doubles and `y` to `len`
/// writable doubles (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_process(
    m: *mut HystcompMpim,
    x: *const f64,
    y: *mut f64,
    len: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let m = unsafe { handle(m, "model handle") }?;
        // SAFETY: `len` elements each, or NULL (the caller's contract).
        let (count, first) = unsafe {
            run_signal(x, y, len, |x| {
                if x.is_finite() {
                    (m.step(x), false)
                } else {
                    (f64::NAN, true)
                }
            })
        }?;
        if count == 0 {
            Ok(())
        } else {
            Err(non_finite_failure(count, first, "model input"))
        }
    })
}

/// Back to zero memory (eq. (1)).
///
/// # Safety
/// `m` must be a live handle or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_reset(m: *mut HystcompMpim) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        unsafe { handle(m, "model handle") }?.model.reset();
        Ok(())
    })
}

/// Checks that the model output is strictly increasing in its input over `[lo, hi]` (in the
/// model's input unit) from any memory reachable from the reset state, i.e. that it can be
/// inverted there (ERRATA item 5). Writes the smallest branch slope (normalised units) to
/// `*min_slope` when it is not NULL, also on `NOT_INVERTIBLE`.
///
/// # Safety
/// `m` must be a live handle or NULL; `min_slope` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_check_invertible(
    m: *const HystcompMpim,
    lo: f64,
    hi: f64,
    min_slope: *mut f64,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract); only read.
        let m = unsafe { m.as_ref() }.ok_or_else(|| Failure::null("model handle"))?;
        let (lo, hi) = match &m.scales {
            Some((input, _)) => (input.normalise(lo), input.normalise(hi)),
            None => (lo, hi),
        };
        let result = m.model.check_invertible(lo, hi);
        let slope = match &result {
            Ok(worst) => Some(worst.slope),
            Err(CoreError::NotInvertible { slope, .. }) => Some(*slope),
            Err(_) => None,
        };
        if let (Some(slope), false) = (slope, min_slope.is_null()) {
            // SAFETY: non-NULL, valid for a write (the caller's contract).
            unsafe { min_slope.write(slope) };
        }
        result.map(|_| ()).map_err(Failure::from)
    })
}

/// Releases a forward model. NULL is accepted (and ignored).
///
/// # Safety
/// `m` must be a live handle from this library or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_free(m: *mut HystcompMpim) {
    if m.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a live handle made by `Box::into_raw` in this library, freed once (the
        // caller's contract).
        drop(unsafe { Box::from_raw(m) });
    }));
}
