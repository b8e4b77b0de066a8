//! `hystcomp bench` (not implemented yet).

use crate::{CliError, Context};

/// Arguments of `hystcomp bench`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hystcomp bench`.
pub fn run(_args: &Args, _ctx: Context) -> Result<(), CliError> {
    Err(CliError::input("`hystcomp bench` is not implemented yet"))
}
