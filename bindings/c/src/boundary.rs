//! The boundary between C and Rust: the status and message of a failed call, the thread's last
//! error, and the catching of panics.

use std::borrow::Cow;
use std::cell::RefCell;
use std::ffi::c_int;
use std::panic::{AssertUnwindSafe, catch_unwind};

use hystcomp_core::CoreError;
use hystcomp_identify::IdentifyError;
use hystcomp_indices::IndexError;
use hystcomp_io::compensator::CompensatorError;
use hystcomp_io::model_file::ModelFileError;

use crate::HystcompStatus;

/// Why a call failed: the status and the message for `hystcomp_last_error_message`.
pub(crate) struct Failure {
    pub(crate) status: HystcompStatus,
    pub(crate) message: Cow<'static, str>,
}

impl Failure {
    pub(crate) fn new(status: HystcompStatus, message: impl Into<Cow<'static, str>>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }

    pub(crate) fn null(what: &'static str) -> Self {
        Failure::new(
            HystcompStatus::NullPointer,
            format!("{what} is NULL; pass a valid pointer"),
        )
    }

    pub(crate) fn invalid(message: impl Into<Cow<'static, str>>) -> Self {
        Failure::new(HystcompStatus::InvalidArgument, message)
    }
}

pub(crate) fn core_status(e: &CoreError) -> HystcompStatus {
    match e {
        CoreError::NotInvertible { .. }
        | CoreError::PiPartNotInvertible { .. }
        | CoreError::NonPositiveA2 { .. } => HystcompStatus::NotInvertible,
        CoreError::DelayedLoopUnstable { .. } => HystcompStatus::UnstableDelay,
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

pub(crate) fn model_file_status(e: &ModelFileError) -> HystcompStatus {
    match e {
        ModelFileError::Io { .. } | ModelFileError::Write(_) => HystcompStatus::Io,
        _ => HystcompStatus::InvalidModelFile,
    }
}

impl From<ModelFileError> for Failure {
    fn from(e: ModelFileError) -> Self {
        Failure::new(model_file_status(&e), e.to_string())
    }
}

impl From<IdentifyError> for Failure {
    fn from(e: IdentifyError) -> Self {
        let status = match &e {
            IdentifyError::Data(_) | IdentifyError::InvalidOption { .. } => {
                HystcompStatus::InvalidArgument
            }
            IdentifyError::Core(core) => core_status(core),
            IdentifyError::ModelFile(file) => model_file_status(file),
            _ => HystcompStatus::IdentificationFailed,
        };
        Failure::new(status, e.to_string())
    }
}

impl From<IndexError> for Failure {
    fn from(e: IndexError) -> Self {
        // Every index error is about the arguments: lengths, NaN, a constant desired record,
        // the number of bins.
        Failure::invalid(e.to_string())
    }
}

thread_local! {
    /// The message of the last failed call on this thread, NUL-terminated.
    pub(crate) static LAST_ERROR: RefCell<Vec<u8>> = RefCell::new(vec![0]);
}

pub(crate) fn set_last_error(message: &str) {
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
pub(crate) fn boundary(body: impl FnOnce() -> Result<(), Failure>) -> c_int {
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
