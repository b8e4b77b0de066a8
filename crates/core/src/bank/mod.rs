//! Banks of compensators: many channels, each with its own model, stepped together once per
//! control tick (a multi-axis stage, the actuators of a deformable mirror).
//!
//! [`IhcBank`], [`WihcBank`] and [`DihcBank`] hold `C` channels of IHC (eqs. (5)-(8)), WIHC
//! (eq. (9)) and DIHC (eq. (10)); `step(&desired, &mut control)` takes one desired position per
//! channel and writes one control per channel, without allocating. Each channel has its own
//! model (operator counts and input polynomials may differ), its own output limits and its own
//! diagnostics; a channel whose model is refused at construction is named by its index
//! ([`BankError::Channel`]).
//!
//! # Layout: structure of arrays, in blocks
//! Channels are grouped in blocks of `W` lanes (`W` = [`LANES`] by default). Within a block
//! every quantity is a row of `W` values, one per channel: the thresholds of operator `i` of
//! the `W` channels side by side, then their weights, and so on. The per-sample work of a
//! block is the single-channel compensator's work written lane by lane, so the compiler turns
//! it into vector instructions across channels (on x86-64 with `std`, compiled also for AVX2 and
//! AVX-512 and the widest the processor has chosen at run time: [`VectorPath`]). Each
//! branch of the single-channel code becomes a mask (each lane all ones or all zeros in an
//! integer as wide as the sample type, the form vector compares produce and blends consume,
//! so that a condition never leaves the vector registers); an exact solve that needs more
//! segments or root-finder iterations in one lane than in the others runs those lanes alone
//! while the others wait masked (a block costs as much as its slowest lane). A block of a
//! multiple of 32 rows takes one row more, so that the same row of neighbouring blocks never
//! lies a multiple of 4 KB apart (4K aliasing of their loads and stores).
//!
//! The plain delayed IHC ([`crate::SolveMode::Delayed`]) steps a block in one pass over its
//! operators, the memory fed while its sum is taken, when a bound proves every lane's drive
//! within its limits before the pass: the drive moves by at most the inverse's greatest slope
//! times the move of its target `w = y_d - h(v(t - Ts))`, with a margin for rounding; the
//! other blocks evaluate first and feed after, as the single [`crate::Ihc`] does. The same
//! bits either way. The guarded delayed IHC ([`crate::SolveMode::DelayedGuarded`]) does the
//! same when its reach test is proven before the pass as well (module `within`).
//!
//! # The single channel is the oracle
//! Every lane performs the operations of its single-channel twin ([`crate::Ihc`],
//! [`crate::Wihc`], [`crate::Dihc`]) in the same order, without fused multiply-adds, so each
//! channel of a bank gives the same bits as its own compensator: outputs, state and
//! diagnostics, including limits, clamps, non-finite inputs and the delayed loops. The tests
//! check this equality on random models and inputs.
//!
//! # Storage without an allocator
//! [`Heap`] storage holds any number of channels; [`Fixed`] storage holds a number fixed at
//! compile time, for a microcontroller ([`plant_bank_rows`], [`dihc_bank_rows`] give the
//! sizes; `docs/microcontroller.md` lists the RAM per channel).

mod channels;
mod dihc;
mod guard;
mod ihc;
mod lanes;
mod plant;
mod play;
mod root;
mod run;
mod storage;
mod wihc;
mod within;

use core::fmt;

pub use dihc::DihcBank;
pub use ihc::IhcBank;
#[cfg(feature = "std")]
pub use run::{VectorPath, with_vector_path};
#[cfg(feature = "alloc")]
pub use storage::Heap;
pub use storage::{BankStorage, Fixed, PLAIN_DEGREE, dihc_bank_rows, plant_bank_rows};
pub use wihc::WihcBank;

use crate::{CoreError, Diagnostics, OutputLimits, Real};

/// The default number of lanes (channels) per block: eight, the `f32` lanes of an AVX2
/// register and two of them in `f64`.
pub const LANES: usize = 8;

/// The most channels a bank accepts: 2^20, beyond any deformable mirror (thousands of
/// actuators), so that every size stays far from overflow.
pub const MAX_CHANNELS: usize = 1 << 20;

/// The most values a bank's storage holds: 2^27 (1 GiB in `f64`), checked before anything is
/// allocated. Every channel takes the rows of the bank's largest model (a block of [`LANES`]
/// channels is one run of rows, so one model of many operators pads every other channel to
/// its size): channels rounded up to whole blocks, times the rows per channel
/// ([`plant_bank_rows`], [`dihc_bank_rows`]: five per operator plus the scalars and input
/// coefficients for IHC and WIHC). 4 096 channels of 10 operators take 250 000 values; a bank
/// of channels whose operator counts differ widely is better split into banks by size.
pub const MAX_BANK_VALUES: usize = 1 << 27;

/// Many compensators of one kind stepped together, one channel each (see the
/// [module documentation](self)).
///
/// Arrays of one value per channel are in channel order; a whole signal is sample after
/// sample (`desired[k * channels + c]` is channel `c` at sample `k`, the row-major layout of a
/// `samples x channels` array).
pub trait CompensatorBank<T: Real> {
    /// The number of channels `C`.
    fn channels(&self) -> usize;

    /// Every channel back to its initial state (as [`crate::Compensator::reset`]).
    fn reset(&mut self);

    /// One control tick: `control[c]` for `desired[c]`, every channel. Refuses arrays that do
    /// not hold one value per channel (without touching the state).
    fn step(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError>;

    /// A whole signal, sample after sample (`samples x channels`, row-major); refuses arrays
    /// of different lengths or not a multiple of the channel count (without touching the
    /// state).
    fn process(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError> {
        let channels = self.channels();
        check_signal(channels, desired.len(), control.len(), "controls")?;
        for (d, c) in desired
            .chunks_exact(channels.max(1))
            .zip(control.chunks_exact_mut(channels.max(1)))
        {
            self.step(d, c)?;
        }
        Ok(())
    }

    /// The output limits of `channel` (`None` beyond the last channel).
    fn limits(&self, channel: usize) -> Option<OutputLimits<T>>;

    /// The diagnostics of `channel` since the last reset (`None` beyond the last channel).
    fn diagnostics(&self, channel: usize) -> Option<Diagnostics>;
}

/// Why a bank could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum BankError {
    /// A channel's model or limits were refused: `channel` is its index (0-based).
    Channel {
        /// The channel's index.
        channel: usize,
        /// Why.
        error: CoreError,
    },
    /// The bank as a whole: no channel or more than [`MAX_CHANNELS`], limits for another
    /// number of channels, a fixed storage too small.
    Bank(CoreError),
}

impl BankError {
    /// The error itself, whichever channel it concerns.
    pub fn error(&self) -> &CoreError {
        match self {
            BankError::Channel { error, .. } | BankError::Bank(error) => error,
        }
    }

    /// The channel concerned, if one.
    pub fn channel(&self) -> Option<usize> {
        match self {
            BankError::Channel { channel, .. } => Some(*channel),
            BankError::Bank(_) => None,
        }
    }
}

impl fmt::Display for BankError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BankError::Channel { channel, error } => write!(f, "channel {channel}: {error}"),
            BankError::Bank(error) => write!(f, "{error}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for BankError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(self.error())
    }
}

impl From<CoreError> for BankError {
    fn from(error: CoreError) -> Self {
        BankError::Bank(error)
    }
}

/// Checks a bank's size: at least one lane per block (`lanes`, the bank's `W`), at least one
/// channel, at most [`MAX_CHANNELS`], and limits for one channel (shared) or for each.
pub(crate) fn check_bank_size(
    channels: usize,
    limits: usize,
    lanes: usize,
) -> Result<(), BankError> {
    if lanes == 0 {
        return Err(BankError::Bank(CoreError::NotPositive {
            what: "lanes per block (the bank's W)",
            index: None,
            value: 0.0,
        }));
    }
    if channels == 0 {
        return Err(BankError::Bank(CoreError::ChannelCount {
            what: "models",
            channels: 1,
            found: 0,
            samples: false,
        }));
    }
    if channels > MAX_CHANNELS {
        return Err(BankError::Bank(CoreError::TooLarge {
            what: "channels",
            found: channels,
            max: MAX_CHANNELS,
        }));
    }
    if limits != 1 && limits != channels {
        return Err(BankError::Bank(CoreError::ChannelCount {
            what: "output limits (one pair for every channel, or one for each)",
            channels,
            found: limits,
            samples: false,
        }));
    }
    Ok(())
}

/// The limits of `channel`: its own, or the only ones given.
pub(crate) fn limits_of<T: Real>(
    limits: &[OutputLimits<T>],
    channel: usize,
) -> Result<OutputLimits<T>, BankError> {
    limits
        .get(channel)
        .or_else(|| limits.first())
        .copied()
        .ok_or(BankError::Bank(CoreError::ChannelCount {
            what: "output limits",
            channels: channel + 1,
            found: limits.len(),
            samples: false,
        }))
}

/// Checks one tick's arrays: one value per channel each; `output` names the output array in
/// the message ("controls" in the core's normalised units, "drives" in volts).
pub fn check_tick(
    channels: usize,
    desired: usize,
    control: usize,
    output: &'static str,
) -> Result<(), CoreError> {
    for (what, found) in [("desired positions", desired), (output, control)] {
        if found != channels {
            return Err(CoreError::ChannelCount {
                what,
                channels,
                found,
                samples: true,
            });
        }
    }
    Ok(())
}

/// Checks a whole signal's arrays (`samples x channels`, row-major): equal lengths, a multiple
/// of the channel count; `output` names the output array as in [`check_tick`].
pub fn check_signal(
    channels: usize,
    desired: usize,
    control: usize,
    output: &'static str,
) -> Result<(), CoreError> {
    if !desired.is_multiple_of(channels.max(1)) {
        return Err(CoreError::ChannelCount {
            what: "desired positions",
            channels,
            found: desired,
            samples: true,
        });
    }
    if control != desired {
        return Err(CoreError::LengthMismatch {
            what: output,
            expected: desired,
            found: control,
        });
    }
    Ok(())
}
