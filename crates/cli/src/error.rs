//! The one error type of the command line: a message a person can act on and an exit code.

use std::fmt;

/// Exit code for bad input (files, data, models, arguments clap could not check).
pub const EXIT_INPUT: u8 = 1;
/// Exit code for a usage error: an unknown option, a missing or malformed argument (clap's).
#[allow(dead_code)] // clap exits with it itself; named here for the list below
pub const EXIT_USAGE: u8 = 2;
/// Exit code for a failure while writing results.
pub const EXIT_OUTPUT: u8 = 3;
/// Exit code when the work was done but the desired trajectory left the reachable range, so
/// the drive was clamped to its limits (the output is written; see `--allow-saturation`).
pub const EXIT_SATURATED: u8 = 4;
/// Exit code when the work was done and written but an acceptance check failed (`reproduce`;
/// `--no-check` exits 0 instead).
pub const EXIT_CHECK_FAILED: u8 = 5;

/// Exit code when the divergence guard stopped the learning (`learn`): the output holds the
/// last good drive.
pub const EXIT_DIVERGED: u8 = 6;

/// The exit codes, as `--help` shows them and the README lists them (one line each; a new
/// code gets a constant above and a line here).
pub const EXIT_CODES_HELP: &str = "\
Exit status:
  0  success
  1  bad input (a file, its data, a model, an option's value)
  2  usage (an unknown option, a missing or malformed argument)
  3  an output could not be written
  4  saturation: the work was done, but the drive was clamped to its limits (compensate)
  5  an acceptance check failed (reproduce; --no-check exits 0)
  6  the divergence guard stopped the learning; the output holds the last good drive (learn)";

/// An error that ends the command with a message on stderr and a non-zero exit code.
#[derive(Debug)]
pub struct CliError {
    message: String,
    exit_code: u8,
}

impl CliError {
    /// An input error (exit code 1).
    pub fn input(message: impl Into<String>) -> Self {
        CliError {
            message: message.into(),
            exit_code: EXIT_INPUT,
        }
    }

    /// An output error (exit code 3).
    pub fn output(message: impl Into<String>) -> Self {
        CliError {
            message: message.into(),
            exit_code: EXIT_OUTPUT,
        }
    }

    /// An error with a given exit code (never 0).
    pub fn with_code(message: impl Into<String>, exit_code: u8) -> Self {
        CliError {
            message: message.into(),
            exit_code: exit_code.max(1),
        }
    }

    /// Prefixes the message with what was being done, e.g. the file involved.
    pub fn context(mut self, what: impl fmt::Display) -> Self {
        self.message = format!("{what}: {}", self.message);
        self
    }

    /// The process exit code, never 0.
    pub fn exit_code(&self) -> u8 {
        self.exit_code
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl<E: std::error::Error> From<E> for CliError {
    fn from(error: E) -> Self {
        CliError::input(error.to_string())
    }
}
