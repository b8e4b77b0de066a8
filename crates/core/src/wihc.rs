//! Without-inverse hysteresis compensation (WIHC), eq. (9).

use crate::compensator::OutputGuard;
use crate::invertibility::{max_delayed_loop_gain, reversal_loop_gains};
use crate::solve::increasing_cubic_root;
use crate::walk::{PlayBank, SegmentEquation, rounding_tolerance};
use crate::{
    Buffer, Compensator, CoreError, Diagnostics, LoopGain, Mpim, OutputLimits, Real, SolveMode,
};

/// WIHC, section 3.2: the identified plant MPIM used directly in a multiplicative structure,
/// `v(t) = (y_d(t) - H[v](t)) / a2` with `H[v](t) = a1 v^3(t) + sum b_i F_{r_i}[v](t)`, eq. (9).
///
/// - [`SolveMode::Exact`]: eq. (9) is implicit (`H[v](t)` depends on `v(t)`); it is solved
///   exactly each sample, so that the plant model gives `P[v](t) = y_d(t)`.
/// - [`SolveMode::Delayed`]: `H[v](t - Ts)` replaces `H[v](t)`, as real-time implementations
///   do (the paper's algorithm). This is a fixed-point iteration
///   `v(t) = (y_d(t) - H[v](t - Ts)) / a2` whose small-signal loop gain on a branch with the
///   first `k` operators moving is `|3 a1 x^2 + b_1 + ... + b_k| / a2`.
///   - Around a reversal only the zero-threshold operators move; the constructor refuses a
///     model whose gain there reaches 1 ([`CoreError::DelayedWihcUnstable`]).
///   - After a jump in `y_d` the loop swings over a wide range and more operators move. Its
///     worst case over the limits is [`Wihc::delayed_loop_gain`] `g`. Below 1 the loop
///     contracts: in the small-signal picture its error shrinks by at least the factor `g` each
///     sample, so settling to a fraction `eps` of the jump takes about `ln(eps) / ln(g)`
///     samples (a few for `g = 0.3`, about 460 for `g = 0.99` and `eps = 0.01`; many more as
///     `g` nears 1). Once settled the model's position follows `y_d`, and once the trajectory has swept past the
///     range of the settling its drive follows the exact WIHC's, both to within a gap that
///     shrinks with the sampling rate. At or above 1 (Table 1 of the paper: 1.66, all
///     ten operators moving near `x = 0`) it can ring between the output limits: from rest at
///     10 kHz, `y_d = 35 + 20 sin(2 pi t)` um makes it alternate between 0 V and 10 V, 151 of
///     the first 230 samples at a limit, before it settles; the operators' memory the ringing
///     leaves then keeps its drive off the exact WIHC's (the model's position still follows
///     `y_d`) until the trajectory sweeps past the ringing's range. The clamped samples count
///     in [`Diagnostics::loop_saturated`], not in [`Diagnostics::saturated`]: the desired
///     position was reachable.
///
///   On smooth trajectories sampled fast, started from a consistent state (the study:
///   10 kHz, 1 Hz, from rest at the trajectory's start) it stays within a fraction of a
///   sample's step of the exact solution. Prefer [`SolveMode::Exact`].
///
///   Cost: a clamped delayed sample also runs one exact solve of eq. (9) from the same state,
///   only to classify the clamp (reachable: [`Diagnostics::loop_saturated`]; not:
///   [`Diagnostics::saturated`]), so it costs about one exact step more. The worst case per
///   sample is the delayed step plus the exact step; real-time budgets should use that bound
///   (the loop can clamp on many consecutive samples while it rings).
///
/// See [`Compensator`] for the output guarantees.
#[derive(Debug, Clone)]
pub struct Wihc<T: Real, B: Buffer<T>> {
    /// `a2 v + sum b_i F_{r_i}[v]`: the plant model without its cubic term.
    bank: PlayBank<T, B>,
    a1: T,
    /// `1 / a2`.
    inverse_a2: T,
    mode: SolveMode,
    guard: OutputGuard<T>,
}

impl<T: Real, B: Buffer<T>> Wihc<T, B> {
    /// A WIHC from a plant model. Checks that `a2 > 0`, that the model is invertible over the
    /// output limits (see [`Mpim::check_invertible`]) and, for the delayed mode, that the
    /// iteration converges. The model's memory is not used: the compensator starts from the
    /// reset state.
    pub fn new<B2: Buffer<T>>(
        plant: &Mpim<T, B2>,
        limits: OutputLimits<T>,
        mode: SolveMode,
    ) -> Result<Self, CoreError> {
        let (a1, a2) = (plant.a1(), plant.a2());
        if a2 <= T::zero() {
            return Err(CoreError::NonPositiveA2 { a2: a2.to_f64() });
        }
        plant.check_invertible(limits.min(), limits.max())?;
        if mode == SolveMode::Delayed {
            check_delayed_contraction(plant, limits)?;
        }
        let mut wihc = Wihc {
            bank: PlayBank::new(a2, plant.thresholds(), plant.weights())?,
            a1,
            inverse_a2: T::one() / a2,
            mode,
            guard: OutputGuard::new(limits),
        };
        wihc.reset();
        Ok(wihc)
    }

    /// The solve mode.
    pub fn mode(&self) -> SolveMode {
        self.mode
    }

    /// The worst-case small-signal loop gain of the delayed iteration, over every branch
    /// reachable within the output limits: `max |3 a1 x^2 + b_1 + ... + b_k| / a2` (see
    /// [`Mpim::delayed_wihc_loop_gain`]). Reported whatever the mode, so that a caller can
    /// choose: below 1 the delayed loop settles after any jump in `y_d`; at or above 1 prefer
    /// [`SolveMode::Exact`]. Table 1 of the paper on `[0, 1]`: 1.66.
    pub fn delayed_loop_gain(&self) -> LoopGain<T> {
        // Computed on demand (a few checkpoints per operator), so that the compensator keeps
        // no more RAM than it needs per sample.
        let limits = self.guard.limits;
        max_delayed_loop_gain(
            self.bank.thresholds(),
            self.bank.weights(),
            self.a1,
            self.bank.a(),
            limits.min(),
            limits.max(),
        )
    }

    /// The plant model's operators' memory as the compensator tracks it (the memory of
    /// `F_{r_i}[v]` for the voltages emitted so far).
    pub fn memory(&self) -> &[T] {
        self.bank.memory()
    }
}

/// Around a reversal only the zero-threshold operators move: the delayed loop's gain on that
/// branch, `|3 a1 x^2 + b_1 + ... + b_k| / a2` with `k` the number of zero-threshold operators
/// (eq. (9) with `H[v](t - Ts)`), must be below 1 over the whole range. The first checkpoint
/// (in the order of [`reversal_loop_gains`]) where it is not is reported.
fn check_delayed_contraction<T: Real, B: Buffer<T>>(
    plant: &Mpim<T, B>,
    limits: OutputLimits<T>,
) -> Result<(), CoreError> {
    let mut failure = None;
    reversal_loop_gains(
        plant.thresholds(),
        plant.weights(),
        plant.a1(),
        plant.a2(),
        limits.min(),
        limits.max(),
        |ratio, x| {
            if failure.is_none() && (ratio.is_nan() || ratio >= T::one()) {
                failure = Some(CoreError::DelayedWihcUnstable {
                    ratio: ratio.to_f64(),
                    input: x.to_f64(),
                });
            }
        },
    );
    failure.map_or(Ok(()), Err)
}

/// `a1 v^3 + (a2 + sum of moving b) v + beta = y_d` on one segment, in the voltage `v` itself.
struct Eq9<T> {
    a1: T,
    desired: T,
}

impl<T: Real> SegmentEquation<T> for Eq9<T> {
    #[inline(always)]
    fn residual(&self, x: T, alpha: T, beta: T) -> T {
        (self.a1 * x * x + alpha) * x + beta - self.desired
    }
    #[inline(always)]
    fn control(&self, x: T, _alpha: T, _beta: T) -> T {
        x
    }
    #[inline(always)]
    fn input_at_control(&self, v: T, _alpha: T, _beta: T) -> T {
        v
    }
    #[inline(always)]
    fn rounding(&self, x: T, alpha: T, beta: T) -> T {
        let terms =
            (self.a1 * x * x * x).abs() + (alpha * x).abs() + beta.abs() + self.desired.abs();
        rounding_tolerance(terms)
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, f_lo: T, f_hi: T, alpha: T, beta: T, _inv: T) -> T {
        increasing_cubic_root(self.a1, alpha, beta - self.desired, lo, hi, f_lo, f_hi)
    }
}

impl<T: Real, B: Buffer<T>> Compensator<T> for Wihc<T, B> {
    fn reset(&mut self) {
        self.bank.reset();
        self.guard.reset();
        // The plant is assumed relaxed at input 0; when 0 lies outside the limits, the
        // compensator starts at the nearest limit, and the plant with it.
        let v0 = self.guard.previous;
        if v0 != T::zero() {
            self.bank.feed(v0);
        }
    }

    #[inline]
    fn step(&mut self, desired: T) -> T {
        let Some(desired) = self.guard.accept(desired) else {
            return self.guard.previous;
        };
        let v_prev = self.bank.input();
        match self.mode {
            SolveMode::Exact => {
                let equation = Eq9 {
                    a1: self.a1,
                    desired,
                };
                let f_prev = self.a1 * v_prev * v_prev * v_prev + self.bank.output() - desired;
                let s = self.bank.solve(&equation, f_prev, self.guard.limits);
                let v = self.guard.emit(s.input, s.saturated);
                if v == s.input {
                    self.bank.feed_solved(&s);
                } else {
                    self.bank.feed(v);
                }
                v
            }
            SolveMode::Delayed => {
                // H[v](t - Ts) = a1 v^3(t - Ts) + sum b_i F_{r_i}[v](t - Ts).
                let h_prev = self.a1 * v_prev * v_prev * v_prev + self.bank.memory_sum();
                // A clamped sample counts as a loop saturation when the exact eq. (9) could
                // have been met within the limits from the same state (solved only then).
                let (a1, bank, limits) = (self.a1, &self.bank, self.guard.limits);
                let reachable = || {
                    let equation = Eq9 { a1, desired };
                    let f_prev = a1 * v_prev * v_prev * v_prev + bank.output() - desired;
                    !bank.solve(&equation, f_prev, limits).saturated
                };
                let v = self.guard.emit_classified(
                    (desired - h_prev) * self.inverse_a2,
                    false,
                    reachable,
                );
                self.bank.feed(v);
                v
            }
        }
    }

    fn limits(&self) -> OutputLimits<T> {
        self.guard.limits
    }

    fn diagnostics(&self) -> Diagnostics {
        self.guard.diagnostics
    }
}
