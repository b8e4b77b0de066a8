//! `hystcomp learn`: iterative learning feedforward for a repeated motion, one trial at a time
//! (hardware: run the drive, record, update) or on the simulated stage (`--simulate`).
//!
//! The state between trials is the drive file itself (the model run forward over it recovers
//! the reference it followed; `hystcomp_learn::Learner::resume`) plus a small state file
//! written atomically beside it, before the drive (`DRIVE.learn.json`: every trial's indices,
//! the best trial, the learning law and a checksum of the drive's values, which must match
//! the drive read), read back from beside `--drive` when present. The drive file's
//! `best_drive_v` column holds the last good drive, which the divergence guard falls back to.

use std::path::{Path, PathBuf};

use hystcomp_experiments::indices::{DEFAULT_MHE_BINS, TrackingIndices};
use hystcomp_experiments::learning::{self, SimulatedTrial};
use hystcomp_identify::{IdentifyOptions, identify};
use hystcomp_io::data::{self, Column, Delimiter, Header, ReadOptions};
use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::{
    DEFAULT_DIVERGENCE_FACTOR, DEFAULT_FILTER_ORDER, DEFAULT_GAIN, Inverse, Learner, LearningLaw,
    LearningOptions, Status, Update,
};
use hystcomp_stage::StageConfig;
use serde::{Deserialize, Serialize};

use crate::commands::compensate::parse_limits;
use crate::error::EXIT_DIVERGED;
use crate::files::{Files, NamesFiles};
use crate::{CliError, Context, number};

/// Arguments of `hystcomp learn`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Desired trajectory (CSV or other delimited text, or .mat): a time column (s) and the
    /// desired position (the model's displacement unit). Periodic (the default): one period.
    #[arg(long, value_name = "FILE")]
    desired: PathBuf,
    /// The drive of the trial just run (e.g. `compensate`'s output or a previous `learn`'s),
    /// aligned with the desired trajectory. Not with --simulate.
    #[arg(long, value_name = "FILE", required_unless_present = "simulate")]
    drive: Option<PathBuf>,
    /// The response measured in that trial (same samples). Not with --simulate.
    #[arg(long, value_name = "FILE", required_unless_present = "simulate")]
    measured: Option<PathBuf>,
    /// Plant model (JSON, voltage -> displacement). Without it: identified by least squares
    /// from the trial's own drive and measured records (--simulate: from the study's
    /// identification run on the stage).
    #[arg(long, value_name = "FILE")]
    model: Option<PathBuf>,
    /// The drive for the next trial (CSV: time_s, drive_v, reference_um, best_drive_v), with
    /// its state file beside it (same name, extension .learn.json).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Run the loop on the simulated stage instead: trial 0 is the model's IHC, each trial
    /// starts from rest.
    #[arg(long, conflicts_with_all = ["drive", "measured"])]
    simulate: bool,
    /// Stage file (TOML) for --simulate; the built-in stage when absent.
    #[arg(long, value_name = "FILE", requires = "simulate")]
    stage: Option<PathBuf>,
    /// Trials --simulate runs (1-1000).
    #[arg(long, default_value_t = 10, requires = "simulate")]
    trials: usize,
    /// Periods of the drive played per simulated trial from rest, the last one measured
    /// (1-1000; periodic trajectories only).
    #[arg(long, default_value_t = 2, requires = "simulate")]
    periods: usize,
    /// Seed of the first simulated trial's sensor noise (trial k uses seed + k) [default: the
    /// stage file's seed + 1].
    #[arg(long, requires = "simulate")]
    seed: Option<u64>,
    /// The learning gain gamma (above 0, at most 10; above 2 diverges even on a perfect model).
    #[arg(long, default_value_t = DEFAULT_GAIN)]
    gain: f64,
    /// Cut-off of the zero-phase robustness filter Q, Hz [default: a hundredth of the sample
    /// rate, a tenth with a model that has a vibration link].
    #[arg(long, value_name = "HZ")]
    bandwidth: Option<f64>,
    /// Order of Q (1-8).
    #[arg(long, default_value_t = DEFAULT_FILTER_ORDER)]
    filter_order: usize,
    /// Phase lead of the learning, samples (0-1000).
    #[arg(long, default_value_t = 0)]
    lead: usize,
    /// A trial whose e_rms exceeds this factor times the best trial's stops the learning.
    #[arg(long, default_value_t = DEFAULT_DIVERGENCE_FACTOR)]
    divergence_factor: f64,
    /// The trajectory is a finite motion repeated from rest, not one period of a periodic one.
    #[arg(long)]
    finite: bool,
    /// The exact inverse the learned reference is fed to: ihc or wihc.
    #[arg(long, default_value = "ihc", value_parser = parse_inverse)]
    inverse: Inverse,
    /// Drive limits MIN:MAX in the model's voltage unit (default: the range the model was
    /// identified on).
    #[arg(long, value_name = "MIN:MAX", value_parser = parse_limits, allow_hyphen_values = true)]
    limits: Option<(f64, f64)>,
    /// Bins of the y_d range for e_mhe (a perfect tracker reads one bin's width, 100 % / bins).
    #[arg(long, default_value_t = DEFAULT_MHE_BINS)]
    bins: usize,
    /// Time column of every record, by name or 1-based index.
    #[arg(long, default_value = "1", value_name = "COLUMN")]
    time_column: Column,
    /// Desired position column of the desired trajectory.
    #[arg(long, default_value = "2", value_name = "COLUMN")]
    desired_column: Column,
    /// Drive voltage column of the drive record.
    #[arg(long, default_value = "2", value_name = "COLUMN")]
    voltage_column: Column,
    /// Measured position column of the measured record [default: `measured_um` if present
    /// (`hystcomp simulate`'s), else 2].
    #[arg(long, value_name = "COLUMN")]
    measured_column: Option<Column>,
    /// Field delimiter of the records: auto, comma, tab, semicolon or whitespace.
    #[arg(long, default_value = "auto")]
    delimiter: Delimiter,
    /// Whether the records start with column names: auto, present or absent.
    #[arg(long, default_value = "auto")]
    header: Header,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .input("--desired", &self.desired)
            .maybe_input("--drive", self.drive.as_ref())
            .maybe_input("--measured", self.measured.as_ref())
            .maybe_input("--model", self.model.as_ref())
            .stage("--stage", self.stage.as_ref())
            .output("--output", &self.output)
    }
}

fn parse_inverse(s: &str) -> Result<Inverse, String> {
    match s.trim().to_ascii_lowercase().as_str() {
        "ihc" => Ok(Inverse::Ihc),
        "wihc" => Ok(Inverse::Wihc),
        _ => Err(format!("{s:?}: choose ihc or wihc (the exact inverses)")),
    }
}

/// The state file beside a drive file: `drive_3.csv` -> `drive_3.learn.json`.
pub fn state_path(drive: &Path) -> PathBuf {
    drive.with_extension("learn.json")
}

/// What the state file holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct State {
    /// Always `hystcomp-learn-state`.
    format: String,
    /// 1.
    version: u32,
    /// The trial the drive beside it is for.
    next_trial: usize,
    /// Every measured trial's indices, in order.
    history: Vec<TrackingIndices>,
    /// The best measured trial (its drive is the drive file's `best_drive_v`).
    best_trial: Option<usize>,
    /// Set when the divergence guard stopped the learning.
    stopped: Option<Status>,
    /// The law in force.
    law: LearningLaw,
    /// [`drive_checksum`] of the drive this state belongs to (absent in files written before
    /// it was kept: those are taken on trust).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    drive_crc32: Option<u32>,
}

/// The CRC-32 of a drive's values (each `f64` as its little-endian bytes, in order): the drive
/// a state file belongs to. The drive file holds each value as the shortest text that parses
/// back to it, so the values read back give the same checksum.
fn drive_checksum(drive: &[f64]) -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    for v in drive {
        hasher.update(&v.to_le_bytes());
    }
    hasher.finalize()
}

/// Writes a trial's state file, then its drive file: both written to temporary files first
/// (`hystcomp_io::atomic::write_atomic_pair`), so that a refused drive or a full disk leaves
/// the old pair as it was, then renamed, the state first, so that an interruption between the
/// two renames never leaves a new drive beside a missing or stale state (the next trial would
/// take it for a first drive, or for another trial); a new state beside an old drive is
/// refused when read, by the drive's checksum. The state is the learner's
/// (history, best trial, law, the checksum of its drive) with the trial that comes next and
/// the divergence guard's stop, if it stopped; the drive file's best drive is the best
/// trial's, or the drive itself before there is one.
fn write_trial(
    output: &Path,
    learner: &hystcomp_learn::Learner,
    next_trial: usize,
    stopped: Option<Status>,
    time: &[f64],
    model: &ModelFile,
) -> Result<(), CliError> {
    let state = State {
        format: STATE_FORMAT.into(),
        version: 1,
        next_trial,
        history: learner.history().to_vec(),
        best_trial: learner.best().map(|(t, _)| t),
        stopped,
        law: learner.law().clone(),
        drive_crc32: Some(drive_checksum(learner.drive())),
    };
    let best = learner.best().map_or(learner.drive(), |(_, d)| d);
    let drive = encode_drive(
        output,
        time,
        learner.drive(),
        learner.reference(),
        best,
        model,
    )?;
    // Both files written before either replaces its old one: a full disk leaves the pair as
    // it was (only a crash between the two renames can part them, which the checksum sees).
    let state_text =
        serde_json::to_string_pretty(&state).map_err(|e| CliError::output(e.to_string()))?;
    hystcomp_io::atomic::write_atomic_pair(
        (&state_path(output), state_text.as_bytes()),
        (output, &drive),
    )
    .map_err(|e| CliError::output(e.to_string()))
}

const STATE_FORMAT: &str = "hystcomp-learn-state";
/// The largest state file read (1000 trials of indices take about 150 kB).
const STATE_MAX_BYTES: u64 = 1 << 20;

/// The report of one update.
#[derive(Debug, Serialize)]
struct TrialReport {
    desired: String,
    output: String,
    state: String,
    samples: usize,
    sample_rate_hz: f64,
    model: String,
    #[serde(flatten)]
    update: Update,
    law: LearningLaw,
}

/// The report of a simulated run.
#[derive(Debug, Serialize)]
struct SimulationReport {
    desired: String,
    output: String,
    samples: usize,
    periods_per_trial: usize,
    model: String,
    law: LearningLaw,
    trials: Vec<SimulatedTrial>,
    stopped: bool,
}

fn read_options(args: &Args) -> ReadOptions {
    ReadOptions {
        delimiter: args.delimiter,
        header: args.header,
        rows: None,
    }
}

/// The desired trajectory and its sample rate.
fn read_desired(args: &Args) -> Result<(Vec<f64>, Vec<f64>, f64), CliError> {
    let columns = data::read_columns(
        &args.desired,
        &[args.time_column.clone(), args.desired_column.clone()],
        &read_options(args),
    )?;
    let (time, desired) = (columns.values[0].clone(), columns.values[1].clone());
    data::check_time_increasing(&time)
        .map_err(|e| CliError::from(e).context(args.desired.display()))?;
    let Some(step) = data::mean_time_step(&time) else {
        return Err(CliError::input(format!(
            "{}: a trial needs at least 2 samples",
            args.desired.display()
        )));
    };
    if let Some(k) = time
        .windows(2)
        .position(|w| ((w[1] - w[0]) - step).abs() > 1e-3 * step)
    {
        return Err(CliError::input(format!(
            "{}, row {}: the time step {} s differs from the mean step {step} s; learning needs \
             a uniformly sampled trajectory",
            args.desired.display(),
            columns.file_row(k + 2),
            time[k + 1] - time[k]
        )));
    }
    Ok((time, desired, 1.0 / step))
}

/// One column and the time column of a record, checked against the desired time axis.
fn read_aligned(
    args: &Args,
    path: &Path,
    column: Column,
    option: &str,
    time: &[f64],
) -> Result<Vec<f64>, CliError> {
    let columns = data::read_columns(
        path,
        &[args.time_column.clone(), column],
        &read_options(args),
    )?;
    let (t, values) = (&columns.values[0], &columns.values[1]);
    if t.len() != time.len() {
        return Err(CliError::input(format!(
            "{} ({option}) has {} samples but the desired trajectory has {}; a trial's records \
             are aligned sample by sample (record exactly the period or motion the desired \
             trajectory describes)",
            path.display(),
            t.len(),
            time.len()
        )));
    }
    // The desired axis has at least two samples (`read_desired`); without, times must match.
    let step = data::mean_time_step(time).unwrap_or(0.0);
    if let Some(k) = t
        .iter()
        .zip(time)
        .position(|(a, b)| (a - b).abs() > 0.01 * step)
    {
        return Err(CliError::input(format!(
            "{} ({option}), row {}: time {} s where the desired trajectory has {} s; the records \
             must share one time axis",
            path.display(),
            columns.file_row(k + 1),
            t[k],
            time[k]
        )));
    }
    Ok(values.clone())
}

fn options(args: &Args, sample_rate_hz: f64) -> Result<LearningOptions, CliError> {
    let options = LearningOptions {
        sample_rate_hz,
        periodic: !args.finite,
        gain: args.gain,
        bandwidth_hz: args.bandwidth,
        filter_order: args.filter_order,
        lead_samples: args.lead,
        divergence_factor: args.divergence_factor,
        inverse: args.inverse,
        limits: args.limits,
        mhe_bins: args.bins,
        max_drive_step: None,
        anti_windup: None,
    };
    options.validate().map_err(learn_error)?;
    Ok(options)
}

/// A learning error, prefixed with the command-line flag of the option it names (the library
/// names options in words: `e_mhe bins = 100000 cannot be used: ...`).
fn learn_error(e: hystcomp_learn::LearnError) -> CliError {
    let text = e.to_string();
    let flag = match text.split(" = ").next().unwrap_or("") {
        "gain" => "--gain",
        "bandwidth" => "--bandwidth",
        "filter order" => "--filter-order",
        "lead" => "--lead",
        "divergence factor" => "--divergence-factor",
        "drive limits" => "--limits",
        "e_mhe bins" => "--bins",
        _ => "",
    };
    CliError::input(if flag.is_empty() {
        text
    } else {
        format!("{flag}: {text}")
    })
}

fn percent_line(label: &str, i: &TrackingIndices, bins: usize) -> String {
    format!(
        "{label}: e_rms = {} %, e_m = {} %, e_mhe = {} % ({bins} bins)",
        number(i.e_rms_percent),
        number(i.e_m_percent),
        number(i.e_mhe_percent)
    )
}

fn law_line(law: &LearningLaw) -> String {
    format!(
        "learning law: gain {}, lead {} samples, Q cut-off {} Hz (order {}), {}; {}",
        number(law.gain),
        law.lead_samples,
        number(law.bandwidth_hz),
        law.filter_order,
        if law.periodic { "periodic" } else { "finite" },
        match law.stationary_noise_ratio {
            Some(r) => format!(
                "the learned reference keeps {} of the sensor noise's variance",
                number(r)
            ),
            None => "gain x Q reaches 2: this law does not contract, expect the guard".into(),
        }
    )
}

/// The drive file's text: time, drive, reference and best drive, the columns named in the
/// model's units.
fn encode_drive(
    path: &Path,
    time: &[f64],
    drive: &[f64],
    reference: &[f64],
    best: &[f64],
    model: &ModelFile,
) -> Result<Vec<u8>, CliError> {
    let drive_name = format!("drive_{}", model.input.unit.to_lowercase());
    let reference_name = format!("reference_{}", model.output.unit);
    let best_name = format!("best_drive_{}", model.input.unit.to_lowercase());
    data::encode_csv(
        path,
        &["time_s", &drive_name, &reference_name, &best_name],
        &[time, drive, reference, best],
    )
    .map_err(|e| CliError::output(e.to_string()))
}

/// Runs `hystcomp learn`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let state_out = state_path(&args.output);
    let state_in = args.drive.as_deref().map(state_path);
    // The state files are inputs and outputs too: the same rule applies to them, beside the
    // command's own files.
    args.files()
        .maybe_input(
            "--drive's state file",
            state_in.as_ref().filter(|p| p.exists()),
        )
        .output("--output's state file", &state_out)
        .check()?;
    if args.simulate {
        simulate(args, ctx)
    } else {
        trial(args, ctx, state_in.as_deref(), &state_out)
    }
}

fn trial(
    args: &Args,
    ctx: Context,
    state_in: Option<&Path>,
    state_out: &Path,
) -> Result<(), CliError> {
    let (time, desired, fs) = read_desired(args)?;
    let drive_path = args.drive.as_deref().expect("clap requires --drive");
    let measured_path = args.measured.as_deref().expect("clap requires --measured");
    let drive = read_aligned(
        args,
        drive_path,
        args.voltage_column.clone(),
        "--drive",
        &time,
    )?;
    let measured_column = match &args.measured_column {
        Some(c) => c.clone(),
        None => {
            let named = Column::Name("measured_um".into());
            match data::read_columns(
                measured_path,
                std::slice::from_ref(&named),
                &read_options(args),
            ) {
                Ok(_) => named,
                Err(_) => Column::Index(2),
            }
        }
    };
    let measured = read_aligned(args, measured_path, measured_column, "--measured", &time)?;
    let (model, model_name) = match &args.model {
        Some(path) => (ModelFile::load(path)?, path.display().to_string()),
        None => {
            let id = identify(&drive, &measured, &IdentifyOptions::default()).map_err(|e| {
                CliError::input(format!(
                    "no --model given, and identifying one from the trial's drive and measured \
                     records failed: {e}; give a plant model with --model"
                ))
            })?;
            (
                id.model,
                "identified by least squares from the trial's drive and measured records".into(),
            )
        }
    };
    super::chain_args::check_model_rate(&model, fs, "the desired trajectory")
        .map_err(|e| e.context(model_name.as_str()))?;
    let options = options(args, fs)?;
    let mut learner = Learner::resume(&model, &desired, &drive, options).map_err(learn_error)?;
    // The previous trials, when the drive came from `learn`.
    let previous: Option<State> = match state_in.filter(|p| p.exists()) {
        Some(path) => {
            let bytes = match hystcomp_io::bounded::read_at_most(path, STATE_MAX_BYTES)
                .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?
            {
                hystcomp_io::bounded::Bounded::Whole(bytes) => bytes,
                hystcomp_io::bounded::Bounded::TooLarge => {
                    return Err(CliError::input(format!(
                        "{}: a learn state file holds at most {STATE_MAX_BYTES} bytes",
                        path.display()
                    )));
                }
            };
            let state: State = serde_json::from_slice(&bytes).map_err(|e| {
                CliError::input(format!("{}: not a learn state file: {e}", path.display()))
            })?;
            if state.format != STATE_FORMAT || state.version != 1 {
                return Err(CliError::input(format!(
                    "{}: not a learn state file (format {:?}, version {})",
                    path.display(),
                    state.format,
                    state.version
                )));
            }
            if let Some(expected) = state.drive_crc32
                && expected != drive_checksum(&drive)
            {
                return Err(CliError::input(format!(
                    "{}: this state file belongs to another drive than the one read from {} \
                     (its values' checksum differs: the drive file was changed or re-saved \
                     with fewer digits, another column was read, or the learn that wrote \
                     them was cut off between writing the state and the drive). Re-run the \
                     learn that wrote them (its inputs are unchanged), or give the drive the \
                     state was written with, or remove the state file to start the learning \
                     history afresh from this drive",
                    path.display(),
                    drive_path.display()
                )));
            }
            Some(state)
        }
        None => None,
    };
    if let Some(state) = &previous {
        if let Some(Status::Diverged { best_trial, .. }) = &state.stopped {
            return Err(CliError::input(format!(
                "the divergence guard stopped this learning at trial {}; {} holds the last good \
                 drive (trial {best_trial}). To learn again from it with a lower --gain or \
                 --bandwidth, remove {} (its state file)",
                state.history.len().saturating_sub(1),
                drive_path.display(),
                state_in
                    .map(|p| p.display().to_string())
                    .unwrap_or_default()
            )));
        }
        // The best earlier trial's drive is the drive file's best_drive_UNIT column (the
        // model's voltage unit, as `encode_drive` names it).
        let best_name = format!("best_drive_{}", model.input.unit.to_lowercase());
        let best_drive = match state.best_trial {
            Some(_) => Some(read_aligned(
                args,
                drive_path,
                Column::Name(best_name.clone()),
                &format!("--drive's {best_name}"),
                &time,
            )?),
            None => None,
        };
        learner
            .restore_history(&state.history, state.best_trial.zip(best_drive.as_deref()))
            .map_err(learn_error)?;
    }
    let update = learner.update(&measured).map_err(learn_error)?;
    let stopped = matches!(update.status, Status::Diverged { .. });
    write_trial(
        &args.output,
        &learner,
        update.trial + 1,
        stopped.then(|| update.status.clone()),
        &time,
        &model,
    )?;
    let report = TrialReport {
        desired: args.desired.display().to_string(),
        output: args.output.display().to_string(),
        state: state_out.display().to_string(),
        samples: desired.len(),
        sample_rate_hz: fs,
        model: model_name,
        update: update.clone(),
        law: learner.law().clone(),
    };
    if ctx.json {
        crate::print_json(&report)?;
    } else {
        outln!(
            "{}",
            percent_line(
                &format!("trial {}", update.trial),
                &update.indices,
                args.bins
            )
        )?;
        if let Some(p) = &update.predicted {
            outln!(
                "{}",
                percent_line(
                    &format!("predicted trial {}", update.trial + 1),
                    p,
                    args.bins
                )
            )?;
        }
        outln!("{}", law_line(learner.law()))?;
        outln!(
            "drive for trial {} -> {} (state {}){}",
            update.trial + 1,
            report.output,
            report.state,
            if update.clamped_samples > 0 {
                format!(
                    "; {} reference samples clamped into the model's reach",
                    update.clamped_samples
                )
            } else {
                String::new()
            }
        )?;
    }
    diverged(&update.status, &args.output)
}

fn diverged(status: &Status, output: &Path) -> Result<(), CliError> {
    match status {
        Status::Learning => Ok(()),
        Status::Diverged {
            e_rms_percent,
            best_trial,
            best_e_rms_percent,
            factor,
        } => Err(CliError::with_code(
            format!(
                "the divergence guard stopped the learning: this trial's e_rms ({} %) is more \
                 than {} times the best trial's (trial {best_trial}, {} %). {} holds that last \
                 good drive; lower --gain or --bandwidth to learn further",
                number(*e_rms_percent),
                number(*factor),
                number(*best_e_rms_percent),
                output.display()
            ),
            EXIT_DIVERGED,
        )),
    }
}

fn simulate(args: &Args, ctx: Context) -> Result<(), CliError> {
    crate::bounds::count("--trials", args.trials, 1..=learning::MAX_TRIALS, "")?;
    crate::bounds::count(
        "--periods",
        args.periods,
        1..=learning::MAX_PERIODS_PER_TRIAL,
        "",
    )?;
    let stage = match &args.stage {
        Some(path) => {
            StageConfig::from_toml_file(path).map_err(|e| CliError::input(e.to_string()))?
        }
        None => StageConfig::default(),
    };
    let (time, desired, fs) = read_desired(args)?;
    if (fs - stage.sample_rate_hz).abs() > 1e-6 * stage.sample_rate_hz {
        return Err(CliError::input(format!(
            "{}: sampled at {} Hz, but the stage runs at {} Hz; give the desired trajectory at \
             the stage's rate (hystcomp signal --sample-rate)",
            args.desired.display(),
            number(fs),
            number(stage.sample_rate_hz)
        )));
    }
    learning::check_trials(args.trials, args.periods, desired.len())
        .map_err(|e| CliError::input(e.to_string()))?;
    let (model, model_name) = match &args.model {
        Some(path) => (ModelFile::load(path)?, path.display().to_string()),
        None => (
            learning::exact_plant_model(&stage, stage.seed, 10)
                .map_err(|e| CliError::input(e.to_string()))?,
            "the study's exact plant model (least squares on its identification run)".into(),
        ),
    };
    super::chain_args::check_model_rate(&model, fs, "the desired trajectory")
        .map_err(|e| e.context(model_name.as_str()))?;
    let options = options(args, fs)?;
    let mut learner = Learner::new(&model, &desired, options).map_err(learn_error)?;
    let seed = args.seed.unwrap_or(stage.seed.wrapping_add(1));
    let bins = args.bins;
    let json = ctx.json;
    let mut printed: Result<(), CliError> = Ok(());
    if !json {
        printed = outln!("{}", law_line(learner.law()));
    }
    let trials = learning::run_trials(
        &stage,
        seed,
        &mut learner,
        args.trials,
        args.periods,
        &mut |t| {
            if !json && printed.is_ok() {
                printed = outln!(
                    "{} (noise floor {} %, {} slew-limited samples)",
                    percent_line(
                        &format!("trial {}", t.update.trial),
                        &t.update.indices,
                        bins
                    ),
                    number(t.noise_floor_percent),
                    t.slew_limited
                );
            }
        },
    )
    .map_err(|e| CliError::input(e.to_string()))?;
    printed?;
    let last = trials.last().expect("at least one trial");
    let stopped = learner.is_stopped();
    write_trial(
        &args.output,
        &learner,
        last.update.trial + 1,
        stopped.then(|| last.update.status.clone()),
        &time,
        &model,
    )?;
    if json {
        crate::print_json(&SimulationReport {
            desired: args.desired.display().to_string(),
            output: args.output.display().to_string(),
            samples: desired.len(),
            periods_per_trial: if args.finite { 1 } else { args.periods },
            model: model_name,
            law: learner.law().clone(),
            trials: trials.clone(),
            stopped,
        })?;
    } else {
        outln!(
            "drive for trial {} -> {}",
            last.update.trial + 1,
            args.output.display()
        )?;
    }
    diverged(&last.update.status, &args.output)
}
