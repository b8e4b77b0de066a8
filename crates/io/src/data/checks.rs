//! The checks the command line and identification run on the columns they use.

use super::DataError;

/// Refuses NaN or infinite values, naming the column and the first bad sample (counted from
/// 1) with [`DataError::NotFinite`].
pub fn check_finite(name: &str, values: &[f64]) -> Result<(), DataError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(DataError::NotFinite {
            path: None,
            line: None,
            row: i + 1,
            column: name.to_owned(),
            value: values[i],
        }),
        None => Ok(()),
    }
}

/// Refuses a time column that does not increase strictly from each sample to the next (a
/// repeated or earlier time), with [`DataError::TimeNotIncreasing`] naming the first
/// offending sample (counted from 1), and NaN or infinite times with
/// [`DataError::NotFinite`]. Fewer than two samples pass.
pub fn check_time_increasing(time: &[f64]) -> Result<(), DataError> {
    check_finite("time", time)?;
    for (i, pair) in time.windows(2).enumerate() {
        let increasing = pair[0] < pair[1];
        if !increasing {
            return Err(DataError::TimeNotIncreasing {
                sample: i + 2,
                previous: pair[0],
                value: pair[1],
            });
        }
    }
    Ok(())
}

/// The mean time step of a time column, `(t_last - t_first) / (samples - 1)` (in the column's
/// unit), or `None` for fewer than two samples. Callers that need a usable rate check the
/// step's sign themselves (a column that passed [`check_time_increasing`] has a positive one).
pub fn mean_time_step(time: &[f64]) -> Option<f64> {
    match time {
        [first, .., last] => Some((last - first) / (time.len() - 1) as f64),
        _ => None,
    }
}

/// Refuses a column whose samples are all equal (e.g. an input that was never driven or a
/// sensor that was not connected) with [`DataError::Constant`], and a column of fewer than
/// two samples with [`DataError::TooFewSamples`].
pub fn check_not_constant(name: &str, values: &[f64]) -> Result<(), DataError> {
    match values {
        [] | [_] => Err(DataError::TooFewSamples {
            what: format!("{name} to vary"),
            needed: 2,
            got: values.len(),
        }),
        [first, rest @ ..] => {
            if rest.iter().all(|v| v == first) {
                Err(DataError::Constant {
                    column: name.to_owned(),
                    value: *first,
                    samples: values.len(),
                })
            } else {
                Ok(())
            }
        }
    }
}

/// Refuses `got` samples when `what` (e.g. `identification of a model with 10 play
/// operators`) needs at least `needed`, with [`DataError::TooFewSamples`].
pub fn check_min_samples(needed: usize, got: usize, what: &str) -> Result<(), DataError> {
    if got < needed {
        Err(DataError::TooFewSamples {
            what: what.to_owned(),
            needed,
            got,
        })
    } else {
        Ok(())
    }
}

/// Refuses named columns of different lengths (e.g. an input and an output recorded
/// separately) with [`DataError::LengthMismatch`] listing every length.
pub fn check_same_length(columns: &[(&str, &[f64])]) -> Result<(), DataError> {
    match columns.first() {
        Some((_, first)) if columns.iter().any(|(_, c)| c.len() != first.len()) => {
            Err(DataError::LengthMismatch {
                path: None,
                lengths: columns
                    .iter()
                    .map(|(name, c)| ((*name).to_owned(), c.len()))
                    .collect(),
            })
        }
        _ => Ok(()),
    }
}
