//! Rust errors as Python exceptions, with the Rust message (which says what to change).
//!
//! The exception classes live in `hystcomp/_errors.py` (so that they can inherit from both
//! `HystcompError` and the matching built-in, e.g. `ValueError`); files that cannot be read or
//! written raise the built-in `OSError` subclasses (`FileNotFoundError`, `PermissionError`...).

use std::io;

use hystcomp_core::CoreError;
use hystcomp_experiments::{IndexError, StudyError};
use hystcomp_identify::IdentifyError;
use hystcomp_io::compensator::CompensatorError;
use hystcomp_io::model_file::ModelFileError;
use hystcomp_stage::StageError;
use pyo3::exceptions::{
    PyFileNotFoundError, PyIsADirectoryError, PyOSError, PyPermissionError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::PyType;

/// The exception classes of `hystcomp._errors`.
#[derive(Debug, Clone, Copy)]
pub enum Kind {
    /// `InvalidValueError(HystcompError, ValueError)`.
    InvalidValue,
    /// `NotInvertibleError(InvalidValueError)`.
    NotInvertible,
    /// `WrongDirectionError(InvalidValueError)`.
    WrongDirection,
    /// `UnstableDelayError(NotInvertibleError)`.
    UnstableDelay,
    /// `ModelFileError(HystcompError, ValueError)`.
    ModelFile,
    /// `IdentificationError(HystcompError, ValueError)`.
    Identification,
    /// `StageConfigError(HystcompError, ValueError)`.
    StageConfig,
    /// `LearningStoppedError(HystcompError, RuntimeError)`.
    LearningStopped,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::InvalidValue => "InvalidValueError",
            Kind::NotInvertible => "NotInvertibleError",
            Kind::WrongDirection => "WrongDirectionError",
            Kind::UnstableDelay => "UnstableDelayError",
            Kind::ModelFile => "ModelFileError",
            Kind::Identification => "IdentificationError",
            Kind::StageConfig => "StageConfigError",
            Kind::LearningStopped => "LearningStoppedError",
        }
    }
}

/// A `hystcomp` exception of `kind` with `message`.
pub fn error(kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| {
        let class = py
            .import("hystcomp._errors")
            .and_then(|m| m.getattr(kind.class_name()))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match class {
            Ok(class) => PyErr::from_type(class, message),
            // Only if the package's Python files are missing: still a ValueError.
            Err(_) => PyValueError::new_err(message),
        }
    })
}

/// `InvalidValueError` with `message`.
pub fn invalid(message: impl Into<String>) -> PyErr {
    error(Kind::InvalidValue, message)
}

/// The built-in `OSError` subclass for `kind`, with the full message and the path.
pub fn os_error(kind: io::ErrorKind, errno: Option<i32>, message: String, path: String) -> PyErr {
    let errno = errno.unwrap_or(0);
    match kind {
        io::ErrorKind::NotFound => PyFileNotFoundError::new_err((errno, message, path)),
        io::ErrorKind::PermissionDenied => PyPermissionError::new_err((errno, message, path)),
        io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err((errno, message, path)),
        _ => PyOSError::new_err((errno, message, path)),
    }
}

fn core_kind(e: &CoreError) -> Kind {
    match e {
        CoreError::NotInvertible { .. }
        | CoreError::PiPartNotInvertible { .. }
        | CoreError::NonPositiveA2 { .. } => Kind::NotInvertible,
        CoreError::DelayedLoopUnstable { .. } => Kind::UnstableDelay,
        _ => Kind::InvalidValue,
    }
}

/// A core error: `NotInvertibleError` or `InvalidValueError`.
pub fn core(e: CoreError) -> PyErr {
    error(core_kind(&e), e.to_string())
}

/// A compensator that could not be built.
pub fn compensator(e: CompensatorError) -> PyErr {
    let kind = match &e {
        CompensatorError::WrongDirection { .. } => Kind::WrongDirection,
        CompensatorError::Core(c) => core_kind(c),
        _ => Kind::InvalidValue,
    };
    error(kind, e.to_string())
}

/// A model file that could not be read, parsed, validated or written.
pub fn model_file(e: ModelFileError) -> PyErr {
    match e {
        ModelFileError::Io {
            ref path,
            ref source,
        } => {
            let (kind, errno, path) = (source.kind(), source.raw_os_error(), path.clone());
            os_error(kind, errno, e.to_string(), path)
        }
        ModelFileError::Write(ref source) => {
            // The message already names the path (write_atomic).
            let message = e.to_string();
            match source.kind() {
                io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
                io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
                io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
                _ => PyOSError::new_err(message),
            }
        }
        ModelFileError::Model(c) => {
            let kind = core_kind(&c);
            error(kind, format!("the model parameters are refused: {c}"))
        }
        other => error(Kind::ModelFile, other.to_string()),
    }
}

/// An identification that failed.
pub fn identify(e: IdentifyError) -> PyErr {
    match e {
        IdentifyError::Data(d) => invalid(d.to_string()),
        IdentifyError::InvalidOption { .. } => invalid(e.to_string()),
        other => error(Kind::Identification, other.to_string()),
    }
}

/// A stage that could not be built.
pub fn stage(e: StageError) -> PyErr {
    match &e {
        StageError::Io { path, .. } => {
            let kind = if path.exists() {
                io::ErrorKind::Other
            } else {
                io::ErrorKind::NotFound
            };
            os_error(kind, None, e.to_string(), path.display().to_string())
        }
        _ => error(Kind::StageConfig, e.to_string()),
    }
}

/// Indices that could not be computed.
pub fn index(e: IndexError) -> PyErr {
    invalid(e.to_string())
}

/// A study that could not run.
pub fn study(e: StudyError) -> PyErr {
    match e {
        StudyError::Stage(s) => stage(s),
        StudyError::Identify {
            model,
            error: inner,
        } => error(
            Kind::Identification,
            format!("identifying the {model} model: {inner}"),
        ),
        StudyError::Compensator { run, error: inner } => {
            let kind = match &inner {
                CompensatorError::Core(c) => core_kind(c),
                _ => Kind::InvalidValue,
            };
            error(kind, format!("{run}: {inner}"))
        }
        other => invalid(other.to_string()),
    }
}
