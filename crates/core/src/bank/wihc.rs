//! A bank of WIHC channels (section 3.2, eq. (9)): [`crate::Wihc`] lane by lane.

use super::channels::{Channels, compensator_bank};
use super::ihc::rounding_tolerance;
use super::lanes::{Lanes, Mask};
use super::plant::{PlantKernel, guarded_target, plant_bank, with_remainder, write_lane};
use super::play::{
    LaneEquation, LaneSolution, PlayState, ReachOnly, feed, feed_solved_or_full, feed_uncounted,
    recount, solve,
};
use super::root::{LaneRemainder, increasing_root};
use super::run::{BankKernel, BlockKernel, run};
use super::storage::{BankStorage, Block, PlantRows};
use super::{BankError, LANES};
use crate::{Buffer, Mpim, OutputLimits, Real, SolveMode, Wihc};

type L<T, const W: usize> = Lanes<T, W>;

/// WIHC for many channels at once: channel `c` is [`crate::Wihc`] built from `plants[c]` with
/// its limits and the bank's solve mode, and gives the same outputs, bit for bit (see the
/// [module documentation](super)).
#[derive(Debug, Clone)]
pub struct WihcBank<T: Real, S: BankStorage<T, W>, const W: usize = LANES> {
    channels: Channels<T, S, WihcKernel, W>,
}

/// Marks the [`PlantKernel`] of a WIHC bank.
#[derive(Debug, Clone, Copy)]
pub(crate) struct WihcMethod;

type WihcKernel = PlantKernel<WihcMethod>;

impl<T: Real, S: BankStorage<T, W>, const W: usize> WihcBank<T, S, W> {
    /// A bank of one WIHC per plant model, with `limits` for every channel (one pair shared by
    /// all, or one per channel) and one solve mode for all. Each channel is checked as
    /// [`crate::Wihc::new`] checks it; a refused one is named by its index.
    pub fn new<B: Buffer<T>>(
        plants: &[Mpim<T, B>],
        limits: &[OutputLimits<T>],
        mode: SolveMode,
    ) -> Result<Self, BankError> {
        let channels = plant_bank(
            plants,
            limits,
            mode,
            |plant, limits, mode| Wihc::<T, B>::new(plant, limits, mode),
            |blocks, rows, lane, c: &Wihc<T, B>| {
                write_lane(
                    blocks,
                    rows,
                    lane,
                    &c.bank,
                    &c.input,
                    c.relaxation,
                    &c.guard,
                )
            },
        )?;
        Ok(WihcBank { channels })
    }

    /// The solve mode of every channel.
    pub fn mode(&self) -> SolveMode {
        self.channels.mode()
    }

    /// The under-relaxation `mu` of [`SolveMode::DelayedGuarded`] of `channel` (see
    /// [`crate::Wihc::guard_relaxation`]).
    pub fn guard_relaxation(&self, channel: usize) -> Option<T> {
        self.channels.relaxation(channel)
    }
}

compensator_bank!(WihcBank);

/// Eq. (9) on one segment of every lane (`crate::wihc::Eq9`), in the voltage itself:
/// `h(v) + alpha v + beta = y_d`.
struct Eq9<T, R, const W: usize> {
    remainder: R,
    desired: L<T, W>,
}

impl<T: Real, R: LaneRemainder<T, W>, const W: usize> LaneEquation<T, W> for Eq9<T, R, W> {
    const INVERSE_ALPHA: bool = false;
    #[inline(always)]
    fn residual(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        self.remainder.with_linear(x, alpha) + beta - self.desired
    }
    #[inline(always)]
    fn control(&self, x: L<T, W>, _alpha: L<T, W>, _beta: L<T, W>) -> L<T, W> {
        x
    }
    #[inline(always)]
    fn input_at_control(&self, v: L<T, W>, _alpha: L<T, W>, _beta: L<T, W>) -> L<T, W> {
        v
    }
    #[inline(always)]
    fn rounding(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        let terms = self.remainder.size(x) + (alpha * x).abs() + beta.abs() + self.desired.abs();
        rounding_tolerance(terms)
    }
    #[inline(always)]
    fn root(
        &self,
        lo: L<T, W>,
        hi: L<T, W>,
        f_lo: L<T, W>,
        f_hi: L<T, W>,
        alpha: L<T, W>,
        beta: L<T, W>,
        _inv: L<T, W>,
        active: Mask<T, W>,
    ) -> L<T, W> {
        increasing_root(
            self.remainder,
            alpha,
            beta - self.desired,
            lo,
            hi,
            f_lo,
            f_hi,
            active,
        )
    }
}

/// The guarded loop's step on one segment of every lane (`crate::wihc::BankOutput`): the
/// plant's PI part `alpha v + beta` brought to `target`, in the voltage itself.
struct BankOutput<T, const W: usize> {
    target: L<T, W>,
}

impl<T: Real, const W: usize> LaneEquation<T, W> for BankOutput<T, W> {
    #[inline(always)]
    fn residual(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        alpha * x + beta - self.target
    }
    #[inline(always)]
    fn control(&self, x: L<T, W>, _alpha: L<T, W>, _beta: L<T, W>) -> L<T, W> {
        x
    }
    #[inline(always)]
    fn input_at_control(&self, v: L<T, W>, _alpha: L<T, W>, _beta: L<T, W>) -> L<T, W> {
        v
    }
    #[inline(always)]
    fn root(
        &self,
        lo: L<T, W>,
        hi: L<T, W>,
        _f_lo: L<T, W>,
        _f_hi: L<T, W>,
        _alpha: L<T, W>,
        beta: L<T, W>,
        inv_alpha: L<T, W>,
        _active: Mask<T, W>,
    ) -> L<T, W> {
        ((self.target - beta) * inv_alpha).max(lo).min(hi)
    }
}

impl PlantKernel<WihcMethod> {
    /// One sample of every lane with the remainder `h` (`crate::wihc::wihc_step`).
    #[inline(always)]
    fn step_with<T: Real, R: LaneRemainder<T, W>, const W: usize>(
        &self,
        block: &mut Block<'_, T, W>,
        desired: L<T, W>,
        remainder: R,
    ) -> L<T, W> {
        let rows = &self.rows;
        let mut guard = self.guard(block);
        let mut state = PlayState::load(block, rows);
        let active = guard.accept(desired);
        let v_prev = state.input;
        let equation = Eq9 { remainder, desired };
        let out = if matches!(self.mode, SolveMode::Exact | SolveMode::DelayedGuarded) {
            // Each mode solves for the sample; one memory update follows (one copy of it in
            // the compiled kernel for both).
            let (s, v) = if self.mode == SolveMode::Exact {
                let f_prev = remainder.value(v_prev) + state.output() - desired;
                let s = solve(
                    block, rows, &state, &equation, f_prev, guard.min, guard.max, active,
                );
                (s, guard.emit(s.input, s.saturated, active))
            } else {
                // `crate::wihc::wihc_step`: beyond reach, the exact solution's limit at once,
                // counted; otherwise the plant's PI part brought to P1(t - Ts) + mu e(t).
                let h_prev = remainder.value(v_prev);
                let p1_prev = state.output();
                let f_prev = h_prev + p1_prev - desired;
                let reach = solve(
                    block,
                    rows,
                    &state,
                    &ReachOnly(&equation),
                    f_prev,
                    guard.min,
                    guard.max,
                    active,
                );
                let beyond = reach.saturated & active;
                let target = guarded_target(block, rows, p1_prev, f_prev, desired, h_prev);
                let stepping = active.and_not(beyond);
                let step = solve(
                    block,
                    rows,
                    &state,
                    &BankOutput { target },
                    p1_prev - target,
                    guard.min,
                    guard.max,
                    stepping,
                );
                let s = reach.select(beyond, step);
                let (out, clamped) = guard.clamp(s.input, s.saturated | beyond);
                (s, guard.record(out, clamped, !beyond, active))
            };
            // The solved segment's state when the output is the solution; a full feed of the
            // clamped output otherwise.
            let changed = v.compare(s.input, |a, b| a != b);
            let fed = LaneSolution { input: v, ..s };
            feed_solved_or_full(block, rows, &mut state, &fed, active, changed, self.uniform);
            v
        } else {
            // H[v](t - Ts) = h(v(t - Ts)) + sum b_i F_{r_i}[v](t - Ts).
            let h_prev = remainder.value(v_prev) + state.memory_sum;
            let next = (desired - h_prev) * state.inverse_a;
            let (out, clamped) = guard.clamp(next, Mask::splat(false));
            // A clamped sample counts as a loop saturation when the exact eq. (9) could have
            // been met within the limits from the same state (solved only then).
            let check = clamped & active;
            let mut reachable = Mask::splat(false);
            if check.any() {
                // The feeds below do not count the operators at the edges: the walk's counts
                // from the memory (the same as a counting feed leaves).
                recount(block, rows, &mut state, check);
                let f_prev = remainder.value(v_prev) + state.output() - desired;
                let s = solve(
                    block, rows, &state, &equation, f_prev, guard.min, guard.max, check,
                );
                reachable = check.and_not(s.saturated);
            }
            let v = guard.record(out, clamped, reachable, active);
            // The memory and its weighted sum only: the counts of operators at the edges,
            // which only the walk above reads, are recomputed before it runs.
            feed_uncounted(block, rows, &mut state, v, active, self.uniform);
            v
        };
        state.store(block, rows);
        guard.store(block, rows.scalar(PlantRows::PREVIOUS));
        out
    }
}

impl<T: Real, const W: usize> BlockKernel<T, W> for PlantKernel<WihcMethod> {
    const HEAD: usize = PlantRows::HEAD;
    const COUNTS: usize = PlantRows::COUNTS;

    #[inline(always)]
    fn step(&self, block: &mut Block<'_, T, W>, desired: L<T, W>) -> L<T, W> {
        with_remainder!(self, block, PlantRows, |remainder| self
            .step_with(block, desired, remainder))
    }
}

impl<T: Real, const W: usize> BankKernel<T, W> for PlantKernel<WihcMethod> {
    /// `Wihc::reset` for every lane of a block.
    fn reset_block(&self, block: &mut Block<'_, T, W>) {
        let rows = &self.rows;
        let mut guard = self.guard(block);
        let mut state = PlayState::load(block, rows);
        super::play::reset(block, rows, &mut state);
        guard.reset();
        // 0 outside the limits: the compensator starts at the nearest limit, the plant with it.
        let v0 = guard.previous;
        let away = v0.compare(Lanes::zero(), |a, b| a != b);
        if away.any() {
            feed(block, rows, &mut state, v0, away, self.uniform);
        }
        state.store(block, rows);
        guard.store(block, rows.scalar(PlantRows::PREVIOUS));
    }

    fn limit_rows(&self) -> (usize, usize) {
        self.rows.limits()
    }

    fn run_tick<'a>(
        &self,
        blocks: impl Iterator<Item = Block<'a, T, W>>,
        desired: &[T],
        control: &mut [T],
    ) where
        T: 'a,
    {
        run(self, blocks, desired, control)
    }
}
