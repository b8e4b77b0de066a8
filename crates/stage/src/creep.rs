//! Creep: a bank of first-order (Kelvin-Voigt) elements in cascade after the hysteresis, as in
//! the hysteresis -> creep -> vibration model of Croft, Shed & Devasia (2001).

use crate::config::CreepConfig;

/// `x_out = x + sum_i w_i z_i`, `tau_i dz_i/dt = x - z_i`, discretised exactly for an input held
/// over each sample. Log-spaced time constants with equal weights approximate the logarithmic
/// creep law `x(t) = x_0 (1 + gamma log10(t / t_0))` between the shortest and the longest time
/// constant (each decade holds `elements_per_decade` elements of weight `gamma /
/// elements_per_decade`, whose summed step responses rise by `gamma` per decade).
#[derive(Debug, Clone)]
pub(crate) struct Creep {
    weights: Vec<f64>,
    gains: Vec<f64>,
    states: Vec<f64>,
}

impl Creep {
    pub(crate) fn new(config: &CreepConfig, period_s: f64) -> Self {
        let mut creep = Creep {
            weights: Vec::new(),
            gains: Vec::new(),
            states: Vec::new(),
        };
        if config.percent_per_decade > 0.0 {
            let per_decade = config.elements_per_decade;
            let weight = config.percent_per_decade / 100.0 / per_decade as f64;
            for i in 0..=config.decades * per_decade {
                let tau = config.first_time_constant_s * 10f64.powf(i as f64 / per_decade as f64);
                creep.weights.push(weight);
                creep.gains.push(1.0 - (-period_s / tau).exp());
                creep.states.push(0.0);
            }
        }
        creep
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
