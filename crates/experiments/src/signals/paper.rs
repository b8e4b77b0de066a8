//! The paper's desired trajectory (section 4.3 of Gu & Zhu 2014), time-compressed:
//! `y_d(t) = 37.35 + 10.5 sin(pi s t + 2.6) + 10.5 sin(1.6 pi s t + 3) + 15.75 sin(2 pi s t +
//! 1.5)` um at speed factor `s`. Its tones are harmonics 5, 8 and 10 of 0.1 Hz (common period
//! 10 s / s), so it is a [`Multisine`]; its range over a period is 2.049 .. 69.309 um, and
//! [`super::Signal::paper`] sets the amplitude and offset that reproduce it exactly. A fastest
//! tone of `f` Hz is speed `f` (the paper's fastest tone is 1 Hz).

use serde::{Deserialize, Serialize};

use super::multisine::{Multisine, Tone};

/// Offset of the paper's trajectory, um.
pub const OFFSET_UM: f64 = 37.35;
/// Fundamental of the paper's tones, Hz (their common period is 10 s).
pub const FUNDAMENTAL_HZ: f64 = 0.1;
/// The paper's tones: harmonics of 0.1 Hz, amplitudes in um, phases in rad.
pub const TONES: [Tone; 3] = [
    Tone {
        harmonic: 5,
        amplitude: 10.5,
        phase_rad: 2.6,
    },
    Tone {
        harmonic: 8,
        amplitude: 10.5,
        phase_rad: 3.0,
    },
    Tone {
        harmonic: 10,
        amplitude: 15.75,
        phase_rad: 1.5,
    },
];

/// The paper's trajectory as a shape (written `{"kind": "paper"}`: it has no parameters).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "PaperSpec", into = "PaperSpec")]
pub struct PaperTrajectory {
    multisine: Multisine,
}

/// The paper's trajectory has no parameters of its own.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PaperSpec {}

impl From<PaperSpec> for PaperTrajectory {
    fn from(_: PaperSpec) -> Self {
        PaperTrajectory::new()
    }
}

impl From<PaperTrajectory> for PaperSpec {
    fn from(_: PaperTrajectory) -> Self {
        PaperSpec {}
    }
}

impl Default for PaperTrajectory {
    fn default() -> Self {
        PaperTrajectory::new()
    }
}

impl PaperTrajectory {
    /// The paper's trajectory.
    pub fn new() -> PaperTrajectory {
        PaperTrajectory {
            multisine: Multisine::new(FUNDAMENTAL_HZ, TONES.to_vec())
                .expect("the paper's tones form a valid multisine"),
        }
    }

    /// Centre of its range, um (35.68).
    pub fn mid_range_um(&self) -> f64 {
        let (lo, hi) = self.multisine.range();
        OFFSET_UM + 0.5 * (lo + hi)
    }

    /// Half its range, um (33.63).
    pub fn half_range_um(&self) -> f64 {
        let (lo, hi) = self.multisine.range();
        0.5 * (hi - lo)
    }

    /// The paper's fastest tone, Hz (1).
    pub fn highest_frequency_hz(&self) -> f64 {
        self.multisine.highest_frequency_hz()
    }

    /// The trajectory at nominal time `tau_s`, normalised to -1 .. +1.
    pub fn unit_value(&self, tau_s: f64) -> f64 {
        self.multisine.unit_value(tau_s)
    }
}

#[cfg(test)]
mod tests {
    use crate::Reference;
    use crate::signals::Signal;

    #[test]
    fn speed_one_is_the_papers_trajectory_and_speed_ten_is_ten_times_faster() {
        let reference = Reference::paper();
        let paper = crate::MultisineTrajectory {
            offset_um: reference.trajectory.offset,
            amplitudes_um: reference.trajectory.amplitudes.clone(),
            frequencies_hz: reference.trajectory.frequencies_hz.clone(),
            phases_rad: reference.trajectory.phases_rad.clone(),
        };
        let slow = Signal::paper(1.0, 20.0, 1000.0);
        let fast = Signal::paper(10.0, 2.0, 1000.0);
        let slow_um = slow.sample().unwrap();
        let fast_um = fast.sample().unwrap();
        for (k, y) in slow_um.iter().enumerate() {
            assert!(
                (y - paper.position_um(k as f64 / 1000.0)).abs() < 1e-9,
                "{k}"
            );
        }
        for (k, y) in fast_um.iter().enumerate() {
            assert!((y - paper.position_um(10.0 * k as f64 / 1000.0)).abs() < 1e-9);
        }
        let [lo, hi] = reference.trajectory.range_um;
        let p = super::PaperTrajectory::new();
        assert!((p.mid_range_um() - 0.5 * (lo + hi)).abs() < 1e-3);
        assert!((p.half_range_um() - 0.5 * (hi - lo)).abs() < 1e-3);
        assert_eq!(fast.highest_frequency_hz(), 10.0);
    }
}
