//! The output guard (`crate::compensator::OutputGuard`) of every lane of a block: limits, the
//! previous output, the counters. The safety invariant (every output within its lane's limits,
//! never NaN) is enforced here, lane by lane, exactly as for one channel.

use super::lanes::{Lanes, Mask};
use super::storage::{Block, LOOP_SATURATED, NON_FINITE, SATURATED};
use crate::Real;

type L<T, const W: usize> = Lanes<T, W>;

/// The guard's state, loaded from a block's rows. The diagnostic counters are not loaded:
/// each sample raises a counter by at most one, so the guard collects the lanes it counts as
/// masks and [`GuardLanes::store`] adds them to the rows only when one is set (a rare event),
/// instead of reading and writing three rows of 64-bit counters every sample.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GuardLanes<T: Real, const W: usize> {
    pub min: L<T, W>,
    pub max: L<T, W>,
    pub previous: L<T, W>,
    saturated: Mask<T, W>,
    loop_saturated: Mask<T, W>,
    non_finite: Mask<T, W>,
    /// Whether [`GuardLanes::store`] clears the counters (after [`GuardLanes::reset`]).
    cleared: bool,
}

impl<T: Real, const W: usize> GuardLanes<T, W> {
    /// The guard with its limits and previous output in rows `min`, `max` and `previous` of
    /// `block`.
    #[inline(always)]
    pub fn load(block: &Block<'_, T, W>, min: usize, max: usize, previous: usize) -> Self {
        let none = Mask::splat(false);
        GuardLanes {
            min: block.get(min),
            max: block.get(max),
            previous: block.get(previous),
            saturated: none,
            loop_saturated: none,
            non_finite: none,
            cleared: false,
        }
    }

    /// Writes the previous output back to row `previous` and adds the sample's counts to the
    /// counters (cleared first after a reset).
    #[inline(always)]
    pub fn store(&self, block: &mut Block<'_, T, W>, previous: usize) {
        block.set(previous, self.previous);
        for (row, counted) in [
            (SATURATED, self.saturated),
            (LOOP_SATURATED, self.loop_saturated),
            (NON_FINITE, self.non_finite),
        ] {
            if self.cleared {
                block.set_counter(row, Lanes::splat(0));
            }
            if counted.any() {
                block.set_counter(row, block.counter(row) + counted.count());
            }
        }
    }

    /// The reset state: previous output 0 clamped into the limits, counters cleared.
    #[inline(always)]
    pub fn reset(&mut self) {
        let zero = Lanes::zero();
        self.previous = self.clamp_or(zero, zero);
        let none = Mask::splat(false);
        self.saturated = none;
        self.loop_saturated = none;
        self.non_finite = none;
        self.cleared = true;
    }

    /// `OutputGuard::accept`: the lanes whose desired position is finite; the others are
    /// counted (their output is the previous one).
    #[inline(always)]
    pub fn accept(&mut self, desired: L<T, W>) -> Mask<T, W> {
        let finite = desired.is_finite();
        self.non_finite = self.non_finite | !finite;
        finite
    }

    /// `OutputLimits::clamp_or` lane by lane.
    #[inline(always)]
    pub fn clamp_or(&self, value: L<T, W>, fallback: L<T, W>) -> L<T, W> {
        let value = fallback.or_keep(value.is_nan(), value);
        L::select(
            value.lt(self.min),
            self.min,
            L::select(
                value.gt(self.max),
                self.max,
                self.min.or_keep(value.is_nan(), value),
            ),
        )
    }

    /// The clamped output of `value` and whether the sample counts as clamped
    /// (`OutputGuard::emit_classified`'s condition: `limited`, a non-finite value, or a clamp
    /// beyond rounding).
    #[inline(always)]
    pub fn clamp(&self, value: L<T, W>, limited: Mask<T, W>) -> (L<T, W>, Mask<T, W>) {
        let out = self.clamp_or(value, self.previous);
        let rounding = Lanes::splat(T::epsilon() * T::from_f64(64.0))
            * value.abs().max(Lanes::splat(T::one()));
        let clamped = limited | !value.is_finite() | (out - value).abs().gt(rounding);
        (out, clamped)
    }

    /// Records the outputs of the lanes of `active`, counting their clamped samples as loop
    /// saturations where `reachable` is set and as saturations elsewhere.
    #[inline(always)]
    pub fn record(
        &mut self,
        out: L<T, W>,
        clamped: Mask<T, W>,
        reachable: Mask<T, W>,
        active: Mask<T, W>,
    ) -> L<T, W> {
        let counted = clamped & active;
        self.loop_saturated = self.loop_saturated | (counted & reachable);
        self.saturated = self.saturated | counted.and_not(reachable);
        self.previous = out.or_keep(active, self.previous);
        self.previous
    }

    /// Records `value`, proven within the limits before it was computed, as the output of the
    /// lanes of `active`: clamped all the same ([`GuardLanes::clamp_or`]: the limits hold
    /// whatever the proof), nothing counted as clamped (within the limits, the clamp keeps
    /// `value`, as [`GuardLanes::clamp`] would). Returns every lane's output.
    #[inline(always)]
    pub fn record_within(&mut self, value: L<T, W>, active: Mask<T, W>) -> L<T, W> {
        self.previous = self
            .clamp_or(value, self.previous)
            .or_keep(active, self.previous);
        self.previous
    }

    /// `OutputGuard::emit` for the lanes of `active`: clamps, counts, records. Returns every
    /// lane's output (the previous one for the lanes not active).
    #[inline(always)]
    pub fn emit(&mut self, value: L<T, W>, limited: Mask<T, W>, active: Mask<T, W>) -> L<T, W> {
        let (out, clamped) = self.clamp(value, limited);
        self.record(out, clamped, Mask::splat(false), active)
    }
}
