//! The plant as a chain of links and its compensator as the chain inverted
//! (`hysteresis -> creep -> vibration`, Croft, Shed & Devasia 2001, doi:10.1115/1.1341197).
//!
//! - [`ChainModel`]: the forward chain `y = D[C[H[v]]]`, each link optional but the MPIM.
//! - [`ChainCompensator`]: the inverse in reverse order, `v = H^-1[C^-1[D^-1[y_d]]]`: the
//!   vibration inverse over a preview of `p` samples ([`VibrationInverse`]), then the creep
//!   inverse ([`CreepInverse`], a filter), then any hysteresis compensator of the paper (IHC,
//!   WIHC, DIHC; exact or delayed). Its output lags its input by `p` samples; offline, over a
//!   known trajectory, [`ChainCompensator::process_aligned`] removes the lag.
//!
//! Everything runs in the normalised units of the hysteresis link's output (the creep link's
//! `origin` is given in them); the model file (`hystcomp-io`) carries the physical scales.

use crate::real::followable;
use crate::{
    Buffer, Compensator, CoreError, Creep, CreepInverse, Diagnostics, Mpim, OutputLimits, Real,
    Vibration, VibrationInverse,
};

/// The forward chain `y = D[C[H[v]]]`: an MPIM, then optionally creep, then optionally
/// vibration. Starts with the MPIM's memory at zero, creep relaxed and the vibration link at
/// rest at its first input.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainModel<T: Real, B: Buffer<T>, C: Buffer<T>> {
    /// The hysteresis link.
    pub hysteresis: Mpim<T, B>,
    /// The creep link, if any.
    pub creep: Option<Creep<T, C>>,
    /// The vibration link, if any.
    pub vibration: Option<Vibration<T, C>>,
}

impl<T: Real, B: Buffer<T>, C: Buffer<T>> ChainModel<T, B, C> {
    /// Back to the initial state of every link.
    pub fn reset(&mut self) {
        self.hysteresis.reset();
        if let Some(c) = &mut self.creep {
            c.reset();
        }
        if let Some(d) = &mut self.vibration {
            d.reset();
        }
    }

    /// One sample through every link.
    #[inline]
    pub fn step(&mut self, input: T) -> T {
        let mut y = self.hysteresis.step(input);
        if let Some(c) = &mut self.creep {
            y = c.step(y);
        }
        if let Some(d) = &mut self.vibration {
            y = d.step(y);
        }
        y
    }

    /// A whole signal; refuses slices of different lengths.
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
}

/// The chain inverted in reverse order (see the [module documentation](self)): `y_d(k + p)`
/// in, the drive `v(k)` out, through the vibration inverse, the creep inverse and the
/// hysteresis compensator `H`.
///
/// Inherits the hysteresis compensator's guarantees (every output within its limits, never
/// NaN); a non-finite desired sample is replaced by the previous one and counted in
/// [`Diagnostics::non_finite`]. `step` never allocates.
#[derive(Debug, Clone)]
pub struct ChainCompensator<T: Real, C: Buffer<T>, H: Compensator<T>> {
    vibration: Option<VibrationInverse<T, C>>,
    creep: Option<CreepInverse<T, C>>,
    hysteresis: H,
    non_finite: u64,
    last: Option<T>,
}

impl<T: Real, C: Buffer<T>, H: Compensator<T>> ChainCompensator<T, C, H> {
    /// The chain of the given inverses around `hysteresis`.
    pub fn new(
        vibration: Option<VibrationInverse<T, C>>,
        creep: Option<CreepInverse<T, C>>,
        hysteresis: H,
    ) -> Self {
        let mut chain = ChainCompensator {
            vibration,
            creep,
            hysteresis,
            non_finite: 0,
            last: None,
        };
        chain.reset();
        chain
    }

    /// The preview `p`, samples (0 without a vibration link): the output lags by `p`.
    pub fn preview(&self) -> usize {
        self.vibration.as_ref().map_or(0, |v| v.preview())
    }

    /// The hysteresis compensator.
    pub fn hysteresis(&self) -> &H {
        &self.hysteresis
    }

    /// The vibration inverse, if any.
    pub fn vibration(&self) -> Option<&VibrationInverse<T, C>> {
        self.vibration.as_ref()
    }

    /// The creep inverse, if any.
    pub fn creep(&self) -> Option<&CreepInverse<T, C>> {
        self.creep.as_ref()
    }

    /// Takes the creep link as having rested long at the displacement `desired` (its elements
    /// settled there) instead of relaxed at its origin: for a record that starts in the middle
    /// of a history, as most measured records do. The other links are untouched.
    pub fn settle_creep(&mut self, desired: T) {
        if let Some(c) = &mut self.creep {
            c.settle(desired);
        }
    }

    /// The whole known trajectory at once: `control[k]` for `desired[k]` without the lag (the
    /// trajectory is held at its last value for the preview's `p` samples after its end).
    /// Resets first; refuses slices of different lengths.
    pub fn process_aligned(&mut self, desired: &[T], control: &mut [T]) -> Result<(), CoreError> {
        if control.len() != desired.len() {
            return Err(CoreError::LengthMismatch {
                what: "control",
                expected: desired.len(),
                found: control.len(),
            });
        }
        self.reset();
        let Some(&last) = desired.last() else {
            return Ok(());
        };
        let p = self.preview();
        for (k, y) in desired
            .iter()
            .chain(core::iter::repeat_n(&last, p))
            .enumerate()
        {
            let v = self.step(*y);
            if k >= p {
                control[k - p] = v;
            }
        }
        Ok(())
    }
}

impl<T: Real, C: Buffer<T>, H: Compensator<T>> Compensator<T> for ChainCompensator<T, C, H> {
    fn reset(&mut self) {
        if let Some(v) = &mut self.vibration {
            v.reset();
        }
        if let Some(c) = &mut self.creep {
            c.reset();
        }
        self.hysteresis.reset();
        self.non_finite = 0;
        self.last = None;
    }

    /// A desired sample not finite, or (with a creep or vibration link) beyond the square
    /// root of the largest value, which those links' states could not follow, is counted as
    /// not finite and the last one is held (before any, the hysteresis compensator holds its
    /// initial output).
    #[inline]
    fn step(&mut self, desired: T) -> T {
        let dynamic = self.vibration.is_some() || self.creep.is_some();
        let usable = if dynamic {
            followable(desired)
        } else {
            desired.is_finite()
        };
        let desired = if usable {
            self.last = Some(desired);
            desired
        } else {
            self.non_finite += 1;
            match self.last {
                Some(last) => last,
                // Nothing to hold yet: the hysteresis compensator holds its initial output
                // (and counts the sample, as this does).
                None => return self.hysteresis.step(T::nan()),
            }
        };
        let mut y = desired;
        if let Some(v) = &mut self.vibration {
            y = v.step(y);
        }
        if let Some(c) = &mut self.creep {
            y = c.step(y);
        }
        self.hysteresis.step(y)
    }

    fn limits(&self) -> OutputLimits<T> {
        self.hysteresis.limits()
    }

    fn diagnostics(&self) -> Diagnostics {
        let mut d = self.hysteresis.diagnostics();
        // A non-finite sample with nothing to hold is counted by the hysteresis compensator.
        d.non_finite = d.non_finite.max(self.non_finite);
        d
    }
}
