//! Periodic multisines: sums of harmonics of one fundamental,
//! `m(tau) = sum_k a_k sin(2 pi h_k f0 tau + phi_k)`, normalised to -1 .. +1 over a period.
//!
//! Because every tone is a harmonic `h_k` of the fundamental `f0`, the signal repeats exactly
//! every `1 / f0` seconds (nominal): a record of whole periods has no spectral leakage, which
//! is what a frequency-response estimate wants. [`Multisine::schroeder`] gives equal amplitudes
//! with Schroeder's phases, which keep the crest factor low (M. R. Schroeder, "Synthesis of
//! low-peak-factor signals and binary sequences with low autocorrelation", IEEE Trans. Inf.
//! Theory 16 (1970) 85-89, doi:10.1109/TIT.1970.1054411).
//!
//! Normalisation: the sum's minimum and maximum over one period are found once, when the
//! multisine is built (a grid of at least 32 points per period of the highest harmonic, then a
//! golden-section refinement of the best local extrema), and the shape is `(m - centre) /
//! half_range`. The refinement finds the extrema to about 1e-9 of the sum's range.

use hystcomp_core::Shown;
use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::SignalError;

/// The highest fundamental accepted, Hz.
pub const MAX_FUNDAMENTAL_HZ: f64 = 1.0e6;
/// The most tones a multisine may have.
pub const MAX_TONES: usize = 10_000;
/// The largest `tones x highest harmonic` accepted (the cost of finding the range).
pub const MAX_TONE_HARMONICS: u64 = 2_000_000;

/// One tone of a multisine.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tone {
    /// Harmonic number `h` (the tone's frequency is `h` times the fundamental), at least 1.
    pub harmonic: u32,
    /// Relative amplitude (any unit: the sum is normalised).
    pub amplitude: f64,
    /// Phase at nominal time 0, rad.
    pub phase_rad: f64,
}

/// What a multisine is made of, as written in files.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultisineSpec {
    /// The fundamental `f0`, Hz: the multisine's period is `1 / f0`.
    pub fundamental_hz: f64,
    /// The tones.
    pub tones: Vec<Tone>,
}

/// A periodic multisine normalised to -1 .. +1 (see the module documentation). Built by
/// [`Multisine::new`] (or deserialised from a [`MultisineSpec`]), which checks it and finds its
/// range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "MultisineSpec", into = "MultisineSpec")]
pub struct Multisine {
    spec: MultisineSpec,
    centre: f64,
    half_range: f64,
}

impl TryFrom<MultisineSpec> for Multisine {
    type Error = SignalError;
    fn try_from(spec: MultisineSpec) -> Result<Self, SignalError> {
        Multisine::new(spec.fundamental_hz, spec.tones)
    }
}

impl From<Multisine> for MultisineSpec {
    fn from(m: Multisine) -> Self {
        m.spec
    }
}

impl Multisine {
    /// A multisine of `tones` on the fundamental `fundamental_hz`; refuses a fundamental out of
    /// (0, [`MAX_FUNDAMENTAL_HZ`]], no tones or more than [`MAX_TONES`], harmonic 0, non-finite
    /// amplitudes or phases, all amplitudes 0, or more than [`MAX_TONE_HARMONICS`] tones x
    /// highest harmonic.
    pub fn new(fundamental_hz: f64, tones: Vec<Tone>) -> Result<Multisine, SignalError> {
        if !(fundamental_hz > 0.0 && fundamental_hz <= MAX_FUNDAMENTAL_HZ) {
            return Err(SignalError::new(
                "fundamental_hz",
                format!(
                    "must be in (0, {MAX_FUNDAMENTAL_HZ}] Hz, got {}",
                    Shown(fundamental_hz)
                ),
            ));
        }
        if tones.is_empty() || tones.len() > MAX_TONES {
            return Err(SignalError::new(
                "tones",
                format!(
                    "between 1 and {MAX_TONES} tones are allowed, got {}",
                    tones.len()
                ),
            ));
        }
        for (k, t) in tones.iter().enumerate() {
            if t.harmonic == 0 || !t.amplitude.is_finite() || !t.phase_rad.is_finite() {
                return Err(SignalError::new(
                    "tones",
                    format!(
                        "tone {k}: harmonic must be at least 1 and amplitude and phase finite, \
                         got harmonic {}, amplitude {}, phase {} rad",
                        t.harmonic, t.amplitude, t.phase_rad
                    ),
                ));
            }
        }
        if tones.iter().all(|t| t.amplitude == 0.0) {
            return Err(SignalError::new("tones", "every amplitude is 0"));
        }
        let highest = tones.iter().map(|t| t.harmonic).max().unwrap_or(1);
        if tones.len() as u64 * highest as u64 > MAX_TONE_HARMONICS {
            return Err(SignalError::new(
                "tones",
                format!(
                    "{} tones up to harmonic {highest}: at most {MAX_TONE_HARMONICS} tones x \
                     highest harmonic are allowed",
                    tones.len()
                ),
            ));
        }
        let spec = MultisineSpec {
            fundamental_hz,
            tones,
        };
        let (lo, hi) = range(&spec);
        if hi - lo <= 0.0 {
            return Err(SignalError::new("tones", "the sum is constant"));
        }
        Ok(Multisine {
            centre: 0.5 * (hi + lo),
            half_range: 0.5 * (hi - lo),
            spec,
        })
    }

    /// `count` equal tones on harmonics `first_harmonic ..` of `fundamental_hz`, with
    /// Schroeder's phases `phi_k = -pi k (k - 1) / count`, k = 1 .. count.
    pub fn schroeder(
        fundamental_hz: f64,
        first_harmonic: u32,
        count: u32,
    ) -> Result<Multisine, SignalError> {
        let n = count as f64;
        let tones = (1..=count)
            .map(|k| Tone {
                harmonic: first_harmonic.saturating_add(k - 1),
                amplitude: 1.0,
                phase_rad: -PI * k as f64 * (k as f64 - 1.0) / n,
            })
            .collect();
        Multisine::new(fundamental_hz, tones)
    }

    /// The fundamental, Hz.
    pub fn fundamental_hz(&self) -> f64 {
        self.spec.fundamental_hz
    }

    /// The tones.
    pub fn tones(&self) -> &[Tone] {
        &self.spec.tones
    }

    /// The un-normalised sum at nominal time `tau_s`.
    pub fn sum(&self, tau_s: f64) -> f64 {
        sum(&self.spec, tau_s)
    }

    /// The sum's minimum and maximum over a period, `(centre - half, centre + half)`.
    pub fn range(&self) -> (f64, f64) {
        (self.centre - self.half_range, self.centre + self.half_range)
    }

    /// The highest tone's frequency, Hz.
    pub fn highest_frequency_hz(&self) -> f64 {
        let highest = self
            .spec
            .tones
            .iter()
            .map(|t| t.harmonic)
            .max()
            .unwrap_or(1);
        highest as f64 * self.spec.fundamental_hz
    }

    /// Always valid once built.
    pub fn validate(&self) -> Result<(), SignalError> {
        Ok(())
    }

    /// The multisine at nominal time `tau_s`, between -1 and +1.
    pub fn unit_value(&self, tau_s: f64) -> f64 {
        ((self.sum(tau_s) - self.centre) / self.half_range).clamp(-1.0, 1.0)
    }
}

fn sum(spec: &MultisineSpec, tau_s: f64) -> f64 {
    // The phase within one period keeps the argument small for long signals.
    let u = (tau_s * spec.fundamental_hz).rem_euclid(1.0);
    spec.tones
        .iter()
        .map(|t| t.amplitude * (2.0 * PI * t.harmonic as f64 * u + t.phase_rad).sin())
        .sum()
}

/// The minimum and maximum of the sum over one period.
fn range(spec: &MultisineSpec) -> (f64, f64) {
    let highest = spec.tones.iter().map(|t| t.harmonic).max().unwrap_or(1) as usize;
    let points = (32 * highest).max(4096);
    let period = 1.0 / spec.fundamental_hz;
    let dt = period / points as f64;
    let grid: Vec<f64> = (0..points).map(|i| sum(spec, i as f64 * dt)).collect();
    let hi = best_extremum(&grid, dt, |t| sum(spec, t));
    let lo = -best_extremum(&grid.iter().map(|g| -g).collect::<Vec<_>>(), dt, |t| {
        -sum(spec, t)
    });
    (lo, hi)
}

/// The maximum of a periodic `f` sampled on `grid` (spacing `dt`): the eight highest local
/// maxima of the grid, each refined by golden-section search over its two neighbouring steps.
fn best_extremum(grid: &[f64], dt: f64, f: impl Fn(f64) -> f64) -> f64 {
    let n = grid.len();
    let mut peaks: Vec<usize> = (0..n)
        .filter(|&i| grid[i] >= grid[(i + n - 1) % n] && grid[i] >= grid[(i + 1) % n])
        .collect();
    peaks.sort_by(|&a, &b| grid[b].total_cmp(&grid[a]));
    peaks.truncate(8);
    let golden = 0.5 * (5f64.sqrt() - 1.0);
    peaks
        .into_iter()
        .map(|i| {
            let (mut a, mut b) = ((i as f64 - 1.0) * dt, (i as f64 + 1.0) * dt);
            for _ in 0..60 {
                let c = b - golden * (b - a);
                let d = a + golden * (b - a);
                if f(c) >= f(d) {
                    b = d;
                } else {
                    a = c;
                }
            }
            f(0.5 * (a + b)).max(grid[i])
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The sum written literally with frequencies in Hz (no phase wrapping).
    fn literal(fundamental: f64, tones: &[Tone], tau: f64) -> f64 {
        tones
            .iter()
            .map(|t| {
                t.amplitude * (2.0 * PI * t.harmonic as f64 * fundamental * tau + t.phase_rad).sin()
            })
            .sum()
    }

    fn tones() -> impl Strategy<Value = Vec<Tone>> {
        proptest::collection::vec(
            (1u32..40, -2.0f64..2.0, -PI..PI).prop_map(|(harmonic, amplitude, phase_rad)| Tone {
                harmonic,
                amplitude,
                phase_rad,
            }),
            1..8,
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        #[test]
        fn multisine_is_the_literal_sum_normalised_to_its_dense_range(
            fundamental in 0.05f64..50.0,
            tones in tones(),
            taus in proptest::collection::vec(0.0f64..5.0, 20),
        ) {
            prop_assume!(tones.iter().any(|t| t.amplitude.abs() > 1e-3));
            let m = Multisine::new(fundamental, tones.clone()).unwrap();
            // The range against a brute-force dense grid: never narrower, barely wider.
            let period = 1.0 / fundamental;
            let dense: Vec<f64> = (0..200_000)
                .map(|i| literal(fundamental, &tones, i as f64 * period / 200_000.0))
                .collect();
            let lo = dense.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = dense.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let (mlo, mhi) = m.range();
            let scale = hi - lo;
            prop_assert!(mlo <= lo + 1e-12 && mhi >= hi - 1e-12, "{mlo} {mhi} vs {lo} {hi}");
            prop_assert!(lo - mlo < 1e-6 * scale && mhi - hi < 1e-6 * scale);
            for tau in taus {
                let tau = tau * period;
                let want = (literal(fundamental, &tones, tau) - 0.5 * (mlo + mhi))
                    / (0.5 * (mhi - mlo));
                prop_assert!((m.unit_value(tau) - want).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn schroeder_phases_keep_the_crest_factor_low() {
        let m = Multisine::schroeder(1.0, 1, 32).unwrap();
        let (lo, hi) = m.range();
        let rms = (32.0f64 / 2.0).sqrt();
        let crest = 0.5 * (hi - lo) / rms;
        // Equal phases would give sqrt(2 * 32) = 8; Schroeder's about 1.4-1.8.
        assert!(crest < 2.0, "crest factor {crest}");
        assert!(m.tones()[0].phase_rad == 0.0 && m.tones()[31].harmonic == 32);
    }

    #[test]
    fn bad_multisines_are_refused_and_round_trip_through_json() {
        let tone = Tone {
            harmonic: 1,
            amplitude: 1.0,
            phase_rad: 0.0,
        };
        assert_eq!(
            Multisine::new(0.0, vec![tone]).unwrap_err().parameter,
            "fundamental_hz"
        );
        assert_eq!(Multisine::new(1.0, vec![]).unwrap_err().parameter, "tones");
        let zero = Tone {
            harmonic: 0,
            ..tone
        };
        assert_eq!(
            Multisine::new(1.0, vec![zero]).unwrap_err().parameter,
            "tones"
        );
        let huge = Tone {
            harmonic: 3_000_000,
            ..tone
        };
        assert_eq!(
            Multisine::new(1.0, vec![huge]).unwrap_err().parameter,
            "tones"
        );
        let m = Multisine::new(2.0, vec![tone]).unwrap();
        let text = serde_json::to_string(&m).unwrap();
        assert_eq!(serde_json::from_str::<Multisine>(&text).unwrap(), m);
        let bad = text.replace("\"harmonic\":1", "\"harmonic\":0");
        assert!(serde_json::from_str::<Multisine>(&bad).is_err());
    }
}
