//! Roots of small real polynomials, for the vibration link's poles and zeros (set-up only,
//! never per sample). Computed in `f64` whatever the sample type.
//!
//! The Aberth-Ehrlich iteration (O. Aberth, "Iteration methods for finding all zeros of a
//! polynomial simultaneously", Math. Comp. 27 (1973) 339-344, doi:10.1090/S0025-5718-1973-0329236-7)
//! refines all roots at once from points on a circle of the Cauchy bound's radius; each root
//! is then polished by Newton's method on the polynomial itself.

use num_traits::Float;

/// The most roots (the highest degree) [`roots`] computes.
pub(crate) const MAX_DEGREE: usize = 16;

/// A complex number, only as much of one as the root finder needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Complex {
    pub re: f64,
    pub im: f64,
}

impl Complex {
    pub const fn new(re: f64, im: f64) -> Self {
        Complex { re, im }
    }
    pub fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    pub fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    pub fn mul(self, o: Complex) -> Complex {
        Complex::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    pub fn div(self, o: Complex) -> Complex {
        let d = o.re * o.re + o.im * o.im;
        Complex::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    pub fn abs(self) -> f64 {
        Float::hypot(self.re, self.im)
    }
}

/// Value and derivative of `c[0] z^d + c[1] z^(d-1) + ... + c[d]` at `z` (Horner).
fn eval(c: &[f64], z: Complex) -> (Complex, Complex) {
    let mut p = Complex::new(0.0, 0.0);
    let mut dp = Complex::new(0.0, 0.0);
    for &a in c {
        dp = dp.mul(z).add(p);
        p = p.mul(z).add(Complex::new(a, 0.0));
    }
    (p, dp)
}

/// The roots of `c[0] z^d + ... + c[d]` (`c[0] != 0`, `d = c.len() - 1 <= MAX_DEGREE`) into
/// `out[..d]`; returns `d`, or `None` when the iteration does not settle (or the input is
/// unusable).
pub(crate) fn roots(c: &[f64], out: &mut [Complex; MAX_DEGREE]) -> Option<usize> {
    let d = c.len().checked_sub(1)?;
    if d > MAX_DEGREE || c[0] == 0.0 || c.iter().any(|v| !v.is_finite()) {
        return None;
    }
    if d == 0 {
        return Some(0);
    }
    // Monic, and the Cauchy bound 1 + max |c_i / c_0| for the starting circle.
    let mut monic = [0.0f64; MAX_DEGREE + 1];
    for (m, &a) in monic.iter_mut().zip(c) {
        *m = a / c[0];
    }
    let monic = &monic[..=d];
    let radius = 1.0 + monic[1..].iter().fold(0.0f64, |m, a| m.max(a.abs()));
    for (k, z) in out.iter_mut().enumerate().take(d) {
        // An angle offset keeps the start off the real axis (and off symmetric traps).
        let angle = 2.0 * core::f64::consts::PI * k as f64 / d as f64 + 0.4;
        *z = Complex::new(radius * Float::cos(angle), radius * Float::sin(angle));
    }
    for _ in 0..500 {
        let mut largest_step = 0.0f64;
        for i in 0..d {
            let z = out[i];
            let (p, dp) = eval(monic, z);
            if p.abs() == 0.0 {
                continue;
            }
            let ratio = p.div(dp);
            let mut sum = Complex::new(0.0, 0.0);
            for (j, w) in out.iter().enumerate().take(d) {
                if j != i {
                    sum = sum.add(Complex::new(1.0, 0.0).div(z.sub(*w)));
                }
            }
            let denominator = Complex::new(1.0, 0.0).sub(ratio.mul(sum));
            let step = ratio.div(denominator);
            if step.re.is_finite() && step.im.is_finite() {
                out[i] = z.sub(step);
                largest_step = largest_step.max(step.abs() / (1.0 + z.abs()));
            }
        }
        if largest_step < 1e-15 {
            break;
        }
    }
    // Newton polish on the polynomial, then a check that each root is one.
    let scale = monic.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    for z in out.iter_mut().take(d) {
        for _ in 0..3 {
            let (p, dp) = eval(monic, *z);
            if dp.abs() > 0.0 {
                let step = p.div(dp);
                if step.re.is_finite() && step.im.is_finite() {
                    *z = z.sub(step);
                }
            }
        }
        let (p, _) = eval(monic, *z);
        let size = (0..=d).fold(0.0f64, |m, k| {
            m.max(monic[k].abs() * Float::powi(z.abs(), (d - k) as i32))
        });
        if p.abs().is_nan() || p.abs() > 1e-7 * size.max(scale) {
            return None;
        }
    }
    Some(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Multiplies out `prod (z - r_k)` for real and conjugate-pair roots.
    fn from_roots(real: &[f64], pairs: &[(f64, f64)]) -> alloc_free::Poly {
        let mut p = alloc_free::Poly::one();
        for &r in real {
            p = p.times(&[1.0, -r]);
        }
        for &(re, im) in pairs {
            p = p.times(&[1.0, -2.0 * re, re * re + im * im]);
        }
        p
    }

    mod alloc_free {
        pub struct Poly {
            pub c: [f64; 17],
            pub len: usize,
        }
        impl Poly {
            pub fn one() -> Poly {
                let mut c = [0.0; 17];
                c[0] = 1.0;
                Poly { c, len: 1 }
            }
            pub fn times(&self, q: &[f64]) -> Poly {
                let mut c = [0.0; 17];
                for i in 0..self.len {
                    for (j, b) in q.iter().enumerate() {
                        c[i + j] += self.c[i] * b;
                    }
                }
                Poly {
                    c,
                    len: self.len + q.len() - 1,
                }
            }
        }
    }

    #[test]
    fn roots_of_products_are_found() {
        type Case<'a> = (&'a [f64], &'a [(f64, f64)]);
        let cases: [Case; 4] = [
            (&[-3.7, -0.27], &[(0.97, 0.2)]),
            (&[0.5], &[]),
            (&[2.0, -2.0, 0.1, -0.3], &[(0.1, 0.9), (-0.5, 0.5)]),
            (&[], &[(0.999, 0.03), (0.8, 0.5)]),
        ];
        for (real, pairs) in cases {
            let p = from_roots(real, pairs);
            let mut out = [Complex::new(0.0, 0.0); MAX_DEGREE];
            let d = roots(&p.c[..p.len], &mut out).unwrap();
            assert_eq!(d, real.len() + 2 * pairs.len());
            let mut expected: [Complex; MAX_DEGREE] = [Complex::new(0.0, 0.0); MAX_DEGREE];
            let mut n = 0;
            for &r in real {
                expected[n] = Complex::new(r, 0.0);
                n += 1;
            }
            for &(re, im) in pairs {
                expected[n] = Complex::new(re, im);
                expected[n + 1] = Complex::new(re, -im);
                n += 2;
            }
            for e in &expected[..n] {
                let nearest = out[..d]
                    .iter()
                    .map(|z| z.sub(*e).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest < 1e-9, "{e:?} not found in {:?}", &out[..d]);
            }
        }
    }
}
