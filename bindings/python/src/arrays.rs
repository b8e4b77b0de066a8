//! numpy arrays in and out, and the checks every boundary makes on them.

use numpy::{AllowTypeChange, PyArray1, PyArrayLike1};
use pyo3::prelude::*;

use crate::errors::invalid;

/// Any one-dimensional array-like of numbers (a numpy array of any real dtype, a list, a
/// tuple), converted to `float64` by numpy.
pub type ArrayIn<'py> = PyArrayLike1<'py, f64, AllowTypeChange>;

/// The values of `array` (any layout, including strided views).
pub fn values(array: &ArrayIn<'_>) -> Vec<f64> {
    array.as_array().iter().copied().collect()
}

/// The values of `array`, refused when one is NaN or infinite (naming the first).
pub fn finite_values(array: &ArrayIn<'_>, name: &str) -> PyResult<Vec<f64>> {
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
