//! What to identify and how: direction, solver, thresholds, warm-up, hold-out, output offset.

use hystcomp_core::Shown;
use hystcomp_io::model_file::Direction;
use serde::{Deserialize, Serialize};

use crate::IdentifyError;
use crate::pso::PsoOptions;

/// The default number of play operators, as in the paper (`n = 10`, section 4.2).
pub const DEFAULT_OPERATORS: usize = 10;

/// The default smallest branch slope the identified model must keep, in normalised units
/// (output range per input range). See [`IdentifyOptions::margin`].
pub const DEFAULT_MARGIN: f64 = 1e-3;

/// The default largest condition number of the column-scaled regressor matrix.
pub const DEFAULT_MAX_CONDITION: f64 = 1e10;

/// `crossval`'s automatic test warm-up ends at the first sample whose voltage is at most this
/// fraction of the test record's voltage range above its minimum. (Identification's
/// [`Warmup::Auto`] waits instead for the memory to become known:
/// [`crate::warmup::MEMORY_TOLERANCE`].)
pub const AUTO_WARMUP_LEVEL: f64 = 0.05;

/// The smallest Pearson correlation between the voltage and the displacement over the fitted
/// samples that [`crate::identify`] accepts. A piezo actuator's displacement rises with its
/// voltage: even with a 15-20 % hysteresis loop, creep and sensor noise the correlation of
/// real records is above 0.95 (0.978 on the DBO record), and a linear fit alone leaves several
/// % RMS error. Below 0.5 the displacement does not follow the voltage: a wrong column, a
/// wrong sign, a column of noise. The MPIM would still be fitted (its weights can take any
/// sign) with a meaningless, tens-of-% error.
pub const MIN_CORRELATION: f64 = 0.5;

/// The default largest RMS fit error accepted, in % of the fitted output range. A linear
/// model alone leaves about 3-8 % on piezo hysteresis (7.3 % on the DBO record), an MPIM
/// well under 1 %; an RMS above 10 % means the data or the options are wrong (an output
/// offset far off the data, a record that is not a hysteresis loop...). See
/// [`IdentifyOptions::max_fit_rms_percent`].
pub const DEFAULT_MAX_FIT_RMS_PERCENT: f64 = 10.0;

/// The default bound on both delayed loops' gains of a model identified for delayed
/// compensation ([`IdentifyOptions::delayed_loop_bound`], the command line's `--for-delayed`):
/// 10 % below 1, so that after a jump the delayed loop's error shrinks by at least 10 % a
/// sample (to 1 % of itself within 44 samples) with room for the model's rounding.
pub const DEFAULT_DELAYED_LOOP_BOUND: f64 = 0.9;

/// The most play operators identification fits (1000): the least-squares problem and its
/// checks grow with the square of the operators (1000 operators: about 12 s and 55 MB on the
/// DBO record; 5000 took 2 GB).
pub const MAX_OPERATORS: usize = 1_000;

/// The most values the model's operator outputs over the record may take, samples times
/// operators (5e7, 400 MB of `f64`): checked before they are computed.
pub const MAX_REGRESSOR_VALUES: usize = 50_000_000;

/// At least this many fitting samples per parameter of the model.
pub const SAMPLES_PER_PARAMETER: usize = 3;

/// How the play-operator thresholds `r_i` are chosen, in normalised input units (fractions of
/// the input range).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Thresholds {
    /// `r_i = (i - 1) / n`, `i = 1..n`: eq. (11) of the paper applied to the normalised input
    /// `(x - x_min) / (x_max - x_min)`, so that it also holds for inputs that do not start at 0
    /// or are bipolar.
    Uniform(usize),
    /// Thresholds given by the user: strictly increasing, in `[0, 1)`.
    Given(Vec<f64>),
}

impl Thresholds {
    /// The thresholds, checked: at least one, finite, strictly increasing, in `[0, 1)` (an
    /// operator with `r >= 1` never moves on inputs within the range and cannot be identified).
    pub fn values(&self) -> Result<Vec<f64>, IdentifyError> {
        let invalid = |value: String, reason: &str| IdentifyError::InvalidOption {
            option: "thresholds",
            value,
            reason: reason.to_owned(),
        };
        match self {
            Thresholds::Uniform(0) => Err(IdentifyError::InvalidOption {
                option: "number of play operators",
                value: "0".to_owned(),
                reason: "give at least 1 (the paper uses 10)".to_owned(),
            }),
            Thresholds::Uniform(n) if *n > MAX_OPERATORS => Err(IdentifyError::InvalidOption {
                option: "number of play operators",
                value: n.to_string(),
                reason: format!(
                    "give at most {MAX_OPERATORS} (the paper uses 10; the fit's cost grows with \
                     the square of the operators)"
                ),
            }),
            Thresholds::Uniform(n) => Ok((0..*n).map(|i| i as f64 / *n as f64).collect()),
            Thresholds::Given(values) => {
                let text = values
                    .iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join(",");
                if values.is_empty() {
                    return Err(invalid(text, "give at least one threshold"));
                }
                if values.len() > MAX_OPERATORS {
                    return Err(invalid(
                        format!("{} thresholds", values.len()),
                        &format!("give at most {MAX_OPERATORS} thresholds"),
                    ));
                }
                if values
                    .iter()
                    .any(|r| !(r.is_finite() && (0.0..1.0).contains(r)))
                {
                    return Err(invalid(
                        text,
                        "thresholds are fractions of the input range: each must lie in [0, 1)",
                    ));
                }
                if values.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(invalid(
                        text,
                        "thresholds must increase strictly (two equal thresholds cannot be told apart)",
                    ));
                }
                Ok(values.clone())
            }
        }
    }
}

impl Default for Thresholds {
    fn default() -> Self {
        Thresholds::Uniform(DEFAULT_OPERATORS)
    }
}

/// Where the play operators' memory at the start of the record comes from, and so which
/// samples are fitted (see [`crate::warmup`] for the reasoning).
///
/// A record may start mid-range, after a history nobody recorded. The operators' memory is
/// then unknown until the voltage first reaches the record's minimum or maximum: there every
/// operator's memory is fixed whatever came before (wiping-out, provided the unknown history
/// stayed within the record's range). The report says which samples were used and why
/// ([`crate::FitReport::warmup`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Warmup {
    /// The warm-up ends where the memory becomes known: at the first sample where the voltage
    /// reaches the record's minimum or maximum (no warm-up when the record starts there). The
    /// voltage decides in both directions: it drives the device's state, and it is clean,
    /// while a displacement record may start with a transient. The operators run from zero
    /// memory at the first sample, which from that sample on gives exactly the memory any
    /// history would.
    #[default]
    Auto,
    /// Every sample is fitted, and the operators' memory at the first sample is estimated
    /// together with the parameters: the memory left by a virtual history (the input came from
    /// one end of the record's range to a turning point `v0`, then to the first sample),
    /// `v0` searched by least squares ([`crate::warmup`]). Best on records that start
    /// mid-range with a clean response; a record starting with a transient (a voltage step the
    /// stage has not followed yet) is better served by [`Warmup::Auto`], which leaves those
    /// samples out. The particle swarm solves with the history least squares chose.
    Estimate,
    /// A fixed number of samples, excluded from the fit (the operators run over them from zero
    /// memory at the first sample).
    Samples(usize),
}

/// How the model output is related to the measured output column. The MPIM of eq. (4) has no
/// constant term: from zero memory at normalised input 0 it outputs 0. A sensor offset must
/// therefore be removed before the fit, or fitted.
///
/// In every case the output scale is `y_max - y_min` over the fitted samples (neither the
/// warm-up nor the hold-out), and the model file's
/// `output.offset` is the physical output the model's normalised output 0 stands for.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OutputOffset {
    /// A constant column is added to the regression; the fitted constant `c` moves into the
    /// model file: `output.offset = y_min + c (y_max - y_min)`. Right for sensors with an
    /// arbitrary zero (the default).
    #[default]
    Fit,
    /// No constant: `output.offset = y_min`, i.e. the output is taken to be at its minimum when
    /// the input is at its minimum (the paper's normalisation).
    None,
    /// No constant: `output.offset` is this physical value (e.g. `0` for a calibrated sensor
    /// that reads 0 at 0 V).
    Value(f64),
}

/// Which solver minimises the RMS model error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Constrained linear least squares: the global optimum for the given thresholds
    /// ([`crate::LeastSquares`]).
    #[default]
    LeastSquares,
    /// Particle swarm optimisation as the paper uses ([`crate::ParticleSwarm`]).
    ParticleSwarm(PsoOptions),
}

/// Everything [`crate::identify`] needs besides the samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IdentifyOptions {
    /// `Plant`: voltage in, displacement out (for IHC and WIHC). `Inverse`: displacement in,
    /// voltage out (for DIHC, section 3.3).
    pub direction: Direction,
    /// The solver.
    pub method: Method,
    /// The play-operator thresholds.
    pub thresholds: Thresholds,
    /// Samples at the start excluded from the fit.
    pub warmup: Warmup,
    /// The fraction of the samples after the warm-up, at the end of the record, held out of
    /// the fit and reported separately, in `[0, 1)`. The held-out samples inform nothing:
    /// not the parameters, nor the normalisation ranges (they may fall outside them).
    pub holdout: f64,
    /// The output offset.
    pub offset: OutputOffset,
    /// The smallest branch slope the model must keep, in normalised units (> 0). Both signals
    /// are normalised by their ranges, so the mean slope of the data is 1 and the default
    /// [`DEFAULT_MARGIN`] is 0.1 % of it: it bounds the gain of the inverse (at most 1000 times
    /// the mean) and leaves room for rounding in the core's check, while real piezo data have
    /// minimum branch slopes of order 0.1 to 1, so it binds only where the data would
    /// otherwise give a non-invertible model.
    pub margin: f64,
    /// The largest condition number of the column-scaled regressor matrix accepted.
    pub max_condition: f64,
    /// The largest RMS fit error accepted, in % of the fitted output range
    /// ([`DEFAULT_MAX_FIT_RMS_PERCENT`]); `None` accepts any fit (the command line's
    /// `--accept-poor-fit`).
    pub max_fit_rms_percent: Option<f64>,
    /// Plant models meant for one-sample-delayed compensation: both delayed loops' gains
    /// (delayed IHC and WIHC, over the whole reachable state) constrained to at most this
    /// bound, in `(0, 1)` ([`DEFAULT_DELAYED_LOOP_BOUND`] from the command line's
    /// `--for-delayed`); the report gives what it costs in fit RMS. `None`: not constrained
    /// (the gains are reported, and `hystcomp compensate` refuses a plain delayed loop whose
    /// gain is 1 or more). Ignored for inverse models, which have no delayed loop.
    pub delayed_loop_bound: Option<f64>,
    /// The degree of the odd input polynomial `g(x) = a2 x + a1 x^3 + c5 x^5 + ...` (eq. (3)
    /// generalised; [`crate::FitProblem::with_input_degree`]): 3 (the paper's cubic, the
    /// default), 5, 7 or 9. Least squares only: the particle swarm fits the cubic.
    #[serde(default = "paper_input_degree")]
    pub input_degree: usize,
    /// The degree of the output map `psi(y) = y - e_2 y^2 - ... - e_K y^K` fitted jointly
    /// with the MPIM, `psi(y) = H[x] + c` ([`crate::FitProblem::with_output_map`];
    /// `hystcomp_core::OutputMap`): 1 (none, the paper's model and the default) to
    /// [`crate::problem::MAX_OUTPUT_MAP_DEGREE`]. Least squares only.
    #[serde(default = "no_output_map")]
    pub output_map_degree: usize,
    /// Unit of the voltage samples, written to the model file.
    pub voltage_unit: String,
    /// Unit of the displacement samples, written to the model file.
    pub displacement_unit: String,
}

/// No output map: the default output map degree (serde's default for older options).
fn no_output_map() -> usize {
    1
}

/// The paper's cubic: the default input degree (serde's default for older options).
fn paper_input_degree() -> usize {
    3
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        IdentifyOptions {
            direction: Direction::Plant,
            method: Method::LeastSquares,
            thresholds: Thresholds::default(),
            warmup: Warmup::Auto,
            holdout: 0.0,
            offset: OutputOffset::Fit,
            margin: DEFAULT_MARGIN,
            max_condition: DEFAULT_MAX_CONDITION,
            max_fit_rms_percent: Some(DEFAULT_MAX_FIT_RMS_PERCENT),
            delayed_loop_bound: None,
            input_degree: 3,
            output_map_degree: 1,
            voltage_unit: "V".to_owned(),
            displacement_unit: "um".to_owned(),
        }
    }
}

impl IdentifyOptions {
    /// Checks the options that do not depend on the data.
    pub fn validate(&self) -> Result<(), IdentifyError> {
        self.thresholds.values()?;
        crate::problem::check_output_map_degree(self.output_map_degree)?;
        if self.output_map_degree > 1 && self.method != Method::LeastSquares {
            return Err(IdentifyError::InvalidOption {
                option: "output map degree",
                value: self.output_map_degree.to_string(),
                reason: "the output map is fitted by least squares only; use ls".to_owned(),
            });
        }
        if let Some(bound) = self.delayed_loop_bound
            && !(bound > 0.0 && bound < 1.0)
        {
            return Err(IdentifyError::InvalidOption {
                option: "delayed loop bound",
                value: Shown(bound).to_string(),
                reason: "the delayed loops' gain bound must lie strictly between 0 and 1"
                    .to_owned(),
            });
        }
        if !(self.holdout.is_finite() && (0.0..1.0).contains(&self.holdout)) {
            return Err(IdentifyError::InvalidOption {
                option: "holdout",
                value: Shown(self.holdout).to_string(),
                reason: "the hold-out is a fraction of the samples in [0, 1), e.g. 0.2".to_owned(),
            });
        }
        if !(self.margin.is_finite() && self.margin > 0.0 && self.margin < 1.0) {
            return Err(IdentifyError::InvalidOption {
                option: "margin",
                value: Shown(self.margin).to_string(),
                reason: "the slope margin is a small positive slope in normalised units, in \
                         (0, 1); the default is 0.001"
                    .to_owned(),
            });
        }
        if !(self.max_condition.is_finite() && self.max_condition > 1.0) {
            return Err(IdentifyError::InvalidOption {
                option: "max-condition",
                value: Shown(self.max_condition).to_string(),
                reason: "give a condition number > 1, e.g. 1e10".to_owned(),
            });
        }
        if let Some(limit) = self.max_fit_rms_percent
            && !(limit.is_finite() && limit > 0.0)
        {
            return Err(IdentifyError::InvalidOption {
                option: "largest fit RMS",
                value: Shown(limit).to_string(),
                reason: "give a positive percentage of the output range (the default is 10)"
                    .to_owned(),
            });
        }
        if let OutputOffset::Value(v) = self.offset
            && !v.is_finite()
        {
            return Err(IdentifyError::InvalidOption {
                option: "offset",
                value: Shown(v).to_string(),
                reason: "give fit, none or a finite number".to_owned(),
            });
        }
        for (option, unit) in [
            ("voltage unit", &self.voltage_unit),
            ("displacement unit", &self.displacement_unit),
        ] {
            if unit.trim().is_empty() {
                return Err(IdentifyError::InvalidOption {
                    option,
                    value: unit.clone(),
                    reason: "name the unit, e.g. V or um".to_owned(),
                });
            }
        }
        crate::problem::check_input_degree(self.input_degree)?;
        if let Method::ParticleSwarm(pso) = &self.method {
            pso.validate()?;
            if self.input_degree != 3 {
                return Err(IdentifyError::InvalidOption {
                    option: "input degree",
                    value: self.input_degree.to_string(),
                    reason: "the particle swarm fits the paper's cubic only (its search \
                             bounds are the cubic's); fit a higher degree by least squares \
                             (method ls)"
                        .to_owned(),
                });
            }
        }
        Ok(())
    }
}
