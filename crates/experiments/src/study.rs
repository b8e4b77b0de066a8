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

use hystcomp_core::CoreError;
use hystcomp_identify::{
    DEFAULT_DELAYED_LOOP_BOUND, Identification, IdentifyError, IdentifyOptions, Method as Solver,
    Progress, PsoOptions, Thresholds, Warmup, identify_observed,
};
use hystcomp_io::compensator::{CompensatorError, Method, ScaledCompensator};
use hystcomp_io::model_file::{Direction, ModelFile};
use hystcomp_stage::{Stage, StageConfig, StageError, quasi_static_stroke_um};
use rayon::prelude::*;
use serde::Serialize;

use crate::chain_excitation::ChainSegments;
use crate::duration::{DurationStudy, run_duration};
use crate::excitation::IdentificationExcitation;
use crate::full::{FullOptions, FullPipeline, identify_full};
use crate::indices::{DEFAULT_MHE_BINS, IndexError, TrackingIndices, check_mhe_bins};
use crate::speed::{SpeedStudy, run_speed};
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
    /// Periods of the trajectory to track (2 to [`MAX_STUDY_PERIODS`]; indices on the last
    /// one).
    pub periods: usize,
    /// The identification excitation.
    pub excitation: IdentificationExcitation,
    /// Keep every `decimation`-th sample of the identification record (1 keeps all).
    pub decimation: usize,
    /// The particle swarm of the `paper` pipeline (its seed is replaced by `pso_seed`). The
    /// study runs the crate's default swarm (50 particles on a ring, constriction
    /// coefficients, branch slopes as coordinates) for 2000 iterations rather than the
    /// default 10 000: at n = 10 it reaches the optimum well before (see the convergence in
    /// the report).
    pub pso: PsoOptions,
    /// Bins of the `y_d` range for e_mhe (at most one per [`crate::indices::MIN_SAMPLES_PER_BIN`] samples of
    /// the evaluated period).
    pub mhe_bins: usize,
    /// The `full` pipeline (hysteresis, creep and vibration) and what the excitation gains for
    /// it.
    pub full: FullOptions,
    /// The learning study's drive kept within the amplifier's slew rate: every trial's drive
    /// projected onto the drives whose steps are within [`crate::speed::max_drive_step_v`]
    /// (the speed study's margin of the slew rate) and the reference learned from the
    /// projected drive (`hystcomp_learn::slew`, constrained ILC). Off by default.
    pub slew_aware_learning: bool,
    /// A learning series whose faithful starting drive asks more than the amplifier's slew
    /// rate starts from the speed study's slew-constrained drive instead
    /// ([`crate::learning_study::feasible_start`], steps within
    /// [`crate::speed::max_drive_step_v`]): trial 0 is the best feasible feedforward, not the
    /// infeasible faithful inverse. On by default: with the `full` pipeline's crowded
    /// thresholds the learning raster's best of 20 trials is 0.080 % from it and 0.135 % from
    /// the faithful drive (issue 12: 0.1; README, learning from repetition).
    pub feasible_learning_start: bool,
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
            full: FullOptions::default(),
            slew_aware_learning: false,
            feasible_learning_start: true,
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
/// prints. Step names are at most 12 characters (the width of the command line's labels).
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
    /// Samples used for identification (after decimation) by the `paper` and `exact`
    /// pipelines.
    pub samples_used: usize,
    /// The hysteresis excitation's samples (the record's first part; the `paper` and `exact`
    /// pipelines identify on them).
    pub hysteresis_samples: usize,
    /// Where the chain's parts of the excitation lie in the record (sample indices).
    pub chain_segments: ChainSegments,
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
    /// Samples the compensator clamped to its limits: desired positions out of reach, and for
    /// the delayed loops also reachable ones where the loop hit a limit (after a jump).
    pub saturated: u64,
    /// RMS difference, over the evaluation window, between the measured position and the
    /// position the compensator's own plant model predicts for the command it sent
    /// (% of the `y_d` range): how much of the tracking error is model mismatch. `None` for
    /// DIHC and the uncompensated run (no plant model in the loop).
    pub model_mismatch_rms_percent: Option<f64>,
    /// Why the run is not what its label says, if it is not: a plain delayed loop refused on
    /// its model (loop gain of 1 or more: it could ring), replaced by its guarded form, which
    /// never oscillates (`method` says which ran).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// How much the indices move when only the sensor noise changes: the uncompensated run and
/// the exact IHC run, repeated with other noise seeds on the same stage and the same
/// commands. A difference between two runs smaller than this spread is not a measured
/// difference.
#[derive(Debug, Clone, Serialize)]
pub struct NoiseFloor {
    /// The noise seeds of the tracking runs: the study's own (`seed + 1`) first, then the
    /// extra ones.
    pub seeds: Vec<u64>,
    /// The uncompensated run's indices with each seed, % of the `y_d` range.
    pub uncompensated: Vec<TrackingIndices>,
    /// The exact IHC run's indices with each seed, % of the `y_d` range.
    pub exact_ihc: Vec<TrackingIndices>,
    /// The largest `max - min` of e_rms over the seeds, of either run, percentage points.
    pub e_rms_spread_percent: f64,
    /// The largest `max - min` of e_mhe over the seeds, of either run, percentage points.
    pub e_mhe_spread_percent: f64,
}

/// One ablation run: the `exact` pipeline (least-squares plant model identified on the same
/// excitation, exact IHC) on the study's stage with some effects switched off.
#[derive(Debug, Clone, Serialize)]
pub struct AblationRun {
    /// What is switched off, e.g. `creep off`; `baseline` for the study's stage.
    pub label: String,
    /// The stage changes, in stage-file terms.
    pub change: String,
    /// Whether the change altered the stage at all (creep already off stays unchanged).
    pub changed: bool,
    /// RMS fit error of the re-identified plant model, % of the output range.
    pub plant_fit_rms_percent: f64,
    /// The exact IHC run's indices, % of the `y_d` range.
    pub ihc: TrackingIndices,
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
    /// The `full` pipeline: hysteresis, creep and vibration.
    pub full: FullPipeline,
    /// The duration study: the paper's trajectory for 200 s, and a held step.
    pub duration: DurationStudy,
    /// The speed study: the paper's trajectory time-compressed, and triangle rasters.
    pub speed: SpeedStudy,
    /// The learning study: e_rms against trial number when the motion repeats (issue 12).
    pub learning: crate::learning_study::LearningStudy,
    /// The cross runs: particle swarm models with exact inverses, least-squares models with
    /// delayed ones (IHC and WIHC each).
    pub cross_runs: Vec<TrackingRun>,
    /// The noise floor of the tracking indices (other sensor-noise seeds).
    pub noise_floor: NoiseFloor,
    /// The ablation runs of the exact IHC: the baseline, then one effect off at a time, then
    /// all of them off (only the hysteresis-model mismatch and quantisation remain).
    pub ablations: Vec<AblationRun>,
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

/// The most samples the study simulates in one run (5 000 000): the identification
/// excitation (43 s by default) and each tracking run (10 s per period) at the stage's
/// `sample_rate_hz`. About 1 GB of memory at the bound; 10 kHz and 2 periods take 430 000 and
/// 200 000 samples.
pub const MAX_STUDY_RUN_SAMPLES: usize = 5_000_000;

/// Refuses a stage rate and study length whose runs exceed [`MAX_STUDY_RUN_SAMPLES`], before
/// anything is allocated ([`run_study`] calls it; callers may call it first to say which
/// stage file is at fault).
pub fn check_run_lengths(options: &StudyOptions) -> Result<(), StudyError> {
    let fs = options.stage.sample_rate_hz;
    let period_s = Reference::paper().trajectory.period_s;
    for (what, duration_s) in [
        (
            "identification excitation".to_owned(),
            options.excitation.duration_s() + options.full.excitation.duration_s(),
        ),
        ("duration study run".to_owned(), crate::duration::DURATION_S),
        (
            format!("tracking run of {} periods", options.periods),
            options.periods as f64 * period_s,
        ),
    ] {
        let samples = duration_s * fs;
        if !(samples.is_finite() && samples <= MAX_STUDY_RUN_SAMPLES as f64) {
            return Err(StudyError::Option(format!(
                "the study's {what} lasts {duration_s} s, which at sample_rate_hz = {fs} Hz is \
                 {samples:.0} samples, more than the {MAX_STUDY_RUN_SAMPLES} the study simulates \
                 in one run; lower sample_rate_hz in the stage file (at most {:.0} Hz here) or \
                 the number of periods",
                MAX_STUDY_RUN_SAMPLES as f64 / duration_s
            )));
        }
    }
    Ok(())
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
    if options.periods > MAX_STUDY_PERIODS {
        return Err(StudyError::Option(format!(
            "the study tracks at most {MAX_STUDY_PERIODS} periods of the trajectory (each adds \
             10 s of simulation to every one of its {} tracking runs and about 20 MB of \
             memory), not {}; the indices use only the last period, so 2 is enough",
            TRACKING_RUNS, options.periods
        )));
    }
    if options.decimation == 0 {
        return Err(StudyError::Option("decimation must be at least 1".into()));
    }
    options.stage.validate()?;
    let fs = options.stage.sample_rate_hz;
    check_run_lengths(options)?;
    // The full pipeline's threshold spacing, before any run.
    crate::full::thresholds(options.full.operators, options.full.threshold_exponent)?;
    let full_scale = options.stage.full_scale_command_v();

    // 1. Identification experiment.
    observer.begin("excitation", 1);
    let mut excitation = options.excitation.clone();
    excitation.full_scale_v = full_scale;
    let mut command = excitation.command_v(fs);
    let hysteresis_samples = command.len();
    let (chain_part, mut chain_segments) = options
        .full
        .excitation
        .command_v(full_scale, fs, command.last().copied().unwrap_or(0.0))
        .map_err(|e| StudyError::Option(format!("the chain's excitation: {e}")))?;
    for range in [
        &mut chain_segments.rate,
        &mut chain_segments.holds,
        &mut chain_segments.vibration,
    ] {
        *range = range.start + hysteresis_samples..range.end + hysteresis_samples;
    }
    command.extend(chain_part);
    let mut stage = Stage::new(&options.stage, options.seed)?;
    let response = stage.run(&command);
    // The paper and exact pipelines: the hysteresis excitation alone.
    let v: Vec<f64> = command[..hysteresis_samples]
        .iter()
        .step_by(options.decimation)
        .copied()
        .collect();
    let y: Vec<f64> = response.measured_position_um[..hysteresis_samples]
        .iter()
        .step_by(options.decimation)
        .copied()
        .collect();
    let record = IdentificationRecord {
        time_s: response.time_s,
        command_v: command,
        measured_um: response.measured_position_um,
        samples_used: v.len(),
        hysteresis_samples,
        chain_segments,
    };
    observer.end();

    // 2. Identification: LS and PSO, plant and inverse.
    let base = IdentifyOptions {
        thresholds: Thresholds::Uniform(options.operators),
        // The record starts at rest with the operators' memory at zero (eq. (1)).
        warmup: Warmup::Samples(0),
        // The study measures what each solver reaches, a poor fit included (a swarm cut short).
        max_fit_rms_percent: None,
        ..IdentifyOptions::default()
    };
    // The full pipeline's identification (the study's longest serial step) needs only the
    // record: it runs on a thread of its own while the paper's and the exact pipeline's models
    // are identified and tracked, their noise floor and ablations run, and is joined before
    // the full pipeline's runs. The same numbers as one after the other.
    std::thread::scope(|scope| {
        // Its own copy of the record, which the study keeps.
        let (command_v, measured_um) = (record.command_v.clone(), record.measured_um.clone());
        let vibration = record.chain_segments.vibration.clone();
        let base = &base;
        let full_thread = scope.spawn(move || {
            identify_full(
                &command_v,
                &measured_um,
                fs,
                options.decimation,
                vibration,
                base,
                &options.full,
            )
        });
        let mut pso = options.pso.clone();
        pso.seed = options.pso_seed;
        let mut times = [0.0; 4];
        let mut fit = |name: &str,
                       step: &str,
                       direction: Direction,
                       solver: Solver,
                       slot: usize,
                       observer: &mut dyn StudyObserver|
         -> Result<(Identification, Vec<f64>), StudyError> {
            // The paper pipeline's plant model drives the one-sample-delayed loops: the swarm
            // holds both delayed loops' gains to at most the default bound (as a penalty), so that
            // they are stable by construction on any stage (issue 10).
            let for_delayed =
                matches!(solver, Solver::ParticleSwarm(_)) && direction == Direction::Plant;
            let opts = IdentifyOptions {
                direction,
                method: solver.clone(),
                delayed_loop_bound: for_delayed.then_some(DEFAULT_DELAYED_LOOP_BOUND),
                ..base.clone()
            };
            let total = match &solver {
                Solver::ParticleSwarm(p) => p.iterations as u64,
                Solver::LeastSquares => 1,
            };
            observer.begin(step, total);
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
            let result = match identify_observed(&v, &y, &opts, &mut watch) {
                // A swarm cut short may find no model within the bound: the model without it,
                // whose plain delayed loops are then refused and run guarded, with a note.
                Err(IdentifyError::SwarmInfeasible { .. }) if for_delayed => {
                    let unbounded = IdentifyOptions {
                        delayed_loop_bound: None,
                        ..opts.clone()
                    };
                    identify_observed(&v, &y, &unbounded, &mut watch)
                }
                other => other,
            }
            .map_err(|error| StudyError::Identify {
                model: name.to_string(),
                error,
            });
            times[slot] = t.elapsed().as_secs_f64();
            observer.end();
            result.map(|id| (id, convergence))
        };
        let (paper_plant, paper_plant_convergence) = fit(
            "paper plant (PSO)",
            "PSO plant",
            Direction::Plant,
            Solver::ParticleSwarm(pso.clone()),
            0,
            observer,
        )?;
        let (paper_inverse, paper_inverse_convergence) = fit(
            "paper inverse (PSO)",
            "PSO inverse",
            Direction::Inverse,
            Solver::ParticleSwarm(pso),
            1,
            observer,
        )?;
        let (exact_plant, _) = fit(
            "exact plant (LS)",
            "LS plant",
            Direction::Plant,
            Solver::LeastSquares,
            2,
            observer,
        )?;
        let (exact_inverse, _) = fit(
            "exact inverse (LS)",
            "LS inverse",
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
        // Checked now, before the runs, by the rule e_mhe applies.
        check_mhe_bins(options.mhe_bins, per_period)
            .map_err(|e| StudyError::Option(format!("the evaluated period (one per run): {e}")))?;
        let stroke_um = quasi_static_stroke_um(&options.stage)?;
        let desired_max = desired.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if stroke_um.is_nan() || stroke_um < desired_max {
            let amplifier = &options.stage.amplifier;
            let amplifier_top = full_scale * amplifier.gain;
            // Below the rail, the DAC's top and the gain limit the voltage, not the rail.
            let more_voltage = if amplifier_top < amplifier.output_max_v * (1.0 - 1e-9) {
                "amplifier.gain or dac.max_v: the DAC's top does not reach amplifier.output_max_v"
            } else {
                "amplifier.output_max_v"
            };
            return Err(StudyError::Option(format!(
                "the stage cannot reach the trajectory: its quasi-static stroke at full command \
             ({full_scale:.3} V, {amplifier_top:.1} V at the amplifier) is {stroke_um:.2} um, \
             below the trajectory's maximum of {desired_max:.2} um; give the stage more stroke \
             (e.g. hysteresis.preisach.stroke_um or hysteresis.bouc_wen.d_p_um_per_v) or more \
             voltage ({more_voltage})"
            )));
        }
        let sensor_span_um = options.stage.adc.max_v / options.stage.sensor.sensitivity_v_per_um;
        if sensor_span_um < desired_max {
            return Err(StudyError::Option(format!(
                "the stage's sensor cannot read the trajectory: its span ends at adc.max_v / \
             sensor.sensitivity_v_per_um = {} / {} = {sensor_span_um:.2} um, below the \
             trajectory's maximum of {desired_max:.2} um, so the measured position would \
             saturate; raise adc.max_v or lower sensor.sensitivity_v_per_um",
                options.stage.adc.max_v, options.stage.sensor.sensitivity_v_per_um
            )));
        }
        let gain = full_scale / stroke_um;
        let tracking_seed = options.seed.wrapping_add(1);

        // The runs without the full pipeline's models now; its three after its identification.
        let mut jobs: Vec<TrackingJob<'_>> = vec![("uncompensated".into(), None, None)];
        jobs.extend(pipeline_jobs(
            "paper",
            [Method::IhcDelayed, Method::WihcDelayed],
            &paper_plant.model,
            &paper_inverse.model,
        ));
        jobs.extend(pipeline_jobs(
            "exact",
            [Method::Ihc, Method::Wihc],
            &exact_plant.model,
            &exact_inverse.model,
        ));
        // Where the full pipeline's runs go, after the paper's and the exact pipeline's.
        let full_at = jobs.len();
        jobs.extend([
            (
                "PSO models / ihc".into(),
                Some(Method::Ihc),
                Some(&paper_plant.model),
            ),
            (
                "PSO models / wihc".into(),
                Some(Method::Wihc),
                Some(&paper_plant.model),
            ),
            (
                "LS models / ihc-delayed".into(),
                Some(Method::IhcDelayed),
                Some(&exact_plant.model),
            ),
            (
                "LS models / wihc-delayed".into(),
                Some(Method::WihcDelayed),
                Some(&exact_plant.model),
            ),
        ]);
        // Independent runs: in parallel, each on its own stage with the same noise seed.
        let track_job =
            |(label, method, model): TrackingJob<'_>| -> Result<TrackingRun, StudyError> {
                let mut note = None;
                let mut method = method;
                let (command_v, saturated) = match (method, model) {
                    (Some(m), Some(model)) => match drive(model, m, &desired, full_scale, &label) {
                        // A plain delayed loop that could ring on its model is refused with
                        // the reason; its guarded form, which never oscillates, runs instead.
                        Err(StudyError::Compensator {
                            error:
                                CompensatorError::Core(refusal @ CoreError::DelayedLoopUnstable { .. }),
                            ..
                        }) if m.guarded().is_some() => {
                            let guarded = m.guarded().unwrap_or(m);
                            note = Some(format!(
                                "{m} refused: {refusal}; {guarded} (the guarded delayed loop) \
                                 ran instead"
                            ));
                            method = Some(guarded);
                            drive(model, guarded, &desired, full_scale, &label)?
                        }
                        other => other?,
                    },
                    _ => (desired.iter().map(|y| y * gain).collect(), 0),
                };
                let measured = track(&options.stage, tracking_seed, &command_v)?;
                let indices = evaluate(
                    &desired,
                    &measured,
                    evaluation_start,
                    options.mhe_bins,
                    &label,
                )?;
                let model_mismatch_rms_percent = match (method, model) {
                    (Some(m), Some(model)) if m.needs() == Direction::Plant => {
                        let predicted = model
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
                Ok(TrackingRun {
                    label,
                    method,
                    command_v,
                    measured_um: measured,
                    indices,
                    saturated,
                    model_mismatch_rms_percent,
                    note,
                })
            };
        observer.begin("tracking", jobs.len() as u64);
        let job_count = jobs.len() as u64;
        let mut runs: Vec<TrackingRun> = jobs
            .into_par_iter()
            .map(&track_job)
            .collect::<Result<_, _>>()?;
        observer.advance(job_count);
        observer.end();

        // 4. The noise floor: the uncompensated and the exact IHC commands again, with other
        // sensor-noise seeds.
        let extra_seeds: Vec<u64> = (2..2 + NOISE_FLOOR_EXTRA_SEEDS)
            .map(|k| options.seed.wrapping_add(k))
            .collect();
        let exact_ihc_index = runs
            .iter()
            .position(|r| r.label == EXACT_IHC_LABEL)
            .ok_or_else(|| StudyError::Option(format!("no {EXACT_IHC_LABEL} run")))?;
        let mut floor = NoiseFloor {
            seeds: std::iter::once(tracking_seed)
                .chain(extra_seeds.iter().copied())
                .collect(),
            uncompensated: vec![runs[0].indices],
            exact_ihc: vec![runs[exact_ihc_index].indices],
            e_rms_spread_percent: 0.0,
            e_mhe_spread_percent: 0.0,
        };
        observer.begin("noise floor", 2 * extra_seeds.len() as u64);
        for (k, &seed) in extra_seeds.iter().enumerate() {
            for (slot, run) in [(0usize, &runs[0]), (1, &runs[exact_ihc_index])] {
                let label = format!("{} (noise seed {seed})", run.label);
                let measured = track(&options.stage, seed, &run.command_v)?;
                let indices = evaluate(
                    &desired,
                    &measured,
                    evaluation_start,
                    options.mhe_bins,
                    &label,
                )?;
                if slot == 0 {
                    floor.uncompensated.push(indices);
                } else {
                    floor.exact_ihc.push(indices);
                }
                observer.advance(2 * k as u64 + slot as u64 + 1);
            }
        }
        observer.end();
        let spread = |runs: &[TrackingIndices], f: fn(&TrackingIndices) -> f64| {
            let (lo, hi) = runs
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                    (a.min(f(r)), b.max(f(r)))
                });
            hi - lo
        };
        floor.e_rms_spread_percent = spread(&floor.uncompensated, |r| r.e_rms_percent)
            .max(spread(&floor.exact_ihc, |r| r.e_rms_percent));
        floor.e_mhe_spread_percent = spread(&floor.uncompensated, |r| r.e_mhe_percent)
            .max(spread(&floor.exact_ihc, |r| r.e_mhe_percent));

        // 5. Ablations: the exact pipeline (LS plant model, exact IHC) with effects switched off.
        let variants = ablation_variants(&options.stage);
        observer.begin("ablations", variants.len() as u64);
        let mut ablations = vec![AblationRun {
            label: "baseline".into(),
            change: "none (the study's stage)".into(),
            changed: false,
            plant_fit_rms_percent: exact_plant.report.fit.rms_percent,
            ihc: runs[exact_ihc_index].indices,
        }];
        for (k, (label, change, config)) in variants.into_iter().enumerate() {
            let changed = config != options.stage;
            let mut stage = Stage::new(&config, options.seed)?;
            let response = stage.run(&record.command_v[..record.hysteresis_samples]);
            let y: Vec<f64> = response
                .measured_position_um
                .iter()
                .step_by(options.decimation)
                .copied()
                .collect();
            let opts = IdentifyOptions {
                direction: Direction::Plant,
                method: Solver::LeastSquares,
                ..base.clone()
            };
            let plant =
                identify_observed(&v, &y, &opts, &mut |_: &Progress| {}).map_err(|error| {
                    StudyError::Identify {
                        model: format!("{label} plant"),
                        error,
                    }
                })?;
            let run_label = format!("{label} / ihc");
            let (command_v, _) =
                drive(&plant.model, Method::Ihc, &desired, full_scale, &run_label)?;
            let measured = track(&config, tracking_seed, &command_v)?;
            let ihc = evaluate(
                &desired,
                &measured,
                evaluation_start,
                options.mhe_bins,
                &run_label,
            )?;
            ablations.push(AblationRun {
                label: label.into(),
                change,
                changed,
                plant_fit_rms_percent: plant.report.fit.rms_percent,
                ihc,
            });
            observer.advance(k as u64 + 1);
        }
        observer.end();

        observer.begin("full chain", 1);
        let crate::full::FullIdentification {
            plant: full_plant,
            inverse: full_inverse,
            seconds: full_identification_s,
            creep_grid,
        } = full_thread
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))?;
        let full_runs: Vec<TrackingRun> = pipeline_jobs(
            "full",
            [Method::Ihc, Method::Wihc],
            &full_plant.model,
            &full_inverse.model,
        )
        .into_par_iter()
        .map(&track_job)
        .collect::<Result<_, _>>()?;
        runs.splice(full_at..full_at, full_runs);
        observer.end();

        // 6. Beyond the paper: how long and how fast (the duration and speed studies).
        // The duration study runs every approach of the full pipeline (issue 11's targets are
        // for each). The speed study, dozens of runs, repeats only IHC (the exact WIHC solves
        // the same equation, P[v] = y_d, eqs. (5) and (9): its drive is IHC's to rounding).
        let approaches = |ihc_only: bool| {
            let mut list = vec![
                Approach::uncompensated(gain),
                Approach::model(EXACT_IHC_LABEL, &exact_plant.model, Method::Ihc),
                Approach::model(FULL_IHC_LABEL, &full_plant.model, Method::Ihc),
            ];
            if !ihc_only {
                list.push(Approach::model(
                    "full / wihc",
                    &full_plant.model,
                    Method::Wihc,
                ));
                list.push(Approach::model(
                    "full / dihc",
                    &full_inverse.model,
                    Method::Dihc,
                ));
            }
            list
        };
        // The duration, speed and learning studies are independent: together, so that each one's
        // last runs share the processors with the others' (the same numbers as one after another).
        // One step for the three, its label within the command line's 12-character column.
        observer.begin("more studies", 1);
        let (duration, (speed, learning)) = rayon::join(
            || {
                run_duration(
                    &options.stage,
                    tracking_seed,
                    &approaches(false),
                    full_scale,
                    options.mhe_bins,
                )
            },
            || {
                rayon::join(
                    || {
                        run_speed(
                            &options.stage,
                            tracking_seed,
                            &approaches(true),
                            full_scale,
                            options.full.inverse_band_hz,
                        )
                    },
                    || {
                        // 7. Learning from repetition, from the exact and the full pipeline's IHC.
                        crate::learning_study::run_learning(
                            &options.stage,
                            tracking_seed,
                            &exact_plant.model,
                            &full_plant.model,
                            options
                                .slew_aware_learning
                                .then(|| crate::speed::max_drive_step_v(&options.stage)),
                            options
                                .feasible_learning_start
                                .then(|| crate::speed::max_drive_step_v(&options.stage)),
                        )
                    },
                )
            },
        );
        let (duration, speed, learning) = (duration?, speed?, learning?);
        observer.end();

        let record_s = record.command_v.len() as f64 / fs;
        let mut runs = runs.into_iter();
        let uncompensated = runs.next().expect("14 runs");
        let paper_runs: Vec<TrackingRun> = runs.by_ref().take(3).collect();
        let exact_runs: Vec<TrackingRun> = runs.by_ref().take(3).collect();
        let full_runs: Vec<TrackingRun> = runs.by_ref().take(3).collect();
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
                    description:
                        "particle swarm identification (as the paper), delayed IHC and WIHC \
                              (as real-time implementations), DIHC"
                            .into(),
                    plant: paper_plant,
                    inverse: paper_inverse,
                    runs: paper_runs,
                    convergence: [paper_plant_convergence, paper_inverse_convergence],
                },
                Pipeline {
                    name: "exact".into(),
                    description:
                        "constrained least-squares identification (global optimum), exact \
                              per-sample IHC and WIHC, DIHC"
                            .into(),
                    plant: exact_plant,
                    inverse: exact_inverse,
                    runs: exact_runs,
                    convergence: [Vec::new(), Vec::new()],
                },
            ],
            full: FullPipeline {
                plant: full_plant,
                inverse: full_inverse,
                runs: full_runs,
                identification_s: full_identification_s,
                creep_grid,
                record_s,
            },
            duration,
            speed,
            learning,
            cross_runs,
            noise_floor: floor,
            ablations,
            identification_times_s: times,
            elapsed_s: started.elapsed().as_secs_f64(),
        })
    })
}

/// A tracking run to make: its label, its compensator (none: the uncompensated feedforward
/// gain) and the model the compensator inverts.
type TrackingJob<'m> = (String, Option<Method>, Option<&'m ModelFile>);

/// A pipeline's three runs, labelled `"{pipeline} / {method}"`: its two IHC-family
/// `methods` on its `plant` model and DIHC on its `inverse` model.
fn pipeline_jobs<'m>(
    pipeline: &str,
    methods: [Method; 2],
    plant: &'m ModelFile,
    inverse: &'m ModelFile,
) -> [TrackingJob<'m>; 3] {
    let job = |method: Method, model| (format!("{pipeline} / {method}"), Some(method), Some(model));
    [
        job(methods[0], plant),
        job(methods[1], plant),
        job(Method::Dihc, inverse),
    ]
}

/// The label of the exact pipeline's IHC run, which the noise floor and the ablations repeat.
pub(crate) const EXACT_IHC_LABEL: &str = "exact / ihc";

/// The label of the full pipeline's IHC run.
pub(crate) const FULL_IHC_LABEL: &str = "full / ihc";

/// What drives the stage in the duration and speed studies: the linear feedforward gain, or a
/// compensator from a model file.
#[derive(Debug, Clone)]
pub(crate) struct Approach<'a> {
    /// E.g. `exact / ihc`.
    pub label: String,
    /// The model and the method, or `None` for the linear gain.
    pub model: Option<(&'a ModelFile, Method)>,
    /// The linear gain, V/um (uncompensated).
    pub gain: f64,
}

impl<'a> Approach<'a> {
    pub(crate) fn uncompensated(gain: f64) -> Self {
        Approach {
            label: "uncompensated".into(),
            model: None,
            gain,
        }
    }

    pub(crate) fn model(label: &str, model: &'a ModelFile, method: Method) -> Self {
        Approach {
            label: label.into(),
            model: Some((model, method)),
            gain: 0.0,
        }
    }

    /// The command for `desired`, and the samples the compensator clamped.
    pub(crate) fn command(
        &self,
        desired: &[f64],
        full_scale: f64,
    ) -> Result<(Vec<f64>, u64), StudyError> {
        self.command_in_band(desired, full_scale, None)
    }

    /// As [`Approach::command`], a chain's vibration inverse limited to `band_hz`.
    pub(crate) fn command_in_band(
        &self,
        desired: &[f64],
        full_scale: f64,
        band_hz: Option<f64>,
    ) -> Result<(Vec<f64>, u64), StudyError> {
        match self.model {
            Some((model, method)) => {
                drive_in_band(model, method, desired, full_scale, band_hz, &self.label)
            }
            None => Ok((desired.iter().map(|y| y * self.gain).collect(), 0)),
        }
    }
}

/// The most trajectory periods the study tracks.
pub const MAX_STUDY_PERIODS: usize = 20;

/// Stage runs of the trajectory in one study: 14 tracking runs, the noise floor's replays and
/// the ablations.
pub const TRACKING_RUNS: usize = 14 + 2 * NOISE_FLOOR_EXTRA_SEEDS as usize + 4;

/// Extra sensor-noise seeds of the noise floor.
pub const NOISE_FLOOR_EXTRA_SEEDS: u64 = 4;

/// The stages of the ablation runs: `(label, change, stage)`, one effect off at a time, then
/// all of them.
pub fn ablation_variants(stage: &StageConfig) -> Vec<(&'static str, String, StageConfig)> {
    let creep_off = |c: &mut StageConfig| c.creep.percent_per_decade = 0.0;
    let noise_off = |c: &mut StageConfig| c.sensor.noise_rms_nm = 0.0;
    let dynamics_off = |c: &mut StageConfig| {
        // An amplifier that follows within a sample (bandwidth and current limit far beyond
        // anything the trajectory asks) and a rigid stage (no resonance).
        c.amplifier.bandwidth_hz = 1e9;
        c.amplifier.peak_current_ma = 1e9;
        c.mechanics.rigid = true;
    };
    let with = |f: &dyn Fn(&mut StageConfig)| {
        let mut c = stage.clone();
        f(&mut c);
        c
    };
    vec![
        (
            "creep off",
            "creep.percent_per_decade = 0".into(),
            with(&creep_off),
        ),
        (
            "sensor noise off",
            "sensor.noise_rms_nm = 0".into(),
            with(&noise_off),
        ),
        (
            "dynamics off",
            "amplifier.bandwidth_hz = 1e9, amplifier.peak_current_ma = 1e9, mechanics.rigid = \
             true"
                .into(),
            with(&dynamics_off),
        ),
        (
            "creep, noise and dynamics off",
            "all three changes above".into(),
            with(&|c: &mut StageConfig| {
                creep_off(c);
                noise_off(c);
                dynamics_off(c);
            }),
        ),
    ]
}

/// The command `method` sends for `desired` with `model`, and the samples it clamped.
pub(crate) fn drive(
    model: &ModelFile,
    method: Method,
    desired: &[f64],
    full_scale: f64,
    label: &str,
) -> Result<(Vec<f64>, u64), StudyError> {
    drive_in_band(model, method, desired, full_scale, None, label)
}

/// As [`drive`], a chain's vibration inverse limited to `band_hz`
/// (`ScaledCompensator::with_inverse_band`).
pub(crate) fn drive_in_band(
    model: &ModelFile,
    method: Method,
    desired: &[f64],
    full_scale: f64,
    band_hz: Option<f64>,
    label: &str,
) -> Result<(Vec<f64>, u64), StudyError> {
    let error = |error| StudyError::Compensator {
        run: label.to_string(),
        error,
    };
    let mut c = ScaledCompensator::new(model, method, Some((0.0, full_scale)))
        .and_then(|c| c.with_inverse_band(band_hz))
        .map_err(error)?;
    let mut out = vec![0.0; desired.len()];
    c.process(desired, &mut out).map_err(error)?;
    // Unreachable positions, and reachable ones where a delayed loop hit a limit (ringing).
    let d = c.diagnostics();
    Ok((out, d.saturated + d.loop_saturated))
}

/// The measured position of a fresh stage driven by `command_v`, um.
pub(crate) fn track(
    stage: &StageConfig,
    seed: u64,
    command_v: &[f64],
) -> Result<Vec<f64>, StudyError> {
    Ok(Stage::new(stage, seed)?.run(command_v).measured_position_um)
}

/// The indices of a run on the evaluation window.
pub(crate) fn evaluate(
    desired: &[f64],
    measured: &[f64],
    start: usize,
    bins: usize,
    label: &str,
) -> Result<TrackingIndices, StudyError> {
    TrackingIndices::compute(&desired[start..], &measured[start..], bins).map_err(|error| {
        StudyError::Index {
            run: label.to_string(),
            error,
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The labels other studies look runs up by are the ones the pipelines' jobs carry.
    #[test]
    fn the_pipelines_label_their_runs_as_the_other_studies_look_them_up() {
        let model =
            ModelFile::load(std::path::Path::new("../../models/table1-plant.json")).unwrap();
        let [exact, ..] = pipeline_jobs("exact", [Method::Ihc, Method::Wihc], &model, &model);
        let [full, wihc, dihc] = pipeline_jobs("full", [Method::Ihc, Method::Wihc], &model, &model);
        assert_eq!(exact.0, EXACT_IHC_LABEL);
        assert_eq!(full.0, FULL_IHC_LABEL);
        assert_eq!(wihc.0, "full / wihc");
        assert_eq!(
            (dihc.0.as_str(), dihc.1),
            ("full / dihc", Some(Method::Dihc))
        );
    }
}
