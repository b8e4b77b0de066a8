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

use crate::{OutputLimits, Real};

/// The equation a compensator solves on one linear segment of the bank, `PI(x) = alpha x + beta`.
pub(crate) trait SegmentEquation<T: Real> {
    /// The residual at `x`, increasing in `x`; the solution makes it zero.
    fn residual(&self, x: T, alpha: T, beta: T) -> T;
    /// The control `v` the compensator emits at `x` (increasing in `x`).
    fn control(&self, x: T, alpha: T, beta: T) -> T;
    /// The `x` where the control equals `v`.
    fn input_at_control(&self, v: T, alpha: T, beta: T) -> T;
    /// The root of the residual in `[lo, hi]`, given its values at both ends (`f_lo <= 0 <= f_hi`).
    fn root(&self, lo: T, hi: T, f_lo: T, f_hi: T, alpha: T, beta: T) -> T;
}

/// The input of the bank that solves the equation, and whether the limits cut it short.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Solution<T> {
    pub input: T,
    pub saturated: bool,
}

/// Walks the segments of the bank `a x + sum b_i F_{r_i}[x]` from `x_prev` (where the residual
/// is `f_prev`) in the direction that brings the residual to zero, keeping the control within
/// `limits`.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn solve<T: Real, E: SegmentEquation<T>>(
    equation: &E,
    a: T,
    thresholds: &[T],
    weights: &[T],
    memory: &[T],
    memory_sum: T,
    x_prev: T,
    f_prev: T,
    limits: OutputLimits<T>,
) -> Solution<T> {
    let mut alpha = a;
    let mut beta = memory_sum;
    if f_prev <= T::zero() {
        // Rising.
        let (mut lo, mut f_lo) = (x_prev, f_prev);
        let v_max = limits.max();
        for ((&w, &r), &b) in memory.iter().zip(thresholds).zip(weights) {
            let u = (w + r).max(lo);
            if equation.control(u, alpha, beta) >= v_max {
                break;
            }
            let f_u = equation.residual(u, alpha, beta);
            if f_u >= T::zero() {
                return Solution {
                    input: equation.root(lo, u, f_lo, f_u, alpha, beta),
                    saturated: false,
                };
            }
            alpha = alpha + b;
            beta = beta - b * (r + w);
            lo = u;
            f_lo = f_u;
        }
        let end = equation.input_at_control(v_max, alpha, beta);
        let f_end = equation.residual(end, alpha, beta);
        if f_end < T::zero() {
            return Solution {
                input: end,
                saturated: true,
            };
        }
        Solution {
            input: equation.root(lo, end, f_lo, f_end, alpha, beta),
            saturated: false,
        }
    } else {
        // Falling.
        let (mut hi, mut f_hi) = (x_prev, f_prev);
        let v_min = limits.min();
        for (&w, &b) in memory.iter().zip(weights) {
            let l = w.min(hi);
            if equation.control(l, alpha, beta) <= v_min {
                break;
            }
            let f_l = equation.residual(l, alpha, beta);
            if f_l <= T::zero() {
                return Solution {
                    input: equation.root(l, hi, f_l, f_hi, alpha, beta),
                    saturated: false,
                };
            }
            alpha = alpha + b;
            beta = beta - b * w;
            hi = l;
            f_hi = f_l;
        }
        let end = equation.input_at_control(v_min, alpha, beta);
        let f_end = equation.residual(end, alpha, beta);
        if f_end > T::zero() {
            return Solution {
                input: end,
                saturated: true,
            };
        }
        Solution {
            input: equation.root(end, hi, f_end, f_hi, alpha, beta),
            saturated: false,
        }
    }
}
