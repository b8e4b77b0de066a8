//! The one error type of the identification crate.

use std::fmt;

use hystcomp_core::CoreError;
use hystcomp_io::data::DataError;
use hystcomp_io::model_file::ModelFileError;

/// Why a model could not be identified or cross-validated. Every message says what to change.
#[derive(Debug)]
#[non_exhaustive]
pub enum IdentifyError {
    /// The samples are unusable: NaN or infinite values, columns of different lengths, a
    /// constant signal, too few samples (the message says how many are needed).
    Data(DataError),
    /// An option that cannot be used (a threshold outside `[0, 1)`, a hold-out fraction of 1,
    /// a swarm of one particle...).
    InvalidOption {
        /// The option, as the command line names it (e.g. `holdout`).
        option: &'static str,
        /// The value given.
        value: String,
        /// Why it cannot be used and what to give instead.
        reason: String,
    },
    /// The regressors of the fitting span are (nearly) linearly dependent: some parameter is
    /// not determined by the data.
    IllConditioned {
        /// The condition number of the column-scaled regressor matrix.
        condition: f64,
        /// The limit it exceeded.
        limit: f64,
    },
    /// The invertibility constraints cannot be met (only possible with unusual thresholds).
    Infeasible {
        /// What the solver reported.
        reason: String,
    },
    /// The quadratic-programming solver failed.
    Solver {
        /// What the solver reported.
        reason: String,
    },
    /// The particle swarm ended without a parameter vector that meets the constraints.
    SwarmInfeasible {
        /// The total constraint violation of the best particle (normalised slope units).
        violation: f64,
    },
    /// The identified parameters were refused by the core (should not happen: every
    /// constraint the core checks is part of the fitting problem).
    Core(CoreError),
    /// The model file could not be built.
    ModelFile(ModelFileError),
}

impl fmt::Display for IdentifyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IdentifyError::Data(e) => e.fmt(f),
            IdentifyError::InvalidOption {
                option,
                value,
                reason,
            } => write!(f, "invalid {option} \"{value}\": {reason}"),
            IdentifyError::IllConditioned { condition, limit } => write!(
                f,
                "the data do not determine every model parameter: the column-scaled regressor \
                 matrix has condition number {condition:.3e} (limit {limit:.0e}). The input \
                 probably does not sweep its range back and forth often enough to tell the play \
                 operators apart: use fewer operators (-n), fewer or more spread thresholds, a \
                 shorter warm-up or hold-out, or a record with full-range cycles"
            ),
            IdentifyError::Infeasible { reason } => write!(
                f,
                "no model meets the invertibility constraints ({reason}); check the thresholds \
                 (they must lie in [0, 1) of the input range) or lower the slope margin"
            ),
            IdentifyError::Solver { reason } => write!(
                f,
                "the quadratic-programming solver failed ({reason}); try --method pso, or fewer \
                 play operators"
            ),
            IdentifyError::SwarmInfeasible { violation } => write!(
                f,
                "the particle swarm found no model that meets the invertibility constraints \
                 (best total violation {violation:.3e}); use more iterations or particles, a \
                 larger penalty, --polish, or --method ls"
            ),
            IdentifyError::Core(e) => write!(f, "the identified model is refused: {e}"),
            IdentifyError::ModelFile(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for IdentifyError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            IdentifyError::Data(e) => Some(e),
            IdentifyError::Core(e) => Some(e),
            IdentifyError::ModelFile(e) => Some(e),
            _ => None,
        }
    }
}

impl From<DataError> for IdentifyError {
    fn from(e: DataError) -> Self {
        IdentifyError::Data(e)
    }
}

impl From<CoreError> for IdentifyError {
    fn from(e: CoreError) -> Self {
        IdentifyError::Core(e)
    }
}

impl From<ModelFileError> for IdentifyError {
    fn from(e: ModelFileError) -> Self {
        IdentifyError::ModelFile(e)
    }
}
