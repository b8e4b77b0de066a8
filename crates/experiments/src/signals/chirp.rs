//! Chirps: `sin(phi(tau))` whose instantaneous frequency `phi'(tau) / 2 pi` sweeps from
//! `start_hz` to `end_hz` over the signal's whole nominal length `T` (`speed * duration_s`).
//!
//! - [`Sweep::Linear`]: `f(tau) = f0 + (f1 - f0) tau / T`, so
//!   `phi(tau) = 2 pi (f0 tau + (f1 - f0) tau^2 / (2 T))`.
//! - [`Sweep::Logarithmic`] (exponential in time, equal time per octave):
//!   `f(tau) = f0 (f1 / f0)^(tau / T)`, so
//!   `phi(tau) = 2 pi f0 T ((f1 / f0)^(tau / T) - 1) / ln(f1 / f0)`.
//!
//! The phase is 0 at the start, so a chirp starts at its offset (with the velocity of its first
//! frequency); its frequencies scale with the signal's speed factor.

use hystcomp_core::Shown;
use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::SignalError;

/// The highest chirp frequency accepted, Hz (at speed 1).
pub const MAX_CHIRP_HZ: f64 = 1.0e6;

/// How the frequency moves from start to end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sweep {
    /// Linear in time.
    Linear,
    /// Exponential in time (linear on a logarithmic frequency axis).
    Logarithmic,
}

/// A swept sine (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chirp {
    /// Frequency at the start, Hz (positive for a logarithmic sweep, non-negative otherwise).
    pub start_hz: f64,
    /// Frequency at the end, Hz (may be below the start: a downward sweep).
    pub end_hz: f64,
    /// Linear or logarithmic.
    pub sweep: Sweep,
}

impl Chirp {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SignalError> {
        let lowest = match self.sweep {
            Sweep::Linear => 0.0,
            Sweep::Logarithmic => f64::MIN_POSITIVE,
        };
        for (name, f) in [("start_hz", self.start_hz), ("end_hz", self.end_hz)] {
            if !(f.is_finite() && f >= lowest && f <= MAX_CHIRP_HZ) {
                let what = match self.sweep {
                    Sweep::Linear => "in [0",
                    Sweep::Logarithmic => "in (0",
                };
                return Err(SignalError::new(
                    name,
                    format!("must be {what}, {MAX_CHIRP_HZ}] Hz, got {}", Shown(f)),
                ));
            }
        }
        Ok(())
    }

    /// The phase at nominal time `tau_s` of a sweep lasting `span_s`, rad.
    pub fn phase_rad(&self, tau_s: f64, span_s: f64) -> f64 {
        let (f0, f1) = (self.start_hz, self.end_hz);
        match self.sweep {
            Sweep::Linear => 2.0 * PI * (f0 * tau_s + (f1 - f0) * tau_s * tau_s / (2.0 * span_s)),
            Sweep::Logarithmic => {
                let ratio = f1 / f0;
                if (ratio - 1.0).abs() < 1e-12 {
                    2.0 * PI * f0 * tau_s
                } else {
                    let k = ratio.ln();
                    2.0 * PI * f0 * span_s * ((k * tau_s / span_s).exp() - 1.0) / k
                }
            }
        }
    }

    /// The chirp at nominal time `tau_s` of a sweep lasting `span_s`, between -1 and +1.
    pub fn unit_value(&self, tau_s: f64, span_s: f64) -> f64 {
        self.phase_rad(tau_s, span_s).sin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The phase as the integral of the instantaneous frequency law (trapezoids).
    fn integrated_phase(c: &Chirp, tau: f64, span: f64) -> f64 {
        let f = |t: f64| match c.sweep {
            Sweep::Linear => c.start_hz + (c.end_hz - c.start_hz) * t / span,
            Sweep::Logarithmic => c.start_hz * (c.end_hz / c.start_hz).powf(t / span),
        };
        let n = 20_000;
        let h = tau / n as f64;
        let inner: f64 = (1..n).map(|i| f(i as f64 * h)).sum();
        2.0 * PI * h * (0.5 * (f(0.0) + f(tau)) + inner)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn chirp_phase_integrates_its_frequency_law(
            start in 0.1f64..100.0,
            end in 0.1f64..100.0,
            logarithmic in any::<bool>(),
            span in 0.5f64..5.0,
            share in 0.0f64..=1.0,
        ) {
            let c = Chirp {
                start_hz: start,
                end_hz: end,
                sweep: if logarithmic { Sweep::Logarithmic } else { Sweep::Linear },
            };
            c.validate().unwrap();
            let tau = share * span;
            let got = c.phase_rad(tau, span);
            let want = integrated_phase(&c, tau, span);
            prop_assert!((got - want).abs() < 1e-5 * (1.0 + want.abs()), "{got} vs {want}");
            prop_assert!((c.unit_value(tau, span) - got.sin()).abs() < 1e-12);
        }
    }

    #[test]
    fn a_linear_chirp_crosses_zero_as_often_as_its_mean_frequency_says() {
        let c = Chirp {
            start_hz: 10.0,
            end_hz: 110.0,
            sweep: Sweep::Linear,
        };
        // Mean frequency 60 Hz over 2 s: 120 cycles, 240 zero crossings.
        let n = 200_000;
        let values: Vec<f64> = (0..=n)
            .map(|k| c.unit_value(2.0 * k as f64 / n as f64, 2.0))
            .collect();
        let crossings = values
            .windows(2)
            .filter(|w| w[0].signum() != w[1].signum())
            .count();
        assert!((239..=241).contains(&crossings), "{crossings}");
    }

    #[test]
    fn bad_chirps_are_refused() {
        let c = Chirp {
            start_hz: 0.0,
            end_hz: 10.0,
            sweep: Sweep::Logarithmic,
        };
        assert_eq!(c.validate().unwrap_err().parameter, "start_hz");
        assert!(
            Chirp {
                sweep: Sweep::Linear,
                ..c.clone()
            }
            .validate()
            .is_ok()
        );
        let c = Chirp {
            end_hz: f64::NAN,
            sweep: Sweep::Linear,
            ..c
        };
        assert_eq!(c.validate().unwrap_err().parameter, "end_hz");
    }
}
