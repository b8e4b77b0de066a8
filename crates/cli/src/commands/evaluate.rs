//! `hystcomp evaluate`: the tracking indices of section 4.3 for any pair of records.

use std::path::PathBuf;

use hystcomp_experiments::TrackingIndices;
use hystcomp_experiments::indices::DEFAULT_MHE_BINS;
use hystcomp_io::data::{self, Column, Delimiter, Header, ReadOptions, RowRange};
use serde::Serialize;

use crate::{CliError, Context};

/// Arguments of `hystcomp evaluate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The desired trajectory y_d (CSV, tab / whitespace separated, or .mat).
    #[arg(long, value_name = "FILE")]
    desired: PathBuf,
    /// The measured position y, sample for sample with the desired file (may be the same file).
    #[arg(long, value_name = "FILE")]
    measured: PathBuf,
    /// Column of y_d in the desired file, by name or 1-based index.
    #[arg(long, default_value = "2", value_name = "COLUMN")]
    desired_column: Column,
    /// Column of y in the measured file, by name or 1-based index.
    #[arg(long, default_value = "2", value_name = "COLUMN")]
    measured_column: Column,
    /// Rows (samples) to evaluate, FIRST..LAST, 1-based and inclusive (e.g. the last period).
    #[arg(long, value_name = "FIRST..LAST")]
    rows: Option<RowRange>,
    /// Number of bins of the y_d range for e_mhe (eq. (12), ERRATA item 6).
    #[arg(long, default_value_t = DEFAULT_MHE_BINS)]
    bins: usize,
    /// Field delimiter of both files: auto, comma, tab, semicolon or whitespace.
    #[arg(long, default_value = "auto")]
    delimiter: Delimiter,
    /// Whether the files start with column names: auto, present or absent.
    #[arg(long, default_value = "auto")]
    header: Header,
}

#[derive(Serialize)]
struct Report {
    desired: String,
    measured: String,
    samples: usize,
    /// Percent of the desired range.
    #[serde(flatten)]
    indices: TrackingIndices,
    desired_range: (f64, f64),
}

/// Runs `hystcomp evaluate`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let options = ReadOptions {
        delimiter: args.delimiter,
        header: args.header,
        rows: args.rows,
    };
    let desired = data::read_columns(
        &args.desired,
        std::slice::from_ref(&args.desired_column),
        &options,
    )?;
    let measured = data::read_columns(
        &args.measured,
        std::slice::from_ref(&args.measured_column),
        &options,
    )?;
    let (d, y) = (&desired.values[0], &measured.values[0]);
    // The indices check the pair (equal lengths, a desired range that is not zero, bins).
    let indices = TrackingIndices::compute(d, y, args.bins).map_err(|e| {
        CliError::from(e).context(format!(
            "{} against {}",
            args.measured.display(),
            args.desired.display()
        ))
    })?;
    let range = d
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let report = Report {
        desired: args.desired.display().to_string(),
        measured: args.measured.display().to_string(),
        samples: d.len(),
        indices,
        desired_range: range,
    };
    if ctx.json {
        crate::print_json(&report)?;
    } else {
        println!(
            "{} samples, y_d from {:.4} to {:.4}\ne_mhe = {:.3} % ({} bins)\ne_m   = {:.3} %\ne_rms = {:.3} %",
            report.samples,
            range.0,
            range.1,
            indices.e_mhe_percent,
            indices.mhe_bins,
            indices.e_m_percent,
            indices.e_rms_percent
        );
    }
    Ok(())
}
