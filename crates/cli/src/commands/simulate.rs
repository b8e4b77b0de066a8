//! `hystcomp simulate` (not implemented yet).

use crate::{CliError, Context};

/// Arguments of `hystcomp simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hystcomp simulate`.
pub fn run(_args: &Args, _ctx: Context) -> Result<(), CliError> {
    Err(CliError::input("`hystcomp simulate` is not implemented yet"))
}
