//! `hystcomp identify` (not implemented yet).

use crate::{CliError, Context};

/// Arguments of `hystcomp identify`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `hystcomp identify`.
pub fn run(_args: &Args, _ctx: Context) -> Result<(), CliError> {
    Err(CliError::input("`hystcomp identify` is not implemented yet"))
}
