//! A chain like the study's, for benchmarks and examples (the criterion benches and
//! `hystcomp bench` time the same links): eleven creep elements (10 ms .. 1000 s, two per
//! decade, weights 0.007 each) and an 800 Hz resonance (damping 0.05) sampled at 10 kHz with a
//! delay of one sample and a zero outside the unit circle (as sampling an amplifier and a
//! flexure gives), so that the vibration inverse runs its anti-causal taps.

use alloc::vec::Vec;

use crate::Real;

/// The links' parameters, in the forms the constructors take.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceLinks<T> {
    /// Creep time constants, s.
    pub time_constants_s: Vec<T>,
    /// Creep weights.
    pub weights: Vec<T>,
    /// Vibration numerator `b_0..b_m` (unit static gain).
    pub numerator: Vec<T>,
    /// Vibration denominator `1, a_1, a_2`.
    pub denominator: Vec<T>,
    /// Vibration delay, samples.
    pub delay: usize,
    /// The sample period, s.
    pub period_s: T,
}

/// The reference links (see the [module documentation](self)).
pub fn chain_links<T: Real>() -> ReferenceLinks<T> {
    let (w, zeta, t) = (2.0 * core::f64::consts::PI * 800.0, 0.05f64, 1e-4f64);
    let r = num_traits::Float::exp(-zeta * w * t);
    let wd = w * num_traits::Float::sqrt(1.0 - zeta * zeta);
    let a = [1.0, -2.0 * r * num_traits::Float::cos(wd * t), r * r];
    // (1 + 2.5 z^-1) (1 + 0.3 z^-1), scaled to the unit static gain.
    let shape = [1.0, 2.8, 0.75];
    let gain = a.iter().sum::<f64>() / shape.iter().sum::<f64>();
    ReferenceLinks {
        time_constants_s: (0..11)
            .map(|i| T::from_f64(0.01 * num_traits::Float::powf(10.0f64, i as f64 / 2.0)))
            .collect(),
        weights: (0..11).map(|_| T::from_f64(0.007)).collect(),
        numerator: shape.iter().map(|b| T::from_f64(b * gain)).collect(),
        denominator: a.iter().map(|v| T::from_f64(*v)).collect(),
        delay: 1,
        period_s: T::from_f64(t),
    }
}
