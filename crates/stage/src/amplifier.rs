//! The piezo amplifier: gain, output rails, first-order small-signal response and a slew-rate
//! (current) limit into the stack's capacitance.

use crate::config::AmplifierConfig;

/// `dv/dt = clamp(w (g u - v), -S, S)` with `g u` clamped to the rails, `w = 2 pi f_bw`,
/// `S = I_max / C`. Over one sample with a held input the solution is exact: a straight line at
/// the slew rate while the error exceeds `S / w`, then the first-order exponential.
#[derive(Debug, Clone)]
pub(crate) struct Amplifier {
    gain: f64,
    min_v: f64,
    max_v: f64,
    omega: f64,
    decay: f64,
    slew_v_per_s: f64,
    period_s: f64,
    output_v: f64,
}

impl Amplifier {
    pub(crate) fn new(config: &AmplifierConfig, period_s: f64) -> Self {
        let omega = 2.0 * std::f64::consts::PI * config.bandwidth_hz;
        Amplifier {
            gain: config.gain,
            min_v: config.output_min_v,
            max_v: config.output_max_v,
            omega,
            decay: (-omega * period_s).exp(),
            slew_v_per_s: config.slew_rate_v_per_s(),
            period_s,
            output_v: config.output_min_v.max(0.0).min(config.output_max_v),
        }
    }

    /// Returns to rest at 0 V (or the nearest rail).
    pub(crate) fn reset(&mut self) {
        self.output_v = self.min_v.max(0.0).min(self.max_v);
    }

    /// Holds `input_v` for one sample; returns the output at the end of the sample and whether
    /// `gain * input_v` lay outside the rails.
    #[cfg(test)]
    pub(crate) fn step(&mut self, input_v: f64) -> (f64, bool) {
        let (v, clamped, _) = self.step_limits(input_v);
        (v, clamped)
    }

    /// As [`Amplifier::step`], also saying whether the output slewed at the current limit for
    /// the whole sample (a staircase input makes it slew for part of many samples: that is the
    /// first-order response's start, not a drive beyond the amplifier).
    pub(crate) fn step_limits(&mut self, input_v: f64) -> (f64, bool, bool) {
        let wanted = self.gain * input_v;
        let clamped = wanted < self.min_v || wanted > self.max_v;
        let target = wanted.clamp(self.min_v, self.max_v);
        let error = target - self.output_v;
        let linear_error = self.slew_v_per_s / self.omega;
        let mut slewing = false;
        if error.abs() <= linear_error {
            self.output_v = target - error * self.decay;
        } else {
            let sign = error.signum();
            let slewing_s = (error.abs() - linear_error) / self.slew_v_per_s;
            if slewing_s >= self.period_s {
                self.output_v += sign * self.slew_v_per_s * self.period_s;
                slewing = true;
            } else {
                let rest_s = self.period_s - slewing_s;
                self.output_v = target - sign * linear_error * (-self.omega * rest_s).exp();
            }
        }
        (self.output_v, clamped, slewing)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn amp(bandwidth_hz: f64, peak_current_ma: f64) -> Amplifier {
        let config = AmplifierConfig {
            bandwidth_hz,
            peak_current_ma,
            ..AmplifierConfig::default()
        };
        Amplifier::new(&config, 1e-4)
    }

    #[test]
    fn small_steps_follow_the_first_order_law() {
        let mut a = amp(2_000.0, 1e6);
        let tau = 1.0 / (2.0 * std::f64::consts::PI * 2_000.0);
        for k in 1..=20 {
            let (v, clamped) = a.step(0.1);
            assert!(!clamped);
            let exact = 1.5 * (1.0 - (-(k as f64) * 1e-4 / tau).exp());
            assert!((v - exact).abs() < 1e-12, "{k}: {v} vs {exact}");
        }
    }

    #[test]
    fn large_steps_are_slew_limited() {
        // 1 mA into 7 uF: 142.9 V/s, i.e. 0.01429 V per 100 us sample.
        let mut a = amp(2_000.0, 1.0);
        let slew = 1e-3 / 7e-6;
        for k in 1..=100 {
            let (v, _) = a.step(10.0);
            assert!((v - slew * 1e-4 * k as f64).abs() < 1e-9);
        }
        // Then the same way down, and never past the target.
        let top = a.step(10.0).0;
        let (v, _) = a.step(0.0);
        assert!((top - v - slew * 1e-4).abs() < 1e-9);
    }

    #[test]
    fn output_stays_within_the_rails() {
        let mut a = amp(5_000.0, 1e4);
        for k in 0..2000 {
            let u = 20.0 * ((k as f64) * 0.01).sin();
            let (v, clamped) = a.step(u);
            assert!((0.0..=150.0).contains(&v));
            assert_eq!(clamped, !(0.0..=150.0).contains(&(15.0 * u)));
        }
    }
}
