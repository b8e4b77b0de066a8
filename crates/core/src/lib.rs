//! The `no_std` core of hystcomp: the play operators, the modified Prandtl-Ishlinskii model
//! (MPIM), its exact inverses and the three feedforward compensators compared by
//!
//! > G.-Y. Gu and L.-M. Zhu, "Comparative experiments regarding approaches to feedforward
//! > hysteresis compensation for piezoceramic actuators", *Smart Mater. Struct.* **23** (2014)
//! > 095029, doi:10.1088/0964-1726/23/9/095029.
//!
//! Equation numbers in the documentation refer to that paper (with the corrections listed in
//! the project's reading notes: eq. (10) uses `a2`, eqs. (5) and (9) are implicit).
//!
//! # Units
//! The core works in the paper's **normalised** units (eq. (11), `||x||_inf = 1`): model inputs
//! and outputs are plain numbers, typically in `[0, 1]`. Physical scales (volts, micrometres)
//! live in the model file (`hystcomp-io`), never here.
//!
//! # Plan once, run many times
//! Constructors validate and do all the set-up (the inverse of eq. (7), the invertibility check);
//! `step` and `process` never allocate, never read clocks or files and never print.
//!
//! # Storage without an allocator
//! Every type is generic over its storage `B:` [`Buffer`]: `Vec<T>` with the `alloc` feature,
//! or a fixed array `[T; N]` on a microcontroller without allocator:
//!
//! ```
//! use hystcomp_core::{Compensator, Ihc, Mpim, OutputLimits, SolveMode};
//!
//! // Table 1 of the paper (normalised voltage in, normalised displacement out).
//! let thresholds = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
//! let weights = [0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032];
//! let plant: Mpim<f64, [f64; 10]> = Mpim::new(&thresholds, &weights, -0.1569, 0.4603)?;
//! let limits = OutputLimits::new(0.0, 1.0)?;
//! let mut ihc: Ihc<f64, [f64; 10]> = Ihc::new(&plant, limits, SolveMode::Exact)?;
//! let mut model = plant.clone();
//! for k in 0..1000 {
//!     let desired = 0.4 + 0.3 * (k as f64 * 0.01).sin();
//!     let voltage = ihc.step(desired);
//!     assert!((model.step(voltage) - desired).abs() < 1e-9); // P[C[y_d]] = y_d
//! }
//! # Ok::<(), hystcomp_core::CoreError>(())
//! ```
#![cfg_attr(not(feature = "std"), no_std)]
#![warn(missing_docs)]

#[cfg(feature = "alloc")]
extern crate alloc;

pub mod bank;
mod buffer;
pub mod chain;
mod compensator;
pub mod creep;
mod dihc;
mod error;
mod ihc;
mod invertibility;
mod mpim;
pub mod output_map;
pub mod paper;
mod play;
mod polynomial;
mod real;
#[cfg(feature = "alloc")]
pub mod reference;
mod roots;
mod shown;
mod solve;
pub mod vibration;
mod walk;
mod wihc;

#[cfg(feature = "alloc")]
pub use bank::Heap;
pub use bank::{
    BankError, BankStorage, CompensatorBank, DihcBank, Fixed, IhcBank, LANES, MAX_BANK_VALUES,
    MAX_CHANNELS, PLAIN_DEGREE, WihcBank, check_signal, check_tick, dihc_bank_rows,
    plant_bank_rows,
};
#[cfg(feature = "std")]
pub use bank::{VectorPath, with_vector_path};
pub use buffer::{Bounded, Buffer};
pub use chain::{ChainCompensator, ChainModel};
pub use compensator::{Compensator, Diagnostics, OutputLimits, SolveMode};
pub use creep::{Creep, CreepInverse, MAX_CREEP_ELEMENTS};
pub use dihc::Dihc;
pub use error::CoreError;
pub use ihc::{DIRECT_OPERATORS, Ihc};
pub use invertibility::{BranchSlope, LoopGain, branch_checkpoints, branch_intervals};
pub use mpim::Mpim;
pub use output_map::{MAX_OUTPUT_MAP_DEGREE, MapSide, MappedCompensator, OutputMap};
pub use play::{OneSidedPlay, SymmetricPlay};
pub use polynomial::{InputPolynomial, MAX_INPUT_DEGREE};
pub use real::Real;
pub use shown::Shown;
pub use vibration::{
    MAX_DELAY_SAMPLES, MAX_PREVIEW_SAMPLES, MAX_VIBRATION_ORDER, STATIC_GAIN_TOLERANCE,
    TAIL_TOLERANCE, Vibration, VibrationInverse,
};
pub use wihc::Wihc;

/// The Rust examples of the README, run as doctests so that they stay true.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
