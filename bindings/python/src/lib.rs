//! The Python bindings of hystcomp: the extension module `hystcomp._hystcomp`, re-exported by
//! the package `hystcomp` (`python/hystcomp/__init__.py`, with type stubs).
//!
//! Thin, safe wrappers over the library (python-control style: systems are objects, numpy
//! arrays in and out, a one-sample `step` and a whole-signal `process`):
//!
//! - `model`: `Mpim` (the core's model, normalised), `Scale`, `ModelFile` (hystcomp-io);
//! - `compensator`: `Compensator` (hystcomp-io's `ScaledCompensator`: IHC, WIHC, DIHC in
//!   physical units);
//! - `bank`: `CompensatorBank` (hystcomp-io's `ScaledBank`: many channels stepped together);
//! - `identify`: `identify(...)` and `predict(...)` (hystcomp-identify);
//! - `stage`: `Stage`, `StageResponse` (hystcomp-stage);
//! - `indices`: `e_m`, `e_rms`, `e_mhe`, `tracking_indices` (hystcomp-experiments);
//! - `study`: `reproduce(...)` (hystcomp-experiments' study);
//! - `learn`: `Learner` (hystcomp-learn: iterative learning between trials).
//!
//! Every argument is validated before it reaches the library, and every library error becomes
//! a Python exception with the library's message (module `errors`); no panic is relied upon.

mod arrays;
mod bank;
mod compensator;
mod errors;
mod identify;
mod indices;
mod learn;
mod model;
mod stage;
mod study;

use pyo3::prelude::*;

/// Feedforward hysteresis compensation of piezoelectric nanopositioners (Gu & Zhu 2014).
#[pymodule]
fn _hystcomp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "DEFAULT_MHE_BINS",
        hystcomp_experiments::indices::DEFAULT_MHE_BINS,
    )?;
    m.add_class::<model::Mpim>()?;
    m.add_class::<model::Scale>()?;
    m.add_class::<model::ModelFile>()?;
    m.add_class::<compensator::Compensator>()?;
    m.add_class::<bank::CompensatorBank>()?;
    m.add_class::<identify::Identification>()?;
    m.add_class::<identify::Prediction>()?;
    m.add_class::<stage::Stage>()?;
    m.add_class::<stage::StageResponse>()?;
    m.add_class::<indices::TrackingIndices>()?;
    m.add_class::<study::StudyResult>()?;
    m.add_class::<learn::Learner>()?;
    m.add_function(wrap_pyfunction!(identify::identify, m)?)?;
    m.add_function(wrap_pyfunction!(identify::predict, m)?)?;
    m.add_function(wrap_pyfunction!(indices::e_m, m)?)?;
    m.add_function(wrap_pyfunction!(indices::e_rms, m)?)?;
    m.add_function(wrap_pyfunction!(indices::e_mhe, m)?)?;
    m.add_function(wrap_pyfunction!(indices::tracking_indices, m)?)?;
    m.add_function(wrap_pyfunction!(study::reproduce, m)?)?;
    m.add_function(wrap_pyfunction!(paper_trajectory, m)?)?;
    Ok(())
}

/// Two numpy arrays (time and value).
type ArrayPair<'py> = (
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
);

/// The paper's desired trajectory (section 4.3),
/// ``y_d(t) = 37.35 + 10.5 sin(pi t + 2.6) + 10.5 sin(1.6 pi t + 3) + 15.75 sin(2 pi t + 1.5)``
/// um, sampled at ``sample_rate_hz`` for ``duration_s`` (one 10 s period by default).
/// Returns ``(time_s, y_d_um)``.
#[pyfunction]
#[pyo3(signature = (duration_s = 10.0, sample_rate_hz = 10_000.0))]
fn paper_trajectory<'py>(
    py: Python<'py>,
    duration_s: f64,
    sample_rate_hz: f64,
) -> PyResult<ArrayPair<'py>> {
    if !(duration_s.is_finite()
        && duration_s > 0.0
        && sample_rate_hz.is_finite()
        && sample_rate_hz > 0.0)
    {
        return Err(errors::invalid(format!(
            "duration_s = {duration_s} and sample_rate_hz = {sample_rate_hz} must be finite and > 0"
        )));
    }
    let samples = (duration_s * sample_rate_hz).round() as usize;
    if samples > 100_000_000 {
        return Err(errors::invalid(format!(
            "{samples} samples is more than 1e8; shorten the duration or lower the rate"
        )));
    }
    let (time, position) = hystcomp_experiments::Reference::paper()
        .trajectory()
        .sample(sample_rate_hz, samples);
    Ok((arrays::array_out(py, time), arrays::array_out(py, position)))
}
