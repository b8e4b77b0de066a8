//! `hystcomp crossval`: identify on one record; on another, the forward prediction error and
//! the offline inverse replay error of every compensator.

use std::path::PathBuf;

use hystcomp_identify::{CrossvalOptions, IdentifyError, Record, TestStart, Warmup, crossval};
use hystcomp_io::compensator::UnstableDelay;
use hystcomp_io::data::{self, Column, RowRange};
use hystcomp_io::model_file::Direction;
use serde::Serialize;

use super::identify::{CONSTRAINTS_HELP, ColumnArgs, FitArgs, fit_error, load, print_fit};
use crate::files::{Files, NamesFiles};
use crate::progress::Bar;
use crate::{CliError, Context};

/// Arguments of `hystcomp crossval`.
#[derive(Debug, clap::Args)]
#[command(after_help = CONSTRAINTS_HELP)]
pub struct Args {
    /// Record to identify the models on (text or .mat; see `hystcomp identify --help`).
    #[arg(long, value_name = "FILE")]
    pub train: PathBuf,
    /// Record to validate them on.
    #[arg(long, value_name = "FILE")]
    pub test: PathBuf,
    /// The column options apply to both files unless overridden with --test-....
    #[command(flatten)]
    pub columns: ColumnArgs,
    /// Voltage column of the test file, when it differs from --voltage-column.
    #[arg(long, value_name = "COLUMN")]
    pub test_voltage_column: Option<Column>,
    /// Displacement column of the test file, when it differs from --displacement-column.
    #[arg(long, value_name = "COLUMN")]
    pub test_displacement_column: Option<Column>,
    /// Time column of the test file, when it differs from --time-column.
    #[arg(long, value_name = "COLUMN")]
    pub test_time_column: Option<Column>,
    /// Rows of the training file (instead of --rows), FIRST..LAST.
    #[arg(long, value_name = "FIRST..LAST", value_parser = parse_rows)]
    pub train_rows: Option<RowRange>,
    /// Rows of the test file (instead of --rows), FIRST..LAST.
    #[arg(long, value_name = "FIRST..LAST", value_parser = parse_rows)]
    pub test_rows: Option<RowRange>,
    /// Test samples left out of the errors at the start: a number, or auto (none when the
    /// test record continues the training record; otherwise up to the first sample within
    /// 5 % of the test voltage range from its minimum).
    #[arg(long, default_value = "auto", value_name = "N|auto")]
    pub test_warmup: String,
    /// Where the models and compensators start on the test record: continue (run over the
    /// training record first and carry the operators' memory into the test record, for
    /// consecutive spans of one record), rest (operators at zero memory at the test record's
    /// first sample, as after the drive rose from the bottom of the range), or auto (continue
    /// when --train and --test are the same file with consecutive row ranges, e.g.
    /// --train-rows 1..3000 --test-rows 3001..4000; rest otherwise). Said on stderr.
    #[arg(long, default_value = "auto", value_name = "auto|continue|rest", value_parser = parse_start)]
    pub test_start: StartArg,
    #[command(flatten)]
    pub fit: FitArgs,
    #[command(flatten)]
    pub chain: super::chain_args::ChainArgs,
    /// Fraction of the training record held out of the fit (reported in the fit summaries).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "FRACTION",
        allow_hyphen_values = true
    )]
    pub holdout: f64,
    /// Also write the plant model (for IHC and WIHC) to this file.
    #[arg(long, value_name = "MODEL.json")]
    pub save_plant: Option<PathBuf>,
    /// Also write the inverse model (for DIHC) to this file.
    #[arg(long, value_name = "MODEL.json")]
    pub save_inverse: Option<PathBuf>,
    /// Replay ihc-delayed and wihc-delayed even when their loop gain on the plant model is 1
    /// or more (they can then ring; by default they are reported as not built, with the gain).
    #[arg(long)]
    pub allow_unstable_delay: bool,
    /// Also write the models' predictions on the test record to this CSV: time_s (or sample),
    /// drive, measured displacement, the plant model's predicted displacement and its error,
    /// the inverse model's predicted drive and its error, and `scored` (0 for the test
    /// warm-up, 1 for the samples the errors are computed over).
    #[arg(long, value_name = "OUT.csv")]
    pub predictions: Option<PathBuf>,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .input("--train", &self.train)
            .input("--test", &self.test)
            .maybe_output("--save-plant", self.save_plant.as_ref())
            .maybe_output("--save-inverse", self.save_inverse.as_ref())
            .maybe_output("--predictions", self.predictions.as_ref())
    }
}

/// `--test-start`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartArg {
    /// Continue when the records are consecutive spans of one file, rest otherwise.
    Auto,
    /// The given start.
    Given(TestStart),
}

fn parse_start(text: &str) -> Result<StartArg, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "auto" => Ok(StartArg::Auto),
        "continue" => Ok(StartArg::Given(TestStart::ContinueTraining)),
        "rest" => Ok(StartArg::Given(TestStart::Rest)),
        _ => Err(format!("expected auto, continue or rest, got {text:?}")),
    }
}

impl Args {
    /// Whether the test record is the span of the training file right after the training
    /// span: the same file (same path once resolved), the same columns, and row ranges
    /// `A..B` and `B+1..`.
    fn consecutive_spans(&self) -> bool {
        let same_file = match (self.train.canonicalize(), self.test.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        let c = &self.columns;
        let same_columns = [
            (&self.test_voltage_column, &c.voltage_column),
            (&self.test_displacement_column, &c.displacement_column),
        ]
        .iter()
        .all(|(test, train)| test.as_ref().is_none_or(|t| t == *train))
            && self
                .test_time_column
                .as_ref()
                .is_none_or(|t| c.time_column.as_ref() == Some(t));
        let train_rows = self.train_rows.or(c.rows);
        let test_rows = self.test_rows.or(c.rows);
        let consecutive = matches!(
            (train_rows, test_rows),
            (Some(RowRange { last: Some(last), .. }), Some(test)) if test.first == last + 1
        );
        same_file && same_columns && consecutive
    }

    fn test_start(&self) -> TestStart {
        match self.test_start {
            StartArg::Given(start) => start,
            StartArg::Auto if self.consecutive_spans() => TestStart::ContinueTraining,
            StartArg::Auto => TestStart::Rest,
        }
    }
}

fn parse_rows(text: &str) -> Result<RowRange, String> {
    let text = if !text.contains("..") {
        text.replacen(':', "..", 1)
    } else {
        text.to_owned()
    };
    text.parse()
        .map_err(|e: hystcomp_io::data::DataError| e.to_string())
}

#[derive(Serialize)]
struct Output<'a> {
    train: String,
    test: String,
    report: &'a hystcomp_identify::CrossvalReport,
    plant_model: &'a hystcomp_io::model_file::ModelFile,
    inverse_model: &'a hystcomp_io::model_file::ModelFile,
    /// The chains' reports (each link's contribution), with --model-structure creep or full.
    #[serde(skip_serializing_if = "Option::is_none")]
    plant_chain: Option<&'a hystcomp_identify::ChainReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    inverse_chain: Option<&'a hystcomp_identify::ChainReport>,
}

/// Runs `hystcomp crossval`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    args.fit.check_sizes()?;
    let c = &args.columns;
    let train = load(
        &args.train,
        c,
        &c.voltage_column,
        &c.displacement_column,
        c.time_column.as_ref(),
        args.train_rows.or(c.rows),
    )?;
    let test = load(
        &args.test,
        c,
        args.test_voltage_column
            .as_ref()
            .unwrap_or(&c.voltage_column),
        args.test_displacement_column
            .as_ref()
            .unwrap_or(&c.displacement_column),
        args.test_time_column.as_ref().or(c.time_column.as_ref()),
        args.test_rows.or(c.rows),
    )?;
    let test_warmup = match args.test_warmup.trim() {
        w if w.eq_ignore_ascii_case("auto") => Warmup::Auto,
        w => Warmup::Samples(w.parse().map_err(|_| {
            CliError::input(format!(
                "--test-warmup {w:?} is not usable: give a number of samples or auto"
            ))
        })?),
    };
    let identify = args
        .fit
        .options(c, Direction::Plant, args.holdout, &train)?;
    let test_start = args.test_start();
    let options = CrossvalOptions {
        identify,
        test_warmup,
        test_start,
        unstable_delay: if args.allow_unstable_delay {
            UnstableDelay::Allow
        } else {
            UnstableDelay::Refuse
        },
    };
    let mut bar = if args.fit.iterates() {
        Bar::new("plant model", args.fit.iterations as u64)
    } else {
        Bar::hidden()
    };
    let train_record = Record {
        voltage: &train.voltage,
        displacement: &train.displacement,
    };
    let test_record = Record {
        voltage: &test.voltage,
        displacement: &test.displacement,
    };
    let chain_options = args.chain.options(c, &train)?;
    if let (Some(chain), Some(time)) = (&chain_options, &test.time) {
        // The vibration link is a discrete model at the training record's rate.
        if let Some(step) = data::mean_time_step(time)
            && ((1.0 / step) / chain.sample_rate_hz - 1.0).abs() > 1e-3
        {
            return Err(CliError::input(format!(
                "the test record is sampled at {} Hz, the training record at {} Hz; \
                     creep and vibration are identified at one rate: resample one of them",
                crate::number(1.0 / step),
                crate::number(chain.sample_rate_hz)
            )));
        }
    }
    let result = match &chain_options {
        Some(chain) => {
            hystcomp_identify::crossval_chain(train_record, test_record, &options, chain)
                .map(|c| (c.crossval, Some((c.plant_chain, c.inverse_chain))))
        }
        None => crossval(train_record, test_record, &options, &mut bar).map(|c| (c, None)),
    };
    let (cv, chains) = result.map_err(|e| match e {
        // Only the identification on the training record looks for it.
        IdentifyError::SameSignal => fit_error(e, &args.train, &train),
        e => CliError::from(e).context(format!(
            "{} (train) / {} (test)",
            args.train.display(),
            args.test.display()
        )),
    })?;
    bar.finish();
    for (path, model) in [
        (&args.save_plant, &cv.plant),
        (&args.save_inverse, &cv.inverse),
    ] {
        if let Some(path) = path {
            model
                .save(path)
                .map_err(|e| CliError::output(e.to_string()))?;
        }
    }

    let report = &cv.report;
    errln!(
        "hystcomp: crossval: the test record starts {}{}",
        report.test.initial_state,
        match (args.test_start, test_start) {
            (StartArg::Auto, TestStart::ContinueTraining) =>
                " (--train and --test are consecutive row ranges of one file; --test-start rest to start from rest)",
            (StartArg::Auto, TestStart::Rest) =>
                " (--test-start continue if the test record follows the training record without a gap)",
            _ => "",
        }
    );
    if let Some(path) = &args.predictions {
        let preceding = (test_start == TestStart::ContinueTraining).then_some(train_record);
        write_predictions(path, &cv, preceding, &test, report.test.warmup, c)?;
    }
    if ctx.json {
        let output = Output {
            train: args.train.display().to_string(),
            test: args.test.display().to_string(),
            report,
            plant_model: &cv.plant,
            inverse_model: &cv.inverse,
            plant_chain: chains.as_ref().map(|c| &c.0),
            inverse_chain: chains.as_ref().map(|c| &c.1),
        };
        crate::print_json(&output)?;
        return Ok(());
    }
    outln!("identified on {}:", args.train.display())?;
    outln!("plant model (voltage -> displacement, for IHC and WIHC):")?;
    print_fit(&report.plant)?;
    if let Some((plant, _)) = &chains {
        super::chain_args::print_chain(plant, &c.displacement_unit)?;
    }
    outln!("inverse model (displacement -> voltage, for DIHC):")?;
    print_fit(&report.inverse)?;
    if let Some((_, inverse)) = &chains {
        super::chain_args::print_chain(inverse, &c.voltage_unit)?;
    }
    let t = &report.test;
    let f = &t.forward;
    outln!(
        "validated on {} ({} samples, the first {} left out as warm-up; {}):",
        args.test.display(),
        t.samples,
        t.warmup,
        match t.start {
            TestStart::Rest => "from rest".to_owned(),
            TestStart::ContinueTraining => format!(
                "memory carried from the {} training samples",
                t.preceding_samples
            ),
        }
    )?;
    outln!(
        "  forward prediction of the displacement: RMS {:.3} %, max {:.3} % of its range \
         ({:.4} {unit}); mean error {:.4} {unit}, RMS without it {:.3} %",
        f.rms_percent,
        f.max_percent,
        f.range,
        f.mean,
        f.std_percent,
        unit = c.displacement_unit
    )?;
    if let Some(g) = &t.delayed_loop_gains {
        outln!(
            "  delayed loop gains of the plant model over the limits: ihc-delayed {:.4}, \
             wihc-delayed {:.4} (below 1: they settle after a jump; at or above 1 they can \
             ring{})",
            g.ihc,
            g.wihc,
            if args.allow_unstable_delay {
                ", replayed anyway (--allow-unstable-delay)"
            } else {
                " and are not replayed without --allow-unstable-delay"
            }
        )?;
    }
    if t.voltage_outside_model_range > 0 || t.displacement_outside_model_range > 0 {
        outln!(
            "  outside the training ranges: {} voltage and {} displacement samples",
            t.voltage_outside_model_range,
            t.displacement_outside_model_range
        )?;
    }
    outln!(
        "  offline inverse replay (measured displacement in, voltage out, vs the voltage \
         applied; % of the test voltage range {} {}, limits {} .. {} {}):",
        crate::number(t.ranges.voltage),
        c.voltage_unit,
        crate::number(t.voltage_limits[0]),
        crate::number(t.voltage_limits[1]),
        c.voltage_unit
    )?;
    outln!(
        "    {:14} {:>9} {:>9} {:>12} {:>10} {:>10}",
        "compensator",
        "RMS %",
        "max %",
        "mean",
        "saturated",
        "loop-sat."
    )?;
    for r in &t.replay {
        match (&r.error, &r.failure) {
            (Some(e), _) => outln!(
                "    {:14} {:>9.3} {:>9.3} {:>12.5} {:>10} {:>10}",
                r.compensator,
                e.rms_percent,
                e.max_percent,
                e.mean,
                r.saturated,
                r.loop_saturated
            )?,
            (None, failure) => outln!(
                "    {:14} not built: {}",
                r.compensator,
                failure.as_deref().unwrap_or("unknown reason")
            )?,
        }
    }
    if t.replay.iter().any(|r| r.loop_saturated > 0) {
        outln!(
            "  loop-sat.: samples clamped to a limit although the displacement was reachable: \
             the one-sample-delayed loop lagged or rang after a jump (the exact ihc and wihc \
             do not)"
        )?;
    }
    Ok(())
}

/// Writes `--predictions`: both models run over the test record as the validation runs them
/// (through `preceding` first when the memory is carried; a creep link settled at the first
/// sample run).
fn write_predictions(
    path: &std::path::Path,
    cv: &hystcomp_identify::CrossValidation,
    preceding: Option<Record<'_>>,
    test: &super::identify::Loaded,
    warmup: usize,
    c: &ColumnArgs,
) -> Result<(), CliError> {
    let (displacement, drive) = hystcomp_identify::predict_test(
        &cv.plant,
        &cv.inverse,
        preceding,
        Record {
            voltage: &test.voltage,
            displacement: &test.displacement,
        },
    )
    .map_err(|e| CliError::input(e.to_string()))?;
    let error: Vec<f64> = displacement
        .iter()
        .zip(&test.displacement)
        .map(|(p, m)| p - m)
        .collect();
    let drive_error: Vec<f64> = drive
        .iter()
        .zip(&test.voltage)
        .map(|(p, m)| p - m)
        .collect();
    let scored: Vec<f64> = (0..test.voltage.len())
        .map(|k| if k < warmup { 0.0 } else { 1.0 })
        .collect();
    let index: Vec<f64>;
    let (time_name, time) = match &test.time {
        Some(t) => ("time_s", t),
        None => {
            index = (1..=test.voltage.len()).map(|k| k as f64).collect();
            ("sample", &index)
        }
    };
    let (v, d) = (
        c.voltage_unit.to_lowercase(),
        c.displacement_unit.to_lowercase(),
    );
    let names = [
        time_name.to_owned(),
        format!("drive_{v}"),
        format!("measured_{d}"),
        format!("predicted_{d}"),
        format!("error_{d}"),
        format!("predicted_drive_{v}"),
        format!("drive_error_{v}"),
        "scored".to_owned(),
    ];
    let header: Vec<&str> = names.iter().map(String::as_str).collect();
    hystcomp_io::data::write_csv(
        path,
        &header,
        &[
            time,
            &test.voltage,
            &test.displacement,
            &displacement,
            &error,
            &drive,
            &drive_error,
            &scored,
        ],
    )
    .map_err(|e| CliError::output(e.to_string()))
}
