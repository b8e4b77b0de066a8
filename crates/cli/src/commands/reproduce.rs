//! `hystcomp reproduce` (not implemented yet).

use crate::{CliError, Context};

/// Arguments of `hystcomp reproduce`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hystcomp reproduce`.
pub fn run(_args: &Args, _ctx: Context) -> Result<(), CliError> {
    Err(CliError::input("`hystcomp reproduce` is not implemented yet"))
}
