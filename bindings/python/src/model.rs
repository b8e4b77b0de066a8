//! `Mpim` (the core's model, normalised units), `Scale` and `ModelFile` (hystcomp-io).

use std::path::PathBuf;

use hystcomp_core::{Mpim as CoreMpim, paper};
use hystcomp_io::model_file::{
    Direction, MAX_OPERATORS, ModelFile as IoModelFile, Scale as IoScale,
};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{
    ArrayIn, array_out, check_finite_scalar, check_outputs, finite_values, record_values,
};
use crate::errors::{self, invalid};

type VecMpim = CoreMpim<f64, Vec<f64>>;

/// Parses `"plant"` / `"inverse"`.
pub fn parse_direction(direction: &str) -> PyResult<Direction> {
    match direction.trim().to_ascii_lowercase().as_str() {
        "plant" => Ok(Direction::Plant),
        "inverse" => Ok(Direction::Inverse),
        _ => Err(invalid(format!(
            "direction {direction:?} is unknown; give \"plant\" (voltage to displacement, for IHC \
             and WIHC) or \"inverse\" (displacement to voltage, for DIHC)"
        ))),
    }
}

/// The modified Prandtl-Ishlinskii model of eq. (4), in normalised units:
/// ``y(t) = a1 x(t)^3 + a2 x(t) + sum_i b_i F_{r_i}[x](t)`` with one-sided play operators
/// ``F_r`` (eqs. (1)-(2)).
///
/// A system object with memory: ``step(x)`` feeds one sample, ``process(x)`` a whole signal
/// (numpy array in, numpy array out), ``reset()`` returns to zero memory (eq. (1)).
///
/// Raises ``InvalidValueError`` for thresholds and weights of different lengths, more than
/// 10 000 operators (a model file's limit, as for the compensators), negative or unsorted
/// thresholds, or NaN/infinite parameters.
#[pyclass(module = "hystcomp", name = "Mpim")]
#[derive(Clone)]
pub struct Mpim {
    pub(crate) inner: VecMpim,
}

#[pymethods]
impl Mpim {
    #[new]
    #[pyo3(signature = (thresholds, weights, a1, a2))]
    fn new(thresholds: ArrayIn<'_>, weights: ArrayIn<'_>, a1: f64, a2: f64) -> PyResult<Self> {
        let thresholds = crate::arrays::values(thresholds);
        let weights = crate::arrays::values(weights);
        if thresholds.len() > MAX_OPERATORS {
            return Err(invalid(format!(
                "thresholds has {} entries: a model holds at most {MAX_OPERATORS} play \
                 operators (the paper uses 10)",
                thresholds.len()
            )));
        }
        let inner = CoreMpim::new(&thresholds, &weights, a1, a2).map_err(errors::core)?;
        Ok(Mpim { inner })
    }

    /// Table 1 of the paper: the plant model identified for IHC and WIHC (normalised voltage
    /// in, normalised displacement out).
    #[staticmethod]
    fn table1() -> PyResult<Self> {
        Ok(Mpim {
            inner: paper::TABLE1.model().map_err(errors::core)?,
        })
    }

    /// Table 2 of the paper: the inverse model identified for DIHC (normalised desired
    /// displacement in, normalised voltage out; eq. (10) with ``a2``).
    #[staticmethod]
    fn table2() -> PyResult<Self> {
        Ok(Mpim {
            inner: paper::TABLE2.model().map_err(errors::core)?,
        })
    }

    /// Thresholds ``r_i`` (a copy).
    #[getter]
    fn thresholds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.inner.thresholds().to_vec())
    }

    /// Weights ``b_i`` (a copy).
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.inner.weights().to_vec())
    }

    /// Cubic coefficient ``a1`` of ``g(x) = a1 x^3 + a2 x``.
    #[getter]
    fn a1(&self) -> f64 {
        self.inner.a1()
    }

    /// Linear coefficient ``a2`` of ``g(x) = a1 x^3 + a2 x``.
    #[getter]
    fn a2(&self) -> f64 {
        self.inner.a2()
    }

    /// The operators' memory ``F_{r_i}[x](t_i)`` (a copy).
    #[getter]
    fn memory<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.inner.memory().to_vec())
    }

    /// Sets the operators' memory (one finite value per operator).
    fn set_memory(&mut self, memory: ArrayIn<'_>) -> PyResult<()> {
        let memory = crate::arrays::values(memory);
        self.inner.set_memory(&memory).map_err(errors::core)
    }

    /// The number of play operators ``n``.
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// Feeds one input sample ``x(t)`` and returns ``y(t)``, eq. (4).
    ///
    /// Raises ``InvalidValueError`` (memory unchanged) when ``x`` is NaN or infinite, or the
    /// output overflows (e.g. the cubic term at ``x = 1e308``).
    fn step(&mut self, x: f64) -> PyResult<f64> {
        check_finite_scalar(x, "x")?;
        // Stepped on a copy, so that an overflowing output leaves the memory unchanged.
        let mut model = self.inner.clone();
        let y = model.step(x);
        check_outputs(&[y], &[x], "x")?;
        self.inner = model;
        Ok(y)
    }

    /// Runs a whole input signal from the current memory; returns the outputs.
    ///
    /// Raises ``InvalidValueError`` (memory unchanged) when a sample is NaN or infinite, or an
    /// output overflows (naming the sample).
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        x: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = finite_values(x, "x")?;
        let mut y = vec![0.0; x.len()];
        let mut model = self.inner.clone();
        model.process(&x, &mut y).map_err(errors::core)?;
        check_outputs(&y, &x, "x")?;
        self.inner = model;
        Ok(array_out(py, y))
    }

    /// Back to zero memory (eq. (1)).
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// Checks that the output is strictly increasing in the current input over ``[lo, hi]``
    /// from any memory reachable from the reset state (i.e. the model can be inverted there).
    /// Returns the smallest branch slope; raises ``NotInvertibleError`` with the offending
    /// slope, input and number of moving operators.
    #[pyo3(signature = (lo = 0.0, hi = 1.0))]
    fn check_invertible(&self, lo: f64, hi: f64) -> PyResult<f64> {
        self.inner
            .check_invertible(lo, hi)
            .map(|worst| worst.slope)
            .map_err(errors::core)
    }

    /// The analytic inverse of the PI part ``a2 v + sum b_i F_{r_i}[v]``, eq. (7), as a model
    /// with ``a1 = 0``. Raises ``NotInvertibleError`` when it does not exist.
    fn pi_part_inverse(&self) -> PyResult<Mpim> {
        Ok(Mpim {
            inner: self.inner.pi_part_inverse().map_err(errors::core)?,
        })
    }

    /// An independent copy, memory included.
    fn copy(&self) -> Mpim {
        self.clone()
    }

    /// ``copy.copy(model)``: an independent copy, memory included (the same as ``copy()``;
    /// the model holds no shared state, so it is also a deep copy).
    fn __copy__(&self) -> Mpim {
        self.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Mpim(n={}, a1={}, a2={}, thresholds={:?}, weights={:?})",
            self.inner.len(),
            self.inner.a1(),
            self.inner.a2(),
            self.inner.thresholds(),
            self.inner.weights()
        )
    }
}

/// The physical meaning of a normalised signal: ``physical = offset + scale * normalised``.
#[pyclass(module = "hystcomp", name = "Scale", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct Scale {
    pub(crate) inner: IoScale,
}

#[pymethods]
impl Scale {
    #[new]
    #[pyo3(signature = (quantity, unit, offset = 0.0, scale = 1.0))]
    fn new(quantity: String, unit: String, offset: f64, scale: f64) -> PyResult<Self> {
        if !(offset.is_finite() && scale.is_finite() && scale > 0.0) {
            return Err(invalid(format!(
                "a scale needs a finite offset and a finite scale > 0 (got offset {offset}, \
                 scale {scale})"
            )));
        }
        Ok(Scale {
            inner: IoScale {
                quantity,
                unit,
                offset,
                scale,
            },
        })
    }

    /// What the signal is, e.g. ``"voltage"``.
    #[getter]
    fn quantity(&self) -> &str {
        &self.inner.quantity
    }

    /// Its unit, e.g. ``"V"``.
    #[getter]
    fn unit(&self) -> &str {
        &self.inner.unit
    }

    /// Physical value at normalised 0.
    #[getter]
    fn offset(&self) -> f64 {
        self.inner.offset
    }

    /// Physical span of one normalised unit.
    #[getter]
    fn scale(&self) -> f64 {
        self.inner.scale
    }

    /// ``(physical - offset) / scale``.
    fn normalise(&self, physical: f64) -> f64 {
        self.inner.normalise(physical)
    }

    /// ``offset + scale * normalised``.
    fn to_physical(&self, normalised: f64) -> f64 {
        self.inner.to_physical(normalised)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scale(quantity={:?}, unit={:?}, offset={}, scale={})",
            self.inner.quantity, self.inner.unit, self.inner.offset, self.inner.scale
        )
    }
}

fn normalised_scale(quantity: &str) -> IoScale {
    IoScale {
        quantity: quantity.to_string(),
        unit: "1".to_string(),
        offset: 0.0,
        scale: 1.0,
    }
}

/// A model file: one identified MPIM in normalised units, the physical scales of its input
/// and output, and the direction it maps (``"plant"``: voltage to displacement, for IHC and
/// WIHC; ``"inverse"``: displacement to voltage, for DIHC). JSON on disk, format version 1.
///
/// Build one with ``ModelFile(...)``, read one with ``ModelFile.load(path)``, get one from
/// ``identify(...)``. Without ``input``/``output`` the scales are normalised (unit ``"1"``).
#[pyclass(module = "hystcomp", name = "ModelFile", eq)]
#[derive(Clone, PartialEq)]
pub struct ModelFile {
    pub(crate) inner: IoModelFile,
}

impl ModelFile {
    pub(crate) fn wrap(inner: IoModelFile) -> Self {
        ModelFile { inner }
    }
}

#[pymethods]
impl ModelFile {
    #[new]
    #[pyo3(signature = (direction, thresholds, weights, a1, a2, *, input = None, output = None, input_range = vec![0.0, 1.0], description = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        direction: &str,
        thresholds: ArrayIn<'_>,
        weights: ArrayIn<'_>,
        a1: f64,
        a2: f64,
        input: Option<Scale>,
        output: Option<Scale>,
        input_range: Vec<f64>,
        description: Option<String>,
    ) -> PyResult<Self> {
        let direction = parse_direction(direction)?;
        let input_range = crate::arrays::pair(input_range, "input_range")?;
        let mut inner = IoModelFile::new(
            direction,
            input.map_or_else(|| normalised_scale("normalised input"), |s| s.inner),
            output.map_or_else(|| normalised_scale("normalised output"), |s| s.inner),
            [input_range.0, input_range.1],
            crate::arrays::values(thresholds),
            crate::arrays::values(weights),
            a1,
            a2,
        )
        .map_err(errors::model_file)?;
        inner.description = description;
        Ok(ModelFile { inner })
    }

    /// Reads and validates a model file. Raises ``FileNotFoundError`` (or another ``OSError``)
    /// when it cannot be read and ``ModelFileError`` when it is not a valid model file.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        IoModelFile::load(&path)
            .map(ModelFile::wrap)
            .map_err(errors::model_file)
    }

    /// Parses and validates a model file's JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        IoModelFile::from_json(text)
            .map(ModelFile::wrap)
            .map_err(errors::model_file)
    }

    /// The file's JSON text.
    fn to_json(&self) -> String {
        self.inner.to_json()
    }

    /// Writes the file atomically (a temporary file, then a rename).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.inner.save(&path).map_err(errors::model_file)
    }

    /// The MPIM of this file (normalised units, zero memory): the hysteresis alone, without
    /// the file's creep or vibration links (``predict`` runs the whole chain).
    fn model(&self) -> PyResult<Mpim> {
        Ok(Mpim {
            inner: self.inner.model().map_err(errors::model_file)?,
        })
    }

    /// The model's output, in physical units, for a whole input signal in physical units
    /// (e.g. volts in, micrometres out for a plant model), from zero memory. Raises
    /// ``InvalidValueError`` for a NaN, an infinity or a magnitude beyond 1e15 (as in a
    /// record read from a file) and for an output that overflows, naming the sample.
    fn predict<'py>(
        &self,
        py: Python<'py>,
        inputs: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let inputs = record_values(inputs, "inputs")?;
        let outputs = self.inner.predict(&inputs).map_err(errors::model_file)?;
        check_outputs(&outputs, &inputs, "inputs")?;
        Ok(array_out(py, outputs))
    }

    /// ``"plant"`` or ``"inverse"``.
    #[getter]
    fn direction(&self) -> String {
        self.inner.direction.to_string()
    }

    /// A line for people, or ``None``.
    #[getter]
    fn description(&self) -> Option<String> {
        self.inner.description.clone()
    }

    #[setter]
    fn set_description(&mut self, description: Option<String>) {
        self.inner.description = description;
    }

    /// Physical meaning of the model input.
    #[getter]
    fn input(&self) -> Scale {
        Scale {
            inner: self.inner.input.clone(),
        }
    }

    /// Physical meaning of the model output.
    #[getter]
    fn output(&self) -> Scale {
        Scale {
            inner: self.inner.output.clone(),
        }
    }

    /// The normalised input range the model is valid (and invertible) on.
    #[getter]
    fn input_range(&self) -> (f64, f64) {
        (self.inner.input_range[0], self.inner.input_range[1])
    }

    /// Thresholds ``r_i`` (normalised, a copy).
    #[getter]
    fn thresholds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.inner.thresholds.clone())
    }

    /// Weights ``b_i`` (normalised, a copy).
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.inner.weights.clone())
    }

    /// Cubic coefficient ``a1``.
    #[getter]
    fn a1(&self) -> f64 {
        self.inner.a1
    }

    /// Linear coefficient ``a2``.
    #[getter]
    fn a2(&self) -> f64 {
        self.inner.a2
    }

    /// The format version (1).
    #[getter]
    fn format_version(&self) -> u32 {
        self.inner.format_version
    }

    /// How the model was obtained (a dict, e.g. the identification report), or ``None``.
    #[getter]
    fn identification<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.inner
            .identification
            .as_ref()
            .map(|value| json_to_python(py, &value.to_string()))
            .transpose()
    }

    fn __repr__(&self) -> String {
        format!(
            "ModelFile(direction={:?}, n={}, input={} [{}], output={} [{}], a1={}, a2={})",
            self.inner.direction.to_string(),
            self.inner.thresholds.len(),
            self.inner.input.quantity,
            self.inner.input.unit,
            self.inner.output.quantity,
            self.inner.output.unit,
            self.inner.a1,
            self.inner.a2
        )
    }
}

/// JSON text as Python objects (dicts, lists, floats...), by the standard library's parser.
pub fn json_to_python<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// A serialisable value as Python objects.
pub fn to_python<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| invalid(format!("could not convert a result to Python: {e}")))?;
    json_to_python(py, &text)
}

/// `value` as the typed report `class` of `hystcomp._reports` (a dataclass with the same
/// fields as the command line's JSON), through its `from_json`.
pub fn typed<'py>(
    py: Python<'py>,
    class: &str,
    data: Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    py.import("hystcomp._reports")?
        .getattr(class)?
        .call_method1("from_json", (data,))
}

/// A dict from `(key, value)` pairs.
pub fn dict<'py, V: IntoPyObject<'py>>(
    py: Python<'py>,
    items: impl IntoIterator<Item = (&'static str, V)>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (k, v) in items {
        dict.set_item(k, v)?;
    }
    Ok(dict)
}
