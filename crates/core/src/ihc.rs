//! Inverse hysteresis compensation (IHC), eqs. (5)-(8).

use crate::buffer::copied;
use crate::compensator::OutputGuard;
use crate::invertibility::DelayedLoop;
use crate::solve::{OddCubic, Remainder, increasing_root};
use crate::walk::{PlayBank, ReachOnly, SegmentEquation, rounding_tolerance};
use crate::{
    Buffer, Compensator, CoreError, Diagnostics, InputPolynomial, LoopGain, Mpim, OutputLimits,
    Real, SolveMode,
};

/// IHC, section 3.1: the inverse of the identified plant MPIM in the feedforward path,
/// `v(t) = P1^{-1}[w](t)` with `w = y_d - a1 v^3` (eqs. (5)-(6)) and `P1^{-1}` the analytic
/// inverse of the PI part, eq. (7) (built once by [`Mpim::pi_part_inverse`]). With a
/// higher-degree input polynomial `g`, `a1 v^3` is its remainder `h(v) = g(v) - a2 v`.
///
/// - [`SolveMode::Exact`]: `w` depends on the `v(t)` being computed; the implicit equation
///   `w + h(P1^{-1}[w](t)) = y_d(t)` is solved exactly each sample, so that the plant model
///   gives `P[v](t) = y_d(t)`.
/// - [`SolveMode::Delayed`]: `w(t) = y_d(t) - h(v(t - Ts))`, as real-time implementations do,
///   and `v(t) = P1^{-1}[w](t)` evaluated directly (the inverse's operators fed `w`, eq. (7));
///   only a `v` beyond the limits walks the inverse's segments to stop at the limit. With more
///   than [`DIRECT_OPERATORS`] (16) operators every sample walks instead (cheaper there: the
///   walk crosses a segment or two, the evaluation passes over every operator), the same
///   drive to rounding.
///   While `y_d` holds, successive `w` differ by at most [`Ihc::delayed_loop_gain`] times the
///   previous difference (`|g'(x) - a2| / (a2 + b_1 + ... + b_k)` over the reachable branches,
///   see [`Mpim::delayed_ihc_loop_gain`]): below 1 the loop settles after any jump in `y_d`;
///   at or above 1 it can ring between the limits (after reversals near the top of the range
///   on models with a large positive `a1`), and the constructor refuses it with
///   [`CoreError::DelayedLoopUnstable`].
/// - [`SolveMode::DelayedAllowUnstable`]: the same loop without that check (the explicit
///   override).
/// - [`SolveMode::DelayedGuarded`]: an under-relaxed delayed loop that cannot oscillate,
///   whatever the model. Each sample first asks whether `y_d` is reachable within the limits
///   from the current state: at once when the relaxed step's `v = P1^{-1}[w]`, evaluated
///   directly (with at most [`DIRECT_OPERATORS`] operators), lies within the limits and the
///   residual of eq. (5) changes sign between `w(t - Ts)` and `w`, or cannot reach zero before
///   `w` has moved the inverse's least reciprocal slope times the distance from `v` to the
///   limit (then that `v` is the output; see `guarded_reach`), otherwise by walking the
///   inverse's segments with the exact residual, without solving on the last one (the walk
///   alone, no root). When it is not, the exact solution is the limit in the direction of
///   travel: the guarded loop emits it at once
///   (bit for bit the exact IHC's output) and counts the sample in
///   [`Diagnostics::saturated`]. When it is, the loop takes the under-relaxed step
///
///   `w(t) = w(t - Ts) + mu e(t)`, `e(t) = y_d(t) - w(t - Ts) - h(v(t - Ts))`,
///   `mu = min(1, 1 / (1 + q_max))`,
///
///   where `w(t - Ts) + h(v(t - Ts))` is the plant model's output for the previous drive
///   (`P1[P1^{-1}[w]] = w`, ERRATA item 3), so `e` is the model's tracking error, and `q_max`
///   is the largest signed gain `(g'(x) - a2) / (a2 + b_1 + ... + b_k)` over the reachable
///   branches. With `mu = 1` a reachable sample is the plain delayed loop's, bit for bit when
///   both evaluate `P1^{-1}[w]` directly; where the guarded loop walks (near the limits, where
///   its reach bound fails) and shortly after, to a few ulp (the walk ends on a segment and
///   evaluates it there).
///
///   *Proof sketch.* While `y_d` holds, moving `w` from `w(t - Ts)` to `w(t)` moves `v` along
///   `P1^{-1}` and the model's output by `integral (1 + q(k, v)) dw` over the move, where each
///   `(k, v)` met is a reachable branch and `1 + q = (g'(v) + b_1 + ... + b_k) /
///   (a2 + b_1 + ... + b_k)` is the model's slope over the PI part's, positive for an
///   invertible model. So `e(t + Ts) = e(t) (1 - mu (1 + q_avg))` with `1 + q_avg` in
///   `[1 + q_min, 1 + q_max]`: the factor lies in `[0, 1 - mu (1 + q_min)]`, below 1. The
///   error keeps its sign and shrinks, and since the exact solution lies within the limits
///   the step never reaches a limit: the model's
///   output approaches `y_d` from one side and the drive moves monotonically towards the exact
///   solution. An unreachable `y_d` sends the drive to the limit the exact solution sits on,
///   where it stays while `y_d` holds (feeding the limit again changes no memory). Either
///   way the drive never alternates between limits. When `y_d` moves, the error is the
///   tracking lag, again without overshoot from the loop. The price: when `q_max > 0` it lags
///   a little more than the plain delayed loop.
///
/// Cost: a sample of the plain delayed loop that hits an output limit also runs the exact
/// solve of eq. (5) from the same state, only to classify the clamp (reachable:
/// [`Diagnostics::loop_saturated`]; not: [`Diagnostics::saturated`]), so it costs about one
/// exact step more; real-time budgets should use the delayed step plus the exact step. The
/// guarded loop mostly costs the plain one's direct evaluation; a sample it cannot settle so
/// (near a limit) recounts the moving operators and walks twice (the reachability walk, then
/// the relaxed step's), never solving a root of the cubic: its worst case is one evaluation,
/// a recount, two walks over the operators and one memory update.
///
/// See [`Compensator`] for the output guarantees.
#[derive(Debug, Clone)]
pub struct Ihc<T: Real, B: Buffer<T>> {
    /// `P1^{-1}[w] = a2_hat w + sum b_hat_j F_{r_hat_j}[w]` of eq. (7), with its memory; its
    /// last input is the last `w`.
    pub(crate) inverse: PlayBank<T, B>,
    /// The plant's input polynomial `g`; the loop uses its remainder `g(v) - a2 v`.
    pub(crate) input: InputPolynomial<T>,
    pub(crate) mode: SolveMode,
    /// `mu` of [`SolveMode::DelayedGuarded`], whatever the mode.
    pub(crate) relaxation: T,
    /// [`PlayBank::least_inverse_alpha`] of the inverse: the guarded loop's bound on how far
    /// `w` must move before `P1^{-1}[w]` reaches a limit.
    pub(crate) least_inverse_alpha: T,
    /// The delayed loop's worst-case gain over the limits, whatever the mode (kept: it needs
    /// the plant's thresholds and weights, which the compensator does not keep).
    pub(crate) loop_gain: LoopGain<T>,
    pub(crate) guard: OutputGuard<T>,
}

impl<T: Real, B: Buffer<T>> Ihc<T, B> {
    /// An IHC from a plant model: builds the inverse of eq. (7), checks that the model is
    /// invertible over the output limits (see [`Mpim::check_invertible`]) and, for
    /// [`SolveMode::Delayed`], that the delayed loop's gain over the limits is below 1.
    pub fn new<B2: Buffer<T>>(
        plant: &Mpim<T, B2>,
        limits: OutputLimits<T>,
        mode: SolveMode,
    ) -> Result<Self, CoreError> {
        plant.check_invertible(limits.min(), limits.max())?;
        // The walk runs eq. (7)'s inverse with a single zero-threshold operator folded into the
        // linear term (`Mpim::pi_part_inverse_folded`), which keeps the segment slopes accurate
        // when a2 is small beside b_1; `pi_part_inverse` reports the literal form.
        let inverse = if folds(plant.thresholds(), plant.a2()) {
            plant.pi_part_inverse_folded()?
        } else {
            plant.pi_part_inverse()?
        };
        let gains = plant.delayed_gain_range(DelayedLoop::Ihc, limits.min(), limits.max());
        // NaN counts as unstable.
        if mode == SolveMode::Delayed && (gains.worst.gain >= T::one() || gains.worst.gain.is_nan())
        {
            return Err(CoreError::DelayedLoopUnstable {
                compensator: "IHC",
                gain: gains.worst.gain.to_f64(),
                input: gains.worst.input.to_f64(),
                active_operators: gains.worst.active_operators,
            });
        }
        let bank = PlayBank::new(inverse.a2(), inverse.thresholds(), inverse.weights())?;
        let mut ihc = Ihc {
            least_inverse_alpha: bank.least_inverse_alpha(),
            inverse: bank,
            input: *plant.input_polynomial(),
            mode,
            relaxation: gains.relaxation(),
            loop_gain: gains.worst,
            guard: OutputGuard::new(limits),
        };
        ihc.reset();
        Ok(ihc)
    }

    /// The solve mode.
    pub fn mode(&self) -> SolveMode {
        self.mode
    }

    /// The worst-case small-signal gain of the delayed loop over every branch reachable within
    /// the output limits, `max |g'(x) - a2| / (a2 + b_1 + ... + b_k)` (see
    /// [`Mpim::delayed_ihc_loop_gain`]). Reported whatever the mode, so that a caller can
    /// choose: below 1 the delayed loop settles after any jump in `y_d`; at or above 1 prefer
    /// [`SolveMode::Exact`] or [`SolveMode::DelayedGuarded`]. Table 1 of the paper on
    /// `[0, 1]`: 0.68.
    pub fn delayed_loop_gain(&self) -> LoopGain<T> {
        self.loop_gain
    }

    /// The under-relaxation `mu` of [`SolveMode::DelayedGuarded`] on this model and limits, in
    /// `(0, 1]` (1: the guarded loop is the plain delayed one). Reported whatever the mode.
    pub fn guard_relaxation(&self) -> T {
        self.relaxation
    }

    /// The inverse PI part `P1^{-1}` of eq. (7) this compensator runs, as a model (`a1 = 0`):
    /// thresholds `r_hat_j`, weights `b_hat_j`, `a2 = a2_hat`, and its current memory.
    pub fn pi_part_inverse(&self) -> Result<Mpim<T, B>, CoreError> {
        let a2 = self.input.a2();
        let mut weights: B = copied(self.inverse.weights())?;
        let mut a_hat = self.inverse.a();
        if folds(self.inverse.thresholds(), a2) {
            // Unfolded: a2_hat = 1 / a2 and b_hat_1 = 1 / (a2 + b_1) - 1 / a2, the very values
            // `Mpim::pi_part_inverse` computes (the folded a2_hat is 1 / (a2 + b_1)).
            let literal = T::one() / a2;
            if let Some(b) = weights.as_mut().first_mut() {
                *b = a_hat - literal;
            }
            a_hat = literal;
        }
        let mut model = Mpim::new(
            self.inverse.thresholds(),
            weights.as_ref(),
            T::zero(),
            a_hat,
        )?;
        model.set_memory(self.inverse.memory())?;
        Ok(model)
    }
}

/// Whether IHC runs eq. (7)'s inverse folded (see [`Ihc::new`]): exactly one operator of zero
/// threshold and `a2 > 0` (otherwise `Mpim::pi_part_inverse` folds already, or has nothing
/// to fold). The inverse's thresholds are zero where the plant's are.
fn folds<T: Real>(thresholds: &[T], a2: T) -> bool {
    let always = thresholds.iter().take_while(|r| **r <= T::zero()).count();
    always == 1 && a2 > T::zero()
}

/// Exact IHC on one segment where `P1^{-1}[w] = alpha w + beta`:
/// `w + h(alpha w + beta) = y_d`, solved in `v = alpha w + beta` as
/// `h(v) + v / alpha - beta / alpha - y_d = 0`.
struct Eq5Exact<T, R> {
    remainder: R,
    desired: T,
}

impl<T: Real, R: Remainder<T>> SegmentEquation<T> for Eq5Exact<T, R> {
    #[inline(always)]
    fn residual(&self, w: T, alpha: T, beta: T) -> T {
        let v = alpha * w + beta;
        w + self.remainder.value(v) - self.desired
    }
    #[inline(always)]
    fn rounding(&self, w: T, alpha: T, beta: T) -> T {
        let v = alpha * w + beta;
        let terms = w.abs() + self.remainder.size(v) + self.desired.abs();
        rounding_tolerance(terms)
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, f_lo: T, f_hi: T, alpha: T, beta: T, inv_alpha: T) -> T {
        let v = increasing_root(
            self.remainder,
            inv_alpha,
            -beta * inv_alpha - self.desired,
            alpha * lo + beta,
            alpha * hi + beta,
            f_lo,
            f_hi,
        );
        ((v - beta) * inv_alpha).max(lo).min(hi)
    }
}

/// Delayed IHC on one segment: `w` is known, `w(t) = y_d(t) - h(v(t - Ts))` (or the guarded
/// update); the walk only keeps the control within the limits.
struct Eq5Delayed<T> {
    w: T,
}

impl<T: Real> SegmentEquation<T> for Eq5Delayed<T> {
    #[inline(always)]
    fn residual(&self, w: T, _alpha: T, _beta: T) -> T {
        w - self.w
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, _f_lo: T, _f_hi: T, _alpha: T, _beta: T, _inv: T) -> T {
        self.w.max(lo).min(hi)
    }
}

/// The `w` where `P1^{-1}[w] = control`, from the current memory (used to start at a limit).
struct ReachControl<T> {
    control: T,
}

impl<T: Real> SegmentEquation<T> for ReachControl<T> {
    #[inline(always)]
    fn residual(&self, w: T, alpha: T, beta: T) -> T {
        alpha * w + beta - self.control
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, _f_lo: T, _f_hi: T, _alpha: T, beta: T, inv_alpha: T) -> T {
        ((self.control - beta) * inv_alpha).max(lo).min(hi)
    }
}

/// The most operators for which the delayed and guarded IHC evaluate `P1^{-1}[w]` directly:
/// a pass over every operator, and another to feed them, against a walk over the segments the
/// sample crosses (usually one or two). One `Ihc` on the criterion bench's trajectory (per
/// trajectory, the two ways taking turns, 2026-11-28): the guarded loop f64 269 -> 223 us with
/// 10 operators, 403 -> 1 108 us with 100 (f32 265 -> 252, 346 -> 1 276): the two cross near
/// 11-16 operators. A bank evaluates a channel directly by the same rule, so that each channel
/// stays its single compensator's twin bit for bit.
pub const DIRECT_OPERATORS: usize = 16;

/// Whether the delayed and guarded loops evaluate this inverse directly
/// ([`DIRECT_OPERATORS`]).
#[inline(always)]
fn evaluates_directly<T: Real, B: Buffer<T>>(inverse: &PlayBank<T, B>) -> bool {
    inverse.thresholds().len() <= DIRECT_OPERATORS
}

/// Whether the guarded loop's step to `w`, whose `v = P1^{-1}[w]` was evaluated directly,
/// proves `y_d` reachable within the limits, so that `v` is the step's output without a walk.
///
/// Eq. (5)'s residual `F(x) = x + h(P1^{-1}[x]) - y_d` increases in `x`, and `P1^{-1}`, moved
/// monotonically from `w(t - Ts)`, gives at each `x` what feeding `x` at once gives. Rising
/// (`F(w(t - Ts)) <= 0`, `w >= w(t - Ts)`, `v <= v_max`): the root lies before the limit when
/// `F` is already `>= 0` at `w`, or at the `x_max` where `P1^{-1}` reaches `v_max`, which lies
/// at least `least_inverse_alpha (v_max - v)` beyond `w`: `F(x_max) >= w +
/// least_inverse_alpha (v_max - v) + h(v_max) - y_d >= 0`. Falling, the mirror image.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn guarded_reach<T: Real, R: Remainder<T>>(
    limits: OutputLimits<T>,
    least_inverse_alpha: T,
    remainder: R,
    desired: T,
    f_exact: T,
    w_prev: T,
    w: T,
    v: T,
) -> bool {
    let (min, max) = (limits.min(), limits.max());
    if !(v >= min && v <= max) {
        return false;
    }
    let f_w = w + remainder.value(v) - desired;
    if f_exact <= T::zero() {
        let at_limit = w + least_inverse_alpha * (max - v) + remainder.value(max) - desired;
        w >= w_prev && (f_w >= T::zero() || at_limit >= T::zero())
    } else {
        let at_limit = w - least_inverse_alpha * (v - min) + remainder.value(min) - desired;
        w <= w_prev && (f_w <= T::zero() || at_limit <= T::zero())
    }
}

/// One sample of IHC with the remainder `h` (the paper's cubic or a higher-degree one, each
/// specialised).
#[inline(always)]
fn ihc_step<T: Real, B: Buffer<T>, R: Remainder<T>>(
    inverse: &mut PlayBank<T, B>,
    guard: &mut OutputGuard<T>,
    mode: SolveMode,
    relaxation: T,
    least_inverse_alpha: T,
    remainder: R,
    desired: T,
) -> T {
    let v_prev = guard.previous;
    let w_prev = inverse.input();
    let h_prev = remainder.value(v_prev);
    let exact = Eq5Exact { remainder, desired };
    // Residual of the exact eq. (5) at the previous sample: w_prev + h(v_prev) - y_d, minus the
    // model's tracking error of the previous drive.
    let f_exact = w_prev + h_prev - desired;
    if mode == SolveMode::Exact {
        let solution = inverse.solve(&exact, f_exact, guard.limits);
        let v = inverse.feed_solved(&solution);
        return guard.emit(v, solution.saturated);
    }
    if mode == SolveMode::DelayedGuarded {
        // The under-relaxed w(t - Ts) + mu (y_d(t) - w(t - Ts) - h(v(t - Ts))); with mu = 1
        // the plain delayed loop's w.
        let w = if relaxation < T::one() {
            w_prev - relaxation * f_exact
        } else {
            desired - h_prev
        };
        if evaluates_directly(inverse) {
            let v = inverse.output_at(w);
            if guarded_reach(
                guard.limits,
                least_inverse_alpha,
                remainder,
                desired,
                f_exact,
                w_prev,
                w,
                v,
            ) {
                inverse.feed(w);
                return guard.emit_classified(v, false, || true);
            }
            // Otherwise the walks, from the counts of the memory as it is.
            inverse.recount();
        }
        // Beyond reach from this state: the exact solution is the limit in the direction of
        // travel; emitted at once and counted, as the exact IHC does.
        let reach = inverse.solve(&ReachOnly(&exact), f_exact, guard.limits);
        if reach.saturated {
            let v = inverse.feed_solved(&reach);
            return guard.emit(v, true);
        }
        let solution = inverse.solve(&Eq5Delayed { w }, w_prev - w, guard.limits);
        let v = inverse.feed_solved(&solution);
        // y_d is reachable: a clamp here (rounding only, by the proof) is the loop's.
        return guard.emit_classified(v, solution.saturated, || true);
    }
    // Eq. (5) with the loop broken: w(t) = y_d(t) - h(v(t - Ts)), and v(t) = P1^{-1}[w](t)
    // evaluated directly, the inverse PI part's operators fed w.
    let w = desired - h_prev;
    if evaluates_directly(inverse) {
        let v = inverse.output_at(w);
        if v >= guard.limits.min() && v <= guard.limits.max() {
            inverse.feed(w);
            return guard.emit_classified(v, false, || false);
        }
        // Beyond the limits (or not finite): the walk towards w, from the counts of the memory
        // as it is (the direct evaluations above leave them unused).
        inverse.recount();
    }
    // The walk towards w, stopped at a limit.
    let solution = inverse.solve(&Eq5Delayed { w }, w_prev - w, guard.limits);
    // A clamped sample: was y_d reachable within the limits? The exact solve from the same
    // state says; it only runs when the delayed loop hit a limit.
    let reachable = solution.saturated && !inverse.solve(&exact, f_exact, guard.limits).saturated;
    let v = inverse.feed_solved(&solution);
    guard.emit_classified(v, solution.saturated, || reachable)
}

impl<T: Real, B: Buffer<T>> Ihc<T, B> {
    /// One sample with a higher-degree input polynomial, out of line so that the cubic's path
    /// stays as short as it was.
    #[inline(never)]
    fn general_step(&mut self, desired: T) -> T {
        let (inverse, guard) = (&mut self.inverse, &mut self.guard);
        ihc_step(
            inverse,
            guard,
            self.mode,
            self.relaxation,
            self.least_inverse_alpha,
            &self.input,
            desired,
        )
    }
}

impl<T: Real, B: Buffer<T>> Compensator<T> for Ihc<T, B> {
    fn reset(&mut self) {
        self.inverse.reset();
        self.guard.reset();
        // The plant is assumed relaxed at input 0. When 0 lies outside the limits, start from
        // the nearest limit: feed the w that P1^{-1} maps to it (P1 from zero memory).
        let v0 = self.guard.previous;
        if v0 != T::zero() {
            let equation = ReachControl { control: v0 };
            let s = self.inverse.solve(&equation, -v0, self.guard.limits);
            self.inverse.feed(s.input);
        }
    }

    #[inline]
    fn step(&mut self, desired: T) -> T {
        let Some(desired) = self.guard.accept(desired) else {
            return self.guard.previous;
        };
        if self.input.is_odd_cubic() {
            let remainder = OddCubic(self.input.a1());
            let (inverse, guard) = (&mut self.inverse, &mut self.guard);
            ihc_step(
                inverse,
                guard,
                self.mode,
                self.relaxation,
                self.least_inverse_alpha,
                remainder,
                desired,
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
