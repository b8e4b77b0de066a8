//! `hystcomp signal`: test signals as CSV (`time_s` and one value column), from the generators of
//! `hystcomp_experiments::signals` and the study's identification excitation, so that every
//! input of the README's session can be made on the command line.

use hystcomp_core::Shown;
use std::path::PathBuf;

use clap::ValueEnum;
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_experiments::signals::multisine::MAX_TONES;
use hystcomp_experiments::signals::{
    Chirp, MAX_SAMPLE_RATE_HZ, MAX_SAMPLES, MAX_SPEED, Multisine, PaperTrajectory, Raster, Shape,
    Signal, Steps, Sweep,
};
use hystcomp_io::data::MAX_MAGNITUDE;
use serde::Serialize;

use crate::files::{Files, NamesFiles};
use crate::{CliError, Context};

/// Which signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Kind {
    /// The study's identification excitation (command, V): from rest, nested reversals over the
    /// full range, then a multisine; 0 .. 10 V unless --amplitude / --offset say otherwise.
    Identification,
    /// The paper's trajectory (section 4.3): 37.35 + 10.5 sin(pi t + 2.6) + 10.5 sin(1.6 pi t
    /// + 3) + 15.75 sin(2 pi t + 1.5) um, period 10 s.
    Paper,
    /// A triangle raster with rounded corners (--frequency, --rounding).
    Triangle,
    /// A sawtooth raster with rounded corners (--frequency, --rise-fraction, --rounding).
    Sawtooth,
    /// Held levels with moves between them (--levels, --hold, --transition).
    Steps,
    /// A periodic multisine with Schroeder phases (--frequency, --first-harmonic, --tones).
    Multisine,
    /// A swept sine (--start-frequency, --end-frequency, --sweep).
    Chirp,
}

/// A chirp's sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SweepArg {
    /// Linear in time.
    Linear,
    /// Exponential in time.
    Logarithmic,
}

/// Arguments of `hystcomp signal`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The signal to write.
    #[arg(value_enum)]
    kind: Kind,
    /// Output CSV file: `time_s` and the value column.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    output: PathBuf,
    /// Half the peak-to-peak range, in the signal's unit. Default: the paper's (26.25 um) for
    /// `paper`, 5 V for `identification`, else 10.
    #[arg(long, allow_negative_numbers = true)]
    amplitude: Option<f64>,
    /// Centre of the range, in the signal's unit. Default: the paper's (about 37.4 um) for
    /// `paper`, 5 V for `identification`, else 20.
    #[arg(long, allow_negative_numbers = true)]
    offset: Option<f64>,
    /// Length, s (real time, after --speed). Default: two periods (20 s) for `paper`, the whole
    /// excitation for `identification`, else 10 s.
    #[arg(long, value_name = "SECONDS")]
    duration: Option<f64>,
    /// Time compression: the signal runs this many times faster than its nominal time base
    /// (10 plays the paper's 10 s period in 1 s); 1e-3 .. 1e4.
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Samples per second, Hz (the built-in stage runs at 10 kHz); at most 1e7, and at most
    /// 2e7 samples in all.
    #[arg(long, default_value_t = 10_000.0, value_name = "HZ")]
    sample_rate: f64,
    /// Name of the value column. Default: `command_v` for `identification`, else `desired_um`
    /// (use e.g. `command_v` for a drive voltage).
    #[arg(long, value_name = "NAME")]
    column: Option<String>,
    /// Raster lines per second or multisine fundamental, Hz (nominal, before --speed).
    #[arg(long, default_value_t = 1.0, value_name = "HZ")]
    frequency: f64,
    /// Fraction of a raster's period spent on each rounded corner, 0 .. 0.5.
    #[arg(long, default_value_t = 0.05)]
    rounding: f64,
    /// Fraction of a sawtooth's period spent rising, 0 .. 1 (exclusive).
    #[arg(long, default_value_t = 0.9)]
    rise_fraction: f64,
    /// Levels of `steps`, in -1 .. 1 of the range (scaled by --amplitude about --offset).
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        default_value = "-1,1"
    )]
    levels: Vec<f64>,
    /// How long `steps` holds each level, s (nominal).
    #[arg(long, default_value_t = 1.0, value_name = "SECONDS")]
    hold: f64,
    /// How long each move between levels takes, s (nominal; 0 jumps).
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
    transition: f64,
    /// The multisine's first harmonic of --frequency.
    #[arg(long, default_value_t = 1)]
    first_harmonic: u32,
    /// The multisine's number of tones (consecutive harmonics, equal amplitudes, Schroeder
    /// phases); 1 .. 10000.
    #[arg(long, default_value_t = 5)]
    tones: u32,
    /// A chirp's first frequency, Hz (nominal).
    #[arg(long, default_value_t = 0.1, value_name = "HZ")]
    start_frequency: f64,
    /// A chirp's last frequency, Hz (nominal).
    #[arg(long, default_value_t = 10.0, value_name = "HZ")]
    end_frequency: f64,
    /// A chirp's sweep.
    #[arg(long, value_enum, default_value = "logarithmic")]
    sweep: SweepArg,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new().output("--output", &self.output)
    }
}

#[derive(Serialize)]
struct Report<'a> {
    output: String,
    column: &'a str,
    samples: usize,
    duration_s: f64,
    sample_rate_hz: f64,
    min: f64,
    max: f64,
    first: f64,
    last: f64,
}

/// `hystcomp signal`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let (column, values) = values(args)?;
    // A record's values are at most MAX_MAGNITUDE (1e15) when read: write none that no
    // command could read back (an --amplitude or --offset of 1e308 overflows to inf).
    if let Some((k, v)) = values
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite() || v.abs() > MAX_MAGNITUDE)
    {
        // Rows counted from 1 as the written file's data rows are; the cause may be the
        // scale (--amplitude, --offset) or the shape's own parameters (a chirp's frequency
        // ratio overflowing, say).
        return Err(CliError::input(format!(
            "row {} (t = {} s) would be {}, beyond the {MAX_MAGNITUDE:e} a record may hold: give \
             a smaller --amplitude or --offset, or check the signal's other parameters",
            k + 1,
            crate::number(k as f64 / args.sample_rate),
            crate::number(*v),
        )));
    }
    let time: Vec<f64> = (0..values.len())
        .map(|k| k as f64 / args.sample_rate)
        .collect();
    hystcomp_io::data::write_csv(&args.output, &["time_s", &column], &[&time, &values])
        .map_err(|e| CliError::output(e.to_string()))?;
    let (min, max) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let report = Report {
        output: args.output.display().to_string(),
        column: &column,
        samples: values.len(),
        duration_s: values.len() as f64 / args.sample_rate,
        sample_rate_hz: args.sample_rate,
        min,
        max,
        first: values.first().copied().unwrap_or(f64::NAN),
        last: values.last().copied().unwrap_or(f64::NAN),
    };
    if ctx.json {
        return crate::print_json(&report);
    }
    outln!(
        "{}: {} samples ({} s at {} Hz), {} {} .. {}, from {} to {}",
        report.output,
        report.samples,
        crate::number(report.duration_s),
        crate::number(report.sample_rate_hz),
        column,
        crate::number(min),
        crate::number(max),
        crate::number(report.first),
        crate::number(report.last),
    )
}

/// The value column's name and the samples.
fn values(args: &Args) -> Result<(String, Vec<f64>), CliError> {
    let bad = |e: hystcomp_experiments::signals::SignalError| {
        CliError::input(format!("{}: {}", option_of(e.parameter), e.message))
    };
    if args.kind == Kind::Identification {
        return identification(args);
    }
    let shape = match args.kind {
        Kind::Identification => unreachable!("handled above"),
        Kind::Paper => Shape::Paper(PaperTrajectory::new()),
        Kind::Triangle => Shape::Raster(Raster::triangle(args.frequency, args.rounding)),
        Kind::Sawtooth => Shape::Raster(Raster::sawtooth(
            args.frequency,
            args.rise_fraction,
            args.rounding,
        )),
        Kind::Steps => Shape::Steps(Steps {
            levels: args.levels.clone(),
            hold_s: args.hold,
            transition_s: args.transition,
        }),
        Kind::Multisine => {
            if args.tones == 0 || args.tones as usize > MAX_TONES {
                return Err(CliError::input(format!(
                    "--tones must be 1 .. {MAX_TONES}, got {}",
                    args.tones
                )));
            }
            Shape::Multisine(
                Multisine::schroeder(args.frequency, args.first_harmonic, args.tones)
                    .map_err(|e| CliError::input(format!("--frequency/--tones: {e}")))?,
            )
        }
        Kind::Chirp => Shape::Chirp(Chirp {
            start_hz: args.start_frequency,
            end_hz: args.end_frequency,
            sweep: match args.sweep {
                SweepArg::Linear => Sweep::Linear,
                SweepArg::Logarithmic => Sweep::Logarithmic,
            },
        }),
    };
    let paper = PaperTrajectory::new();
    let (amplitude, offset, duration) = match args.kind {
        Kind::Paper => (
            paper.half_range_um(),
            paper.mid_range_um(),
            20.0 / args.speed,
        ),
        _ => (10.0, 20.0, 10.0),
    };
    let signal = Signal {
        shape,
        amplitude: args.amplitude.unwrap_or(amplitude),
        offset: args.offset.unwrap_or(offset),
        duration_s: args.duration.unwrap_or(duration),
        speed: args.speed,
        sample_rate_hz: args.sample_rate,
    };
    let values = signal.sample().map_err(bad)?;
    let column = args.column.clone().unwrap_or_else(|| "desired_um".into());
    Ok((column, values))
}

/// The study's identification excitation, scaled from its 0 .. 10 V to offset +- amplitude,
/// time-compressed by the speed factor, cut (or held at its end) to the duration.
fn identification(args: &Args) -> Result<(String, Vec<f64>), CliError> {
    check_range("--speed", args.speed, 1e-3, MAX_SPEED)?;
    check_range("--sample-rate", args.sample_rate, 1e-3, MAX_SAMPLE_RATE_HZ)?;
    let excitation = IdentificationExcitation::default();
    // Sampled at rate / speed on its own time base, then played at `rate`: `speed` times faster.
    let natural_s = excitation_length_s(&excitation) / args.speed;
    let duration = args.duration.unwrap_or(natural_s);
    check_range("--duration", duration, 0.0, f64::MAX)?;
    let samples = (duration * args.sample_rate).round();
    if samples > MAX_SAMPLES as f64 || samples < 1.0 {
        return Err(CliError::input(format!(
            "--duration {duration} s at --sample-rate {} Hz gives {samples} samples; give 1 .. \
             {MAX_SAMPLES}",
            args.sample_rate
        )));
    }
    // The excitation is built whole on its own time base before it is cut: bounded as well.
    let built = (excitation_length_s(&excitation) * args.sample_rate / args.speed).ceil();
    if built > MAX_SAMPLES as f64 {
        return Err(CliError::input(format!(
            "the identification excitation ({} s) sampled at --sample-rate {} Hz / --speed {} \
             is {built} samples before it is cut to --duration, more than {MAX_SAMPLES}; give a \
             lower --sample-rate or a higher --speed",
            excitation_length_s(&excitation),
            args.sample_rate,
            args.speed
        )));
    }
    let mut command = excitation.command_v(args.sample_rate / args.speed);
    let last = command.last().copied().unwrap_or(0.0);
    command.resize(samples as usize, last);
    let half = excitation.full_scale_v / 2.0;
    let amplitude = args.amplitude.unwrap_or(half);
    let offset = args.offset.unwrap_or(half);
    let values = command
        .iter()
        .map(|v| offset + amplitude * (v / half - 1.0))
        .collect();
    let column = args.column.clone().unwrap_or_else(|| "command_v".into());
    Ok((column, values))
}

/// The option that sets a signal parameter (the generators name their fields).
fn option_of(parameter: &str) -> String {
    match parameter {
        "duration_s" => "--duration".into(),
        "sample_rate_hz" => "--sample-rate".into(),
        "frequency_hz" | "fundamental_hz" => "--frequency".into(),
        "hold_s" => "--hold".into(),
        "transition_s" => "--transition".into(),
        "start_hz" => "--start-frequency".into(),
        "end_hz" => "--end-frequency".into(),
        other => format!("--{}", other.replace('_', "-")),
    }
}

/// The length of the default excitation at speed 1, s.
fn excitation_length_s(excitation: &IdentificationExcitation) -> f64 {
    // The command at 1 kHz has one sample per millisecond of its nominal time.
    excitation.command_v(1000.0).len() as f64 / 1000.0
}

fn check_range(option: &str, value: f64, lo: f64, hi: f64) -> Result<(), CliError> {
    if value.is_finite() && value > lo && value <= hi {
        Ok(())
    } else {
        Err(CliError::input(format!(
            "{option} must be above {lo} and at most {}, got {}",
            Shown(hi),
            Shown(value)
        )))
    }
}
