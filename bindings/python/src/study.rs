//! `reproduce(...)`: the comparative study of section 4 on the simulated stage
//! (`hystcomp_experiments::run_study`), as `hystcomp reproduce` runs it.

use std::path::PathBuf;

use hystcomp_experiments::study::Silent;
use hystcomp_experiments::{
    RunMeta, Study, StudyOptions, StudySummary, run_study, summarize, write_outputs,
};
use hystcomp_stage::StageConfig;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::arrays::array_out;
use crate::errors::{self, invalid};
use crate::indices::{TrackingIndices, indices_dict};
use crate::model::{ModelFile, dict, to_python};

/// The result of ``reproduce()``: the paper's Table 3 measured on the simulated stage.
///
/// - ``table``: ``{"uncompensated": {...}, "paper": {"ihc": {...}, "wihc": {...},
///   "dihc": {...}}, "exact": {...}}`` with ``{"e_mhe", "e_m", "e_rms"}`` in percent;
/// - ``published``: the paper's Table 3 in the same shape;
/// - ``summary``: everything ``hystcomp reproduce --json`` prints (acceptance checks, cross
///   runs, fits...); ``passed``: whether every acceptance check holds;
/// - ``models``: the identified model files, ``{"paper": {"plant": ..., "inverse": ...},
///   "exact": {...}}``;
/// - ``time``, ``desired_um`` and ``runs`` (label -> ``{"command_v", "measured_um"}``) for
///   plots; the indices are taken from ``evaluation_start`` on (the last full period);
/// - ``report``: the path of the HTML report when ``out_dir`` was given, else ``None``.
///
/// ``str(result)`` is the plain-text Table 3 of ``hystcomp reproduce``.
#[pyclass(module = "hystcomp", name = "StudyResult", frozen)]
pub struct StudyResult {
    study: Study,
    summary: StudySummary,
    report: Option<PathBuf>,
}

/// `"ihc"`, `"wihc"` or `"dihc"` for a run's method.
fn family(run: &hystcomp_experiments::study::TrackingRun) -> &'static str {
    match run.method.map(|m| m.name()) {
        Some(name) if name.starts_with("ihc") => "ihc",
        Some(name) if name.starts_with("wihc") => "wihc",
        Some(_) => "dihc",
        None => "uncompensated",
    }
}

#[pymethods]
impl StudyResult {
    /// Our Table 3, percent.
    #[getter]
    fn table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let table = PyDict::new(py);
        table.set_item(
            "uncompensated",
            indices_dict(py, &self.study.uncompensated.indices)?,
        )?;
        for pipeline in &self.study.pipelines {
            let runs = PyDict::new(py);
            for run in &pipeline.runs {
                runs.set_item(family(run), indices_dict(py, &run.indices)?)?;
            }
            table.set_item(&pipeline.name, runs)?;
        }
        Ok(table)
    }

    /// The paper's Table 3 (measured on its hardware), percent.
    #[getter]
    fn published<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.summary.published;
        let table = PyDict::new(py);
        table.set_item(
            "uncompensated",
            dict(py, [("e_mhe", p.uncompensated_e_mhe)])?,
        )?;
        for (name, r) in [("ihc", p.ihc), ("wihc", p.wihc), ("dihc", p.dihc)] {
            table.set_item(
                name,
                dict(py, [("e_mhe", r.e_mhe), ("e_m", r.e_m), ("e_rms", r.e_rms)])?,
            )?;
        }
        Ok(table)
    }

    /// The indices of one run: ``result.indices("exact", "ihc")``, or
    /// ``result.indices("uncompensated")``.
    #[pyo3(signature = (pipeline, method = None))]
    fn indices(&self, pipeline: &str, method: Option<&str>) -> PyResult<TrackingIndices> {
        if pipeline == "uncompensated" {
            return Ok(TrackingIndices {
                inner: self.study.uncompensated.indices,
            });
        }
        let p = self.study.pipeline(pipeline).ok_or_else(|| {
            invalid(format!(
                "pipeline {pipeline:?} is unknown; give \"paper\", \"exact\" or \"uncompensated\""
            ))
        })?;
        let method = method.unwrap_or("");
        p.run(method)
            .map(|run| TrackingIndices { inner: run.indices })
            .ok_or_else(|| {
                invalid(format!(
                    "method {method:?} is unknown; give \"ihc\", \"wihc\" or \"dihc\""
                ))
            })
    }

    /// Everything ``hystcomp reproduce --json`` reports, as a ``StudySummary`` dataclass with
    /// the same fields (``.to_dict()`` for the dict).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::model::typed(py, "StudySummary", to_python(py, &self.summary)?)
    }

    /// The acceptance checks: a list of ``{"what", "value", "bound", "passed"}``.
    #[getter]
    fn acceptance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.summary.acceptance)
    }

    /// Whether every acceptance check holds.
    #[getter]
    fn passed(&self) -> bool {
        self.summary.acceptance.iter().all(|a| a.passed)
    }

    /// The identified model files of each pipeline.
    #[getter]
    fn models<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let models = PyDict::new(py);
        for p in &self.study.pipelines {
            let pair = PyDict::new(py);
            pair.set_item("plant", ModelFile::wrap(p.plant.model.clone()))?;
            pair.set_item("inverse", ModelFile::wrap(p.inverse.model.clone()))?;
            models.set_item(&p.name, pair)?;
        }
        Ok(models)
    }

    /// Time axis of the tracking runs, s.
    #[getter]
    fn time<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.study.time_s.clone())
    }

    /// The desired trajectory, um.
    #[getter]
    fn desired_um<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array_out(py, self.study.desired_um.clone())
    }

    /// First sample of the evaluation window (the last full period).
    #[getter]
    fn evaluation_start(&self) -> usize {
        self.study.evaluation_start
    }

    /// Every tracking run, by label (e.g. ``"exact / ihc"``): its command (V) and measured
    /// position (um).
    #[getter]
    fn runs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let runs = PyDict::new(py);
        let all = std::iter::once(&self.study.uncompensated)
            .chain(self.study.pipelines.iter().flat_map(|p| p.runs.iter()))
            .chain(self.study.cross_runs.iter());
        for run in all {
            let arrays = PyDict::new(py);
            arrays.set_item("command_v", array_out(py, run.command_v.clone()))?;
            arrays.set_item("measured_um", array_out(py, run.measured_um.clone()))?;
            runs.set_item(&run.label, arrays)?;
        }
        Ok(runs)
    }

    /// The labels of the runs, in order.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let labels: Vec<&str> = std::iter::once(&self.study.uncompensated)
            .chain(self.study.pipelines.iter().flat_map(|p| p.runs.iter()))
            .chain(self.study.cross_runs.iter())
            .map(|r| r.label.as_str())
            .collect();
        PyList::new(py, labels)
    }

    /// The HTML report written to ``out_dir``, or ``None``.
    #[getter]
    fn report(&self) -> Option<PathBuf> {
        self.report.clone()
    }

    /// Wall-clock time of the study, s.
    #[getter]
    fn elapsed_s(&self) -> f64 {
        self.study.elapsed_s
    }

    fn __str__(&self) -> String {
        self.summary.to_string()
    }

    fn __repr__(&self) -> String {
        format!(
            "StudyResult(pipelines={:?}, passed={}, elapsed_s={:.1})",
            self.study
                .pipelines
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>(),
            self.summary.acceptance.iter().all(|a| a.passed),
            self.study.elapsed_s
        )
    }
}

/// Reproduces the paper's comparative study (section 4, Table 3) on the simulated stage, as
/// ``hystcomp reproduce`` does: an identification experiment, a plant and an inverse model
/// identified by particle swarm (``paper`` pipeline, with delayed IHC and WIHC) and by least
/// squares (``exact`` pipeline, with exact IHC and WIHC), DIHC in both, and the uncompensated
/// run; the indices on the last of ``periods`` periods of the paper's trajectory.
///
/// - ``stage_toml``: a stage file's TOML text (the default stage without it);
/// - ``seed``: the stage noise (identification; tracking runs use ``seed + 1``) and the swarm;
/// - ``pso_iterations``, ``pso_particles``: the ``paper`` pipeline's swarm (by default that of
///   ``hystcomp reproduce``; fewer is faster);
/// - ``out_dir``: also write the HTML report, the figures and the models there.
///
/// Releases the GIL while it runs. Raises
/// ``StageConfigError``, ``IdentificationError``, ``InvalidValueError`` (e.g. fewer than 2
/// periods) or ``OSError`` (the report could not be written).
#[pyfunction]
#[pyo3(signature = (*, stage_toml = None, seed = 1, periods = 2, operators = 10, pso_iterations = None, pso_particles = None, out_dir = None))]
#[allow(clippy::too_many_arguments)]
pub fn reproduce(
    py: Python<'_>,
    stage_toml: Option<&str>,
    seed: u64,
    periods: usize,
    operators: usize,
    pso_iterations: Option<usize>,
    pso_particles: Option<usize>,
    out_dir: Option<PathBuf>,
) -> PyResult<StudyResult> {
    let stage = match stage_toml {
        Some(text) => StageConfig::from_toml_str(text).map_err(errors::stage)?,
        None => StageConfig::default(),
    };
    let mut options = StudyOptions {
        stage,
        seed,
        pso_seed: seed,
        periods,
        operators,
        ..StudyOptions::default()
    };
    // Without them, the study's own swarm (that of `hystcomp reproduce`).
    if let Some(iterations) = pso_iterations {
        options.pso = options
            .pso
            .clone()
            .with_iterations(iterations)
            .map_err(errors::identify)?;
    }
    if let Some(particles) = pso_particles {
        options.pso = options
            .pso
            .clone()
            .with_particles(particles)
            .map_err(errors::identify)?;
    }
    // The study reads no clock; the report's time stamp comes from Python's.
    let generated_at: String = py
        .import("datetime")?
        .getattr("datetime")?
        .call_method0("now")?
        .call_method0("astimezone")?
        .call_method("isoformat", (), Some(&dict(py, [("timespec", "seconds")])?))?
        .extract()?;
    let outcome = py.detach(|| {
        let study = run_study(&options, &mut Silent).map_err(Failure::Study)?;
        let report = match &out_dir {
            Some(dir) => {
                let meta = RunMeta {
                    generated_at,
                    git_description: None,
                    command_line: Some("hystcomp.reproduce() (Python)".into()),
                };
                let files = write_outputs(&study, dir, &meta, &mut Silent)
                    .map_err(|e| Failure::Output(e.to_string()))?;
                Some(files.report)
            }
            None => None,
        };
        Ok((study, report))
    });
    let (study, report) = outcome.map_err(|failure| match failure {
        Failure::Study(e) => errors::study(e),
        Failure::Output(message) => errors::os_error(
            std::io::ErrorKind::Other,
            None,
            message,
            out_dir
                .as_ref()
                .map(|d| d.display().to_string())
                .unwrap_or_default(),
        ),
    })?;
    let summary = summarize(&study);
    Ok(StudyResult {
        study,
        summary,
        report,
    })
}

/// Why `reproduce` failed, carried out of the GIL-free section.
enum Failure {
    Study(hystcomp_experiments::StudyError),
    Output(String),
}
