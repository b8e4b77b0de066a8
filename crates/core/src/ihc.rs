//! Inverse hysteresis compensation (IHC), eqs. (5)-(8).

use crate::compensator::OutputGuard;
use crate::solve::increasing_cubic_root;
use crate::walk::{PlayBank, SegmentEquation, rounding_tolerance};
use crate::{Buffer, Compensator, CoreError, Diagnostics, Mpim, OutputLimits, Real, SolveMode};

/// IHC, section 3.1: the inverse of the identified plant MPIM in the feedforward path,
/// `v(t) = P1^{-1}[w](t)` with `w = y_d - a1 v^3` (eqs. (5)-(6)) and `P1^{-1}` the analytic
/// inverse of the PI part, eq. (7) (built once by [`Mpim::pi_part_inverse`]).
///
/// - [`SolveMode::Exact`]: `w` depends on the `v(t)` being computed; the implicit equation
///   `w + a1 (P1^{-1}[w](t))^3 = y_d(t)` is solved exactly each sample, so that the plant model
///   gives `P[v](t) = y_d(t)`.
/// - [`SolveMode::Delayed`]: `w(t) = y_d(t) - a1 v^3(t - Ts)`, as real-time implementations do.
///   Cost: a sample where the delayed solve hits an output limit also runs the exact solve of
///   eq. (5) from the same state, only to classify the clamp (reachable:
///   [`Diagnostics::loop_saturated`]; not: [`Diagnostics::saturated`]), so it costs about one
///   exact step more. The worst case per sample is the delayed step plus the exact step;
///   real-time budgets should use that bound.
///
/// See [`Compensator`] for the output guarantees.
#[derive(Debug, Clone)]
pub struct Ihc<T: Real, B: Buffer<T>> {
    /// `P1^{-1}[w] = a2_hat w + sum b_hat_j F_{r_hat_j}[w]` of eq. (7), with its memory; its
    /// last input is the last `w`.
    inverse: PlayBank<T, B>,
    a1: T,
    mode: SolveMode,
    guard: OutputGuard<T>,
}

impl<T: Real, B: Buffer<T>> Ihc<T, B> {
    /// An IHC from a plant model: builds the inverse of eq. (7) and checks that the model is
    /// invertible over the output limits (see [`Mpim::check_invertible`]).
    pub fn new<B2: Buffer<T>>(
        plant: &Mpim<T, B2>,
        limits: OutputLimits<T>,
        mode: SolveMode,
    ) -> Result<Self, CoreError> {
        plant.check_invertible(limits.min(), limits.max())?;
        let inverse = plant.pi_part_inverse()?;
        let mut ihc = Ihc {
            inverse: PlayBank::new(inverse.a2(), inverse.thresholds(), inverse.weights())?,
            a1: plant.a1(),
            mode,
            guard: OutputGuard::new(limits),
        };
        ihc.reset();
        Ok(ihc)
    }

    /// The solve mode.
    pub fn mode(&self) -> SolveMode {
        self.mode
    }

    /// The inverse PI part `P1^{-1}` of eq. (7) this compensator runs, as a model (`a1 = 0`):
    /// thresholds `r_hat_j`, weights `b_hat_j`, `a2 = a2_hat`, and its current memory.
    pub fn pi_part_inverse(&self) -> Result<Mpim<T, B>, CoreError> {
        let mut model = Mpim::new(
            self.inverse.thresholds(),
            self.inverse.weights(),
            T::zero(),
            self.inverse.a(),
        )?;
        model.set_memory(self.inverse.memory())?;
        Ok(model)
    }
}

/// Exact IHC on one segment where `P1^{-1}[w] = alpha w + beta`:
/// `w + a1 (alpha w + beta)^3 = y_d`, solved in `v = alpha w + beta` as
/// `a1 v^3 + v / alpha - beta / alpha - y_d = 0`.
struct Eq5Exact<T> {
    a1: T,
    desired: T,
}

impl<T: Real> SegmentEquation<T> for Eq5Exact<T> {
    #[inline(always)]
    fn residual(&self, w: T, alpha: T, beta: T) -> T {
        let v = alpha * w + beta;
        w + self.a1 * v * v * v - self.desired
    }
    #[inline(always)]
    fn rounding(&self, w: T, alpha: T, beta: T) -> T {
        let v = alpha * w + beta;
        let terms = w.abs() + (self.a1 * v * v * v).abs() + self.desired.abs();
        rounding_tolerance(terms)
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, f_lo: T, f_hi: T, alpha: T, beta: T, inv_alpha: T) -> T {
        let v = increasing_cubic_root(
            self.a1,
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

/// Delayed IHC on one segment: `w` is known, `w(t) = y_d(t) - a1 v^3(t - Ts)`; the walk only
/// keeps the control within the limits.
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
        let v_prev = self.guard.previous;
        let w_prev = self.inverse.input();
        let cubic_prev = self.a1 * v_prev * v_prev * v_prev;
        let exact = Eq5Exact {
            a1: self.a1,
            desired,
        };
        // Residual of the exact eq. (5) at the previous sample: w_prev + a1 v_prev^3 - y_d.
        let f_exact = w_prev + cubic_prev - desired;
        match self.mode {
            SolveMode::Exact => {
                let solution = self.inverse.solve(&exact, f_exact, self.guard.limits);
                let v = self.inverse.feed_solved(&solution);
                self.guard.emit(v, solution.saturated)
            }
            SolveMode::Delayed => {
                // Eq. (5) with the loop broken: w(t) = y_d(t) - a1 v^3(t - Ts).
                let w = desired - cubic_prev;
                let solution = self
                    .inverse
                    .solve(&Eq5Delayed { w }, w_prev - w, self.guard.limits);
                // A clamped sample: was y_d reachable within the limits? The exact solve from
                // the same state says; it only runs when the delayed loop hit a limit.
                let reachable = solution.saturated
                    && !self
                        .inverse
                        .solve(&exact, f_exact, self.guard.limits)
                        .saturated;
                let v = self.inverse.feed_solved(&solution);
                self.guard
                    .emit_classified(v, solution.saturated, || reachable)
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
