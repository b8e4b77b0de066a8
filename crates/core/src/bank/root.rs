//! The input function's remainder `h(x) = g(x) - a2 x` and the scalar root finder of
//! `crate::solve`, lane by lane: the same operations in the same order, the finder's
//! iterations masked per lane (a block iterates as long as its slowest lane).

use super::lanes::{Lanes, Mask};
use crate::{MAX_INPUT_DEGREE, Real};

/// The remainder `h` of every lane of a block (`crate::solve::Remainder` lane by lane).
pub(crate) trait LaneRemainder<T: Real, const W: usize>: Copy {
    /// `h(x)`.
    fn value(self, x: Lanes<T, W>) -> Lanes<T, W>;
    /// `h(x) + c x`.
    fn with_linear(self, x: Lanes<T, W>, c: Lanes<T, W>) -> Lanes<T, W>;
    /// `h'(x) + c`.
    fn slope_with_linear(self, x: Lanes<T, W>, c: Lanes<T, W>) -> Lanes<T, W>;
    /// `h''(x)`.
    fn curvature(self, x: Lanes<T, W>) -> Lanes<T, W>;
    /// `sum |c_j x^j|` over the terms of `h`.
    fn size(self, x: Lanes<T, W>) -> Lanes<T, W>;
    /// `g(x) = h(x) + a2 x` as `crate::InputPolynomial::value` evaluates it (DIHC's eq. (10)).
    fn input_function(self, x: Lanes<T, W>, a2: Lanes<T, W>) -> Lanes<T, W>;
}

/// `h(x) = a1 x^3` in every lane: the paper's cubic (`crate::solve::OddCubic`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct CubicLanes<T, const W: usize>(pub Lanes<T, W>);

impl<T: Real, const W: usize> LaneRemainder<T, W> for CubicLanes<T, W> {
    #[inline(always)]
    fn value(self, x: Lanes<T, W>) -> Lanes<T, W> {
        self.0 * x * x * x
    }
    #[inline(always)]
    fn with_linear(self, x: Lanes<T, W>, c: Lanes<T, W>) -> Lanes<T, W> {
        (self.0 * x * x + c) * x
    }
    #[inline(always)]
    fn slope_with_linear(self, x: Lanes<T, W>, c: Lanes<T, W>) -> Lanes<T, W> {
        Lanes::splat(T::from_f64(3.0)) * self.0 * x * x + c
    }
    #[inline(always)]
    fn curvature(self, x: Lanes<T, W>) -> Lanes<T, W> {
        Lanes::splat(T::from_f64(6.0)) * self.0 * x
    }
    #[inline(always)]
    fn size(self, x: Lanes<T, W>) -> Lanes<T, W> {
        (self.0 * x * x * x).abs()
    }
    #[inline(always)]
    fn input_function(self, x: Lanes<T, W>, a2: Lanes<T, W>) -> Lanes<T, W> {
        (self.0 * x * x + a2) * x
    }
}

/// Input polynomials of different degrees side by side (`&crate::InputPolynomial` lane by
/// lane): the coefficients `c_1 .. c_rows` of every lane, each lane's own degree (higher
/// coefficients are skipped, not multiplied by zero, so that the bits equal its own), and the
/// lanes that are the paper's odd cubic, which take its arithmetic.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PolynomialLanes<T: Real, const W: usize> {
    /// `coefficients[j]` is `c_{j + 1}` of every lane (0 beyond a lane's degree).
    pub coefficients: [Lanes<T, W>; MAX_INPUT_DEGREE],
    /// How many coefficient rows the bank stores (the largest degree, at least 3).
    pub rows: usize,
    /// Each lane's number of coefficients `D`.
    pub degree: Lanes<u32, W>,
    /// The lanes with the paper's odd cubic.
    pub odd_cubic: Mask<T, W>,
}

impl<T: Real, const W: usize> PolynomialLanes<T, W> {
    #[inline(always)]
    fn a1(&self) -> Lanes<T, W> {
        self.coefficients[2]
    }

    /// Whether coefficient `j` (of `x^(j + 1)`) belongs to each lane.
    #[inline(always)]
    fn has(&self, j: usize) -> Mask<T, W> {
        let j = j as u32;
        self.degree.test(|d| j < d)
    }

    /// The coefficients `c_2 .. c_rows` (of `x^2` and up), as a slice whose length the loops
    /// below take from it (no index to check, no panic path).
    #[inline(always)]
    fn higher(&self) -> &[Lanes<T, W>] {
        self.coefficients
            .get(1..self.rows.min(MAX_INPUT_DEGREE))
            .unwrap_or(&[])
    }

    /// `sum_{j >= 2} c_j x^(j - 2)` by Horner's rule from each lane's top coefficient.
    #[inline(always)]
    fn higher_horner(&self, x: Lanes<T, W>) -> Lanes<T, W> {
        let mut p = Lanes::zero();
        for (k, &c) in self.higher().iter().enumerate().rev() {
            p = (p * x + c).or_keep(self.has(k + 1), p);
        }
        p
    }

    /// The general (not odd-cubic) remainder.
    #[inline(always)]
    fn general_value(&self, x: Lanes<T, W>) -> Lanes<T, W> {
        self.higher_horner(x) * x * x
    }

    /// The general remainder's slope `sum_{j >= 2} j c_j x^(j - 1)`.
    #[inline(always)]
    fn general_slope(&self, x: Lanes<T, W>) -> Lanes<T, W> {
        let mut p = Lanes::zero();
        for (k, &c) in self.higher().iter().enumerate().rev() {
            let j = k + 1;
            let term = Lanes::splat(T::from_f64((j + 1) as f64)) * c;
            p = (p * x + term).or_keep(self.has(j), p);
        }
        p * x
    }

    /// The general remainder's curvature `sum_{j >= 2} j (j - 1) c_j x^(j - 2)`.
    #[inline(always)]
    fn general_curvature(&self, x: Lanes<T, W>) -> Lanes<T, W> {
        let mut p = Lanes::zero();
        for (k, &c) in self.higher().iter().enumerate().rev() {
            let i = k + 1;
            let term = Lanes::splat(T::from_f64(((i + 1) * i) as f64)) * c;
            p = (p * x + term).or_keep(self.has(i), p);
        }
        p
    }

    #[inline(always)]
    fn general_size(&self, x: Lanes<T, W>) -> Lanes<T, W> {
        let mut power = x * x;
        let mut size = Lanes::zero();
        for (k, &c) in self.higher().iter().enumerate() {
            size = (size + (c * power).abs()).or_keep(self.has(k + 1), size);
            power = power * x;
        }
        size
    }
}

impl<T: Real, const W: usize> LaneRemainder<T, W> for PolynomialLanes<T, W> {
    #[inline(always)]
    fn value(self, x: Lanes<T, W>) -> Lanes<T, W> {
        let cubic = CubicLanes(self.a1()).value(x);
        cubic.or_keep(self.odd_cubic, self.general_value(x))
    }
    #[inline(always)]
    fn with_linear(self, x: Lanes<T, W>, c: Lanes<T, W>) -> Lanes<T, W> {
        let cubic = CubicLanes(self.a1()).with_linear(x, c);
        cubic.or_keep(self.odd_cubic, self.general_value(x) + c * x)
    }
    #[inline(always)]
    fn slope_with_linear(self, x: Lanes<T, W>, c: Lanes<T, W>) -> Lanes<T, W> {
        let cubic = CubicLanes(self.a1()).slope_with_linear(x, c);
        cubic.or_keep(self.odd_cubic, self.general_slope(x) + c)
    }
    #[inline(always)]
    fn curvature(self, x: Lanes<T, W>) -> Lanes<T, W> {
        let cubic = CubicLanes(self.a1()).curvature(x);
        cubic.or_keep(self.odd_cubic, self.general_curvature(x))
    }
    #[inline(always)]
    fn size(self, x: Lanes<T, W>) -> Lanes<T, W> {
        let cubic = CubicLanes(self.a1()).size(x);
        cubic.or_keep(self.odd_cubic, self.general_size(x))
    }
    #[inline(always)]
    fn input_function(self, x: Lanes<T, W>, a2: Lanes<T, W>) -> Lanes<T, W> {
        let cubic = CubicLanes(self.a1()).input_function(x, a2);
        cubic.or_keep(self.odd_cubic, (self.higher_horner(x) * x + a2) * x)
    }
}

/// `crate::solve::inverse_step_slope` in every lane.
#[inline(always)]
fn inverse_step_slope<T: Real, R: LaneRemainder<T, W>, const W: usize>(
    h: R,
    x: Lanes<T, W>,
    c1: Lanes<T, W>,
    f: Lanes<T, W>,
    halley: bool,
) -> Lanes<T, W> {
    let slope = h.slope_with_linear(x, c1);
    if !halley {
        return Lanes::splat(T::one()) / slope;
    }
    let twice = slope + slope;
    let newton = twice * slope;
    let corrected = newton - f * h.curvature(x);
    let denominator = corrected.or_keep(corrected.gt(slope * slope), newton);
    twice / denominator
}

/// `crate::solve::increasing_root` in every lane of `active`: the root in `[lo, hi]` of
/// `f(x) = h(x) + c1 x + c0`, given `f(lo) <= 0 <= f(hi)` and `f` increasing. Each lane takes
/// the steps its scalar twin takes and stops where it stops; the block runs until its last
/// lane has stopped (at most `crate::solve::MAX_ITERATIONS` iterations).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn increasing_root<T: Real, R: LaneRemainder<T, W>, const W: usize>(
    h: R,
    c1: Lanes<T, W>,
    c0: Lanes<T, W>,
    mut lo: Lanes<T, W>,
    mut hi: Lanes<T, W>,
    f_lo: Lanes<T, W>,
    f_hi: Lanes<T, W>,
    active: Mask<T, W>,
) -> Lanes<T, W> {
    let zero = Lanes::zero();
    // The early returns: the bracket's ends.
    let at_lo = f_lo.ge(zero) | hi.le(lo);
    let at_hi = f_hi.le(zero).and_not(at_lo);
    let mut result = hi.or_keep(at_hi, lo);
    let mut done = !active | at_lo | at_hi;
    if done.all() {
        return result;
    }
    let half = Lanes::splat(T::from_f64(0.5));
    let chord_gain = Lanes::splat(T::from_f64(1e-3));
    let tolerance = Lanes::splat(crate::solve::tolerance::<T>());
    let halley = crate::solve::halley_steps::<T>();
    let one = Lanes::splat(T::one());
    let from_lo = (-f_lo).le(f_hi);
    let mut x = lo.or_keep(from_lo, hi);
    let mut f = f_lo.or_keep(from_lo, f_hi);
    let mut inverse_slope = inverse_step_slope(h, x, c1, f, halley);
    let mut refresh = Mask::splat(false);
    for _ in 0..crate::solve::MAX_ITERATIONS {
        let running = !done;
        if (refresh & running).any() {
            inverse_slope = inverse_step_slope(h, x, c1, f, halley).or_keep(refresh, inverse_slope);
        }
        let mut next = x - f * inverse_slope;
        let inside = next.gt(lo) & next.lt(hi);
        next = next.or_keep(inside, half * (lo + hi));
        let f_next = h.with_linear(next, c1) + c0;
        let size = h.size(next) + (c1 * next).abs() + c0.abs();
        // The scalar finder's two early returns: the residual small against its terms, or a
        // Newton step from `next` (fresh slope) within the tolerance of the input's scale.
        let slope = h.slope_with_linear(next, c1);
        let newton = f_next
            .abs()
            .le(tolerance * next.abs().max(one) * slope.abs());
        let converged = running & (f_next.abs().le(tolerance * size) | newton);
        let below = f_next.lt(zero);
        let moving = running.and_not(converged);
        lo = next.or_keep(moving & below, lo);
        hi = next.or_keep(moving.and_not(below), hi);
        let collapsed = moving & (hi - lo).le(tolerance * next.abs().max(one));
        let stops = converged | collapsed;
        result = next.or_keep(stops, result);
        done = done | stops;
        if done.all() {
            return result;
        }
        // A fresh slope for Halley's steps; for Newton's unless the chord step cut the
        // residual by 1e3 (NaN: refresh).
        refresh = f_next.abs().gt(chord_gain * f.abs()) | f_next.is_nan() | Mask::splat(halley);
        x = next;
        f = f_next;
    }
    // Lanes still running after the last iteration return their last iterate.
    x.or_keep(!done, result)
}
