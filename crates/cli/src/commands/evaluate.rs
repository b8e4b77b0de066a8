//! `hystcomp evaluate` (not implemented yet).

use crate::{CliError, Context};

/// Arguments of `hystcomp evaluate`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hystcomp evaluate`.
pub fn run(_args: &Args, _ctx: Context) -> Result<(), CliError> {
    Err(CliError::input("`hystcomp evaluate` is not implemented yet"))
}
