//! Inverse hysteresis compensation (IHC), eqs. (5)-(8).

use crate::buffer::copied;
use crate::compensator::OutputGuard;
use crate::play::update_bank;
use crate::solve::increasing_cubic_root;
use crate::walk::{self, SegmentEquation};
use crate::{Buffer, Compensator, CoreError, Diagnostics, Mpim, OutputLimits, Real, SolveMode};

/// IHC, section 3.1: the inverse of the identified plant MPIM in the feedforward path,
/// `v(t) = P1^{-1}[w](t)` with `w = y_d - a1 v^3` (eqs. (5)-(6)) and `P1^{-1}` the analytic
/// inverse of the PI part, eq. (7) (built once by [`Mpim::pi_part_inverse`]).
///
/// - [`SolveMode::Exact`]: `w` depends on the `v(t)` being computed; the implicit equation
///   `w + a1 (P1^{-1}[w](t))^3 = y_d(t)` is solved exactly each sample, so that the plant model
///   gives `P[v](t) = y_d(t)`.
/// - [`SolveMode::Delayed`]: `w(t) = y_d(t) - a1 v^3(t - Ts)`, as real-time implementations do.
///
/// See [`Compensator`] for the output guarantees.
#[derive(Debug, Clone)]
pub struct Ihc<T: Real, B: Buffer<T>> {
    /// `r_hat_j` of eq. (7).
    thresholds: B,
    /// `b_hat_j` of eq. (7).
    weights: B,
    /// Memory of `F_{r_hat_j}[w]`.
    memory: B,
    a1: T,
    /// `a2_hat` of eq. (7).
    a2_hat: T,
    mode: SolveMode,
    /// `sum b_hat_j w_hat_j` of the current memory.
    memory_sum: T,
    /// The last `w` fed to `P1^{-1}`.
    w_prev: T,
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
            thresholds: copied(inverse.thresholds())?,
            weights: copied(inverse.weights())?,
            memory: copied(inverse.memory())?,
            a1: plant.a1(),
            a2_hat: inverse.a2(),
            mode,
            memory_sum: T::zero(),
            w_prev: T::zero(),
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
            self.thresholds.as_ref(),
            self.weights.as_ref(),
            T::zero(),
            self.a2_hat,
        )?;
        model.set_memory(self.memory.as_ref())?;
        Ok(model)
    }

    /// `P1^{-1}[w](t)` from the current memory, updating it.
    #[inline]
    fn feed(&mut self, w: T) -> T {
        self.memory_sum = update_bank(
            self.thresholds.as_ref(),
            self.weights.as_ref(),
            self.memory.as_mut(),
            w,
        );
        self.w_prev = w;
        self.a2_hat * w + self.memory_sum
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
    fn control(&self, w: T, alpha: T, beta: T) -> T {
        alpha * w + beta
    }
    #[inline(always)]
    fn input_at_control(&self, v: T, alpha: T, beta: T) -> T {
        (v - beta) / alpha
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, f_lo: T, f_hi: T, alpha: T, beta: T) -> T {
        let inv_alpha = T::one() / alpha;
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
    fn control(&self, w: T, alpha: T, beta: T) -> T {
        alpha * w + beta
    }
    #[inline(always)]
    fn input_at_control(&self, v: T, alpha: T, beta: T) -> T {
        (v - beta) / alpha
    }
    #[inline(always)]
    fn root(&self, lo: T, hi: T, _f_lo: T, _f_hi: T, _alpha: T, _beta: T) -> T {
        self.w.max(lo).min(hi)
    }
}

impl<T: Real, B: Buffer<T>> Compensator<T> for Ihc<T, B> {
    fn reset(&mut self) {
        self.memory.as_mut().fill(T::zero());
        self.memory_sum = T::zero();
        self.w_prev = T::zero();
        self.guard.reset();
        // The plant is assumed relaxed at input 0. When 0 lies outside the limits, start from
        // the nearest limit: feed the w that P1^{-1} maps to it (P1 from zero memory).
        let v0 = self.guard.previous;
        if v0 != T::zero() {
            let equation = Eq5Delayed { w: T::zero() };
            let limits = self.guard.limits;
            let s = walk::solve(
                &equation,
                self.a2_hat,
                self.thresholds.as_ref(),
                self.weights.as_ref(),
                self.memory.as_ref(),
                T::zero(),
                T::zero(),
                if v0 > T::zero() { -T::one() } else { T::one() },
                OutputLimits::new(v0.min(T::zero()), v0.max(T::zero())).unwrap_or(limits),
            );
            self.feed(s.input);
        }
    }

    #[inline]
    fn step(&mut self, desired: T) -> T {
        let Some(desired) = self.guard.accept(desired) else {
            return self.guard.previous;
        };
        let v_prev = self.guard.previous;
        let solution = match self.mode {
            SolveMode::Exact => {
                let equation = Eq5Exact {
                    a1: self.a1,
                    desired,
                };
                // Residual at the previous sample: w_prev + a1 v_prev^3 - y_d.
                let f_prev = self.w_prev + self.a1 * v_prev * v_prev * v_prev - desired;
                walk::solve(
                    &equation,
                    self.a2_hat,
                    self.thresholds.as_ref(),
                    self.weights.as_ref(),
                    self.memory.as_ref(),
                    self.memory_sum,
                    self.w_prev,
                    f_prev,
                    self.guard.limits,
                )
            }
            SolveMode::Delayed => {
                // Eq. (5) with the loop broken: w(t) = y_d(t) - a1 v^3(t - Ts).
                let w = desired - self.a1 * v_prev * v_prev * v_prev;
                let equation = Eq5Delayed { w };
                walk::solve(
                    &equation,
                    self.a2_hat,
                    self.thresholds.as_ref(),
                    self.weights.as_ref(),
                    self.memory.as_ref(),
                    self.memory_sum,
                    self.w_prev,
                    self.w_prev - w,
                    self.guard.limits,
                )
            }
        };
        let v = self.feed(solution.input);
        self.guard.emit(v, solution.saturated)
    }

    fn limits(&self) -> OutputLimits<T> {
        self.guard.limits
    }

    fn diagnostics(&self) -> Diagnostics {
        self.guard.diagnostics
    }
}
