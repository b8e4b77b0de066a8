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
    /// The displacement does not rise with the voltage over the fitted samples: their Pearson
    /// correlation is below [`MIN_CORRELATION`](crate::MIN_CORRELATION) (a wrong column, a
    /// wrong sign, a column of noise).
    NotRising {
        /// The correlation found (NaN when a signal is constant over the fitted samples).
        correlation: f64,
        /// The smallest accepted.
        minimum: f64,
    },
    /// The displacement is the voltage, or an exact linear function of it (correlation 1): the
    /// same column given twice.
    SameSignal,
    /// The fit's RMS error exceeds the limit of
    /// [`IdentifyOptions::max_fit_rms_percent`](crate::IdentifyOptions::max_fit_rms_percent).
    PoorFit {
        /// The RMS error, % of the fitted output range.
        rms_percent: f64,
        /// The limit.
        limit: f64,
    },
    /// The particle swarm ended far from the optimum: its model's RMS error exceeds the
    /// limit while the least-squares optimum of the same problem is within it, so the data
    /// are fine and the swarm did not converge.
    SwarmNotConverged {
        /// The swarm's RMS error, % of the fitted output range.
        rms_percent: f64,
        /// The least-squares optimum's, on the same problem.
        least_squares_rms_percent: f64,
        /// The limit.
        limit: f64,
    },
    /// The identified parameters were refused by the core (should not happen: every
    /// constraint the core checks is part of the fitting problem).
    Core(CoreError),
    /// The model file could not be built.
    ModelFile(ModelFileError),
    /// The chain's vibration link could not be identified (the reason says why).
    Dynamics(String),
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
                 matrix has condition number {condition:.3e} (limit {}). The input \
                 probably does not sweep its range back and forth often enough to tell the play \
                 operators apart: use fewer operators (-n), fewer or more spread thresholds, a \
                 shorter warm-up or hold-out, or a record with full-range cycles",
                number(*limit)
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
            IdentifyError::NotRising {
                correlation,
                minimum,
            } => write!(
                f,
                "the displacement does not rise with the voltage: their correlation over the \
                 fitted samples is {correlation:.3} (at least {minimum} is needed; a piezo \
                 record has about 0.95 or more). Check the columns (--voltage-column, \
                 --displacement-column), the sign (a sensor that reads lower as the stage \
                 extends needs a negative --displacement-factor) and the factors; \
                 --accept-poor-fit fits it anyway"
            ),
            IdentifyError::SameSignal => write!(
                f,
                "the displacement is an exact linear function of the voltage (correlation 1), \
                 which no piezo record is: the same column was probably given for both; check \
                 --voltage-column and --displacement-column"
            ),
            IdentifyError::PoorFit { rms_percent, limit } => write!(
                f,
                "the best model leaves an RMS error of {rms_percent:.1} % of the output range, \
                 more than the {limit} % a usable hysteresis model leaves (an MPIM fits a piezo \
                 record to about 1 %). Check the columns, the factors and the output offset \
                 (--offset fit is right for a sensor with an arbitrary zero); pass \
                 --accept-poor-fit to write the model anyway"
            ),
            IdentifyError::SwarmNotConverged {
                rms_percent,
                least_squares_rms_percent,
                limit,
            } => write!(
                f,
                "the particle swarm did not converge: its best model leaves an RMS error of \
                 {rms_percent:.3} % of the output range, more than {limit} %, where least \
                 squares reaches {least_squares_rms_percent:.3} % on the same data and \
                 thresholds; give the swarm more iterations or particles (--pso-iterations, \
                 --pso-particles), --polish, or use --method ls (pass --accept-poor-fit to \
                 write the swarm's model anyway)"
            ),
            IdentifyError::Core(e) => write!(f, "the identified model is refused: {e}"),
            IdentifyError::ModelFile(e) => e.fmt(f),
            IdentifyError::Dynamics(reason) => {
                write!(f, "the vibration link could not be identified: {reason}")
            }
        }
    }
}

/// A number as people write it: `1e10`, `1.5`, `2500`.
fn number(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e5).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        x.to_string()
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
