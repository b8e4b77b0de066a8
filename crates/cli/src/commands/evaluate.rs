//! `hystcomp evaluate`: the tracking indices of section 4.3 for any pair of records.

use hystcomp_core::Shown;
use std::path::PathBuf;

use hystcomp_experiments::TrackingIndices;
use hystcomp_experiments::indices::DEFAULT_MHE_BINS;
use hystcomp_io::data::{self, Column, DataError, Delimiter, Header, ReadOptions, RowRange};
use serde::Serialize;

use crate::files::{Files, NamesFiles};
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
    /// Column of y in the measured file, by name or 1-based index. Default: the column named
    /// `measured_um` when the file has one (a `hystcomp simulate` output; also its former name
    /// `measured_position_um`), else column 2.
    #[arg(long, value_name = "COLUMN")]
    measured_column: Option<Column>,
    /// Time column (s), by name or 1-based index, in both files: when given, the two files'
    /// times must agree row by row (to 1 % of the time step), since the indices compare the
    /// records sample by sample.
    #[arg(long, value_name = "COLUMN")]
    time_column: Option<Column>,
    /// Rows (samples) to evaluate, FIRST..LAST, 1-based and inclusive (e.g. the last period).
    #[arg(long, value_name = "FIRST..LAST")]
    rows: Option<RowRange>,
    /// Score only the last PERIOD seconds (the last full period of a periodic trajectory, as
    /// the paper does: the start from rest is left out). Needs --time-column.
    #[arg(long, value_name = "SECONDS")]
    period: Option<f64>,
    /// Number of bins of the y_d range for e_mhe (eq. (12), ERRATA item 6); at most one per
    /// 10 samples evaluated, so that each bin holds enough samples for a width.
    #[arg(long, default_value_t = DEFAULT_MHE_BINS)]
    bins: usize,
    /// Field delimiter of both files: auto, comma, tab, semicolon or whitespace.
    #[arg(long, default_value = "auto")]
    delimiter: Delimiter,
    /// Whether the files start with column names: auto, present or absent.
    #[arg(long, default_value = "auto")]
    header: Header,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .input("--desired", &self.desired)
            .input("--measured", &self.measured)
    }
}

#[derive(Serialize)]
struct Report {
    desired: String,
    measured: String,
    /// The measured file's column that was read.
    measured_column: String,
    samples: usize,
    /// Time of the first and last sample scored, s (with --time-column).
    scored_s: Option<(f64, f64)>,
    /// Percent of the desired range.
    #[serde(flatten)]
    indices: TrackingIndices,
    desired_range: (f64, f64),
}

/// The name `hystcomp simulate` gives its measured position.
const SIMULATE_MEASURED: &str = "measured_um";
/// What `hystcomp simulate` called it before 0.2 (read for one release).
const SIMULATE_MEASURED_OLD: &str = "measured_position_um";

/// Reads `value` (and `time`, when given) from `path`.
fn read(
    path: &std::path::Path,
    value: &Column,
    time: Option<&Column>,
    options: &ReadOptions,
) -> Result<data::Columns, DataError> {
    let mut columns = vec![value.clone()];
    columns.extend(time.cloned());
    data::read_columns(path, &columns, options)
}

/// Refuses two records whose times differ at some row by more than 1 % of the time step.
fn check_times(desired: &data::Columns, measured: &data::Columns) -> Result<(), CliError> {
    let (td, tm) = (&desired.values[1], &measured.values[1]);
    let step = td
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(f64::INFINITY, f64::min);
    let tolerance = if step.is_finite() && step > 0.0 {
        0.01 * step
    } else {
        1e-9
    };
    if let Some(k) = td
        .iter()
        .zip(tm)
        .position(|(a, b)| (a - b).abs() > tolerance)
    {
        return Err(CliError::input(format!(
            "the times differ at sample {} (row {} of {}, row {} of {}): {} s against {} s; \
             the indices compare the records sample by sample, so give records on the same \
             time axis (or select matching rows with --rows)",
            k + 1,
            desired.file_row(k + 1),
            desired.path.display(),
            measured.file_row(k + 1),
            measured.path.display(),
            td[k],
            tm[k]
        )));
    }
    Ok(())
}

/// How many of the last samples make up the last `period` seconds, from the time column
/// (`values[1]`) of the desired record.
fn last_period(values: &[Vec<f64>], period: f64, has_time: bool) -> Result<usize, CliError> {
    if !has_time {
        return Err(CliError::input(
            "--period needs --time-column (the time of each sample, s)",
        ));
    }
    if !(period.is_finite() && period > 0.0) {
        return Err(CliError::input(format!(
            "--period must be a positive number of seconds, got {}",
            Shown(period)
        )));
    }
    let t = &values[1];
    let span = t.last().copied().unwrap_or(0.0) - t.first().copied().unwrap_or(0.0);
    let step = data::mean_time_step(t).unwrap_or(0.0);
    if step.is_nan() || step <= 0.0 || period > span + step * 0.5 {
        return Err(CliError::input(format!(
            "--period {period} s is longer than the record ({} s)",
            crate::number(span + step)
        )));
    }
    Ok(((period / step).round() as usize).clamp(1, t.len()))
}

/// Runs `hystcomp evaluate`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let options = ReadOptions {
        delimiter: args.delimiter,
        header: args.header,
        rows: args.rows,
    };
    let time = args.time_column.as_ref();
    let desired = read(&args.desired, &args.desired_column, time, &options)?;
    let measured = match &args.measured_column {
        Some(column) => read(&args.measured, column, time, &options)?,
        None => {
            let named = Column::Name(SIMULATE_MEASURED.to_string());
            let old = Column::Name(SIMULATE_MEASURED_OLD.to_string());
            let by_name = match read(&args.measured, &named, time, &options) {
                Err(DataError::NoSuchColumn { .. } | DataError::NoSuchVariable { .. }) => {
                    read(&args.measured, &old, time, &options)
                        .or_else(|_| read(&args.measured, &named, time, &options))
                }
                other => other,
            };
            match by_name {
                // No such column in a text file: the second column. A MAT-file's variables
                // have no order, so there the name must be given.
                Err(DataError::NoSuchColumn { .. }) => {
                    read(&args.measured, &Column::Index(2), time, &options)?
                }
                Err(error @ DataError::NoSuchVariable { .. }) => {
                    return Err(CliError::from(error).context(format!(
                        "no --measured-column given, and no variable {SIMULATE_MEASURED} to \
                         take by default"
                    )));
                }
                other => other?,
            }
        }
    };
    if time.is_some() && desired.len() == measured.len() {
        check_times(&desired, &measured)?;
    }
    let (mut d, mut y) = (&desired.values[0][..], &measured.values[0][..]);
    let mut scored_s = time.map(|_| {
        let t = &desired.values[1];
        (
            t.first().copied().unwrap_or(0.0),
            t.last().copied().unwrap_or(0.0),
        )
    });
    if let Some(period) = args.period {
        let keep = last_period(&desired.values, period, time.is_some())?;
        let start = d.len().saturating_sub(keep);
        d = &d[start..];
        y = &y[start.min(y.len())..];
        let t = &desired.values[1];
        scored_s = Some((t[start], t[t.len() - 1]));
    }
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
        measured_column: measured.names[0].clone(),
        samples: d.len(),
        scored_s,
        indices,
        desired_range: range,
    };
    if ctx.json {
        crate::print_json(&report)?;
    } else {
        let scored = match scored_s {
            Some((a, b)) => format!(", t = {} .. {} s", crate::number(a), crate::number(b)),
            None => String::new(),
        };
        outln!(
            "{} samples{scored}, y_d from {} to {} µm\ne_mhe = {} % ({} bins)\ne_m   = {} %\ne_rms = {} %",
            report.samples,
            crate::number(range.0),
            crate::number(range.1),
            crate::number(indices.e_mhe_percent),
            indices.mhe_bins,
            crate::number(indices.e_m_percent),
            crate::number(indices.e_rms_percent)
        )?;
    }
    Ok(())
}
