//! `Compensator`: `hystcomp_io::compensator::ScaledCompensator` (physical units, limits in
//! volts), with a one-sample `step` and a whole-signal `process`.

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

use hystcomp_io::compensator::{Method, ScaledCompensator, UnstableDelay};
use hystcomp_io::model_file::{
    Direction, ModelFile as IoModelFile, ModelFileError, Scale as IoScale,
};
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::arrays::{ArrayIn, array_out, check_record_scalar, pair, record_values};
use crate::errors::{self, invalid};
use crate::model::{ModelFile, Mpim, dict};

/// A model given as a `ModelFile` or as the path of one.
#[derive(FromPyObject)]
pub enum ModelArg<'py> {
    /// A model file already read.
    File(PyRef<'py, ModelFile>),
    /// The path of a model file.
    Path(PathBuf),
}

impl ModelArg<'_> {
    /// The model file: the one given, or read from the path.
    pub(crate) fn load(self) -> PyResult<IoModelFile> {
        self.read().map_err(errors::model_file)
    }

    /// [`ModelArg::load`] with the reader's own error (for a caller that names the file its
    /// own way).
    pub(crate) fn read(self) -> Result<IoModelFile, ModelFileError> {
        match self {
            ModelArg::File(f) => Ok(f.inner.clone()),
            ModelArg::Path(p) => IoModelFile::load(&p),
        }
    }
}

pub(crate) fn parse_method(method: &str) -> PyResult<Method> {
    method.parse().map_err(errors::compensator)
}

fn check_limits(limits: Option<(f64, f64)>) -> PyResult<()> {
    if let Some((lo, hi)) = limits
        && !(lo.is_finite() && hi.is_finite() && lo < hi)
    {
        return Err(invalid(format!(
            "limits ({lo}, {hi}) are invalid: give finite (min, max) with min < max"
        )));
    }
    Ok(())
}

/// A feedforward hysteresis compensator (figure 1 of the paper): desired position in, drive
/// voltage out, in the physical units of its model file (e.g. um in, V out).
///
/// - ``model``: a ``ModelFile`` or the path of one;
/// - ``method``: ``"ihc"``, ``"ihc-delayed"``, ``"ihc-guarded"``, ``"wihc"``,
///   ``"wihc-delayed"``, ``"wihc-guarded"`` (plant models) or ``"dihc"`` (inverse models);
/// - ``limits``: ``(min, max)`` drive limits in the model's voltage unit; by default the range
///   the model was identified on;
/// - ``allow_unstable_delay``: build ``"ihc-delayed"`` or ``"wihc-delayed"`` even when its loop
///   gain over the limits is 1 or more (it can then ring between the limits after a jump); by
///   default that raises ``UnstableDelayError``. The ``-guarded`` methods never oscillate.
///
/// Every output lies within ``limits`` and is never NaN. ``step`` and ``process`` refuse NaN,
/// infinite and beyond-1e15 desired positions with ``InvalidValueError`` (state unchanged). Raises
/// ``WrongDirectionError``, ``NotInvertibleError`` (over the limits), ``UnstableDelayError``,
/// ``InvalidValueError``, ``ModelFileError`` or ``FileNotFoundError`` when it cannot be built.
#[pyclass(module = "hystcomp", name = "Compensator", subclass, frozen)]
pub struct Compensator {
    // `ScaledCompensator` is `Send` but not `Sync`; Python objects must be both.
    inner: Mutex<ScaledCompensator>,
}

impl Compensator {
    fn lock(&self) -> MutexGuard<'_, ScaledCompensator> {
        // A poisoned lock only means a panic elsewhere; the compensator state is still valid.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[pymethods]
impl Compensator {
    #[new]
    #[pyo3(signature = (model, method = "ihc", limits = None, *, allow_unstable_delay = false))]
    fn new(
        model: ModelArg<'_>,
        method: &str,
        limits: Option<Vec<f64>>,
        allow_unstable_delay: bool,
    ) -> PyResult<Self> {
        let method = parse_method(method)?;
        let limits = limits.map(|l| pair(l, "limits")).transpose()?;
        check_limits(limits)?;
        let file = model.load()?;
        let inner = ScaledCompensator::with_unstable_delay(
            &file,
            method,
            limits,
            unstable_delay(allow_unstable_delay),
        )
        .map_err(errors::compensator)?;
        Ok(Compensator {
            inner: Mutex::new(inner),
        })
    }

    /// A compensator from a model in normalised units (desired position and control both
    /// normalised, eq. (11)): a plant model for IHC and WIHC, an inverse model (valid for
    /// desired positions in ``[0, 1]``) for DIHC.
    #[staticmethod]
    #[pyo3(signature = (model, method = "ihc", limits = vec![0.0, 1.0], *, allow_unstable_delay = false))]
    fn from_mpim(
        model: &Mpim,
        method: &str,
        limits: Vec<f64>,
        allow_unstable_delay: bool,
    ) -> PyResult<Self> {
        let method = parse_method(method)?;
        let limits = pair(limits, "limits")?;
        check_limits(Some(limits))?;
        let scale = |quantity: &str| IoScale {
            quantity: quantity.to_string(),
            unit: "1".to_string(),
            offset: 0.0,
            scale: 1.0,
        };
        let (input, output) = match method.needs() {
            Direction::Plant => ("normalised voltage", "normalised displacement"),
            Direction::Inverse => ("normalised displacement", "normalised voltage"),
        };
        let file = IoModelFile::from_model(
            method.needs(),
            scale(input),
            scale(output),
            [0.0, 1.0],
            &model.inner,
        )
        .map_err(errors::model_file)?;
        let inner = ScaledCompensator::with_unstable_delay(
            &file,
            method,
            Some(limits),
            unstable_delay(allow_unstable_delay),
        )
        .map_err(errors::compensator)?;
        Ok(Compensator {
            inner: Mutex::new(inner),
        })
    }

    /// One sample: the drive for the desired position ``y_d``.
    fn step(&self, y_d: f64) -> PyResult<f64> {
        check_record_scalar(y_d, "y_d")?;
        Ok(self.lock().step(y_d))
    }

    /// A whole desired trajectory (array-like) from the current state: the drive signal
    /// (numpy array). Releases the GIL while it runs.
    fn process<'py>(
        &self,
        py: Python<'py>,
        y_d: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let desired = record_values(y_d, "y_d")?;
        // The lock is taken and released without the GIL, so that a thread waiting for the
        // GIL can never hold up one waiting for the lock.
        let control = py.detach(|| {
            let mut control = vec![0.0; desired.len()];
            self.lock()
                .process(&desired, &mut control)
                .map(|()| control)
        });
        Ok(array_out(py, control.map_err(errors::compensator)?))
    }

    /// Back to the initial state: operators' memory zero (eq. (1)), diagnostics cleared.
    fn reset(&self) {
        self.lock().reset();
    }

    /// ``(min, max)`` drive limits, in ``control_unit``.
    #[getter]
    fn limits(&self) -> (f64, f64) {
        self.lock().limits()
    }

    /// The method: ``"ihc"``, ``"ihc-delayed"``, ``"ihc-guarded"``, ``"wihc"``,
    /// ``"wihc-delayed"``, ``"wihc-guarded"`` or ``"dihc"``.
    #[getter]
    fn method(&self) -> &'static str {
        self.lock().method().name()
    }

    /// Unit of the desired position (the input), e.g. ``"um"``.
    #[getter]
    fn desired_unit(&self) -> String {
        self.lock().desired_unit().to_string()
    }

    /// Unit of the drive (the output), e.g. ``"V"``.
    #[getter]
    fn control_unit(&self) -> String {
        self.lock().control_unit().to_string()
    }

    /// Counters since the last reset:
    /// A ``Diagnostics`` dataclass: ``saturated``, ``loop_saturated``, ``non_finite``. ``saturated``: desired
    /// positions out of reach within the limits (DIHC: outside the inverse model's range), the
    /// drive was clamped; ``loop_saturated``: a delayed loop (``ihc-delayed``, ``wihc-delayed``)
    /// drove the output to a limit although the position was reachable (it lagged or rang);
    /// ``non_finite``: NaN or infinite desired positions (``step`` and ``process`` refuse them,
    /// so this stays 0 here).
    #[getter]
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let d = self.lock().diagnostics();
        let data = dict(
            py,
            [
                ("saturated", d.saturated),
                ("loop_saturated", d.loop_saturated),
                ("non_finite", d.non_finite),
            ],
        )?;
        crate::model::typed(py, "Diagnostics", data.into_any())
    }

    /// For the IHC and WIHC methods: the worst-case gain of the family's one-sample-delayed
    /// loop over the limits, whatever the method's own mode: ``max |3 a1 x^2| / (a2 + b_1 +
    /// ... + b_k)`` for IHC (Table 1: 0.68), ``max |3 a1 x^2 + b_1 + ... + b_k| / a2`` for WIHC
    /// (eq. (9) with ``H[v](t - Ts)``; Table 1: 1.66). At or above 1 the plain delayed loop can
    /// ring between the limits after a jump in the desired position and is refused unless
    /// ``allow_unstable_delay=True``; the exact and ``-guarded`` methods never oscillate.
    /// ``None`` for DIHC.
    #[getter]
    fn delayed_loop_gain(&self) -> Option<f64> {
        self.lock().delayed_loop_gain()
    }

    /// For the IHC and WIHC methods: the under-relaxation of the family's guarded delayed
    /// loop, in ``(0, 1]`` (1: no under-relaxation). ``None`` for DIHC.
    #[getter]
    fn guard_relaxation(&self) -> Option<f64> {
        self.lock().guard_relaxation()
    }

    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let class = slf.get_type().name()?;
        let c = slf.get().lock();
        Ok(format!(
            "{class}(method={:?}, desired_unit={:?}, control_unit={:?}, limits={:?})",
            c.method().name(),
            c.desired_unit(),
            c.control_unit(),
            c.limits()
        ))
    }
}

/// The override `allow_unstable_delay` asks for.
pub(crate) fn unstable_delay(allow: bool) -> UnstableDelay {
    if allow {
        UnstableDelay::Allow
    } else {
        UnstableDelay::Refuse
    }
}
