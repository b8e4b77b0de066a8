//! The vibration link of the chain `hysteresis -> creep -> vibration` (Croft, Shed & Devasia
//! 2001, doi:10.1115/1.1341197): a linear, discrete-time model of the stage's dynamics with
//! unit static gain, and its stable inverse over a preview of future samples (Leang, Zou &
//! Devasia's inversion-based feedforward, the paper's ref. \[19\]).
//!
//! # The model
//! `y(k) = sum_{j=0}^{m} b_j x(k - d - j) - sum_{i=1}^{n} a_i y(k - i)`, i.e.
//! `Y(z) = z^-d B(z^-1) / A(z^-1) X(z)` with `A(0) = 1`, `b_0 != 0` (a leading zero belongs in
//! the delay `d`), every pole inside the unit circle and `B(1) = A(1)` (unit static gain: the
//! link moves nothing at rest, so the hysteresis and creep links keep their meaning).
//!
//! # The stable inverse with a preview
//! Sampling a continuous-time model of relative degree two or more gives zeros of `B` outside
//! the unit circle (K. J. Astrom, P. Hagander, J. Sternby, "Zeros of sampled systems",
//! Automatica 20 (1984) 31-38, doi:10.1016/0005-1098(84)90062-1), so `A / B` run forward in
//! time is unstable. The inverse is split: with `B(z^-1) = b_0 B_s(z^-1) B_u(z^-1)`, the zeros
//! inside the unit circle (`B_s`) are inverted causally and those outside (`B_u`) anti-causally,
//! by the convergent series `1 / B_u(z^-1) = z^(m_u) sum_{n>=0} q_n z^n` in future samples
//! (the non-causal stable inversion of Devasia, Chen & Paden 1996,
//! doi:10.1109/9.508898, in discrete time). Streaming, the series is cut after the samples the
//! preview holds, its tail added to the last tap so that the static gain stays exactly 1; the
//! relative size of the cut tail is reported ([`VibrationInverse::truncation`]). Offline over a
//! known trajectory the preview is simply long enough for the tail to vanish.
//!
//! Given a preview of `p` samples, [`VibrationInverse::step`] takes the desired output
//! `y_d(k + p)` and returns the input `x(k)`: its output lags its input by `p` samples, and
//! `p` must be at least `d + m_u` (the delay and the unstable zeros). Zeros within `1e-6` of
//! the unit circle have no stable inverse either way and are refused.

use core::marker::PhantomData;

use crate::buffer::{copied, filled};
use crate::real::followable;
use crate::roots::{Complex, MAX_DEGREE, roots};
use crate::{Buffer, CoreError, Real};

/// The highest order of `A` or `B`.
pub const MAX_VIBRATION_ORDER: usize = MAX_DEGREE;
/// The longest pure delay, samples.
pub const MAX_DELAY_SAMPLES: usize = 1000;
/// The longest preview, samples.
pub const MAX_PREVIEW_SAMPLES: usize = 4096;
/// The static gain must be 1 within this (relative).
pub const STATIC_GAIN_TOLERANCE: f64 = 1e-6;
/// Zeros and poles closer than this to the unit circle are refused.
const UNIT_CIRCLE_MARGIN: f64 = 1e-6;
/// The anti-causal series is cut where its remaining tail is this small, relative to its
/// absolute sum ([`VibrationInverse::needed_preview`]).
pub const TAIL_TOLERANCE: f64 = 1e-12;

/// Checks the parameters of a vibration model: `numerator` `b_0..b_m`, `denominator`
/// `a_0..a_n` with `a_0 = 1`; returns them.
fn validate<T: Real>(numerator: &[T], denominator: &[T], delay: usize) -> Result<(), CoreError> {
    if numerator.is_empty() || denominator.is_empty() {
        return Err(CoreError::LengthMismatch {
            what: if numerator.is_empty() {
                "vibration numerator"
            } else {
                "vibration denominator"
            },
            expected: 1,
            found: 0,
        });
    }
    for (what, values, most) in [
        ("vibration numerator", numerator, MAX_VIBRATION_ORDER + 1),
        (
            "vibration denominator",
            denominator,
            MAX_VIBRATION_ORDER + 1,
        ),
    ] {
        if values.len() > most {
            return Err(CoreError::TooLarge {
                what,
                found: values.len(),
                max: most,
            });
        }
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(CoreError::NonFinite {
                what,
                index: Some(index),
            });
        }
    }
    if delay > MAX_DELAY_SAMPLES {
        return Err(CoreError::TooLarge {
            what: "vibration delay",
            found: delay,
            max: MAX_DELAY_SAMPLES,
        });
    }
    if denominator[0].to_f64() != 1.0 {
        return Err(CoreError::VibrationModel {
            reason: "the denominator's first coefficient a_0 must be 1",
            value: denominator[0].to_f64(),
        });
    }
    if numerator[0].to_f64() == 0.0 {
        return Err(CoreError::VibrationModel {
            reason: "the numerator's first coefficient b_0 is 0; move the leading zero into the delay",
            value: 0.0,
        });
    }
    let b1: f64 = numerator.iter().map(|b| (*b).to_f64()).sum();
    let a1: f64 = denominator.iter().map(|a| (*a).to_f64()).sum();
    let gain = b1 / a1;
    if !(gain.is_finite() && (gain - 1.0).abs() <= STATIC_GAIN_TOLERANCE) {
        return Err(CoreError::VibrationModel {
            reason: "the static gain B(1) / A(1) must be 1",
            value: gain,
        });
    }
    let mut poles = [Complex::new(0.0, 0.0); MAX_DEGREE];
    let a: [f64; MAX_DEGREE + 1] = to_f64_array(denominator);
    let n = roots(&a[..denominator.len()], &mut poles).ok_or(CoreError::VibrationModel {
        reason: "the poles could not be computed",
        value: f64::NAN,
    })?;
    let largest = poles[..n].iter().fold(0.0f64, |m, p| m.max(p.abs()));
    if largest.is_nan() || largest >= 1.0 - UNIT_CIRCLE_MARGIN {
        return Err(CoreError::VibrationModel {
            reason: "a pole lies on or outside the unit circle (the model is not stable); its magnitude",
            value: largest,
        });
    }
    Ok(())
}

fn to_f64_array<T: Real>(values: &[T]) -> [f64; MAX_DEGREE + 1] {
    let mut out = [0.0; MAX_DEGREE + 1];
    for (o, v) in out.iter_mut().zip(values) {
        *o = (*v).to_f64();
    }
    out
}

/// The forward vibration link: `x` (the creep link's output) in, displacement `y` out. It
/// starts at rest at its first input (every past input and output equal to it).
#[derive(Debug, Clone, PartialEq)]
pub struct Vibration<T: Real, B: Buffer<T>> {
    numerator: B,
    /// `a_1..a_n`.
    denominator: B,
    delay: usize,
    /// `x(k), x(k-1), ..., x(k - d - m)`.
    inputs: B,
    /// `y(k-1), ..., y(k-n)`.
    outputs: B,
    started: bool,
    _sample: PhantomData<T>,
}

impl<T: Real, B: Buffer<T>> Vibration<T, B> {
    /// A vibration link `z^-delay B(z^-1) / A(z^-1)` (see the [module documentation](self)):
    /// refuses non-finite or too many coefficients, `a_0 != 1`, `b_0 = 0`, a static gain other
    /// than 1 (within [`STATIC_GAIN_TOLERANCE`]) and poles on or outside the unit circle.
    pub fn new(numerator: &[T], denominator: &[T], delay: usize) -> Result<Self, CoreError> {
        validate(numerator, denominator, delay)?;
        Ok(Vibration {
            numerator: copied(numerator)?,
            denominator: copied(&denominator[1..])?,
            delay,
            inputs: filled(T::zero(), delay + numerator.len())?,
            outputs: filled(T::zero(), denominator.len() - 1)?,
            started: false,
            _sample: PhantomData,
        })
    }

    /// `b_0..b_m`.
    pub fn numerator(&self) -> &[T] {
        self.numerator.as_ref()
    }

    /// `a_1..a_n` (`a_0 = 1` is implied).
    pub fn denominator_tail(&self) -> &[T] {
        self.denominator.as_ref()
    }

    /// The pure delay `d`, samples.
    pub fn delay(&self) -> usize {
        self.delay
    }

    /// Forgets the past: the next input is taken as the rest it starts from.
    pub fn reset(&mut self) {
        self.started = false;
    }

    /// At rest at `value`: every past input and output equal to it.
    pub fn settle(&mut self, value: T) {
        self.inputs.as_mut().fill(value);
        self.outputs.as_mut().fill(value);
        self.started = true;
    }

    /// One sample: `y(k)` for `x(k)`. A NaN input is replaced by the previous input.
    #[inline]
    pub fn step(&mut self, x: T) -> T {
        if !self.started {
            self.settle(if x.is_finite() { x } else { T::zero() });
        }
        let inputs = self.inputs.as_mut();
        let x = if x.is_finite() { x } else { inputs[0] };
        push_front(inputs, x);
        let b = self.numerator.as_ref();
        let a = self.denominator.as_ref();
        let mut y = T::zero();
        for (j, bj) in b.iter().enumerate() {
            y = y + *bj * inputs[self.delay + j];
        }
        let outputs = self.outputs.as_mut();
        for (ai, yi) in a.iter().zip(outputs.iter()) {
            y = y - *ai * *yi;
        }
        push_front(outputs, y);
        y
    }
}

/// The stable inverse of a [`Vibration`] link with a preview of `p` samples (see the
/// [module documentation](self)): `y_d(k + p)` in, `x(k)` out.
#[derive(Debug, Clone, PartialEq)]
pub struct VibrationInverse<T: Real, B: Buffer<T>> {
    /// The model's `a_0..a_n` (numerator of the causal part).
    a: B,
    /// `B_s`'s `s_1..s_ms` (monic; the causal part's poles).
    s: B,
    b0: T,
    /// Anti-causal taps on `y_d(k + d + m_u + n)`, `n = 0..=L`, tail folded into the last.
    taps: B,
    /// `d + m_u`: where the taps start in the preview.
    lead: usize,
    /// The last `p + 1` desired samples, a ring whose oldest (`y_d(k)`) is at `head`.
    ring: B,
    head: usize,
    /// `u(k), ..., u(k - n)`.
    u: B,
    /// `x(k-1), ..., x(k - ms)`.
    x: B,
    started: bool,
    truncation: f64,
    needed: usize,
}

impl<T: Real, B: Buffer<T>> VibrationInverse<T, B> {
    /// The inverse of `z^-delay B(z^-1) / A(z^-1)` with a preview of `preview` samples (at
    /// least [`VibrationInverse::minimum_preview`], at most [`MAX_PREVIEW_SAMPLES`]).
    pub fn new(
        numerator: &[T],
        denominator: &[T],
        delay: usize,
        preview: usize,
    ) -> Result<Self, CoreError> {
        validate(numerator, denominator, delay)?;
        let plan = Plan::new(numerator, delay)?;
        let minimum = delay + plan.unstable;
        if preview < minimum || preview > MAX_PREVIEW_SAMPLES {
            return Err(CoreError::Preview {
                preview,
                minimum,
                maximum: MAX_PREVIEW_SAMPLES,
            });
        }
        let needed_taps = plan.needed_taps;
        let taps_len = (preview - minimum + 1).min(needed_taps);
        let mut taps: B = filled(T::zero(), taps_len)?;
        let (mut kept, mut kept_abs, mut last_value) = (0.0, 0.0, 0.0);
        plan.series(taps_len, |n, q| {
            taps.as_mut()[n] = T::from_f64(q);
            kept += q;
            kept_abs += q.abs();
            last_value = q;
        });
        // The cut tail goes into the last tap: the static gain stays exactly 1 / Q(1).
        taps.as_mut()[taps_len - 1] = T::from_f64(last_value + (plan.series_sum - kept));
        let total_abs = plan.series_abs;
        let tail_abs = (total_abs - kept_abs).max(0.0);
        let mut s: B = filled(T::zero(), plan.stable)?;
        for (o, v) in s
            .as_mut()
            .iter_mut()
            .zip(&plan.stable_poly[1..=plan.stable])
        {
            *o = T::from_f64(*v);
        }
        Ok(VibrationInverse {
            a: copied(denominator)?,
            s,
            b0: numerator[0],
            taps,
            lead: minimum,
            ring: filled(T::zero(), preview + 1)?,
            head: 0,
            u: filled(T::zero(), denominator.len())?,
            x: filled(T::zero(), plan.stable)?,
            started: false,
            truncation: if total_abs > 0.0 {
                tail_abs / total_abs
            } else {
                0.0
            },
            needed: minimum + needed_taps - 1,
        })
    }

    /// The shortest preview that can invert `numerator` with `delay`: the delay plus the number
    /// of zeros outside the unit circle (the anti-causal series then has one tap).
    pub fn minimum_preview(numerator: &[T], delay: usize) -> Result<usize, CoreError> {
        Ok(delay + Plan::new(numerator, delay)?.unstable)
    }

    /// The preview at which the anti-causal series' cut tail falls below [`TAIL_TOLERANCE`]
    /// of its absolute sum, at most [`MAX_PREVIEW_SAMPLES`]: offline inversion uses it. A zero
    /// just outside the unit circle makes the series converge too slowly for that; the inverse
    /// at the longest preview then folds the cut tail into its last tap (the static gain kept)
    /// and [`VibrationInverse::truncation`] says how much was cut.
    pub fn needed_preview(numerator: &[T], delay: usize) -> Result<usize, CoreError> {
        let plan = Plan::new(numerator, delay)?;
        Ok((delay + plan.unstable + plan.needed_taps - 1).min(MAX_PREVIEW_SAMPLES))
    }

    /// The preview `p`, samples: the output lags the input by `p`.
    pub fn preview(&self) -> usize {
        self.ring.as_ref().len() - 1
    }

    /// The cut tail of the anti-causal series, relative to its absolute sum (0 when nothing
    /// was cut; below [`TAIL_TOLERANCE`] at [`VibrationInverse::needed_preview`] unless that
    /// is [`MAX_PREVIEW_SAMPLES`]).
    pub fn truncation(&self) -> f64 {
        self.truncation
    }

    /// The preview this inverse would need for a negligible cut: what
    /// [`VibrationInverse::needed_preview`] gives, before it is capped at
    /// [`MAX_PREVIEW_SAMPLES`].
    pub fn recommended_preview(&self) -> usize {
        self.needed
    }

    /// Forgets the past: the next desired sample is taken as the rest the trajectory starts
    /// from (every earlier desired sample equal to it).
    pub fn reset(&mut self) {
        self.started = false;
    }

    fn settle(&mut self, value: T) {
        self.ring.as_mut().fill(value);
        self.head = 0;
        let dc: T = self.taps.as_ref().iter().fold(T::zero(), |s, q| s + *q);
        self.u.as_mut().fill(value * dc);
        self.x.as_mut().fill(value);
        self.started = true;
    }

    /// One sample: takes `y_d(k + p)` and returns `x(k)`. A desired sample not finite, or
    /// beyond the square root of the largest value (which the filter's states could not
    /// follow without overflowing), is replaced by the previous one (callers count it). A
    /// sample whose arithmetic overflows all the same gives NaN and leaves the state as it
    /// was, so that the filter's memory of its past outputs never holds an infinity or NaN.
    #[inline]
    pub fn step(&mut self, desired: T) -> T {
        if !self.started {
            self.settle(if followable(desired) {
                desired
            } else {
                T::zero()
            });
        }
        // Every read and write below goes through `get`/`get_mut` or an iterator: the head and
        // the taps' start are always within the ring (`settle` and the wrap below keep them
        // so), and a microcontroller's per-sample path then has no bounds check that could
        // panic (`examples/thumbv7em` checks it).
        let len = self.ring.as_ref().len();
        let newest = if self.head == 0 {
            len.wrapping_sub(1)
        } else {
            self.head - 1
        };
        let desired = if followable(desired) {
            desired
        } else {
            self.ring.as_ref().get(newest).copied().unwrap_or(T::zero())
        };
        // The oldest slot becomes the newest sample (restored below if the sample overflows).
        let head = self.head;
        let oldest = self.ring.as_ref().get(head).copied();
        if let Some(slot) = self.ring.as_mut().get_mut(self.head) {
            *slot = desired;
        }
        self.head = if self.head + 1 >= len {
            0
        } else {
            self.head + 1
        };
        // u(k) = sum_n q_n y_d(k + lead + n), the oldest being y_d(k).
        let mut u = T::zero();
        let mut index = self.head + self.lead;
        if index >= len {
            index -= len;
        }
        let ring = self.ring.as_ref();
        for q in self.taps.as_ref() {
            u = u + *q * ring.get(index).copied().unwrap_or(T::zero());
            index += 1;
            if index == len {
                index = 0;
            }
        }
        // b0 B_s x = A u, with u(k) in front of the past ones (pushed only once x is known
        // to be finite).
        let mut acc = T::zero();
        let mut a = self.a.as_ref().iter();
        if let Some(a0) = a.next() {
            acc = acc + *a0 * u;
        }
        for (a, u) in a.zip(self.u.as_ref()) {
            acc = acc + *a * *u;
        }
        let mut feedback = T::zero();
        for (s, x) in self.s.as_ref().iter().zip(self.x.as_ref()) {
            feedback = feedback + *s * *x;
        }
        let x = acc / self.b0 - feedback;
        if !x.is_finite() {
            if let (Some(slot), Some(oldest)) = (self.ring.as_mut().get_mut(head), oldest) {
                *slot = oldest;
            }
            self.head = head;
            return T::nan();
        }
        push_front(self.u.as_mut(), u);
        push_front(self.x.as_mut(), x);
        x
    }

    /// Offline inversion of a whole known trajectory: `x[k]` for `desired[k]`, aligned (no
    /// lag), the trajectory held at its last value after its end and taken at rest at its first
    /// before its start. Refuses slices of different lengths. Resets first.
    pub fn process_aligned(&mut self, desired: &[T], x: &mut [T]) -> Result<(), CoreError> {
        if x.len() != desired.len() {
            return Err(CoreError::LengthMismatch {
                what: "vibration inverse output",
                expected: desired.len(),
                found: x.len(),
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
            let out = self.step(*y);
            if k >= p {
                x[k - p] = out;
            }
        }
        Ok(())
    }
}

/// What the inverse needs from the numerator: the stable factor and the anti-causal series.
struct Plan {
    /// Number of zeros inside the unit circle, and `B_s` (monic, `1, s_1, ..`).
    stable: usize,
    stable_poly: [f64; MAX_DEGREE + 1],
    /// Number of zeros outside.
    unstable: usize,
    /// `Q(z) = prod (z - rho)` over the zeros outside, ascending powers of `z`.
    q_asc: [f64; MAX_DEGREE + 1],
    /// `1 / Q(1)`, the series' full sum (its static gain).
    series_sum: f64,
    /// The series' absolute sum up to [`MAX_PREVIEW_SAMPLES`] terms.
    series_abs: f64,
    /// Taps for a tail below [`TAIL_TOLERANCE`].
    needed_taps: usize,
}

impl Plan {
    fn new<T: Real>(numerator: &[T], _delay: usize) -> Result<Plan, CoreError> {
        if numerator.is_empty() || numerator.len() > MAX_DEGREE + 1 || numerator[0].to_f64() == 0.0
        {
            return Err(CoreError::VibrationModel {
                reason: "the numerator must have 1 to 17 coefficients with b_0 != 0",
                value: numerator.len() as f64,
            });
        }
        let b = to_f64_array(numerator);
        let mut zeros = [Complex::new(0.0, 0.0); MAX_DEGREE];
        let m = roots(&b[..numerator.len()], &mut zeros).ok_or(CoreError::VibrationModel {
            reason: "the zeros could not be computed",
            value: f64::NAN,
        })?;
        let mut stable = [Complex::new(0.0, 0.0); MAX_DEGREE];
        let mut unstable = [Complex::new(0.0, 0.0); MAX_DEGREE];
        let (mut ns, mut nu) = (0, 0);
        for z in &zeros[..m] {
            let r = z.abs();
            if (r - 1.0).abs() <= UNIT_CIRCLE_MARGIN {
                return Err(CoreError::VibrationModel {
                    reason: "a zero lies on the unit circle (no stable inverse); its magnitude",
                    value: r,
                });
            }
            if r < 1.0 {
                stable[ns] = *z;
                ns += 1;
            } else {
                unstable[nu] = *z;
                nu += 1;
            }
        }
        // B_s(z^-1) = prod (1 - rho z^-1): coefficients of z^0, z^-1, ...
        let stable_poly = real_product(&stable[..ns]);
        // Q(z) = prod (z - rho) = z^mu B_u(z^-1): ascending coefficients Q_i = beta_{mu - i}.
        let beta = real_product(&unstable[..nu]);
        let mut q_asc = [0.0; MAX_DEGREE + 1];
        for i in 0..=nu {
            q_asc[i] = beta[nu - i];
        }
        let mut plan = Plan {
            stable: ns,
            stable_poly,
            unstable: nu,
            q_asc,
            series_sum: 1.0 / q_asc[..=nu].iter().sum::<f64>(),
            series_abs: 0.0,
            needed_taps: MAX_PREVIEW_SAMPLES + 1,
        };
        let mut total = 0.0;
        plan.series(MAX_PREVIEW_SAMPLES + 1, |_, q| total += q.abs());
        plan.series_abs = total;
        let mut tail = total;
        let mut needed = None;
        plan.series(MAX_PREVIEW_SAMPLES + 1, |n, q| {
            tail -= q.abs();
            if needed.is_none() && tail <= TAIL_TOLERANCE * total {
                needed = Some(n + 1);
            }
        });
        plan.needed_taps = needed.unwrap_or(MAX_PREVIEW_SAMPLES + 1);
        Ok(plan)
    }

    /// Calls `f(n, q_n)` for the first `count` terms of `1 / Q(z) = sum q_n z^n`
    /// (`q_0 = 1 / Q_0`, `q_n = -sum_{i=1}^{min(n, mu)} Q_i q_{n-i} / Q_0`), keeping only the
    /// last `mu` terms.
    fn series(&self, count: usize, mut f: impl FnMut(usize, f64)) {
        let nu = self.unstable;
        let q = &self.q_asc;
        // recent[i] = q_{n-1-i}.
        let mut recent = [0.0; MAX_DEGREE + 1];
        for n in 0..count {
            let value = if n == 0 {
                1.0 / q[0]
            } else {
                let mut acc = 0.0;
                for i in 1..=nu.min(n) {
                    acc += q[i] * recent[i - 1];
                }
                -acc / q[0]
            };
            f(n, value);
            push_front(&mut recent[..nu], value);
        }
    }
}

/// `prod (1 - rho_k w)` as real coefficients of `w^0, w^1, ...` (conjugate pairs cancel the
/// imaginary parts).
fn real_product(zeros: &[Complex]) -> [f64; MAX_DEGREE + 1] {
    let mut c = [Complex::new(0.0, 0.0); MAX_DEGREE + 1];
    c[0] = Complex::new(1.0, 0.0);
    for (k, rho) in zeros.iter().enumerate() {
        for i in (1..=k + 1).rev() {
            c[i] = c[i].sub(rho.mul(c[i - 1]));
        }
    }
    let mut out = [0.0; MAX_DEGREE + 1];
    for (o, z) in out.iter_mut().zip(&c) {
        *o = z.re;
    }
    out
}

/// Moves every value of `values` one place towards the end (the last one drops out) and puts
/// `value` first; nothing for an empty slice. Moves only, without a path to a panic.
#[inline]
fn push_front<T: Copy>(values: &mut [T], value: T) {
    let mut carry = value;
    for v in values.iter_mut() {
        carry = core::mem::replace(v, carry);
    }
}
