//! `Stage` and `StageResponse`: the simulated piezo stage of `hystcomp-stage`.

use std::path::PathBuf;

use hystcomp_stage::{ClampCounts, Stage as RustStage, StageConfig, quasi_static_stroke_um};
use numpy::{PyArray1, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{ArrayIn, array_out, check_finite_scalar, finite_values};
use crate::errors;
use crate::model::dict;

/// The counts as a ``Clamps`` dataclass.
fn clamps_dict(py: Python<'_>, c: ClampCounts) -> PyResult<Bound<'_, PyAny>> {
    let data = dict(
        py,
        [
            ("dac_clamped", c.dac_clamped),
            ("amplifier_clamped", c.amplifier_clamped),
            ("non_finite", c.non_finite),
            ("adc_clamped", c.adc_clamped),
        ],
    )?;
    crate::model::typed(py, "Clamps", data.into_any())
}

/// A simulated piezo nanopositioning stage (DAC, amplifier, hysteresis, creep, resonance,
/// sensor, ADC), standing in for the set-up of the paper's section 4.1.
///
/// ``Stage(config_toml=None, seed=0)``: the built-in default stage, or a stage file's TOML
/// text (unspecified keys keep their defaults); ``seed`` seeds the sensor noise. Deterministic:
/// the same seed gives the same response. ``step(command_v)`` writes one DAC command (V) and
/// returns the measured position (um) one sample period later; ``run(volts)`` runs a whole
/// command signal and returns a ``StageResponse``.
///
/// Raises ``StageConfigError`` for an invalid stage file and ``InvalidValueError`` for NaN or
/// infinite commands (the state is then unchanged).
#[pyclass(module = "hystcomp", name = "Stage")]
pub struct Stage {
    inner: RustStage,
}

#[pymethods]
impl Stage {
    #[new]
    #[pyo3(signature = (config_toml = None, seed = 0))]
    fn new(config_toml: Option<&str>, seed: u64) -> PyResult<Self> {
        let config = match config_toml {
            Some(text) => StageConfig::from_toml_str(text).map_err(errors::stage)?,
            None => StageConfig::default(),
        };
        let inner = RustStage::new(&config, seed).map_err(errors::stage)?;
        Ok(Stage { inner })
    }

    /// A stage from a stage file (TOML). Raises ``FileNotFoundError`` when it is missing.
    #[staticmethod]
    #[pyo3(signature = (path, seed = 0))]
    fn from_file(path: PathBuf, seed: u64) -> PyResult<Self> {
        let config = StageConfig::from_toml_file(&path).map_err(errors::stage)?;
        let inner = RustStage::new(&config, seed).map_err(errors::stage)?;
        Ok(Stage { inner })
    }

    /// One sample: writes ``command_v`` (V) to the DAC, holds it for one period and returns the
    /// measured position at the end of the period (um).
    fn step(&mut self, command_v: f64) -> PyResult<f64> {
        check_finite_scalar(command_v, "command_v")?;
        Ok(self.inner.step(command_v))
    }

    /// A whole command signal (V, one value per sample) from the current state. Releases the
    /// GIL while it runs.
    fn run(&mut self, py: Python<'_>, command_v: ArrayIn<'_>) -> PyResult<StageResponse> {
        let command = finite_values(command_v, "command_v")?;
        let stage = &mut self.inner;
        let response = py.detach(|| stage.run(&command));
        Ok(StageResponse {
            time_s: array_out(py, response.time_s).unbind(),
            command_v: array_out(py, response.command_v).unbind(),
            amplifier_v: array_out(py, response.amplifier_v).unbind(),
            true_position_um: array_out(py, response.true_position_um).unbind(),
            measured_position_um: array_out(py, response.measured_position_um).unbind(),
            clamps: response.clamps,
        })
    }

    /// Back to rest: relaxed, at 0 V, time 0, noise generator re-seeded.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// The controller's sample rate, Hz.
    #[getter]
    fn sample_rate_hz(&self) -> f64 {
        self.inner.sample_rate_hz()
    }

    /// The sample period, s.
    #[getter]
    fn period_s(&self) -> f64 {
        self.inner.period_s()
    }

    /// Samples run since the stage was built or reset.
    #[getter]
    fn samples(&self) -> u64 {
        self.inner.samples()
    }

    /// The stage's time, s.
    #[getter]
    fn time_s(&self) -> f64 {
        self.inner.time_s()
    }

    /// The noise seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed()
    }

    /// Samples clamped or ignored since the stage was built or reset: ``dac_clamped`` and
    /// ``amplifier_clamped`` (commands beyond the DAC's span or the amplifier's rails),
    /// ``non_finite`` (NaN or infinite commands) and ``adc_clamped`` (readings beyond the ADC's
    /// span: the measured position saturated).
    #[getter]
    fn clamps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        clamps_dict(py, self.inner.clamps())
    }

    /// The full-scale command, V: the one that drives the amplifier to its upper rail, or the
    /// DAC's top when the amplifier's gain cannot reach the rail from it.
    #[getter]
    fn full_scale_command_v(&self) -> f64 {
        self.inner.config().full_scale_command_v()
    }

    /// The stage's configuration as a complete stage file (TOML text).
    #[getter]
    fn config_toml(&self) -> String {
        self.inner.config().to_toml_string()
    }

    /// The quasi-static stroke at full command (a slow ramp on a fresh copy of this stage's
    /// configuration), um. The linear feedforward gain of section 4.3.1 is
    /// ``full_scale_command_v / quasi_static_stroke_um()``.
    fn quasi_static_stroke_um(&self, py: Python<'_>) -> PyResult<f64> {
        let config = self.inner.config().clone();
        py.detach(|| quasi_static_stroke_um(&config))
            .map_err(errors::stage)
    }

    fn __repr__(&self) -> String {
        format!(
            "Stage(sample_rate_hz={}, seed={}, samples={})",
            self.inner.sample_rate_hz(),
            self.inner.seed(),
            self.inner.samples()
        )
    }
}

/// The response of ``Stage.run`` (python-control style): one entry per command sample.
///
/// ``time[k]`` is when command ``k`` was written; the positions are read one sample period
/// later. ``inputs`` is ``command_v`` and ``outputs`` is ``measured_position_um``; the stage's
/// internal signals are ``amplifier_v`` and ``true_position_um``. It unpacks as ``t, y =
/// stage.run(volts)``, and ``hystcomp.plot_response(response)`` plots it (matplotlib).
#[pyclass(module = "hystcomp", name = "StageResponse", frozen)]
pub struct StageResponse {
    time_s: Py<PyArray1<f64>>,
    command_v: Py<PyArray1<f64>>,
    amplifier_v: Py<PyArray1<f64>>,
    true_position_um: Py<PyArray1<f64>>,
    measured_position_um: Py<PyArray1<f64>>,
    clamps: ClampCounts,
}

#[pymethods]
impl StageResponse {
    /// Time at which each command was written, s.
    #[getter]
    fn time(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.time_s.clone_ref(py)
    }

    /// The commands, V (same as ``command_v``).
    #[getter]
    fn inputs(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.command_v.clone_ref(py)
    }

    /// The measured positions, um (same as ``measured_position_um``).
    #[getter]
    fn outputs(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.measured_position_um.clone_ref(py)
    }

    /// The commands, V.
    #[getter]
    fn command_v(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.command_v.clone_ref(py)
    }

    /// The amplifier's output, V.
    #[getter]
    fn amplifier_v(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.amplifier_v.clone_ref(py)
    }

    /// The true position, um.
    #[getter]
    fn true_position_um(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.true_position_um.clone_ref(py)
    }

    /// The measured position (sensor and ADC), um.
    #[getter]
    fn measured_position_um(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.measured_position_um.clone_ref(py)
    }

    /// Samples the stage clamped during this run, by the same keys as ``Stage.clamps``.
    #[getter]
    fn clamps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        clamps_dict(py, self.clamps)
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.command_v.bind(py).len()
    }

    /// Unpacks as ``t, y = stage.run(volts)``: the time and the measured positions.
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pair = (
            self.time_s.clone_ref(py),
            self.measured_position_um.clone_ref(py),
        );
        Ok(pair.into_pyobject(py)?.into_any().try_iter()?.into_any())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!("StageResponse(samples={})", self.command_v.bind(py).len())
    }
}
