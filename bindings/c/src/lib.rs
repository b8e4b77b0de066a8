//! The C ABI of hystcomp: feedforward hysteresis compensators (IHC, WIHC, DIHC of Gu & Zhu,
//! *Smart Mater. Struct.* **23** (2014) 095029) and the forward MPIM (eq. (4)) for real-time
//! controllers programmed in C (dSPACE, Speedgoat, an STM32 with an operating system...).
//!
//! A thin, safe wrapper: the compensators are `hystcomp_io::compensator::ScaledCompensator`
//! (physical units, limits in volts) and the forward model is `hystcomp_core::Mpim` scaled by a
//! model file's `hystcomp_io::model_file::Scale`s. Nothing is re-implemented here.
//!
//! The header `include/hystcomp.h` is generated from this file by cbindgen
//! (`bindings/c/cbindgen.toml`) and committed; a test fails when it is stale. Regenerate it with
//! `HYSTCOMP_UPDATE_HEADER=1 cargo test -p hystcomp-c --test header`.
//!
//! # Conventions
//! - Every function that can fail returns an `int` status, one of [`HystcompStatus`]
//!   (`HYSTCOMP_STATUS_OK` = 0). Results come back through out-parameters.
//! - On failure, `hystcomp_last_error_message()` gives the reason, in English, for people. It is
//!   **thread-local** and describes the most recent failed call on the calling thread; successful
//!   calls leave it unchanged.
//! - Objects are opaque handles (`HystcompCompensator*`, `HystcompMpim*`) created by a
//!   `*_from_*` function and released by the matching `*_free` (which accepts NULL). A handle
//!   may be moved between threads but must not be used by two threads at once.
//! - Every pointer is checked: NULL gives `HYSTCOMP_STATUS_NULL_POINTER`. Every entry point
//!   catches Rust panics, so nothing ever unwinds into C (a caught panic is
//!   `HYSTCOMP_STATUS_INTERNAL`, a bug to report).
//! - A compensator's output always lies within its limits and is never NaN, whatever it is fed
//!   (see `hystcomp_core::Compensator`). `step` and `process` never allocate on success.
//!
//! # Example (Rust calling the C ABI, as C would)
//! ```
//! use std::ffi::CString;
//! use hystcomp::*;
//!
//! let path = CString::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/table1-plant.json")).unwrap();
//! let method = CString::new("ihc").unwrap();
//! let mut ihc: *mut HystcompCompensator = std::ptr::null_mut();
//! let mut plant: *mut HystcompMpim = std::ptr::null_mut();
//! unsafe {
//!     assert_eq!(hystcomp_compensator_from_model_file(path.as_ptr(), method.as_ptr(), 0.0, 0.0, 0, &mut ihc), 0);
//!     assert_eq!(hystcomp_mpim_from_model_file(path.as_ptr(), &mut plant), 0);
//!     let (mut volts, mut um) = (0.0, 0.0);
//!     for k in 0..1000 {
//!         let desired_um = 37.5 + 20.0 * (k as f64 * 0.01).sin();
//!         assert_eq!(hystcomp_compensator_step(ihc, desired_um, &mut volts), 0);
//!         assert_eq!(hystcomp_mpim_step(plant, volts, &mut um), 0);
//!         assert!((um - desired_um).abs() < 1e-9); // P[C[y_d]] = y_d
//!     }
//!     hystcomp_compensator_free(ihc);
//!     hystcomp_mpim_free(plant);
//! }
//! ```
#![warn(missing_docs)]

use std::borrow::Cow;
use std::cell::RefCell;
use std::ffi::{CStr, c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

use hystcomp_core::{CoreError, Mpim};
use hystcomp_io::compensator::{CompensatorError, Method, ScaledCompensator};
use hystcomp_io::model_file::{Direction, ModelFile, ModelFileError, Scale};

/// The status every fallible function returns (as an `int`). `HYSTCOMP_STATUS_OK` is 0; every
/// other value comes with a message from `hystcomp_last_error_message()`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HystcompStatus {
    /// Success.
    Ok = 0,
    /// A required pointer (a handle, an array, an out-parameter, a string) was NULL.
    NullPointer = 1,
    /// An argument is unusable: NaN or infinite parameters, a zero operator count, thresholds
    /// negative or unsorted, limits not finite and increasing, an unknown method, a string that
    /// is not UTF-8, a misaligned array.
    InvalidArgument = 2,
    /// The model cannot be inverted (or used by this method) over the given range: a branch
    /// slope is not positive, the PI part has no eq. (7) inverse, `a2 <= 0` for WIHC, or the
    /// delayed WIHC would diverge.
    NotInvertible = 3,
    /// A file could not be read: missing, a directory, no permission (the message has the
    /// operating system's reason and the path).
    Io = 4,
    /// The file is not a valid hystcomp model file: not JSON, another format version, a field
    /// missing or of the wrong type, invalid scales or parameters.
    InvalidModelFile = 5,
    /// The model file maps the other direction from the one the method needs (IHC and WIHC
    /// need a plant model, DIHC an inverse model).
    WrongDirection = 6,
    /// An input sample was NaN or infinite. The call still completed: a compensator held its
    /// previous output (always within its limits) for that sample, a forward model output NaN
    /// for it, and the state was not changed by it.
    NonFiniteInput = 7,
    /// A Rust panic was caught at the boundary: a bug in hystcomp, please report it with the
    /// message. The handle involved should be freed.
    Internal = 8,
}

/// The compensation methods, for `hystcomp_compensator_from_parameters` (passed as an `int`).
/// The model file constructor takes the same methods by name: `"ihc"`, `"ihc-delayed"`,
/// `"wihc"`, `"wihc-delayed"`, `"dihc"`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HystcompMethod {
    /// IHC, eqs. (5)-(8): the inverse of a plant model, implicit equation solved exactly.
    Ihc = 0,
    /// IHC with `v(t - Ts)` in the cubic term (real-time Simulink style).
    IhcDelayed = 1,
    /// WIHC, eq. (9): a plant model in a multiplicative structure, solved exactly.
    Wihc = 2,
    /// WIHC with `H[v](t - Ts)` (real-time Simulink style).
    WihcDelayed = 3,
    /// DIHC, eq. (10): an inverse model evaluated on the desired trajectory.
    Dihc = 4,
}

/// A feedforward compensator: desired position in, drive voltage out (opaque).
///
/// Created by `hystcomp_compensator_from_model_file` (physical units of the model file) or
/// `hystcomp_compensator_from_parameters` (normalised units), released by
/// `hystcomp_compensator_free`.
pub struct HystcompCompensator {
    inner: ScaledCompensator,
}

/// A forward MPIM, eq. (4): model input in, model output out (opaque). Useful to check a
/// compensator (`P[C[y_d]] = y_d`) or to predict a plant's displacement.
///
/// Created by `hystcomp_mpim_from_model_file` (physical units of the model file) or
/// `hystcomp_mpim_from_parameters` (normalised units), released by `hystcomp_mpim_free`.
pub struct HystcompMpim {
    model: Mpim<f64, Vec<f64>>,
    /// Physical meaning of the input and the output; `None` for normalised units.
    scales: Option<(Scale, Scale)>,
}

// ----------------------------------------------------------------------------------------------
// Errors and the boundary
// ----------------------------------------------------------------------------------------------

/// Why a call failed: the status and the message for `hystcomp_last_error_message`.
struct Failure {
    status: HystcompStatus,
    message: Cow<'static, str>,
}

impl Failure {
    fn new(status: HystcompStatus, message: impl Into<Cow<'static, str>>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }

    fn null(what: &'static str) -> Self {
        Failure::new(
            HystcompStatus::NullPointer,
            format!("{what} is NULL; pass a valid pointer"),
        )
    }

    fn invalid(message: impl Into<Cow<'static, str>>) -> Self {
        Failure::new(HystcompStatus::InvalidArgument, message)
    }
}

fn core_status(e: &CoreError) -> HystcompStatus {
    match e {
        CoreError::NotInvertible { .. }
        | CoreError::PiPartNotInvertible { .. }
        | CoreError::DelayedWihcUnstable { .. }
        | CoreError::NonPositiveA2 { .. } => HystcompStatus::NotInvertible,
        _ => HystcompStatus::InvalidArgument,
    }
}

impl From<CoreError> for Failure {
    fn from(e: CoreError) -> Self {
        Failure::new(core_status(&e), e.to_string())
    }
}

impl From<CompensatorError> for Failure {
    fn from(e: CompensatorError) -> Self {
        let status = match &e {
            CompensatorError::WrongDirection { .. } => HystcompStatus::WrongDirection,
            CompensatorError::Core(core) => core_status(core),
            _ => HystcompStatus::InvalidArgument,
        };
        Failure::new(status, e.to_string())
    }
}

impl From<ModelFileError> for Failure {
    fn from(e: ModelFileError) -> Self {
        let status = match &e {
            ModelFileError::Io { .. } | ModelFileError::Write(_) => HystcompStatus::Io,
            _ => HystcompStatus::InvalidModelFile,
        };
        Failure::new(status, e.to_string())
    }
}

thread_local! {
    /// The message of the last failed call on this thread, NUL-terminated.
    static LAST_ERROR: RefCell<Vec<u8>> = RefCell::new(vec![0]);
}

fn set_last_error(message: &str) {
    LAST_ERROR.with(|cell| {
        let mut buffer = cell.borrow_mut();
        buffer.clear();
        // A C string ends at the first NUL: keep the message whole.
        buffer.extend(message.bytes().map(|b| if b == 0 { b'?' } else { b }));
        buffer.push(0);
    });
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_string());
    format!("internal error in hystcomp (please report it): {what}")
}

/// Runs `body` at the boundary: no panic escapes, failures set the thread's last error.
fn boundary(body: impl FnOnce() -> Result<(), Failure>) -> c_int {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => HystcompStatus::Ok as c_int,
        Ok(Err(failure)) => {
            set_last_error(&failure.message);
            failure.status as c_int
        }
        Err(payload) => {
            set_last_error(&panic_message(payload.as_ref()));
            HystcompStatus::Internal as c_int
        }
    }
}

// ----------------------------------------------------------------------------------------------
// Checked access to C arguments
// ----------------------------------------------------------------------------------------------

/// The `len` doubles at `ptr`, checked for NULL and alignment.
///
/// # Safety
/// When `ptr` is not NULL it must point to `len` readable doubles that stay valid and are not
/// written during the borrow.
unsafe fn doubles<'a>(
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

fn check_array(ptr: *const f64, len: usize, what: &'static str) -> Result<(), Failure> {
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
unsafe fn path_arg(ptr: *const c_char, what: &'static str) -> Result<PathBuf, Failure> {
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
unsafe fn str_arg<'a>(ptr: *const c_char, what: &'static str) -> Result<&'a str, Failure> {
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
unsafe fn handle<'a, H>(ptr: *mut H, what: &'static str) -> Result<&'a mut H, Failure> {
    // SAFETY: a non-NULL handle is a live `Box<H>` made by this library (the caller's
    // contract), so it is valid, aligned and exclusively ours for the call.
    unsafe { ptr.as_mut() }.ok_or_else(|| Failure::null(what))
}

/// Clears `*out` (when `out` is not NULL) so that a failed constructor leaves NULL behind.
///
/// # Safety
/// When `out` is not NULL it must be valid for one write.
unsafe fn clear_out<H>(out: *mut *mut H) -> Result<(), Failure> {
    if out.is_null() {
        return Err(Failure::null("out"));
    }
    // SAFETY: non-NULL, and valid for a write by the caller's contract.
    unsafe { out.write(std::ptr::null_mut()) };
    Ok(())
}

/// Writes one double to an out-parameter.
///
/// # Safety
/// When `out` is not NULL it must be valid for one write.
unsafe fn write_out<T>(out: *mut T, value: T, what: &'static str) -> Result<(), Failure> {
    if out.is_null() {
        return Err(Failure::null(what));
    }
    // SAFETY: non-NULL, and valid for a write by the caller's contract.
    unsafe { out.write(value) };
    Ok(())
}

/// Runs `step` over `len` samples from `input` into `output`, element by element, so that the
/// two arrays may be the same (in place). Returns how many inputs were not finite, and the
/// first such index.
///
/// # Safety
/// When `len > 0`, `input` and `output` must be valid for `len` reads and writes respectively
/// (checked for NULL and alignment here).
unsafe fn run_signal(
    input: *const f64,
    output: *mut f64,
    len: usize,
    mut step: impl FnMut(f64) -> f64,
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
        if !x.is_finite() {
            if count == 0 {
                first = k;
            }
            count += 1;
        }
        let y = step(x);
        // SAFETY: as above.
        unsafe { output.add(k).write(y) };
    }
    Ok((count, first))
}

fn non_finite_failure(count: usize, first: usize, what: &'static str) -> Failure {
    Failure::new(
        HystcompStatus::NonFiniteInput,
        format!(
            "{count} {what} sample(s) were NaN or infinite (the first at index {first}); \
             their outputs are held or NaN, see the status documentation"
        ),
    )
}

/// Normalised (identity) scales for models given by their parameters.
fn normalised_scale(quantity: &str) -> Scale {
    Scale {
        quantity: quantity.to_string(),
        unit: "1".to_string(),
        offset: 0.0,
        scale: 1.0,
    }
}

/// Reads `n` operators' thresholds and weights.
///
/// # Safety
/// As [`doubles`] for both arrays.
unsafe fn parameters<'a>(
    thresholds: *const f64,
    weights: *const f64,
    n: usize,
) -> Result<(&'a [f64], &'a [f64]), Failure> {
    if n == 0 {
        return Err(Failure::invalid(
            "n = 0: a model needs at least one play operator (the paper uses 10)",
        ));
    }
    // SAFETY: forwarded contract.
    let thresholds = unsafe { doubles(thresholds, n, "thresholds") }?;
    // SAFETY: forwarded contract.
    let weights = unsafe { doubles(weights, n, "weights") }?;
    Ok((thresholds, weights))
}

// ----------------------------------------------------------------------------------------------
// Library information
// ----------------------------------------------------------------------------------------------

/// The message of the most recent failed call on the calling thread (an empty string when no
/// call has failed on it). Never NULL. The string stays valid until the next failed call on the
/// same thread; copy it to keep it.
#[unsafe(no_mangle)]
pub extern "C" fn hystcomp_last_error_message() -> *const c_char {
    catch_unwind(|| LAST_ERROR.with(|cell| cell.borrow().as_ptr().cast::<c_char>()))
        .unwrap_or(c"internal error in hystcomp while reading the last error".as_ptr())
}

/// A short, static description of a status code (e.g. `"null pointer"`), for logs. Never NULL.
#[unsafe(no_mangle)]
pub extern "C" fn hystcomp_status_name(status: c_int) -> *const c_char {
    let name: &'static CStr = match status {
        0 => c"ok",
        1 => c"null pointer",
        2 => c"invalid argument",
        3 => c"model not invertible",
        4 => c"file could not be read",
        5 => c"invalid model file",
        6 => c"model of the wrong direction for the method",
        7 => c"non-finite input sample",
        8 => c"internal error",
        _ => c"unknown status",
    };
    name.as_ptr()
}

/// The library's version, e.g. `"0.1.0"`. Never NULL, static.
#[unsafe(no_mangle)]
pub extern "C" fn hystcomp_version() -> *const c_char {
    const VERSION: &CStr =
        match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
            Ok(v) => v,
            Err(_) => c"unknown",
        };
    VERSION.as_ptr()
}

// ----------------------------------------------------------------------------------------------
// Compensators
// ----------------------------------------------------------------------------------------------

/// Creates a compensator from a model file, in the file's physical units: desired position in
/// (e.g. um), drive voltage out (e.g. V).
///
/// - `path`: the JSON model file (e.g. `models/table1-plant.json`).
/// - `method`: `"ihc"`, `"ihc-delayed"`, `"wihc"`, `"wihc-delayed"` (plant models) or `"dihc"`
///   (inverse models), case-insensitive.
/// - `v_min`, `v_max`, `use_limits`: with `use_limits != 0`, the drive limits in the model's
///   voltage unit (finite, `v_min < v_max`); with `use_limits == 0` they are ignored and the
///   range the model was identified on is used.
/// - `out`: receives the handle (NULL on failure). Free it with `hystcomp_compensator_free`.
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (unknown method, limits), `IO` (missing
/// file), `INVALID_MODEL_FILE`, `WRONG_DIRECTION` or `NOT_INVERTIBLE` (over the limits).
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
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let path = unsafe { path_arg(path, "path") }?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let method: Method = unsafe { str_arg(method, "method") }?.parse()?;
        let file = ModelFile::load(&path)?;
        let limits = (use_limits != 0).then_some((v_min, v_max));
        let inner = ScaledCompensator::new(&file, method, limits)?;
        let boxed = Box::into_raw(Box::new(HystcompCompensator { inner }));
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { out.write(boxed) };
        Ok(())
    })
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
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (n = 0, NaN, unsorted thresholds, limits,
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
                     2 = WIHC, 3 = WIHC delayed, 4 = DIHC)"
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
        let boxed = Box::into_raw(Box::new(HystcompCompensator { inner }));
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { out.write(boxed) };
        Ok(())
    })
}

/// One sample: writes to `*v_out` the drive for the desired position `y_d`.
///
/// `*v_out` always lies within the compensator's limits and is never NaN. A NaN or infinite
/// `y_d` holds the previous output, writes it to `*v_out` and returns
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
        let v = c.inner.step(y_d);
        // SAFETY: non-NULL, valid for a write (the caller's contract).
        unsafe { write_out(v_out, v, "v_out") }?;
        if y_d.is_finite() {
            Ok(())
        } else {
            Err(Failure::new(
                HystcompStatus::NonFiniteInput,
                "the desired position is NaN or infinite; the previous output was held",
            ))
        }
    })
}

/// A whole signal: `v[k]` is the drive for `y_d[k]`, `k = 0 .. len - 1`, as `len` calls of
/// `hystcomp_compensator_step`. `y_d` and `v` may be the same array (in place). With `len == 0`
/// nothing is done and the arrays may be NULL.
///
/// Non-finite samples hold the previous output; the whole signal is still processed and
/// `HYSTCOMP_STATUS_NON_FINITE_INPUT` is returned, with their count and first index in the
/// message.
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
        let (count, first) = unsafe { run_signal(y_d, v, len, |x| c.inner.step(x)) }?;
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

/// Writes the worst-case loop gain of the delayed WIHC over the drive limits,
/// `max |3 a1 x^2 + b_1 + ... + b_k| / a2` (eq. (9) with `H[v](t - Ts)`), for a compensator of
/// method `wihc` or `wihc-delayed`. At or above 1 the delayed loop can ring between the limits
/// after a jump in the desired position; prefer `wihc` then (Table 1 of the paper: 1.66).
/// Other methods: `HYSTCOMP_STATUS_INVALID_ARGUMENT`.
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
                    "{} has no delayed WIHC loop; the loop gain exists for wihc and wihc-delayed",
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

// ----------------------------------------------------------------------------------------------
// Forward models
// ----------------------------------------------------------------------------------------------

/// Creates the forward model of a model file, in its physical units: for a plant model, drive
/// voltage in and displacement out (the inverse model of a DIHC file maps desired displacement
/// to voltage). The memory starts at zero (eq. (1)).
///
/// Fails with `NULL_POINTER`, `IO` (missing file) or `INVALID_MODEL_FILE`.
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
        let file = ModelFile::load(&path)?;
        let model = file.model()?;
        let boxed = Box::into_raw(Box::new(HystcompMpim {
            model,
            scales: Some((file.input.clone(), file.output.clone())),
        }));
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { out.write(boxed) };
        Ok(())
    })
}

/// Creates a forward model from its parameters, in normalised units (eq. (4)):
/// `y = a1 x^3 + a2 x + sum b_i F_{r_i}[x]`. `n >= 1` thresholds (`>= 0`, increasing) and
/// weights, all finite.
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
            run_signal(
                x,
                y,
                len,
                |x| if x.is_finite() { m.step(x) } else { f64::NAN },
            )
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

/// The Rust example of `docs/microcontroller.md`, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../../../docs/microcontroller.md")]
pub struct MicrocontrollerDoc;
