//! The input function `g(x)` of the MPIM, eqs. (3)-(4): the paper's odd cubic `a1 x^3 + a2 x`,
//! or a higher-degree polynomial `g(x) = c_1 x + c_2 x^2 + ... + c_D x^D` (`c_1 = a2`,
//! `c_3 = a1`), up to degree [`MAX_INPUT_DEGREE`].
//!
//! The paper's cubic keeps its own evaluation path (`(a1 x^2 + a2) x`); a higher degree is
//! evaluated by Horner's rule. Both live in a fixed array, so a model needs no allocator
//! whatever its degree.

use crate::{CoreError, Real};

/// The highest degree of the input polynomial `g(x)` a model may have.
///
/// Nine is well beyond what piezo records support (a degree-7 polynomial fits the DBO
/// micromanipulator record slightly better than the paper's cubic, degree 9 no better), and
/// keeps the fixed storage small: nine coefficients per model and compensator.
pub const MAX_INPUT_DEGREE: usize = 9;

/// The polynomial input function `g(x) = sum_{j=1}^{D} c_j x^j` of the MPIM (eq. (3) with the
/// paper's `g(x) = a1 x^3 + a2 x` as the case `D = 3`, `c_2 = 0`). It has no constant term:
/// `g(0) = 0`, so that the model outputs 0 from its reset state at input 0 (eq. (1)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputPolynomial<T> {
    /// `coefficients[j - 1] = c_j`; entries beyond the degree are 0.
    coefficients: [T; MAX_INPUT_DEGREE],
    /// `D`, the number of coefficients given (at least 3 for the paper's form).
    degree: u8,
    /// `D <= 3` and `c_2 = 0`: the paper's odd cubic, evaluated as `(a1 x^2 + a2) x`.
    odd_cubic: bool,
}

impl<T: Real> InputPolynomial<T> {
    /// The paper's input function `g(x) = a1 x^3 + a2 x` (eq. (3)). Both must be finite.
    pub fn cubic(a1: T, a2: T) -> Result<Self, CoreError> {
        for (what, value) in [("a1", a1), ("a2", a2)] {
            if !value.is_finite() {
                return Err(CoreError::NonFinite { what, index: None });
            }
        }
        let mut coefficients = [T::zero(); MAX_INPUT_DEGREE];
        coefficients[0] = a2;
        coefficients[2] = a1;
        Ok(InputPolynomial {
            coefficients,
            degree: 3,
            odd_cubic: true,
        })
    }

    /// `g(x) = c_1 x + c_2 x^2 + ... + c_D x^D` from `[c_1, c_2, ..., c_D]`, `1 <= D <=`
    /// [`MAX_INPUT_DEGREE`], every coefficient finite. `[a2, 0, a1]` is the paper's cubic (and
    /// takes its evaluation path).
    pub fn new(coefficients: &[T]) -> Result<Self, CoreError> {
        if coefficients.is_empty() || coefficients.len() > MAX_INPUT_DEGREE {
            return Err(CoreError::InputDegree {
                degree: coefficients.len(),
                max: MAX_INPUT_DEGREE,
            });
        }
        if let Some(index) = coefficients.iter().position(|c| !c.is_finite()) {
            return Err(CoreError::NonFinite {
                what: "input polynomial coefficients",
                index: Some(index),
            });
        }
        let mut stored = [T::zero(); MAX_INPUT_DEGREE];
        stored[..coefficients.len()].copy_from_slice(coefficients);
        let degree = coefficients.len();
        Ok(InputPolynomial {
            coefficients: stored,
            // At most MAX_INPUT_DEGREE (9): fits.
            degree: degree as u8,
            odd_cubic: degree <= 3 && stored[1] == T::zero(),
        })
    }

    /// `[c_1, ..., c_D]`: the coefficients of `x, x^2, ..., x^D` (`D = 3` for the paper's cubic,
    /// `[a2, 0, a1]`).
    pub fn coefficients(&self) -> &[T] {
        let d = usize::from(self.degree).min(MAX_INPUT_DEGREE);
        &self.coefficients[..d]
    }

    /// `D`, the number of coefficients (the degree unless the leading ones are 0).
    pub fn degree(&self) -> usize {
        usize::from(self.degree)
    }

    /// `true` for the paper's odd cubic `a1 x^3 + a2 x` (no `x^2` term, degree at most 3).
    #[inline(always)]
    pub fn is_odd_cubic(&self) -> bool {
        self.odd_cubic
    }

    /// `a2 = c_1`, the linear coefficient.
    #[inline(always)]
    pub fn a2(&self) -> T {
        self.coefficients[0]
    }

    /// `a1 = c_3`, the cubic coefficient (0 below degree 3).
    #[inline(always)]
    pub fn a1(&self) -> T {
        self.coefficients[2]
    }

    /// `g(x)`.
    #[inline(always)]
    pub fn value(&self, x: T) -> T {
        if self.odd_cubic {
            (self.a1() * x * x + self.a2()) * x
        } else {
            self.general_value(x)
        }
    }

    /// `g(x)` by Horner's rule, out of line so that the cubic's path stays as short as it was.
    #[inline(never)]
    fn general_value(&self, x: T) -> T {
        (self.higher_horner(x) * x + self.a2()) * x
    }

    /// `g'(x)`.
    #[inline]
    pub fn slope(&self, x: T) -> T {
        if self.odd_cubic {
            self.a2() + T::from_f64(3.0) * self.a1() * x * x
        } else {
            self.a2() + self.remainder_slope(x)
        }
    }

    /// `h(x) = g(x) - a2 x`, the part of `g` beyond the linear term (`a1 x^3` for the paper's
    /// cubic): what IHC moves out of the PI part (eq. (5)) and WIHC into `H` (eq. (9)).
    #[inline(always)]
    pub fn remainder(&self, x: T) -> T {
        if self.odd_cubic {
            self.a1() * x * x * x
        } else {
            self.higher_horner(x) * x * x
        }
    }

    /// `h'(x) = g'(x) - a2`.
    #[inline]
    pub fn remainder_slope(&self, x: T) -> T {
        if self.odd_cubic {
            return T::from_f64(3.0) * self.a1() * x * x;
        }
        // sum_{j >= 2} j c_j x^(j - 1), by Horner's rule from the top (iterators: the per-sample
        // path holds no bounds check).
        let p = self
            .coefficients()
            .iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(T::zero(), |p, (i, &c)| {
                p * x + T::from_f64((i + 1) as f64) * c
            });
        p * x
    }

    /// `h''(x) = g''(x)`: `sum_{j >= 2} j (j - 1) c_j x^(j - 2)` by Horner's rule from the
    /// top (`6 a1 x` for the paper's cubic), for the root finder's Halley steps.
    #[inline]
    pub(crate) fn remainder_curvature(&self, x: T) -> T {
        if self.odd_cubic {
            return T::from_f64(6.0) * self.a1() * x;
        }
        self.coefficients()
            .iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(T::zero(), |p, (i, &c)| {
                p * x + T::from_f64(((i + 1) * i) as f64) * c
            })
    }

    /// `sum_{j >= 2} c_j x^(j - 2)` (Horner), so that `h(x) = x^2` times it.
    #[inline(always)]
    fn higher_horner(&self, x: T) -> T {
        self.coefficients()
            .iter()
            .skip(1)
            .rev()
            .fold(T::zero(), |p, &c| p * x + c)
    }

    /// `sum_{j >= 2} |c_j x^j|`: the size of the terms of `h(x)`, for rounding allowances.
    #[inline]
    pub(crate) fn remainder_size(&self, x: T) -> T {
        let mut power = x * x;
        let mut size = T::zero();
        for &c in self.coefficients().iter().skip(1) {
            size = size + (c * power).abs();
            power = power * x;
        }
        size
    }

    /// Calls `visit(x)` for every input strictly inside `(lo, hi)` where `g'` may have a local
    /// extreme: the real roots of `g''`. For the paper's cubic `g'' = 6 a1 x`, so the only one is
    /// 0 (visited whenever it lies inside, whatever `a1`). For a higher degree they are found by
    /// isolating the roots of `g''` between those of its own derivatives (each derivative is
    /// monotone between consecutive roots of the next one) and bisecting each sign change to
    /// full precision. Over an interval, `g'` is therefore extreme at `lo`, at `hi` or at one
    /// of these points.
    pub fn slope_critical_points(&self, lo: T, hi: T, mut visit: impl FnMut(T)) {
        if lo >= hi || lo.is_nan() || hi.is_nan() {
            return;
        }
        if self.odd_cubic {
            if lo < T::zero() && T::zero() < hi {
                visit(T::zero());
            }
            return;
        }
        // g''(x) = sum_{j >= 2} j (j - 1) c_j x^(j - 2): coefficients in increasing powers.
        let d = self.degree();
        let mut second = [T::zero(); MAX_INPUT_DEGREE];
        let mut len = 0;
        for j in 2..=d {
            second[j - 2] = T::from_f64((j * (j - 1)) as f64) * self.coefficients[j - 1];
            len = j - 1;
        }
        let mut roots = [T::zero(); MAX_INPUT_DEGREE];
        let count = roots_in(&second[..len], lo, hi, &mut roots);
        for &x in &roots[..count] {
            visit(x);
        }
    }
}

/// `p(x)` for coefficients in increasing powers.
fn evaluate<T: Real>(p: &[T], x: T) -> T {
    p.iter().rev().fold(T::zero(), |acc, &c| acc * x + c)
}

/// The real roots of `p` (coefficients in increasing powers, at most [`MAX_INPUT_DEGREE`] of
/// them) strictly inside `(lo, hi)`, increasing, written to `out`; returns how many. Roots of
/// even multiplicity (no sign change) may be missed: they are not extremes of `p`'s integral.
fn roots_in<T: Real>(p: &[T], lo: T, hi: T, out: &mut [T; MAX_INPUT_DEGREE]) -> usize {
    // Drop leading zero coefficients: the degree decides the recursion.
    let mut len = p.len();
    while len > 0 && p[len - 1] == T::zero() {
        len -= 1;
    }
    let p = &p[..len];
    if len <= 1 {
        // A constant: no isolated root.
        return 0;
    }
    // The roots of p' split (lo, hi) into pieces where p is monotone.
    let mut derivative = [T::zero(); MAX_INPUT_DEGREE];
    for j in 1..len {
        derivative[j - 1] = T::from_f64(j as f64) * p[j];
    }
    let mut turns = [T::zero(); MAX_INPUT_DEGREE];
    let turn_count = roots_in(&derivative[..len - 1], lo, hi, &mut turns);
    let mut count = 0;
    let mut a = lo;
    let mut f_a = evaluate(p, a);
    let ends = turns[..turn_count].iter().map(|&t| (t, true));
    for (b, inside) in ends.chain(core::iter::once((hi, false))) {
        let f_b = evaluate(p, b);
        let changes = (f_a < T::zero() && f_b > T::zero()) || (f_a > T::zero() && f_b < T::zero());
        if changes && count < MAX_INPUT_DEGREE {
            out[count] = bisect(p, a, b, f_a);
            count += 1;
        } else if f_b == T::zero() && inside && count < MAX_INPUT_DEGREE {
            // Exactly zero at a turning point (inside the interval).
            out[count] = b;
            count += 1;
        }
        a = b;
        f_a = f_b;
    }
    count
}

/// The root of the monotone `p` between `a` and `b` (sign change, `f_a = p(a)`), to full
/// precision.
fn bisect<T: Real>(p: &[T], mut a: T, mut b: T, f_a: T) -> T {
    let half = T::from_f64(0.5);
    let rising = f_a < T::zero();
    for _ in 0..200 {
        let mid = half * (a + b);
        if !(mid > a && mid < b) {
            break;
        }
        let f = evaluate(p, mid);
        if f == T::zero() {
            return mid;
        }
        if (f < T::zero()) == rising {
            a = mid;
        } else {
            b = mid;
        }
    }
    half * (a + b)
}
