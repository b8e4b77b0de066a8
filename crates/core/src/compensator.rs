//! The interface shared by the three feedforward compensators (IHC, WIHC, DIHC).

use crate::{CoreError, Real};

/// The range of control outputs a compensator may emit, in normalised units (the model file
/// converts from volts). No compensator ever leaves it, whatever it is fed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputLimits<T> {
    min: T,
    max: T,
}

impl<T: Real> OutputLimits<T> {
    /// Limits `[min, max]`, both finite, `min < max`.
    pub fn new(min: T, max: T) -> Result<Self, CoreError> {
        if min.is_finite() && max.is_finite() && min < max {
            Ok(OutputLimits { min, max })
        } else {
            Err(CoreError::InvalidLimits {
                min: min.to_f64(),
                max: max.to_f64(),
            })
        }
    }

    /// The lower limit.
    pub fn min(&self) -> T {
        self.min
    }

    /// The upper limit.
    pub fn max(&self) -> T {
        self.max
    }

    /// `value` clamped into the limits; NaN becomes `fallback` (itself clamped).
    #[inline]
    pub fn clamp_or(&self, value: T, fallback: T) -> T {
        let value = if value.is_nan() { fallback } else { value };
        if value < self.min {
            self.min
        } else if value > self.max {
            self.max
        } else if value.is_nan() {
            self.min
        } else {
            value
        }
    }

    /// `true` when `value` lies within the limits.
    pub fn contains(&self, value: T) -> bool {
        value >= self.min && value <= self.max
    }
}

/// How an implicit control law is solved each sample.
///
/// The three delayed modes break the implicit loop with the previous sample, as real-time
/// implementations do; they differ in how they treat a model on which that loop can oscillate
/// (loop gain of 1 or more, see [`crate::LoopGain`]): [`SolveMode::Delayed`] refuses it,
/// [`SolveMode::DelayedGuarded`] cannot oscillate on any model, and
/// [`SolveMode::DelayedAllowUnstable`] runs it anyway, an override that must be spelled out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SolveMode {
    /// The exact per-sample solution of the implicit equation (ERRATA item 4): a bracketed
    /// scalar solve on the piecewise-polynomial branch, so that `P[v](t) = y_d(t)` to machine
    /// precision when `y_d` is reachable.
    Exact,
    /// The loop broken with the previous sample, as real-time Simulink implementations do:
    /// `v(t - Ts)` in the cubic term of IHC, `H[v](t - Ts)` in WIHC. Lags by one sample. The
    /// constructors refuse a model whose delayed loop gain over the output limits is 1 or more
    /// ([`crate::CoreError::DelayedLoopUnstable`]): below 1 the loop settles after any jump in
    /// `y_d`.
    Delayed,
    /// The delayed loop with a guard that makes it unable to oscillate, whatever the model: only
    /// the input polynomial's remainder is delayed, under-relaxed where needed, and the
    /// operators are solved exactly (see [`crate::Ihc`] and [`crate::Wihc`] for the law and the
    /// proof sketch). While a reachable `y_d` holds, the model's output approaches it from one
    /// side, never passing it, so the drive moves monotonically and never rings; an unreachable
    /// `y_d` gives the exact solution's limit at once, counted in [`Diagnostics::saturated`]. On
    /// models whose delayed IHC loop already approaches monotonically (the paper's Table 1) the
    /// guarded IHC is the plain delayed IHC on reachable positions; otherwise it lags a little
    /// more. The guarded WIHC follows the same law on the plant's own operators.
    DelayedGuarded,
    /// The plain delayed loop without the loop-gain check: the explicit override for a model
    /// whose delayed loop can oscillate (gain of 1 or more). The outputs still never leave the
    /// limits or become NaN, but the loop may ring between the limits after a jump in `y_d`
    /// (counted in [`Diagnostics::loop_saturated`]).
    DelayedAllowUnstable,
}

impl SolveMode {
    /// `true` for the three one-sample-delayed modes.
    pub fn is_delayed(self) -> bool {
        self != SolveMode::Exact
    }
}

/// What a compensator had to do besides its control law, counted since the last reset.
///
/// A sample whose output was clamped to a limit counts either in `saturated` (the desired
/// position was out of reach) or in `loop_saturated` (it was reachable, but a delayed loop
/// asked for more than the limits), never in both.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Diagnostics {
    /// Samples whose desired position could not be reached within the output limits from the
    /// plant model's current state (for DIHC: lay outside the inverse model's input range, or
    /// needed a control beyond the limits): the output was clamped.
    pub saturated: u64,
    /// Samples where the output was clamped to a limit although the desired position was
    /// reachable within the limits from the plant model's current state: only the delayed
    /// loops ([`SolveMode::Delayed`], [`SolveMode::DelayedAllowUnstable`]) do this, when they
    /// lag or ring after a jump in `y_d` (see [`crate::Wihc`]). The exact solves never do, nor
    /// do the guarded loops beyond rounding.
    pub loop_saturated: u64,
    /// Samples whose desired position was NaN or infinite: the previous output was held.
    pub non_finite: u64,
}

/// A feedforward hysteresis compensator: desired position `y_d(t)` in, control `v(t)` out, both
/// normalised (figure 1 of the paper).
///
/// # Safety of the hardware
/// Every implementation guarantees that each output lies within [`Compensator::limits`] and is
/// never NaN, whatever it is fed. A NaN or infinite desired position holds the previous output
/// (the initial output before any sample is 0 clamped into the limits) and is counted in
/// [`Diagnostics::non_finite`]; a finite desired position that cannot be reached within the
/// limits gives the nearest limit and is counted in [`Diagnostics::saturated`]; a delayed loop
/// that hits a limit although the desired position was reachable is counted in
/// [`Diagnostics::loop_saturated`].
///
/// `step` and `process` never allocate.
pub trait Compensator<T: Real> {
    /// Back to the initial state: operators' memory zero (eq. (1)), previous output 0 clamped
    /// into the limits, diagnostics cleared.
    fn reset(&mut self);

    /// One sample: the control `v(t)` for the desired position `y_d(t)`.
    fn step(&mut self, desired: T) -> T;

    /// A whole signal: `control[k]` for `desired[k]`; refuses slices of different lengths
    /// (without touching the state).
    fn process(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError> {
        if control.len() != desired.len() {
            return Err(CoreError::LengthMismatch {
                what: "control",
                expected: desired.len(),
                found: control.len(),
            });
        }
        for (y_d, v) in desired.iter().zip(control.iter_mut()) {
            *v = self.step(*y_d);
        }
        Ok(())
    }

    /// The output limits.
    fn limits(&self) -> OutputLimits<T>;

    /// Counters of saturated, loop-saturated and non-finite samples since the last reset.
    fn diagnostics(&self) -> Diagnostics;
}

/// The state every compensator keeps besides its model: the previous output, the limits and
/// the counters. Enforces the safety invariant in one place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OutputGuard<T> {
    pub limits: OutputLimits<T>,
    pub previous: T,
    pub diagnostics: Diagnostics,
}

impl<T: Real> OutputGuard<T> {
    pub fn new(limits: OutputLimits<T>) -> Self {
        OutputGuard {
            limits,
            previous: limits.clamp_or(T::zero(), T::zero()),
            diagnostics: Diagnostics::default(),
        }
    }

    pub fn reset(&mut self) {
        *self = OutputGuard::new(self.limits);
    }

    /// `Some(y_d)` when finite; otherwise counts it and returns `None` (hold the output).
    #[inline]
    pub fn accept(&mut self, desired: T) -> Option<T> {
        if desired.is_finite() {
            Some(desired)
        } else {
            self.diagnostics.non_finite += 1;
            None
        }
    }

    /// Clamps `value` into the limits (counting a saturation when `saturated` or when the
    /// clamp moved it by more than rounding: an exact solution on a limit is not a
    /// saturation), records and returns it.
    #[inline]
    pub fn emit(&mut self, value: T, saturated: bool) -> T {
        self.emit_classified(value, saturated, || false)
    }

    /// As [`OutputGuard::emit`], but a clamped sample is counted as a loop saturation when
    /// `reachable()` says the desired position could have been reached within the limits
    /// (asked only for clamped samples: it may cost an exact solve).
    #[inline]
    pub fn emit_classified(
        &mut self,
        value: T,
        limited: bool,
        reachable: impl FnOnce() -> bool,
    ) -> T {
        let out = self.limits.clamp_or(value, self.previous);
        let rounding = T::epsilon() * T::from_f64(64.0) * value.abs().max(T::one());
        // An infinite value (an overflowed solve) is clamped too; its rounding is infinite, so
        // it is counted here rather than by the comparison.
        if limited || !value.is_finite() || (out - value).abs() > rounding {
            if reachable() {
                self.diagnostics.loop_saturated += 1;
            } else {
                self.diagnostics.saturated += 1;
            }
        }
        self.previous = out;
        out
    }
}

/// A boxed compensator is one (so that a chain can hold any of them behind `dyn`).
#[cfg(feature = "alloc")]
impl<T: Real, C: Compensator<T> + ?Sized> Compensator<T> for alloc::boxed::Box<C> {
    fn reset(&mut self) {
        (**self).reset()
    }

    #[inline]
    fn step(&mut self, desired: T) -> T {
        (**self).step(desired)
    }

    fn process(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError> {
        (**self).process(desired, control)
    }

    fn limits(&self) -> OutputLimits<T> {
        (**self).limits()
    }

    fn diagnostics(&self) -> Diagnostics {
        (**self).diagnostics()
    }
}
