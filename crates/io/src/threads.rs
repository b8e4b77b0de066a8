//! Threads for very large banks (issue 16; feature `parallel`, off by default): a bank's
//! channels split into parts of whole blocks, each part a bank of its own, stepped on rayon's
//! threads.
//!
//! Each channel of a core bank depends on its own lane only, so a part of channels `a..b`
//! gives channel `c` the same bits as the whole bank does; splitting at whole blocks of
//! [`LANES`] channels keeps every part's blocks full.
//!
//! **Off by default: tick by tick, it does not pay at the tick sizes of issue 16.** Measured
//! with `cargo bench -p hystcomp-io --features parallel --bench threads_probe` (the plain bank
//! and a `ThreadedBank` of two parts, runs interleaved, wall time per channel-step, median of
//! nine; the channels and signal of `hystcomp bench --channels`, 400 ticks at 4 096 channels,
//! 1 000 (IHC) or 2 000 (DIHC) at 1 024) on this project's shared
//! 2-core Intel Xeon (AVX-512, load average 1.3-1.4 from other work):
//!
//! | bank | plain, by tick | threads, by tick | threads, whole signal |
//! | --- | --- | --- | --- |
//! | exact IHC f32, 4 096 channels | 13.6 ns | 23.2 ns (best run 16.3) | 7.2 ns |
//! | exact IHC f64, 4 096 channels | 25.0 ns | 29.1 ns (25.3) | 11.4 ns |
//! | delayed IHC f32, 4 096 channels | 7.5 ns | 16.7 ns (12.5) | 4.3 ns |
//! | DIHC f32, 4 096 channels | 3.1 ns | 10.4 ns (8.5) | 3.3 ns (1.7) |
//! | exact IHC f32, 1 024 channels | 14.1 ns | 39.7 ns (19.4) | 7.5 ns |
//! | DIHC f32, 1 024 channels | 3.2 ns | 22.5 ns (16.8) | 2.1 ns |
//!
//! [`ThreadedBank::step`] forks and joins once per tick: a tick of 4 096 exact IHC channels is
//! about 56 us of work, and the fork, the join and waiting for the slower of two threads on a
//! machine that also runs other work cost more than the second core gives back, at every tick
//! size measured. [`ThreadedBank::process`] forks once for a whole signal (each part runs every
//! tick of its channels) and nearly halves the time of the heavier kernels (exact IHC 1.9x in
//! f32, 2.2x in f64): it pays offline, for a known trajectory of many channels, not for a
//! controller stepping tick by tick. Measure on the target machine (its own cores, a thread
//! pool pinned and spinning rather than rayon's) before using it in a control loop.

use std::ops::Range;

use hystcomp_core::{
    BankError, CompensatorBank, CoreError, Diagnostics, LANES, OutputLimits, Real, check_signal,
    check_tick,
};
use rayon::prelude::*;

/// A bank split into parts of whole blocks, stepped in parallel (see the
/// [module documentation](self)). It is itself a [`CompensatorBank`]: channel `c` gives what
/// the unsplit bank's channel `c` gives, bit for bit.
#[derive(Debug, Clone)]
pub struct ThreadedBank<B> {
    parts: Vec<B>,
    /// Channels per part (every part but the last), a multiple of [`LANES`].
    part_channels: usize,
    channels: usize,
}

impl<B> ThreadedBank<B> {
    /// `channels` channels in `parts` parts (at least one, at most one per block of
    /// [`LANES`] channels): `build(range)` makes the bank of the channels in `range` (e.g. a
    /// core bank of `models[range]`). Its first error is returned, a refused channel named by
    /// its index in the whole bank (`build` names it within its part).
    pub fn new(
        channels: usize,
        parts: usize,
        mut build: impl FnMut(Range<usize>) -> Result<B, BankError>,
    ) -> Result<Self, BankError> {
        let blocks = channels.div_ceil(LANES).max(1);
        let parts = parts.clamp(1, blocks);
        let part_channels = blocks.div_ceil(parts) * LANES;
        let mut built = Vec::with_capacity(parts);
        let mut start = 0;
        while start < channels {
            let end = (start + part_channels).min(channels);
            let part = build(start..end).map_err(|error| match error {
                BankError::Channel { channel, error } => BankError::Channel {
                    channel: channel + start,
                    error,
                },
                other => other,
            })?;
            built.push(part);
            start = end;
        }
        Ok(ThreadedBank {
            parts: built,
            part_channels,
            channels,
        })
    }

    /// The number of parts.
    pub fn parts(&self) -> usize {
        self.parts.len()
    }

    /// The part holding `channel` and the channel's index within it.
    fn locate(&self, channel: usize) -> Option<(&B, usize)> {
        if channel >= self.channels {
            return None;
        }
        let part = self.parts.get(channel / self.part_channels)?;
        Some((part, channel % self.part_channels))
    }
}

impl<T: Real, B: CompensatorBank<T> + Send> CompensatorBank<T> for ThreadedBank<B> {
    fn channels(&self) -> usize {
        self.channels
    }

    fn reset(&mut self) {
        self.parts.par_iter_mut().for_each(|p| p.reset());
    }

    /// One tick, every part on its own thread (one fork and join per tick).
    fn step(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError> {
        check_tick(self.channels, desired.len(), control.len(), "controls")?;
        self.parts
            .par_iter_mut()
            .zip(desired.par_chunks(self.part_channels))
            .zip(control.par_chunks_mut(self.part_channels))
            .try_for_each(|((part, d), c)| part.step(d, c))
    }

    /// A whole signal (`samples x channels`, row-major): every part runs all the ticks of its
    /// channels on its own thread (one fork and join per signal).
    fn process(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError> {
        let channels = self.channels;
        check_signal(channels, desired.len(), control.len(), "controls")?;
        // Every part's slice of every row of the controls, disjoint.
        let mut columns: Vec<Vec<&mut [T]>> = self.parts.iter().map(|_| Vec::new()).collect();
        for row in control.chunks_exact_mut(channels.max(1)) {
            for (piece, column) in row.chunks_mut(self.part_channels).zip(columns.iter_mut()) {
                column.push(piece);
            }
        }
        let part_channels = self.part_channels;
        self.parts
            .par_iter_mut()
            .zip(columns.into_par_iter())
            .enumerate()
            .try_for_each(|(p, (part, column))| {
                let start = p * part_channels;
                for (row, c) in desired.chunks_exact(channels.max(1)).zip(column) {
                    let end = (start + c.len()).min(row.len());
                    let d = row.get(start..end).unwrap_or_default();
                    part.step(d, c)?;
                }
                Ok(())
            })
    }

    fn limits(&self, channel: usize) -> Option<OutputLimits<T>> {
        let (part, c) = self.locate(channel)?;
        part.limits(c)
    }

    fn diagnostics(&self, channel: usize) -> Option<Diagnostics> {
        let (part, c) = self.locate(channel)?;
        part.diagnostics(c)
    }
}
