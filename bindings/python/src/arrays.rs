//! numpy arrays in and out, and the checks every boundary makes on them.

use std::marker::PhantomData;

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::invalid;

/// A one-dimensional array-like of real numbers (a numpy array of any real dtype, a list, a
/// tuple), converted to `float64`. Anything else is refused with a `TypeError` that says what
/// was expected and what was given: an array of another shape (not flattened), complex values
/// (not silently truncated to their real part), strings.
pub struct ArrayIn<'py> {
    values: Vec<f64>,
    _py: PhantomData<&'py ()>,
}

/// `(3, 4)` as Python prints a shape.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for ArrayIn<'py> {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let py = obj.py();
        let numpy = py.import("numpy")?;
        let array = numpy
            .call_method1("asarray", (obj.to_owned(),))
            .map_err(|e| {
                PyTypeError::new_err(format!(
                    "expected a 1-D array of floats (a numpy array, list or tuple of numbers), \
                     but numpy cannot make an array of it: {e}"
                ))
            })?;
        let shape: Vec<usize> = array.getattr("shape")?.extract()?;
        let dtype = array.getattr("dtype")?;
        let kind: String = dtype.getattr("kind")?.extract()?;
        let dtype_name: String = dtype.getattr("name")?.extract()?;
        if shape.len() != 1 {
            let hint = match shape.len() {
                0 => "; wrap a single number in a list, [x]".to_string(),
                _ if shape.iter().filter(|n| **n != 1).count() <= 1 => {
                    "; flatten it first (a.ravel()) if it holds one signal".to_string()
                }
                _ => "; pass one signal (one row or column) at a time".to_string(),
            };
            return Err(PyTypeError::new_err(format!(
                "expected a 1-D array of floats, but got a {}-D array of shape {} ({dtype_name}){hint}",
                shape.len(),
                shape_text(&shape)
            )));
        }
        match kind.as_str() {
            "f" | "i" | "u" | "b" | "O" => {}
            "c" => {
                return Err(PyTypeError::new_err(format!(
                    "expected a 1-D array of real floats, but got complex values ({dtype_name}, \
                     shape {}); pass the real part (a.real) or the magnitude (abs(a)) explicitly",
                    shape_text(&shape)
                )));
            }
            _ => {
                return Err(PyTypeError::new_err(format!(
                    "expected a 1-D array of floats, but got an array of {dtype_name} (shape {})",
                    shape_text(&shape)
                )));
            }
        }
        // A native float64 array (asarray kept it as given) is read in place: `copy=False`
        // converts only when the dtype or byte order differs, so the values are copied once,
        // into the Vec below.
        let kwargs = PyDict::new(py);
        kwargs.set_item("copy", false)?;
        let floats = array
            .call_method("astype", ("float64",), Some(&kwargs))
            .map_err(|e| {
                PyTypeError::new_err(format!(
                    "expected a 1-D array of floats, but these values are not all numbers: {e}"
                ))
            })?;
        let readonly: PyReadonlyArray1<'py, f64> = floats.extract()?;
        let values = match readonly.as_slice() {
            Ok(contiguous) => contiguous.to_vec(),
            // A strided view (a[::2]): gathered element by element, still one copy.
            Err(_) => readonly.as_array().iter().copied().collect(),
        };
        Ok(ArrayIn {
            values,
            _py: PhantomData,
        })
    }
}

impl ArrayIn<'_> {
    /// The values, moved out (no copy).
    pub fn into_values(self) -> Vec<f64> {
        self.values
    }
}

/// The values of `array`, moved out (no copy).
pub fn values(array: ArrayIn<'_>) -> Vec<f64> {
    array.into_values()
}

/// The values of `array`, refused when one is NaN or infinite (naming the first).
pub fn finite_values(array: ArrayIn<'_>, name: &str) -> PyResult<Vec<f64>> {
    let v = values(array);
    check_finite(&v, name)?;
    Ok(v)
}

/// Refuses a NaN or infinite value, naming the first.
pub fn check_finite(values: &[f64], name: &str) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(invalid(format!(
            "{name}[{i}] = {} is not finite; every sample must be a finite number",
            values[i]
        ))),
    }
}

/// The largest magnitude of a position or voltage given to a model or compensator in physical
/// units (1e15, the bound on the values of a record read from a file,
/// [`hystcomp_io::data::MAX_MAGNITUDE`]): beyond it a model's output scale turns the value
/// into an infinity, or its cubic term overflows.
pub const MAX_MAGNITUDE: f64 = hystcomp_io::data::MAX_MAGNITUDE;

/// The values of `array`, refusing a NaN, an infinity or a magnitude beyond [`MAX_MAGNITUDE`],
/// naming the first.
pub fn record_values(array: ArrayIn<'_>, name: &str) -> PyResult<Vec<f64>> {
    let v = finite_values(array, name)?;
    match v.iter().position(|x| x.abs() > MAX_MAGNITUDE) {
        None => Ok(v),
        Some(i) => Err(beyond(&format!("{name}[{i}]"), v[i])),
    }
}

/// Refuses a NaN, an infinity or a magnitude beyond [`MAX_MAGNITUDE`].
pub fn check_record_scalar(value: f64, name: &str) -> PyResult<()> {
    check_finite_scalar(value, name)?;
    if value.abs() > MAX_MAGNITUDE {
        return Err(beyond(name, value));
    }
    Ok(())
}

fn beyond(what: &str, value: f64) -> PyErr {
    invalid(format!(
        "{what} = {value:e} is beyond the {MAX_MAGNITUDE:e} a record's value may be; give the \
         values in a unit that keeps them within it"
    ))
}

/// Refuses a non-finite output of a model (its terms overflowed), naming the input's sample.
pub fn check_outputs(outputs: &[f64], inputs: &[f64], name: &str) -> PyResult<()> {
    match outputs.iter().position(|y| !y.is_finite()) {
        None => Ok(()),
        Some(i) => Err(invalid(format!(
            "{name}[{i}] = {:e} gives a non-finite output ({}): the model's terms overflow there",
            inputs.get(i).copied().unwrap_or(f64::NAN),
            outputs[i]
        ))),
    }
}

/// Refuses a NaN or infinite scalar.
pub fn check_finite_scalar(value: f64, name: &str) -> PyResult<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(invalid(format!(
            "{name} = {value} is not finite; give a finite number"
        )))
    }
}

/// A new numpy array holding `values`.
pub fn array_out(py: Python<'_>, values: Vec<f64>) -> Bound<'_, PyArray1<f64>> {
    PyArray1::from_vec(py, values)
}

/// Two numbers `(lo, hi)` from any sequence of length 2 (a tuple, a list, a numpy array).
pub fn pair(values: Vec<f64>, name: &str) -> PyResult<(f64, f64)> {
    match values[..] {
        [lo, hi] => Ok((lo, hi)),
        _ => Err(invalid(format!(
            "{name} must be two numbers (min, max), not {} value(s)",
            values.len()
        ))),
    }
}
