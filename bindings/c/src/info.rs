//! Library information: the last error's message, status names, the version.

use std::ffi::{CStr, c_char, c_int};
use std::panic::catch_unwind;

use crate::boundary::LAST_ERROR;

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
        9 => c"identification failed",
        10 => c"delayed loop can oscillate on this model",
        11 => c"learning stopped by the divergence guard",
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
