//! The exact per-sample solve shared by IHC and WIHC (ERRATA item 4).
//!
//! Given the memory `w_i` of a bank of one-sided play operators and the previous input
//! `x_prev`, the bank's output `a x + sum_i b_i F_{r_i}[x]` is piecewise linear in the next
//! input `x`: rising from `x_prev`, operator `i` holds `w_i` until `x` reaches `w_i + r_i`, then
//! follows `x - r_i`; falling, it holds until `x` reaches `w_i`, then follows `x`. From the
//! reset state these breakpoints come in operator order (the moving operators are always the
//! first ones by threshold), so one pass over the operators visits the linear segments
//! `alpha x + beta` in order. On each segment the compensator's equation is a cubic (or linear)
//! residual; the walk stops at the first segment whose end makes the residual change sign and
//! solves there. A running maximum (minimum) of the breakpoints absorbs rounding.
//!
//! The operators already moving at `x_prev` in the direction of the walk (the first
//! `rising_active` or `falling_active` ones, counted by the previous update) are folded into
//! the first segment in O(1) with prefix sums of the weights, so a small step costs a residual
//! or two, a root solve and the memory update.

use crate::buffer::{copied, filled};
use crate::play::{feed_bank, four_way_sum, one_sided};
use crate::{Buffer, CoreError, OutputLimits, Real};

/// The equation a compensator solves on one linear segment of the bank, `PI(x) = alpha x + beta`.
pub(crate) trait SegmentEquation<T: Real> {
    /// The residual at `x`, increasing in `x`; the solution makes it zero.
    fn residual(&self, x: T, alpha: T, beta: T) -> T;
    /// The control `v` the compensator emits at `x` (increasing in `x`): by default the bank's
    /// output `alpha x + beta` (IHC, whose bank is `P1^{-1}`).
    #[inline(always)]
    fn control(&self, x: T, alpha: T, beta: T) -> T {
        alpha * x + beta
    }
    /// The `x` where the control equals `v`: by default `(v - beta) / alpha`.
    #[inline(always)]
    fn input_at_control(&self, v: T, alpha: T, beta: T) -> T {
        (v - beta) / alpha
    }
    /// How far below zero (rising) or above zero (falling) the residual at a limit may be and
    /// still count as reached: rounding of its terms. By default 0 (strict).
    #[inline(always)]
    fn rounding(&self, _x: T, _alpha: T, _beta: T) -> T {
        T::zero()
    }
    /// The root of the residual in `[lo, hi]`, given its values at both ends (`f_lo <= 0 <= f_hi`);
    /// `inverse_alpha` is `1 / alpha`, from a table.
    #[allow(clippy::too_many_arguments)]
    fn root(&self, lo: T, hi: T, f_lo: T, f_hi: T, alpha: T, beta: T, inverse_alpha: T) -> T;
}

/// An equation walked only to learn whether its root lies within the limits: the same
/// residual, control and rounding, and no root solve (the walk's segment start stands for it).
/// [`PlayBank::solve`] with it reports `saturated` exactly when the solve of the wrapped
/// equation would, for the cost of the walk alone.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ReachOnly<'a, E>(pub &'a E);

impl<T: Real, E: SegmentEquation<T>> SegmentEquation<T> for ReachOnly<'_, E> {
    #[inline(always)]
    fn residual(&self, x: T, alpha: T, beta: T) -> T {
        self.0.residual(x, alpha, beta)
    }
    #[inline(always)]
    fn control(&self, x: T, alpha: T, beta: T) -> T {
        self.0.control(x, alpha, beta)
    }
    #[inline(always)]
    fn input_at_control(&self, v: T, alpha: T, beta: T) -> T {
        self.0.input_at_control(v, alpha, beta)
    }
    #[inline(always)]
    fn rounding(&self, x: T, alpha: T, beta: T) -> T {
        self.0.rounding(x, alpha, beta)
    }
    #[inline(always)]
    fn root(&self, lo: T, _hi: T, _f_lo: T, _f_hi: T, _alpha: T, _beta: T, _inv: T) -> T {
        lo
    }
}

/// The rounding allowance of a residual that sums terms of total magnitude `terms`:
/// `256 eps (1 + terms)`, absolute as well as relative, because the desired position itself
/// carries the rounding of the plant model that produced it (sums of `b_i w_i`, eqs. (2), (5)
/// and (9)). Shared by the exact IHC and WIHC equations.
#[inline(always)]
pub(crate) fn rounding_tolerance<T: Real>(terms: T) -> T {
    T::epsilon() * T::from_f64(256.0) * (T::one() + terms)
}

/// A linear piece of the bank: its output is `alpha x + beta` there, with the first `moving`
/// operators moving with the input, up (`rising`) or down.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Segment<T> {
    pub alpha: T,
    pub beta: T,
    /// How many operators (the first ones) move on the segment.
    pub moving: usize,
    /// Whether the walk went up (the moving operators sit at the upper edge of their band) or
    /// down (at the lower edge). A solution at a limit may lie an ulp the other side of the
    /// previous input; the direction of the walk is what counts.
    pub rising: bool,
}

/// The input of the bank that solves the equation, whether the limits cut it short, and the
/// segment it lies on.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Solution<T> {
    pub input: T,
    pub saturated: bool,
    pub segment: Segment<T>,
}

/// A bank of one-sided play operators with a linear term, `a x + sum_i b_i F_{r_i}[x]`, and
/// what the exact solve needs to know about its state.
#[derive(Debug, Clone)]
pub(crate) struct PlayBank<T: Real, B: Buffer<T>> {
    pub(crate) thresholds: B,
    pub(crate) weights: B,
    /// `prefix[k] = b_1 + ... + b_{k+1}`.
    pub(crate) prefix: B,
    /// `inverse_alpha[k] = 1 / (a + b_1 + ... + b_{k+1})`: the reciprocal slope of each segment.
    pub(crate) inverse_alpha: B,
    /// `1 / a`.
    pub(crate) inverse_a: T,
    pub(crate) memory: B,
    pub(crate) a: T,
    /// The last input fed.
    pub(crate) input: T,
    /// `sum_i b_i w_i` of the current memory.
    pub(crate) memory_sum: T,
    /// How many operators (the first ones) moved up with the last input: `w_i = x - r_i`.
    pub(crate) rising_active: usize,
    /// How many operators (the first ones) moved down with the last input: `w_i = x`.
    pub(crate) falling_active: usize,
    /// How many operators have a zero threshold (always moving).
    pub(crate) always_active: usize,
    /// Samples fed since `memory_sum` was last recomputed from the memory.
    pub(crate) since_sync: u32,
}

/// How often (in samples) [`PlayBank::feed_solved`] recomputes the memory sum from the memory
/// instead of taking it from the solved segment, so that rounding never accumulates.
pub(crate) const SYNC_INTERVAL: u32 = 64;

impl<T: Real, B: Buffer<T>> PlayBank<T, B> {
    /// A bank at the reset state (zero memory, last input 0).
    pub fn new(a: T, thresholds: &[T], weights: &[T]) -> Result<Self, CoreError> {
        let mut prefix: B = filled(T::zero(), weights.len())?;
        let mut inverse_alpha: B = filled(T::zero(), weights.len())?;
        let mut sum = T::zero();
        for ((p, q), &b) in prefix
            .as_mut()
            .iter_mut()
            .zip(inverse_alpha.as_mut().iter_mut())
            .zip(weights)
        {
            sum = sum + b;
            *p = sum;
            *q = T::one() / (a + sum);
        }
        let mut bank = PlayBank {
            thresholds: copied(thresholds)?,
            weights: copied(weights)?,
            prefix,
            inverse_alpha,
            inverse_a: T::one() / a,
            memory: filled(T::zero(), weights.len())?,
            a,
            input: T::zero(),
            memory_sum: T::zero(),
            rising_active: 0,
            falling_active: 0,
            always_active: thresholds.iter().take_while(|r| **r <= T::zero()).count(),
            since_sync: 0,
        };
        bank.reset();
        Ok(bank)
    }

    /// Zero memory, last input 0 (eq. (1)).
    pub fn reset(&mut self) {
        self.memory.as_mut().fill(T::zero());
        self.input = T::zero();
        self.memory_sum = T::zero();
        self.since_sync = 0;
        let zero = T::zero();
        // At x = 0 with zero memory every operator sits at its lower edge (w = x), and those
        // with r = 0 also at their upper edge.
        self.rising_active = self
            .thresholds
            .as_ref()
            .iter()
            .take_while(|r| **r <= zero)
            .count();
        self.falling_active = self.thresholds.as_ref().len();
    }

    pub fn thresholds(&self) -> &[T] {
        self.thresholds.as_ref()
    }

    pub fn weights(&self) -> &[T] {
        self.weights.as_ref()
    }

    pub fn memory(&self) -> &[T] {
        self.memory.as_ref()
    }

    /// The coefficient `a` of the linear term.
    pub fn a(&self) -> T {
        self.a
    }

    /// The least reciprocal slope over the bank's segments, `1 / max(a, a + b_1 + ... +
    /// b_k)`: however the memory lies, moving the input from `x` to `y` moves the output by at
    /// most `|y - x| / least_inverse_alpha`.
    pub fn least_inverse_alpha(&self) -> T {
        self.inverse_alpha
            .as_ref()
            .iter()
            .fold(self.inverse_a, |least, &q| least.min(q))
    }

    /// `|a| + sum_i |b_i|`: with [`PlayBank::reach_sum`], a bound on the size of the terms of
    /// `a x + sum_i b_i F_{r_i}[x]` at an input `x` (each `|F_{r_i}[x]| <= |x| + r_i`), the
    /// scale of its rounding.
    pub fn slope_sum(&self) -> T {
        self.weights
            .as_ref()
            .iter()
            .fold(self.a.abs(), |sum, &b| sum + b.abs())
    }

    /// `sum_i |b_i r_i|` (see [`PlayBank::slope_sum`]).
    pub fn reach_sum(&self) -> T {
        self.weights
            .as_ref()
            .iter()
            .zip(self.thresholds.as_ref())
            .fold(T::zero(), |sum, (&b, &r)| sum + (b * r).abs())
    }

    /// The last input fed.
    pub fn input(&self) -> T {
        self.input
    }

    /// `sum_i b_i w_i` of the current memory.
    pub fn memory_sum(&self) -> T {
        self.memory_sum
    }

    /// The bank's output at the last input: `a x + sum_i b_i w_i`.
    pub fn output(&self) -> T {
        self.a * self.input + self.memory_sum
    }

    /// Feeds `x` (eqs. (1)-(2)), updating the memory and the counts of moving operators.
    /// Returns the bank's output `a x + sum b_i F_{r_i}[x]`.
    #[inline]
    pub fn feed(&mut self, x: T) -> T {
        let update = feed_bank(
            self.thresholds.as_ref(),
            self.weights.as_ref(),
            self.memory.as_mut(),
            x,
        );
        self.input = x;
        self.memory_sum = update.sum;
        self.rising_active = update.rising;
        self.falling_active = update.falling;
        self.a * x + update.sum
    }

    /// The bank's output if `x` were fed, `a x + sum b_i F_{r_i}[x]`, without changing it: the
    /// same bits as [`PlayBank::feed`] returns.
    #[inline]
    pub fn output_at(&self, x: T) -> T {
        let (thresholds, weights, memory) = (
            self.thresholds.as_ref(),
            self.weights.as_ref(),
            self.memory.as_ref(),
        );
        let n = memory.len().min(thresholds.len()).min(weights.len());
        let (thresholds, weights, memory) = (&thresholds[..n], &weights[..n], &memory[..n]);
        let sum = four_way_sum(n, |i| weights[i] * one_sided(x, thresholds[i], memory[i]));
        self.a * x + sum
    }

    /// The counts of moving operators recomputed from the memory and the last input, as
    /// [`PlayBank::feed`] counts them when it feeds that input (the same comparisons on the
    /// same values): for a loop that feeds without using them and walks only now and then, so
    /// that every walk starts from counts that do not depend on how the memory was reached.
    pub fn recount(&mut self) {
        let x = self.input;
        let mut rising = 0usize;
        let mut falling = 0usize;
        for (&w, &r) in self.memory.as_ref().iter().zip(self.thresholds.as_ref()) {
            rising += usize::from(w <= x - r);
            falling += usize::from(w >= x);
        }
        self.rising_active = rising;
        self.falling_active = falling;
    }

    /// Feeds the solution of [`PlayBank::solve`] itself (`x == solution.input`): the same memory
    /// as [`PlayBank::feed`], but the new memory sum and the counts of moving operators come
    /// from the solved segment, so that the next sample's solve need not wait for the weighted
    /// sum over all operators (the compensators are latency-bound). Every [`SYNC_INTERVAL`]
    /// samples the sum is recomputed from the memory.
    #[inline]
    pub fn feed_solved(&mut self, solution: &Solution<T>) -> T {
        let x = solution.input;
        self.since_sync += 1;
        if self.since_sync >= SYNC_INTERVAL {
            self.since_sync = 0;
            return self.feed(x);
        }
        for (w, &r) in self
            .memory
            .as_mut()
            .iter_mut()
            .zip(self.thresholds.as_ref())
        {
            *w = one_sided(x, r, *w);
        }
        // Operators beyond the moving ones hold their memory, away from the edge of their band
        // on the side the input went; only the zero-threshold ones sit on both edges. (When the
        // input did not move, these counts can only be too small, which the walk tolerates.)
        if solution.segment.rising {
            self.rising_active = solution.segment.moving;
            self.falling_active = self.always_active;
        } else {
            self.falling_active = solution.segment.moving;
            self.rising_active = self.always_active;
        }
        self.input = x;
        // On the segment the bank's output is alpha x + beta = a x + memory sum.
        let Segment { alpha, beta, .. } = solution.segment;
        self.memory_sum = (alpha - self.a) * x + beta;
        alpha * x + beta
    }

    /// `1 / (a + b_1 + ... + b_k)`, the reciprocal slope of the segment with `k` moving.
    #[inline(always)]
    fn inverse_alpha(&self, k: usize) -> T {
        // `get`, not indexing: the per-sample path holds no panic (k <= n always).
        match k.checked_sub(1) {
            Some(j) => self
                .inverse_alpha
                .as_ref()
                .get(j)
                .copied()
                .unwrap_or(self.inverse_a),
            None => self.inverse_a,
        }
    }

    /// Walks the segments of the bank from the last input (where the residual is `f_prev`) in
    /// the direction that brings the residual to zero, keeping the control within `limits`.
    #[inline]
    pub fn solve<E: SegmentEquation<T>>(
        &self,
        equation: &E,
        f_prev: T,
        limits: OutputLimits<T>,
    ) -> Solution<T> {
        // One length for the three (they are equal), so that the walk below indexes within it
        // without a bounds check: the per-sample path holds no panic.
        let n = self
            .weights
            .as_ref()
            .len()
            .min(self.thresholds.as_ref().len())
            .min(self.memory.as_ref().len());
        let thresholds = &self.thresholds.as_ref()[..n];
        let weights = &self.weights.as_ref()[..n];
        let memory = &self.memory.as_ref()[..n];
        let x_prev = self.input;
        let rising = f_prev <= T::zero();
        let active = if rising {
            self.rising_active
        } else {
            self.falling_active
        }
        .min(n);
        // The moving operators contribute b_i x to the output: w_i + r_i = x_prev rising,
        // w_i = x_prev falling, so their held part is b_i x_prev either way.
        let moving_weight = match active.checked_sub(1) {
            Some(j) => self.prefix.as_ref().get(j).copied().unwrap_or(T::zero()),
            None => T::zero(),
        };
        let mut segment = Segment {
            alpha: self.a + moving_weight,
            beta: self.memory_sum - moving_weight * x_prev,
            moving: active,
            rising,
        };
        let root = |lo: T, hi: T, f_lo: T, f_hi: T, s: &Segment<T>| {
            equation.root(
                lo,
                hi,
                f_lo,
                f_hi,
                s.alpha,
                s.beta,
                self.inverse_alpha(s.moving),
            )
        };
        let found = |input: T, saturated: bool, segment: Segment<T>| Solution {
            input,
            saturated,
            segment,
        };
        if rising {
            let (mut lo, mut f_lo) = (x_prev, f_prev);
            let v_max = limits.max();
            for i in active..n {
                let (w, r, b) = (memory[i], thresholds[i], weights[i]);
                let u = (w + r).max(lo);
                if equation.control(u, segment.alpha, segment.beta) >= v_max {
                    break;
                }
                let f_u = equation.residual(u, segment.alpha, segment.beta);
                if f_u >= T::zero() {
                    return found(root(lo, u, f_lo, f_u, &segment), false, segment);
                }
                // Operator i starts moving at u: b_i w_i becomes b_i (x - r_i).
                segment.moving = i + 1;
                segment.alpha = segment.alpha + b;
                segment.beta = segment.beta - b * (r + w);
                lo = u;
                f_lo = f_u;
            }
            let end = equation.input_at_control(v_max, segment.alpha, segment.beta);
            let f_end = equation.residual(end, segment.alpha, segment.beta);
            if f_end < -equation.rounding(end, segment.alpha, segment.beta) {
                return found(end.max(lo), true, segment);
            }
            found(root(lo, end, f_lo, f_end, &segment), false, segment)
        } else {
            let (mut hi, mut f_hi) = (x_prev, f_prev);
            let v_min = limits.min();
            for i in active..n {
                let (w, b) = (memory[i], weights[i]);
                let l = w.min(hi);
                if equation.control(l, segment.alpha, segment.beta) <= v_min {
                    break;
                }
                let f_l = equation.residual(l, segment.alpha, segment.beta);
                if f_l <= T::zero() {
                    return found(root(l, hi, f_l, f_hi, &segment), false, segment);
                }
                // Operator i starts moving at l: b_i w_i becomes b_i x.
                segment.moving = i + 1;
                segment.alpha = segment.alpha + b;
                segment.beta = segment.beta - b * w;
                hi = l;
                f_hi = f_l;
            }
            let end = equation.input_at_control(v_min, segment.alpha, segment.beta);
            let f_end = equation.residual(end, segment.alpha, segment.beta);
            if f_end > equation.rounding(end, segment.alpha, segment.beta) {
                return found(end.min(hi), true, segment);
            }
            found(root(end, hi, f_end, f_hi, &segment), false, segment)
        }
    }
}
