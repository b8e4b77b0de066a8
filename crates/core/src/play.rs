//! Play operators: the one-sided operator of eqs. (1)-(2) and the classical symmetric one.

use crate::{CoreError, Real};

/// `f_r(v, w) = max(v - r, min(v, w))`, eq. (2), written as a clamp of the memory `w` into the
/// band `[v - r, v]` (the same value for `r >= 0`), as two selects that compile to `maxsd` /
/// `minsd` (and vectorise in a bank).
#[inline(always)]
pub(crate) fn one_sided<T: Real>(input: T, threshold: T, memory: T) -> T {
    let lower = input - threshold;
    let raised = if memory < lower { lower } else { memory };
    if raised > input { input } else { raised }
}

/// The one-sided play operator `F_r` of eqs. (1)-(2) (Gu, Zhu & Su 2014, ref. \[9\] of the paper):
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
/// (Krasnosel'skii & Pokrovskii 1989; Brokate & Sprekels 1996). It is the one-sided operator
/// of threshold `2r` fed with `x + r`, and is built that way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymmetricPlay<T> {
    band: OneSidedPlay<T>,
}

impl<T: Real> SymmetricPlay<T> {
    /// An operator with threshold `r >= 0` and explicit initial memory `w`.
    pub fn new(threshold: T, initial_memory: T) -> Result<Self, CoreError> {
        check_threshold(threshold)?;
        Ok(SymmetricPlay {
            band: OneSidedPlay::new(threshold + threshold, initial_memory)?,
        })
    }

    /// The threshold `r`.
    pub fn threshold(&self) -> T {
        self.band.threshold() / T::from_f64(2.0)
    }

    /// The current memory (last output).
    pub fn memory(&self) -> T {
        self.band.memory()
    }

    /// Feeds the next input sample and returns the operator output.
    ///
    /// A NaN input leaves the memory unchanged and returns it.
    #[inline]
    pub fn step(&mut self, input: T) -> T {
        self.band.step(input + self.threshold())
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

/// What feeding one input to a bank of play operators gives.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BankUpdate<T> {
    /// `sum_i b_i F_{r_i}[x](t)`.
    pub sum: T,
    /// How many operators sit at the upper edge of their band (`w_i = x - r_i`): moving up.
    pub rising: usize,
    /// How many operators sit at the lower edge of their band (`w_i = x`): moving down.
    pub falling: usize,
}

/// Feeds `input` to a bank of one-sided play operators (eqs. (1)-(2)): updates every memory,
/// counts the operators at either edge of their band and returns `sum_i b_i F_{r_i}[x](t)`.
/// The inner loop of the MPIM and of every compensator: the clamp loop vectorises, and the
/// weighted sum uses four partial sums, so that its add chain (the latency every exact
/// compensator waits for) is a quarter as long.
#[inline(always)]
pub(crate) fn feed_bank<T: Real>(
    thresholds: &[T],
    weights: &[T],
    memory: &mut [T],
    input: T,
) -> BankUpdate<T> {
    let n = memory.len().min(thresholds.len()).min(weights.len());
    let (memory, thresholds, weights) = (&mut memory[..n], &thresholds[..n], &weights[..n]);
    let mut rising = 0usize;
    let mut falling = 0usize;
    for (w, &r) in memory.iter_mut().zip(thresholds) {
        let lower = input - r;
        let next = one_sided(input, r, *w);
        rising += usize::from(next <= lower);
        falling += usize::from(next >= input);
        *w = next;
    }
    let sum = four_way_sum(n, |i| weights[i] * memory[i]);
    BankUpdate {
        sum,
        rising,
        falling,
    }
}

/// `sum_{i < n} term(i)` in four partial sums (`i mod 4` of the first `4 floor(n / 4)` terms, then
/// the rest in order): a quarter of the add chain of a plain sum. Every weighted sum over the
/// operators goes through here, so that all of them round the same way.
#[inline(always)]
pub(crate) fn four_way_sum<T: Real>(n: usize, term: impl Fn(usize) -> T) -> T {
    let mut partial = [T::zero(); 4];
    let full = n / 4 * 4;
    let mut i = 0;
    while i < full {
        partial[0] = partial[0] + term(i);
        partial[1] = partial[1] + term(i + 1);
        partial[2] = partial[2] + term(i + 2);
        partial[3] = partial[3] + term(i + 3);
        i += 4;
    }
    let mut sum = (partial[0] + partial[1]) + (partial[2] + partial[3]);
    for j in full..n {
        sum = sum + term(j);
    }
    sum
}
