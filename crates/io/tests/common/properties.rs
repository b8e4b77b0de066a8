//! What the readers promise on any input, whatever its bytes: shared by the proptests
//! (`tests/any_input.rs`, on stable, in CI) and the fuzz targets `text`, `mat` and `model`
//! (`fuzz/`), so that both check the same properties.
//!
//! - A record read is usable: one name and one column per selected column, all of one
//!   length of at least one sample, every value finite and within `MAX_MAGNITUDE`.
//! - A refusal names the file (all but a refused selection, which names no file).
//! - A model file that loads reloads from its own text to the same text (bit for bit), and
//!   every compensator built from it emits finite drives within its limits, whatever it is fed.
#![allow(dead_code)]

use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::data::{Columns, DataError, MAX_MAGNITUDE};
use hystcomp_io::model_file::ModelFile;

/// Checks the result of reading `selected` columns of a file named `name`.
pub fn check_record(
    result: &Result<Columns, DataError>,
    name: &str,
    selected: usize,
) -> Result<(), String> {
    match result {
        Ok(columns) => {
            if columns.names.len() != selected || columns.values.len() != selected {
                return Err(format!(
                    "{selected} columns selected, {} names and {} columns read",
                    columns.names.len(),
                    columns.values.len()
                ));
            }
            let len = columns.len();
            if len == 0 || columns.values.iter().any(|c| c.len() != len) {
                return Err(format!("columns of lengths {:?}", lengths(columns)));
            }
            if let Some(v) = columns
                .values
                .iter()
                .flatten()
                .find(|v| !(v.is_finite() && v.abs() <= MAX_MAGNITUDE))
            {
                return Err(format!("a value {v} was read"));
            }
            if columns.first_row == 0 {
                return Err("rows count from 1, not 0".to_owned());
            }
            Ok(())
        }
        Err(error) => {
            let message = error.to_string();
            if message.trim().is_empty() {
                return Err(format!("an empty message for {error:?}"));
            }
            if !matches!(error, DataError::InvalidArgument { .. }) && !message.contains(name) {
                return Err(format!("the message does not name {name}: {message}"));
            }
            Ok(())
        }
    }
}

fn lengths(columns: &Columns) -> Vec<usize> {
    columns.values.iter().map(Vec::len).collect()
}

/// Desired positions every compensator is fed: the model's range, beyond it and the values no
/// trajectory should hold.
fn probes(file: &ModelFile) -> Vec<f64> {
    let (offset, scale) = match file.direction {
        hystcomp_io::model_file::Direction::Plant => (file.output.offset, file.output.scale),
        hystcomp_io::model_file::Direction::Inverse => (file.input.offset, file.input.scale),
    };
    let mut values: Vec<f64> = [0.0, 0.25, 0.5, 0.75, 1.0, 0.5, -0.5, 2.0, 0.1]
        .iter()
        .map(|x| offset + scale * x)
        .collect();
    values.extend([
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e308,
        -1e308,
        5e-324,
        0.0,
        offset,
    ]);
    values
}

/// Checks a model file's text: refused with a message, or loaded, reloaded to the same text,
/// and every compensator built from it safe on any desired position.
pub fn check_model_text(text: &str) -> Result<(), String> {
    let file = match ModelFile::from_json(text) {
        Ok(file) => file,
        Err(error) => {
            return if error.to_string().trim().is_empty() {
                Err(format!("an empty message for {error:?}"))
            } else {
                Ok(())
            };
        }
    };
    let saved = file.to_json();
    let again = ModelFile::from_json(&saved)
        .map_err(|e| format!("a loaded model does not reload from its own text: {e}"))?;
    if again.to_json() != saved {
        return Err(format!(
            "the model does not reload bit for bit:\n{saved}\n{}",
            again.to_json()
        ));
    }
    for method in Method::ALL {
        let Ok(mut compensator) = ScaledCompensator::new(&file, method, None) else {
            continue;
        };
        let (lo, hi) = compensator.limits();
        for y in probes(&file) {
            let v = compensator.step(y);
            if !(v.is_finite() && lo <= v && v <= hi) {
                return Err(format!(
                    "{method}: drive {v} for y_d = {y}, outside the limits [{lo}, {hi}]"
                ));
            }
        }
    }
    Ok(())
}
