//! What every bank is besides its kernel: the blocks of lanes, the kernel that steps them and
//! the number of channels, with the [`CompensatorBank`] methods written once for
//! [`super::IhcBank`], [`super::WihcBank`] and [`super::DihcBank`].

use super::run::BankKernel;
use super::storage::{BankStorage, Blocks, LOOP_SATURATED, NON_FINITE, SATURATED};
use super::{CompensatorBank, check_tick};
use crate::{CoreError, Diagnostics, OutputLimits, Real};

/// A bank's channels: `count` channels in `blocks` of `W` lanes, stepped by `kernel`.
#[derive(Debug, Clone)]
pub(crate) struct Channels<T: Real, S: BankStorage<T, W>, K, const W: usize> {
    pub blocks: Blocks<T, S, W>,
    pub kernel: K,
    pub count: usize,
}

impl<T: Real, S: BankStorage<T, W>, K, const W: usize> Channels<T, S, K, W> {
    /// The value of row `row` of `channel` (`None` beyond the last channel).
    pub fn value(&self, channel: usize, row: usize) -> Option<T> {
        (channel < self.count).then(|| self.blocks.value(channel, row))
    }
}

impl<T: Real, S: BankStorage<T, W>, K: BankKernel<T, W>, const W: usize> CompensatorBank<T>
    for Channels<T, S, K, W>
{
    fn channels(&self) -> usize {
        self.count
    }

    fn reset(&mut self) {
        for mut block in self.blocks.blocks_mut() {
            self.kernel.reset_block(&mut block);
        }
    }

    #[inline]
    fn step(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError> {
        check_tick(self.count, desired.len(), control.len(), "controls")?;
        self.kernel
            .run_tick(self.blocks.blocks_mut(), desired, control);
        Ok(())
    }

    fn limits(&self, channel: usize) -> Option<OutputLimits<T>> {
        let (min_row, max_row) = self.kernel.limit_rows();
        let min = self.value(channel, min_row)?;
        let max = self.value(channel, max_row)?;
        OutputLimits::new(min, max).ok()
    }

    fn diagnostics(&self, channel: usize) -> Option<Diagnostics> {
        (channel < self.count).then(|| Diagnostics {
            saturated: self.blocks.counter(channel, SATURATED),
            loop_saturated: self.blocks.counter(channel, LOOP_SATURATED),
            non_finite: self.blocks.counter(channel, NON_FINITE),
        })
    }
}

/// [`CompensatorBank`] for a bank type whose field `channels` is a [`Channels`]: every method
/// passed on to it.
macro_rules! compensator_bank {
    ($bank:ident) => {
        impl<T: $crate::Real, S: $crate::BankStorage<T, W>, const W: usize>
            $crate::CompensatorBank<T> for $bank<T, S, W>
        {
            fn channels(&self) -> usize {
                $crate::CompensatorBank::channels(&self.channels)
            }

            fn reset(&mut self) {
                $crate::CompensatorBank::reset(&mut self.channels)
            }

            #[inline]
            fn step(&mut self, desired: &[T], control: &mut [T]) -> Result<(), $crate::CoreError> {
                $crate::CompensatorBank::step(&mut self.channels, desired, control)
            }

            fn limits(&self, channel: usize) -> Option<$crate::OutputLimits<T>> {
                $crate::CompensatorBank::limits(&self.channels, channel)
            }

            fn diagnostics(&self, channel: usize) -> Option<$crate::Diagnostics> {
                $crate::CompensatorBank::diagnostics(&self.channels, channel)
            }
        }
    };
}

pub(crate) use compensator_bank;
