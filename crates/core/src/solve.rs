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
    /// `h''(x)`.
    fn curvature(self, x: T) -> T;
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
    fn curvature(self, x: T) -> T {
        T::from_f64(6.0) * self.0 * x
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
    fn curvature(self, x: T) -> T {
        self.remainder_curvature(x)
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
pub(crate) fn tolerance<T: Real>() -> T {
    T::from_f64(1e-13).max(T::epsilon() * T::from_f64(8.0))
}

/// Whether the finder takes Halley's steps, every iteration (`f64`), rather than Newton's
/// followed by chord steps (`f32`; see [`increasing_root`]). From the first segment's end,
/// about 1e-3 of the bracket from the root, Newton's step and the chords after it approach
/// `f64`'s `1e-13` in three or four iterations (about 1e-6, 1e-9, 1e-12, 1e-15) and Halley's
/// in two (1e-9, 1e-27), which saves a bank of eight lanes (which iterates as long as its
/// slowest lane) one or two iterations of its dependent chain; `f32`'s few ulp take Newton
/// and one chord step, where Halley's would add its arithmetic and save nothing. Measured on
/// the bank's workload (`hystcomp bench --channels`'s, 64 single IHC channels, 200 ticks):
/// `f64` solves take two iterations in all but 0.4 % of samples (three in 66 % and four in
/// 30 % with Newton's steps and chords); in `f32` Halley's first step and chords would take
/// one in 69 % (16 % with Newton's) and made the bank no faster and the single compensator
/// slower.
#[inline(always)]
pub(crate) fn halley_steps<T: Real>() -> bool {
    tolerance::<T>() < T::from_f64(1e-10)
}

/// The reciprocal of the slope a step from `x` (where `f(x) = f`) divides by: Newton's
/// `1 / f'`, or with `halley` Halley's `f' - f f'' / (2 f')`, as `2 f' / (2 f'^2 - f f'')`
/// (one division, a third-order step; Newton's where the correction would more than double
/// the step, `f f'' >= f'^2`).
#[inline(always)]
fn inverse_step_slope<T: Real, R: Remainder<T>>(h: R, x: T, c1: T, f: T, halley: bool) -> T {
    let slope = h.slope_with_linear(x, c1);
    if !halley {
        return T::one() / slope;
    }
    let twice = slope + slope;
    let newton = twice * slope;
    let corrected = newton - f * h.curvature(x);
    let denominator = if corrected > slope * slope {
        corrected
    } else {
        newton
    };
    twice / denominator
}

/// The root in `[lo, hi]` of `f(x) = h(x) + c1 x + c0` (`h(x) = c3 x^3` for the paper's cubic),
/// given `f(lo) <= 0 <= f(hi)` and `f` increasing on the interval.
///
/// Starts from the end with the smaller residual (for the small steps of a sampled trajectory,
/// the previous solution). In `f64` ([`halley_steps`]) every step is Halley's; in `f32` a
/// Newton step is followed by chord steps with the same slope as long as each cuts the
/// residual by 1e3 or more (no division), a fresh Newton step otherwise. A bisection whenever
/// a step would leave the bracket. Stops when the residual is at the
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
    let halley = halley_steps::<T>();
    let (mut x, mut f) = if -f_lo <= f_hi {
        (lo, f_lo)
    } else {
        (hi, f_hi)
    };
    let mut inverse_slope = inverse_step_slope(h, x, c1, f, halley);
    let mut refresh = false;
    for _ in 0..MAX_ITERATIONS {
        if refresh {
            inverse_slope = inverse_step_slope(h, x, c1, f, halley);
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
        // A fresh slope for Halley's steps; for Newton's unless the chord step cut the
        // residual by 1e3 (NaN: refresh).
        refresh = halley || f_next.abs() > chord_gain * f.abs() || f_next.is_nan();
        x = next;
        f = f_next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MAX_INPUT_DEGREE;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random input polynomial of degree 1 to `MAX_INPUT_DEGREE` with `c_j` in [-1, 1]
    /// (the paper's odd cubic one time in four).
    fn polynomial(rng: &mut ChaCha8Rng) -> InputPolynomial<f64> {
        if rng.random::<f64>() < 0.25 {
            return InputPolynomial::cubic(rng.random::<f64>(), 0.5 + rng.random::<f64>())
                .expect("finite");
        }
        let degree = 1 + (rng.random::<f64>() * MAX_INPUT_DEGREE as f64) as usize;
        let mut c = [0.0; MAX_INPUT_DEGREE];
        for c in c.iter_mut() {
            *c = 2.0 * rng.random::<f64>() - 1.0;
        }
        InputPolynomial::new(&c[..degree.min(MAX_INPUT_DEGREE)])
            .expect("finite, 1 to 9 coefficients")
    }

    /// `h''(x)` term by term with `powi`: the plain reference.
    fn curvature_reference(p: &InputPolynomial<f64>, x: f64) -> (f64, f64) {
        let mut value = 0.0;
        let mut size = 0.0;
        for (i, &c) in p.coefficients().iter().enumerate().skip(1) {
            let j = (i + 1) as f64;
            let term = j * (j - 1.0) * c * x.powi(i as i32 - 1);
            value += term;
            size += term.abs();
        }
        (value, size)
    }

    #[test]
    fn curvature_is_the_remainders_second_derivative() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..2000 {
            let p = polynomial(&mut rng);
            let x = 4.0 * rng.random::<f64>() - 2.0;
            let (expected, size) = curvature_reference(&p, x);
            let got = p.remainder_curvature(x);
            assert!(
                (got - expected).abs() <= 1e-13 * (1.0 + size),
                "{:?} at {x}: {got} against {expected}",
                p.coefficients()
            );
            assert_eq!(OddCubic(p.a1()).curvature(x), 6.0 * p.a1() * x);
        }
    }

    /// The root of an increasing `f` in `[lo, hi]` by 200 halvings: the plain reference.
    fn bisection(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if f(mid) < 0.0 { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    }

    #[test]
    fn the_root_finder_agrees_with_bisection_on_random_increasing_polynomials() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let mut checked = 0;
        while checked < 3000 {
            let p = polynomial(&mut rng);
            let lo = 2.0 * rng.random::<f64>() - 1.0;
            // Brackets from 1e-6 (a sample's step) to 1 wide.
            let hi = lo + 10f64.powf(-6.0 * rng.random::<f64>());
            let c1 = 4.0 * rng.random::<f64>() - 2.0;
            // `f` must increase on the bracket: its slope at the ends and at the critical
            // points of `g'` (where the slope is extreme) positive.
            let slope = |x: f64| p.remainder_slope(x) + c1;
            let mut increasing = slope(lo) > 0.0 && slope(hi) > 0.0;
            p.slope_critical_points(lo, hi, |x| increasing &= slope(x) > 0.0);
            if !increasing {
                continue;
            }
            let root = lo + (hi - lo) * rng.random::<f64>();
            let c0 = -(p.remainder(root) + c1 * root);
            let f = |x: f64| p.remainder(x) + c1 * x + c0;
            let (f_lo, f_hi) = (f(lo), f(hi));
            let got = if p.is_odd_cubic() {
                increasing_root(OddCubic(p.a1()), c1, c0, lo, hi, f_lo, f_hi)
            } else {
                increasing_root(&p, c1, c0, lo, hi, f_lo, f_hi)
            };
            let expected = bisection(f, lo, hi);
            assert!((lo..=hi).contains(&got), "{got} outside [{lo}, {hi}]");
            // Both within rounding of the root: the bisection's own error is where `f` is
            // below its rounding, 1e-13 of the scale besides the tolerance.
            let scale = got.abs().max(1.0);
            let size = Remainder::size(&p, got) + (c1 * got).abs() + c0.abs();
            let allowance = 1e-12 * scale + 1e-13 * size / slope(got);
            assert!(
                (got - expected).abs() <= allowance,
                "{:?}, c1 {c1}, [{lo}, {hi}]: {got} against {expected}",
                p.coefficients()
            );
            checked += 1;
        }
    }
}
