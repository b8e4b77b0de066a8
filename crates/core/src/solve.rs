//! The scalar root finder of the exact compensators, and the input function's remainder
//! `h(x) = g(x) - a2 x` it works with.

use crate::{InputPolynomial, Real};

/// The remainder `h(x) = g(x) - a2 x` of the input polynomial, as the per-sample solves use it:
/// the paper's `a1 x^3` ([`OddCubic`], its own arithmetic) or a higher-degree polynomial (the
/// [`InputPolynomial`] itself). Each compensator dispatches once per sample and then runs code
/// specialised for the shape.
pub(crate) trait Remainder<T: Real>: Copy {
    /// `h(x)`.
    fn value(self, x: T) -> T;
    /// `h(x) + c x`.
    fn with_linear(self, x: T, c: T) -> T;
    /// `h'(x) + c`.
    fn slope_with_linear(self, x: T, c: T) -> T;
    /// The size of the terms of `h(x)` (`sum |c_j x^j|`), for rounding allowances.
    fn size(self, x: T) -> T;
}

/// `h(x) = a1 x^3`, the paper's cubic.
#[derive(Debug, Clone, Copy)]
pub(crate) struct OddCubic<T>(pub T);

impl<T: Real> Remainder<T> for OddCubic<T> {
    #[inline(always)]
    fn value(self, x: T) -> T {
        self.0 * x * x * x
    }
    #[inline(always)]
    fn with_linear(self, x: T, c: T) -> T {
        (self.0 * x * x + c) * x
    }
    #[inline(always)]
    fn slope_with_linear(self, x: T, c: T) -> T {
        T::from_f64(3.0) * self.0 * x * x + c
    }
    #[inline(always)]
    fn size(self, x: T) -> T {
        (self.0 * x * x * x).abs()
    }
}

impl<T: Real> Remainder<T> for &InputPolynomial<T> {
    #[inline(always)]
    fn value(self, x: T) -> T {
        self.remainder(x)
    }
    #[inline(always)]
    fn with_linear(self, x: T, c: T) -> T {
        self.remainder(x) + c * x
    }
    #[inline(always)]
    fn slope_with_linear(self, x: T, c: T) -> T {
        self.remainder_slope(x) + c
    }
    #[inline(always)]
    fn size(self, x: T) -> T {
        self.remainder_size(x)
    }
}

/// Upper bound on iterations of [`increasing_root`]. Every iteration either shrinks the
/// bracket by bisection or takes a (quasi-)Newton step inside it, so the bound is never reached
/// in practice; 64 halvings alone resolve any bracket of width <= 1e3 to `f64` precision.
pub(crate) const MAX_ITERATIONS: usize = 64;

/// The relative accuracy the exact compensators solve to: `1e-13` in `f64` (the issue asks for
/// 1e-12), a few ulp in `f32`.
#[inline(always)]
fn tolerance<T: Real>() -> T {
    T::from_f64(1e-13).max(T::epsilon() * T::from_f64(8.0))
}

/// The root in `[lo, hi]` of `f(x) = h(x) + c1 x + c0` (`h(x) = c3 x^3` for the paper's cubic),
/// given `f(lo) <= 0 <= f(hi)` and `f` increasing on the interval.
///
/// Starts from the end with the smaller residual (for the small steps of a sampled trajectory,
/// the previous solution), takes a Newton step and then chord steps with the same slope as long
/// as each cuts the residual by 1e3 or more (no division), a fresh Newton step otherwise, and a
/// bisection whenever a step would leave the bracket. Stops when the residual is at the
/// tolerance relative to the size of the terms, or the bracket has collapsed, or after
/// [`MAX_ITERATIONS`].
#[inline]
pub(crate) fn increasing_root<T: Real, R: Remainder<T>>(
    h: R,
    c1: T,
    c0: T,
    mut lo: T,
    mut hi: T,
    f_lo: T,
    f_hi: T,
) -> T {
    if f_lo >= T::zero() || hi <= lo {
        return lo;
    }
    if f_hi <= T::zero() {
        return hi;
    }
    let half = T::from_f64(0.5);
    let chord_gain = T::from_f64(1e-3);
    let tolerance = tolerance::<T>();
    let (mut x, mut f) = if -f_lo <= f_hi {
        (lo, f_lo)
    } else {
        (hi, f_hi)
    };
    let mut inverse_slope = T::one() / h.slope_with_linear(x, c1);
    let mut refresh = false;
    for _ in 0..MAX_ITERATIONS {
        if refresh {
            inverse_slope = T::one() / h.slope_with_linear(x, c1);
        }
        let mut next = x - f * inverse_slope;
        if !(next > lo && next < hi) {
            next = half * (lo + hi);
        }
        let f_next = h.with_linear(next, c1) + c0;
        let size = h.size(next) + (c1 * next).abs() + c0.abs();
        if f_next.abs() <= tolerance * size {
            return next;
        }
        // A Newton step from `next` (fresh slope) within the tolerance of the input's scale:
        // the root is there even when the residual is not small against its terms (a root
        // at 0 with a tiny or subnormal constant term, which a chord approaches only
        // geometrically and which the bracket never closes on).
        let slope = h.slope_with_linear(next, c1);
        if f_next.abs() <= tolerance * next.abs().max(T::one()) * slope.abs() {
            return next;
        }
        if f_next < T::zero() {
            lo = next;
        } else {
            hi = next;
        }
        if hi - lo <= tolerance * next.abs().max(T::one()) {
            return next;
        }
        // A fresh Newton slope unless the chord step cut the residual by 1e3 (NaN: refresh).
        refresh = f_next.abs() > chord_gain * f.abs() || f_next.is_nan();
        x = next;
        f = f_next;
    }
    x
}
