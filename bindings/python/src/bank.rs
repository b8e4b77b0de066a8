//! `CompensatorBank`: `hystcomp_io::bank::ScaledBank` (many channels, physical units), with a
//! one-tick `step` over an array of shape `(channels,)` and a whole-signal `process` over an
//! array of shape `(samples, channels)` (issue 16).

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

use hystcomp_io::bank::{Channel, MAX_CHANNELS, ModelSet, ModelSetError, ScaledBank};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::compensator::{ModelArg, parse_method, unstable_delay};
use crate::errors::{self, Kind, error, invalid};
use crate::model::dict;

/// The models of a bank: a model set's path, or a list of models (each a ``ModelFile`` or the
/// path of one).
#[derive(FromPyObject)]
pub enum SetArg<'py> {
    /// A model-set file, a directory of model files or one model file.
    Path(PathBuf),
    /// One model per channel.
    List(Vec<ModelArg<'py>>),
}

/// Drive limits: one `(min, max)` for every channel, or one per channel.
#[derive(FromPyObject)]
pub enum LimitsArg {
    /// One pair per channel.
    Many(Vec<Vec<f64>>),
    /// One pair for every channel.
    One(Vec<f64>),
}

/// A model set's error as a Python exception.
fn set_error(e: ModelSetError) -> PyErr {
    // The set's own message (it names the file holding a refused channel's model once).
    let message = e.to_string();
    match e {
        ModelSetError::File { error, .. } => {
            let inner = errors::model_file(error);
            Python::attach(|py| PyErr::from_type(inner.get_type(py), message))
        }
        ModelSetError::Channel {
            channel,
            name,
            error,
        } => {
            let inner = errors::compensator(error);
            Python::attach(|py| {
                let message = format!("channel {channel} ({name}): {}", inner.value(py));
                PyErr::from_type(inner.get_type(py), message)
            })
        }
        ModelSetError::Bank(core) => errors::core(core),
        ModelSetError::Set { ref message, .. } if message.starts_with("cannot read") => {
            pyo3::exceptions::PyOSError::new_err(e.to_string())
        }
        other => error(Kind::ModelFile, other.to_string()),
    }
}

/// A numpy array of `ndim` dimensions of real numbers as `float64`, C-contiguous: its values
/// and shape. Refuses other shapes, complex values and strings with `TypeError`.
fn real_array(
    obj: &Bound<'_, PyAny>,
    ndim: usize,
    name: &str,
    shape_hint: &str,
) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let py = obj.py();
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (obj,)).map_err(|e| {
        PyTypeError::new_err(format!(
            "{name}: expected an array of floats of shape {shape_hint}, but numpy cannot make \
             an array of it: {e}"
        ))
    })?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "b" | "i" | "u" | "f") {
        let dtype: String = array.getattr("dtype")?.getattr("name")?.extract()?;
        return Err(PyTypeError::new_err(format!(
            "{name}: expected real numbers, got an array of {dtype}"
        )));
    }
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape.len() != ndim {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected an array of shape {shape_hint}, got one of {} dimension(s) {shape:?}",
            shape.len()
        )));
    }
    let flat = numpy.call_method1("ascontiguousarray", (array, "float64"))?;
    let flat = flat.call_method0("ravel")?;
    let flat = flat.cast_into::<PyArray1<f64>>().map_err(PyErr::from)?;
    let values = flat.readonly().as_slice()?.to_vec();
    Ok((values, shape))
}

/// Refuses a NaN, an infinity or a magnitude beyond [`crate::arrays::MAX_MAGNITUDE`] (as
/// ``Compensator`` does), naming its sample and channel.
fn check_finite(values: &[f64], channels: usize, name: &str) -> PyResult<()> {
    let bound = crate::arrays::MAX_MAGNITUDE;
    if let Some(k) = values
        .iter()
        .position(|x| !x.is_finite() || x.abs() > bound)
    {
        let what = if values[k].is_finite() {
            format!(
                "{:e}, beyond the {bound:e} a desired position may be",
                values[k]
            )
        } else {
            format!("{}", values[k])
        };
        return Err(invalid(format!(
            "{name} at sample {}, channel {} is {what}; give finite desired positions (the \
             bank's state is unchanged)",
            k / channels.max(1),
            k % channels.max(1),
        )));
    }
    Ok(())
}

/// Many feedforward hysteresis compensators of one method, one channel per model, stepped
/// together (the axes of a stage, the actuators of a deformable mirror): desired positions in,
/// drive voltages out, each in its own model's physical units. Channel ``c`` gives what a
/// ``Compensator`` built from its own model gives, bit for bit.
///
/// - ``models``: the path of a model-set file (``{"format": "hystcomp-model-set", ...}``), of
///   a directory of model files (one channel per ``*.json``, in the order of their names) or of
///   one model file; or a list of models (each a ``ModelFile`` or the path of one);
/// - ``method``: as ``Compensator``, the same for every channel;
/// - ``limits``: ``(min, max)`` for every channel, or one pair per channel; by default each
///   channel's identified range;
/// - ``allow_unstable_delay``: as ``Compensator``.
///
/// ``step(y_d)`` takes an array of shape ``(channels,)``, ``process(y_d)`` one of shape
/// ``(samples, channels)``; both return arrays of the same shape, every drive within its
/// channel's limits. NaN, infinite and beyond-1e15 desired positions are refused with
/// ``InvalidValueError`` naming the sample and channel (state unchanged). A channel that cannot be built raises the
/// error ``Compensator`` would, its message beginning ``channel K (NAME): ``.
#[pyclass(module = "hystcomp", name = "CompensatorBank", subclass, frozen)]
pub struct CompensatorBank {
    inner: Mutex<ScaledBank>,
}

impl CompensatorBank {
    fn lock(&self) -> MutexGuard<'_, ScaledBank> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// `value` of every channel, in channel order, under one lock.
    fn per_channel<T>(&self, value: impl Fn(&ScaledBank, usize) -> T) -> Vec<T> {
        let bank = self.lock();
        (0..bank.channels()).map(|c| value(&bank, c)).collect()
    }
}

#[pymethods]
impl CompensatorBank {
    #[new]
    #[pyo3(signature = (models, method = "ihc", limits = None, *, allow_unstable_delay = false))]
    fn new(
        models: SetArg<'_>,
        method: &str,
        limits: Option<LimitsArg>,
        allow_unstable_delay: bool,
    ) -> PyResult<Self> {
        let method = parse_method(method)?;
        let set = match models {
            SetArg::Path(path) => ModelSet::load(&path).map_err(set_error)?,
            SetArg::List(list) => {
                if list.len() > MAX_CHANNELS {
                    return Err(invalid(format!(
                        "models holds {} entries, more than the {MAX_CHANNELS} channels a bank \
                         may have",
                        list.len()
                    )));
                }
                let mut channels = Vec::with_capacity(list.len());
                for (k, model) in list.into_iter().enumerate() {
                    let (name, path) = match &model {
                        ModelArg::Path(p) => (
                            p.file_stem()
                                .map(|s| s.to_string_lossy().into_owned())
                                .unwrap_or_else(|| format!("channel_{k}")),
                            p.display().to_string(),
                        ),
                        ModelArg::File(_) => (format!("channel_{k}"), String::new()),
                    };
                    // Named by its place in the list, as a set names its channels.
                    let model = model.read().map_err(|error| {
                        set_error(ModelSetError::File {
                            path,
                            channel: k,
                            name: name.clone(),
                            error,
                        })
                    })?;
                    channels.push(Channel { name, model });
                }
                // Two files of the same stem in different directories: number them instead.
                let mut names: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
                names.sort_unstable();
                if names.windows(2).any(|w| w[0] == w[1]) {
                    for (k, c) in channels.iter_mut().enumerate() {
                        c.name = format!("channel_{k}");
                    }
                }
                ModelSet::new(None, channels).map_err(set_error)?
            }
        };
        let limits = match limits {
            None => None,
            Some(LimitsArg::One(pair)) => Some(vec![crate::arrays::pair(pair, "limits")?]),
            Some(LimitsArg::Many(pairs)) => Some(
                pairs
                    .into_iter()
                    .enumerate()
                    .map(|(k, p)| crate::arrays::pair(p, &format!("limits[{k}]")))
                    .collect::<PyResult<Vec<_>>>()?,
            ),
        };
        let inner = ScaledBank::new(
            &set,
            method,
            limits.as_deref(),
            unstable_delay(allow_unstable_delay),
        )
        .map_err(set_error)?;
        Ok(CompensatorBank {
            inner: Mutex::new(inner),
        })
    }

    /// One control tick: the drives (shape ``(channels,)``) for the desired positions
    /// ``y_d`` (shape ``(channels,)``).
    fn step<'py>(
        &self,
        py: Python<'py>,
        y_d: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (desired, _) = real_array(y_d, 1, "y_d", "(channels,)")?;
        let mut bank = self.lock();
        let channels = bank.channels();
        if desired.len() != channels {
            return Err(invalid(format!(
                "y_d has {} values, but the bank has {channels} channels",
                desired.len()
            )));
        }
        check_finite(&desired, channels, "y_d")?;
        let mut control = vec![0.0; channels];
        bank.step(&desired, &mut control).map_err(errors::core)?;
        Ok(PyArray1::from_vec(py, control))
    }

    /// A whole desired trajectory of shape ``(samples, channels)`` from the current state:
    /// the drives, same shape. Releases the GIL while it runs.
    fn process<'py>(
        &self,
        py: Python<'py>,
        y_d: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (desired, shape) = real_array(y_d, 2, "y_d", "(samples, channels)")?;
        let channels = self.lock().channels();
        if shape[1] != channels {
            return Err(invalid(format!(
                "y_d has shape {shape:?}: {} columns, but the bank has {channels} channels \
                 (one column per channel, one row per sample)",
                shape[1]
            )));
        }
        check_finite(&desired, channels, "y_d")?;
        let control = py.detach(|| {
            let mut control = vec![0.0; desired.len()];
            self.lock()
                .process(&desired, &mut control)
                .map(|()| control)
        });
        let control = control.map_err(errors::core)?;
        let array = PyArray1::from_vec(py, control);
        array.reshape([shape[0], shape[1]]).map(|a| a.into_any())
    }

    /// Every channel back to its initial state: operators' memory zero (eq. (1)), diagnostics
    /// cleared.
    fn reset(&self) {
        self.lock().reset();
    }

    /// The number of channels.
    #[getter]
    fn channels(&self) -> usize {
        self.lock().channels()
    }

    fn __len__(&self) -> usize {
        self.lock().channels()
    }

    /// The channels' names (a model set's names, file stems, or ``channel_K``).
    #[getter]
    fn names(&self) -> Vec<String> {
        self.lock().names().to_vec()
    }

    /// The method of every channel.
    #[getter]
    fn method(&self) -> &'static str {
        self.lock().method().name()
    }

    /// ``(min, max)`` drive limits of every channel, each in its ``control_units``.
    #[getter]
    fn limits(&self) -> Vec<(f64, f64)> {
        self.per_channel(|bank, c| bank.limits(c).unwrap_or_default())
    }

    /// Every channel's unit of the desired position, e.g. ``"um"``.
    #[getter]
    fn desired_units(&self) -> Vec<String> {
        self.per_channel(|bank, c| bank.desired_unit(c).unwrap_or_default().to_string())
    }

    /// Every channel's unit of the drive, e.g. ``"V"``.
    #[getter]
    fn control_units(&self) -> Vec<String> {
        self.per_channel(|bank, c| bank.control_unit(c).unwrap_or_default().to_string())
    }

    /// Every channel's counters since the last reset, a list of ``Diagnostics`` (as
    /// ``Compensator.diagnostics``).
    #[getter]
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyAny>>> {
        self.per_channel(|bank, c| bank.diagnostics(c).unwrap_or_default())
            .into_iter()
            .map(|d| {
                let data = dict(
                    py,
                    [
                        ("saturated", d.saturated),
                        ("loop_saturated", d.loop_saturated),
                        ("non_finite", d.non_finite),
                    ],
                )?;
                crate::model::typed(py, "Diagnostics", data.into_any())
            })
            .collect()
    }

    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let class = slf.get_type().name()?;
        let b = slf.get().lock();
        Ok(format!(
            "{class}(method={:?}, channels={})",
            b.method().name(),
            b.channels()
        ))
    }
}
