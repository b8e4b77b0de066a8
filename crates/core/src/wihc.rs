//! Without-inverse hysteresis compensation (WIHC), eq. (9).

use crate::compensator::OutputGuard;
use crate::invertibility::{DelayedLoop, delayed_gain_range};
use crate::solve::{OddCubic, Remainder, increasing_root};
use crate::walk::{PlayBank, ReachOnly, SegmentEquation, rounding_tolerance};
use crate::{
    Buffer, Compensator, CoreError, Diagnostics, InputPolynomial, LoopGain, Mpim, OutputLimits,
    Real, SolveMode,
};

/// WIHC, section 3.2: the identified plant MPIM used directly in a multiplicative structure,
/// `v(t) = (y_d(t) - H[v](t)) / a2` with `H[v](t) = a1 v^3(t) + sum b_i F_{r_i}[v](t)`, eq. (9)
/// (with a higher-degree input polynomial `g`, `a1 v^3` is its remainder `h(v) = g(v) - a2 v`).
///
/// - [`SolveMode::Exact`]: eq. (9) is implicit (`H[v](t)` depends on `v(t)`); it is solved
///   exactly each sample, so that the plant model gives `P[v](t) = y_d(t)`.
/// - [`SolveMode::Delayed`]: `H[v](t - Ts)` replaces `H[v](t)`, as real-time implementations
///   do (the paper's algorithm). This is a fixed-point iteration
///   `v(t) = (y_d(t) - H[v](t - Ts)) / a2` whose small-signal loop gain on a branch with the
///   first `k` operators moving is `|g'(x) - a2 + b_1 + ... + b_k| / a2`
///   (`|3 a1 x^2 + b_1 + ... + b_k| / a2` for the paper's cubic). Its worst case over every
///   branch reachable within the limits is [`Wihc::delayed_loop_gain`] `G`; the constructor
///   refuses a model with `G >= 1` ([`CoreError::DelayedLoopUnstable`]). Below 1 the loop
///   contracts: while `y_d` holds, the difference between successive drives shrinks at
///   least by the factor `G` each sample (along each sample's move the pairs `(k, x)` met are
///   reachable branches, so this holds for large moves too), so settling to a fraction `eps`
///   of a jump takes about `ln(eps) / ln(G)` samples (a few for `G = 0.3`, about 460 for
///   `G = 0.99` and `eps = 0.01`). Once settled the model's position follows `y_d`, and once
///   the trajectory has swept past the range of the settling its drive follows the exact
///   WIHC's, both to within a gap that shrinks with the sampling rate. On smooth
///   trajectories sampled fast, started from a consistent state (the study: 10 kHz, 1 Hz,
///   from rest at the trajectory's start) it stays within a fraction of a sample's step of
///   the exact solution.
/// - [`SolveMode::DelayedAllowUnstable`]: the same loop without the check, the explicit
///   override. At `G >= 1` (Table 1 of the paper: 1.66, all ten operators moving near
///   `x = 0`) it can ring between the output limits: from rest at 10 kHz,
///   `y_d = 35 + 20 sin(2 pi t)` um makes it alternate between 0 V and 10 V, 151 of the first
///   230 samples at a limit, before it settles; the operators' memory the ringing leaves then
///   keeps its drive off the exact WIHC's (the model's position still follows `y_d`) until
///   the trajectory sweeps past the ringing's range. The clamped samples count in
///   [`Diagnostics::loop_saturated`], not in [`Diagnostics::saturated`]: the desired position
///   was reachable.
/// - [`SolveMode::DelayedGuarded`]: a delayed loop that cannot oscillate, whatever the model.
///   It delays only the input polynomial's remainder `h` and keeps the operators' part of
///   `H[v](t)` implicit, solved exactly by the walk over the plant's own segments (no inverse
///   model): eq. (9) as `a2 v(t) + sum b_i F_{r_i}[v](t) = z(t)`, with
///
///   `z(t) = P1_{t - Ts} + mu e(t)`, `e(t) = y_d(t) - h(v(t - Ts)) - P1_{t - Ts}`,
///   `mu = min(1, 1 / (1 + q_max))`,
///
///   where `P1_{t - Ts} = a2 v(t - Ts) + sum b_i F_{r_i}[v](t - Ts)`, so that `e` is the
///   model's tracking error for the previous drive, and `q_max` the largest signed gain
///   `(g'(x) - a2) / (a2 + b_1 + ... + b_k)` over the reachable branches: the guarded IHC's law
///   ([`crate::Ihc`]), walked on the plant's PI part instead of eq. (7)'s inverse (the same
///   drive up to rounding). Before it, each sample walks the segments with the exact residual
///   of eq. (9), without a root solve, to learn whether `y_d` is reachable within the limits:
///   when it is not, the exact solution is the limit in the direction of travel, emitted at
///   once (bit for bit the exact WIHC's output) and counted in [`Diagnostics::saturated`].
///
///   *Proof sketch.* While `y_d` holds, moving `P1` from `P1_{t - Ts}` to `z(t)` along the
///   walk moves the drive monotonically and the model's output `h(v) + P1` by
///   `integral (1 + q(k, v)) dP1` over the move, each `(k, v)` met a reachable branch, with
///   `1 + q = (g'(v) + b_1 + ... + b_k) / (a2 + b_1 + ... + b_k)` in `[1 + q_min, 1 + q_max]`,
///   positive for an invertible model (which also makes `a2 + b_1 + ... + b_k > 0`: every
///   branch passes through the reset input 0, where `g'(0) = a2`). So
///   `e(t + Ts) = e(t) (1 - mu (1 + q_avg))`, a factor in `[0, 1 - mu (1 + q_min)]`, below 1:
///   the error keeps its sign and shrinks. When `y_d` is reachable the exact solution lies
///   within the limits and the step, never passing it, never reaches a limit; an unreachable
///   `y_d` sends the drive to the limit the exact solution sits on, where it stays while `y_d`
///   holds. The model's output approaches `y_d` from one side, the drive never alternates
///   between limits, and never clamps while `y_d` is reachable. Unlike the plain delayed loop,
///   whose gain `|g'(x) - a2 + b_1 + ... + b_k| / a2` grows with the operators' weights (3 to
///   37 on the DBO record's least-squares models), its gain only involves the input
///   polynomial's curvature against the PI part's slope (Table 1: `q` in `[-0.68, 0]`,
///   `mu = 1`): it lags the exact WIHC by about what the delayed IHC does.
///
/// Prefer [`SolveMode::Exact`] where the budget allows.
///
/// Cost: a clamped sample of the plain delayed loop also runs one exact solve of eq. (9) from
/// the same state, only to classify the clamp (reachable: [`Diagnostics::loop_saturated`];
/// not: [`Diagnostics::saturated`]), so it costs about one exact step more. The worst case
/// per sample is the delayed step plus the exact step; real-time budgets should use that bound
/// (the unchecked loop can clamp on many consecutive samples while it rings). The guarded loop
/// walks twice every sample (reachability, then the step) and never solves a root of the
/// cubic: its worst case is two walks over the operators and one memory update.
///
/// See [`Compensator`] for the output guarantees.
#[derive(Debug, Clone)]
pub struct Wihc<T: Real, B: Buffer<T>> {
    /// `a2 v + sum b_i F_{r_i}[v]`: the plant model without its input polynomial's remainder.
    pub(crate) bank: PlayBank<T, B>,
    /// The plant's input polynomial `g`; `H` uses its remainder `g(v) - a2 v`.
    pub(crate) input: InputPolynomial<T>,
    /// `1 / a2`.
    pub(crate) inverse_a2: T,
    pub(crate) mode: SolveMode,
    /// `mu` of [`SolveMode::DelayedGuarded`], whatever the mode.
    pub(crate) relaxation: T,
    pub(crate) guard: OutputGuard<T>,
}

impl<T: Real, B: Buffer<T>> Wihc<T, B> {
    /// A WIHC from a plant model. Checks that `a2 > 0`, that the model is invertible over the
    /// output limits (see [`Mpim::check_invertible`]) and, for [`SolveMode::Delayed`], that the
    /// delayed loop's gain over the limits is below 1. The model's memory is not used: the
    /// compensator starts from the reset state.
    pub fn new<B2: Buffer<T>>(
        plant: &Mpim<T, B2>,
        limits: OutputLimits<T>,
        mode: SolveMode,
    ) -> Result<Self, CoreError> {
        let a2 = plant.a2();
        if a2 <= T::zero() {
            return Err(CoreError::NonPositiveA2 { a2: a2.to_f64() });
        }
        plant.check_invertible(limits.min(), limits.max())?;
        let gains = plant.delayed_gain_range(DelayedLoop::Wihc, limits.min(), limits.max());
        // The guarded loop delays only the remainder of the input polynomial, as the delayed
        // IHC does: its relaxation is the IHC loop's.
        let guarded = plant.delayed_gain_range(DelayedLoop::Ihc, limits.min(), limits.max());
        // NaN counts as unstable.
        if mode == SolveMode::Delayed && (gains.worst.gain >= T::one() || gains.worst.gain.is_nan())
        {
            return Err(CoreError::DelayedLoopUnstable {
                compensator: "WIHC",
                gain: gains.worst.gain.to_f64(),
                input: gains.worst.input.to_f64(),
                active_operators: gains.worst.active_operators,
            });
        }
        let mut wihc = Wihc {
            bank: PlayBank::new(a2, plant.thresholds(), plant.weights())?,
            input: *plant.input_polynomial(),
            inverse_a2: T::one() / a2,
            mode,
            relaxation: guarded.relaxation(),
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
    /// reachable within the output limits: `max |g'(x) - a2 + b_1 + ... + b_k| / a2` (see
    /// [`Mpim::delayed_wihc_loop_gain`]). Reported whatever the mode, so that a caller can
    /// choose: below 1 the delayed loop settles after any jump in `y_d`; at or above 1 prefer
    /// [`SolveMode::Exact`] or [`SolveMode::DelayedGuarded`]. Table 1 of the paper on
    /// `[0, 1]`: 1.66.
    pub fn delayed_loop_gain(&self) -> LoopGain<T> {
        // Computed on demand (a few checkpoints per operator), so that the compensator keeps
        // no more RAM than it needs per sample.
        let limits = self.guard.limits;
        delayed_gain_range(
            DelayedLoop::Wihc,
            self.bank.thresholds(),
            self.bank.weights(),
            &self.input,
            limits.min(),
            limits.max(),
        )
        .worst
    }

    /// The under-relaxation `mu` of [`SolveMode::DelayedGuarded`] on this model and limits, in
    /// `(0, 1]` (1: no under-relaxation): the guarded IHC's, [`crate::Ihc::guard_relaxation`].
    /// Reported whatever the mode.
    pub fn guard_relaxation(&self) -> T {
        self.relaxation
    }

    /// The plant model's operators' memory as the compensator tracks it (the memory of
    /// `F_{r_i}[v]` for the voltages emitted so far).
    pub fn memory(&self) -> &[T] {
        self.bank.memory()
    }
}

/// `h(v) + (a2 + sum of moving b) v + beta = y_d` on one segment (`h(v) = a1 v^3` for the
/// paper's cubic), in the voltage `v` itself.
struct Eq9<T, R> {
    remainder: R,
    desired: T,
}

impl<T: Real, R: Remainder<T>> SegmentEquation<T> for Eq9<T, R> {
    #[inline(always)]
    fn residual(&self, x: T, alpha: T, beta: T) -> T {
        self.remainder.with_linear(x, alpha) + beta - self.desired
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
        let terms = self.remainder.size(x) + (alpha * x).abs() + beta.abs() + self.desired.abs();
        rounding_tolerance(terms)
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, f_lo: T, f_hi: T, alpha: T, beta: T, _inv: T) -> T {
        increasing_root(
            self.remainder,
            alpha,
            beta - self.desired,
            lo,
            hi,
            f_lo,
            f_hi,
        )
    }
}

/// The guarded loop's step on one segment: the plant's PI part `alpha v + beta` (the bank's
/// output) brought to `target`, in the voltage itself.
struct BankOutput<T> {
    target: T,
}

impl<T: Real> SegmentEquation<T> for BankOutput<T> {
    #[inline(always)]
    fn residual(&self, x: T, alpha: T, beta: T) -> T {
        alpha * x + beta - self.target
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
    fn root(&self, lo: T, hi: T, _f_lo: T, _f_hi: T, _alpha: T, beta: T, inv_alpha: T) -> T {
        ((self.target - beta) * inv_alpha).max(lo).min(hi)
    }
}

impl<T: Real, B: Buffer<T>> Wihc<T, B> {
    /// One sample with a higher-degree input polynomial, out of line so that the cubic's path
    /// stays as short as it was.
    #[inline(never)]
    fn general_step(&mut self, desired: T) -> T {
        let (bank, guard) = (&mut self.bank, &mut self.guard);
        let (mode, relaxation, inverse_a2) = (self.mode, self.relaxation, self.inverse_a2);
        wihc_step(
            bank,
            guard,
            mode,
            relaxation,
            inverse_a2,
            &self.input,
            desired,
        )
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
        if self.input.is_odd_cubic() {
            let remainder = OddCubic(self.input.a1());
            let (bank, guard) = (&mut self.bank, &mut self.guard);
            let (mode, relaxation, inverse_a2) = (self.mode, self.relaxation, self.inverse_a2);
            wihc_step(
                bank, guard, mode, relaxation, inverse_a2, remainder, desired,
            )
        } else {
            self.general_step(desired)
        }
    }

    fn limits(&self) -> OutputLimits<T> {
        self.guard.limits
    }

    fn diagnostics(&self) -> Diagnostics {
        self.guard.diagnostics
    }
}

/// One sample of WIHC with the remainder `h` (the paper's cubic or a higher-degree one, each
/// specialised).
#[inline(always)]
fn wihc_step<T: Real, B: Buffer<T>, R: Remainder<T>>(
    bank: &mut PlayBank<T, B>,
    guard: &mut OutputGuard<T>,
    mode: SolveMode,
    relaxation: T,
    inverse_a2: T,
    remainder: R,
    desired: T,
) -> T {
    let v_prev = bank.input();
    if mode == SolveMode::Exact {
        let equation = Eq9 { remainder, desired };
        let f_prev = remainder.value(v_prev) + bank.output() - desired;
        let s = bank.solve(&equation, f_prev, guard.limits);
        let v = guard.emit(s.input, s.saturated);
        if v == s.input {
            bank.feed_solved(&s);
        } else {
            bank.feed(v);
        }
        return v;
    }
    if mode == SolveMode::DelayedGuarded {
        let equation = Eq9 { remainder, desired };
        let h_prev = remainder.value(v_prev);
        let p1_prev = bank.output();
        // The model's output for the previous drive minus y_d: -e(t).
        let f_prev = h_prev + p1_prev - desired;
        // Beyond reach from this state: the exact solution is the limit in the direction of
        // travel; emitted at once and counted, as the exact WIHC does.
        let reach = bank.solve(&ReachOnly(&equation), f_prev, guard.limits);
        let s = if reach.saturated {
            reach
        } else {
            // P1 = z(t) = P1(t - Ts) + mu e(t); with mu = 1, y_d - h(v(t - Ts)).
            let target = if relaxation < T::one() {
                p1_prev - relaxation * f_prev
            } else {
                desired - h_prev
            };
            bank.solve(&BankOutput { target }, p1_prev - target, guard.limits)
        };
        // A clamp of a reachable y_d (rounding only, by the proof) is the loop's.
        let reachable = !reach.saturated;
        let v = guard.emit_classified(s.input, s.saturated, || reachable);
        if v == s.input {
            bank.feed_solved(&s);
        } else {
            bank.feed(v);
        }
        return v;
    }
    // H[v](t - Ts) = h(v(t - Ts)) + sum b_i F_{r_i}[v](t - Ts).
    let h_prev = remainder.value(v_prev) + bank.memory_sum();
    let next = (desired - h_prev) * inverse_a2;
    // A clamped sample counts as a loop saturation when the exact eq. (9) could have been met
    // within the limits from the same state (solved only then).
    let limits = guard.limits;
    let state: &PlayBank<T, B> = bank;
    let reachable = || {
        let equation = Eq9 { remainder, desired };
        let f_prev = remainder.value(v_prev) + state.output() - desired;
        !state.solve(&equation, f_prev, limits).saturated
    };
    let v = guard.emit_classified(next, false, reachable);
    bank.feed(v);
    v
}
