//! The play-operator bank of IHC and WIHC (`crate::walk::PlayBank`) for every lane of a block:
//! its state, the exact per-sample solve (the walk over the linear segments, ERRATA item 4) and
//! the memory update, eqs. (1)-(2).
//!
//! The walk of each lane starts at its own first operator that is not yet moving and visits as
//! many segments as its own solution needs: lane `l` reads its operator `cursor[l]` (a gather),
//! and the block walks as long as one of its lanes does. Most samples of a sampled trajectory
//! end on the first segment, so a block usually walks once.

use super::lanes::{Lanes, Mask};
use super::storage::{Block, OperatorTables, PlantRows, gather};
use crate::Real;
use crate::walk::SYNC_INTERVAL;

type L<T, const W: usize> = Lanes<T, W>;
type U<const W: usize> = Lanes<u32, W>;

/// The equation a compensator solves on one linear segment, lane by lane
/// (`crate::walk::SegmentEquation`).
pub(crate) trait LaneEquation<T: Real, const W: usize> {
    /// The residual at `x`, increasing in `x`.
    fn residual(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W>;
    /// The control emitted at `x`: by default the bank's output `alpha x + beta`.
    #[inline(always)]
    fn control(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        alpha * x + beta
    }
    /// The `x` where the control equals `v`: by default `(v - beta) / alpha`.
    #[inline(always)]
    fn input_at_control(&self, v: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        (v - beta) / alpha
    }
    /// The rounding allowance of the residual at a limit (by default 0).
    #[inline(always)]
    fn rounding(&self, _x: L<T, W>, _alpha: L<T, W>, _beta: L<T, W>) -> L<T, W> {
        Lanes::zero()
    }
    /// Whether [`LaneEquation::root`] reads its `inverse_alpha` (otherwise [`solve`] passes
    /// `1 / a` without reading the table).
    const INVERSE_ALPHA: bool = true;
    /// The root in `[lo, hi]` for the lanes of `active`.
    #[allow(clippy::too_many_arguments)]
    fn root(
        &self,
        lo: L<T, W>,
        hi: L<T, W>,
        f_lo: L<T, W>,
        f_hi: L<T, W>,
        alpha: L<T, W>,
        beta: L<T, W>,
        inverse_alpha: L<T, W>,
        active: Mask<T, W>,
    ) -> L<T, W>;
}

/// The state of every lane's bank besides its memory (`crate::walk::PlayBank`'s fields).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlayState<T, const W: usize> {
    pub a: L<T, W>,
    pub inverse_a: L<T, W>,
    pub input: L<T, W>,
    pub memory_sum: L<T, W>,
    pub operators: U<W>,
    pub rising: U<W>,
    pub falling: U<W>,
    pub always: U<W>,
    pub since_sync: U<W>,
}

impl<T: Real, const W: usize> PlayState<T, W> {
    #[inline(always)]
    pub fn load(block: &Block<'_, T, W>, rows: &PlantRows) -> Self {
        PlayState {
            a: block.get(rows.scalar(PlantRows::A)),
            inverse_a: block.get(rows.scalar(PlantRows::INVERSE_A)),
            input: block.get(rows.scalar(PlantRows::INPUT)),
            memory_sum: block.get(rows.scalar(PlantRows::MEMORY_SUM)),
            operators: block.count(PlantRows::OPERATORS),
            rising: block.count(PlantRows::RISING),
            falling: block.count(PlantRows::FALLING),
            always: block.count(PlantRows::ALWAYS),
            since_sync: block.count(PlantRows::SINCE_SYNC),
        }
    }

    /// Writes back what a sample changes.
    #[inline(always)]
    pub fn store(&self, block: &mut Block<'_, T, W>, rows: &PlantRows) {
        block.set(rows.scalar(PlantRows::INPUT), self.input);
        block.set(rows.scalar(PlantRows::MEMORY_SUM), self.memory_sum);
        block.set_count(PlantRows::RISING, self.rising);
        block.set_count(PlantRows::FALLING, self.falling);
        block.set_count(PlantRows::SINCE_SYNC, self.since_sync);
    }

    /// Writes back what feeding a directly evaluated input changes (the input and the memory
    /// sum; the counts are left unused, recounted before a walk): [`PlayState::store`] without
    /// the count rows, which a one-pass step would otherwise write unchanged.
    #[inline(always)]
    pub fn store_evaluated(&self, block: &mut Block<'_, T, W>, rows: &PlantRows) {
        block.set(rows.scalar(PlantRows::INPUT), self.input);
        block.set(rows.scalar(PlantRows::MEMORY_SUM), self.memory_sum);
    }

    /// Records `x` as the last input of the lanes of `lanes`, with `sum` the memory sum it
    /// left.
    #[inline(always)]
    pub fn record_input(&mut self, x: L<T, W>, sum: L<T, W>, lanes: Mask<T, W>) {
        self.input = x.or_keep(lanes, self.input);
        self.memory_sum = sum.or_keep(lanes, self.memory_sum);
    }

    /// The bank's output at its last input, `a x + sum b_i w_i`.
    #[inline(always)]
    pub fn output(&self) -> L<T, W> {
        self.a * self.input + self.memory_sum
    }
}

/// The solution of [`solve`] in every lane: the bank's input, whether a limit cut it short,
/// and the segment it lies on.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LaneSolution<T: Real, const W: usize> {
    pub input: L<T, W>,
    pub saturated: Mask<T, W>,
    pub alpha: L<T, W>,
    pub beta: L<T, W>,
    pub moving: U<W>,
    pub rising: Mask<T, W>,
}

impl<T: Real, const W: usize> LaneSolution<T, W> {
    /// `self` in the lanes of `mask`, `other` elsewhere.
    #[inline(always)]
    pub fn select(self, mask: Mask<T, W>, other: Self) -> Self {
        LaneSolution {
            input: self.input.or_keep(mask, other.input),
            saturated: Mask::choose(mask, self.saturated, other.saturated),
            alpha: self.alpha.or_keep(mask, other.alpha),
            beta: self.beta.or_keep(mask, other.beta),
            moving: self.moving.or_keep(mask, other.moving),
            rising: Mask::choose(mask, self.rising, other.rising),
        }
    }
}

/// `crate::walk::ReachOnly` lane by lane: the wrapped equation walked without its root, only to
/// learn which lanes' roots lie beyond the limits.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ReachOnly<'a, E>(pub &'a E);

impl<T: Real, E: LaneEquation<T, W>, const W: usize> LaneEquation<T, W> for ReachOnly<'_, E> {
    const INVERSE_ALPHA: bool = false;
    #[inline(always)]
    fn residual(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        self.0.residual(x, alpha, beta)
    }
    #[inline(always)]
    fn control(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        self.0.control(x, alpha, beta)
    }
    #[inline(always)]
    fn input_at_control(&self, v: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        self.0.input_at_control(v, alpha, beta)
    }
    #[inline(always)]
    fn rounding(&self, x: L<T, W>, alpha: L<T, W>, beta: L<T, W>) -> L<T, W> {
        self.0.rounding(x, alpha, beta)
    }
    #[inline(always)]
    fn root(
        &self,
        lo: L<T, W>,
        _hi: L<T, W>,
        _f_lo: L<T, W>,
        _f_hi: L<T, W>,
        _alpha: L<T, W>,
        _beta: L<T, W>,
        _inv: L<T, W>,
        _active: Mask<T, W>,
    ) -> L<T, W> {
        lo
    }
}

/// `crate::walk::PlayBank::solve` for the lanes of `active` (the others' results are
/// meaningless): walks each lane's segments from its last input in the direction that brings
/// its residual to zero, keeping the control within `[limit_min, limit_max]`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn solve<T: Real, E: LaneEquation<T, W>, const W: usize>(
    block: &Block<'_, T, W>,
    rows: &PlantRows,
    state: &PlayState<T, W>,
    equation: &E,
    f_prev: L<T, W>,
    limit_min: L<T, W>,
    limit_max: L<T, W>,
    active: Mask<T, W>,
) -> LaneSolution<T, W> {
    let zero = Lanes::zero();
    let rising = f_prev.le(zero);
    let first = U::select(rising, state.rising, state.falling).zip(state.operators, u32::min);
    // The moving operators fold into the first segment: prefix[first - 1], and the reciprocal
    // slope 1 / (a + prefix[first - 1]) from the table (1 / a with none moving).
    let n = rows.n;
    let operator_rows = [
        block.table(rows.memory(), n),
        block.table(rows.thresholds(), n),
        block.table(rows.weights(), n),
    ];
    let some_moving = first.test::<T>(|k| k > 0);
    let before = first.map(|k| k.saturating_sub(1));
    let [prefix] = gather(
        [block.table(rows.prefix(), n)],
        before,
        block.hardware_gather,
    );
    let moving_weight = prefix.or_keep(some_moving, zero);
    let mut alpha = state.a + moving_weight;
    let mut beta = state.memory_sum - moving_weight * state.input;
    let mut moving = first;
    // The walk: `edge` is the end of the segment reached so far (lo rising, hi falling).
    let (mut edge, mut f_edge) = (state.input, f_prev);
    let (mut lo, mut hi, mut f_lo, mut f_hi) = (zero, zero, zero, zero);
    let mut found = Mask::splat(false);
    let mut walking = active;
    let mut cursor = first;
    loop {
        walking = walking & cursor.compare(state.operators, |k, n| k < n);
        if !walking.any() {
            break;
        }
        // Each lane's operator `cursor`: its memory, threshold and weight.
        let [w, r, b] = gather(operator_rows, cursor, block.hardware_gather);
        // Rising, operator i starts moving at u = max(w_i + r_i, lo); falling, at
        // l = min(w_i, hi).
        let breakpoint = (w + r).max(edge).or_keep(rising, w.min(edge));
        let control = equation.control(breakpoint, alpha, beta);
        let at_limit = Mask::choose(rising, control.ge(limit_max), control.le(limit_min));
        let walks = walking.and_not(at_limit);
        let f_break = equation.residual(breakpoint, alpha, beta);
        let crossed = Mask::choose(rising, f_break.ge(zero), f_break.le(zero));
        let hit = walks & crossed;
        lo = edge.or_keep(rising, breakpoint).or_keep(hit, lo);
        hi = breakpoint.or_keep(rising, edge).or_keep(hit, hi);
        f_lo = f_edge.or_keep(rising, f_break).or_keep(hit, f_lo);
        f_hi = f_break.or_keep(rising, f_edge).or_keep(hit, f_hi);
        found = found | hit;
        let advance = walks.and_not(hit);
        // Operator i starts moving: b_i w_i becomes b_i (x - r_i) rising, b_i x falling.
        let next = cursor.map(|k| k + 1);
        moving = next.or_keep(advance, moving);
        alpha = (alpha + b).or_keep(advance, alpha);
        let held = (b * (r + w)).or_keep(rising, b * w);
        beta = (beta - held).or_keep(advance, beta);
        edge = breakpoint.or_keep(advance, edge);
        f_edge = f_break.or_keep(advance, f_edge);
        cursor = next;
        walking = advance;
    }
    // The lanes whose walk ended without a sign change: up to the limit.
    let to_limit = active.and_not(found);
    let mut saturated = Mask::splat(false);
    let mut input = zero;
    if to_limit.any() {
        let v_limit = limit_max.or_keep(rising, limit_min);
        let end = equation.input_at_control(v_limit, alpha, beta);
        let f_end = equation.residual(end, alpha, beta);
        let rounding = equation.rounding(end, alpha, beta);
        saturated = to_limit & Mask::choose(rising, f_end.lt(-rounding), f_end.gt(rounding));
        // A clamped lane's input stays on the walk's last segment: the end clamped to its
        // start (as `crate::walk::PlayBank::solve`).
        let clamped = end.max(edge).or_keep(rising, end.min(edge));
        input = clamped.or_keep(saturated, input);
        let bracketed = to_limit.and_not(saturated);
        lo = edge.or_keep(rising, end).or_keep(bracketed, lo);
        hi = end.or_keep(rising, edge).or_keep(bracketed, hi);
        f_lo = f_edge.or_keep(rising, f_end).or_keep(bracketed, f_lo);
        f_hi = f_end.or_keep(rising, f_edge).or_keep(bracketed, f_hi);
    }
    // The reciprocal slope of the segment reached, from the table: 1 / (a + prefix[moving - 1])
    // (1 / a with none moving), read once after the walk instead of at every segment.
    let inverse_alpha = if E::INVERSE_ALPHA {
        let some_moving = moving.test::<T>(|k| k > 0);
        let before = moving.map(|k| k.saturating_sub(1));
        let [inverse] = gather(
            [block.table(rows.inverse_alpha(), n)],
            before,
            block.hardware_gather,
        );
        inverse.or_keep(some_moving, state.inverse_a)
    } else {
        state.inverse_a
    };
    let solving = active.and_not(saturated);
    let root = equation.root(lo, hi, f_lo, f_hi, alpha, beta, inverse_alpha, solving);
    LaneSolution {
        input: root.or_keep(solving, input),
        saturated,
        alpha,
        beta,
        moving,
        rising,
    }
}

/// What feeding an input to the operators gives, when counted.
pub(crate) struct Fed<T, const W: usize> {
    pub rising: U<W>,
    pub falling: U<W>,
    pub sum: L<T, W>,
}

/// Feeds `x` to the operators of the `active` lanes (eqs. (1)-(2), `crate::play::feed_bank`).
/// With `count`, also counts the operators at either edge of their band and sums `b_i w_i` in
/// four partial sums exactly as `crate::play::four_way_sum` does for each lane's own operator
/// count (`uniform`: every lane has the bank's `rows.n` operators).
#[inline(always)]
pub(crate) fn update_memory<T: Real, const W: usize>(
    block: &mut Block<'_, T, W>,
    tables: OperatorTables,
    operators: U<W>,
    x: L<T, W>,
    active: Mask<T, W>,
    count: bool,
    uniform: bool,
) -> Fed<T, W> {
    if count {
        update_memory_with::<_, _, true, true>(block, tables, operators, x, active, uniform)
    } else {
        update_memory_with::<_, _, false, false>(block, tables, operators, x, active, uniform)
    }
}

/// [`update_memory`], with the counts of operators at either edge (`EDGES`) and the weighted
/// sum (`SUM`) asked for separately.
///
/// The operator rows are sliced once and walked four operators at a time, so that the four
/// partial sums stay in registers; each combination of `EDGES`, `SUM` and `uniform` has its
/// own loop (no test inside it). `EDGES` and `SUM` are constants of each call, so that only
/// the loops a kernel uses are compiled into it (every one is inlined into every vector path).
#[inline(always)]
pub(crate) fn update_memory_with<T: Real, const W: usize, const EDGES: bool, const SUM: bool>(
    block: &mut Block<'_, T, W>,
    tables: OperatorTables,
    operators: U<W>,
    x: L<T, W>,
    active: Mask<T, W>,
    uniform: bool,
) -> Fed<T, W> {
    let Some(rows) = OperatorRows::of(block, tables) else {
        // The layouts always hold the rows (thresholds and weights before the memory).
        return Fed {
            rising: Lanes::splat(0),
            falling: Lanes::splat(0),
            sum: Lanes::zero(),
        };
    };
    // Without counts or sum, the operators beyond a lane's own count change nothing it reads.
    if uniform || !(EDGES || SUM) {
        rows.update::<EDGES, SUM, true, true>(operators, x, active)
    } else {
        rows.update::<EDGES, SUM, false, true>(operators, x, active)
    }
}

/// `crate::walk::PlayBank::output_at` for every lane: the memory sum `sum b_i w_i` the
/// operators would have after `x`, the same bits as [`update_memory`] gives, without changing
/// the memory.
#[inline(always)]
pub(crate) fn memory_sum_at<T: Real, const W: usize>(
    block: &mut Block<'_, T, W>,
    tables: OperatorTables,
    operators: U<W>,
    x: L<T, W>,
    uniform: bool,
) -> L<T, W> {
    let Some(operator_rows) = OperatorRows::of(block, tables) else {
        return Lanes::zero();
    };
    let all = Mask::splat(true);
    let fed = if uniform {
        operator_rows.update::<false, true, true, false>(operators, x, all)
    } else {
        operator_rows.update::<false, true, false, false>(operators, x, all)
    };
    fed.sum
}

/// The operator rows of a block: thresholds, weights and the memory they update.
struct OperatorRows<'a, T, const W: usize> {
    thresholds: &'a [[T; W]],
    weights: &'a [[T; W]],
    memory: &'a mut [[T; W]],
}

/// The running results of [`OperatorRows::update`].
struct Accumulated<T: Real, const W: usize> {
    rising: U<W>,
    falling: U<W>,
    partial: [L<T, W>; 4],
    tail: [L<T, W>; 3],
}

impl<'a, T: Real, const W: usize> OperatorRows<'a, T, W> {
    /// `n` rows of each from `thresholds`, `weights` and `memory` (the first two before the
    /// third), if the block holds them.
    #[inline(always)]
    fn of(block: &'a mut Block<'_, T, W>, tables: OperatorTables) -> Option<Self> {
        let OperatorTables {
            thresholds,
            weights,
            memory,
            n,
        } = tables;
        let (head, rest) = block.values.split_at_mut_checked(memory)?;
        Some(OperatorRows {
            thresholds: head.get(thresholds..thresholds.checked_add(n)?)?,
            weights: head.get(weights..weights.checked_add(n)?)?,
            memory: rest.get_mut(..n)?,
        })
    }

    /// Feeds `x` to every operator (the memory of the lanes of `active`; with `STORE` false
    /// the memory is left as it was), counting the operators at either edge (`EDGES`) and
    /// summing `b_i w_i` (`SUM`) as `crate::play::four_way_sum` does for each lane's own
    /// operator count (`UNIFORM`: every lane has them all).
    ///
    /// With every lane active (the usual case) the memory rows are written whole
    /// ([`OperatorRows::update_all`]): a blend of the new memory with the old written back to
    /// the row it was read from becomes a masked store where the target has one, and AVX2's
    /// (`vmaskmovps`) costs many plain stores on some processors (AMD's).
    #[inline(always)]
    fn update<const EDGES: bool, const SUM: bool, const UNIFORM: bool, const STORE: bool>(
        self,
        operators: U<W>,
        x: L<T, W>,
        active: Mask<T, W>,
    ) -> Fed<T, W> {
        if active.all() {
            self.update_all::<EDGES, SUM, UNIFORM, true, STORE>(operators, x, active)
        } else {
            self.update_all::<EDGES, SUM, UNIFORM, false, STORE>(operators, x, active)
        }
    }

    /// [`OperatorRows::update`], knowing (`ALL`) whether every lane is active.
    #[inline(always)]
    fn update_all<
        const EDGES: bool,
        const SUM: bool,
        const UNIFORM: bool,
        const ALL: bool,
        const STORE: bool,
    >(
        self,
        operators: U<W>,
        x: L<T, W>,
        active: Mask<T, W>,
    ) -> Fed<T, W> {
        let zero = Lanes::<T, W>::zero();
        let mut acc = Accumulated {
            rising: Lanes::splat(0u32),
            falling: Lanes::splat(0u32),
            partial: [zero; 4],
            tail: [zero; 3],
        };
        // The lanes' first operator beyond the four-way groups.
        let full = operators.map(|n| n / 4 * 4);
        let (thresholds, t_rest) = self.thresholds.as_chunks::<4>();
        let (weights, b_rest) = self.weights.as_chunks::<4>();
        let (memory, m_rest) = self.memory.as_chunks_mut::<4>();
        let mut i = 0usize;
        for ((r4, b4), m4) in thresholds.iter().zip(weights).zip(memory.iter_mut()) {
            for j in 0..4 {
                Self::operator::<EDGES, SUM, UNIFORM, ALL, STORE>(
                    &mut acc,
                    i,
                    Some(j),
                    r4[j],
                    b4[j],
                    &mut m4[j],
                    operators,
                    full,
                    x,
                    active,
                );
                i += 1;
            }
        }
        for ((r, b), m) in t_rest.iter().zip(b_rest).zip(m_rest.iter_mut()) {
            Self::operator::<EDGES, SUM, UNIFORM, ALL, STORE>(
                &mut acc, i, None, *r, *b, m, operators, full, x, active,
            );
            i += 1;
        }
        let partial = acc.partial;
        let mut total = (partial[0] + partial[1]) + (partial[2] + partial[3]);
        if SUM {
            for (k, t) in acc.tail.into_iter().enumerate() {
                let has = full.compare::<T>(operators, |f, n| f + (k as u32) < n);
                total = (total + t).or_keep(has, total);
            }
        }
        Fed {
            rising: acc.rising,
            falling: acc.falling,
            sum: total,
        }
    }

    /// Operator `i`: `group` is `i mod 4` within the four-way groups of the whole bank, `None`
    /// beyond them.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn operator<
        const EDGES: bool,
        const SUM: bool,
        const UNIFORM: bool,
        const ALL: bool,
        const STORE: bool,
    >(
        acc: &mut Accumulated<T, W>,
        i: usize,
        group: Option<usize>,
        r: [T; W],
        b: [T; W],
        m: &mut [T; W],
        operators: U<W>,
        full: U<W>,
        x: L<T, W>,
        active: Mask<T, W>,
    ) {
        let (r, w) = (Lanes(r), Lanes(*m));
        // f_r(x, w) = max(x - r, min(x, w)) as `crate::play::one_sided` writes it.
        let lower = x - r;
        let raised = lower.or_keep(w.lt(lower), w);
        let next = x.or_keep(raised.gt(x), raised);
        if STORE {
            *m = if ALL {
                next.0
            } else {
                next.or_keep(active, w).0
            };
        }
        let i32 = i as u32;
        if EDGES {
            let (up, down) = if UNIFORM {
                (next.le(lower), next.ge(x))
            } else {
                let inside = operators.test(|n| i32 < n);
                (next.le(lower) & inside, next.ge(x) & inside)
            };
            acc.rising = acc.rising + up.count32();
            acc.falling = acc.falling + down.count32();
        }
        if !SUM {
            return;
        }
        let term = Lanes(b) * next;
        if UNIFORM {
            match group {
                Some(j) => acc.partial[j] = acc.partial[j] + term,
                None => {
                    // At most three operators beyond the groups.
                    let k = (i % 4).min(2);
                    acc.tail[k] = term;
                }
            }
        } else {
            if let Some(j) = group {
                let grouped = full.test::<T>(|f| i32 < f);
                acc.partial[j] = (acc.partial[j] + term).or_keep(grouped, acc.partial[j]);
            }
            let inside = operators.test::<T>(|n| i32 < n);
            for (k, t) in acc.tail.iter_mut().enumerate() {
                let here = full.test(|f| f + k as u32 == i32) & inside;
                *t = term.or_keep(here, *t);
            }
        }
    }
}

/// `crate::walk::PlayBank::feed` for the lanes of `active`: the memory, the counts of moving
/// operators and the memory sum from `x`. Returns the bank's output `a x + sum b_i w_i`.
#[inline(always)]
pub(crate) fn feed<T: Real, const W: usize>(
    block: &mut Block<'_, T, W>,
    rows: &PlantRows,
    state: &mut PlayState<T, W>,
    x: L<T, W>,
    active: Mask<T, W>,
    uniform: bool,
) -> L<T, W> {
    let fed = update_memory(
        block,
        rows.operators(),
        state.operators,
        x,
        active,
        true,
        uniform,
    );
    state.record_input(x, fed.sum, active);
    state.rising = fed.rising.or_keep(active, state.rising);
    state.falling = fed.falling.or_keep(active, state.falling);
    state.a * x + fed.sum
}

/// [`feed`] without the counts of moving operators (left unused, recounted before a walk):
/// the memory and the memory sum from `x` in the lanes of `active`. Returns the memory sum.
#[inline(always)]
pub(crate) fn feed_uncounted<T: Real, const W: usize>(
    block: &mut Block<'_, T, W>,
    rows: &PlantRows,
    state: &mut PlayState<T, W>,
    x: L<T, W>,
    active: Mask<T, W>,
    uniform: bool,
) -> L<T, W> {
    let fed = update_memory_with::<_, _, false, true>(
        block,
        rows.operators(),
        state.operators,
        x,
        active,
        uniform,
    );
    state.record_input(x, fed.sum, active);
    fed.sum
}

/// `crate::walk::PlayBank::feed_solved` for the lanes of `active`: the memory from the solved
/// input, the memory sum and the counts of moving operators from the solved segment, except
/// every `SYNC_INTERVAL` samples of a lane, when they are recomputed ([`feed`]).
#[inline(always)]
pub(crate) fn feed_solved<T: Real, const W: usize>(
    block: &mut Block<'_, T, W>,
    rows: &PlantRows,
    state: &mut PlayState<T, W>,
    solution: &LaneSolution<T, W>,
    active: Mask<T, W>,
    uniform: bool,
) -> L<T, W> {
    feed_solved_or_full(
        block,
        rows,
        state,
        solution,
        active,
        Mask::splat(false),
        uniform,
    )
}

/// [`feed_solved`] for the lanes of `active`, except those of `full`, which take [`feed`]
/// (with the same input) without counting towards the next recomputation.
#[inline(always)]
pub(crate) fn feed_solved_or_full<T: Real, const W: usize>(
    block: &mut Block<'_, T, W>,
    rows: &PlantRows,
    state: &mut PlayState<T, W>,
    solution: &LaneSolution<T, W>,
    active: Mask<T, W>,
    full: Mask<T, W>,
    uniform: bool,
) -> L<T, W> {
    let x = solution.input;
    let solved = active.and_not(full);
    let since = state.since_sync.map(|s| s + 1);
    let sync = solved & since.test(|s| s >= SYNC_INTERVAL);
    state.since_sync = since
        .or_keep(solved, state.since_sync)
        .or_keep(!sync, Lanes::splat(0));
    let recount = (sync | full) & active;
    let fed = update_memory(
        block,
        rows.operators(),
        state.operators,
        x,
        active,
        recount.any(),
        uniform,
    );
    // Beyond the moving operators the others hold, away from the edge of their band on the
    // side the input went; only the zero-threshold ones sit on both edges.
    let rising = U::select(solution.rising, solution.moving, state.always);
    let falling = U::select(solution.rising, state.always, solution.moving);
    state.rising = U::select(recount, fed.rising, rising).or_keep(active, state.rising);
    state.falling = U::select(recount, fed.falling, falling).or_keep(active, state.falling);
    state.input = x.or_keep(active, state.input);
    let (alpha, beta) = (solution.alpha, solution.beta);
    let segment_sum = (alpha - state.a) * x + beta;
    state.memory_sum = fed
        .sum
        .or_keep(recount, segment_sum)
        .or_keep(active, state.memory_sum);
    (state.a * x + fed.sum).or_keep(recount, alpha * x + beta)
}

/// `crate::walk::PlayBank::reset` for every lane: zero memory, last input 0, the moving
/// operators of the reset state.
#[inline(always)]
pub(crate) fn reset<T: Real, const W: usize>(
    block: &mut Block<'_, T, W>,
    rows: &PlantRows,
    state: &mut PlayState<T, W>,
) {
    for i in 0..rows.n {
        block.set(rows.memory() + i, Lanes::zero());
    }
    state.input = Lanes::zero();
    state.memory_sum = Lanes::zero();
    state.since_sync = Lanes::splat(0);
    state.rising = state.always;
    state.falling = state.operators;
}

/// The counts of operators at either edge of their band, recomputed from the memory and the
/// last input of the lanes of `lanes`, as [`update_memory`] counts them when it feeds that
/// input (the same comparisons on the same values, so the same counts): for a loop that feeds
/// without counting (the plain delayed WIHC, the delayed and guarded IHC's direct evaluations)
/// and walks only now and then. The other lanes keep their counts (a walk's, which may differ
/// from the memory's at an operator's edge by rounding).
#[inline(always)]
pub(crate) fn recount<T: Real, const W: usize>(
    block: &Block<'_, T, W>,
    rows: &PlantRows,
    state: &mut PlayState<T, W>,
    lanes: Mask<T, W>,
) {
    if !lanes.any() {
        return;
    }
    let x = state.input;
    let mut rising = Lanes::splat(0u32);
    let mut falling = Lanes::splat(0u32);
    for i in 0..rows.n {
        let lower = x - block.get(rows.thresholds() + i);
        let w = block.get(rows.memory() + i);
        let i32 = i as u32;
        let inside = state.operators.test::<T>(|n| i32 < n);
        rising = rising + (w.le(lower) & inside).count32();
        falling = falling + (w.ge(x) & inside).count32();
    }
    state.rising = rising.or_keep(lanes, state.rising);
    state.falling = falling.or_keep(lanes, state.falling);
}
