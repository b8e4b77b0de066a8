//! `hystcomp compensate --model SET`: a multi-column desired trajectory through a bank of
//! compensators, one channel per model of the set (a model-set file or a directory of model
//! files), one column per channel (issue 16).
//!
//! The desired columns are `--desired-columns` when given (one per channel, in the set's
//! order); else the columns named after the channels when the file has them all; else the
//! consecutive columns from `--desired-column` (by default 2, 3, ...). The drive file holds the
//! time, one `drive_NAME_UNIT` column per channel, then one `desired_NAME_UNIT` per channel.

use hystcomp_io::bank::{ModelSet, ScaledBank};
use hystcomp_io::compensator::Method;
use hystcomp_io::data::{self, Column, Columns, DataError, ReadOptions};
use serde::Serialize;

use super::{Args, build_error, clamped, earliest, range};
use crate::{CliError, Context};

/// What `compensate` reports for one channel of a bank.
#[derive(Debug, Serialize)]
struct ChannelReport {
    name: String,
    /// The trajectory column it was read from.
    desired_column: String,
    limits: (f64, f64),
    control_unit: String,
    desired_unit: String,
    /// Ticks whose drive was clamped to a limit (`unreachable + loop_saturated`).
    saturated: u64,
    /// Ticks whose desired position was out of the model's reach within the limits.
    unreachable: u64,
    /// Ticks a delayed loop drove into a limit although the position was reachable.
    loop_saturated: u64,
    first_unreachable_time_s: Option<f64>,
    first_loop_saturated_time_s: Option<f64>,
    control_range: (f64, f64),
    /// What this channel's drive asks of the stage's amplifier.
    feasibility: hystcomp_stage::Feasibility,
}

/// What `compensate` reports for a bank.
#[derive(Debug, Serialize)]
struct Report {
    model: String,
    method: Method,
    trajectory: String,
    output: String,
    samples: usize,
    channels: Vec<ChannelReport>,
    allow_unstable_delay: bool,
}

/// The trajectory's time column then its desired columns for `set` (see the module
/// documentation). The file is read once: when it has the columns named after the channels,
/// the read that finds them is the record.
fn read_trajectory(
    args: &Args,
    set: &ModelSet,
    options: &ReadOptions,
) -> Result<Columns, CliError> {
    let read = |desired: Vec<Column>| {
        let mut wanted = vec![args.time_column.clone()];
        wanted.extend(desired);
        data::read_columns(&args.trajectory, &wanted, options)
    };
    let channels = set.len();
    let desired = if let Some(columns) = &args.desired_columns {
        if columns.len() != channels {
            return Err(CliError::input(format!(
                "--desired-columns names {} columns, but the model set {} has {channels} \
                 channels ({}); name one column per channel, in the set's order",
                columns.len(),
                args.model.display(),
                set.names().join(", ")
            )));
        }
        columns.clone()
    } else {
        let named = set
            .names()
            .iter()
            .map(|n| Column::Name((*n).to_string()))
            .collect();
        // Only a file without those columns falls back to positions: any other failure (a
        // bad value, a name matching two columns) is this read's error, not a reason to drive
        // the channels from other columns.
        match read(named) {
            Ok(record) => return distinct_columns(record, set),
            Err(DataError::NoSuchColumn { .. } | DataError::NoSuchVariable { .. }) => {}
            Err(error) => {
                return Err(CliError::from(error).context(format!(
                    "reading the columns named after the channels of {} ({})",
                    args.model.display(),
                    set.names().join(", ")
                )));
            }
        }
        match &args.desired_column {
            Column::Index(first) => (0..channels)
                .map(|c| {
                    first.checked_add(c).map(Column::Index).ok_or_else(|| {
                        CliError::input(format!(
                            "--desired-column {first} leaves no column for channel {c}: the \
                             columns of the {channels} channels run past the largest index"
                        ))
                    })
                })
                .collect::<Result<_, _>>()?,
            other if channels == 1 => vec![other.clone()],
            other => {
                return Err(CliError::input(format!(
                    "--desired-column {other} names one column, but the model set {} has \
                     {channels} channels ({}); give --desired-columns with one column per \
                     channel",
                    args.model.display(),
                    set.names().join(", ")
                )));
            }
        }
    };
    distinct_columns(read(desired)?, set)
}

/// `record` (the time column, then one per channel) when no channel reads the time column
/// or another channel's: a channel driven by the clock, or two channels sharing a
/// trajectory, is almost certainly a wrong index or name.
fn distinct_columns(record: Columns, set: &ModelSet) -> Result<Columns, CliError> {
    let Some((time, channels)) = record.names.split_first() else {
        return Ok(record);
    };
    let names = set.names();
    let channel = |c: usize| names.get(c).copied().unwrap_or("?");
    for (c, name) in channels.iter().enumerate() {
        if name == time {
            return Err(CliError::input(format!(
                "the desired column of channel {c} ({}) is the time column {name}: give the \
                 channels' own columns",
                channel(c)
            )));
        }
        if let Some(d) = channels[..c].iter().position(|other| other == name) {
            return Err(CliError::input(format!(
                "channels {d} ({}) and {c} ({}) read the same column {name}: give one column \
                 per channel",
                channel(d),
                channel(c)
            )));
        }
    }
    Ok(record)
}

/// The most drive values (samples times channels) one `compensate` run with a model set
/// writes: 50 million, about 1 GB of CSV text and 400 MB of drives held for it.
const MAX_BANK_VALUES: usize = 50_000_000;

/// Refuses `samples` of `channels` channels beyond [`MAX_BANK_VALUES`] drive values: every
/// channel's drives are kept for the output file, which is written whole, so they are bounded
/// before they are allocated.
fn check_drive_values(samples: usize, channels: usize) -> Result<(), CliError> {
    let values = samples.saturating_mul(channels);
    if values > MAX_BANK_VALUES {
        return Err(CliError::input(format!(
            "{samples} samples of {channels} channels are {values} drive values, more than the \
             {MAX_BANK_VALUES} one run writes; split the trajectory into shorter files"
        )));
    }
    Ok(())
}

/// Runs `hystcomp compensate` with a model set.
pub(super) fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let set = ModelSet::load(&args.model).map_err(|e| CliError::input(e.to_string()))?;
    if args.preview.is_some() {
        return Err(CliError::input(
            "--preview concerns a model's vibration link, but a bank compensates the hysteresis \
             of each channel only",
        ));
    }
    if args.inverse_band_hz.is_some() || args.within_slew.is_some() {
        return Err(CliError::input(
            "--inverse-band-hz and --within-slew concern a model's vibration link, but a bank \
             compensates the hysteresis of each channel only",
        ));
    }
    let limits = args.limits.clone();
    let mut bank = ScaledBank::new(&set, args.method, limits.as_deref(), args.unstable_delay())
        .map_err(|e| match e {
            hystcomp_io::bank::ModelSetError::Channel {
                channel,
                name,
                error,
            } => build_error(error, args.method).context(format!(
                "{}: channel {channel} ({name})",
                args.model.display()
            )),
            other => CliError::input(other.to_string()),
        })?;
    let stage = args.stage()?;
    let columns = read_trajectory(args, &set, &args.read_options())?;
    let time = &columns.values[0];
    data::check_time_increasing(time)
        .map_err(|e| CliError::from(e).context(args.trajectory.display()))?;
    let channels = set.len();
    let n = time.len();
    if n == 0 {
        return Err(
            CliError::input("the trajectory has no samples").context(args.trajectory.display())
        );
    }
    check_drive_values(n, channels).map_err(|e| e.context(args.trajectory.display()))?;
    let mut tick = vec![0.0; channels];
    let mut drive = vec![0.0; channels];
    let mut control: Vec<Vec<f64>> = vec![vec![0.0; n]; channels];
    let mut first_unreachable = vec![None; channels];
    let mut first_loop = vec![None; channels];
    let mut before: Vec<_> = (0..channels)
        .map(|c| bank.diagnostics(c).unwrap_or_default())
        .collect();
    for k in 0..n {
        for (c, t) in tick.iter_mut().enumerate() {
            *t = columns.values[c + 1][k];
        }
        bank.step(&tick, &mut drive)?;
        for c in 0..channels {
            control[c][k] = drive[c];
            let after = bank.diagnostics(c).unwrap_or_default();
            if after.non_finite > before[c].non_finite {
                return Err(CliError::input(format!(
                    "{}, row {}, channel {c} ({}): the desired position {} {} is not finite \
                     once normalised by its model; check the trajectory's unit against the \
                     model's",
                    args.trajectory.display(),
                    columns.file_row(k + 1),
                    set.channels[c].name,
                    tick[c],
                    bank.desired_unit(c).unwrap_or_default(),
                )));
            }
            if after.saturated > before[c].saturated && first_unreachable[c].is_none() {
                first_unreachable[c] = Some(time[k]);
            }
            if after.loop_saturated > before[c].loop_saturated && first_loop[c].is_none() {
                first_loop[c] = Some(time[k]);
            }
            before[c] = after;
        }
    }

    let mut header = vec![columns.names[0].clone()];
    let unit = |u: &str| u.to_lowercase();
    for c in 0..channels {
        header.push(format!(
            "drive_{}_{}",
            set.channels[c].name,
            unit(bank.control_unit(c).unwrap_or_default())
        ));
    }
    for c in 0..channels {
        header.push(format!(
            "desired_{}_{}",
            set.channels[c].name,
            bank.desired_unit(c).unwrap_or_default()
        ));
    }
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut data_columns: Vec<&[f64]> = vec![time];
    data_columns.extend(control.iter().map(Vec::as_slice));
    data_columns.extend(columns.values[1..].iter().map(Vec::as_slice));
    data::write_csv(&args.output, &header_refs, &data_columns)
        .map_err(|e| CliError::output(e.to_string()))?;

    let mut reports = Vec::with_capacity(channels);
    for c in 0..channels {
        let d = bank.diagnostics(c).unwrap_or_default();
        reports.push(ChannelReport {
            name: set.channels[c].name.clone(),
            desired_column: columns.names[c + 1].clone(),
            limits: bank.limits(c).unwrap_or_default(),
            control_unit: bank.control_unit(c).unwrap_or_default().to_string(),
            desired_unit: bank.desired_unit(c).unwrap_or_default().to_string(),
            saturated: d.saturated + d.loop_saturated,
            unreachable: d.saturated,
            loop_saturated: d.loop_saturated,
            first_unreachable_time_s: first_unreachable[c],
            first_loop_saturated_time_s: first_loop[c],
            control_range: range(&control[c]),
            feasibility: hystcomp_stage::feasibility(&stage, &control[c])
                .map_err(|e| CliError::input(e.to_string()))?,
        });
    }
    let report = Report {
        model: args.model.display().to_string(),
        method: args.method,
        trajectory: args.trajectory.display().to_string(),
        output: args.output.display().to_string(),
        samples: n,
        channels: reports,
        allow_unstable_delay: args.allow_unstable_delay,
    };
    if ctx.json {
        crate::print_json(&report)?;
    } else {
        outln!(
            "{}: {} samples x {} channels through {} -> {}",
            report.trajectory,
            report.samples,
            channels,
            report.method,
            report.output
        )?;
        for r in &report.channels {
            outln!(
                "  {} ({}): drive {:.4} .. {:.4} {}, limits {:.4} .. {:.4} {}{}",
                r.name,
                r.desired_column,
                r.control_range.0,
                r.control_range.1,
                r.control_unit,
                r.limits.0,
                r.limits.1,
                r.control_unit,
                if r.saturated > 0 {
                    format!(", {} clamped", r.saturated)
                } else {
                    String::new()
                }
            )?;
        }
    }
    let infeasible: Vec<&str> = report
        .channels
        .iter()
        .filter(|r| !r.feasibility.is_feasible())
        .map(|r| r.name.as_str())
        .collect();
    if !infeasible.is_empty() {
        errln!(
            "hystcomp: warning: the stage's amplifier cannot deliver the drive of channel(s) {} \
             as asked ({}); slow the trajectory down or reduce its amplitude",
            infeasible.join(", "),
            args.stage_name(),
        );
    }
    let problems: Vec<String> = report
        .channels
        .iter()
        .filter(|r| r.saturated > 0)
        .map(|r| {
            let first = earliest(r.first_unreachable_time_s, r.first_loop_saturated_time_s)
                .unwrap_or(f64::NAN);
            format!(
                "channel {}: {} of {} drives clamped to the limits {:.4} .. {:.4} {} ({} out of \
                 reach, {} by the delayed loop; first at t = {first} s)",
                r.name,
                r.saturated,
                report.samples,
                r.limits.0,
                r.limits.1,
                r.control_unit,
                r.unreachable,
                r.loop_saturated
            )
        })
        .collect();
    if problems.is_empty() {
        return Ok(());
    }
    clamped(
        problems.join("; "),
        "scale the trajectory into the stages' range or widen --limits; ",
        args.allow_saturation,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound on drive values: up to it accepted, one more (or an overflowing product)
    /// refused with the counts named. (A file that large is too slow to write in a test.)
    #[test]
    fn drive_values_are_bounded_before_they_are_allocated() {
        check_drive_values(MAX_BANK_VALUES / 4096, 4096).unwrap();
        check_drive_values(1, MAX_BANK_VALUES).unwrap();
        let refused = check_drive_values(MAX_BANK_VALUES / 4096 + 1, 4096).unwrap_err();
        assert!(refused.to_string().contains("4096 channels"), "{refused}");
        assert!(check_drive_values(usize::MAX, 2).is_err());
        assert!(check_drive_values(2000, 65536).is_err());
    }
}
