//! Shared by the tests that call the C ABI from Rust as C calls it: the statuses as `int`s, the
//! last error's message, the repository's model files as C strings.
#![allow(dead_code)]

use std::ffi::{CStr, CString, c_int};

use hystcomp::{HystcompStatus, hystcomp_last_error_message};

pub const OK: c_int = HystcompStatus::Ok as c_int;
pub const NULL_POINTER: c_int = HystcompStatus::NullPointer as c_int;
pub const INVALID_ARGUMENT: c_int = HystcompStatus::InvalidArgument as c_int;
pub const NOT_INVERTIBLE: c_int = HystcompStatus::NotInvertible as c_int;
pub const IO: c_int = HystcompStatus::Io as c_int;
pub const INVALID_MODEL_FILE: c_int = HystcompStatus::InvalidModelFile as c_int;
pub const WRONG_DIRECTION: c_int = HystcompStatus::WrongDirection as c_int;
pub const NON_FINITE_INPUT: c_int = HystcompStatus::NonFiniteInput as c_int;
pub const IDENTIFICATION_FAILED: c_int = HystcompStatus::IdentificationFailed as c_int;
pub const UNSTABLE_DELAY: c_int = HystcompStatus::UnstableDelay as c_int;

/// The message of the last failed call on this thread.
pub fn last_error() -> String {
    // SAFETY: the library returns a NUL-terminated thread-local string, never NULL.
    unsafe { CStr::from_ptr(hystcomp_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

/// `models/{name}` of the repository, as a C string.
pub fn model_path(name: &str) -> CString {
    CString::new(format!(
        "{}/../../models/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}
