//! Play operators: the one-sided operator of eqs. (1)-(2) and the classical symmetric one.

use crate::{CoreError, Real};

/// `f_r(v, w) = max(v - r, min(v, w))`, eq. (2), written as a clamp of the memory `w` into the
/// band `[v - r, v]` (the same value for `r >= 0`, without the cost of two float min/max calls).
#[inline(always)]
pub(crate) fn one_sided<T: Real>(input: T, threshold: T, memory: T) -> T {
    let lower = input - threshold;
    if memory > input {
        input
    } else if memory < lower {
        lower
    } else {
        memory
    }
}

/// The one-sided play operator `F_r` of eqs. (1)-(2) (Gu, Zhu & Su 2014, ref. [9] of the paper):
/// a piston of length `r` whose output lags the input by at most `r`, from below:
/// `F_r[x](t) = f_r(x(t), F_r[x](t_i))` with `f_r(v, w) = max(v - r, min(v, w))`.
///
/// Its output always lies in `[x - r, x]`. Rate independent: only the sequence of input values
/// matters, not their timing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneSidedPlay<T> {
    threshold: T,
    memory: T,
}

impl<T: Real> OneSidedPlay<T> {
    /// An operator with threshold `r >= 0` and explicit initial memory `w` (eq. (1) uses
    /// `w = 0`: `F_r[x](0) = f_r(x(0), 0)`).
    pub fn new(threshold: T, initial_memory: T) -> Result<Self, CoreError> {
        check_threshold(threshold)?;
        if !initial_memory.is_finite() {
            return Err(CoreError::NonFinite {
                what: "initial memory",
                index: None,
            });
        }
        Ok(OneSidedPlay {
            threshold,
            memory: initial_memory,
        })
    }

    /// The threshold `r`.
    pub fn threshold(&self) -> T {
        self.threshold
    }

    /// The current memory, i.e. the last output `F_r[x](t_i)`.
    pub fn memory(&self) -> T {
        self.memory
    }

    /// Feeds the next input sample and returns the operator output, eq. (1).
    ///
    /// A NaN input leaves the memory unchanged and returns it (the operator ignores it).
    #[inline]
    pub fn step(&mut self, input: T) -> T {
        if !input.is_nan() {
            self.memory = one_sided(input, self.threshold, self.memory);
        }
        self.memory
    }
}

/// The classical (symmetric) play operator of threshold `r`:
/// `F_r[x](t) = max(x(t) - r, min(x(t) + r, F_r[x](t_i)))`, output in `[x - r, x + r]`
/// (Krasnosel'skii & Pokrovskii 1989; Brokate & Sprekels 1996).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymmetricPlay<T> {
    threshold: T,
    memory: T,
}

impl<T: Real> SymmetricPlay<T> {
    /// An operator with threshold `r >= 0` and explicit initial memory `w`.
    pub fn new(threshold: T, initial_memory: T) -> Result<Self, CoreError> {
        check_threshold(threshold)?;
        if !initial_memory.is_finite() {
            return Err(CoreError::NonFinite {
                what: "initial memory",
                index: None,
            });
        }
        Ok(SymmetricPlay {
            threshold,
            memory: initial_memory,
        })
    }

    /// The threshold `r`.
    pub fn threshold(&self) -> T {
        self.threshold
    }

    /// The current memory (last output).
    pub fn memory(&self) -> T {
        self.memory
    }

    /// Feeds the next input sample and returns the operator output.
    ///
    /// A NaN input leaves the memory unchanged and returns it.
    #[inline]
    pub fn step(&mut self, input: T) -> T {
        if !input.is_nan() {
            // Shift by r: the symmetric band [x - r, x + r] is the one-sided band of width 2r
            // whose top is x + r.
            self.memory = one_sided(
                input + self.threshold,
                self.threshold + self.threshold,
                self.memory,
            );
        }
        self.memory
    }
}

fn check_threshold<T: Real>(threshold: T) -> Result<(), CoreError> {
    if !threshold.is_finite() {
        return Err(CoreError::NonFinite {
            what: "threshold",
            index: None,
        });
    }
    if threshold < T::zero() {
        return Err(CoreError::NegativeThreshold {
            index: 0,
            value: threshold.to_f64(),
        });
    }
    Ok(())
}

/// Feeds `input` to a bank of one-sided play operators (eqs. (1)-(2)) and returns
/// `sum_i b_i F_{r_i}[x](t)`. The inner loop of the MPIM and of every compensator.
#[inline(always)]
pub(crate) fn update_bank<T: Real>(
    thresholds: &[T],
    weights: &[T],
    memory: &mut [T],
    input: T,
) -> T {
    let mut sum = T::zero();
    for ((w, &r), &b) in memory.iter_mut().zip(thresholds).zip(weights) {
        *w = one_sided(input, r, *w);
        sum = sum + b * *w;
    }
    sum
}
