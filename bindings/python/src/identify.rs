//! `identify(...)`: `hystcomp_identify::identify` with Python keyword arguments.

use hystcomp_identify::{
    Identification as RustIdentification, IdentifyOptions, Method, OutputOffset, PsoOptions,
    Thresholds, Warmup,
};
use pyo3::prelude::*;

use crate::arrays::{ArrayIn, values};
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
///   ``thresholds`` gives them (fractions of the input range in ``[0, 1)``, increasing);
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
///   output range a usable hysteresis model stays under (by default ``IdentificationError``).
///
/// Releases the GIL while it runs. Raises ``InvalidValueError`` for unusable samples or
/// options and ``IdentificationError`` when no model can be identified (the message says what
/// to change).
#[pyfunction]
#[pyo3(signature = (voltage, displacement, n = 10, method = "ls", direction = "plant", *, seed = 0, thresholds = None, warmup = WarmupArg::Name("auto".into()), holdout = 0.2, offset = OffsetArg::Name("fit".into()), margin = hystcomp_identify::DEFAULT_MARGIN, particles = 40, iterations = 200, polish = false, accept_poor_fit = false, voltage_unit = "V", displacement_unit = "um"))]
#[allow(clippy::too_many_arguments)]
pub fn identify(
    py: Python<'_>,
    voltage: ArrayIn<'_>,
    displacement: ArrayIn<'_>,
    n: usize,
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
) -> PyResult<Identification> {
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
        voltage_unit: voltage_unit.to_string(),
        displacement_unit: displacement_unit.to_string(),
        ..IdentifyOptions::default()
    };
    let voltage = values(voltage);
    let displacement = values(displacement);
    let result = py.detach(|| hystcomp_identify::identify(&voltage, &displacement, &options));
    Ok(Identification {
        inner: result.map_err(errors::identify)?,
    })
}
