//! What the study's identification excitation gains for the full chain (hysteresis -> creep
//! -> vibration): after the nested reversals and the multisine of
//! [`crate::excitation::IdentificationExcitation`], the command goes on with
//!
//! 1. **a rate sweep**: a logarithmic chirp of `rate_amplitude` of the full scale about mid-range
//!    from `rate_start_hz` to `rate_end_hz` (1 to 30 Hz over 10 s by default), so that the
//!    creep link's short time constants are seen at the speeds the speed study asks;
//! 2. **holds**: a rest near the bottom (`rest_level`, `rest_s`), a step up to `high_level` held
//!    `hold_s` (60 s), and a step down to `low_level` held `second_hold_s` (30 s), each step a
//!    raised cosine of `step_s`: creep after a large step, up and down, as a step-and-hold
//!    test measures it on hardware;
//! 3. **a vibration segment**: a small-amplitude Schroeder multisine at mid-range
//!    (`vibration_amplitude` of the full scale: 0.06 V, about 0.5 um), on harmonics of
//!    `vibration_fundamental_hz` from `vibration_band_hz[0]` to `vibration_band_hz[1]` (20 Hz to
//!    1.5 kHz), for `vibration_s`, after `settle_s` at its level: the dynamics around the
//!    800 Hz resonance, below the amplifier's slew limit (the whole excitation asks at most
//!    8.5 kV/s of its 14.3 kV/s).
//!
//! Moves between the parts are raised cosines of `lead_s`. Levels and amplitudes are fractions
//! of the full-scale command.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::signals::{Chirp, Multisine, Shape, Signal, SignalError, Sweep};

/// The chain's part of the identification excitation (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainExcitation {
    /// Duration of each move between parts, s.
    pub lead_s: f64,
    /// Duration of the rate sweep, s (0 leaves it out).
    pub rate_s: f64,
    /// The sweep's first frequency, Hz.
    pub rate_start_hz: f64,
    /// The sweep's last frequency, Hz.
    pub rate_end_hz: f64,
    /// The sweep's amplitude about mid-range, fraction of the full scale.
    pub rate_amplitude: f64,
    /// The rest level before the step up, fraction of the full scale.
    pub rest_level: f64,
    /// The rest, s.
    pub rest_s: f64,
    /// Duration of each step, s.
    pub step_s: f64,
    /// The level of the first hold, fraction of the full scale.
    pub high_level: f64,
    /// The first hold, s.
    pub hold_s: f64,
    /// The level of the second hold, fraction of the full scale.
    pub low_level: f64,
    /// The second hold, s (0 leaves it out).
    pub second_hold_s: f64,
    /// The vibration segment's level, fraction of the full scale.
    pub vibration_level: f64,
    /// Time at that level before the vibration segment, s.
    pub settle_s: f64,
    /// The vibration multisine's peak deviation, fraction of the full scale.
    pub vibration_amplitude: f64,
    /// The multisine's fundamental, Hz: its tones are harmonics of it.
    pub vibration_fundamental_hz: f64,
    /// The multisine's band, Hz.
    pub vibration_band_hz: [f64; 2],
    /// The vibration segment, s.
    pub vibration_s: f64,
}

impl Default for ChainExcitation {
    fn default() -> Self {
        ChainExcitation {
            lead_s: 1.0,
            rate_s: 10.0,
            rate_start_hz: 1.0,
            rate_end_hz: 30.0,
            rate_amplitude: 0.3,
            rest_level: 0.05,
            rest_s: 5.0,
            step_s: 0.2,
            high_level: 0.7,
            hold_s: 60.0,
            low_level: 0.3,
            second_hold_s: 30.0,
            vibration_level: 0.5,
            settle_s: 0.5,
            vibration_amplitude: 0.006,
            vibration_fundamental_hz: 10.0,
            vibration_band_hz: [20.0, 1500.0],
            vibration_s: 2.0,
        }
    }
}

/// Where the parts lie in the command [`ChainExcitation::command_v`] returns (sample indices
/// from its start).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ChainSegments {
    /// The rate sweep.
    pub rate: Range<usize>,
    /// The rest and the holds.
    pub holds: Range<usize>,
    /// The vibration multisine.
    pub vibration: Range<usize>,
}

/// A raised-cosine move from `from` to `to` over `samples` samples (excluding `from`).
fn raised_cosine(from: f64, to: f64, samples: usize) -> impl Iterator<Item = f64> {
    (1..=samples).map(move |k| {
        let s = k as f64 / samples as f64;
        from + (to - from) * 0.5 * (1.0 - (std::f64::consts::PI * s).cos())
    })
}

impl ChainExcitation {
    /// Its length, s.
    pub fn duration_s(&self) -> f64 {
        let mut d = 0.0;
        if self.rate_s > 0.0 {
            d += self.lead_s + self.rate_s;
        }
        d += self.lead_s + self.rest_s + self.step_s + self.hold_s;
        if self.second_hold_s > 0.0 {
            d += self.step_s + self.second_hold_s;
        }
        d + self.lead_s + self.settle_s + self.vibration_s
    }

    /// The command, V, at `sample_rate_hz`, continuing from `from_v`, for a stage whose
    /// full-scale command is `full_scale_v`, and where its parts lie.
    pub fn command_v(
        &self,
        full_scale_v: f64,
        sample_rate_hz: f64,
        from_v: f64,
    ) -> Result<(Vec<f64>, ChainSegments), SignalError> {
        let fs = full_scale_v;
        let n = |s: f64| ((s * sample_rate_hz).round() as usize).max(1);
        let mut out: Vec<f64> = Vec::new();
        let mut last = from_v;
        let move_to = |out: &mut Vec<f64>, last: &mut f64, to: f64, seconds: f64| {
            out.extend(raised_cosine(*last, to, n(seconds)));
            *last = to;
        };
        let rate_start = out.len();
        if self.rate_s > 0.0 {
            move_to(&mut out, &mut last, 0.5 * fs, self.lead_s);
            let sweep = Signal {
                shape: Shape::Chirp(Chirp {
                    start_hz: self.rate_start_hz,
                    end_hz: self.rate_end_hz,
                    sweep: Sweep::Logarithmic,
                }),
                amplitude: self.rate_amplitude * fs,
                offset: 0.5 * fs,
                duration_s: self.rate_s,
                speed: 1.0,
                sample_rate_hz,
            }
            .sample()?;
            last = *sweep.last().unwrap_or(&last);
            out.extend(sweep);
        }
        let rate = rate_start..out.len();
        let holds_start = out.len();
        move_to(&mut out, &mut last, self.rest_level * fs, self.lead_s);
        out.extend(std::iter::repeat_n(last, n(self.rest_s)));
        move_to(&mut out, &mut last, self.high_level * fs, self.step_s);
        out.extend(std::iter::repeat_n(last, n(self.hold_s)));
        if self.second_hold_s > 0.0 {
            move_to(&mut out, &mut last, self.low_level * fs, self.step_s);
            out.extend(std::iter::repeat_n(last, n(self.second_hold_s)));
        }
        let holds = holds_start..out.len();
        move_to(&mut out, &mut last, self.vibration_level * fs, self.lead_s);
        out.extend(std::iter::repeat_n(last, n(self.settle_s)));
        let first = (self.vibration_band_hz[0] / self.vibration_fundamental_hz).round() as u32;
        let last_harmonic =
            (self.vibration_band_hz[1] / self.vibration_fundamental_hz).round() as u32;
        let multisine = Multisine::schroeder(
            self.vibration_fundamental_hz,
            first.max(1),
            last_harmonic.saturating_sub(first.max(1)) + 1,
        )?;
        let segment = Signal {
            shape: Shape::Multisine(multisine),
            amplitude: self.vibration_amplitude * fs,
            offset: self.vibration_level * fs,
            duration_s: self.vibration_s,
            speed: 1.0,
            sample_rate_hz,
        }
        .sample()?;
        let vibration_start = out.len();
        out.extend(segment);
        let vibration = vibration_start..out.len();
        Ok((
            out,
            ChainSegments {
                rate,
                holds,
                vibration,
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chain_excitation_has_its_parts_where_it_says_and_no_jumps() {
        let e = ChainExcitation::default();
        let (v, segments) = e.command_v(10.0, 10_000.0, 5.0).unwrap();
        assert!((v.len() as f64 / 10_000.0 - e.duration_s()).abs() < 1e-3);
        assert_eq!(segments.vibration.end, v.len());
        assert_eq!(segments.vibration.len(), 20_000);
        assert_eq!(segments.rate.len(), 110_000);
        let hold = &v[segments.holds.clone()];
        assert!(hold.iter().filter(|x| (**x - 7.0).abs() < 1e-12).count() >= 600_000);
        let vib = &v[segments.vibration.clone()];
        let (lo, hi) = vib
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        // Sampled at 10 kHz the peaks are met within a few mV, never passed.
        assert!(
            (hi - 5.06).abs() < 3e-3 && (lo - 4.94).abs() < 3e-3,
            "{lo} {hi}"
        );
        assert!(hi <= 5.06 + 1e-9 && lo >= 4.94 - 1e-9);
        assert!(v.iter().all(|x| (0.0..=10.0).contains(x)));
        // The largest step between samples, outside the vibration multisine, is that of the
        // sweep's fastest tone (2 pi 30 Hz x 3 V / 10 kHz = 0.057 V): no jumps.
        let steepest = v[..segments.vibration.start]
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(steepest < 0.06, "{steepest}");
        let steepest_hold = v[segments.holds.clone()]
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(steepest_hold < 0.006, "{steepest_hold}");
    }
}
