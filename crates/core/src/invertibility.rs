//! Where the branch slopes of an MPIM must be checked for it to be invertible.
//!
//! Given the operators' memory, the MPIM output of eq. (4) is a continuous, piecewise-cubic
//! function of the current input `x` (ERRATA item 4). While the input moves, operator `i` either
//! holds its memory (slope 0) or moves with the input (slope 1). From the reset state (zero
//! memory, eq. (1)) the operators moving together are always the first `k` by threshold, and
//! operator `k` can only be moving at an input `x` with `x >= lo + r_k` (after rising by `r_k`) or
//! `x <= max(hi - r_k, 0)` (after falling by `r_k`, or falling from the reset state). The slope of
//! such a branch is `a2 + 3 a1 x^2 + b_1 + ... + b_k`, a function of `x^2` only, so over an
//! interval of `x` it is smallest at the smallest or at the largest `x^2`. Checking those few
//! points for every reachable `k` is therefore exact, and the identification uses the very same
//! points as linear constraints on `(a1, a2, b)`.

use crate::Real;

/// [`branch_checkpoints`] with the weight of the moving operators: calls `visit(k, x, b_1 + ...
/// + b_k)`. The sums come from a running prefix, since `k` only increases.
fn moving_weight_checkpoints<T: Real>(
    thresholds: &[T],
    weights: &[T],
    lo: T,
    hi: T,
    mut visit: impl FnMut(usize, T, T),
) {
    let mut summed = 0;
    let mut prefix = T::zero();
    branch_checkpoints(thresholds, lo, hi, |k, x| {
        while summed < k {
            prefix = prefix + weights.get(summed).copied().unwrap_or(T::zero());
            summed += 1;
        }
        visit(k, x, prefix);
    });
}

/// The smallest branch slope of a model over an input range, and where it occurs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchSlope<T> {
    /// `a2 + 3 a1 x^2 + b_1 + ... + b_k`.
    pub slope: T,
    /// The (normalised) input `x`.
    pub input: T,
    /// `k`, the number of operators (the first ones by threshold) moving with the input.
    pub active_operators: usize,
}

/// Calls `visit(k, x)` for every checkpoint: each number `k` of moving operators reachable within
/// the input range `[min(lo, 0), max(hi, 0)]` (the range always includes the reset input 0, since
/// the memory starts at zero), with the inputs `x` where the branch slope of that `k` is extreme.
///
/// `thresholds` must be sorted increasingly (as [`crate::Mpim`] guarantees). A model is
/// invertible on the range when `a2 + 3 a1 x^2 + b_1 + ... + b_k > 0` at every checkpoint.
pub fn branch_checkpoints<T: Real>(
    thresholds: &[T],
    lo: T,
    hi: T,
    mut visit: impl FnMut(usize, T),
) {
    let zero = T::zero();
    let lo = lo.min(zero);
    let hi = hi.max(zero);
    // Operators with r = 0 always move with the input (F_0[x] = x).
    let always = thresholds.iter().take_while(|r| **r <= zero).count();
    let mut visit_interval = |k: usize, p: T, q: T| {
        visit(k, p);
        visit(k, q);
        if p < zero && zero < q {
            visit(k, zero);
        }
    };
    for k in always..=thresholds.len() {
        let r = match k.checked_sub(1) {
            Some(j) => thresholds.get(j).copied().unwrap_or(zero),
            None => zero,
        };
        // Falling: reachable down to lo from max(hi - r, 0).
        let falling_top = (hi - r).max(zero);
        // Rising: reachable from lo + r up to hi.
        let rising_bottom = lo + r;
        if rising_bottom <= falling_top {
            visit_interval(k, lo, hi);
        } else {
            visit_interval(k, lo, falling_top);
            if rising_bottom <= hi {
                visit_interval(k, rising_bottom, hi);
            }
        }
    }
}

/// The smallest branch slope of `a2 + 3 a1 x^2 + sum b_i F_ri` over the checkpoints of
/// [`branch_checkpoints`].
pub(crate) fn min_branch_slope<T: Real>(
    thresholds: &[T],
    weights: &[T],
    a1: T,
    a2: T,
    lo: T,
    hi: T,
) -> BranchSlope<T> {
    let three = T::from_f64(3.0);
    let mut worst = BranchSlope {
        slope: T::infinity(),
        input: lo,
        active_operators: 0,
    };
    moving_weight_checkpoints(thresholds, weights, lo, hi, |k, x, prefix| {
        let slope = a2 + three * a1 * x * x + prefix;
        if slope < worst.slope {
            worst = BranchSlope {
                slope,
                input: x,
                active_operators: k,
            };
        }
    });
    worst
}

/// The worst-case small-signal loop gain of the delayed WIHC (eq. (9) with `H[v](t - Ts)`) over
/// an input range, and where it occurs. See [`crate::Mpim::delayed_wihc_loop_gain`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopGain<T> {
    /// `|3 a1 x^2 + b_1 + ... + b_k| / a2`: below 1 the delayed loop contracts on every branch
    /// and settles after a jump in `y_d`; at or above 1 it can ring between the output limits.
    pub gain: T,
    /// The (normalised) input `x` where it occurs.
    pub input: T,
    /// `k`, the number of operators (the first ones by threshold) moving with the input there.
    pub active_operators: usize,
}

/// The largest `|3 a1 x^2 + b_1 + ... + b_k| / a2` over the checkpoints of
/// [`branch_checkpoints`] (the quantity is a function of `x^2`, so its extremes over each
/// reachable interval lie at those points).
pub(crate) fn max_delayed_loop_gain<T: Real>(
    thresholds: &[T],
    weights: &[T],
    a1: T,
    a2: T,
    lo: T,
    hi: T,
) -> LoopGain<T> {
    let three = T::from_f64(3.0);
    let mut worst = LoopGain {
        gain: T::zero(),
        input: lo,
        active_operators: 0,
    };
    moving_weight_checkpoints(thresholds, weights, lo, hi, |k, x, prefix| {
        let gain = delayed_loop_gain_at(three, a1, a2, x, prefix);
        // NaN (a2 = 0) must not hide: it compares false, so test it explicitly.
        if gain > worst.gain || gain.is_nan() {
            worst = LoopGain {
                gain,
                input: x,
                active_operators: k,
            };
        }
    });
    worst
}

/// The delayed WIHC's small-signal loop gain `|3 a1 x^2 + b_1 + ... + b_k| / a2` (eq. (9) with
/// `H[v](t - Ts)`) at `x`, given the moving operators' weight `b_1 + ... + b_k` and `three = 3`.
#[inline]
fn delayed_loop_gain_at<T: Real>(three: T, a1: T, a2: T, x: T, moving_weight: T) -> T {
    (three * a1 * x * x + moving_weight).abs() / a2
}

/// Calls `visit(gain, x)` with the delayed WIHC's loop gain at the checkpoints of
/// [`branch_checkpoints`] for the branch around a reversal, where only the always-moving
/// (zero-threshold) operators move (`k` = their number, the first `k` the walk visits). The
/// same walk and formula as [`max_delayed_loop_gain`], restricted to that `k`; the points come
/// in the walk's order: `min(lo, 0)`, `max(hi, 0)`, then 0 when it lies strictly between.
pub(crate) fn reversal_loop_gains<T: Real>(
    thresholds: &[T],
    weights: &[T],
    a1: T,
    a2: T,
    lo: T,
    hi: T,
    mut visit: impl FnMut(T, T),
) {
    let three = T::from_f64(3.0);
    let always = thresholds.iter().take_while(|r| **r <= T::zero()).count();
    moving_weight_checkpoints(thresholds, weights, lo, hi, |k, x, prefix| {
        if k == always {
            visit(delayed_loop_gain_at(three, a1, a2, x, prefix), x);
        }
    });
}
