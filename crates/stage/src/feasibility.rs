//! Feasibility of a drive before it is sent: can the stage's amplifier deliver it? A piezo
//! stack is a capacitor, so the amplifier's current limit is a slew-rate limit
//! (`peak_current / load_capacitance`: 14 300 V/s for the built-in stage), its rails bound the
//! voltage and its bandwidth delays it. [`feasibility`] runs the DAC and the amplifier alone
//! (exactly as the stage does, without the stack's mechanics) over the command and reports
//! what it asked and what it got.

use hystcomp_core::Shown;
use serde::Serialize;

use crate::amplifier::Amplifier;
use crate::config::StageConfig;
use crate::converters::Quantiser;
use crate::error::StageError;

/// What a drive asks of the amplifier, and what it gets.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Feasibility {
    /// Samples of the command.
    pub samples: usize,
    /// The fastest change the command asks at the amplifier's output, `gain * max |dv| / T`,
    /// V/s.
    pub peak_slew_v_per_s: f64,
    /// The amplifier's slew-rate limit, V/s.
    pub slew_limit_v_per_s: f64,
    /// Samples during which the output slewed at the limit for the whole sample.
    pub slew_limited: usize,
    /// Samples whose amplified command lay outside the rails.
    pub rail_limited: usize,
    /// Commands outside the DAC's span.
    pub dac_limited: usize,
    /// Samples at any of the three limits above, each sample counted once.
    pub limited: usize,
    /// RMS of the difference between the amplifier's output and `gain *` the command, V: the
    /// lag of its bandwidth and slew limit.
    pub lag_rms_v: f64,
    /// The largest such difference, V.
    pub lag_max_v: f64,
    /// The amplifier's output range the command spans, V (`gain * (max - min)`).
    pub swing_v: f64,
}

impl Feasibility {
    /// Share of the samples at the slew or rail limit (or the DAC's), 0..1.
    pub fn limited_share(&self) -> f64 {
        if self.samples == 0 {
            return 0.0;
        }
        self.limited_samples() as f64 / self.samples as f64
    }

    /// Samples at any limit: slew, rails or the DAC's span (a sample at two counts once).
    pub fn limited_samples(&self) -> usize {
        self.limited
    }

    /// `true` when the amplifier delivers the command without reaching a limit.
    pub fn is_feasible(&self) -> bool {
        self.limited_samples() == 0
    }

    /// A line for people: what the drive asks, what the amplifier gives, and how often it is
    /// limited.
    pub fn summary(&self) -> String {
        format!(
            "peak slew {:.4} kV/s (the amplifier gives {:.4} kV/s), {} of {} samples \
             ({:.2} %) at the slew limit, {} at the rails, {} beyond the DAC; amplifier lag \
             {:.3} V RMS ({:.3} V max) over a {:.1} V swing",
            self.peak_slew_v_per_s / 1e3,
            self.slew_limit_v_per_s / 1e3,
            self.slew_limited,
            self.samples,
            100.0 * self.slew_limited as f64 / self.samples.max(1) as f64,
            self.rail_limited,
            self.dac_limited,
            self.lag_rms_v,
            self.lag_max_v,
            self.swing_v
        )
    }
}

/// Runs the stage's DAC and amplifier over `command_v` from rest, one command per sample
/// period of the stage (see the [module documentation](self)). Non-finite commands are held,
/// as the stage holds them.
pub fn feasibility(config: &StageConfig, command_v: &[f64]) -> Result<Feasibility, StageError> {
    config.validate()?;
    feasibility_held(config, command_v, 1.0 / config.sample_rate_hz)
}

/// As [`feasibility`], for a command whose samples are each held for `period_s` seconds (a
/// drive computed at its own rate, for example a trajectory sampled at 1 kHz sent through
/// a stage that samples at 10 kHz). The amplifier's response to a held input is computed
/// exactly over the whole period (its slew then its first-order approach), so a sample counts
/// as slew-limited when the output slewed for the whole period, and the lag is the one at the
/// period's end; with `period_s` the stage's own period this is [`feasibility`].
pub fn feasibility_held(
    config: &StageConfig,
    command_v: &[f64],
    period_s: f64,
) -> Result<Feasibility, StageError> {
    config.validate()?;
    if !(period_s.is_finite() && period_s > 0.0) {
        return Err(StageError::invalid(
            "the command's sample period (s)",
            "a positive, finite number of seconds",
            Shown(period_s),
        ));
    }
    let gain = config.amplifier.gain;
    let dac = Quantiser::new(&config.dac);
    let mut amplifier = Amplifier::new(&config.amplifier, period_s);
    let mut held = dac.quantise(0.0).0;
    let mut report = Feasibility {
        samples: command_v.len(),
        peak_slew_v_per_s: 0.0,
        slew_limit_v_per_s: config.amplifier.slew_rate_v_per_s(),
        slew_limited: 0,
        rail_limited: 0,
        dac_limited: 0,
        limited: 0,
        lag_rms_v: 0.0,
        lag_max_v: 0.0,
        swing_v: 0.0,
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut previous = held;
    let mut sum = 0.0;
    for &command in command_v {
        let mut dac_clamped = false;
        if command.is_finite() {
            let (v, clamped) = dac.quantise(command);
            held = v;
            dac_clamped = clamped;
            report.dac_limited += usize::from(clamped);
        }
        report.peak_slew_v_per_s = report
            .peak_slew_v_per_s
            .max(gain * (held - previous).abs() / period_s);
        previous = held;
        let (out, rail, slewing) = amplifier.step_limits(held);
        report.rail_limited += usize::from(rail);
        report.slew_limited += usize::from(slewing);
        report.limited += usize::from(dac_clamped || rail || slewing);
        let wanted =
            (gain * held).clamp(config.amplifier.output_min_v, config.amplifier.output_max_v);
        let lag = (out - wanted).abs();
        sum += lag * lag;
        report.lag_max_v = report.lag_max_v.max(lag);
        lo = lo.min(gain * held);
        hi = hi.max(gain * held);
    }
    if !command_v.is_empty() {
        report.lag_rms_v = (sum / command_v.len() as f64).sqrt();
        report.swing_v = hi - lo;
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(frequency_hz: f64, amplitude_v: f64, seconds: f64) -> Vec<f64> {
        (0..(seconds * 1e4) as usize)
            .map(|k| {
                let t = k as f64 * 1e-4;
                // From rest: the offset reached over 0.5 s, then the tone.
                let rise = 0.5 - 0.5 * (std::f64::consts::PI * (t / 0.5).min(1.0)).cos();
                rise * (5.0 + amplitude_v * (2.0 * std::f64::consts::PI * frequency_hz * t).sin())
            })
            .collect()
    }

    #[test]
    fn a_drive_held_for_its_own_period_is_judged_at_that_period() {
        let config = StageConfig::default();
        // 1 kHz samples of a 5 Hz, 4 V tone from rest: 15 * 4 * 2 pi 5 = 1.9 kV/s, well within the
        // amplifier's 14.3 kV/s; read at the stage's 10 kHz the same steps would ask 10x.
        let tone: Vec<f64> = (0..2000)
            .map(|k| 4.0 - 4.0 * (2.0 * std::f64::consts::PI * 5.0 * k as f64 * 1e-3).cos())
            .collect();
        let held = feasibility_held(&config, &tone, 1e-3).unwrap();
        assert!(held.is_feasible(), "{}", held.summary());
        assert!(
            (held.peak_slew_v_per_s - 1_885.0).abs() < 20.0,
            "{}",
            held.summary()
        );
        let fast = feasibility(&config, &tone).unwrap();
        assert!(
            (fast.peak_slew_v_per_s / held.peak_slew_v_per_s - 10.0).abs() < 1e-9,
            "{}",
            fast.summary()
        );
        // The stage's own period gives the stage's own counts.
        let own = feasibility_held(&config, &tone, 1.0 / config.sample_rate_hz).unwrap();
        assert_eq!(own, fast);
        for bad in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
            let message = feasibility_held(&config, &tone, bad)
                .unwrap_err()
                .to_string();
            assert!(message.contains("sample period"), "{message}");
        }
    }

    #[test]
    fn a_slow_sine_is_feasible_and_a_fast_one_is_slew_limited() {
        let config = StageConfig::default();
        let slow = feasibility(&config, &sine(1.0, 4.0, 2.0)).unwrap();
        assert!(slow.is_feasible(), "{}", slow.summary());
        assert!(slow.peak_slew_v_per_s < 500.0, "{}", slow.summary());
        // 4 V at 100 Hz: 15 * 4 * 2 pi 100 = 37.7 kV/s against 14.3 kV/s.
        let fast = feasibility(&config, &sine(100.0, 4.0, 1.0)).unwrap();
        assert!(!fast.is_feasible());
        assert!(
            (fast.peak_slew_v_per_s - 37_700.0).abs() < 1_000.0,
            "{}",
            fast.summary()
        );
        assert!(fast.limited_share() > 0.3, "{}", fast.summary());
        assert!(fast.lag_max_v > 10.0);
        // The stage counts the same samples.
        let response = crate::simulate(&config, 0, &sine(100.0, 4.0, 1.0)).unwrap();
        assert_eq!(response.clamps.slew_limited as usize, fast.slew_limited);
        // Beyond the DAC's span; beyond the rails of a stronger amplifier.
        let high = feasibility(&config, &vec![11.0; 100]).unwrap();
        assert_eq!((high.dac_limited, high.rail_limited), (100, 0));
        let mut strong = config.clone();
        strong.amplifier.gain = 20.0;
        let high = feasibility(&strong, &vec![9.0; 100]).unwrap();
        assert_eq!((high.dac_limited, high.rail_limited), (0, 100));
        assert_eq!(high.limited_share(), 1.0);
    }
}
