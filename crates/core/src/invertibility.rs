//! Where the branch slopes and the delayed loops' gains of an MPIM must be checked.
//!
//! Given the operators' memory, the MPIM output of eq. (4) is a continuous, piecewise-polynomial
//! function of the current input `x` (ERRATA item 4). While the input moves, operator `i` either
//! holds its memory (slope 0) or moves with the input (slope 1). From the reset state (zero
//! memory, eq. (1)) the operators moving together are always the first `k` by threshold, and
//! operator `k` can only be moving at an input `x` with `x >= lo + r_k` (after rising by `r_k`) or
//! `x <= max(hi - r_k, 0)` (after falling by `r_k`, or falling from the reset state): for each
//! reachable `k` one or two intervals of `x` ([`branch_intervals`]). The slope of such a branch
//! is `g'(x) + b_1 + ... + b_k`, with `g` the input polynomial ([`crate::InputPolynomial`]); over
//! an interval it is extreme at the interval's ends or where `g'' = 0` inside it. For the
//! paper's cubic `g'(x) = a2 + 3 a1 x^2` is a function of `x^2`, so the ends and 0 suffice
//! ([`branch_checkpoints`]); the identification uses the very same points as linear
//! constraints on `(a1, a2, b)`. Checking these few points for every reachable `k` is exact,
//! and so are the delayed loops' gains below, which are functions of `g'(x)` and `k` too.

use crate::{InputPolynomial, MAX_INPUT_DEGREE, Real};

/// Calls `visit(k, p, q)` for every number `k` of moving operators reachable within the input
/// range `[min(lo, 0), max(hi, 0)]` (the range always includes the reset input 0, since the
/// memory starts at zero), with each interval `[p, q]` of inputs where the first `k` operators
/// can be moving together (one or two intervals per `k`).
///
/// `thresholds` must be sorted increasingly (as [`crate::Mpim`] guarantees).
pub fn branch_intervals<T: Real>(
    thresholds: &[T],
    lo: T,
    hi: T,
    mut visit: impl FnMut(usize, T, T),
) {
    let zero = T::zero();
    let lo = lo.min(zero);
    let hi = hi.max(zero);
    // Operators with r = 0 always move with the input (F_0[x] = x).
    let always = thresholds.iter().take_while(|r| **r <= zero).count();
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
            visit(k, lo, hi);
        } else {
            visit(k, lo, falling_top);
            if rising_bottom <= hi {
                visit(k, rising_bottom, hi);
            }
        }
    }
}

/// Calls `visit(k, x)` for every checkpoint of the paper's cubic input function: each interval
/// of [`branch_intervals`] gives its two ends, and 0 when it lies strictly inside (where
/// `x^2`, and so `a2 + 3 a1 x^2 + b_1 + ... + b_k`, is extreme).
///
/// A model with the cubic `g` is invertible on the range when
/// `a2 + 3 a1 x^2 + b_1 + ... + b_k > 0` at every checkpoint. For a higher-degree `g` the
/// extremes also lie where `g'' = 0` ([`InputPolynomial::slope_critical_points`]), which
/// depends on the coefficients.
pub fn branch_checkpoints<T: Real>(
    thresholds: &[T],
    lo: T,
    hi: T,
    mut visit: impl FnMut(usize, T),
) {
    let zero = T::zero();
    branch_intervals(thresholds, lo, hi, |k, p, q| {
        visit(k, p);
        visit(k, q);
        if p < zero && zero < q {
            visit(k, zero);
        }
    });
}

/// The checkpoints of a model with input polynomial `g`: every interval of
/// [`branch_intervals`] with its ends and the roots of `g''` inside it; calls
/// `visit(k, x, b_1 + ... + b_k)`. For the paper's cubic these are exactly the points of
/// [`branch_checkpoints`]. The weight sums come from a running prefix, since `k` only increases.
pub(crate) fn model_checkpoints<T: Real>(
    thresholds: &[T],
    weights: &[T],
    input: &InputPolynomial<T>,
    lo: T,
    hi: T,
    mut visit: impl FnMut(usize, T, T),
) {
    // The roots of g'' over the whole range, once; each interval takes those inside it.
    let mut critical = [T::zero(); MAX_INPUT_DEGREE];
    let mut count = 0;
    input.slope_critical_points(lo.min(T::zero()), hi.max(T::zero()), |x| {
        if count < MAX_INPUT_DEGREE {
            critical[count] = x;
            count += 1;
        }
    });
    let mut summed = 0;
    let mut prefix = T::zero();
    branch_intervals(thresholds, lo, hi, |k, p, q| {
        while summed < k {
            prefix = prefix + weights.get(summed).copied().unwrap_or(T::zero());
            summed += 1;
        }
        visit(k, p, prefix);
        visit(k, q, prefix);
        for &x in &critical[..count] {
            if p < x && x < q {
                visit(k, x, prefix);
            }
        }
    });
}

/// The smallest branch slope of a model over an input range, and where it occurs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchSlope<T> {
    /// `g'(x) + b_1 + ... + b_k` (`a2 + 3 a1 x^2 + b_1 + ... + b_k` for the paper's cubic).
    pub slope: T,
    /// The (normalised) input `x`.
    pub input: T,
    /// `k`, the number of operators (the first ones by threshold) moving with the input.
    pub active_operators: usize,
}

/// The smallest branch slope `g'(x) + b_1 + ... + b_k` over the checkpoints of
/// [`model_checkpoints`].
pub(crate) fn min_branch_slope<T: Real>(
    thresholds: &[T],
    weights: &[T],
    input: &InputPolynomial<T>,
    lo: T,
    hi: T,
) -> BranchSlope<T> {
    let mut worst = BranchSlope {
        slope: T::infinity(),
        input: lo,
        active_operators: 0,
    };
    model_checkpoints(thresholds, weights, input, lo, hi, |k, x, prefix| {
        let slope = input.slope(x) + prefix;
        if slope < worst.slope || slope.is_nan() {
            worst = BranchSlope {
                slope,
                input: x,
                active_operators: k,
            };
        }
    });
    worst
}

/// The worst-case small-signal loop gain of a one-sample-delayed compensator (IHC or WIHC)
/// over an input range, and where it occurs. See [`crate::Mpim::delayed_ihc_loop_gain`] and
/// [`crate::Mpim::delayed_wihc_loop_gain`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopGain<T> {
    /// The largest gain over the reachable branches: `|g'(x) - a2 + b_1 + ... + b_k| / a2` for
    /// the delayed WIHC, `|g'(x) - a2| / (a2 + b_1 + ... + b_k)` for the delayed IHC (for the
    /// paper's cubic `g'(x) - a2 = 3 a1 x^2`). Below 1 the delayed loop contracts on every
    /// branch and settles after a jump in `y_d`; at or above 1 it can ring between the output
    /// limits, and the constructors refuse it unless asked explicitly
    /// ([`crate::SolveMode::DelayedAllowUnstable`]).
    pub gain: T,
    /// The (normalised) input `x` where it occurs.
    pub input: T,
    /// `k`, the number of operators (the first ones by threshold) moving with the input there.
    pub active_operators: usize,
}

/// Which delayed loop a gain belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum DelayedLoop {
    /// `w(t) = y_d(t) - h(v(t - Ts))`, `v = P1^{-1}[w]` (eq. (5) with the loop broken).
    Ihc,
    /// `v(t) = (y_d(t) - H[v](t - Ts)) / a2` (eq. (9) with the loop broken).
    Wihc,
}

/// The range of a delayed loop's signed gain `q(k, x)` over the reachable branches, where the
/// loop's error is multiplied by `-q` each sample (small signal):
/// `q = (g'(x) - a2 + b_1 + ... + b_k) / a2` (WIHC) or `(g'(x) - a2) / (a2 + b_1 + ... + b_k)`
/// (IHC). `1 + q` is the model's branch slope over the slope of the part the loop inverts
/// exactly (`a2` for WIHC, the PI part for IHC): positive for an invertible model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GainRange<T> {
    /// The largest `|q|`, where it occurs.
    pub worst: LoopGain<T>,
    /// The largest `q`.
    pub largest: T,
    /// The smallest `q`.
    pub smallest: T,
}

impl<T: Real> GainRange<T> {
    /// The under-relaxation of the guarded delayed loop ([`crate::SolveMode::DelayedGuarded`]):
    /// `min(1, 1 / (1 + largest))`, so that `relaxation * (1 + q) <= 1` on every branch.
    pub fn relaxation(&self) -> T {
        let one = T::one();
        let top = one + self.largest;
        if top > one { one / top } else { one }
    }
}

/// The range of the signed gain of `which` loop over the checkpoints of [`model_checkpoints`]
/// (`q` depends on `x` only through `g'(x)`, so its extremes over each reachable interval lie
/// at those points).
pub(crate) fn delayed_gain_range<T: Real>(
    which: DelayedLoop,
    thresholds: &[T],
    weights: &[T],
    input: &InputPolynomial<T>,
    lo: T,
    hi: T,
) -> GainRange<T> {
    let a2 = input.a2();
    let mut range = GainRange {
        worst: LoopGain {
            gain: T::zero(),
            input: lo,
            active_operators: 0,
        },
        largest: T::neg_infinity(),
        smallest: T::infinity(),
    };
    model_checkpoints(thresholds, weights, input, lo, hi, |k, x, prefix| {
        let q = match which {
            DelayedLoop::Wihc => (input.remainder_slope(x) + prefix) / a2,
            // A branch whose PI slope is not positive has no inverse (eq. (7) divides by it):
            // no delayed IHC exists there, so its gain is NaN, not a finite `|q|` of a
            // meaningless sign (the constructors refuse such a model as not invertible).
            DelayedLoop::Ihc if a2 + prefix > T::zero() => input.remainder_slope(x) / (a2 + prefix),
            DelayedLoop::Ihc => T::nan(),
        };
        let gain = q.abs();
        // NaN (a2 = 0, or a PI part with zero slope) must not hide: it compares false.
        if gain > range.worst.gain || gain.is_nan() {
            range.worst = LoopGain {
                gain,
                input: x,
                active_operators: k,
            };
        }
        if q > range.largest || q.is_nan() {
            range.largest = q;
        }
        if q < range.smallest || q.is_nan() {
            range.smallest = q;
        }
    });
    range
}
