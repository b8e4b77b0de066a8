//! Why a learning update could not be made.

use std::fmt;

use hystcomp_indices::IndexError;
use hystcomp_io::compensator::CompensatorError;
use hystcomp_io::model_file::ModelFileError;

/// Why a [`crate::Learner`] could not be built or updated. The messages name what to change.
#[derive(Debug, Clone, PartialEq)]
pub enum LearnError {
    /// An option out of its range: the option, its value and the range.
    Option {
        /// The option, e.g. `gain`.
        option: &'static str,
        /// The value given.
        value: String,
        /// What is accepted.
        reason: String,
    },
    /// Two records of one trial differ in length.
    Length {
        /// Which record, e.g. `measured`.
        what: &'static str,
        /// Samples expected (the desired trajectory's).
        expected: usize,
        /// Samples found.
        found: usize,
    },
    /// A sample is NaN or infinite.
    NonFinite {
        /// Which record.
        what: &'static str,
        /// The sample, 0-based.
        index: usize,
    },
    /// The model file cannot drive the learning (an inverse model, a broken model).
    Model(String),
    /// The compensator could not be built.
    Compensator(CompensatorError),
    /// The trial's indices could not be computed.
    Index(IndexError),
    /// The divergence guard stopped the learning earlier; the drive is the last good one.
    Stopped {
        /// The trial whose error tripped the guard.
        trial: usize,
        /// The trial whose drive is kept.
        best_trial: usize,
    },
}

impl fmt::Display for LearnError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LearnError::Option {
                option,
                value,
                reason,
            } => write!(f, "{option} = {value} cannot be used: {reason}"),
            LearnError::Length {
                what,
                expected,
                found,
            } => write!(
                f,
                "the {what} record has {found} samples but the desired trajectory has {expected}; \
                 a trial's desired, drive and measured records must be aligned sample by sample"
            ),
            LearnError::NonFinite { what, index } => write!(
                f,
                "the {what} record's sample {} (row {} of its data) is not a finite number",
                index,
                index + 1
            ),
            LearnError::Model(message) => f.write_str(message),
            LearnError::Compensator(e) => write!(f, "{e}"),
            LearnError::Index(e) => write!(f, "{e}"),
            LearnError::Stopped { trial, best_trial } => write!(
                f,
                "the divergence guard stopped the learning at trial {trial}; the drive is the \
                 last good one (trial {best_trial}); start again with a lower gain or bandwidth"
            ),
        }
    }
}

impl std::error::Error for LearnError {}

impl From<CompensatorError> for LearnError {
    fn from(e: CompensatorError) -> Self {
        LearnError::Compensator(e)
    }
}

impl From<IndexError> for LearnError {
    fn from(e: IndexError) -> Self {
        LearnError::Index(e)
    }
}

impl From<ModelFileError> for LearnError {
    fn from(e: ModelFileError) -> Self {
        LearnError::Model(e.to_string())
    }
}
