//! The comparative study of section 4 of the paper, on a simulated stage: identification,
//! two pipelines of three compensators, the uncompensated run, and measured explanations of
//! the differences. [`run_study`] computes; [`crate::study_report`] draws and writes.
//!
//! - **Identification** (section 4.2): the [`IdentificationExcitation`] drives the stage from
//!   rest; the record (decimated, the MPIM being rate independent) identifies a plant MPIM
//!   (command voltage -> measured position, for IHC and WIHC) and an inverse MPIM (measured
//!   position -> command voltage, for DIHC), with `n` operators at thresholds `(i - 1)/n` of
//!   the input range (eq. (11)).
//! - **Pipelines**: `paper` identifies with particle swarm optimisation as the paper does and
//!   runs the delayed IHC and WIHC, as real-time implementations do; `exact` identifies by
//!   constrained least squares (the global optimum for the thresholds) and runs the exact
//!   per-sample inverses. DIHC is the same law in both, with each pipeline's inverse model.
//! - **Uncompensated** (section 4.3.1): the desired trajectory through a linear feedforward
//!   gain, `command = y_d * full-scale command / quasi-static stroke`.
//! - **Tracking** (section 4.3): the paper's trajectory for `periods` periods; the indices
//!   e_mhe, e_m, e_rms (eq. (12), (D1), (D2)) on the last full period.
//! - **Cross runs** that separate the two differences between the pipelines: the particle
//!   swarm models with the exact inverses, and the least-squares models with the delayed ones.
//!   Each stage run uses the same noise seed, so that differences between runs are never noise.

use std::fmt;
use std::time::Instant;

use hystcomp_identify::{
    Identification, IdentifyError, IdentifyOptions, Method as Solver, Progress, PsoOptions,
    Thresholds, Warmup, identify_observed,
};
use hystcomp_io::compensator::{CompensatorError, Method, ScaledCompensator};
use hystcomp_io::model_file::Direction;
use hystcomp_stage::{Stage, StageConfig, StageError, quasi_static_stroke_um};
use serde::Serialize;

use crate::excitation::IdentificationExcitation;
use crate::indices::{DEFAULT_MHE_BINS, IndexError, TrackingIndices};
use crate::{MultisineTrajectory, Reference};

/// Particle swarm iterations of the study's `paper` pipeline.
pub const STUDY_PSO_ITERATIONS: usize = 2000;

/// Everything the study can be asked to do differently.
#[derive(Debug, Clone, Serialize)]
pub struct StudyOptions {
    /// The stage (the built-in default unless a stage file is given).
    pub stage: StageConfig,
    /// Seed of the stage's sensor noise in the identification run; the tracking runs use
    /// `seed + 1`.
    pub seed: u64,
    /// Seed of the particle swarm.
    pub pso_seed: u64,
    /// Number of play operators (10, as in the paper).
    pub operators: usize,
    /// Periods of the trajectory to track (at least 2; indices on the last one).
    pub periods: usize,
    /// The identification excitation.
    pub excitation: IdentificationExcitation,
    /// Keep every `decimation`-th sample of the identification record (1 keeps all).
    pub decimation: usize,
    /// The particle swarm of the `paper` pipeline (its seed is replaced by `pso_seed`). The
    /// study runs the literature's swarm (40 particles, constriction coefficients) for 2000
    /// iterations rather than the 200 of the crate's default: on this problem the swarm is still
    /// far from the optimum after 200 (see the convergence in the report).
    pub pso: PsoOptions,
    /// Bins of the `y_d` range for e_mhe.
    pub mhe_bins: usize,
}

impl Default for StudyOptions {
    fn default() -> Self {
        StudyOptions {
            stage: StageConfig::default(),
            seed: 1,
            pso_seed: 1,
            operators: 10,
            periods: 2,
            excitation: IdentificationExcitation::default(),
            decimation: 10,
            pso: PsoOptions {
                iterations: STUDY_PSO_ITERATIONS,
                ..PsoOptions::default()
            },
            mhe_bins: DEFAULT_MHE_BINS,
        }
    }
}

/// Why the study could not run.
#[derive(Debug)]
pub enum StudyError {
    /// The stage file or the stage.
    Stage(StageError),
    /// An identification.
    Identify {
        /// Which model (e.g. `exact plant`).
        model: String,
        /// Why.
        error: IdentifyError,
    },
    /// A compensator could not be built from an identified model.
    Compensator {
        /// Which run.
        run: String,
        /// Why.
        error: CompensatorError,
    },
    /// The indices of a run.
    Index {
        /// Which run.
        run: String,
        /// Why.
        error: IndexError,
    },
    /// An option that cannot be used.
    Option(String),
}

impl fmt::Display for StudyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StudyError::Stage(e) => write!(f, "stage: {e}"),
            StudyError::Identify { model, error } => {
                write!(f, "identifying the {model} model: {error}")
            }
            StudyError::Compensator { run, error } => write!(f, "{run}: {error}"),
            StudyError::Index { run, error } => write!(f, "indices of {run}: {error}"),
            StudyError::Option(message) => f.write_str(message),
        }
    }
}

impl std::error::Error for StudyError {}

impl From<StageError> for StudyError {
    fn from(e: StageError) -> Self {
        StudyError::Stage(e)
    }
}

/// Watches the study's long steps (a progress bar in the command line). The study never
/// prints.
pub trait StudyObserver {
    /// A step begins, with `total` units of work.
    fn begin(&mut self, step: &str, total: u64);
    /// `done` units of the current step are finished.
    fn advance(&mut self, done: u64);
    /// The current step is finished.
    fn end(&mut self);
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl StudyObserver for Silent {
    fn begin(&mut self, _step: &str, _total: u64) {}
    fn advance(&mut self, _done: u64) {}
    fn end(&mut self) {}
}

/// The identification record (full rate).
#[derive(Debug, Clone, Serialize)]
pub struct IdentificationRecord {
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Command, V.
    pub command_v: Vec<f64>,
    /// Measured position, um.
    pub measured_um: Vec<f64>,
    /// Samples used for identification (after decimation).
    pub samples_used: usize,
}

/// One tracking run on the stage.
#[derive(Debug, Clone, Serialize)]
pub struct TrackingRun {
    /// What drove the stage, e.g. `exact / ihc`.
    pub label: String,
    /// The compensator (`None` for the linear feedforward gain).
    pub method: Option<Method>,
    /// Command sent to the stage, V.
    #[serde(skip)]
    pub command_v: Vec<f64>,
    /// Measured position, um.
    #[serde(skip)]
    pub measured_um: Vec<f64>,
    /// The indices on the evaluation window, % of the `y_d` range.
    pub indices: TrackingIndices,
    /// Samples the compensator had to clamp to its limits.
    pub saturated: u64,
    /// RMS difference, over the evaluation window, between the measured position and the
    /// position the compensator's own plant model predicts for the command it sent
    /// (% of the `y_d` range): how much of the tracking error is model mismatch. `None` for
    /// DIHC and the uncompensated run (no plant model in the loop).
    pub model_mismatch_rms_percent: Option<f64>,
}

/// One pipeline: its two models and its three runs.
#[derive(Debug, Clone, Serialize)]
pub struct Pipeline {
    /// `paper` or `exact`.
    pub name: String,
    /// One line for people.
    pub description: String,
    /// The plant model (IHC, WIHC).
    pub plant: Identification,
    /// The inverse model (DIHC).
    pub inverse: Identification,
    /// IHC, WIHC and DIHC, in that order.
    pub runs: Vec<TrackingRun>,
    /// The particle swarm's best RMS fit error after each iteration, % of the output range,
    /// for the plant and the inverse model (empty for least squares).
    pub convergence: [Vec<f64>; 2],
}

impl Pipeline {
    /// The run of `method`'s family (`ihc`, `wihc` or `dihc`, exact or delayed).
    pub fn run(&self, family: &str) -> Option<&TrackingRun> {
        self.runs.iter().find(|r| {
            r.method
                .is_some_and(|m| m.name().split('-').next() == Some(family))
        })
    }
}

/// Everything the study measured.
#[derive(Debug, Clone, Serialize)]
pub struct Study {
    /// The options it ran with.
    pub options: StudyOptions,
    /// Controller sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Time axis of the tracking runs, s.
    #[serde(skip)]
    pub time_s: Vec<f64>,
    /// The desired trajectory, um.
    #[serde(skip)]
    pub desired_um: Vec<f64>,
    /// First sample of the evaluation window (the last full period).
    pub evaluation_start: usize,
    /// The trajectory's period, s.
    pub period_s: f64,
    /// The linear feedforward gain of the uncompensated run, V/um.
    pub feedforward_gain_v_per_um: f64,
    /// The stage's quasi-static stroke at full command, um.
    pub stroke_um: f64,
    /// The identification record.
    #[serde(skip)]
    pub identification: IdentificationRecord,
    /// The uncompensated run.
    pub uncompensated: TrackingRun,
    /// The `paper` and the `exact` pipelines, in that order.
    pub pipelines: Vec<Pipeline>,
    /// The cross runs: particle swarm models with exact inverses, least-squares models with
    /// delayed ones (IHC and WIHC each).
    pub cross_runs: Vec<TrackingRun>,
    /// Wall-clock time of the identifications, s: (paper plant, paper inverse, exact plant,
    /// exact inverse).
    pub identification_times_s: [f64; 4],
    /// Wall-clock time of the whole study, s.
    pub elapsed_s: f64,
}

impl Study {
    /// The pipeline named `name`.
    pub fn pipeline(&self, name: &str) -> Option<&Pipeline> {
        self.pipelines.iter().find(|p| p.name == name)
    }

    /// The cross run labelled `label`.
    pub fn cross_run(&self, label: &str) -> Option<&TrackingRun> {
        self.cross_runs.iter().find(|r| r.label == label)
    }
}

/// Runs the study. Deterministic for given options: the same seeds give the same numbers.
pub fn run_study(
    options: &StudyOptions,
    observer: &mut dyn StudyObserver,
) -> Result<Study, StudyError> {
    let started = Instant::now();
    if options.periods < 2 {
        return Err(StudyError::Option(format!(
            "the study tracks at least 2 periods of the trajectory (indices on the last full \
             one), not {}",
            options.periods
        )));
    }
    if options.decimation == 0 {
        return Err(StudyError::Option("decimation must be at least 1".into()));
    }
    options.stage.validate()?;
    let fs = options.stage.sample_rate_hz;
    let full_scale = options.stage.full_scale_command_v();

    // 1. Identification experiment.
    observer.begin("excitation", 1);
    let mut excitation = options.excitation.clone();
    excitation.full_scale_v = full_scale;
    let command = excitation.command_v(fs);
    let mut stage = Stage::new(&options.stage, options.seed)?;
    let response = stage.run(&command);
    let v: Vec<f64> = command
        .iter()
        .step_by(options.decimation)
        .copied()
        .collect();
    let y: Vec<f64> = response
        .measured_position_um
        .iter()
        .step_by(options.decimation)
        .copied()
        .collect();
    let record = IdentificationRecord {
        time_s: response.time_s,
        command_v: command,
        measured_um: response.measured_position_um,
        samples_used: v.len(),
    };
    observer.end();

    // 2. Identification: LS and PSO, plant and inverse.
    let base = IdentifyOptions {
        thresholds: Thresholds::Uniform(options.operators),
        // The record starts at rest with the operators' memory at zero (eq. (1)).
        warmup: Warmup::Samples(0),
        ..IdentifyOptions::default()
    };
    let mut pso = options.pso.clone();
    pso.seed = options.pso_seed;
    let mut times = [0.0; 4];
    let mut fit = |name: &str,
                   direction: Direction,
                   solver: Solver,
                   slot: usize,
                   observer: &mut dyn StudyObserver|
     -> Result<(Identification, Vec<f64>), StudyError> {
        let opts = IdentifyOptions {
            direction,
            method: solver.clone(),
            ..base.clone()
        };
        let total = match &solver {
            Solver::ParticleSwarm(p) => p.iterations as u64,
            Solver::LeastSquares => 1,
        };
        observer.begin(name, total);
        let t = Instant::now();
        let mut convergence = Vec::new();
        let is_swarm = matches!(solver, Solver::ParticleSwarm(_));
        let mut watch = |p: &Progress| {
            observer.advance(p.iteration as u64);
            if is_swarm {
                // The cost is the RMS error in normalised output units (output / its range).
                convergence.push(p.best_cost * 100.0);
            }
        };
        let result =
            identify_observed(&v, &y, &opts, &mut watch).map_err(|error| StudyError::Identify {
                model: name.to_string(),
                error,
            });
        times[slot] = t.elapsed().as_secs_f64();
        observer.end();
        result.map(|id| (id, convergence))
    };
    let (paper_plant, paper_plant_convergence) = fit(
        "paper plant (PSO)",
        Direction::Plant,
        Solver::ParticleSwarm(pso.clone()),
        0,
        observer,
    )?;
    let (paper_inverse, paper_inverse_convergence) = fit(
        "paper inverse (PSO)",
        Direction::Inverse,
        Solver::ParticleSwarm(pso),
        1,
        observer,
    )?;
    let (exact_plant, _) = fit(
        "exact plant (LS)",
        Direction::Plant,
        Solver::LeastSquares,
        2,
        observer,
    )?;
    let (exact_inverse, _) = fit(
        "exact inverse (LS)",
        Direction::Inverse,
        Solver::LeastSquares,
        3,
        observer,
    )?;

    // 3. Tracking.
    let reference = Reference::paper();
    let trajectory: MultisineTrajectory = reference.trajectory();
    let period_s = reference.trajectory.period_s;
    let samples = (options.periods as f64 * period_s * fs).round() as usize;
    let per_period = (period_s * fs).round() as usize;
    let (time_s, desired) = trajectory.sample(fs, samples);
    let evaluation_start = samples - per_period;
    let stroke_um = quasi_static_stroke_um(&options.stage)?;
    let gain = full_scale / stroke_um;
    let tracking_seed = options.seed.wrapping_add(1);

    let jobs: Vec<(String, Option<Method>, Option<&Identification>)> = vec![
        ("uncompensated".into(), None, None),
        (
            "paper / ihc-delayed".into(),
            Some(Method::IhcDelayed),
            Some(&paper_plant),
        ),
        (
            "paper / wihc-delayed".into(),
            Some(Method::WihcDelayed),
            Some(&paper_plant),
        ),
        (
            "paper / dihc".into(),
            Some(Method::Dihc),
            Some(&paper_inverse),
        ),
        ("exact / ihc".into(), Some(Method::Ihc), Some(&exact_plant)),
        (
            "exact / wihc".into(),
            Some(Method::Wihc),
            Some(&exact_plant),
        ),
        (
            "exact / dihc".into(),
            Some(Method::Dihc),
            Some(&exact_inverse),
        ),
        (
            "PSO models / ihc".into(),
            Some(Method::Ihc),
            Some(&paper_plant),
        ),
        (
            "PSO models / wihc".into(),
            Some(Method::Wihc),
            Some(&paper_plant),
        ),
        (
            "LS models / ihc-delayed".into(),
            Some(Method::IhcDelayed),
            Some(&exact_plant),
        ),
        (
            "LS models / wihc-delayed".into(),
            Some(Method::WihcDelayed),
            Some(&exact_plant),
        ),
    ];
    observer.begin("tracking runs", jobs.len() as u64);
    let mut runs = Vec::with_capacity(jobs.len());
    for (k, (label, method, model)) in jobs.into_iter().enumerate() {
        let (command_v, saturated) = match (method, model) {
            (Some(method), Some(model)) => {
                let mut c = ScaledCompensator::new(&model.model, method, Some((0.0, full_scale)))
                    .map_err(|error| StudyError::Compensator {
                    run: label.clone(),
                    error,
                })?;
                let mut out = vec![0.0; samples];
                c.process(&desired, &mut out)
                    .map_err(|error| StudyError::Compensator {
                        run: label.clone(),
                        error,
                    })?;
                (out, c.diagnostics().saturated)
            }
            _ => (desired.iter().map(|y| y * gain).collect(), 0),
        };
        let mut stage = Stage::new(&options.stage, tracking_seed)?;
        let measured = stage.run(&command_v).measured_position_um;
        let indices = TrackingIndices::compute(
            &desired[evaluation_start..],
            &measured[evaluation_start..],
            options.mhe_bins,
        )
        .map_err(|error| StudyError::Index {
            run: label.clone(),
            error,
        })?;
        let model_mismatch_rms_percent = match (method, model) {
            (Some(m), Some(model)) if m.needs() == Direction::Plant => {
                let predicted = model
                    .model
                    .predict(&command_v)
                    .map_err(|e| StudyError::Option(e.to_string()))?;
                let range = indices_range(&desired[evaluation_start..]);
                let sum: f64 = predicted[evaluation_start..]
                    .iter()
                    .zip(&measured[evaluation_start..])
                    .map(|(p, y)| (p - y).powi(2))
                    .sum();
                Some((sum / per_period as f64).sqrt() / range * 100.0)
            }
            _ => None,
        };
        runs.push(TrackingRun {
            label,
            method,
            command_v,
            measured_um: measured,
            indices,
            saturated,
            model_mismatch_rms_percent,
        });
        observer.advance(k as u64 + 1);
    }
    observer.end();

    let mut runs = runs.into_iter();
    let uncompensated = runs.next().expect("11 runs");
    let paper_runs: Vec<TrackingRun> = runs.by_ref().take(3).collect();
    let exact_runs: Vec<TrackingRun> = runs.by_ref().take(3).collect();
    let cross_runs: Vec<TrackingRun> = runs.collect();
    Ok(Study {
        options: options.clone(),
        sample_rate_hz: fs,
        time_s,
        desired_um: desired,
        evaluation_start,
        period_s,
        feedforward_gain_v_per_um: gain,
        stroke_um,
        identification: record,
        uncompensated,
        pipelines: vec![
            Pipeline {
                name: "paper".into(),
                description: "particle swarm identification (as the paper), delayed IHC and WIHC \
                              (as real-time implementations), DIHC"
                    .into(),
                plant: paper_plant,
                inverse: paper_inverse,
                runs: paper_runs,
                convergence: [paper_plant_convergence, paper_inverse_convergence],
            },
            Pipeline {
                name: "exact".into(),
                description: "constrained least-squares identification (global optimum), exact \
                              per-sample IHC and WIHC, DIHC"
                    .into(),
                plant: exact_plant,
                inverse: exact_inverse,
                runs: exact_runs,
                convergence: [Vec::new(), Vec::new()],
            },
        ],
        cross_runs,
        identification_times_s: times,
        elapsed_s: started.elapsed().as_secs_f64(),
    })
}

/// `max - min` of a record.
fn indices_range(values: &[f64]) -> f64 {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    hi - lo
}
