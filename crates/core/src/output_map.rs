//! The hysteresis link's output map: a static, strictly increasing map `psi` on the output
//! side of the MPIM, `psi(y) = H[x]`, so that the link is `y = psi^-1(H[x])`.
//!
//! With a Prandtl-Ishlinskii superposition `H` this is Kuhnen's modified Prandtl-Ishlinskii
//! operator `Gamma = S[H]` (Kuhnen 2003, *Eur. J. Control* 9 407-418,
//! doi:10.3166/ejc.9.407-418), whose static output nonlinearity `S = psi^-1` makes the loops
//! asymmetric, and whose inverse keeps the same structure: `H^-1[psi(y_d)]`. Identified
//! through the error model `psi(y) - H[x] = 0`, linear in every parameter (Kuhnen's
//! normalisation: `psi`'s linear coefficient is 1). Here `psi` is a polynomial
//! `m_0 + m_1 w + ... + m_K w^K` (`K` at most [`MAX_OUTPUT_MAP_DEGREE`]) of the normalised
//! output `w` on the interval `[lo, hi]` it was identified on, continued linearly beyond it
//! with its end slopes, so that it is strictly increasing on the whole real line.
//!
//! IHC and WIHC (plant models) solve the MPIM's equation for `psi(y_d)` instead of `y_d`; DIHC
//! (an inverse model, whose output is the voltage) maps its MPIM's output back through
//! `psi^-1` ([`MappedCompensator`]).

use crate::{Compensator, CoreError, Diagnostics, OutputLimits, Real};

/// The highest degree of an output map.
pub const MAX_OUTPUT_MAP_DEGREE: usize = 5;

/// Points of the grid on which [`OutputMap::new`] brackets the extremes of the slope.
const SLOPE_GRID: usize = 256;

/// A strictly increasing polynomial map, continued linearly outside `[lo, hi]` (see the
/// [module documentation](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputMap<T: Real> {
    coefficients: [T; MAX_OUTPUT_MAP_DEGREE + 1],
    count: usize,
    lo: T,
    hi: T,
    value_lo: T,
    value_hi: T,
    slope_lo: T,
    slope_hi: T,
}

impl<T: Real> OutputMap<T> {
    /// The map `m_0 + m_1 w + ... + m_K w^K` on `[lo, hi]` from `coefficients = [m_0, ...,
    /// m_K]` (2 to [`MAX_OUTPUT_MAP_DEGREE`]` + 1` of them, finite). Refuses a range that is
    /// not finite with `lo < hi`, and a map whose slope is not positive somewhere on the
    /// range (`CoreError::NotPositive` with the smallest slope found: the slope's extremes
    /// are where its derivative changes sign, bracketed on a grid of 256 intervals and
    /// bisected, or at the ends).
    pub fn new(coefficients: &[T], lo: T, hi: T) -> Result<Self, CoreError> {
        if coefficients.len() < 2 {
            return Err(CoreError::LengthMismatch {
                what: "output map coefficients",
                expected: 2,
                found: coefficients.len(),
            });
        }
        if coefficients.len() > MAX_OUTPUT_MAP_DEGREE + 1 {
            return Err(CoreError::TooLarge {
                what: "output map coefficients",
                found: coefficients.len(),
                max: MAX_OUTPUT_MAP_DEGREE + 1,
            });
        }
        if let Some(index) = coefficients.iter().position(|c| !c.is_finite()) {
            return Err(CoreError::NonFinite {
                what: "output map coefficients",
                index: Some(index),
            });
        }
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(CoreError::InvalidRange {
                lo: lo.to_f64(),
                hi: hi.to_f64(),
            });
        }
        let mut c = [T::zero(); MAX_OUTPUT_MAP_DEGREE + 1];
        c[..coefficients.len()].copy_from_slice(coefficients);
        let mut map = OutputMap {
            coefficients: c,
            count: coefficients.len(),
            lo,
            hi,
            value_lo: T::zero(),
            value_hi: T::zero(),
            slope_lo: T::zero(),
            slope_hi: T::zero(),
        };
        let slope = map.min_slope();
        if slope.is_nan() || slope <= T::zero() {
            return Err(CoreError::NotPositive {
                what: "output map slope",
                index: None,
                value: slope.to_f64(),
            });
        }
        map.value_lo = map.polynomial(lo);
        map.value_hi = map.polynomial(hi);
        map.slope_lo = map.derivative(lo);
        map.slope_hi = map.derivative(hi);
        if map.value_lo.is_nan() || map.value_hi.is_nan() || map.value_lo >= map.value_hi {
            return Err(CoreError::NotPositive {
                what: "output map slope",
                index: None,
                value: (map.value_hi - map.value_lo).to_f64(),
            });
        }
        Ok(map)
    }

    /// The identity on `[0, 1]`.
    pub fn identity() -> Self {
        let mut c = [T::zero(); MAX_OUTPUT_MAP_DEGREE + 1];
        c[1] = T::one();
        OutputMap {
            coefficients: c,
            count: 2,
            lo: T::zero(),
            hi: T::one(),
            value_lo: T::zero(),
            value_hi: T::one(),
            slope_lo: T::one(),
            slope_hi: T::one(),
        }
    }

    /// The coefficients `[m_0, ..., m_K]`.
    pub fn coefficients(&self) -> &[T] {
        &self.coefficients[..self.count]
    }

    /// The range `[lo, hi]` on which the map is the polynomial.
    pub fn range(&self) -> (T, T) {
        (self.lo, self.hi)
    }

    fn polynomial(&self, w: T) -> T {
        self.coefficients[..self.count]
            .iter()
            .rev()
            .fold(T::zero(), |acc, c| acc * w + *c)
    }

    fn derivative(&self, w: T) -> T {
        let mut acc = T::zero();
        for j in (1..self.count).rev() {
            acc = acc * w + T::from_f64(j as f64) * self.coefficients[j];
        }
        acc
    }

    fn second_derivative(&self, w: T) -> T {
        let mut acc = T::zero();
        for j in (2..self.count).rev() {
            acc = acc * w + T::from_f64((j * (j - 1)) as f64) * self.coefficients[j];
        }
        acc
    }

    /// The smallest slope on `[lo, hi]`.
    fn min_slope(&self) -> T {
        let mut best = self.derivative(self.lo).min(self.derivative(self.hi));
        let step = (self.hi - self.lo) / T::from_f64(SLOPE_GRID as f64);
        let mut a = self.lo;
        let mut fa = self.second_derivative(a);
        for i in 1..=SLOPE_GRID {
            let b = if i == SLOPE_GRID {
                self.hi
            } else {
                self.lo + step * T::from_f64(i as f64)
            };
            let fb = self.second_derivative(b);
            if (fa <= T::zero()) != (fb <= T::zero()) {
                let (mut p, mut q, mut fp) = (a, b, fa);
                for _ in 0..60 {
                    let m = (p + q) * T::from_f64(0.5);
                    let fm = self.second_derivative(m);
                    if (fm <= T::zero()) == (fp <= T::zero()) {
                        p = m;
                        fp = fm;
                    } else {
                        q = m;
                    }
                }
                best = best.min(self.derivative((p + q) * T::from_f64(0.5)));
            }
            best = best.min(self.derivative(b));
            a = b;
            fa = fb;
        }
        best
    }

    /// `psi(w)`.
    #[inline]
    pub fn apply(&self, w: T) -> T {
        if w.is_nan() {
            w
        } else if w < self.lo {
            self.value_lo + self.slope_lo * (w - self.lo)
        } else if w > self.hi {
            self.value_hi + self.slope_hi * (w - self.hi)
        } else {
            self.polynomial(w)
        }
    }

    /// `psi^-1(u)`: outside `[psi(lo), psi(hi)]` the linear continuation's inverse, inside the
    /// root of the polynomial by Newton steps kept within a shrinking bracket (bisection when a
    /// step leaves it), to the last few ulps. NaN gives NaN.
    #[inline]
    pub fn invert(&self, u: T) -> T {
        if u.is_nan() {
            return u;
        }
        if u <= self.value_lo {
            return self.lo + (u - self.value_lo) / self.slope_lo;
        }
        if u >= self.value_hi {
            return self.hi + (u - self.value_hi) / self.slope_hi;
        }
        let (mut a, mut b) = (self.lo, self.hi);
        let span = self.value_hi - self.value_lo;
        let mut w = a + (b - a) * (u - self.value_lo) / span;
        let half = T::from_f64(0.5);
        for _ in 0..100 {
            let f = self.polynomial(w) - u;
            if f == T::zero() {
                return w;
            }
            if f < T::zero() {
                a = w;
            } else {
                b = w;
            }
            let d = self.derivative(w);
            let mut next = w - f / d;
            if next.is_nan() || next <= a || next >= b {
                next = (a + b) * half;
            }
            if (next - w).abs() <= T::epsilon() * (T::one() + w.abs()) || b - a <= T::epsilon() {
                return next;
            }
            w = next;
        }
        w
    }
}

/// Where the output map acts around a hysteresis compensator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapSide {
    /// A plant model's map (IHC, WIHC): the desired position `y_d` is mapped to `psi(y_d)`,
    /// which the compensator's MPIM equation is solved for.
    Desired,
    /// An inverse model's map (DIHC, whose MPIM output is the mapped voltage): the
    /// compensator's output `u` is mapped back to the voltage `psi^-1(u)`, within the limits.
    Control,
}

/// A hysteresis compensator with its model's output map (see the [module
/// documentation](self)). Keeps the inner compensator's guarantees: the output within
/// [`Compensator::limits`], never NaN (a NaN desired position is passed to the inner
/// compensator, which handles it).
#[derive(Debug, Clone)]
pub struct MappedCompensator<T: Real, H: Compensator<T>> {
    inner: H,
    map: OutputMap<T>,
    side: MapSide,
    limits: OutputLimits<T>,
}

impl<T: Real, H: Compensator<T>> MappedCompensator<T, H> {
    /// `inner` with `map` on `side`. For [`MapSide::Control`], `inner` must have been built
    /// with the limits mapped, `psi(min)..psi(max)` ([`MappedCompensator::mapped_limits`]);
    /// `limits` are the drive's own.
    pub fn new(inner: H, map: OutputMap<T>, side: MapSide, limits: OutputLimits<T>) -> Self {
        MappedCompensator {
            inner,
            map,
            side,
            limits,
        }
    }

    /// `psi(min)..psi(max)`: the limits of an inner DIHC whose output is mapped back.
    pub fn mapped_limits(
        map: &OutputMap<T>,
        limits: OutputLimits<T>,
    ) -> Result<OutputLimits<T>, CoreError> {
        OutputLimits::new(map.apply(limits.min()), map.apply(limits.max()))
    }

    /// The inner compensator.
    pub fn inner(&self) -> &H {
        &self.inner
    }

    /// The output map.
    pub fn map(&self) -> &OutputMap<T> {
        &self.map
    }
}

impl<T: Real, H: Compensator<T>> Compensator<T> for MappedCompensator<T, H> {
    fn reset(&mut self) {
        self.inner.reset();
    }

    #[inline]
    fn step(&mut self, desired: T) -> T {
        match self.side {
            MapSide::Desired => self.inner.step(self.map.apply(desired)),
            MapSide::Control => {
                let u = self.inner.step(desired);
                let v = self.map.invert(u);
                if v.is_nan() {
                    self.limits.min()
                } else {
                    v.max(self.limits.min()).min(self.limits.max())
                }
            }
        }
    }

    fn limits(&self) -> OutputLimits<T> {
        self.limits
    }

    fn diagnostics(&self) -> Diagnostics {
        self.inner.diagnostics()
    }
}
