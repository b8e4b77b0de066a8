//! One module per subcommand; each has an `Args` (clap) and a `run`.

pub mod bench;
pub mod bench_bank;
pub mod chain_args;
pub mod clock;
pub mod compensate;
pub mod crossval;
pub mod evaluate;
pub mod identify;
pub mod learn;
pub mod predict;
pub mod reproduce;
pub mod signal;
pub mod simulate;
