//! Checked access to the arguments C passes: arrays, strings, handles and out-parameters.

use std::ffi::{CStr, c_char};
use std::path::PathBuf;

use hystcomp_io::model_file::{MAX_OPERATORS, Scale};

use crate::HystcompStatus;
use crate::boundary::Failure;

/// The `len` doubles at `ptr`, checked for NULL and alignment.
///
/// # Safety
/// When `ptr` is not NULL it must point to `len` readable doubles that stay valid and are not
/// written during the borrow.
pub(crate) unsafe fn doubles<'a>(
    ptr: *const f64,
    len: usize,
    what: &'static str,
) -> Result<&'a [f64], Failure> {
    if ptr.is_null() {
        return Err(Failure::null(what));
    }
    check_array(ptr, len, what)?;
    // SAFETY: non-NULL and aligned (checked above), `len * 8 <= isize::MAX` (checked by
    // `check_array`); validity for `len` reads is the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

pub(crate) fn check_array(ptr: *const f64, len: usize, what: &'static str) -> Result<(), Failure> {
    if !ptr.is_aligned() {
        return Err(Failure::invalid(format!(
            "{what} is not aligned for double; pass an array of double"
        )));
    }
    if len > isize::MAX as usize / size_of::<f64>() {
        return Err(Failure::invalid(format!(
            "{what} length {len} is impossibly large"
        )));
    }
    Ok(())
}

/// The NUL-terminated string at `ptr` as a path.
///
/// # Safety
/// When `ptr` is not NULL it must point to a NUL-terminated string.
pub(crate) unsafe fn path_arg(ptr: *const c_char, what: &'static str) -> Result<PathBuf, Failure> {
    if ptr.is_null() {
        return Err(Failure::null(what));
    }
    // SAFETY: non-NULL; NUL termination is the caller's contract.
    let bytes = unsafe { CStr::from_ptr(ptr) }.to_bytes();
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        Ok(PathBuf::from(std::ffi::OsStr::from_bytes(bytes)))
    }
    #[cfg(not(unix))]
    {
        std::str::from_utf8(bytes)
            .map(PathBuf::from)
            .map_err(|_| Failure::invalid(format!("{what} is not valid UTF-8")))
    }
}

/// The NUL-terminated UTF-8 string at `ptr`.
///
/// # Safety
/// When `ptr` is not NULL it must point to a NUL-terminated string.
pub(crate) unsafe fn str_arg<'a>(
    ptr: *const c_char,
    what: &'static str,
) -> Result<&'a str, Failure> {
    if ptr.is_null() {
        return Err(Failure::null(what));
    }
    // SAFETY: non-NULL; NUL termination is the caller's contract.
    unsafe { CStr::from_ptr(ptr) }
        .to_str()
        .map_err(|_| Failure::invalid(format!("{what} is not valid UTF-8")))
}

/// The object behind a handle.
///
/// # Safety
/// When `ptr` is not NULL it must be a live handle of this type, not used elsewhere meanwhile.
pub(crate) unsafe fn handle<'a, H>(ptr: *mut H, what: &'static str) -> Result<&'a mut H, Failure> {
    // SAFETY: a non-NULL handle is a live `Box<H>` made by this library (the caller's
    // contract), so it is valid, aligned and exclusively ours for the call.
    unsafe { ptr.as_mut() }.ok_or_else(|| Failure::null(what))
}

/// Clears `*out` (when `out` is not NULL) so that a failed constructor leaves NULL behind.
///
/// # Safety
/// When `out` is not NULL it must be valid for one write.
pub(crate) unsafe fn clear_out<H>(out: *mut *mut H) -> Result<(), Failure> {
    if out.is_null() {
        return Err(Failure::null("out"));
    }
    // SAFETY: non-NULL, and valid for a write by the caller's contract.
    unsafe { out.write(std::ptr::null_mut()) };
    Ok(())
}

/// Moves `value` into a new handle and writes it to `*out`.
///
/// # Safety
/// `out` must be non-NULL and valid for one write (checked by [`clear_out`] before).
pub(crate) unsafe fn put_handle<H>(out: *mut *mut H, value: H) {
    let boxed = Box::into_raw(Box::new(value));
    // SAFETY: non-NULL and valid for a write (the caller's contract).
    unsafe { out.write(boxed) };
}

/// The `len` doubles of a signal at `ptr`: NULL and empty signals are refused (`what` names
/// the signal in the message).
///
/// # Safety
/// As [`doubles`].
pub(crate) unsafe fn signal<'a>(
    ptr: *const f64,
    len: usize,
    what: &'static str,
) -> Result<&'a [f64], Failure> {
    if ptr.is_null() {
        return Err(Failure::null(what));
    }
    if len == 0 {
        return Err(Failure::invalid(format!(
            "{what} is empty (length 0); give at least one sample"
        )));
    }
    // SAFETY: forwarded contract.
    unsafe { doubles(ptr, len, what) }
}

/// Writes one double to an out-parameter.
///
/// # Safety
/// When `out` is not NULL it must be valid for one write.
pub(crate) unsafe fn write_out<T>(
    out: *mut T,
    value: T,
    what: &'static str,
) -> Result<(), Failure> {
    if out.is_null() {
        return Err(Failure::null(what));
    }
    // SAFETY: non-NULL, and valid for a write by the caller's contract.
    unsafe { out.write(value) };
    Ok(())
}

/// Runs `step` over `len` samples from `input` into `output`, element by element, so that the
/// two arrays may be the same (in place). `step` returns the output and whether it held its
/// input back (not finite, or not usable). Returns how many were held, and the first such
/// index.
///
/// # Safety
/// When `len > 0`, `input` and `output` must be valid for `len` reads and writes respectively
/// (checked for NULL and alignment here).
pub(crate) unsafe fn run_signal(
    input: *const f64,
    output: *mut f64,
    len: usize,
    mut step: impl FnMut(f64) -> (f64, bool),
) -> Result<(usize, usize), Failure> {
    if len == 0 {
        return Ok((0, 0));
    }
    if input.is_null() {
        return Err(Failure::null("input array"));
    }
    if output.is_null() {
        return Err(Failure::null("output array"));
    }
    check_array(input, len, "input array")?;
    check_array(output, len, "output array")?;
    let (mut count, mut first) = (0, 0);
    for k in 0..len {
        // SAFETY: `k < len`, both arrays valid for `len` elements (the caller's contract),
        // non-NULL and aligned (checked); reading before writing allows `input == output`.
        let x = unsafe { input.add(k).read() };
        let (y, held) = step(x);
        if held {
            if count == 0 {
                first = k;
            }
            count += 1;
        }
        // SAFETY: as above.
        unsafe { output.add(k).write(y) };
    }
    Ok((count, first))
}

pub(crate) fn non_finite_failure(count: usize, first: usize, what: &'static str) -> Failure {
    Failure::new(
        HystcompStatus::NonFiniteInput,
        format!(
            "{count} {what} sample(s) were NaN or infinite, or too large to use (the first at \
             index {first}); their outputs are held or NaN, see the status documentation"
        ),
    )
}

/// Normalised (identity) scales for models given by their parameters.
pub(crate) fn normalised_scale(quantity: &str) -> Scale {
    Scale {
        quantity: quantity.to_string(),
        unit: "1".to_string(),
        offset: 0.0,
        scale: 1.0,
    }
}

/// Reads `n` operators' thresholds and weights (1 to `MAX_OPERATORS`, 10 000, checked before
/// anything is read).
///
/// # Safety
/// As [`doubles`] for both arrays.
pub(crate) unsafe fn parameters<'a>(
    thresholds: *const f64,
    weights: *const f64,
    n: usize,
) -> Result<(&'a [f64], &'a [f64]), Failure> {
    if n == 0 {
        return Err(Failure::invalid(
            "n = 0: a model needs at least one play operator (the paper uses 10)",
        ));
    }
    if n > MAX_OPERATORS {
        return Err(Failure::invalid(format!(
            "n = {n}: a model holds at most {MAX_OPERATORS} play operators (the paper uses 10)"
        )));
    }
    // SAFETY: forwarded contract.
    let thresholds = unsafe { doubles(thresholds, n, "thresholds") }?;
    // SAFETY: forwarded contract.
    let weights = unsafe { doubles(weights, n, "weights") }?;
    Ok((thresholds, weights))
}
