//! `hystcomp compensate` (not implemented yet).

use crate::{CliError, Context};

/// Arguments of `hystcomp compensate`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hystcomp compensate`.
pub fn run(_args: &Args, _ctx: Context) -> Result<(), CliError> {
    Err(CliError::input("`hystcomp compensate` is not implemented yet"))
}
