//! A model's prediction of a record (`hystcomp predict`, Python's `predict`, C's
//! `hystcomp_predict`): the model run over its input, beside what was measured.

use hystcomp_io::data::DataError;
use hystcomp_io::model_file::{Direction, ModelFile};
use serde::{Deserialize, Serialize};

use crate::crossval::Record;
use crate::{ErrorStats, IdentifyError};

/// How a [`Prediction`] started.
pub const INITIAL_STATE_RESET: &str = "reset (zero operator memory, eq. (1))";
/// How a [`Prediction`] with a settled creep link started.
pub const INITIAL_STATE_SETTLED: &str = "reset operators, creep settled at the first sample";

/// What [`predict`] found: one predicted and one error value per sample, and their summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Prediction {
    /// The model's direction: a plant model predicts the displacement from the voltage, an
    /// inverse model the voltage from the displacement.
    pub direction: Direction,
    /// The predicted output, physical units (the model file's output unit), one per sample.
    pub predicted: Vec<f64>,
    /// Predicted minus measured output, one per sample.
    pub error: Vec<f64>,
    /// The errors over every sample, in the output's unit and in % of the measured output's
    /// range over the record.
    pub stats: ErrorStats,
    /// Samples whose input lies outside the range the model was identified on (it
    /// extrapolates there).
    pub outside_input_range: usize,
    /// The initial state in words: [`INITIAL_STATE_RESET`] or [`INITIAL_STATE_SETTLED`]. The
    /// first samples, before the input has reached both ends of its range, depend on the
    /// record's history, which the model does not know.
    pub initial_state: String,
}

/// Runs `model` over a record from its reset state (zero operator memory, eq. (1)): a plant
/// model over the voltage, an inverse model over the displacement, each compared with the
/// other column. `settled`: a creep link taken as having rested long at the first sample
/// (see [`ModelFile::predict_settled`]) instead of relaxed at the model's origin.
///
/// Refuses records of different lengths, empty, or not finite ([`IdentifyError::Data`]), and
/// a prediction that is not finite (naming the sample).
pub fn predict(
    model: &ModelFile,
    record: Record<'_>,
    settled: bool,
) -> Result<Prediction, IdentifyError> {
    use hystcomp_io::data::{check_finite, check_min_samples, check_same_length};
    check_same_length(&[
        ("voltage", record.voltage),
        ("displacement", record.displacement),
    ])?;
    check_min_samples(1, record.voltage.len(), "a prediction")?;
    check_finite("voltage", record.voltage)?;
    check_finite("displacement", record.displacement)?;
    let (input, measured) = match model.direction {
        Direction::Plant => (record.voltage, record.displacement),
        Direction::Inverse => (record.displacement, record.voltage),
    };
    let predicted = if settled {
        model.predict_settled(input)
    } else {
        model.predict(input)
    }?;
    let error: Vec<f64> = predicted.iter().zip(measured).map(|(p, m)| p - m).collect();
    if let Some(k) = error.iter().position(|e| !(e * e).is_finite()) {
        return Err(IdentifyError::Data(DataError::NotFinite {
            path: None,
            line: None,
            row: k + 1,
            column: format!(
                "the model's prediction (input {}, predicted {})",
                input[k], predicted[k]
            ),
            value: error[k],
        }));
    }
    let (lo, hi) = measured
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let stats =
        ErrorStats::new(&predicted, measured, hi - lo).expect("the record has a sample at least");
    let (in_lo, in_hi) = (
        model.input.to_physical(model.input_range[0]),
        model.input.to_physical(model.input_range[1]),
    );
    let (in_lo, in_hi) = (in_lo.min(in_hi), in_lo.max(in_hi));
    let slack = 1e-9 * (in_hi - in_lo);
    let outside_input_range = input
        .iter()
        .filter(|&&v| v < in_lo - slack || v > in_hi + slack)
        .count();
    Ok(Prediction {
        direction: model.direction,
        predicted,
        error,
        stats,
        outside_input_range,
        initial_state: if settled {
            INITIAL_STATE_SETTLED
        } else {
            INITIAL_STATE_RESET
        }
        .to_owned(),
    })
}
