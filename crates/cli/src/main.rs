//! `hystcomp`: the command line of the toolkit. Argument parsing, file formats, progress bars,
//! exit codes and messages for people live here; the maths lives in the library crates.
//!
//! Two rules hold for every subcommand, and the structure below makes them the default:
//! - no command overwrites one of its inputs: its arguments implement [`files::NamesFiles`],
//!   and [`run`] checks them before the command reads anything;
//! - nothing panics on a closed pipe: output goes through `outln!` / `errln!` ([`out`]);
//!   `println!` and `eprintln!` are denied.
#![deny(clippy::print_stdout, clippy::print_stderr)]

#[macro_use]
mod out;
mod bounds;
mod commands;
mod error;
mod files;
#[allow(dead_code)]
mod progress;
mod time_unit;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

pub use error::CliError;
use files::NamesFiles;

/// Feedforward hysteresis compensation for piezoelectric nanopositioners.
#[derive(Debug, Parser)]
#[command(
    name = "hystcomp",
    version = env!("HYSTCOMP_VERSION"),
    about,
    long_about = None,
    after_help = error::EXIT_CODES_HELP
)]
struct Cli {
    /// Print results as JSON on stdout (for machines) instead of text.
    #[arg(long, global = true)]
    json: bool,

    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a desired trajectory through a compensator: CSV in, drive voltage CSV out.
    Compensate(commands::compensate::Args),
    /// Per-sample cost of the forward model and every compensator.
    Bench(commands::bench::Args),
    /// Identify a model from measured (voltage, displacement) samples.
    Identify(Box<commands::identify::Args>),
    /// Identify on one record, predict and replay the compensators on another.
    Crossval(Box<commands::crossval::Args>),
    /// Write a test signal as CSV: the study's excitation, the paper's trajectory, rasters,
    /// steps, multisines, chirps.
    Signal(commands::signal::Args),
    /// Run a model file over a record: time, input, measured, predicted and error as CSV.
    Predict(commands::predict::Args),
    /// Drive the simulated stage with a voltage record.
    Simulate(commands::simulate::Args),
    /// Learn from repetition: the next trial's drive from the last trial's measurement
    /// (iterative learning), or the whole loop on the simulated stage (--simulate).
    Learn(commands::learn::Args),
    /// Reproduce the paper's comparative study on the simulated stage.
    Reproduce(commands::reproduce::Args),
    /// Tracking indices e_m, e_rms and e_mhe of a measured record against a desired one.
    Evaluate(commands::evaluate::Args),
}

/// What every subcommand gets besides its own arguments.
#[derive(Debug, Clone, Copy)]
pub struct Context {
    /// `--json` was given: print one JSON document on stdout and nothing else there.
    pub json: bool,
}

/// Prints `value` as the one JSON document of a `--json` run.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| CliError::output(e.to_string()))?;
    outln!("{text}")
}

/// Runs one subcommand: refuses outputs that name one of its inputs, before anything is read,
/// then runs it.
/// A number for people: four significant digits, trailing zeros trimmed (`9.602`, `0.3346`,
/// `10000`), scientific notation below 1e-4 and from 1e7; JSON keeps full precision.
pub fn number(v: f64) -> String {
    if !v.is_finite() {
        return v.to_string();
    }
    if v == 0.0 {
        return "0".into();
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-4..7).contains(&magnitude) {
        return format!("{v:.3e}");
    }
    let decimals = (3 - magnitude).max(0) as usize;
    let text = format!("{v:.decimals$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.')
    } else {
        &text
    };
    match text {
        "-0" => "0".into(),
        t => t.into(),
    }
}

fn run<A: NamesFiles>(
    args: &A,
    ctx: Context,
    command: fn(&A, Context) -> Result<(), CliError>,
) -> Result<(), CliError> {
    args.files().check()?;
    command(args, ctx)
}

fn main() -> ExitCode {
    // Every subcommand's --help ends with the exit codes too.
    let command = Cli::command().mut_subcommands(|s| s.after_help(error::EXIT_CODES_HELP));
    let cli = Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit());
    let ctx = Context { json: cli.json };
    let result = match &cli.command {
        Command::Compensate(args) => run(args, ctx, commands::compensate::run),
        Command::Bench(args) => run(args, ctx, commands::bench::run),
        Command::Identify(args) => run(&**args, ctx, commands::identify::run),
        Command::Crossval(args) => run(&**args, ctx, commands::crossval::run),
        Command::Signal(args) => run(args, ctx, commands::signal::run),
        Command::Predict(args) => run(args, ctx, commands::predict::run),
        Command::Simulate(args) => run(args, ctx, commands::simulate::run),
        Command::Learn(args) => run(args, ctx, commands::learn::run),
        Command::Reproduce(args) => run(args, ctx, commands::reproduce::run),
        Command::Evaluate(args) => run(args, ctx, commands::evaluate::run),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            errln!("hystcomp: error: {error}");
            ExitCode::from(error.exit_code())
        }
    }
}
