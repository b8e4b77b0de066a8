//! Direct inverse hysteresis compensation (DIHC), eq. (10).

use crate::compensator::OutputGuard;
use crate::mpim::check_range;
use crate::{Buffer, Compensator, CoreError, Diagnostics, Mpim, OutputLimits, Real};

/// DIHC, section 3.3: an MPIM identified directly from (displacement -> voltage) data models the
/// inverse hysteresis, and is evaluated on the desired trajectory,
/// `v(t) = a1 y_d^3(t) + a2 y_d(t) + sum b_i F_{r_i}[y_d](t)`, eq. (10) with the corrected
/// `a2` term (ERRATA item 1).
///
/// The desired position is clamped into the model's input range (the range of positions it was
/// identified on; a clamp counts as a saturation), then the output into the limits.
/// See [`Compensator`] for the output guarantees.
#[derive(Debug, Clone)]
pub struct Dihc<T: Real, B: Buffer<T>> {
    pub(crate) model: Mpim<T, B>,
    pub(crate) input_min: T,
    pub(crate) input_max: T,
    pub(crate) guard: OutputGuard<T>,
}

impl<T: Real, B: Buffer<T>> Dihc<T, B> {
    /// A DIHC from an inverse model (input: normalised desired position, output: normalised
    /// control) valid on the input range `[input_min, input_max]`. The model must be strictly
    /// increasing there (see [`Mpim::check_invertible`]): an inverse of a monotone plant is.
    pub fn new<B2: Buffer<T>>(
        inverse_model: &Mpim<T, B2>,
        input_min: T,
        input_max: T,
        limits: OutputLimits<T>,
    ) -> Result<Self, CoreError> {
        check_range(input_min, input_max)?;
        inverse_model.check_invertible(input_min, input_max)?;
        let mut model: Mpim<T, B> = inverse_model.to_storage()?;
        model.reset();
        Ok(Dihc {
            model,
            input_min,
            input_max,
            guard: OutputGuard::new(limits),
        })
    }

    /// The inverse model, with its current memory.
    pub fn model(&self) -> &Mpim<T, B> {
        &self.model
    }

    /// The input range `[min, max]` of desired positions the model accepts.
    pub fn input_range(&self) -> (T, T) {
        (self.input_min, self.input_max)
    }
}

impl<T: Real, B: Buffer<T>> Compensator<T> for Dihc<T, B> {
    fn reset(&mut self) {
        self.model.reset();
        self.guard.reset();
    }

    #[inline]
    fn step(&mut self, desired: T) -> T {
        let Some(desired) = self.guard.accept(desired) else {
            return self.guard.previous;
        };
        let x = desired.max(self.input_min).min(self.input_max);
        let v = self.model.step(x);
        self.guard.emit(v, x != desired)
    }

    fn limits(&self) -> OutputLimits<T> {
        self.guard.limits
    }

    fn diagnostics(&self) -> Diagnostics {
        self.guard.diagnostics
    }
}
