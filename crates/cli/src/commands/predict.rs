//! `hystcomp predict`: run a model file over a record's input and write what it predicts beside
//! what was measured, so that a user can plot what the model does.

use std::path::PathBuf;

use hystcomp_identify::ErrorStats;
use hystcomp_io::data;
use hystcomp_io::model_file::{Direction, ModelFile};
use serde::Serialize;

use super::identify::ColumnArgs;
use crate::files::{Files, NamesFiles};
use crate::{CliError, Context};

/// Arguments of `hystcomp predict`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file: a plant model predicts the displacement from the voltage, an inverse model
    /// the voltage from the displacement.
    #[arg(long, value_name = "FILE")]
    pub model: PathBuf,
    /// Record of voltage and displacement (text or .mat; see `hystcomp identify --help`).
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,
    /// Output CSV: time_s (or sample), the model's input, the measured output, the predicted
    /// output and the error (predicted minus measured), named with their units.
    #[arg(short, long, value_name = "OUT.csv")]
    pub output: PathBuf,
    #[command(flatten)]
    pub columns: ColumnArgs,
    /// Models with a creep link: take the stage as having rested long at the record's first
    /// sample (the creep settled there) instead of relaxed at the model's origin.
    #[arg(long)]
    pub settled: bool,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .input("--model", &self.model)
            .input("--data", &self.data)
            .output("--output", &self.output)
    }
}

#[derive(Serialize)]
struct Report {
    model: String,
    data: String,
    output: String,
    direction: Direction,
    samples: usize,
    /// The model started from its reset state (zero operator memory, eq. (1)) at the first
    /// sample: the first samples before the input has reached both ends of its range depend on
    /// the record's history, which the model does not know.
    initial_state: String,
    /// Samples whose input lies outside the range the model was identified on.
    outside_input_range: usize,
    /// Errors over every sample, in the output's unit and % of the measured output's range.
    error: ErrorStats,
}

/// Runs `hystcomp predict`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let model = ModelFile::load(&args.model)?;
    let c = &args.columns;
    let loaded = c.load(&args.data)?;
    let (input, measured, input_unit, output_unit) = match model.direction {
        Direction::Plant => (
            &loaded.voltage,
            &loaded.displacement,
            &c.voltage_unit,
            &c.displacement_unit,
        ),
        Direction::Inverse => (
            &loaded.displacement,
            &loaded.voltage,
            &c.displacement_unit,
            &c.voltage_unit,
        ),
    };
    for (what, given, expected) in [
        ("input", input_unit, &model.input.unit),
        ("output", output_unit, &model.output.unit),
    ] {
        if given != expected {
            return Err(CliError::input(format!(
                "the model's {what} is in {expected}, the record's in {given}: give the record's \
                 unit and factor (--voltage-unit/--voltage-factor, --displacement-unit/\
                 --displacement-factor) so that they agree"
            ))
            .context(args.model.display()));
        }
    }
    super::chain_args::check_record_rate(&model, c, &loaded)
        .map_err(|e| e.context(args.data.display()))?;
    let prediction = hystcomp_identify::predict(
        &model,
        hystcomp_identify::Record {
            voltage: &loaded.voltage,
            displacement: &loaded.displacement,
        },
        args.settled,
    )
    .map_err(|e| {
        CliError::input(e.to_string()).context(format!(
            "{} through {}",
            args.data.display(),
            args.model.display()
        ))
    })?;
    let stats = prediction.stats;
    // In % of a range so small that the percentages overflow (subnormal values): refused, not
    // reported as an infinite error.
    if ![stats.rms_percent, stats.max_percent, stats.std_percent]
        .iter()
        .all(|p| p.is_finite())
    {
        return Err(CliError::input(format!(
            "the measured output spans {} {}: too small a range to give the prediction's errors \
             in % of it (are the values in the unit the record's options say?)",
            crate::number(stats.range),
            output_unit
        ))
        .context(args.data.display()));
    }
    let outside = prediction.outside_input_range;
    let (in_lo, in_hi) = (
        model.input.to_physical(model.input_range[0]),
        model.input.to_physical(model.input_range[1]),
    );
    let (in_lo, in_hi) = (in_lo.min(in_hi), in_lo.max(in_hi));

    let (input_name, measured_name) = match model.direction {
        Direction::Plant => ("drive", "measured"),
        Direction::Inverse => ("measured", "drive"),
    };
    let suffix = |unit: &str| unit.to_lowercase();
    let names = [
        if loaded.time.is_some() {
            "time_s".to_owned()
        } else {
            "sample".to_owned()
        },
        format!("{input_name}_{}", suffix(input_unit)),
        format!("{measured_name}_{}", suffix(output_unit)),
        format!("predicted_{}", suffix(output_unit)),
        format!("error_{}", suffix(output_unit)),
    ];
    let index: Vec<f64>;
    let time = match &loaded.time {
        Some(t) => t,
        None => {
            index = (1..=input.len()).map(|k| k as f64).collect();
            &index
        }
    };
    let header: Vec<&str> = names.iter().map(String::as_str).collect();
    data::write_csv(
        &args.output,
        &header,
        &[
            time,
            input,
            measured,
            &prediction.predicted,
            &prediction.error,
        ],
    )
    .map_err(|e| CliError::output(e.to_string()))?;

    let report = Report {
        model: args.model.display().to_string(),
        data: args.data.display().to_string(),
        output: args.output.display().to_string(),
        direction: model.direction,
        samples: input.len(),
        initial_state: prediction.initial_state.clone(),
        outside_input_range: outside,
        error: stats,
    };
    if ctx.json {
        crate::print_json(&report)?;
    } else {
        outln!(
            "{}: {} samples through {} ({}) -> {}: error RMS {} % max {} % of the measured \
             range ({} {}), mean {} {}",
            report.data,
            report.samples,
            report.model,
            report.direction,
            report.output,
            crate::number(stats.rms_percent),
            crate::number(stats.max_percent),
            crate::number(stats.range),
            output_unit,
            crate::number(stats.mean),
            output_unit,
        )?;
        if outside > 0 {
            errln!(
                "hystcomp: note: {outside} of {} input samples lie outside the range the model \
                 was identified on ({} .. {} {input_unit}); it extrapolates there",
                report.samples,
                crate::number(in_lo),
                crate::number(in_hi),
            );
        }
    }
    Ok(())
}
