//! The flexure stage's first resonance, discretised exactly (zero-order hold) at the sample rate.

use crate::config::MechanicsConfig;

/// `x'' + 2 zeta w x' + w^2 x = w^2 u`: state `(x, x')`, `s[k+1] = Phi s[k] + Gamma u[k]` with
/// `Phi = e^(A T)` and `Gamma = int_0^T e^(A s) B ds`, both read off the exponential of the
/// augmented matrix `[[A, B], [0, 0]] T` (Van Loan's construction). The discrete poles are
/// exactly `e^(p T)` for the continuous poles `p`, whatever the damping.
#[derive(Debug, Clone)]
pub(crate) struct Mechanics {
    phi: [[f64; 2]; 2],
    gamma: [f64; 2],
    state: [f64; 2],
}

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// `e^M` by scaling and squaring with a Taylor series (accurate to rounding for the small
/// matrices met here: the series runs until its terms vanish).
pub(crate) fn expm3(m: &M3) -> M3 {
    let norm = m
        .iter()
        .map(|row| row.iter().map(|x| x.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let squarings = if norm > 0.5 {
        (norm / 0.5).log2().ceil() as u32
    } else {
        0
    };
    let scale = 0.5f64.powi(squarings as i32);
    let a: M3 = m.map(|row| row.map(|x| x * scale));
    let mut result: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut term = result;
    for k in 1..40 {
        term = mul(&term, &a).map(|row| row.map(|x| x / k as f64));
        result = std::array::from_fn(|i| std::array::from_fn(|j| result[i][j] + term[i][j]));
        if term.iter().flatten().all(|x| x.abs() < 1e-18) {
            break;
        }
    }
    for _ in 0..squarings {
        result = mul(&result, &result);
    }
    result
}

impl Mechanics {
    pub(crate) fn new(config: &MechanicsConfig, period_s: f64) -> Self {
        if config.rigid {
            // x[k+1] = u[k]: the position follows the free displacement, no resonance.
            return Mechanics {
                phi: [[0.0, 0.0], [0.0, 0.0]],
                gamma: [1.0, 0.0],
                state: [0.0, 0.0],
            };
        }
        let w = 2.0 * std::f64::consts::PI * config.resonance_hz;
        let z = config.damping_ratio;
        let t = period_s;
        let m: M3 = [
            [0.0, t, 0.0],
            [-w * w * t, -2.0 * z * w * t, w * w * t],
            [0.0, 0.0, 0.0],
        ];
        let e = expm3(&m);
        Mechanics {
            phi: [[e[0][0], e[0][1]], [e[1][0], e[1][1]]],
            gamma: [e[0][2], e[1][2]],
            state: [0.0, 0.0],
        }
    }

    /// Back to rest.
    pub(crate) fn reset(&mut self) {
        self.state = [0.0, 0.0];
    }

    /// Holds the free displacement `u_um` for one sample; returns the position at its end.
    pub(crate) fn step(&mut self, u_um: f64) -> f64 {
        let [x, v] = self.state;
        self.state = [
            self.phi[0][0] * x + self.phi[0][1] * v + self.gamma[0] * u_um,
            self.phi[1][0] * x + self.phi[1][1] * v + self.gamma[1] * u_um,
        ];
        self.state[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discrete_poles_are_the_exact_images_of_the_continuous_poles() {
        for (f, z) in [(800.0, 0.05), (300.0, 0.7), (1000.0, 1.0), (200.0, 3.0)] {
            let m = Mechanics::new(
                &MechanicsConfig {
                    resonance_hz: f,
                    damping_ratio: z,
                    rigid: false,
                },
                1e-4,
            );
            let w = 2.0 * std::f64::consts::PI * f;
            // trace and determinant of Phi against those of e^(pT) for the continuous poles.
            let det = m.phi[0][0] * m.phi[1][1] - m.phi[0][1] * m.phi[1][0];
            let trace = m.phi[0][0] + m.phi[1][1];
            let expected_det = (-2.0 * z * w * 1e-4).exp();
            let expected_trace = if z < 1.0 {
                2.0 * (-z * w * 1e-4).exp() * (w * (1.0 - z * z).sqrt() * 1e-4).cos()
            } else {
                2.0 * (-z * w * 1e-4).exp() * (w * (z * z - 1.0).sqrt() * 1e-4).cosh()
            };
            assert!((det - expected_det).abs() < 1e-12, "{f} {z}: {det}");
            assert!((trace - expected_trace).abs() < 1e-12, "{f} {z}: {trace}");
            // Unit DC gain: (I - Phi)^-1 Gamma has first component 1.
            let a = 1.0 - m.phi[0][0];
            let b = -m.phi[0][1];
            let c = -m.phi[1][0];
            let d = 1.0 - m.phi[1][1];
            let dc = (d * m.gamma[0] - b * m.gamma[1]) / (a * d - b * c);
            assert!((dc - 1.0).abs() < 1e-9, "{dc}");
        }
    }
}
