//! The tracking indices of section 4.3 (`hystcomp_indices`), in percent of the desired range
//! `max y_d - min y_d`: e_m (D1, ERRATA item 2), e_rms (D2) and e_mhe (eq. (12), ERRATA item 6).

use std::ffi::c_int;

use hystcomp_indices::{IndexError, e_m_percent, e_mhe_percent, e_rms_percent};

use crate::args::{signal, write_out};
use crate::boundary::{Failure, boundary};

/// The default number of e_mhe bins across the desired range (100; at least 10 samples per bin
/// on average are needed, see `hystcomp_e_mhe`).
pub const HYSTCOMP_DEFAULT_MHE_BINS: usize = 100;
const _: () = assert!(HYSTCOMP_DEFAULT_MHE_BINS == hystcomp_indices::DEFAULT_MHE_BINS);

/// Computes `index` of the desired and measured records (checked for NULL and emptiness here,
/// for lengths, NaN and a constant desired record by the index) into `*percent`.
///
/// # Safety
/// `desired` and `measured` must point to `desired_len` and `measured_len` readable doubles or
/// be NULL; `percent` valid for one write or NULL.
unsafe fn index(
    desired: *const f64,
    desired_len: usize,
    measured: *const f64,
    measured_len: usize,
    percent: *mut f64,
    index: impl FnOnce(&[f64], &[f64]) -> Result<f64, IndexError>,
) -> c_int {
    boundary(|| {
        // SAFETY: forwarded contract.
        let d = unsafe { signal(desired, desired_len, "desired") }?;
        // SAFETY: forwarded contract.
        let y = unsafe { signal(measured, measured_len, "measured") }?;
        if percent.is_null() {
            return Err(Failure::null("percent"));
        }
        let value = index(d, y)?;
        // SAFETY: non-NULL, valid for a write (the caller's contract).
        unsafe { write_out(percent, value, "percent") }
    })
}

/// (D1), corrected (ERRATA item 2): writes `max |y - y_d| / (max y_d - min y_d) * 100` to
/// `*percent`, `y_d` the desired record and `y` the measured one.
///
/// Fails with `NULL_POINTER` or `INVALID_ARGUMENT`: lengths differ, a record is empty or has
/// fewer than 2 samples, a sample is NaN or infinite (the message gives its index), the desired
/// record is constant.
///
/// # Safety
/// `desired` and `measured` must point to `desired_len` and `measured_len` readable doubles or
/// be NULL; `percent` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_e_m(
    desired: *const f64,
    desired_len: usize,
    measured: *const f64,
    measured_len: usize,
    percent: *mut f64,
) -> c_int {
    // SAFETY: forwarded contract.
    unsafe {
        index(
            desired,
            desired_len,
            measured,
            measured_len,
            percent,
            e_m_percent,
        )
    }
}

/// (D2): writes `sqrt(mean (y - y_d)^2) / (max y_d - min y_d) * 100` to `*percent`.
///
/// Fails as `hystcomp_e_m`.
///
/// # Safety
/// As `hystcomp_e_m`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_e_rms(
    desired: *const f64,
    desired_len: usize,
    measured: *const f64,
    measured_len: usize,
    percent: *mut f64,
) -> c_int {
    // SAFETY: forwarded contract.
    unsafe {
        index(
            desired,
            desired_len,
            measured,
            measured_len,
            percent,
            e_rms_percent,
        )
    }
}

/// Eq. (12) (ERRATA item 6): writes to `*percent` the largest vertical width of the `y` versus
/// `y_d` map, `max y - min y` within one of `bins` equal bins of the desired range, divided by
/// that range, times 100. `bins` is at least 1 and at most `max(1, len / 10)` (at least 10
/// samples per bin on average; with fewer, bins hold one sample or none and e_mhe reads low);
/// `HYSTCOMP_DEFAULT_MHE_BINS` is the usual choice.
///
/// Fails as `hystcomp_e_m`, and with `INVALID_ARGUMENT` for `bins` out of range (the message
/// gives the largest the records support).
///
/// # Safety
/// As `hystcomp_e_m`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_e_mhe(
    desired: *const f64,
    desired_len: usize,
    measured: *const f64,
    measured_len: usize,
    bins: usize,
    percent: *mut f64,
) -> c_int {
    // SAFETY: forwarded contract.
    unsafe {
        index(
            desired,
            desired_len,
            measured,
            measured_len,
            percent,
            |d, y| e_mhe_percent(d, y, bins),
        )
    }
}
