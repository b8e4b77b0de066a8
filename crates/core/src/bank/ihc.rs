//! A bank of IHC channels (section 3.1, eqs. (5)-(8)): [`crate::Ihc`] lane by lane.

use super::channels::{Channels, compensator_bank};
use super::lanes::{Lanes, Mask};
use super::plant::{PlantKernel, guarded_target, plant_bank, with_remainder, write_lane};
use super::play::{
    LaneEquation, PlayState, ReachOnly, feed, feed_solved, feed_uncounted, memory_sum_at, recount,
    solve, update_memory_with,
};
use super::root::{LaneRemainder, increasing_root};
use super::run::{BankKernel, BlockKernel, run};
use super::storage::{BankStorage, Block, OperatorTables, PlantRows};
use super::within::{LastInput, proven_reachable, proven_within};
use super::{BankError, LANES};
use crate::{Buffer, Ihc, Mpim, OutputLimits, Real, SolveMode};

type L<T, const W: usize> = Lanes<T, W>;

/// IHC for many channels at once: channel `c` is [`crate::Ihc`] built from `plants[c]` with
/// its limits and the bank's solve mode, and gives the same outputs, bit for bit (see the
/// [module documentation](super)).
///
/// ```
/// use hystcomp_core::{CompensatorBank, Heap, IhcBank, OutputLimits, SolveMode, paper};
///
/// let plants = [paper::TABLE1.model::<f64, Vec<f64>>()?, paper::TABLE1.spread(20)?];
/// let limits = [OutputLimits::new(0.0, 1.0)?];
/// let mut bank: IhcBank<f64, Heap> = IhcBank::new(&plants, &limits, SolveMode::Exact)?;
/// let mut control = [0.0; 2];
/// bank.step(&[0.3, 0.5], &mut control)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct IhcBank<T: Real, S: BankStorage<T, W>, const W: usize = LANES> {
    channels: Channels<T, S, IhcKernel, W>,
}

/// Marks the [`PlantKernel`] of an IHC bank.
#[derive(Debug, Clone, Copy)]
pub(crate) struct IhcMethod;

type IhcKernel = PlantKernel<IhcMethod>;

impl<T: Real, S: BankStorage<T, W>, const W: usize> IhcBank<T, S, W> {
    /// A bank of one IHC per plant model, with `limits` for every channel (one pair shared by
    /// all, or one per channel) and one solve mode for all. Each channel is checked as
    /// [`crate::Ihc::new`] checks it; a refused one is named by its index.
    pub fn new<B: Buffer<T>>(
        plants: &[Mpim<T, B>],
        limits: &[OutputLimits<T>],
        mode: SolveMode,
    ) -> Result<Self, BankError> {
        let channels = plant_bank(
            plants,
            limits,
            mode,
            |plant, limits, mode| Ihc::<T, B>::new(plant, limits, mode),
            |blocks, rows, lane, c: &Ihc<T, B>| {
                write_lane(
                    blocks,
                    rows,
                    lane,
                    &c.inverse,
                    &c.input,
                    c.relaxation,
                    &c.guard,
                )
            },
        )?;
        Ok(IhcBank { channels })
    }

    /// The solve mode of every channel.
    pub fn mode(&self) -> SolveMode {
        self.channels.mode()
    }

    /// The under-relaxation `mu` of [`SolveMode::DelayedGuarded`] of `channel` (see
    /// [`crate::Ihc::guard_relaxation`]).
    pub fn guard_relaxation(&self, channel: usize) -> Option<T> {
        self.channels.relaxation(channel)
    }
}

compensator_bank!(IhcBank);

/// Exact IHC on one segment of every lane (`crate::ihc::Eq5Exact`):
/// `w + h(alpha w + beta) = y_d`.
struct Eq5Exact<T, R, const W: usize> {
    remainder: R,
    desired: L<T, W>,
}

impl<T: Real, R: LaneRemainder<T, W>, const W: usize> LaneEquation<T, W> for Eq5Exact<T, R, W> {
    #[inline(always)]
    fn residual(&self, w: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        let v = alpha * w + beta;
        w + self.remainder.value(v) - self.desired
    }
    #[inline(always)]
    fn rounding(&self, w: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        let v = alpha * w + beta;
        let terms = w.abs() + self.remainder.size(v) + self.desired.abs();
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
        inv_alpha: L<T, W>,
        active: Mask<T, W>,
    ) -> L<T, W> {
        let v = increasing_root(
            self.remainder,
            inv_alpha,
            -beta * inv_alpha - self.desired,
            alpha * lo + beta,
            alpha * hi + beta,
            f_lo,
            f_hi,
            active,
        );
        ((v - beta) * inv_alpha).max(lo).min(hi)
    }
}

/// The lanes whose delayed and guarded loops evaluate `P1^{-1}[w]` directly: those of at most
/// [`crate::DIRECT_OPERATORS`] operators, as their single compensators do.
#[inline(always)]
fn evaluate_directly<T: Real, const W: usize>(state: &PlayState<T, W>) -> Mask<T, W> {
    state
        .operators
        .test(|n| n as usize <= crate::DIRECT_OPERATORS)
}

/// The operator tables the direct evaluation passes over: the block's, or none when no lane of
/// `direct` evaluates directly (a block of many-operator channels, which only walk). Chosen as
/// a value, not a branch around the passes: the branch made the guarded IHC's step 10-20 %
/// slower at 10 operators, and the plain delayed loop's in f64 a third slower (in f32 the
/// delayed loop is faster with the branch).
#[inline(always)]
fn direct_tables<T: Real, const W: usize>(rows: &PlantRows, direct: Mask<T, W>) -> OperatorTables {
    let tables = rows.operators();
    if direct.any() {
        tables
    } else {
        OperatorTables { n: 0, ..tables }
    }
}

/// The guarded loop's reach test (`crate::ihc::guarded_reach` lane by lane).
struct GuardedReach<T, const W: usize> {
    min: L<T, W>,
    max: L<T, W>,
    least_inverse_alpha: L<T, W>,
}

impl<T: Real, const W: usize> GuardedReach<T, W> {
    /// The lanes whose step to `w`, with `v = P1^{-1}[w]`, proves `y_d` within reach.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn proves<R: LaneRemainder<T, W>>(
        &self,
        remainder: R,
        desired: L<T, W>,
        f_exact: L<T, W>,
        w_prev: L<T, W>,
        w: L<T, W>,
        v: L<T, W>,
    ) -> Mask<T, W> {
        let zero = Lanes::zero();
        let (min, max, least) = (self.min, self.max, self.least_inverse_alpha);
        let inside = v.ge(min) & v.le(max);
        let f_w = w + remainder.value(v) - desired;
        let up = w + least * (max - v) + remainder.value(max) - desired;
        let down = w - least * (v - min) + remainder.value(min) - desired;
        let rises = w.ge(w_prev) & (f_w.ge(zero) | up.ge(zero));
        let falls = w.le(w_prev) & (f_w.le(zero) | down.le(zero));
        inside & Mask::choose(f_exact.le(zero), rises, falls)
    }
}

/// `crate::walk::rounding_tolerance` lane by lane: `256 eps (1 + terms)`.
#[inline(always)]
pub(crate) fn rounding_tolerance<T: Real, const W: usize>(terms: L<T, W>) -> L<T, W> {
    Lanes::splat(T::epsilon() * T::from_f64(256.0)) * (Lanes::splat(T::one()) + terms)
}

/// Delayed IHC on one segment (`crate::ihc::Eq5Delayed`): `w` is known.
struct Eq5Delayed<T, const W: usize> {
    w: L<T, W>,
}

impl<T: Real, const W: usize> LaneEquation<T, W> for Eq5Delayed<T, W> {
    const INVERSE_ALPHA: bool = false;
    #[inline(always)]
    fn residual(&self, w: L<T, W>, _alpha: L<T, W>, _beta: L<T, W>) -> L<T, W> {
        w - self.w
    }
    #[inline(always)]
    fn root(
        &self,
        lo: L<T, W>,
        hi: L<T, W>,
        _f_lo: L<T, W>,
        _f_hi: L<T, W>,
        _alpha: L<T, W>,
        _beta: L<T, W>,
        _inv: L<T, W>,
        _active: Mask<T, W>,
    ) -> L<T, W> {
        self.w.max(lo).min(hi)
    }
}

/// The `w` where `P1^{-1}[w] = control` (`crate::ihc::ReachControl`), to start at a limit.
struct ReachControl<T, const W: usize> {
    control: L<T, W>,
}

impl<T: Real, const W: usize> LaneEquation<T, W> for ReachControl<T, W> {
    #[inline(always)]
    fn residual(&self, w: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        alpha * w + beta - self.control
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
        ((self.control - beta) * inv_alpha).max(lo).min(hi)
    }
}

impl PlantKernel<IhcMethod> {
    /// `crate::walk::PlayBank::output_at` in every lane: the operators' memory sum at `w` over
    /// `tables` (none: 0), and `P1^{-1}[w] = a w + sum`.
    #[inline(always)]
    fn evaluate<T: Real, const W: usize>(
        &self,
        block: &mut Block<'_, T, W>,
        tables: OperatorTables,
        state: &PlayState<T, W>,
        w: L<T, W>,
    ) -> (L<T, W>, L<T, W>) {
        let sum = memory_sum_at(block, tables, state.operators, w, self.uniform);
        (sum, state.a * w + sum)
    }

    /// `crate::walk::PlayBank::feed` of `w` in the lanes of `lanes`, evaluated before with
    /// [`Self::evaluate`] to `sum`: their memory, last input and memory sum (the counts left
    /// unused, recounted before a walk).
    #[inline(always)]
    fn feed_evaluated<T: Real, const W: usize>(
        &self,
        block: &mut Block<'_, T, W>,
        tables: OperatorTables,
        state: &mut PlayState<T, W>,
        w: L<T, W>,
        sum: L<T, W>,
        lanes: Mask<T, W>,
    ) {
        update_memory_with::<_, _, false, false>(
            block,
            tables,
            state.operators,
            w,
            lanes,
            self.uniform,
        );
        state.record_input(w, sum, lanes);
    }

    /// The delayed loops' sample in one pass over the operators (as the DIHC's), when
    /// [`proven_within`] proves every active lane's `v = P1^{-1}[w]` within its limits before
    /// the evaluation, every active lane evaluates directly and, in the guarded loop
    /// (`MODE == GUARDED`), [`proven_reachable`] proves its reach test; `None`, the block
    /// unchanged, otherwise. The same bits as the two passes of [`Self::step_with`]: the pass
    /// feeding `w` computes the sum the first of those would, `v` is within the limits, and
    /// the guarded loop's lanes are those its reach test settles.
    #[inline(always)]
    fn delayed_in_one_pass<T: Real, R: LaneRemainder<T, W>, const W: usize, const MODE: u8>(
        &self,
        block: &mut Block<'_, T, W>,
        desired: L<T, W>,
        remainder: R,
    ) -> Option<L<T, W>> {
        let rows = &self.rows;
        let mut guard = self.guard(block);
        let active = guard.accept(desired);
        if !active.any() {
            return None;
        }
        let mut state = PlayState::load(block, rows);
        let last = LastInput {
            output: state.output(),
            input: state.input,
            least_inverse_alpha: block.get(rows.scalar(PlantRows::LEAST_INVERSE_ALPHA)),
            slope_sum: block.get(rows.scalar(PlantRows::SLOPE_SUM)),
            reach_sum: block.get(rows.scalar(PlantRows::REACH_SUM)),
        };
        let h_prev = remainder.value(guard.previous);
        let mut proven = evaluate_directly(&state);
        // w(t) = y_d(t) - h(v(t - Ts)) (the guarded loop's under-relaxed target), as the two
        // passes compute it.
        let w = if MODE == GUARDED {
            let f_exact = state.input + h_prev - desired;
            let w = guarded_target(block, rows, state.input, f_exact, desired, h_prev);
            let (h_min, h_max) = (remainder.value(guard.min), remainder.value(guard.max));
            proven = proven
                & proven_reachable(
                    &last, w, desired, f_exact, h_min, h_max, guard.min, guard.max,
                );
            w
        } else {
            let w = desired - h_prev;
            proven = proven & proven_within(&last, w, guard.min, guard.max);
            w
        };
        if active.and_not(proven).any() {
            return None;
        }
        let sum = feed_uncounted(block, rows, &mut state, w, active, self.uniform);
        let out = guard.record_within(state.a * w + sum, active);
        state.store_evaluated(block, rows);
        guard.store(block, rows.scalar(PlantRows::PREVIOUS));
        Some(out)
    }

    /// One sample of every lane with the remainder `h` (`crate::ihc::ihc_step`).
    #[inline(always)]
    fn step_with<T: Real, R: LaneRemainder<T, W>, const W: usize, const MODE: u8>(
        &self,
        block: &mut Block<'_, T, W>,
        desired: L<T, W>,
        remainder: R,
    ) -> L<T, W> {
        let rows = &self.rows;
        if MODE != EXACT
            && let Some(out) = self.delayed_in_one_pass::<_, _, W, MODE>(block, desired, remainder)
        {
            return out;
        }
        let mut guard = self.guard(block);
        let mut state = PlayState::load(block, rows);
        let active = guard.accept(desired);
        let v_prev = guard.previous;
        let w_prev = state.input;
        let h_prev = remainder.value(v_prev);
        let exact = Eq5Exact { remainder, desired };
        let f_exact = w_prev + h_prev - desired;
        let out = if MODE == EXACT {
            let solution = solve(
                block, rows, &state, &exact, f_exact, guard.min, guard.max, active,
            );
            let v = feed_solved(block, rows, &mut state, &solution, active, self.uniform);
            guard.emit(v, solution.saturated, active)
        } else if MODE == GUARDED {
            // w(t - Ts) + mu (y_d - w(t - Ts) - h(v(t - Ts))); with mu = 1, y_d - h(v(t - Ts)).
            let w = guarded_target(block, rows, w_prev, f_exact, desired, h_prev);
            // v = P1^{-1}[w] evaluated directly in the lanes of few operators, kept where it
            // proves y_d within reach (`crate::ihc::guarded_reach`).
            let direct_lanes = active & evaluate_directly(&state);
            let tables = direct_tables(rows, direct_lanes);
            let (sum, mut v) = self.evaluate(block, tables, &state, w);
            let least = block.get(rows.scalar(PlantRows::LEAST_INVERSE_ALPHA));
            let reach = GuardedReach {
                min: guard.min,
                max: guard.max,
                least_inverse_alpha: least,
            };
            let settled = direct_lanes & reach.proves(remainder, desired, f_exact, w_prev, w, v);
            let walking = active.and_not(settled);
            let mut limited = Mask::splat(false);
            let mut beyond = Mask::splat(false);
            if walking.any() {
                // The walks, from the counts of the memory as it is (recounted where direct
                // evaluations left them unused). Beyond reach: the exact solution's limit at
                // once, counted (`crate::ihc::ihc_step`).
                recount(block, rows, &mut state, walking & direct_lanes);
                let reach = solve(
                    block,
                    rows,
                    &state,
                    &ReachOnly(&exact),
                    f_exact,
                    guard.min,
                    guard.max,
                    walking,
                );
                beyond = reach.saturated & walking;
                let stepping = walking.and_not(beyond);
                let step = solve(
                    block,
                    rows,
                    &state,
                    &Eq5Delayed { w },
                    w_prev - w,
                    guard.min,
                    guard.max,
                    stepping,
                );
                let solution = reach.select(beyond, step);
                let fed = feed_solved(block, rows, &mut state, &solution, walking, self.uniform);
                v = fed.or_keep(walking, v);
                limited = (solution.saturated | beyond) & walking;
            }
            // The memory of the settled lanes, and its sum (counts left unused).
            self.feed_evaluated(block, tables, &mut state, w, sum, settled);
            let (out, clamped) = guard.clamp(v, limited);
            guard.record(out, clamped, !beyond, active)
        } else {
            // w(t) = y_d(t) - h(v(t - Ts)), and v(t) = P1^{-1}[w](t) evaluated directly
            // (`crate::ihc::ihc_step`): the operators' sum at w, the memory fed only after.
            let w = desired - h_prev;
            let direct_lanes = active & evaluate_directly(&state);
            // In f32 a branch around the passes, in f64 the tables chosen as a value (see
            // `direct_tables`): each the faster in its precision, measured at 10 operators
            // (f32 5.2-5.3 against 7.1-7.4 ns per channel-step, f64 15-16 against 10-11 ns).
            let branch = core::mem::size_of::<T>() == 4;
            let tables = if branch {
                rows.operators()
            } else {
                direct_tables(rows, direct_lanes)
            };
            let (mut inside, mut sum, mut v) = (Mask::splat(false), Lanes::zero(), Lanes::zero());
            if !branch || direct_lanes.any() {
                (sum, v) = self.evaluate(block, tables, &state, w);
                inside = direct_lanes & v.ge(guard.min) & v.le(guard.max);
            }
            // Many operators, or beyond the limits (or not finite): the walk towards w,
            // stopped at a limit, from the counts of the memory as it is (recounted where
            // direct evaluations left them unused).
            let walking = active.and_not(inside);
            let mut saturated = Mask::splat(false);
            let mut reachable = Mask::splat(false);
            if walking.any() {
                recount(block, rows, &mut state, walking & direct_lanes);
                let solution = solve(
                    block,
                    rows,
                    &state,
                    &Eq5Delayed { w },
                    w_prev - w,
                    guard.min,
                    guard.max,
                    walking,
                );
                // A clamped sample: was y_d reachable? The exact solve from the same state
                // says.
                let check = solution.saturated & walking;
                if check.any() {
                    let e = solve(
                        block, rows, &state, &exact, f_exact, guard.min, guard.max, check,
                    );
                    reachable = check.and_not(e.saturated);
                }
                let fed = feed_solved(block, rows, &mut state, &solution, walking, self.uniform);
                v = fed.or_keep(walking, v);
                saturated = solution.saturated & walking;
            }
            // The memory of the lanes evaluated directly, and its sum (counts left unused).
            if !branch || inside.any() {
                self.feed_evaluated(block, tables, &mut state, w, sum, inside);
            }
            let (out, clamped) = guard.clamp(v, saturated);
            guard.record(out, clamped, reachable, active)
        };
        state.store(block, rows);
        guard.store(block, rows.scalar(PlantRows::PREVIOUS));
        out
    }
}

/// [`SolveMode::Exact`], [`SolveMode::DelayedGuarded`] and the plain delayed modes, as the
/// constant `MODE` of [`IhcMode`].
const EXACT: u8 = 0;
const GUARDED: u8 = 1;
const DELAYED: u8 = 2;

/// The IHC kernel with its solve mode fixed when compiled, so that each mode's loop over the
/// blocks is compiled on its own (the bank's mode is set when it is built).
#[derive(Clone, Copy)]
struct IhcMode<const MODE: u8>(IhcKernel);

impl PlantKernel<IhcMethod> {
    /// One sample of a block in mode `MODE`, with the block's remainder (the paper's cubic in
    /// every lane, or each lane's own polynomial).
    #[inline(always)]
    fn step_in<T: Real, const W: usize, const MODE: u8>(
        &self,
        block: &mut Block<'_, T, W>,
        desired: L<T, W>,
    ) -> L<T, W> {
        with_remainder!(self, block, PlantRows, |remainder| self
            .step_with::<_, _, W, MODE>(block, desired, remainder))
    }
}

impl<T: Real, const W: usize, const MODE: u8> BlockKernel<T, W> for IhcMode<MODE> {
    const HEAD: usize = PlantRows::HEAD;
    const COUNTS: usize = PlantRows::COUNTS;

    #[inline(always)]
    fn step(&self, block: &mut Block<'_, T, W>, desired: L<T, W>) -> L<T, W> {
        self.0.step_in::<T, W, MODE>(block, desired)
    }
}

impl<T: Real, const W: usize> BankKernel<T, W> for PlantKernel<IhcMethod> {
    /// `Ihc::reset` for every lane of a block.
    fn reset_block(&self, block: &mut Block<'_, T, W>) {
        let rows = &self.rows;
        let mut guard = self.guard(block);
        let mut state = PlayState::load(block, rows);
        super::play::reset(block, rows, &mut state);
        guard.reset();
        // 0 outside the limits: start from the nearest limit, feeding the w that P1^{-1} maps
        // to it.
        let v0 = guard.previous;
        let away = v0.compare(Lanes::zero(), |a, b| a != b);
        if away.any() {
            let equation = ReachControl { control: v0 };
            let s = solve(
                block, rows, &state, &equation, -v0, guard.min, guard.max, away,
            );
            feed(block, rows, &mut state, s.input, away, self.uniform);
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
        match self.mode {
            SolveMode::Exact => run(&IhcMode::<EXACT>(*self), blocks, desired, control),
            SolveMode::DelayedGuarded => run(&IhcMode::<GUARDED>(*self), blocks, desired, control),
            _ => run(&IhcMode::<DELAYED>(*self), blocks, desired, control),
        }
    }
}
