//! `hystcomp simulate`: drive the simulated piezo stage with a command-voltage record.

use std::path::PathBuf;

use hystcomp_io::data::{self, Column, DataError, ReadOptions};
use hystcomp_stage::{Stage, StageConfig, StageResponse};

use crate::files::{Files, NamesFiles};
use crate::time_unit::TimeUnit;
use crate::{CliError, Context};

/// Arguments of `hystcomp simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Stage file (TOML, see crates/stage/stages/default.toml); the built-in default stage
    /// when absent.
    #[arg(long, value_name = "STAGE.toml")]
    pub stage: Option<PathBuf>,

    /// Input record (CSV, other delimited text or .mat) with a time column (s) and a command
    /// voltage column (V, the controller's DAC output, nominally 0..10 V). The time step must
    /// be the stage's sample period.
    #[arg(long = "drive", alias = "input", value_name = "VOLTS.csv")]
    pub input: PathBuf,

    /// Output CSV, one row per input sample: time_s, command_v, amplifier_v,
    /// true_position_um, measured_um (positions at the end of each sample period).
    #[arg(short = 'o', long = "output", value_name = "OUT.csv")]
    pub output: PathBuf,

    /// Time column of the input: a header name or a number counted from 1.
    #[arg(long, value_name = "COLUMN", default_value = "1")]
    pub time_column: Column,

    /// Command voltage column of the input: a header name or a number counted from 1.
    #[arg(long, value_name = "COLUMN", default_value = "2")]
    pub voltage_column: Column,

    /// Unit of the time column: s, ms or us (the output's time_s is in seconds).
    #[arg(long, value_enum, default_value = "s", value_name = "UNIT")]
    pub time_unit: TimeUnit,

    /// Seed of the sensor noise (the same seed gives the same output) [default: the stage
    /// file's `seed`, 1 for the built-in stage].
    #[arg(long)]
    pub seed: Option<u64>,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .stage("--stage", self.stage.as_ref())
            .input("--drive", &self.input)
            .output("--output", &self.output)
    }
}

/// Largest relative difference allowed between the input's time step and the stage's period.
const STEP_TOLERANCE: f64 = 1e-6;

/// Output columns, in order.
const HEADER: [&str; 5] = [
    "time_s",
    "command_v",
    "amplifier_v",
    "true_position_um",
    "measured_um",
];

fn data_error(error: DataError) -> CliError {
    if error.is_output() {
        CliError::output(error.to_string())
    } else {
        CliError::input(error.to_string())
    }
}

/// Refuses an input whose time step (in seconds, read in `unit`) is not the stage's sample
/// period; when it is 1000 or 10^6 times off, the message names the `--time-unit` that fits.
fn check_time_step(
    time: &[f64],
    unit: TimeUnit,
    config: &StageConfig,
    stage_name: &str,
) -> Result<(), CliError> {
    let period = 1.0 / config.sample_rate_hz;
    for (i, pair) in time.windows(2).enumerate() {
        let step = pair[1] - pair[0];
        if ((step - period) / period).abs() > STEP_TOLERANCE {
            let (first, second) = (i + 1, i + 2);
            let rate = config.sample_rate_hz;
            return Err(CliError::input(match unit.likely_instead(step, period) {
                Some(likely) => format!(
                    "the input's time step between rows {first} and {second} is {step} s read \
                     in {}, {} times {stage_name}'s period of {period} s (sample_rate_hz = \
                     {rate} Hz): the time column is probably in {}; give --time-unit {}",
                    unit.name(),
                    step / period,
                    likely.name(),
                    likely.name()
                ),
                None => format!(
                    "the input's time step between rows {first} and {second} is {step} s, but \
                     {stage_name} samples at sample_rate_hz = {rate} Hz (a step of {period} \
                     s); give a record sampled at that rate, or set sample_rate_hz = {} in a \
                     stage file (--time-unit ms or us if the time column is not in seconds)",
                    1.0 / step,
                ),
            }));
        }
    }
    Ok(())
}

fn min_max(values: &[f64]) -> serde_json::Value {
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    serde_json::json!({ "min": lo, "max": hi })
}

/// The output's columns, named as [`HEADER`] names them, in order.
fn columns<'a>(time: &'a [f64], response: &'a StageResponse) -> [(&'static str, &'a [f64]); 5] {
    [
        (HEADER[0], time),
        (HEADER[1], &response.command_v),
        (HEADER[2], &response.amplifier_v),
        (HEADER[3], &response.true_position_um),
        (HEADER[4], &response.measured_position_um),
    ]
}

fn summary(
    args: &Args,
    config: &StageConfig,
    time: &[f64],
    response: &StageResponse,
) -> serde_json::Value {
    let ranges: serde_json::Map<String, serde_json::Value> = columns(time, response)
        .iter()
        .map(|(name, values)| (name.to_string(), min_max(values)))
        .collect();
    serde_json::json!({
        "input": args.input.display().to_string(),
        "output": args.output.display().to_string(),
        "stage": args.stage.as_ref().map(|p| p.display().to_string()),
        "hysteresis_model": config.hysteresis.model,
        "sample_rate_hz": config.sample_rate_hz,
        "seed": args.seed.unwrap_or(config.seed),
        "samples": time.len(),
        "duration_s": time.len() as f64 / config.sample_rate_hz,
        "columns": ranges,
        "clamped": {
            "dac": response.clamps.dac_clamped,
            "amplifier": response.clamps.amplifier_clamped,
            "slew_limited": response.clamps.slew_limited,
            "adc": response.clamps.adc_clamped,
            "any_drive_limit": response.clamps.limited,
        },
        "limited_share": limited_share(response),
    })
}

/// Share of the samples at the amplifier's slew limit or its rails (or beyond the DAC's span),
/// 0..1 (a sample at two limits counts once).
fn limited_share(response: &hystcomp_stage::StageResponse) -> f64 {
    response.clamps.limited as f64 / response.command_v.len().max(1) as f64
}

/// Runs `hystcomp simulate`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let (config, stage_name) = match &args.stage {
        Some(path) => (
            StageConfig::from_toml_file(path).map_err(|e| match e {
                hystcomp_stage::StageError::Io { .. } => CliError::input(e.to_string()),
                _ => CliError::input(e.to_string()).context(path.display()),
            })?,
            format!("the stage of {}", path.display()),
        ),
        None => (StageConfig::default(), "the built-in stage".to_string()),
    };

    let record = data::read_columns(
        &args.input,
        &[args.time_column.clone(), args.voltage_column.clone()],
        &ReadOptions::default(),
    )
    .map_err(data_error)?;
    let time = &args.time_unit.to_seconds(&record.values[0]);
    let command_v = &record.values[1];
    data::check_min_samples(2, time.len(), "a simulation")
        .map_err(|e| data_error(e).context(args.input.display()))?;
    data::check_time_increasing(time).map_err(|e| data_error(e).context(args.input.display()))?;
    check_time_step(time, args.time_unit, &config, &stage_name)
        .map_err(|e| e.context(args.input.display()))?;

    let mut stage = Stage::new(&config, args.seed.unwrap_or(config.seed))?;
    let response = stage.run(command_v);
    // The time and the drive are finite (the reader refuses anything else): a non-finite
    // response comes from the stage, whose fields each passed validation but together
    // overflow. Said as such, naming the row, before anything is written.
    let output = columns(time, &response);
    for (name, values) in &output[2..] {
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(CliError::input(format!(
                "{stage_name} gives a non-finite {name} at row {} (t = {} s): its fields \
                 overflow together (spans, gains, bandwidth or capacitance far beyond any \
                 stage's); check them",
                k + 1,
                crate::number(time.get(k).copied().unwrap_or(f64::NAN)),
            )));
        }
    }

    data::write_csv(&args.output, &HEADER, &output.map(|(_, values)| values))
        .map_err(data_error)?;

    if ctx.json {
        let document = summary(args, &config, time, &response);
        crate::print_json(&document)?;
    } else {
        let clamped = response.clamps.dac_clamped + response.clamps.amplifier_clamped;
        outln!(
            "simulated {} samples ({} s) on {stage_name}; wrote {}",
            time.len(),
            time.len() as f64 / config.sample_rate_hz,
            args.output.display()
        )?;
        if clamped > 0 || response.clamps.slew_limited > 0 {
            errln!(
                "{:.2} % of the samples were at the amplifier's slew limit ({:.4} kV/s into the \
                 stack) or its rails: {} slew-limited, {} beyond the rails, {} beyond the DAC",
                100.0 * limited_share(&response),
                config.amplifier.slew_rate_v_per_s() / 1e3,
                response.clamps.slew_limited,
                response.clamps.amplifier_clamped,
                response.clamps.dac_clamped
            );
        }
        if clamped > 0 {
            errln!(
                "warning: {} command samples were outside the DAC span and {} outside the \
                 amplifier's {}..{} V rails once amplified; they were clamped",
                response.clamps.dac_clamped,
                response.clamps.amplifier_clamped,
                config.amplifier.output_min_v,
                config.amplifier.output_max_v
            );
        }
    }
    if response.clamps.adc_clamped > 0 {
        // On stderr in both modes: the measured positions in the output file are wrong there.
        errln!(
            "warning: {} samples of the sensor reading lay outside the ADC's span ({}..{} V, \
             i.e. {:.2}..{:.2} um at sensor.sensitivity_v_per_um = {}): measured_position_um \
             is saturated there; widen adc.min_v/adc.max_v or lower the sensitivity",
            response.clamps.adc_clamped,
            config.adc.min_v,
            config.adc.max_v,
            config.adc.min_v / config.sensor.sensitivity_v_per_um,
            config.adc.max_v / config.sensor.sensitivity_v_per_um,
            config.sensor.sensitivity_v_per_um
        );
    }
    Ok(())
}
