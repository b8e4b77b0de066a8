//! Shared by the core's integration tests: the paper's tables, seeded random models and inputs,
//! and plain reference implementations (the oracles the fast paths are checked against).
#![allow(dead_code)]

pub mod invariants;

use hystcomp_core::{Mpim, OutputLimits, paper};
use proptest::test_runner::{Config, RngSeed};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Table 1 of the paper (plant model for IHC and WIHC).
pub const TABLE1_R: [f64; 10] = paper::TABLE1.thresholds;
pub const TABLE1_B: [f64; 10] = paper::TABLE1.weights;
pub const TABLE1_A1: f64 = paper::TABLE1.a1;
pub const TABLE1_A2: f64 = paper::TABLE1.a2;

/// Table 2 of the paper (inverse model for DIHC).
pub const TABLE2_B: [f64; 10] = paper::TABLE2.weights;
pub const TABLE2_A1: f64 = paper::TABLE2.a1;
pub const TABLE2_A2: f64 = paper::TABLE2.a2;

pub type VecMpim = Mpim<f64, Vec<f64>>;

pub fn table1() -> VecMpim {
    Mpim::new(&TABLE1_R, &TABLE1_B, TABLE1_A1, TABLE1_A2).unwrap()
}

pub fn table2() -> VecMpim {
    Mpim::new(&TABLE1_R, &TABLE2_B, TABLE2_A1, TABLE2_A2).unwrap()
}

pub fn unit_limits() -> OutputLimits<f64> {
    OutputLimits::new(0.0, 1.0).unwrap()
}

/// A fixed-seed proptest configuration: reproducible on every machine, no persistence files.
pub fn seeded(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A random model with `n` operators, thresholds `(i - 1)/n` (eq. (11)) or random increasing
/// ones, weights of both signs; not necessarily invertible.
pub fn random_model(rng: &mut impl Rng, n: usize) -> VecMpim {
    let uniform_thresholds = rng.random::<bool>();
    let mut thresholds: Vec<f64> = if uniform_thresholds {
        (0..n).map(|i| i as f64 / n as f64).collect()
    } else {
        let mut t: Vec<f64> = (0..n).map(|_| rng.random::<f64>() * 0.95).collect();
        t.sort_by(f64::total_cmp);
        t
    };
    if rng.random::<f64>() < 0.7 && n > 0 {
        thresholds[0] = 0.0;
    }
    let weights: Vec<f64> = (0..n)
        .map(|_| rng.random::<f64>() * 0.8 / n as f64 * 5.0 - 0.15 * rng.random::<f64>())
        .collect();
    let a1 = rng.random::<f64>() * 0.8 - 0.4;
    let a2 = rng.random::<f64>() * 1.2 + 0.05;
    Mpim::new(&thresholds, &weights, a1, a2).unwrap()
}

/// A random model with `n` operators whose weights scale with `1 / n` (both signs), so that
/// models of 100 operators are as varied as models of 10: thresholds as [`random_model`],
/// weights `(4 u - 0.75 u') / n`.
pub fn random_scaled_model(rng: &mut impl Rng, n: usize) -> VecMpim {
    let m = random_model(rng, n);
    let weights: Vec<f64> = (0..n)
        .map(|_| (4.0 * rng.random::<f64>() - 0.75 * rng.random::<f64>()) / n.max(1) as f64)
        .collect();
    Mpim::new(m.thresholds(), &weights, m.a1(), m.a2()).unwrap()
}

/// A random model of [`random_scaled_model`] that is invertible on [0, 1] with a smallest
/// slope of at least 0.02 and whose PI part has an inverse (eq. (7)); any `n` up to hundreds.
pub fn random_invertible_scaled_model(rng: &mut impl Rng, n: usize) -> VecMpim {
    loop {
        let m = random_scaled_model(rng, n);
        if m.check_invertible(0.0, 1.0).is_ok()
            && m.min_branch_slope(0.0, 1.0).unwrap().slope > 0.02
            && m.pi_part_inverse().is_ok()
        {
            return m;
        }
    }
}

/// A random model that is invertible on [0, 1] and whose PI part has an inverse (eq. (7)).
pub fn random_invertible_model(rng: &mut impl Rng, n: usize) -> VecMpim {
    loop {
        let m = random_model(rng, n);
        if m.check_invertible(0.0, 1.0).is_ok()
            && m.min_branch_slope(0.0, 1.0).unwrap().slope > 0.02
            && m.pi_part_inverse().is_ok()
        {
            return m;
        }
    }
}

/// A random input in `[lo, hi]`: a random walk with occasional jumps and reversals, so that
/// minor loops of every size appear.
pub fn random_input(rng: &mut impl Rng, len: usize, lo: f64, hi: f64) -> Vec<f64> {
    let mut x = lo + (hi - lo) * rng.random::<f64>();
    let mut direction = 1.0;
    (0..len)
        .map(|_| {
            let u: f64 = rng.random();
            if u < 0.05 {
                x = lo + (hi - lo) * rng.random::<f64>();
            } else {
                if u < 0.15 {
                    direction = -direction;
                }
                x += direction * (hi - lo) * 0.02 * rng.random::<f64>();
            }
            x = x.clamp(lo, hi);
            x
        })
        .collect()
}

/// The literal play operator of eqs. (1)-(2): `F_r[x](t) = f_r(x(t), F_r[x](t_i))` where `t_i`
/// is the last turning point of the (linearly interpolated, hence piecewise monotone) input
/// before `t`, and `f_r(v, w) = max(v - r, min(v, w))`. Memory is taken only at turning points.
pub fn literal_one_sided_play(r: f64, x: &[f64], initial_memory: f64) -> Vec<f64> {
    let f = |v: f64, w: f64| (v - r).max(v.min(w));
    let mut out = Vec::with_capacity(x.len());
    if x.is_empty() {
        return out;
    }
    // F(t_0) = f_r(x(t_0), w0), eq. (1).
    let mut at_turn = f(x[0], initial_memory);
    out.push(at_turn);
    let mut last_direction = 0.0f64;
    for k in 1..x.len() {
        let direction = (x[k] - x[k - 1]).signum();
        if x[k] != x[k - 1] && last_direction != 0.0 && direction != last_direction {
            // x[k-1] was a turning point: its output becomes the memory.
            at_turn = out[k - 1];
        }
        if x[k] != x[k - 1] {
            last_direction = direction;
        }
        out.push(f(x[k], at_turn));
    }
    out
}

/// The model output for input `x` by the literal operators, from zero memory.
pub fn literal_mpim(model: &VecMpim, x: &[f64]) -> Vec<f64> {
    let mut y: Vec<f64> = x
        .iter()
        .map(|&v| model.a1() * v * v * v + model.a2() * v)
        .collect();
    for (&r, &b) in model.thresholds().iter().zip(model.weights()) {
        for (yk, fk) in y.iter_mut().zip(literal_one_sided_play(r, x, 0.0)) {
            *yk += b * fk;
        }
    }
    y
}

/// The plain bisection inverse: the `v` in `[lo, hi]` where the plant's current branch gives
/// `y_d` (the nearest limit when out of reach), 200 halvings.
pub fn bisection_inverse(plant: &VecMpim, desired: f64, limits: OutputLimits<f64>) -> f64 {
    let (mut lo, mut hi) = (limits.min(), limits.max());
    if plant.branch_output(lo) >= desired {
        return lo;
    }
    if plant.branch_output(hi) <= desired {
        return hi;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if plant.branch_output(mid) < desired {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A random model whose delayed WIHC loop gain `|3 a1 x^2 + b_1 + ... + b_k| / a2` is at most
/// `gain` (< 1) for every `k` and `|x| <= sqrt(2)`: `a2 = (6 |a1| + sum |b_i|) / gain`. Such a
/// model is also invertible there (every branch slope is at least `a2 (1 - gain)`) and so is
/// its PI part, so every compensator can be built from it with limits inside `[-1.4, 1.4]`.
pub fn random_model_with_gain_below(rng: &mut impl Rng, n: usize, gain: f64) -> VecMpim {
    let m = random_model(rng, n);
    let spread = 6.0 * m.a1().abs() + m.weights().iter().map(|b| b.abs()).sum::<f64>();
    let a2 = spread.max(1e-3) / gain;
    Mpim::new(m.thresholds(), m.weights(), m.a1(), a2).unwrap()
}

/// The largest `|3 a1 x^2 + b_1 + ... + b_k| / a2` over a dense grid of the (x, k) reachable from
/// the reset state within `[min(lo, 0), max(hi, 0)]`: operator `k` moves at `x` only after the
/// input travelled `r_k` from a reversal, so `x >= lo + r_k` or `x <= max(hi - r_k, 0)`.
pub fn grid_delayed_loop_gain(model: &VecMpim, lo: f64, hi: f64) -> f64 {
    let (lo, hi) = (lo.min(0.0), hi.max(0.0));
    let (r, b) = (model.thresholds(), model.weights());
    let always = r.iter().take_while(|r| **r <= 0.0).count();
    let mut worst: f64 = 0.0;
    for k in always..=r.len() {
        let rk = if k == 0 { 0.0 } else { r[k - 1] };
        let prefix: f64 = b[..k].iter().sum();
        let mut xs: Vec<f64> = (0..=4000)
            .map(|i| lo + (hi - lo) * i as f64 / 4000.0)
            .collect();
        xs.extend([lo, hi, lo + rk, (hi - rk).max(0.0), 0.0]);
        for x in xs {
            let reachable = x >= lo && x <= hi && (x >= lo + rk || x <= (hi - rk).max(0.0));
            if reachable {
                let g = (3.0 * model.a1() * x * x + prefix).abs() / model.a2();
                worst = worst.max(g);
            }
        }
    }
    worst
}

/// `g'(x) = sum_j j c_j x^(j - 1)` from the coefficients `[c_1, ..., c_D]`, term by term.
pub fn plain_slope(coefficients: &[f64], x: f64) -> f64 {
    coefficients
        .iter()
        .enumerate()
        .map(|(i, c)| (i + 1) as f64 * c * x.powi(i as i32))
        .sum()
}

/// `g(x) = sum_j c_j x^j`, term by term.
pub fn plain_value(coefficients: &[f64], x: f64) -> f64 {
    coefficients
        .iter()
        .enumerate()
        .map(|(i, c)| c * x.powi(i as i32 + 1))
        .sum()
}

/// The reachable `(k, x)` of a dense grid (4001 points plus the ends and the operators' edges):
/// operator `k` moves at `x` only after the input travelled `r_k` from a reversal, so
/// `x >= lo + r_k` or `x <= max(hi - r_k, 0)`, within `[min(lo, 0), max(hi, 0)]`. Calls
/// `visit(k, x, b_1 + ... + b_k)`.
pub fn grid_reachable(model: &VecMpim, lo: f64, hi: f64, mut visit: impl FnMut(usize, f64, f64)) {
    let (lo, hi) = (lo.min(0.0), hi.max(0.0));
    let (r, b) = (model.thresholds(), model.weights());
    let always = r.iter().take_while(|r| **r <= 0.0).count();
    for k in always..=r.len() {
        let rk = if k == 0 { 0.0 } else { r[k - 1] };
        let prefix: f64 = b[..k].iter().sum();
        let mut xs: Vec<f64> = (0..=4000)
            .map(|i| lo + (hi - lo) * i as f64 / 4000.0)
            .collect();
        xs.extend([lo, hi, lo + rk, (hi - rk).max(0.0), 0.0]);
        for x in xs {
            if x >= lo && x <= hi && (x >= lo + rk || x <= (hi - rk).max(0.0)) {
                visit(k, x, prefix);
            }
        }
    }
}

/// The delayed loops' largest gains over the grid of [`grid_reachable`]: IHC
/// `|g'(x) - a2| / (a2 + b_1 + ... + b_k)` and WIHC `|g'(x) - a2 + b_1 + ... + b_k| / a2`, with
/// `g'` evaluated term by term. The IHC's is NaN when the PI part's slope
/// `a2 + b_1 + ... + b_k` is zero or negative on a reachable branch: eq. (7) has no inverse
/// there (the branch passes through x = 0, where the model's slope is that very sum, so the
/// model is not invertible either) and no IHC is built from it.
pub fn grid_loop_gains(model: &VecMpim, lo: f64, hi: f64) -> (f64, f64) {
    let c = model.input_polynomial().coefficients().to_vec();
    let a2 = model.a2();
    let (mut ihc, mut wihc) = (0.0f64, 0.0f64);
    let mut pi_part_increases = true;
    grid_reachable(model, lo, hi, |_, x, prefix| {
        let h = plain_slope(&c, x) - a2;
        pi_part_increases &= a2 + prefix > 0.0;
        ihc = ihc.max(h.abs() / (a2 + prefix));
        wihc = wihc.max((h + prefix).abs() / a2);
    });
    (if pi_part_increases { ihc } else { f64::NAN }, wihc)
}

/// The smallest branch slope `g'(x) + b_1 + ... + b_k` over the grid of [`grid_reachable`].
pub fn grid_min_slope(model: &VecMpim, lo: f64, hi: f64) -> f64 {
    let c = model.input_polynomial().coefficients().to_vec();
    let mut worst = f64::INFINITY;
    grid_reachable(model, lo, hi, |_, x, prefix| {
        worst = worst.min(plain_slope(&c, x) + prefix);
    });
    worst
}

/// A random model with `n` operators and an input polynomial of `degree` (1 to 9) with
/// coefficients of both signs (the extremes of `g'` then often lie inside the range);
/// invertible on [0, 1] with a smallest slope of at least 0.02 and an invertible PI part. It
/// starts from a random invertible cubic model and adds the other powers, halving them until
/// the model is invertible (so it always ends).
pub fn random_polynomial_model(rng: &mut impl Rng, n: usize, degree: usize) -> VecMpim {
    let base = random_invertible_scaled_model(rng, n);
    let extra: Vec<f64> = (0..degree)
        .map(|j| (rng.random::<f64>() * 2.0 - 1.0) * 1.5 / (j + 1) as f64)
        .collect();
    let mut amplitude = 1.0;
    loop {
        let mut c: Vec<f64> = vec![0.0; degree];
        for (j, cj) in c.iter_mut().enumerate() {
            *cj = match j {
                0 => base.a2(),
                2 => base.a1() + amplitude * extra[2],
                _ => amplitude * extra[j],
            };
        }
        if degree < 3 {
            // No cubic term: the base's a1 is dropped; keep the slope positive with a2.
            c[0] = base.a2() + 3.0 * base.a1().abs();
        }
        let input = hystcomp_core::InputPolynomial::new(&c).unwrap();
        let model = Mpim::with_input_polynomial(base.thresholds(), base.weights(), input).unwrap();
        if model.check_invertible(0.0, 1.0).is_ok()
            && model.min_branch_slope(0.0, 1.0).unwrap().slope > 0.02
            && model.pi_part_inverse().is_ok()
        {
            return model;
        }
        amplitude *= 0.5;
        if amplitude < 1e-6 {
            return base;
        }
    }
}

/// The plain bisection inverse of a model whose branch is given by `branch` (the model's
/// output for input `v` from a fixed state), over `[lo, hi]`.
pub fn bisect_branch(branch: impl Fn(f64) -> f64, desired: f64, lo: f64, hi: f64) -> f64 {
    let (mut lo, mut hi) = (lo, hi);
    if branch(lo) >= desired {
        return lo;
    }
    if branch(hi) <= desired {
        return hi;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if branch(mid) < desired {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
