//! The published numbers of the reference paper (Gu & Zhu 2014), compiled into the binary from
//! `reference.toml` (a copy of `../shared/paper/reference.toml`) so that reports can print them
//! beside ours on any machine.

use serde::Deserialize;

use crate::trajectory::MultisineTrajectory;

const REFERENCE_TOML: &str = include_str!("../reference.toml");

/// Everything `reference.toml` holds.
#[derive(Debug, Clone, Deserialize)]
pub struct Reference {
    /// Section 4.1: the experimental set-up.
    pub stage: ReferenceStage,
    /// Section 4.3: the desired trajectory.
    pub trajectory: ReferenceTrajectory,
    /// Table 1: the MPIM identified for IHC and WIHC (input: normalised voltage).
    pub table1_forward_mpim: ReferenceMpim,
    /// Table 2: the MPIM identified for DIHC (input: normalised desired position).
    pub table2_inverse_mpim: ReferenceMpim,
    /// Table 3: indices measured on the real stage, percent of the `y_d` range.
    pub table3_results_percent: ReferenceTable3,
}

/// Section 4.1 of the paper.
#[derive(Debug, Clone, Deserialize)]
pub struct ReferenceStage {
    /// The piezo actuator, e.g. a Piezomechanik PSt 150/7/100 preloaded stack.
    pub actuator: String,
    /// The positioning stage it drives (75 um nominal stroke).
    pub stage: String,
    /// Amplifier gain, V/V.
    pub amplifier_gain: f64,
    /// Amplifier output range, V.
    pub amplifier_range_v: [f64; 2],
    /// Resolution of the controller's DAC, bits.
    pub dac_bits: u32,
    /// Resolution of the controller's ADC, bits.
    pub adc_bits: u32,
    /// The position sensor, in words.
    pub sensor: String,
    /// The real-time controller board.
    pub controller: String,
}

/// `y_d(t) = offset + sum amp_k sin(2 pi f_k t + phase_k)`, micrometres.
#[derive(Debug, Clone, Deserialize)]
pub struct ReferenceTrajectory {
    /// Unit of `offset`, `amplitudes` and `range_um` (`"um"`).
    pub unit: String,
    /// Constant offset, um.
    pub offset: f64,
    /// Amplitude of each tone, um.
    pub amplitudes: Vec<f64>,
    /// Frequency of each tone, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Phase of each tone, rad.
    pub phases_rad: Vec<f64>,
    /// Common period of the tones, s.
    pub period_s: f64,
    /// Minimum and maximum over one period, um.
    pub range_um: [f64; 2],
}

/// An MPIM in the paper's normalised units (eq. (4)).
#[derive(Debug, Clone, Deserialize)]
pub struct ReferenceMpim {
    /// Thresholds `r_i` of the play operators, normalised input units (eq. (11)).
    pub thresholds: Vec<f64>,
    /// Weights `p_i` of the play operators, normalised output per normalised input.
    pub weights: Vec<f64>,
    /// Cubic coefficient `a1` of the input function `g(x) = a1 x^3 + a2 x`, normalised units.
    pub a1: f64,
    /// Linear coefficient `a2` of `g(x)`, normalised units.
    pub a2: f64,
}

/// One column of Table 3, percent. Read from `reference.toml` as `e_mhe`, `e_m`, `e_rms`;
/// written (JSON) as `e_mhe_percent`, `e_m_percent`, `e_rms_percent`, the key names of our
/// own [`crate::TrackingIndices`].
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq)]
pub struct ReferenceIndices {
    /// Maximum hysteresis error, eq. (12), % of the `y_d` range.
    #[serde(rename(serialize = "e_mhe_percent"))]
    pub e_mhe: f64,
    /// Maximum tracking error, (D1), % of the `y_d` range.
    #[serde(rename(serialize = "e_m_percent"))]
    pub e_m: f64,
    /// RMS tracking error, (D2), % of the `y_d` range.
    #[serde(rename(serialize = "e_rms_percent"))]
    pub e_rms: f64,
}

/// Table 3 of the paper, percent of the `y_d` range.
#[derive(Debug, Clone, Deserialize)]
pub struct ReferenceTable3 {
    /// e_mhe of the uncompensated stage, % of the `y_d` range.
    pub uncompensated_e_mhe: f64,
    /// IHC, %.
    pub ihc: ReferenceIndices,
    /// WIHC, %.
    pub wihc: ReferenceIndices,
    /// DIHC, %.
    pub dihc: ReferenceIndices,
}

impl Reference {
    /// The paper's numbers. The embedded file is checked by a unit test, so this cannot fail.
    pub fn paper() -> Reference {
        toml::from_str(REFERENCE_TOML).expect("the embedded reference.toml is valid (unit-tested)")
    }

    /// The desired trajectory of section 4.3.
    pub fn trajectory(&self) -> MultisineTrajectory {
        let t = &self.trajectory;
        MultisineTrajectory {
            offset_um: t.offset,
            amplitudes_um: t.amplitudes.clone(),
            frequencies_hz: t.frequencies_hz.clone(),
            phases_rad: t.phases_rad.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_reference_parses_and_matches_the_shared_copy_where_present() {
        let r = Reference::paper();
        assert_eq!(r.table1_forward_mpim.weights.len(), 10);
        assert_eq!(r.table2_inverse_mpim.thresholds.len(), 10);
        let shared = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/paper/reference.toml"
        );
        match std::fs::read_to_string(shared) {
            Ok(text) => {
                // The copy only adds a citation header; the body must be identical.
                assert!(
                    REFERENCE_TOML.ends_with(&text),
                    "reference.toml differs from {shared}"
                );
            }
            Err(_) => eprintln!("skipping the comparison: {shared} is absent on this machine"),
        }
    }

    #[test]
    fn trajectory_range_matches_the_published_range() {
        let r = Reference::paper();
        let traj = r.trajectory();
        let (lo, hi) = (0..100_000)
            .map(|i| traj.position_um(i as f64 * r.trajectory.period_s / 100_000.0))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
                (lo.min(y), hi.max(y))
            });
        assert!((lo - r.trajectory.range_um[0]).abs() < 2e-3, "{lo}");
        assert!((hi - r.trajectory.range_um[1]).abs() < 2e-3, "{hi}");
    }
}
