//! The modified Prandtl-Ishlinskii model (MPIM), eqs. (3)-(4).

use crate::buffer::{copied, filled};
use crate::invertibility::{DelayedLoop, delayed_gain_range, min_branch_slope};
use crate::play::{feed_bank, four_way_sum, one_sided};
use crate::{BranchSlope, Buffer, CoreError, InputPolynomial, LoopGain, Real};

/// The discrete MPIM of eq. (4):
/// `y(t) = a1 x^3(t) + a2 x(t) + sum_{i=1}^{n} b_i F_{r_i}[x](t)`,
/// with one-sided play operators `F_r` (eqs. (1)-(2)), thresholds `r_i` and weights `b_i`.
///
/// The input function `g(x) = a1 x^3 + a2 x` of eq. (3) may also be a higher-degree polynomial
/// `g(x) = c_1 x + ... + c_D x^D` ([`InputPolynomial`], [`Mpim::with_input_polynomial`]); every
/// check (invertibility, loop gains) covers it exactly.
///
/// The same type describes a plant model (input: normalised voltage, output: normalised
/// displacement; Table 1), an inverse model used by DIHC (input: normalised desired position,
/// output: normalised voltage; Table 2), and with `a1 = 0` the PI part `P1` and its analytic
/// inverse of eq. (7) (see [`Mpim::pi_part_inverse`]).
///
/// `B` is the storage of the per-operator arrays: `Vec<T>` (feature `alloc`) or `[T; n]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Mpim<T: Real, B: Buffer<T>> {
    thresholds: B,
    weights: B,
    memory: B,
    input: InputPolynomial<T>,
}

impl<T: Real, B: Buffer<T>> Mpim<T, B> {
    /// A validated model: `thresholds` and `weights` of equal length, every value finite,
    /// thresholds non-negative and sorted increasingly. The operators' memory starts at zero
    /// (eq. (1)).
    pub fn new(thresholds: &[T], weights: &[T], a1: T, a2: T) -> Result<Self, CoreError> {
        Self::with_input_polynomial(thresholds, weights, InputPolynomial::cubic(a1, a2)?)
    }

    /// A validated model with the input polynomial `input` instead of the paper's cubic (the
    /// same checks as [`Mpim::new`]).
    pub fn with_input_polynomial(
        thresholds: &[T],
        weights: &[T],
        input: InputPolynomial<T>,
    ) -> Result<Self, CoreError> {
        if weights.len() != thresholds.len() {
            return Err(CoreError::LengthMismatch {
                what: "weights",
                expected: thresholds.len(),
                found: weights.len(),
            });
        }
        for (what, values) in [("thresholds", thresholds), ("weights", weights)] {
            if let Some(index) = values.iter().position(|v| !v.is_finite()) {
                return Err(CoreError::NonFinite {
                    what,
                    index: Some(index),
                });
            }
        }
        if let Some(index) = thresholds.iter().position(|r| *r < T::zero()) {
            return Err(CoreError::NegativeThreshold {
                index,
                value: thresholds[index].to_f64(),
            });
        }
        if let Some(index) = (1..thresholds.len()).find(|&i| thresholds[i] < thresholds[i - 1]) {
            return Err(CoreError::UnsortedThresholds { index });
        }
        Ok(Mpim {
            thresholds: copied(thresholds)?,
            weights: copied(weights)?,
            memory: filled(T::zero(), thresholds.len())?,
            input,
        })
    }

    /// The same model in another storage (e.g. from `Vec<T>` to `[T; N]`), memory included.
    pub fn to_storage<B2: Buffer<T>>(&self) -> Result<Mpim<T, B2>, CoreError> {
        Ok(Mpim {
            thresholds: copied(self.thresholds())?,
            weights: copied(self.weights())?,
            memory: copied(self.memory())?,
            input: self.input,
        })
    }

    /// Number of play operators `n`.
    pub fn len(&self) -> usize {
        self.thresholds.as_ref().len()
    }

    /// `true` when the model has no play operator (a pure cubic).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Thresholds `r_i`, increasing.
    pub fn thresholds(&self) -> &[T] {
        self.thresholds.as_ref()
    }

    /// Weights `b_i`, one per threshold.
    pub fn weights(&self) -> &[T] {
        self.weights.as_ref()
    }

    /// Cubic coefficient `a1` of the input function `g(x) = a1 x^3 + a2 x` (`c_3` of a
    /// higher-degree `g`).
    pub fn a1(&self) -> T {
        self.input.a1()
    }

    /// Linear coefficient `a2` of the input function `g(x) = a1 x^3 + a2 x` (`c_1` of a
    /// higher-degree `g`).
    pub fn a2(&self) -> T {
        self.input.a2()
    }

    /// The input function `g` (eq. (3)).
    pub fn input_polynomial(&self) -> &InputPolynomial<T> {
        &self.input
    }

    /// The operators' memory `F_{r_i}[x](t_i)`, one per operator.
    pub fn memory(&self) -> &[T] {
        self.memory.as_ref()
    }

    /// Back to zero memory (eq. (1): `F_r[x](0) = f_r(x(0), 0)`).
    pub fn reset(&mut self) {
        self.memory.as_mut().fill(T::zero());
    }

    /// Sets the operators' memory explicitly (one finite value per operator).
    ///
    /// The invertibility guarantees of [`Mpim::check_invertible`] hold for memories reachable
    /// from the reset state; an arbitrary memory is accepted but is the caller's responsibility.
    pub fn set_memory(&mut self, memory: &[T]) -> Result<(), CoreError> {
        if memory.len() != self.len() {
            return Err(CoreError::LengthMismatch {
                what: "memory",
                expected: self.len(),
                found: memory.len(),
            });
        }
        if let Some(index) = memory.iter().position(|v| !v.is_finite()) {
            return Err(CoreError::NonFinite {
                what: "memory",
                index: Some(index),
            });
        }
        self.memory.as_mut().copy_from_slice(memory);
        Ok(())
    }

    /// Feeds the next input sample `x(t)` and returns `y(t)`, eq. (4), updating the memory.
    ///
    /// NaN in gives NaN out and leaves the memory as it was (a NaN never enters the memory).
    #[inline]
    pub fn step(&mut self, input: T) -> T {
        if input.is_nan() {
            return input;
        }
        let g = self.input_function(input);
        let sum = feed_bank(
            self.thresholds.as_ref(),
            self.weights.as_ref(),
            self.memory.as_mut(),
            input,
        )
        .sum;
        g + sum
    }

    /// Runs a whole signal through [`Mpim::step`]: `output[k] = y(t_k)`.
    pub fn process(&mut self, input: &[T], output: &mut [T]) -> Result<(), CoreError> {
        if output.len() != input.len() {
            return Err(CoreError::LengthMismatch {
                what: "output",
                expected: input.len(),
                found: output.len(),
            });
        }
        for (x, y) in input.iter().zip(output.iter_mut()) {
            *y = self.step(*x);
        }
        Ok(())
    }

    /// The output the model would give for input `x` from its current memory, without
    /// changing the memory: the current branch of the piecewise-cubic map (ERRATA item 4).
    pub fn branch_output(&self, input: T) -> T {
        let (r, b, w) = (self.thresholds(), self.weights(), self.memory());
        let n = r.len().min(b.len()).min(w.len());
        self.input_function(input) + four_way_sum(n, |i| b[i] * one_sided(input, r[i], w[i]))
    }

    /// `g(x) = a1 x^3 + a2 x`, the polynomial input function of eq. (3) (or the higher-degree
    /// polynomial the model was built with).
    #[inline]
    pub fn input_function(&self, x: T) -> T {
        self.input.value(x)
    }

    /// The smallest slope of the model output with respect to its current input over every
    /// branch reachable from the reset state with inputs in `[lo, hi]` (the range is widened to
    /// include the reset input 0). See [`crate::branch_checkpoints`].
    pub fn min_branch_slope(&self, lo: T, hi: T) -> Result<BranchSlope<T>, CoreError> {
        check_range(lo, hi)?;
        Ok(min_branch_slope(
            self.thresholds(),
            self.weights(),
            &self.input,
            lo,
            hi,
        ))
    }

    /// Checks that the model output is strictly increasing in its current input over
    /// `[lo, hi]` from any memory reachable from the reset state, i.e. that the model can be
    /// inverted there (ERRATA item 5). Refuses with the offending slope, input and number of
    /// moving operators.
    pub fn check_invertible(&self, lo: T, hi: T) -> Result<BranchSlope<T>, CoreError> {
        let worst = self.min_branch_slope(lo, hi)?;
        if worst.slope > T::zero() {
            Ok(worst)
        } else {
            Err(CoreError::NotInvertible {
                slope: worst.slope.to_f64(),
                input: worst.input.to_f64(),
                active_operators: worst.active_operators,
                range: (lo.min(T::zero()).to_f64(), hi.max(T::zero()).to_f64()),
            })
        }
    }

    /// The worst-case small-signal loop gain of the delayed WIHC built on this (plant) model,
    /// over every branch reachable from the reset state with inputs in `[lo, hi]` (widened to
    /// include 0).
    ///
    /// The delayed WIHC evaluates eq. (9) with `H[v](t - Ts)`, `v(t) = (y_d(t) - H[v](t - Ts)) / a2`,
    /// `H[v] = g(v) - a2 v + sum b_i F_{r_i}[v]`: a fixed-point iteration whose gain on a branch
    /// with the first `k` operators moving is `|g'(x) - a2 + b_1 + ... + b_k| / a2`
    /// (`|3 a1 x^2 + b_1 + ... + b_k| / a2` for the paper's cubic). Around a reversal only the
    /// zero-threshold operators move; after a jump in `y_d` the loop swings over a wide range,
    /// more operators move, and this worst case over every reachable `k` and `x` decides whether
    /// it settles (below 1: the difference between successive drives shrinks at least by this
    /// factor each sample while `y_d` holds) or can ring between the output limits.
    /// Table 1 of the paper over `[0, 1]`: 1.66 (all ten operators moving near `x = 0`).
    pub fn delayed_wihc_loop_gain(&self, lo: T, hi: T) -> Result<LoopGain<T>, CoreError> {
        check_range(lo, hi)?;
        Ok(self.delayed_gain_range(DelayedLoop::Wihc, lo, hi).worst)
    }

    /// The worst-case small-signal loop gain of the delayed IHC built on this (plant) model,
    /// over every branch reachable from the reset state with inputs in `[lo, hi]` (widened to
    /// include 0).
    ///
    /// The delayed IHC evaluates eq. (5) with the previous drive in the input function's
    /// remainder, `w(t) = y_d(t) - h(v(t - Ts))` with `h(v) = g(v) - a2 v` (`a1 v^3` for the
    /// paper's cubic), and `v(t) = P1^{-1}[w](t)` (eq. (7)). On a branch with the first `k`
    /// operators moving, `P1^{-1}` has slope `1 / (a2 + b_1 + ... + b_k)`, so the loop's gain
    /// is `|g'(x) - a2| / (a2 + b_1 + ... + b_k)` (`|3 a1 x^2| / (a2 + b_1 + ... + b_k)`). Below
    /// 1 the difference between successive `w` shrinks at least by this factor each sample
    /// while `y_d` holds (along each sample's move the pairs `(k, x)` are reachable ones, so the
    /// bound holds for large moves as well); at or above 1 the loop can ring between the
    /// limits. Table 1 of the paper over `[0, 1]`: 0.68 (`x = 1`, only the zero-threshold
    /// operator moving).
    pub fn delayed_ihc_loop_gain(&self, lo: T, hi: T) -> Result<LoopGain<T>, CoreError> {
        check_range(lo, hi)?;
        Ok(self.delayed_gain_range(DelayedLoop::Ihc, lo, hi).worst)
    }

    /// The signed gains of a delayed loop over the reachable branches.
    pub(crate) fn delayed_gain_range(
        &self,
        which: DelayedLoop,
        lo: T,
        hi: T,
    ) -> crate::invertibility::GainRange<T> {
        delayed_gain_range(
            which,
            self.thresholds(),
            self.weights(),
            &self.input,
            lo,
            hi,
        )
    }

    /// The analytic inverse of the PI part `P1[v] = a2 v + sum b_i F_{r_i}[v]`, eq. (7):
    /// `P1^{-1}[w] = a2_hat w + sum b_hat_j F_{r_hat_j}[w]` with
    /// `r_hat_j = a2 r_j + sum_{i<j} b_i (r_j - r_i)`, `a2_hat = 1 / a2` and
    /// `b_hat_j = -b_j / ((a2 + sum_{i<j} b_i)(a2 + sum_{i<=j} b_i))`.
    ///
    /// Both start from zero memory, and then `P1^{-1}[P1[v]] = v` exactly (ERRATA item 3).
    /// The cubic term `a1` (the whole remainder `g(x) - a2 x` of a higher-degree input
    /// polynomial) is not part of `P1`; the result has `a1 = 0`.
    ///
    /// When `a2` itself is not positive but operators with `r = 0` (always moving, `F_0[v] = v`)
    /// make every reachable slope positive, the equivalent form `a2_hat = 1 / (a2 + sum_{r_i=0} b_i)`
    /// with zero weights on those operators is returned.
    pub fn pi_part_inverse(&self) -> Result<Mpim<T, B>, CoreError> {
        self.pi_part_inverse_in(false)
    }

    /// [`Mpim::pi_part_inverse`] in the equivalent form with the zero-threshold operators
    /// folded into `a2_hat = 1 / (a2 + sum_{r_i=0} b_i)` (zero weights on them) whenever there
    /// are any: what the compensators run. The literal `a2_hat = 1 / a2` and first weight
    /// `1 / (a2 + b_1) - 1 / a2` nearly cancel when `a2` is small beside `b_1`, and their sum
    /// then carries the rounding of `1 / a2` (in `f32`, `a2 = 2.4e-6` beside `b_1 = 0.1` made
    /// the inverse's slopes 2.5 % off).
    pub(crate) fn pi_part_inverse_folded(&self) -> Result<Mpim<T, B>, CoreError> {
        self.pi_part_inverse_in(true)
    }

    fn pi_part_inverse_in(&self, fold: bool) -> Result<Mpim<T, B>, CoreError> {
        let n = self.len();
        let r = self.thresholds();
        let b = self.weights();
        let always = r.iter().take_while(|r| **r <= T::zero()).count();
        // slope(k) = a2 + b_1 + ... + b_k, the slope of P1 with the first k operators moving,
        // summed in one pass (linear set-up cost for models of many operators).
        let mut literal = true;
        let mut slope = self.a2();
        let mut slope_always = self.a2();
        for k in 0..=n {
            if k == always {
                slope_always = slope;
            }
            if k >= always {
                if slope.is_nan() || slope <= T::zero() {
                    return Err(CoreError::PiPartNotInvertible {
                        active_operators: k,
                        slope: slope.to_f64(),
                    });
                }
            } else {
                literal = literal && slope > T::zero();
            }
            if let Some(&bk) = b.get(k) {
                slope = slope + bk;
            }
        }
        if fold && always > 0 {
            literal = false;
        }
        let mut r_hat: B = filled(T::zero(), n)?;
        let mut b_hat: B = filled(T::zero(), n)?;
        // r_hat_j = a2 r_j + sum_{i<j} b_i (r_j - r_i), computed as r_hat_0 = a2 r_0 and
        // r_hat_j = r_hat_{j-1} + slope(j) (r_j - r_{j-1}) (the same sum, term by term).
        let mut before = self.a2(); // slope(j)
        for j in 0..n {
            let after = before + b[j]; // slope(j + 1)
            r_hat.as_mut()[j] = if j == 0 {
                self.a2() * r[0]
            } else {
                r_hat.as_ref()[j - 1] + before * (r[j] - r[j - 1])
            };
            b_hat.as_mut()[j] = if literal || j >= always {
                // -b_j / (s_{j-1} s_j) = 1/s_j - 1/s_{j-1} (0-based: slopes j and j + 1).
                // Otherwise the zero-threshold operators are folded into a2_hat below.
                T::one() / after - T::one() / before
            } else {
                T::zero()
            };
            before = after;
        }
        let a2_hat = if literal {
            T::one() / self.a2()
        } else {
            T::one() / slope_always
        };
        let inverse = Mpim {
            thresholds: r_hat,
            weights: b_hat,
            memory: filled(T::zero(), n)?,
            input: InputPolynomial::cubic(T::zero(), a2_hat)?,
        };
        if let Some(index) = (0..n).find(|&j| !inverse.weights()[j].is_finite()) {
            return Err(CoreError::NonFinite {
                what: "inverse weights",
                index: Some(index),
            });
        }
        Ok(inverse)
    }
}

/// Validates an input range.
pub(crate) fn check_range<T: Real>(lo: T, hi: T) -> Result<(), CoreError> {
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok(())
    } else {
        Err(CoreError::InvalidRange {
            lo: lo.to_f64(),
            hi: hi.to_f64(),
        })
    }
}
