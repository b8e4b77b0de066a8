//! The one error type of the stage crate.

use std::fmt;
use std::path::PathBuf;

/// Why a stage could not be built: a stage file that does not parse, a value that is
/// physically impossible, or a file that could not be read.
#[derive(Debug, Clone, PartialEq)]
pub enum StageError {
    /// The TOML text is not valid, has an unknown key or a value of the wrong type. The
    /// message of the TOML parser names the key and the line.
    Parse {
        /// What the parser said.
        message: String,
    },
    /// A value is out of its allowed range, e.g. a negative damping ratio.
    Invalid {
        /// Dotted path of the field in the stage file, e.g. `amplifier.bandwidth_hz`.
        field: &'static str,
        /// What the value must be, e.g. `> 0`.
        requirement: String,
        /// The value found, as written back.
        value: String,
    },
    /// A file named in the stage file (`field`) could not be read or is not usable.
    FieldFile {
        /// Dotted path of the field that names the file, e.g. `hysteresis.mpim.model_file`.
        field: &'static str,
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The stage file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        message: String,
    },
}

impl StageError {
    pub(crate) fn invalid(
        field: &'static str,
        requirement: impl Into<String>,
        value: impl fmt::Display,
    ) -> Self {
        StageError::Invalid {
            field,
            requirement: requirement.into(),
            value: value.to_string(),
        }
    }

    /// The dotted field path of an [`StageError::Invalid`] or [`StageError::FieldFile`]
    /// error, `None` otherwise.
    pub fn field(&self) -> Option<&'static str> {
        match self {
            StageError::Invalid { field, .. } | StageError::FieldFile { field, .. } => Some(field),
            _ => None,
        }
    }
}

impl fmt::Display for StageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StageError::Parse { message } => {
                write!(
                    f,
                    "invalid stage file: {}",
                    message.trim_end().replace('\n', "\n  ")
                )
            }
            StageError::Invalid {
                field,
                requirement,
                value,
            } => write!(f, "{field} must be {requirement}, got {value}"),
            StageError::FieldFile {
                field,
                path,
                message,
            } => write!(
                f,
                "{field}: cannot use the file {}: {message}",
                path.display()
            ),
            StageError::Io { path, message } => {
                write!(
                    f,
                    "cannot read the stage file {}: {message}",
                    path.display()
                )
            }
        }
    }
}

impl std::error::Error for StageError {}
