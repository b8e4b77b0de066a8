//! `Learner`: iterative learning feedforward between trials of a repeated motion
//! (`hystcomp_learn::Learner`): the measured response of a trial in, the next trial's drive out.

use std::sync::{Mutex, MutexGuard};

use hystcomp_io::model_file::Direction;
use hystcomp_learn::{Inverse, LearnError, Learner as RustLearner, LearningOptions, Status};
use numpy::PyArray1;
use pyo3::prelude::*;

use crate::arrays::{ArrayIn, array_out, finite_values, pair};
use crate::compensator::ModelArg;
use crate::errors::{self, Kind, error, invalid};
use crate::indices::TrackingIndices;
use crate::model::{to_python, typed};

/// A learning error as a Python exception: `LearningStoppedError` once the divergence guard
/// stopped the learning, `InvalidValueError` for a bad argument or record, the compensator's
/// own classes for a model it cannot invert.
pub fn learn_error(e: LearnError) -> PyErr {
    match e {
        LearnError::Compensator(c) => errors::compensator(c),
        LearnError::Stopped { .. } => error(Kind::LearningStopped, e.to_string()),
        other => invalid(other.to_string()),
    }
}

fn parse_inverse(inverse: &str) -> PyResult<Inverse> {
    match inverse {
        "ihc" => Ok(Inverse::Ihc),
        "wihc" => Ok(Inverse::Wihc),
        other => Err(invalid(format!(
            "inverse = {other:?} is unknown: give \"ihc\" or \"wihc\" (the exact inverses, whose \
             drive the model maps back onto the reference it followed)"
        ))),
    }
}

/// Iterative learning feedforward for a repeated motion (raster scans, periodic patterns): the
/// learner keeps the reference its exact inverse (IHC or WIHC of the plant ``model``) follows,
/// and after each trial moves it by the filtered error,
/// ``r_k+1 = sat(r_k + Q[gamma z^m e_k])``, ``e_k = y_d - y_k`` (Leang & Devasia 2006,
/// doi:10.1016/j.mechatronics.2005.11.006; Longman 2000, doi:10.1080/002071700405905; ``Q`` a
/// zero-phase low-pass). The law is in the crate ``hystcomp-learn``'s documentation and in
/// ``law``.
///
/// - ``model``: a plant ``ModelFile`` (voltage -> displacement) or the path of one;
/// - ``desired``: one trial of the desired trajectory (``2`` to ``5_000_000`` samples, the
///   model's displacement unit), one whole period of a periodic motion when ``periodic``;
/// - ``sample_rate_hz``: the records' sample rate;
/// - ``drive``: the drive of the first trial, if not the exact inverse's own (any
///   compensator's, or an earlier learner's): the reference is recovered from it by the model;
/// - ``gain`` (``gamma``, default 0.8, at most 10), ``bandwidth_hz`` (``Q``'s cut-off; default
///   a hundredth of the sample rate, a tenth for a model with a vibration link),
///   ``filter_order`` (1 to 8, default 4), ``lead_samples`` (``m``, 0 to 1000),
///   ``divergence_factor`` (above 1, default 1.5), ``inverse`` (``"ihc"`` or ``"wihc"``),
///   ``limits`` (``(min, max)`` drive limits, by default the model's identified range),
///   ``mhe_bins`` (bins of e_mhe).
///
/// The loop: send ``learner.drive`` to the stage (periodic: play it until the motion is
/// periodic, record the last period), then ``drive = learner.update(measured)`` and repeat.
/// Every drive lies within ``limits`` and is never NaN. When a trial's e_rms exceeds
/// ``divergence_factor`` times the best trial's, the divergence guard stops the learning:
/// ``update`` warns (``LearningDivergedWarning``) and returns the best trial's drive (the last
/// good one), ``stopped`` turns true and further updates raise ``LearningStoppedError``.
/// Raises ``InvalidValueError`` for a bad option or record (naming it), ``WrongDirectionError``
/// for an inverse model, ``NotInvertibleError`` when the model cannot be inverted over the
/// limits.
#[pyclass(module = "hystcomp", name = "Learner", frozen)]
pub struct Learner {
    // The learner is `Send`; Python objects must also be `Sync`.
    inner: Mutex<RustLearner>,
    last: Mutex<Option<hystcomp_learn::Update>>,
}

impl Learner {
    fn lock(&self) -> MutexGuard<'_, RustLearner> {
        // A poisoned lock only means a panic elsewhere; the learner's state is still valid.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn last(&self) -> MutexGuard<'_, Option<hystcomp_learn::Update>> {
        self.last.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[pymethods]
impl Learner {
    #[new]
    #[pyo3(signature = (
        model,
        desired,
        sample_rate_hz,
        drive = None,
        *,
        periodic = true,
        gain = hystcomp_learn::DEFAULT_GAIN,
        bandwidth_hz = None,
        filter_order = hystcomp_learn::DEFAULT_FILTER_ORDER,
        lead_samples = 0,
        divergence_factor = hystcomp_learn::DEFAULT_DIVERGENCE_FACTOR,
        inverse = "ihc",
        limits = None,
        mhe_bins = hystcomp_experiments::indices::DEFAULT_MHE_BINS,
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        model: ModelArg<'_>,
        desired: ArrayIn<'_>,
        sample_rate_hz: f64,
        drive: Option<ArrayIn<'_>>,
        periodic: bool,
        gain: f64,
        bandwidth_hz: Option<f64>,
        filter_order: usize,
        lead_samples: usize,
        divergence_factor: f64,
        inverse: &str,
        limits: Option<Vec<f64>>,
        mhe_bins: usize,
    ) -> PyResult<Self> {
        let file = model.load()?;
        if file.direction != Direction::Plant {
            return Err(error(
                Kind::WrongDirection,
                "the Learner needs a plant model (voltage -> displacement): the model run \
                 forward over a drive recovers the reference it followed; identify one with \
                 direction=\"plant\" (a DIHC drive can still be the first trial's drive)",
            ));
        }
        let desired = finite_values(desired, "desired")?;
        let drive = drive.map(|d| finite_values(d, "drive")).transpose()?;
        let options = LearningOptions {
            sample_rate_hz,
            periodic,
            gain,
            bandwidth_hz,
            filter_order,
            lead_samples,
            divergence_factor,
            inverse: parse_inverse(inverse)?,
            limits: limits.map(|l| pair(l, "limits")).transpose()?,
            mhe_bins,
            // The slew-projected learned drive is measured worse on the built-in stage (README):
            // not offered here yet.
            max_drive_step: None,
            anti_windup: None,
        };
        // Options are checked before the records' length (bounded there) allocates anything.
        options.validate().map_err(learn_error)?;
        let learner = py
            .detach(|| match &drive {
                Some(drive) => RustLearner::resume(&file, &desired, drive, options),
                None => RustLearner::new(&file, &desired, options),
            })
            .map_err(learn_error)?;
        Ok(Learner {
            inner: Mutex::new(learner),
            last: Mutex::new(None),
        })
    }

    /// The trial's measured response (array-like, aligned sample by sample with ``desired``
    /// and the drive that was sent) in; the next trial's drive (numpy array) out. Refuses a
    /// record of another length or with a NaN or infinite sample (``InvalidValueError``, state
    /// unchanged). When the divergence guard trips on this trial, warns with
    /// ``LearningDivergedWarning`` and returns the last good drive; after that, raises
    /// ``LearningStoppedError``. ``last_update`` holds the trial's indices and the prediction
    /// for the next. Releases the GIL while it computes.
    fn update<'py>(
        &self,
        py: Python<'py>,
        measured: ArrayIn<'py>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let measured = finite_values(measured, "measured")?;
        let outcome = py.detach(|| {
            let mut learner = self.lock();
            learner
                .update(&measured)
                .map(|update| (update, learner.drive().to_vec()))
        });
        let (update, drive) = outcome.map_err(learn_error)?;
        if let Status::Diverged {
            e_rms_percent,
            best_trial,
            best_e_rms_percent,
            factor,
        } = &update.status
        {
            let message = format!(
                "the divergence guard stopped the learning at trial {}: its e_rms {:.4} % exceeds \
                 {} times the best trial's ({best_trial}: {:.4} %); the drive returned is trial \
                 {best_trial}'s (the last good one); start again with a lower gain or bandwidth",
                update.trial, e_rms_percent, factor, best_e_rms_percent
            );
            let category = py
                .import("hystcomp._errors")?
                .getattr("LearningDivergedWarning")?;
            let message = std::ffi::CString::new(message)
                .map_err(|e| invalid(format!("warning text: {e}")))?;
            PyErr::warn(py, &category, &message, 1)?;
        }
        *self.last() = Some(update);
        Ok(array_out(py, drive))
    }

    /// The drive of the next trial (numpy array, the model's voltage unit): within the limits,
    /// never NaN; after the divergence guard stopped the learning, the last good drive.
    #[getter]
    fn drive<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.lock().drive().to_vec())
    }

    /// The reference the exact inverse follows in the next trial (numpy array, the model's
    /// displacement unit).
    #[getter]
    fn reference<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.lock().reference().to_vec())
    }

    /// The desired trajectory of one trial (numpy array).
    #[getter]
    fn desired<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.lock().desired().to_vec())
    }

    /// Trials measured so far (the next ``update`` measures trial ``trials``; trial 0 ran the
    /// first drive).
    #[getter]
    fn trials(&self) -> usize {
        self.lock().history().len()
    }

    /// The indices of every trial measured so far (``TrackingIndices``, % of the desired
    /// range).
    #[getter]
    fn history(&self) -> Vec<TrackingIndices> {
        self.lock()
            .history()
            .iter()
            .map(|&inner| TrackingIndices { inner })
            .collect()
    }

    /// The best trial measured so far (lowest e_rms), or ``None`` before the first update.
    #[getter]
    fn best_trial(&self) -> Option<usize> {
        self.lock().best().map(|(trial, _)| trial)
    }

    /// The best trial's drive (numpy array: the last good drive), or ``None``.
    #[getter]
    fn best_drive<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.lock()
            .best()
            .map(|(_, drive)| array_out(py, drive.to_vec()))
    }

    /// Whether the divergence guard stopped the learning.
    #[getter]
    fn stopped(&self) -> bool {
        self.lock().is_stopped()
    }

    /// The last trial's outcome, a ``LearningUpdate`` dataclass (``trial``, ``indices``,
    /// ``predicted`` indices of the next trial, ``clamped_samples`` of the next reference,
    /// ``status``), or ``None`` before the first update.
    #[getter]
    fn last_update<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        match &*self.last() {
            Some(update) => Ok(Some(typed(py, "LearningUpdate", to_python(py, update)?)?)),
            None => Ok(None),
        }
    }

    /// The learning law in force, a ``LearningLaw`` dataclass: ``gain``, ``lead_samples``,
    /// ``bandwidth_hz``, ``filter_order``, ``periodic``, ``padding_samples``, ``noise_gain``,
    /// ``stationary_noise_ratio`` (the learned reference's noise variance relative to the
    /// sensor's, bounded: noise is not amplified trial after trial), ``divergence_factor``,
    /// ``inverse``, ``limits``, ``model_has_vibration``.
    #[getter]
    fn law<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let law = self.lock().law().clone();
        typed(py, "LearningLaw", to_python(py, &law)?)
    }

    fn __repr__(&self) -> String {
        let learner = self.lock();
        let law = learner.law();
        format!(
            "Learner(samples={}, trials={}, gain={}, bandwidth_hz={:.4}, periodic={}, stopped={})",
            learner.desired().len(),
            learner.history().len(),
            law.gain,
            law.bandwidth_hz,
            if law.periodic { "True" } else { "False" },
            if learner.is_stopped() {
                "True"
            } else {
                "False"
            },
        )
    }
}
