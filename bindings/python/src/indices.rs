//! The tracking indices of section 4.3 (`hystcomp_experiments::indices`).

use hystcomp_experiments::TrackingIndices as RustIndices;
use hystcomp_experiments::indices::{DEFAULT_MHE_BINS, e_m_percent, e_mhe_percent, e_rms_percent};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{ArrayIn, values};
use crate::errors;
use crate::model::dict;

/// The three indices of the paper's Table 3, in percent of the desired range:
/// ``e_mhe`` (eq. (12), the largest vertical width of the ``y`` versus ``y_d`` map over
/// ``mhe_bins`` bins of ``y_d``), ``e_m`` ((D1), the largest tracking error) and ``e_rms``
/// ((D2), the RMS tracking error).
#[pyclass(module = "hystcomp", name = "TrackingIndices", frozen, eq)]
#[derive(Clone, Copy, PartialEq)]
pub struct TrackingIndices {
    pub(crate) inner: RustIndices,
}

#[pymethods]
impl TrackingIndices {
    /// Maximum hysteresis error, eq. (12), %.
    #[getter]
    fn e_mhe(&self) -> f64 {
        self.inner.e_mhe_percent
    }

    /// Maximum tracking error, (D1), %.
    #[getter]
    fn e_m(&self) -> f64 {
        self.inner.e_m_percent
    }

    /// RMS tracking error, (D2), %.
    #[getter]
    fn e_rms(&self) -> f64 {
        self.inner.e_rms_percent
    }

    /// Bins of the ``y_d`` range used for ``e_mhe``.
    #[getter]
    fn mhe_bins(&self) -> usize {
        self.inner.mhe_bins
    }

    /// ``{"e_mhe": ..., "e_m": ..., "e_rms": ...}`` (percent).
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        indices_dict(py, &self.inner)
    }

    fn __repr__(&self) -> String {
        format!(
            "TrackingIndices(e_mhe={:.3} %, e_m={:.3} %, e_rms={:.3} %, mhe_bins={})",
            self.inner.e_mhe_percent,
            self.inner.e_m_percent,
            self.inner.e_rms_percent,
            self.inner.mhe_bins
        )
    }
}

/// The three indices as a dict (percent).
pub fn indices_dict<'py>(py: Python<'py>, i: &RustIndices) -> PyResult<Bound<'py, PyDict>> {
    dict(
        py,
        [
            ("e_mhe", i.e_mhe_percent),
            ("e_m", i.e_m_percent),
            ("e_rms", i.e_rms_percent),
        ],
    )
}

/// (D1): ``max |y - y_d| / (max y_d - min y_d) * 100`` (percent).
///
/// Raises ``InvalidValueError`` for records of different lengths, fewer than 2 samples, NaN
/// or infinite samples, or a constant desired trajectory.
#[pyfunction]
pub fn e_m(desired: ArrayIn<'_>, measured: ArrayIn<'_>) -> PyResult<f64> {
    e_m_percent(&values(desired), &values(measured)).map_err(errors::index)
}

/// (D2): ``sqrt(mean (y - y_d)^2) / (max y_d - min y_d) * 100`` (percent).
#[pyfunction]
pub fn e_rms(desired: ArrayIn<'_>, measured: ArrayIn<'_>) -> PyResult<f64> {
    e_rms_percent(&values(desired), &values(measured)).map_err(errors::index)
}

/// Eq. (12): the largest ``max y - min y`` within one of ``bins`` equal bins of the ``y_d``
/// range, divided by ``max y_d - min y_d``, times 100 (percent). Needs at least 10 samples per
/// bin on average (``bins <= max(1, len(desired) // 10)``): with fewer, bins hold one sample or
/// none and e_mhe reads low; otherwise raises with the largest ``bins`` the record supports.
#[pyfunction]
#[pyo3(signature = (desired, measured, bins = DEFAULT_MHE_BINS))]
pub fn e_mhe(desired: ArrayIn<'_>, measured: ArrayIn<'_>, bins: usize) -> PyResult<f64> {
    e_mhe_percent(&values(desired), &values(measured), bins).map_err(errors::index)
}

/// All three indices of ``measured`` (``y``) against ``desired`` (``y_d``); ``bins`` as for
/// :func:`e_mhe` (at least 10 samples per bin on average).
#[pyfunction]
#[pyo3(signature = (desired, measured, bins = DEFAULT_MHE_BINS))]
pub fn tracking_indices(
    desired: ArrayIn<'_>,
    measured: ArrayIn<'_>,
    bins: usize,
) -> PyResult<TrackingIndices> {
    RustIndices::compute(&values(desired), &values(measured), bins)
        .map(|inner| TrackingIndices { inner })
        .map_err(errors::index)
}
