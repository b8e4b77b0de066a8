//! The one error type of the core.

use crate::Shown;
use core::fmt;

/// Why a model, a compensator or a call was refused. Values are reported as `f64` whatever the
/// sample type, so that messages read the same on every target.
#[derive(Debug, Clone, PartialEq)]
pub enum CoreError {
    /// Two arrays that must have one entry per operator (or per sample) have different lengths.
    LengthMismatch {
        /// What was being compared, e.g. `"weights"`.
        what: &'static str,
        /// The length required.
        expected: usize,
        /// The length given.
        found: usize,
    },
    /// A parameter is NaN or infinite.
    NonFinite {
        /// Which parameter, e.g. `"thresholds"` or `"a1"`.
        what: &'static str,
        /// Its index when it is one entry of an array.
        index: Option<usize>,
    },
    /// A play-operator threshold is negative (eqs. (1)-(2) need `r >= 0`).
    NegativeThreshold {
        /// Index of the threshold (0-based).
        index: usize,
        /// Its value.
        value: f64,
    },
    /// Thresholds must be sorted in increasing order (`r_1 <= r_2 <= ... <= r_n`).
    UnsortedThresholds {
        /// Index (0-based) of the first threshold smaller than its predecessor.
        index: usize,
    },
    /// A fixed-size storage (`[T; N]`) cannot hold the number of operators asked for.
    Capacity {
        /// Number of operators asked for.
        needed: usize,
        /// Number the storage holds.
        capacity: usize,
    },
    /// Output limits must be finite with `min < max`.
    InvalidLimits {
        /// The lower limit given.
        min: f64,
        /// The upper limit given.
        max: f64,
    },
    /// An input range must be finite with `lo < hi`.
    InvalidRange {
        /// The lower end given.
        lo: f64,
        /// The upper end given.
        hi: f64,
    },
    /// The model output is not strictly increasing in its current input on some branch
    /// reachable within the stated input range, so it cannot be inverted.
    NotInvertible {
        /// The smallest branch slope found, `a2 + 3 a1 x^2 + b_1 + ... + b_k`.
        slope: f64,
        /// The (normalised) input `x` where it occurs.
        input: f64,
        /// How many operators (`k`, the first ones by threshold) are moving with the input there.
        active_operators: usize,
        /// The input range checked.
        range: (f64, f64),
    },
    /// The PI part `P1[v] = a2 v + sum b_i F_ri[v]` has a non-positive branch slope
    /// `a2 + b_1 + ... + b_k`, so its analytic inverse, eq. (7), does not exist.
    PiPartNotInvertible {
        /// Number of operators `k` in the offending prefix sum.
        active_operators: usize,
        /// The value of `a2 + b_1 + ... + b_k`.
        slope: f64,
    },
    /// A one-sample-delayed loop (IHC: `w(t) = y_d(t) - h(v(t - Ts))`; WIHC:
    /// `v(t) = (y_d(t) - H[v](t - Ts)) / a2`) has a loop gain of 1 or more on some branch
    /// reachable within the output limits, so it can ring between the limits (see
    /// [`crate::LoopGain`]). Refused unless [`crate::SolveMode::DelayedAllowUnstable`] asks for it
    /// explicitly; [`crate::SolveMode::DelayedGuarded`] and [`crate::SolveMode::Exact`] never
    /// oscillate.
    DelayedLoopUnstable {
        /// `"IHC"` or `"WIHC"`.
        compensator: &'static str,
        /// The largest loop gain found (must stay below 1).
        gain: f64,
        /// The (normalised) input where it occurs.
        input: f64,
        /// How many operators (the first ones by threshold) are moving there.
        active_operators: usize,
    },
    /// The input polynomial `g(x) = c_1 x + ... + c_D x^D` has no coefficient or more than the
    /// largest degree supported ([`crate::MAX_INPUT_DEGREE`]).
    InputDegree {
        /// The number of coefficients given.
        degree: usize,
        /// The largest degree supported.
        max: usize,
    },
    /// WIHC divides by `a2` (eq. (9)), which must be positive.
    NonPositiveA2 {
        /// The value of `a2`.
        a2: f64,
    },
    /// More entries than the core accepts (creep elements, filter order, delay).
    TooLarge {
        /// What, e.g. `"creep elements"`.
        what: &'static str,
        /// How many were given.
        found: usize,
        /// The most accepted.
        max: usize,
    },
    /// A parameter that must be positive is not (a time constant, the sample period).
    NotPositive {
        /// Which parameter.
        what: &'static str,
        /// Its index when it is one entry of an array.
        index: Option<usize>,
        /// Its value.
        value: f64,
    },
    /// The creep link's weights sum (in absolute value) to 1 or more: its forward link could
    /// be unstable (see `Creep`).
    CreepUnstable {
        /// `sum |c_i|`.
        weight_sum: f64,
    },
    /// The vibration link is unusable: the reason says why.
    VibrationModel {
        /// What is wrong.
        reason: &'static str,
        /// The value concerned (gain, magnitude...).
        value: f64,
    },
    /// The preview is too short for the vibration inverse, or too long.
    Preview {
        /// The preview asked for, samples.
        preview: usize,
        /// The shortest that inverts the model (its delay plus its zeros outside the unit
        /// circle).
        minimum: usize,
        /// The longest accepted.
        maximum: usize,
    },
    /// An array given to a bank of compensators does not hold one value per channel (per
    /// sample, for a whole signal: a multiple of the channel count).
    ChannelCount {
        /// What, e.g. `"desired positions"`.
        what: &'static str,
        /// The bank's number of channels.
        channels: usize,
        /// The number of values given.
        found: usize,
        /// Whether the values are samples (a tick's or a whole signal's), which the message
        /// then says may be a multiple of the channel count; else they are per channel, given
        /// once (models, limits, input ranges).
        samples: bool,
    },
}

impl fmt::Display for CoreError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CoreError::LengthMismatch {
                what,
                expected,
                found,
            } => write!(
                f,
                "{what} has {found} entries but {expected} are needed (one per play operator or per sample)"
            ),
            CoreError::NonFinite {
                what,
                index: Some(i),
            } => {
                write!(
                    f,
                    "{what}[{i}] is NaN or infinite; every parameter must be finite"
                )
            }
            CoreError::NonFinite { what, index: None } => {
                write!(f, "{what} is NaN or infinite; it must be finite")
            }
            CoreError::NegativeThreshold { index, value } => write!(
                f,
                "threshold r[{index}] = {} is negative; play-operator thresholds must be >= 0 (eqs. (1)-(2))",
                Shown(*value)
            ),
            CoreError::UnsortedThresholds { index } => write!(
                f,
                "threshold r[{index}] is smaller than r[{}]; sort the operators by increasing threshold",
                index - 1
            ),
            CoreError::Capacity { needed, capacity } => write!(
                f,
                "the model has {needed} play operators but the fixed storage holds {capacity}; \
                 use storage of length {needed}"
            ),
            CoreError::InvalidLimits { min, max } => write!(
                f,
                "output limits [{min}, {max}] are invalid: both must be finite and min < max"
            ),
            CoreError::InvalidRange { lo, hi } => write!(
                f,
                "input range [{lo}, {hi}] is invalid: both ends must be finite and lo < hi"
            ),
            CoreError::NotInvertible {
                slope,
                input,
                active_operators,
                range,
            } => write!(
                f,
                "the model is not invertible on the input range [{}, {}]: {}, the branch slope \
                 a2 + 3 a1 x^2{} is {slope:.6} at normalised input x = {input:.6} (it must stay \
                 > 0); identify the model with invertibility constraints or narrow the range",
                range.0,
                range.1,
                Moving(*active_operators),
                WeightSum(*active_operators),
            ),
            CoreError::PiPartNotInvertible {
                active_operators,
                slope,
            } => write!(
                f,
                "the PI part a2 v + sum b_i F_ri[v] has no inverse (eq. (7)): \
                 a2{} = {slope:.6} is not > 0; \
                 IHC cannot be built from this model (WIHC may still work)",
                WeightSum(*active_operators),
            ),
            CoreError::DelayedLoopUnstable {
                compensator,
                gain,
                input,
                active_operators,
            } => write!(
                f,
                "the one-sample-delayed {compensator} can oscillate on this model: its loop gain \
                 is {gain:.4} >= 1 at normalised input x = {input:.4} {} ({}); use the exact \
                 solve or the guarded delayed loop, which never oscillate, identify the model \
                 for delayed compensation, or allow the unstable loop explicitly",
                Moving(*active_operators),
                if *compensator == "IHC" {
                    "|g'(x) - a2| / (a2 + b_1 + ... + b_k)"
                } else {
                    "|g'(x) - a2 + b_1 + ... + b_k| / a2"
                },
            ),
            CoreError::InputDegree { degree, max } => write!(
                f,
                "the input polynomial has {degree} coefficient(s); give between 1 and {max} \
                 (c_1 = a2, c_2, c_3 = a1, ..., up to degree {max})"
            ),
            CoreError::NonPositiveA2 { a2 } => {
                write!(f, "WIHC divides by a2 (eq. (9)) but a2 = {a2} is not > 0")
            }
            CoreError::TooLarge { what, found, max } => {
                write!(f, "{found} {what} given; at most {max} are accepted")
            }
            CoreError::NotPositive {
                what,
                index: Some(i),
                value,
            } => write!(
                f,
                "{what}[{i}] = {} must be positive and finite",
                Shown(*value)
            ),
            CoreError::NotPositive {
                what,
                index: None,
                value,
            } => write!(f, "{what} = {} must be positive and finite", Shown(*value)),
            CoreError::CreepUnstable { weight_sum } => write!(
                f,
                "the creep weights sum to {weight_sum:.6} in absolute value; below 1 is needed \
                 for the creep link to be stable"
            ),
            CoreError::VibrationModel { reason, value } => {
                write!(f, "the vibration model is refused: {reason} ({value})")
            }
            CoreError::Preview {
                preview,
                minimum,
                maximum,
            } => write!(
                f,
                "a preview of {preview} samples cannot invert this vibration model: between \
                 {minimum} (its delay plus its zeros outside the unit circle) and {maximum} \
                 are needed"
            ),
            CoreError::ChannelCount {
                what,
                channels,
                found,
                samples,
            } => {
                write!(
                    f,
                    "{what} has {found} values, but a bank of {channels} channels needs one per \
                     channel"
                )?;
                if *samples {
                    write!(
                        f,
                        " (a whole signal: a multiple of {channels}, sample after sample)"
                    )?;
                }
                Ok(())
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for CoreError {}

/// ` + b_1 + ... + b_k` written for people: nothing for `k = 0`, ` + b_1`, ` + b_1 + b_2`,
/// then the ellipsis.
struct WeightSum(usize);

impl fmt::Display for WeightSum {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            0 => Ok(()),
            1 => f.write_str(" + b_1"),
            2 => f.write_str(" + b_1 + b_2"),
            k => write!(f, " + b_1 + ... + b_{k}"),
        }
    }
}

/// "with no play operator moving", "with the first play operator moving", "with the first k
/// play operators moving".
struct Moving(usize);

impl fmt::Display for Moving {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            0 => f.write_str("with no play operator moving"),
            1 => f.write_str("with the first play operator moving"),
            k => write!(f, "with the first {k} play operators moving"),
        }
    }
}
