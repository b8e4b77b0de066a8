//! What the command prints: its results on stdout, messages on stderr.
//!
//! Every print goes through the macros here (the crate denies `println!` and `eprintln!`,
//! which panic when the stream is gone):
//!
//! - `outln!` / `out!`: results on stdout; return `Result<(), CliError>`. When the reader
//!   has closed stdout (`hystcomp evaluate --json | head -1`), the rest of the output is
//!   dropped without a message and the command goes on to its usual exit status, as other
//!   command-line tools exit quietly on a broken pipe; any other write error is an output
//!   error (exit code 3).
//! - `errln!`: messages for people on stderr; a stderr that cannot be written is ignored
//!   (there is nowhere left to say so).

use std::fmt;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::CliError;

/// Set once a write to stdout found the pipe closed: nothing more is written there.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Prints a line of the command's output on stdout (see the module docs); use with `?`.
macro_rules! outln {
    () => {
        $crate::out::stdout(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::out::stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Prints the command's output on stdout without a newline (see the module docs).
#[allow(unused_macros)]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::stdout(format_args!($($arg)*))
    };
}

/// Prints a line for people on stderr (warnings, notes, the final error).
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::out::stderr(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Writes `text` to stdout: a closed pipe is not an error (the rest is dropped), anything
/// else is an output error.
pub fn stdout(text: fmt::Arguments<'_>) -> Result<(), CliError> {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return Ok(());
    }
    let mut lock = io::stdout().lock();
    match lock.write_fmt(text).and_then(|()| lock.flush()) {
        Ok(()) => Ok(()),
        Err(error) if error.kind() == io::ErrorKind::BrokenPipe => {
            STDOUT_CLOSED.store(true, Ordering::Relaxed);
            Ok(())
        }
        Err(error) => Err(CliError::output(format!(
            "could not write to stdout: {error}"
        ))),
    }
}

/// Whether stdout was found closed (a command producing much output may stop early).
#[allow(dead_code)]
pub fn stdout_closed() -> bool {
    STDOUT_CLOSED.load(Ordering::Relaxed)
}

/// Writes `text` to stderr, ignoring failures.
pub fn stderr(text: fmt::Arguments<'_>) {
    let mut lock = io::stderr().lock();
    let _ = lock.write_fmt(text).and_then(|()| lock.flush());
}
