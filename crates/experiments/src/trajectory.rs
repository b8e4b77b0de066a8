//! Desired trajectories.

use serde::{Deserialize, Serialize};

/// A sum of sines, `y_d(t) = offset + sum_k amp_k sin(2 pi f_k t + phase_k)` (section 4.3 of the
/// paper: 37.35 + 10.5 sin(pi t + 2.6) + 10.5 sin(1.6 pi t + 3) + 15.75 sin(2 pi t + 1.5) um).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultisineTrajectory {
    /// Constant offset, um.
    pub offset_um: f64,
    /// Amplitude of each tone, um.
    pub amplitudes_um: Vec<f64>,
    /// Frequency of each tone, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Phase of each tone, rad.
    pub phases_rad: Vec<f64>,
}

impl MultisineTrajectory {
    /// The desired position at time `t_s` (seconds), um.
    pub fn position_um(&self, t_s: f64) -> f64 {
        self.offset_um
            + self
                .amplitudes_um
                .iter()
                .zip(&self.frequencies_hz)
                .zip(&self.phases_rad)
                .map(|((a, f), p)| a * (2.0 * std::f64::consts::PI * f * t_s + p).sin())
                .sum::<f64>()
    }

    /// `samples` values at `t = k / sample_rate_hz`, k = 0, 1, ...: (time s, position um).
    pub fn sample(&self, sample_rate_hz: f64, samples: usize) -> (Vec<f64>, Vec<f64>) {
        let time: Vec<f64> = (0..samples).map(|k| k as f64 / sample_rate_hz).collect();
        let position = time.iter().map(|&t| self.position_um(t)).collect();
        (time, position)
    }
}
