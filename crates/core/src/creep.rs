//! The creep link of the chain `hysteresis -> creep -> vibration` (Croft, Shed & Devasia 2001,
//! doi:10.1115/1.1341197): a linear operator with log-spaced first-order elements (Kuhnen's
//! creep operators, K. Kuhnen, "Modeling, identification and compensation of complex
//! hysteretic and log(t)-type creep nonlinearities", Control and Intelligent Systems 33 (2005)
//! 134-147), acting on the hysteresis output.
//!
//! The structure follows Krejci & Kuhnen, "Inverse control of systems with hysteresis and
//! creep", IEE Proc. Control Theory Appl. 148 (2001) 185-192, and
//! Kuhnen & Krejci, "Compensation of complex hysteresis and creep effects in piezoelectrically
//! actuated systems - a new Preisach modeling approach", IEEE Trans. Autom. Control 54 (2009)
//! 537-550 (the paper's refs. \[25\] and \[8\]): creep as a linear
//! superposition of first-order (Kelvin-Voigt) elements at fixed time constants, weighted by
//! identified coefficients. **Where it acts**: on the hysteresis output, not on the voltage,
//! because what creeps in a stack is the displacement the domains produced (a held voltage
//! keeps moving the stack while the voltage does not change); written this way the chain's
//! creep is identified jointly with the MPIM by linear least squares and inverted by a filter
//! (below). A creep acting on the voltage before the hysteresis would make the fit nonlinear
//! in the MPIM's memory.
//!
//! # The inverse parameterisation
//! The link is written through its inverse, which is a plain filter of its output `x`:
//!
//! `h = C^-1[x] = x - sum_i c_i z_i[x]`, `tau_i dz_i/dt = x - z_i`,
//!
//! with displacements taken from the relaxed position `origin`. Each element is discretised
//! for an input held over the sample, `z_i(k) = z_i(k-1) + g_i (x(k) - z_i(k-1))`,
//! `g_i = 1 - exp(-T / tau_i)`, as the stage samples its position at the end of each period.
//! Three things follow:
//!
//! - **Identification is linear**: `y = H[v] + sum_i c_i z_i[y]` is linear in the MPIM's
//!   parameters and the weights `c_i` jointly (an equation-error fit on filtered measurements),
//!   where the same chain with the forward creep `C` as parameters would be bilinear.
//! - **The inverse is explicit and always stable** (a filter of the desired position): the
//!   compensator needs no solve for creep.
//! - **The forward link** solves `x(k) = h(k) + sum_i c_i z_i(k)` with the element's own
//!   input `x(k)`, which is explicit because the elements have direct feedthrough `g_i`:
//!   `x(k) = (h(k) + sum_i c_i (1 - g_i) z_i(k-1)) / (1 - sum_i c_i g_i)`. It is stable when
//!   `sum_i |c_i| < 1` (each element's gain is at most 1 on and outside the unit circle, so the
//!   loop gain is below 1: small-gain theorem); the constructor requires it. A step of `h`
//!   then creeps to `1 / (1 - sum_i c_i)` of itself, with the rise spread over the time
//!   constants.
//!
//! [`Creep`] is the forward link, [`CreepInverse`] its exact inverse: fed each other's output
//! sample by sample from the same state they undo each other to rounding.

use crate::buffer::{copied, filled};
use crate::real::followable;
use crate::{Buffer, CoreError, Real};

/// The most creep elements a link may have.
pub const MAX_CREEP_ELEMENTS: usize = 64;

/// The parameters shared by the forward link and its inverse, with the element states.
#[derive(Debug, Clone, PartialEq)]
struct Elements<T: Real, B: Buffer<T>> {
    time_constants: B,
    weights: B,
    gains: B,
    states: B,
    /// The relaxed position: displacements are taken from it.
    origin: T,
    period: T,
}

impl<T: Real, B: Buffer<T>> Elements<T, B> {
    fn new(
        time_constants_s: &[T],
        weights: &[T],
        origin: T,
        period_s: T,
    ) -> Result<Self, CoreError> {
        if weights.len() != time_constants_s.len() {
            return Err(CoreError::LengthMismatch {
                what: "creep weights",
                expected: time_constants_s.len(),
                found: weights.len(),
            });
        }
        if time_constants_s.len() > MAX_CREEP_ELEMENTS {
            return Err(CoreError::TooLarge {
                what: "creep elements",
                found: time_constants_s.len(),
                max: MAX_CREEP_ELEMENTS,
            });
        }
        for (what, values) in [
            ("creep time constants", time_constants_s),
            ("creep weights", weights),
        ] {
            if let Some(index) = values.iter().position(|v| !v.is_finite()) {
                return Err(CoreError::NonFinite {
                    what,
                    index: Some(index),
                });
            }
        }
        if !origin.is_finite() {
            return Err(CoreError::NonFinite {
                what: "creep origin",
                index: None,
            });
        }
        if !(period_s.is_finite() && period_s > T::zero()) {
            return Err(CoreError::NotPositive {
                what: "sample period",
                index: None,
                value: period_s.to_f64(),
            });
        }
        if let Some(index) = time_constants_s.iter().position(|t| *t <= T::zero()) {
            return Err(CoreError::NotPositive {
                what: "creep time constants",
                index: Some(index),
                value: time_constants_s[index].to_f64(),
            });
        }
        let sum = weights.iter().fold(0.0, |s, c| s + (*c).to_f64().abs());
        if sum.is_nan() || sum >= 1.0 {
            return Err(CoreError::CreepUnstable { weight_sum: sum });
        }
        let mut gains: B = filled(T::zero(), weights.len())?;
        for (g, tau) in gains.as_mut().iter_mut().zip(time_constants_s) {
            *g = T::one() - (-(period_s / *tau)).exp();
        }
        Ok(Elements {
            time_constants: copied(time_constants_s)?,
            weights: copied(weights)?,
            gains,
            states: filled(origin, weights.len())?,
            origin,
            period: period_s,
        })
    }

    fn reset(&mut self) {
        let origin = self.origin;
        self.states.as_mut().fill(origin);
    }

    /// `sum_i c_i g_i` and `sum_i c_i (1 - g_i) (z_i(k-1) - origin)`.
    #[inline]
    fn feedthrough_and_memory(&self) -> (T, T) {
        let (c, g, z) = (
            self.weights.as_ref(),
            self.gains.as_ref(),
            self.states.as_ref(),
        );
        let n = c.len().min(g.len()).min(z.len());
        let mut direct = T::zero();
        let mut memory = T::zero();
        for i in 0..n {
            direct = direct + c[i] * g[i];
            memory = memory + c[i] * (T::one() - g[i]) * (z[i] - self.origin);
        }
        (direct, memory)
    }

    /// Feeds `x(k)` to every element; returns `sum_i c_i (z_i(k) - origin)`. A sample that
    /// would leave a state or the sum not finite (an `x` too large for the arithmetic: `x -
    /// z_i` overflows) leaves every state as it was and returns NaN, so that one absurd sample
    /// cannot leave the link's states infinite or NaN for good.
    #[inline]
    fn feed(&mut self, x: T) -> T {
        let origin = self.origin;
        let (c, g) = (self.weights.as_ref(), self.gains.as_ref());
        let n = c.len().min(g.len()).min(self.states.as_ref().len());
        let next = |z: T, g: T| z + g * (x - z);
        let mut sum = T::zero();
        let mut finite = true;
        for ((z, g), c) in self.states.as_ref().iter().zip(g).zip(c) {
            let z = next(*z, *g);
            finite = finite && z.is_finite();
            sum = sum + *c * (z - origin);
        }
        if !(finite && sum.is_finite()) {
            return T::nan();
        }
        for (z, g) in self.states.as_mut().iter_mut().zip(g).take(n) {
            *z = next(*z, *g);
        }
        sum
    }

    fn weight_sum(&self) -> T {
        self.weights.as_ref().iter().fold(T::zero(), |s, c| s + *c)
    }
}

macro_rules! accessors {
    () => {
        /// The time constants `tau_i`, s.
        pub fn time_constants_s(&self) -> &[T] {
            self.elements.time_constants.as_ref()
        }

        /// The weights `c_i` of the inverse parameterisation.
        pub fn weights(&self) -> &[T] {
            self.elements.weights.as_ref()
        }

        /// The relaxed position the displacements are taken from (the link's units).
        pub fn origin(&self) -> T {
            self.elements.origin
        }

        /// The sample period the elements are discretised for, s.
        pub fn period_s(&self) -> T {
            self.elements.period
        }

        /// The element states `z_i` (absolute, in the link's units).
        pub fn states(&self) -> &[T] {
            self.elements.states.as_ref()
        }

        /// Back to relaxed: every element at `origin`.
        pub fn reset(&mut self) {
            self.elements.reset();
        }

        /// Every element at `output`: the state of a link that has rested long at the output
        /// `output` (its input then was `origin + (1 - sum c_i) (output - origin)`). An
        /// `output` not finite or beyond the square root of the largest value changes nothing.
        pub fn settle(&mut self, output: T) {
            if followable(output) {
                self.elements.states.as_mut().fill(output);
            }
        }

        /// The static gain of the forward link, `1 / (1 - sum_i c_i)`: how far a held step
        /// creeps in the end.
        pub fn static_gain(&self) -> T {
            T::one() / (T::one() - self.elements.weight_sum())
        }
    };
}

/// The forward creep link: hysteresis output `h` in, displacement `x` out (see the
/// [module documentation](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct Creep<T: Real, B: Buffer<T>> {
    elements: Elements<T, B>,
}

impl<T: Real, B: Buffer<T>> Creep<T, B> {
    /// A creep link with time constants `time_constants_s` (s, positive), weights `weights`
    /// (`sum |c_i| < 1`), relaxed position `origin`, discretised for `period_s` (s). Starts
    /// relaxed.
    pub fn new(
        time_constants_s: &[T],
        weights: &[T],
        origin: T,
        period_s: T,
    ) -> Result<Self, CoreError> {
        Ok(Creep {
            elements: Elements::new(time_constants_s, weights, origin, period_s)?,
        })
    }

    accessors!();

    /// Its exact inverse, in the same state.
    pub fn inverse(&self) -> CreepInverse<T, B> {
        CreepInverse {
            elements: self.elements.clone(),
        }
    }

    /// One sample: `x(k)` for the hysteresis output `h(k)`. NaN in gives NaN out and leaves the
    /// state as it was; so does an `h` whose arithmetic overflows (an infinite one too).
    #[inline]
    pub fn step(&mut self, h: T) -> T {
        if h.is_nan() {
            return h;
        }
        let origin = self.elements.origin;
        let (direct, memory) = self.elements.feedthrough_and_memory();
        let x = origin + ((h - origin) + memory) / (T::one() - direct);
        if self.elements.feed(x).is_nan() {
            return T::nan();
        }
        x
    }
}

/// The exact inverse of the creep link: desired displacement `x` in, hysteresis output `h`
/// that gives it out, `h = x - sum_i c_i (z_i[x] - origin)`. A filter: explicit, stable,
/// allocation-free.
#[derive(Debug, Clone, PartialEq)]
pub struct CreepInverse<T: Real, B: Buffer<T>> {
    elements: Elements<T, B>,
}

impl<T: Real, B: Buffer<T>> CreepInverse<T, B> {
    /// The inverse of the link with these parameters (see [`Creep::new`]). Starts relaxed.
    pub fn new(
        time_constants_s: &[T],
        weights: &[T],
        origin: T,
        period_s: T,
    ) -> Result<Self, CoreError> {
        Ok(CreepInverse {
            elements: Elements::new(time_constants_s, weights, origin, period_s)?,
        })
    }

    accessors!();

    /// One sample: the hysteresis output `h(k)` for the displacement `x(k)`. NaN in gives NaN
    /// out and leaves the state as it was; so does an `x` not finite or beyond the square root
    /// of the largest value (a state charged that far would take the link's slowest time
    /// constant many times over to recover), and an `x` whose arithmetic overflows.
    #[inline]
    pub fn step(&mut self, x: T) -> T {
        if !followable(x) {
            return T::nan();
        }
        x - self.elements.feed(x)
    }
}
