//! `identify(...)`: `hystcomp_identify::identify` with Python keyword arguments.

use hystcomp_identify::{
    Identification as RustIdentification, IdentifyOptions, Method, OrderSelection, OutputOffset,
    PsoOptions, Thresholds, Warmup,
};
use pyo3::prelude::*;

use crate::arrays::{ArrayIn, array_out, record_values, values};
use crate::errors::{self, invalid};
use crate::model::{ModelFile, parse_direction, to_python, typed};

/// `"auto"` or a number of samples.
#[derive(FromPyObject)]
pub enum WarmupArg {
    /// A number of samples.
    Samples(usize),
    /// `"auto"`.
    Name(String),
}

/// A number of play operators, or `"auto"`.
#[derive(FromPyObject)]
pub enum OperatorsArg {
    /// This many.
    Count(usize),
    /// `"auto"`.
    Name(String),
}

/// `"fit"`, `"none"` or a physical output offset.
#[derive(FromPyObject)]
pub enum OffsetArg {
    /// A physical value.
    Value(f64),
    /// `"fit"` or `"none"`.
    Name(String),
}

/// An identified model: ``.model`` (a ``ModelFile``, physical scales and normalised
/// parameters), ``.report`` (a ``FitReport`` dataclass: fit errors in physical units and % of the output range,
/// sample counts, solver details, smallest branch slope...) and ``.parameters`` (a dict of the
/// normalised ``a1``, ``a2``, ``weights`` and fitted ``offset``).
#[pyclass(module = "hystcomp", name = "Identification", frozen)]
pub struct Identification {
    inner: RustIdentification,
    selection: Option<OrderSelection>,
}

#[pymethods]
impl Identification {
    /// The model file (its ``identification`` field holds the report too).
    #[getter]
    fn model(&self) -> ModelFile {
        ModelFile::wrap(self.inner.model.clone())
    }

    /// The fit report, a ``FitReport`` dataclass with the fields of ``hystcomp identify
    /// --json``'s report (``.fit.rms_percent``, ``.samples.warmup``, ``.holdout``, ...;
    /// ``.to_dict()`` for the dict).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        typed(py, "FitReport", to_python(py, &self.inner.report)?)
    }

    /// The normalised parameters, as a dict.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.parameters)
    }

    /// With ``n="auto"``: how the number of play operators was chosen, a dict with
    /// ``operators`` (the choice), ``holdout`` (the fraction of the record held out to choose
    /// it) and ``candidates`` (each tried: ``operators``, ``fit_rms_percent``,
    /// ``holdout_rms_percent``); ``None`` when ``n`` was given.
    #[getter]
    fn order_selection<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.selection
            .as_ref()
            .map(|s| to_python(py, s))
            .transpose()
    }

    fn __repr__(&self) -> String {
        let r = &self.inner.report;
        format!(
            "Identification(direction={:?}, solver={:?}, n={}, fit_rms={:.4} {} ({:.3} %))",
            r.direction.to_string(),
            r.solver,
            r.thresholds.len(),
            r.fit.rms,
            r.output.unit,
            r.fit.rms_percent
        )
    }
}

/// Identifies a modified Prandtl-Ishlinskii model (eq. (4)) from a record of drive voltages
/// and measured displacements (equal lengths, finite), as ``hystcomp identify`` does.
///
/// - ``n``: play operators at thresholds ``(i - 1)/n`` of the input range (eq. (11)), unless
///   ``thresholds`` gives them (fractions of the input range in ``[0, 1)``, increasing); or
///   ``"auto"``: the one of 5, 10, 15, 20, 30, 40, 50 whose model predicts the last
///   ``holdout`` of the record (25 % when ``holdout`` is 0) best, fitted on the rest, as
///   ``hystcomp identify -n auto`` (``.order_selection`` says which and why);
/// - ``method``: ``"ls"`` (constrained least squares, the global optimum) or ``"pso"``
///   (particle swarm, as the paper; ``seed``, ``particles``, ``iterations``, ``polish``);
/// - ``direction``: ``"plant"`` (voltage to displacement, for IHC and WIHC) or ``"inverse"``
///   (displacement to voltage, for DIHC);
/// - ``warmup``: ``"auto"`` (up to where the operators' memory becomes known: the voltage
///   within 1 % of an end of the record's range), ``"estimate"`` (every sample fitted, the
///   memory at the first one estimated with the parameters) or a number of leading samples
///   excluded from the fit; ``report.warmup.reason`` says which samples were used and why;
/// - ``holdout``: the fraction of samples at the end held out of the fit and reported (0.2,
///   as ``hystcomp identify``; 0 fits the whole record);
/// - ``offset``: ``"fit"`` (a constant fitted for the sensor's arbitrary zero), ``"none"`` or a
///   physical output offset;
/// - ``margin``: the smallest branch slope the model must keep (normalised);
/// - ``accept_poor_fit``: return the model even when its RMS fit error exceeds the 10 % of the
///   output range a usable hysteresis model stays under (by default ``IdentificationError``);
/// - ``for_delayed``: a plant model meant for the one-sample-delayed compensators
///   (``ihc-delayed``, ``wihc-delayed``): both delayed loops' gains, over every number of
///   moving operators and every drive in the fitted range, held to at most
///   ``delayed_loop_bound`` (in ``(0, 1)``), so that neither loop can oscillate, as ``hystcomp
///   identify --for-delayed``; the report's ``delayed_constraint`` says what it cost in fit
///   RMS. Inverse models ignore it.
///
/// Releases the GIL while it runs. Raises ``InvalidValueError`` for unusable samples or
/// options and ``IdentificationError`` when no model can be identified (the message says what
/// to change).
#[pyfunction]
#[pyo3(signature = (voltage, displacement, n = OperatorsArg::Count(10), method = "ls", direction = "plant", *, seed = 0, thresholds = None, warmup = WarmupArg::Name("auto".into()), holdout = 0.2, offset = OffsetArg::Name("fit".into()), margin = hystcomp_identify::DEFAULT_MARGIN, particles = hystcomp_identify::DEFAULT_PARTICLES, iterations = hystcomp_identify::DEFAULT_ITERATIONS, polish = false, accept_poor_fit = false, voltage_unit = "V", displacement_unit = "um", for_delayed = false, delayed_loop_bound = hystcomp_identify::DEFAULT_DELAYED_LOOP_BOUND))]
#[allow(clippy::too_many_arguments)]
pub fn identify(
    py: Python<'_>,
    voltage: ArrayIn<'_>,
    displacement: ArrayIn<'_>,
    n: OperatorsArg,
    method: &str,
    direction: &str,
    seed: u64,
    thresholds: Option<ArrayIn<'_>>,
    warmup: WarmupArg,
    holdout: f64,
    offset: OffsetArg,
    margin: f64,
    particles: usize,
    iterations: usize,
    polish: bool,
    accept_poor_fit: bool,
    voltage_unit: &str,
    displacement_unit: &str,
    for_delayed: bool,
    delayed_loop_bound: f64,
) -> PyResult<Identification> {
    let auto = match n {
        OperatorsArg::Count(_) => false,
        OperatorsArg::Name(ref name) if name.trim().eq_ignore_ascii_case("auto") => true,
        OperatorsArg::Name(name) => {
            return Err(invalid(format!(
                "n {name:?} is unknown; give a number of play operators or \"auto\""
            )));
        }
    };
    let n = match n {
        OperatorsArg::Count(n) => n,
        OperatorsArg::Name(_) => hystcomp_identify::DEFAULT_OPERATORS,
    };
    let method = match method.trim().to_ascii_lowercase().as_str() {
        "ls" | "least-squares" | "least_squares" => Method::LeastSquares,
        "pso" | "particle-swarm" | "particle_swarm" => Method::ParticleSwarm(
            PsoOptions::default()
                .with_particles(particles)
                .and_then(|o| o.with_iterations(iterations))
                .map_err(errors::identify)?
                .with_seed(seed)
                .with_polish(polish),
        ),
        other => {
            return Err(invalid(format!(
                "method {other:?} is unknown; give \"ls\" (least squares) or \"pso\" (particle swarm)"
            )));
        }
    };
    let warmup = match warmup {
        WarmupArg::Samples(k) => Warmup::Samples(k),
        WarmupArg::Name(name) if name.trim().eq_ignore_ascii_case("auto") => Warmup::Auto,
        WarmupArg::Name(name) if name.trim().eq_ignore_ascii_case("estimate") => Warmup::Estimate,
        WarmupArg::Name(name) => {
            return Err(invalid(format!(
                "warmup {name:?} is unknown; give \"auto\", \"estimate\" or a number of samples"
            )));
        }
    };
    let offset = match offset {
        OffsetArg::Value(v) => OutputOffset::Value(v),
        OffsetArg::Name(name) => match name.trim().to_ascii_lowercase().as_str() {
            "fit" => OutputOffset::Fit,
            "none" => OutputOffset::None,
            _ => {
                return Err(invalid(format!(
                    "offset {name:?} is unknown; give \"fit\", \"none\" or a number"
                )));
            }
        },
    };
    let options = IdentifyOptions {
        direction: parse_direction(direction)?,
        method,
        thresholds: match thresholds {
            Some(t) => Thresholds::Given(values(t)),
            None => Thresholds::Uniform(n),
        },
        warmup,
        holdout,
        offset,
        margin,
        max_fit_rms_percent: if accept_poor_fit {
            None
        } else {
            IdentifyOptions::default().max_fit_rms_percent
        },
        delayed_loop_bound: for_delayed.then_some(delayed_loop_bound),
        voltage_unit: voltage_unit.to_string(),
        displacement_unit: displacement_unit.to_string(),
        ..IdentifyOptions::default()
    };
    let auto = auto && matches!(options.thresholds, Thresholds::Uniform(_));
    let voltage = values(voltage);
    let displacement = values(displacement);
    let result = py.detach(|| -> Result<_, hystcomp_identify::IdentifyError> {
        options.validate()?;
        if !auto {
            return hystcomp_identify::identify(&voltage, &displacement, &options)
                .map(|fit| (fit, None));
        }
        let selection = hystcomp_identify::select_operators(
            &voltage,
            &displacement,
            &options,
            &hystcomp_identify::AUTO_OPERATOR_CANDIDATES,
        )?;
        let chosen = IdentifyOptions {
            thresholds: Thresholds::Uniform(selection.operators),
            ..options
        };
        hystcomp_identify::identify(&voltage, &displacement, &chosen)
            .map(|fit| (fit, Some(selection)))
    });
    let (inner, selection) = result.map_err(errors::identify)?;
    Ok(Identification { inner, selection })
}

/// A model's prediction of a record (``hystcomp predict``): ``.predicted`` and ``.error``
/// (predicted minus measured; numpy arrays, one per sample, in the model's output unit),
/// ``.stats`` (an ``ErrorStats``: RMS, max, mean, in the unit and in % of the measured
/// output's range ``.stats.range``), ``.outside_input_range`` (samples the model
/// extrapolates), ``.initial_state`` and ``.direction``.
#[pyclass(module = "hystcomp", name = "Prediction", frozen)]
pub struct Prediction {
    inner: hystcomp_identify::Prediction,
}

#[pymethods]
impl Prediction {
    /// The predicted output: the displacement for a plant model, the voltage for an inverse
    /// one.
    #[getter]
    fn predicted<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        array_out(py, self.inner.predicted.clone())
    }

    /// Predicted minus measured, one per sample.
    #[getter]
    fn error<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        array_out(py, self.inner.error.clone())
    }

    /// The errors over every sample, an ``ErrorStats`` (``rms_percent`` is in % of the measured
    /// output's range over the record, ``range``).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        typed(py, "ErrorStats", to_python(py, &self.inner.stats)?)
    }

    /// Samples whose input lies outside the range the model was identified on.
    #[getter]
    fn outside_input_range(&self) -> usize {
        self.inner.outside_input_range
    }

    /// How the model started (its reset state, eq. (1); a creep link settled with
    /// ``settled=True``).
    #[getter]
    fn initial_state(&self) -> String {
        self.inner.initial_state.clone()
    }

    /// ``"plant"`` or ``"inverse"``.
    #[getter]
    fn direction(&self) -> String {
        self.inner.direction.to_string()
    }

    fn __len__(&self) -> usize {
        self.inner.predicted.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Prediction(direction={:?}, samples={}, rms_percent={:.4})",
            self.inner.direction.to_string(),
            self.inner.predicted.len(),
            self.inner.stats.rms_percent
        )
    }
}

/// Runs ``model`` (a ``ModelFile``) over a record from its reset state (zero operator memory,
/// eq. (1)), as ``hystcomp predict`` does: a plant model over ``voltage``, compared with
/// ``displacement``; an inverse model the other way round (equal lengths, finite, not empty).
/// ``settled``: a creep link taken as having rested long at the first sample. Returns a
/// ``Prediction``. Raises ``InvalidValueError`` for unusable samples or a prediction that is
/// not finite (naming the sample). Releases the GIL while it runs.
#[pyfunction]
#[pyo3(signature = (model, voltage, displacement, *, settled = false))]
pub fn predict(
    py: Python<'_>,
    model: PyRef<'_, ModelFile>,
    voltage: ArrayIn<'_>,
    displacement: ArrayIn<'_>,
    settled: bool,
) -> PyResult<Prediction> {
    let voltage = record_values(voltage, "voltage")?;
    let displacement = record_values(displacement, "displacement")?;
    let file = model.inner.clone();
    drop(model);
    let result = py.detach(|| {
        hystcomp_identify::predict(
            &file,
            hystcomp_identify::Record {
                voltage: &voltage,
                displacement: &displacement,
            },
            settled,
        )
    });
    Ok(Prediction {
        inner: result.map_err(errors::identify)?,
    })
}
