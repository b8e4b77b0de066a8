//! The scalar root finder of the exact compensators.

use crate::Real;

/// Upper bound on iterations of [`increasing_cubic_root`]. Each iteration at least halves the
/// bracket or takes a Newton step inside it, so 64 iterations reach the resolution of `f64` from
/// any bracket of width <= 1e3.
pub(crate) const MAX_ITERATIONS: usize = 64;

/// The root in `[lo, hi]` of `f(x) = c3 x^3 + c1 x + c0`, given `f(lo) <= 0 <= f(hi)` and `f`
/// increasing on the interval: Newton's method safeguarded by bisection, started from the
/// secant (regula falsi) point. Stops when a step is below 16 ulp of the iterate, when `f`
/// vanishes, or after [`MAX_ITERATIONS`].
#[inline]
pub(crate) fn increasing_cubic_root<T: Real>(
    c3: T,
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
    let three = T::from_f64(3.0);
    let half = T::from_f64(0.5);
    let tolerance = T::epsilon() * T::from_f64(16.0);
    let mut x = lo - f_lo * (hi - lo) / (f_hi - f_lo);
    if !(x > lo && x < hi) {
        x = half * (lo + hi);
    }
    for _ in 0..MAX_ITERATIONS {
        let x2 = x * x;
        let f = (c3 * x2 + c1) * x + c0;
        if f == T::zero() {
            return x;
        }
        if f < T::zero() {
            lo = x;
        } else {
            hi = x;
        }
        let slope = three * c3 * x2 + c1;
        let mut next = x - f / slope;
        if !(next > lo && next < hi) {
            next = half * (lo + hi);
        }
        let scale = x.abs().max(T::one());
        if (next - x).abs() <= tolerance * scale || hi - lo <= tolerance * scale {
            return next;
        }
        x = next;
    }
    x
}
