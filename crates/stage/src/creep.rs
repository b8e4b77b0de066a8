//! Creep of the stack, acting on the hysteresis output as in the hysteresis -> creep ->
//! vibration cascade of Croft, Shed & Devasia (2001), doi:10.1115/1.1341197. Two laws
//! ([`CreepLaw`]), both sums of first-order elements discretised exactly for a held input,
//! `x_out = x + sum_i w_i z_i`, `tau_i dz_i/dt = x - z_i`:
//!
//! - **logarithmic** (default): after a step of `x`, `x_out(t) = x (1 + gamma log10(1 + t /
//!   t0))`. By Frullani's integral, `ln(1 + t / t0) = int_0^inf (1 - e^(-s t)) e^(-s t0) ds / s`:
//!   a continuous spectrum of rates `s` with density `e^(-s t0) / s`. With `u = ln s` the
//!   integrand is smooth, and the trapezoidal rule on a grid of `elements_per_decade` nodes per
//!   decade of `u` (`tau = 1 / s` from `t0 / 40`, where `e^(-s t0)` is below 1e-17, to
//!   `longest_time_constant_s`) gives elements of weight `gamma / ln 10 * h * e^(-t0 / tau)`
//!   (`h` the grid step in `u`). A test checks the step response against the literal
//!   logarithm.
//! - **Kelvin-Voigt**: a finite bank, `elements_per_decade` elements per decade from
//!   `first_time_constant_s` over `decades` decades, each of weight `gamma /
//!   elements_per_decade`, whose summed step responses rise by `gamma` per decade between
//!   about `10 tau_min` and `tau_max / 10`.

use crate::config::{CreepConfig, CreepLaw};

/// The summed first-order elements (see the module documentation).
#[derive(Debug, Clone)]
pub(crate) struct Creep {
    weights: Vec<f64>,
    gains: Vec<f64>,
    states: Vec<f64>,
}

/// The elements of a creep law: `(time constant s, weight)` pairs.
pub(crate) fn elements(config: &CreepConfig) -> Vec<(f64, f64)> {
    let gamma = config.percent_per_decade / 100.0;
    if gamma <= 0.0 {
        return Vec::new();
    }
    let per_decade = config.elements_per_decade.max(1) as f64;
    match config.law {
        CreepLaw::KelvinVoigt => (0..=config.decades * config.elements_per_decade)
            .map(|i| {
                let tau = config.first_time_constant_s * 10f64.powf(i as f64 / per_decade);
                (tau, gamma / per_decade)
            })
            .collect(),
        CreepLaw::Logarithmic => {
            let t0 = config.onset_time_s;
            let step = std::f64::consts::LN_10 / per_decade;
            let shortest = t0 / 40.0;
            let mut out = Vec::new();
            let mut tau = config.longest_time_constant_s;
            while tau >= shortest {
                let weight = gamma / std::f64::consts::LN_10 * step * (-t0 / tau).exp();
                out.push((tau, weight));
                tau /= 10f64.powf(1.0 / per_decade);
            }
            out.reverse();
            out
        }
    }
}

impl Creep {
    pub(crate) fn new(config: &CreepConfig, period_s: f64) -> Self {
        let elements = elements(config);
        Creep {
            weights: elements.iter().map(|e| e.1).collect(),
            gains: elements
                .iter()
                .map(|e| 1.0 - (-period_s / e.0).exp())
                .collect(),
            states: vec![0.0; elements.len()],
        }
    }

    /// Back to fully relaxed.
    pub(crate) fn reset(&mut self) {
        self.states.iter_mut().for_each(|z| *z = 0.0);
    }

    /// Holds `x_um` for one sample; returns the displacement with creep at its end.
    pub(crate) fn step(&mut self, x_um: f64) -> f64 {
        let mut out = x_um;
        for ((z, g), w) in self.states.iter_mut().zip(&self.gains).zip(&self.weights) {
            *z += g * (x_um - *z);
            out += w * *z;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logarithmic_law_follows_the_literal_logarithm_from_milliseconds_to_hours() {
        for per_decade in [3, 4, 6] {
            let config = CreepConfig {
                elements_per_decade: per_decade,
                ..CreepConfig::default()
            };
            let gamma = config.percent_per_decade / 100.0;
            let t0 = config.onset_time_s;
            let e = elements(&config);
            for k in 0..=70 {
                let t = 1e-3 * 10f64.powf(k as f64 / 10.0);
                let bank: f64 = e.iter().map(|(tau, w)| w * (1.0 - (-t / tau).exp())).sum();
                let literal = gamma * (1.0 + t / t0).log10();
                let tolerance = if per_decade >= 4 { 2e-3 } else { 2e-2 };
                assert!(
                    (bank - literal).abs() <= tolerance * literal,
                    "{per_decade}/decade, t = {t} s: {bank} vs {literal}"
                );
            }
        }
    }
}
