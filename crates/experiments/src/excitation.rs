//! The identification excitation of the study (section 4.2 of the paper does not print its
//! own; this one is chosen and documented here).
//!
//! The command starts at rest (0 V) and has two parts:
//!
//! 1. **Nested reversals** covering the full command range: `0 -> 100 % -> 0 -> 100 % -> 10 %
//!    -> 90 % -> 20 % -> ... -> 50 %`, then a second, irregular family of nested minor loops
//!    ([`REVERSALS`]). Each move is a raised-cosine half period of `segment_s` seconds; with the
//!    default 1 s a full-range move peaks at about 120 um/s on a 75 um stage, the speed of the
//!    paper's trajectory (up to about 185 um/s), so creep and dynamics enter the record as they
//!    enter the tracking runs.
//! 2. **A full-range multisine** of `multisine_s` seconds in the trajectory's band but at other
//!    frequencies than the paper's trajectory (0.35, 0.7 and 1.1 Hz instead of 0.5, 0.8 and
//!    1 Hz; see [`MULTISINE_FREQUENCIES_HZ`]), so that identification never sees the test
//!    signal. It is reached from the last reversal by a raised-cosine lead-in of `lead_s`.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use crate::MultisineTrajectory;

/// Turning points of the nested reversals, as fractions of the full-scale command.
pub const REVERSALS: [f64; 22] = [
    1.0, 0.0, 1.0, 0.1, 0.9, 0.2, 0.8, 0.3, 0.7, 0.4, 0.6, 0.5, 1.0, 0.05, 0.6, 0.2, 0.95, 0.45,
    0.75, 0.0, 1.0, 0.0,
];

/// Frequencies of the identification multisine, Hz.
pub const MULTISINE_FREQUENCIES_HZ: [f64; 3] = [0.35, 0.7, 1.1];
/// Amplitudes of the identification multisine (before scaling to the full range).
pub const MULTISINE_AMPLITUDES: [f64; 3] = [10.5, 10.5, 15.75];
/// Phases of the identification multisine, rad.
pub const MULTISINE_PHASES_RAD: [f64; 3] = [0.3, 1.9, 4.0];

/// How the identification command is built (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IdentificationExcitation {
    /// Full-scale command, V (10 V: 150 V at the stack).
    pub full_scale_v: f64,
    /// Duration of each reversal move, s.
    pub segment_s: f64,
    /// Duration of the lead-in from the last reversal to the multisine, s.
    pub lead_s: f64,
    /// Duration of the multisine, s (0 for reversals only).
    pub multisine_s: f64,
}

impl Default for IdentificationExcitation {
    fn default() -> Self {
        IdentificationExcitation {
            full_scale_v: 10.0,
            segment_s: 1.0,
            lead_s: 1.0,
            multisine_s: 20.0,
        }
    }
}

/// A raised-cosine move from `from` to `to` over `samples` samples (excluding `from`).
fn raised_cosine(from: f64, to: f64, samples: usize) -> impl Iterator<Item = f64> {
    (1..=samples).map(move |k| {
        let s = k as f64 / samples as f64;
        from + (to - from) * 0.5 * (1.0 - (PI * s).cos())
    })
}

impl IdentificationExcitation {
    /// The multisine part's shape, a sum of sines in arbitrary units.
    pub fn multisine() -> MultisineTrajectory {
        MultisineTrajectory {
            offset_um: 0.0,
            amplitudes_um: MULTISINE_AMPLITUDES.to_vec(),
            frequencies_hz: MULTISINE_FREQUENCIES_HZ.to_vec(),
            phases_rad: MULTISINE_PHASES_RAD.to_vec(),
        }
    }

    /// The excitation's duration, s: the reversal moves, the lead-in and the multisine.
    pub fn duration_s(&self) -> f64 {
        REVERSALS.len() as f64 * self.segment_s + self.lead_s + self.multisine_s
    }

    /// The command, V, sampled at `sample_rate_hz`, from rest.
    pub fn command_v(&self, sample_rate_hz: f64) -> Vec<f64> {
        let per_segment = ((self.segment_s * sample_rate_hz).round() as usize).max(1);
        let mut command = Vec::new();
        let mut last = 0.0;
        for &turn in &REVERSALS {
            let to = turn * self.full_scale_v;
            command.extend(raised_cosine(last, to, per_segment));
            last = to;
        }
        let samples = (self.multisine_s * sample_rate_hz).round() as usize;
        if samples > 0 {
            let shape = Self::multisine();
            let (time, raw) = shape.sample(sample_rate_hz, samples);
            let (lo, hi) = raw
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                    (a.min(y), b.max(y))
                });
            let scale = |y: f64| self.full_scale_v * (y - lo) / (hi - lo);
            let lead = ((self.lead_s * sample_rate_hz).round() as usize).max(1);
            command.extend(raised_cosine(last, scale(raw[0]), lead));
            command.extend(raw.iter().map(|&y| scale(y)));
            debug_assert_eq!(time.len(), samples);
        }
        command
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excitation_starts_at_rest_covers_the_full_range_and_is_smooth() {
        let e = IdentificationExcitation::default();
        let fs = 1000.0;
        let v = e.command_v(fs);
        let expected = REVERSALS.len() * 1000 + 1000 + 20_000;
        assert_eq!(v.len(), expected);
        assert!(v[0].abs() < 1e-3, "starts at rest: {}", v[0]);
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        assert!(
            (0.0..1e-9).contains(&lo) && (hi - 10.0).abs() < 1e-9,
            "{lo} {hi}"
        );
        // No jumps: the largest step is that of the fastest full-range move.
        let max_step = v
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(
            max_step < 10.0 * PI / 2.0 / 1000.0 * 1.01 + 0.05,
            "{max_step}"
        );
        // Nested minor loops: the reversals shrink towards the middle.
        let turns: Vec<f64> = REVERSALS[2..12].to_vec();
        for w in turns.windows(3) {
            assert!((w[2] - w[1]).abs() < (w[1] - w[0]).abs());
        }
    }

    #[test]
    fn multisine_avoids_the_trajectory_frequencies() {
        let paper = crate::Reference::paper();
        for f in MULTISINE_FREQUENCIES_HZ {
            for g in &paper.trajectory.frequencies_hz {
                assert!((f - g).abs() >= 0.1, "{f} Hz is too close to {g} Hz");
            }
        }
    }
}
