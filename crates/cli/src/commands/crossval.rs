//! `hystcomp crossval` (not implemented yet).

use crate::{CliError, Context};

/// Arguments of `hystcomp crossval`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hystcomp crossval`.
pub fn run(_args: &Args, _ctx: Context) -> Result<(), CliError> {
    Err(CliError::input("`hystcomp crossval` is not implemented yet"))
}
