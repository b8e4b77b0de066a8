//! The C ABI of hystcomp: feedforward hysteresis compensators (IHC, WIHC, DIHC of Gu & Zhu,
//! *Smart Mater. Struct.* **23** (2014) 095029) and the forward MPIM (eq. (4)) for real-time
//! controllers programmed in C (dSPACE, Speedgoat, an STM32 with an operating system...), and
//! for the bindings over C (MATLAB/Octave's MEX gateway in `bindings/matlab`): models in
//! memory, identification from arrays, the tracking indices.
//!
//! A thin, safe wrapper: the compensators are `hystcomp_io::compensator::ScaledCompensator`
//! (physical units, limits in volts), the forward model is `hystcomp_core::Mpim` scaled by a
//! model file's `hystcomp_io::model_file::Scale`s, a model is a
//! `hystcomp_io::model_file::ModelFile`, identification is `hystcomp_identify::identify` and the
//! indices are `hystcomp_indices`. Nothing is re-implemented here.
//!
//! One module per job: `compensator` and `compensate` (compensators, from files, parameters or
//! models, and the one-shot compensation), `bank` (many channels in one handle), `mpim`
//! (forward models), `model` (models in memory: files, values), `identify`, `indices`, `learn`
//! (learning from repetition between trials), `info`
//! (messages, version); `boundary` and `args` hold the checks every entry point shares.
//!
//! The header `include/hystcomp.h` is generated from these files by cbindgen
//! (`bindings/c/cbindgen.toml`) and committed; a test fails when it is stale. Regenerate it with
//! `HYSTCOMP_UPDATE_HEADER=1 cargo test -p hystcomp-c --test header`.
//!
//! # Conventions
//! - Every function that can fail returns an `int` status, one of [`HystcompStatus`]
//!   (`HYSTCOMP_STATUS_OK` = 0). Results come back through out-parameters.
//! - On failure, `hystcomp_last_error_message()` gives the reason, in English, for people. It is
//!   **thread-local** and describes the most recent failed call on the calling thread; successful
//!   calls leave it unchanged.
//! - Objects are opaque handles (`HystcompCompensator*`, `HystcompBank*`, `HystcompMpim*`,
//!   `HystcompModel*`)
//!   created by a `*_from_*`, `*_load` or `hystcomp_identify` function and released by the
//!   matching `*_free` (which accepts NULL). A handle may be moved between threads but must not
//!   be used by two threads at once (a model, which never changes, may be read by several).
//! - Arrays come with their lengths; NULL, empty (where a signal is needed), mismatched lengths
//!   and NaN samples are refused with a status and a message, and every size a caller sets is
//!   bounded before anything is allocated (`HYSTCOMP_MAX_*`).
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

mod args;
mod bank;
mod boundary;
mod compensate;
mod compensator;
mod identify;
mod indices;
mod info;
mod learn;
mod model;
mod mpim;

pub use bank::*;
pub use compensate::*;
pub use compensator::*;
pub use identify::*;
pub use indices::*;
pub use info::*;
pub use learn::*;
pub use model::*;
pub use mpim::*;

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
    /// slope is not positive, the PI part has no eq. (7) inverse, or `a2 <= 0` for WIHC.
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
    /// An input sample was NaN or infinite (or, for a compensator, too large to normalise by
    /// the model's scale or for its creep or vibration links to follow). The call still
    /// completed: a compensator held its previous output (always within its limits) for that
    /// sample, a forward model output NaN for it, and the state was not changed by it.
    NonFiniteInput = 7,
    /// A Rust panic was caught at the boundary: a bug in hystcomp, please report it with the
    /// message. The handle involved should be freed.
    Internal = 8,
    /// No model could be identified from the samples with the options given: the displacement
    /// does not rise with the voltage (a wrong column or sign), the regressors are
    /// ill-conditioned, the constraints cannot be met, the swarm found no feasible model, or
    /// the fit's RMS error exceeds its limit. The message says what to change.
    IdentificationFailed = 9,
    /// A plain one-sample-delayed method (`ihc-delayed`, `wihc-delayed`) was asked for on a
    /// model whose delayed loop gain over the limits is 1 or more, so the loop can oscillate
    /// between the limits. Use the exact method, the guarded one (`ihc-guarded`,
    /// `wihc-guarded`), or pass `HYSTCOMP_ALLOW_UNSTABLE_DELAY` to
    /// `hystcomp_compensator_from_model_file_with`.
    UnstableDelay = 10,
    /// The divergence guard stopped the learning (`hystcomp_learner_update`): on the trial that
    /// tripped it the call wrote the last good drive; every later update is refused, the
    /// learner unchanged. Start a new learner with a lower gain or bandwidth.
    LearningStopped = 11,
}

/// Flag of `hystcomp_compensator_from_model_file_with`: build a plain delayed method even when
/// its loop gain over the limits is 1 or more (it may then ring between the limits; the output
/// still never leaves them).
pub const HYSTCOMP_ALLOW_UNSTABLE_DELAY: std::ffi::c_int = 1;

/// The compensation methods, for `hystcomp_compensator_from_parameters` (passed as an `int`).
/// The model file constructor takes the same methods by name: `"ihc"`, `"ihc-delayed"`,
/// `"wihc"`, `"wihc-delayed"`, `"dihc"`, `"ihc-guarded"`, `"wihc-guarded"`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HystcompMethod {
    /// IHC, eqs. (5)-(8): the inverse of a plant model, implicit equation solved exactly.
    Ihc = 0,
    /// IHC with `v(t - Ts)` in the cubic term (real-time Simulink style); refused with
    /// `HYSTCOMP_STATUS_UNSTABLE_DELAY` when its loop gain over the limits is 1 or more.
    IhcDelayed = 1,
    /// WIHC, eq. (9): a plant model in a multiplicative structure, solved exactly.
    Wihc = 2,
    /// WIHC with `H[v](t - Ts)` (real-time Simulink style); refused with
    /// `HYSTCOMP_STATUS_UNSTABLE_DELAY` when its loop gain over the limits is 1 or more.
    WihcDelayed = 3,
    /// DIHC, eq. (10): an inverse model evaluated on the desired trajectory.
    Dihc = 4,
    /// The delayed IHC with its guard (an under-relaxed update): never oscillates.
    IhcGuarded = 5,
    /// The delayed WIHC with its guard (an under-relaxed update): never oscillates.
    WihcGuarded = 6,
}

/// The Rust example of `docs/microcontroller.md`, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../../../docs/microcontroller.md")]
pub struct MicrocontrollerDoc;
