//! `hystcomp compensate`: a desired trajectory through a compensator, CSV in, CSV out.

use std::path::PathBuf;

use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::data::{self, Column, Delimiter, Header, ReadOptions};
use hystcomp_io::model_file::ModelFile;
use serde::Serialize;

use crate::error::EXIT_SATURATED;
use crate::{CliError, Context};

/// Arguments of `hystcomp compensate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (JSON): a plant model for ihc / wihc, an inverse model for dihc.
    #[arg(long, value_name = "FILE")]
    model: PathBuf,
    /// Compensator: ihc, ihc-delayed, wihc, wihc-delayed or dihc.
    #[arg(long, value_name = "METHOD", value_parser = parse_method)]
    method: Method,
    /// Desired trajectory: a CSV (or tab / whitespace separated, or .mat) file with a time
    /// column (s) and a desired position column (in the model's displacement unit).
    #[arg(long, value_name = "FILE")]
    trajectory: PathBuf,
    /// Where to write the drive signal (CSV: time, drive voltage, desired position; the drive
    /// is the second column, which `hystcomp simulate` reads by default).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Time column of the trajectory, by name or 1-based index.
    #[arg(long, default_value = "1", value_name = "COLUMN")]
    time_column: Column,
    /// Desired position column of the trajectory, by name or 1-based index.
    #[arg(long, default_value = "2", value_name = "COLUMN")]
    desired_column: Column,
    /// Field delimiter of the trajectory file: auto, comma, tab, semicolon or whitespace.
    #[arg(long, default_value = "auto")]
    delimiter: Delimiter,
    /// Whether the trajectory file starts with column names: auto, present or absent.
    #[arg(long, default_value = "auto")]
    header: Header,
    /// Drive limits MIN:MAX in the model's voltage unit (default: the voltage range the model
    /// was identified on). The compensator never leaves them.
    #[arg(long, value_name = "MIN:MAX", value_parser = parse_limits, allow_hyphen_values = true)]
    limits: Option<(f64, f64)>,
    /// Exit with status 0 even when the trajectory leaves the reachable range (the drive is
    /// clamped to the limits and the samples are counted either way).
    #[arg(long)]
    allow_saturation: bool,
}

fn parse_method(s: &str) -> Result<Method, String> {
    s.parse()
        .map_err(|e: hystcomp_io::compensator::CompensatorError| e.to_string())
}

/// Parses `MIN:MAX`.
pub fn parse_limits(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = s
        .split_once(':')
        .ok_or_else(|| format!("expected MIN:MAX, e.g. 0:10, got {s:?}"))?;
    let parse = |t: &str| {
        t.trim()
            .parse::<f64>()
            .map_err(|_| format!("{t:?} is not a number (expected MIN:MAX, e.g. 0:10)"))
    };
    Ok((parse(lo)?, parse(hi)?))
}

/// What `compensate` reports.
#[derive(Debug, Serialize)]
struct Report {
    model: String,
    method: Method,
    trajectory: String,
    output: String,
    samples: usize,
    limits: (f64, f64),
    control_unit: String,
    desired_unit: String,
    /// Samples whose desired position could not be reached within the limits (clamped).
    saturated: u64,
    /// Time (s) of the first saturated sample.
    first_saturated_time_s: Option<f64>,
    /// Smallest and largest drive emitted.
    control_range: (f64, f64),
}

/// Runs `hystcomp compensate`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let model = ModelFile::load(&args.model)?;
    let mut compensator = ScaledCompensator::new(&model, args.method, args.limits)
        .map_err(|e| CliError::input(e.to_string()).context(args.model.display()))?;
    let options = ReadOptions {
        delimiter: args.delimiter,
        header: args.header,
        rows: None,
    };
    let columns = data::read_columns(
        &args.trajectory,
        &[args.time_column.clone(), args.desired_column.clone()],
        &options,
    )?;
    let (time, desired) = (&columns.values[0], &columns.values[1]);
    data::check_time_increasing(time)
        .map_err(|e| CliError::from(e).context(args.trajectory.display()))?;

    let mut control = vec![0.0; desired.len()];
    let mut first_saturated = None;
    let mut saturated_so_far = 0;
    for (k, (&d, v)) in desired.iter().zip(control.iter_mut()).enumerate() {
        *v = compensator.step(d);
        let saturated = compensator.diagnostics().saturated;
        if saturated > saturated_so_far && first_saturated.is_none() {
            first_saturated = Some(time[k]);
        }
        saturated_so_far = saturated;
    }

    let time_name = columns.names[0].clone();
    let desired_name = format!("desired_{}", compensator.desired_unit());
    let control_name = format!("drive_{}", compensator.control_unit());
    data::write_csv(
        &args.output,
        &[&time_name, &control_name, &desired_name],
        &[time, &control, desired],
    )
    .map_err(|e| CliError::output(e.to_string()))?;

    let report = Report {
        model: args.model.display().to_string(),
        method: args.method,
        trajectory: args.trajectory.display().to_string(),
        output: args.output.display().to_string(),
        samples: desired.len(),
        limits: compensator.limits(),
        control_unit: compensator.control_unit().to_string(),
        desired_unit: compensator.desired_unit().to_string(),
        saturated: compensator.diagnostics().saturated,
        first_saturated_time_s: first_saturated,
        control_range: control
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            }),
    };
    if ctx.json {
        crate::print_json(&report)?;
    } else {
        println!(
            "{}: {} samples through {} -> {} (drive {:.4} .. {:.4} {}, limits {:.4} .. {:.4} {})",
            report.trajectory,
            report.samples,
            report.method,
            report.output,
            report.control_range.0,
            report.control_range.1,
            report.control_unit,
            report.limits.0,
            report.limits.1,
            report.control_unit,
        );
    }
    if report.saturated > 0 {
        let message = format!(
            "{} of {} desired positions lie outside what the model can reach within the drive \
             limits {:.4} .. {:.4} {} (first at t = {} s); the drive was clamped to the limits there. \
             Scale the trajectory into the stage's range or widen --limits{}",
            report.saturated,
            report.samples,
            report.limits.0,
            report.limits.1,
            report.control_unit,
            first_saturated.unwrap_or(f64::NAN),
            if args.allow_saturation {
                ""
            } else {
                "; --allow-saturation accepts the clamped output with exit status 0"
            }
        );
        if args.allow_saturation {
            eprintln!("hystcomp: warning: {message}");
        } else {
            return Err(CliError::with_code(message, EXIT_SATURATED));
        }
    }
    Ok(())
}
