//! A Preisach model with a smooth, asymmetric density, evaluated in O(1) amortised time per
//! sample with the memory of dominant extrema (the wiping-out property) and the Everett
//! function (Mayergoyz, "Mathematical Models of Hysteresis", 1991).

use super::RateIndependentHysteresis;
use crate::config::PreisachConfig;
use crate::error::StageError;

/// Most turning points kept. Deeper nesting (more than 128 ever-narrower loops inside each
/// other) forgets the innermost loop, which changes the output by less than that loop's width.
const MAX_TURNS: usize = 256;

/// A turning point of the input and the (normalised) irreversible output at it.
#[derive(Debug, Clone, Copy)]
struct Turn {
    value: f64,
    output: f64,
}

/// A Preisach model `x = stroke (R(u) + sum of the relays that are on)` of the normalised
/// voltage `u` in `[0, 1]` (see [`PreisachConfig`] for the density).
///
/// Relays `(alpha, beta)`, `0 <= beta <= alpha <= 1`, switch on when `u >= alpha` and off when
/// `u <= beta`; all are off at rest (0 V). The state is the stack of dominant extrema
/// `M_1 > M_2 > ...` and `m_1 < m_2 < ...`; with the Everett function
/// `E(alpha, beta)` = mass of the relays in the triangle `beta <= beta' <= alpha' <= alpha`,
/// the output on an ascending branch from the last minimum `m` is `y(m) + E(u, m)` and on a
/// descending branch from the last maximum `M` it is `y(M) - E(M, u)`; an input that passes
/// the previous extremum of its direction wipes out the pair of extrema it closes.
///
/// `E` is tabulated once on a `grid_cells`-by-`grid_cells` grid in `(beta, alpha - beta)`
/// (so that `E(u, u) = 0` exactly) by 3 x 3 Gauss-Legendre cell integrals and inclusion-exclusion,
/// and read by bilinear interpolation.
#[derive(Debug, Clone)]
pub struct PreisachHysteresis {
    stroke_um: f64,
    low_v: f64,
    span_v: f64,
    reversible_fraction: f64,
    reversible_curvature: f64,
    cells: usize,
    /// `E(min((j + k) h, 1), j h)` at `j * (cells + 1) + k`, normalised so that `E(1, 0) =
    /// 1 - reversible_fraction`.
    everett: Vec<f64>,
    turns: Vec<Turn>,
    input: f64,
}

/// The relay density up to a constant factor.
fn density(config: &PreisachConfig, alpha: f64, beta: f64) -> f64 {
    let width = (alpha - beta) / config.relay_width_sd;
    (-0.5 * width * width).exp() * (1.0 + config.density_tilt * (alpha + beta - 1.0))
}

/// Gauss-Legendre nodes and weights on `[0, 1]`.
const GAUSS: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

impl PreisachHysteresis {
    /// Builds the model and its Everett table (`(grid_cells + 1)^2` values).
    pub fn new(config: &PreisachConfig) -> Result<PreisachHysteresis, StageError> {
        config.validate()?;
        let n = config.grid_cells as usize;
        let h = 1.0 / n as f64;
        let side = n + 1;
        // E on the (alpha index i, beta index j) grid, zero for i <= j.
        let mut e = vec![0.0; side * side];
        let at = |i: usize, j: usize| i * side + j;
        for d in 1..=n {
            for j in 0..=(n - d) {
                let i = j + d;
                let cell = if d == 1 {
                    // Triangle alpha' in [x_j, x_j+1], beta' in [x_j, alpha'].
                    let mut sum = 0.0;
                    for &(s, ws) in &GAUSS {
                        for &(t, wt) in &GAUSS {
                            let alpha = (j as f64 + s) * h;
                            let beta = (j as f64 + s * t) * h;
                            sum += ws * wt * s * density(config, alpha, beta);
                        }
                    }
                    sum * h * h
                } else {
                    let mut sum = 0.0;
                    for &(s, ws) in &GAUSS {
                        for &(t, wt) in &GAUSS {
                            let alpha = (i as f64 - 1.0 + s) * h;
                            let beta = (j as f64 + t) * h;
                            sum += ws * wt * density(config, alpha, beta);
                        }
                    }
                    sum * h * h
                };
                e[at(i, j)] = e[at(i, j + 1)] + e[at(i - 1, j)] - e[at(i - 1, j + 1)] + cell;
            }
        }
        let scale = (1.0 - config.reversible_fraction) / e[at(n, 0)];
        let mut everett = vec![0.0; side * side];
        for j in 0..=n {
            for k in 0..=n {
                everett[j * side + k] = e[at((j + k).min(n), j)] * scale;
            }
        }
        Ok(PreisachHysteresis {
            stroke_um: config.stroke_um,
            low_v: config.voltage_range_v[0],
            span_v: config.voltage_range_v[1] - config.voltage_range_v[0],
            reversible_fraction: config.reversible_fraction,
            reversible_curvature: config.reversible_curvature,
            cells: n,
            everett,
            turns: Vec::with_capacity(MAX_TURNS),
            input: 0.0,
        })
    }

    /// The normalised input of a voltage, clamped to `[0, 1]`.
    pub fn normalised_input(&self, voltage_v: f64) -> f64 {
        ((voltage_v - self.low_v) / self.span_v).clamp(0.0, 1.0)
    }

    /// The Everett function `E(alpha, beta)`, `0 <= beta <= alpha <= 1`, normalised so that
    /// `E(1, 0) = 1 - reversible_fraction`.
    pub fn everett(&self, alpha: f64, beta: f64) -> f64 {
        let n = self.cells;
        let b = beta * n as f64;
        let d = (alpha - beta).max(0.0) * n as f64;
        let j = (b as usize).min(n - 1);
        let k = (d as usize).min(n - 1);
        let fb = b - j as f64;
        let fd = d - k as f64;
        let row = j * (n + 1) + k;
        let t = &self.everett;
        let lower = t[row] + (t[row + 1] - t[row]) * fd;
        let upper = t[row + n + 1] + (t[row + n + 2] - t[row + n + 1]) * fd;
        lower + (upper - lower) * fb
    }

    /// Number of turning points held in the memory of dominant extrema.
    pub fn memory_depth(&self) -> usize {
        self.turns.len()
    }

    fn reversible(&self, u: f64) -> f64 {
        self.reversible_fraction * (u + self.reversible_curvature * (u * u - u))
    }

    /// The irreversible (relay) part at the current input.
    fn irreversible(&self) -> f64 {
        let u = self.input;
        match self.turns.last() {
            None => self.everett(u, 0.0),
            Some(last) if self.turns.len().is_multiple_of(2) => {
                last.output + self.everett(u, last.value)
            }
            Some(last) => last.output - self.everett(last.value, u),
        }
    }

    fn push(&mut self, value: f64) {
        if self.turns.len() >= MAX_TURNS {
            self.turns.truncate(self.turns.len() - 2);
        }
        // The output at the turning point: the input is still there.
        let saved = self.input;
        self.input = value;
        let output = self.irreversible();
        self.input = saved;
        self.turns.push(Turn { value, output });
    }

    fn update(&mut self, u: f64) {
        let previous = self.input;
        if u == previous {
            return;
        }
        let ascending = self.turns.len().is_multiple_of(2);
        // A reversal: the previous input becomes a turning point.
        if (ascending && u < previous) || (!ascending && u > previous) {
            self.push(previous);
        }
        self.input = u;
        // Wipe out the extrema the input has passed.
        loop {
            let len = self.turns.len();
            let wiped = if len == 0 {
                false
            } else if len.is_multiple_of(2) {
                u >= self.turns[len - 2].value
            } else if len == 1 {
                u <= 0.0
            } else {
                u <= self.turns[len - 2].value
            };
            if !wiped {
                break;
            }
            self.turns.truncate(len.saturating_sub(2));
        }
    }
}

impl RateIndependentHysteresis for PreisachHysteresis {
    fn displacement_um(&mut self, voltage_v: f64) -> f64 {
        if voltage_v.is_finite() {
            let u = self.normalised_input(voltage_v);
            self.update(u);
        }
        self.stroke_um * (self.reversible(self.input) + self.irreversible())
    }

    fn reset(&mut self) {
        self.turns.clear();
        self.input = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The plain, obviously correct model: a grid of relays at cell centres, each switched by
    /// the literal rule, weighted by the density. The test oracle of the fast path.
    struct RelayGrid {
        relays: Vec<(f64, f64, f64, bool)>,
        total: f64,
    }

    impl RelayGrid {
        fn new(config: &PreisachConfig, m: usize) -> Self {
            let h = 1.0 / m as f64;
            let mut relays = Vec::new();
            for i in 0..m {
                for j in 0..=i {
                    let (alpha, beta, area) = if i == j {
                        // Triangle: centroid and half the area.
                        (
                            (i as f64 + 2.0 / 3.0) * h,
                            (j as f64 + 1.0 / 3.0) * h,
                            0.5 * h * h,
                        )
                    } else {
                        ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h, h * h)
                    };
                    relays.push((alpha, beta, density(config, alpha, beta) * area, false));
                }
            }
            let total = relays.iter().map(|r| r.2).sum();
            RelayGrid { relays, total }
        }

        fn output(&mut self, u: f64) -> f64 {
            let mut on = 0.0;
            for relay in &mut self.relays {
                if u >= relay.0 {
                    relay.3 = true;
                } else if u <= relay.1 {
                    relay.3 = false;
                }
                if relay.3 {
                    on += relay.2;
                }
            }
            on / self.total
        }
    }

    fn random_path(rng: &mut ChaCha8Rng, turns: usize, per_leg: usize) -> Vec<f64> {
        let mut path = Vec::new();
        let mut x = 0.0;
        for _ in 0..turns {
            let next: f64 = rng.random();
            for k in 1..=per_leg {
                path.push(x + (next - x) * k as f64 / per_leg as f64);
            }
            x = next;
        }
        path
    }

    #[test]
    fn everett_memory_matches_a_brute_force_relay_grid_on_random_inputs() {
        let config = PreisachConfig {
            reversible_fraction: 0.0,
            stroke_um: 1.0,
            ..PreisachConfig::default()
        };
        let mut fast = PreisachHysteresis::new(&config).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..3 {
            fast.reset();
            let mut slow = RelayGrid::new(&config, 300);
            let mut worst: f64 = 0.0;
            for u in random_path(&mut rng, 25, 12) {
                let a = fast.displacement_um(u * 150.0);
                let b = slow.output(u);
                worst = worst.max((a - b).abs());
            }
            // The relay grid is a midpoint discretisation with cells of 1/300.
            assert!(worst < 5e-3, "largest difference {worst}");
        }
    }

    #[test]
    fn output_depends_on_the_input_values_only_not_on_their_timing() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let config = PreisachConfig::default();
        let mut coarse = PreisachHysteresis::new(&config).unwrap();
        let mut fine = PreisachHysteresis::new(&config).unwrap();
        let mut x = 0.0;
        for _ in 0..200 {
            let next = 150.0 * rng.random::<f64>();
            let a = coarse.displacement_um(next);
            let mut b = 0.0;
            for k in 1..=37 {
                b = fine.displacement_um(x + (next - x) * k as f64 / 37.0);
            }
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
            x = next;
        }
    }

    #[test]
    fn branches_are_monotone_and_continuous_and_minor_loops_close() {
        let mut p = PreisachHysteresis::new(&PreisachConfig::default()).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut previous_v = 0.0;
        let mut previous_x = p.displacement_um(0.0);
        for _ in 0..300 {
            let v = 150.0 * rng.random::<f64>();
            for k in 1..=50 {
                let vk = previous_v + (v - previous_v) * k as f64 / 50.0;
                let x = p.displacement_um(vk);
                let step = x - previous_x;
                // Same sign as the voltage step, and bounded by it (Lipschitz: no jumps; the
                // steepest branch of the default loop is about 0.6 um/V).
                let dv = (v - previous_v) / 50.0;
                assert!(step * dv >= -1e-12, "not monotone");
                assert!(
                    step.abs() <= 1.0 * dv.abs() + 1e-9,
                    "jump of {step} um for {dv} V"
                );
                previous_x = x;
            }
            previous_v = v;
            assert!(p.memory_depth() <= 2 * 300);
        }
        // Return-point memory (wiping out): an excursion against the direction the input
        // arrived from, not past the point it came from, and back, leaves no trace: same
        // output, same future.
        for _ in 0..100 {
            let v1 = 150.0 * rng.random::<f64>();
            let start = p.displacement_um(v1);
            let r: f64 = rng.random();
            let v2 = v1 + (previous_v - v1) * r;
            let mut untouched = p.clone();
            p.displacement_um(v2);
            assert_eq!(p.displacement_um(v1), start);
            for _ in 0..5 {
                let v = 150.0 * rng.random::<f64>();
                assert_eq!(p.displacement_um(v), untouched.displacement_um(v));
            }
            previous_v = untouched.input * 150.0;
        }
    }

    #[test]
    fn full_cycle_from_rest_reaches_the_stroke_and_returns_to_zero() {
        let config = PreisachConfig::default();
        let mut p = PreisachHysteresis::new(&config).unwrap();
        assert_eq!(p.displacement_um(0.0), 0.0);
        let top = p.displacement_um(150.0);
        assert!((top - config.stroke_um).abs() < 1e-9, "{top}");
        assert!(p.displacement_um(0.0).abs() < 1e-12);
        assert_eq!(p.memory_depth(), 0);
    }
}
