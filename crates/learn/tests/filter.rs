//! The frequency-domain learning filter against a plain reference: the same weights applied by
//! a literal DFT sum, on many seeded random records, periodic and finite.

use std::f64::consts::PI;

use hystcomp_learn::LearningFilter;
use hystcomp_learn::filter::q_response;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `Q L e` by the literal sums: zero-pad by `pad`, DFT, weigh, inverse DFT.
fn reference(
    e: &[f64],
    pad: usize,
    fs: f64,
    gamma: f64,
    fc: f64,
    order: usize,
    lead: usize,
) -> Vec<f64> {
    let n = e.len();
    let m = n + 2 * pad;
    let mut x = vec![0.0; m];
    x[pad..pad + n].copy_from_slice(e);
    let mut spectrum = vec![(0.0, 0.0); m];
    for (h, s) in spectrum.iter_mut().enumerate() {
        let (mut re, mut im) = (0.0, 0.0);
        for (k, v) in x.iter().enumerate() {
            let a = -2.0 * PI * (h * k) as f64 / m as f64;
            re += v * a.cos();
            im += v * a.sin();
        }
        let f = h.min(m - h) as f64 * fs / m as f64;
        let w = gamma * q_response(f, fc, order);
        let phase = 2.0 * PI * (h * lead) as f64 / m as f64;
        let (c, s_) = (w * phase.cos(), w * phase.sin());
        *s = (re * c - im * s_, re * s_ + im * c);
    }
    (pad..pad + n)
        .map(|k| {
            spectrum
                .iter()
                .enumerate()
                .map(|(h, (re, im))| {
                    let a = 2.0 * PI * (h * k) as f64 / m as f64;
                    re * a.cos() - im * a.sin()
                })
                .sum::<f64>()
                / m as f64
        })
        .collect()
}

#[test]
fn filter_matches_the_literal_dft_on_random_records() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for case in 0..60 {
        let n = rng.random_range(2..80usize);
        let periodic = case % 2 == 0;
        let fs = 1000.0;
        let fc = rng.random_range(5.0..500.0);
        let order = rng.random_range(1..5usize);
        let gamma = rng.random_range(0.1..2.0);
        let lead = rng.random_range(0..n.min(4));
        let e: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut filter = LearningFilter::new(n, periodic, fs, gamma, fc, order, lead);
        let mut out = vec![0.0; n];
        filter.apply(&e, &mut out);
        let expected = reference(&e, filter.padding(), fs, gamma, fc, order, lead);
        for (k, (a, b)) in out.iter().zip(&expected).enumerate() {
            assert!(
                (a - b).abs() < 1e-9,
                "case {case} (n {n}, periodic {periodic}) sample {k}: {a} vs {b}"
            );
        }
    }
}

/// A finite record's padding is long enough that nothing wraps around: doubling it changes
/// the result by less than 1e-3 of the input's size.
#[test]
fn finite_padding_keeps_the_tail_from_wrapping() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..10 {
        let n = rng.random_range(200..400usize);
        let fc = rng.random_range(20.0..200.0);
        let order = rng.random_range(1..5usize);
        let e: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut filter = LearningFilter::new(n, false, 1000.0, 1.0, fc, order, 0);
        let mut out = vec![0.0; n];
        filter.apply(&e, &mut out);
        let longer = reference(&e, 2 * filter.padding().max(1), 1000.0, 1.0, fc, order, 0);
        let worst = out
            .iter()
            .zip(&longer)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-3,
            "padding {} too short: {worst}",
            filter.padding()
        );
    }
}

/// A periodic record's constant passes with the gain (Q(0) = 1) and a lead advances it.
#[test]
fn constant_passes_with_the_gain_and_lead_advances() {
    let mut filter = LearningFilter::new(64, true, 1000.0, 0.7, 400.0, 2, 0);
    let mut out = vec![0.0; 64];
    filter.apply(&[2.0; 64], &mut out);
    assert!(out.iter().all(|v| (v - 1.4).abs() < 1e-12));
    // A slow sine (below the cut-off) advanced by 3 samples.
    let n = 200;
    let e: Vec<f64> = (0..n)
        .map(|k| (2.0 * PI * k as f64 / n as f64).sin())
        .collect();
    let mut filter = LearningFilter::new(n, true, 1000.0, 1.0, 400.0, 4, 3);
    let mut out = vec![0.0; n];
    filter.apply(&e, &mut out);
    for k in 0..n {
        assert!((out[k] - e[(k + 3) % n]).abs() < 1e-9);
    }
}
