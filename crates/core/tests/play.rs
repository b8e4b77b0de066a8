//! The play operators against the literal definition of eqs. (1)-(2), and their properties.

mod common;

use common::*;
use hystcomp_core::{Mpim, OneSidedPlay, SymmetricPlay};
use proptest::prelude::*;
use rand::RngExt;

#[test]
fn fast_play_equals_literal_eq_1_2_on_random_inputs() {
    let mut rng = rng(1);
    for case in 0..200 {
        let r = rng.random::<f64>() * 0.6;
        let w0 = rng.random::<f64>() * 0.5;
        let x = random_input(&mut rng, 500, -0.2, 1.0);
        let reference = literal_one_sided_play(r, &x, w0);
        let mut op = OneSidedPlay::new(r, w0).unwrap();
        for (k, (&xk, &yk)) in x.iter().zip(&reference).enumerate() {
            assert_eq!(op.step(xk), yk, "case {case}, sample {k}");
        }
    }
}

#[test]
fn mpim_equals_the_literal_operators_and_a_bank_of_single_operators() {
    let mut rng = rng(2);
    for _ in 0..50 {
        let n = 1 + (rng.random::<u32>() % 20) as usize;
        let mut model = random_model(&mut rng, n);
        let x = random_input(&mut rng, 400, 0.0, 1.0);
        let literal = literal_mpim(&model, &x);
        let mut bank: Vec<OneSidedPlay<f64>> = model
            .thresholds()
            .iter()
            .map(|&r| OneSidedPlay::new(r, 0.0).unwrap())
            .collect();
        for (k, &xk) in x.iter().enumerate() {
            let branch = model.branch_output(xk);
            let y = model.step(xk);
            assert_eq!(y, branch, "branch_output must predict step");
            let by_bank = model.a1() * xk * xk * xk
                + model.a2() * xk
                + bank
                    .iter_mut()
                    .zip(model.weights())
                    .map(|(op, b)| b * op.step(xk))
                    .sum::<f64>();
            assert!((y - by_bank).abs() <= 1e-12, "sample {k}: {y} vs {by_bank}");
            assert!(
                (y - literal[k]).abs() <= 1e-12,
                "sample {k}: {y} vs {}",
                literal[k]
            );
        }
    }
}

proptest! {
    #![proptest_config(seeded(256, 3))]

    /// Rate independence: inserting samples inside monotone segments changes no output at the
    /// original samples.
    #[test]
    fn adding_samples_inside_monotone_segments_changes_nothing(
        seed in any::<u64>(),
        refine in 1usize..8,
    ) {
        let mut rng = rng(seed);
        let model = random_model(&mut rng, 8);
        let x = random_input(&mut rng, 200, 0.0, 1.0);
        let mut fine = Vec::new();
        let mut original_index = Vec::new();
        for k in 0..x.len() {
            if k > 0 {
                for j in 1..refine {
                    let s = j as f64 / refine as f64;
                    fine.push(x[k - 1] + s * (x[k] - x[k - 1]));
                }
            }
            original_index.push(fine.len());
            fine.push(x[k]);
        }
        let mut coarse_model = model.clone();
        let mut fine_model = model.clone();
        let mut coarse_y = vec![0.0; x.len()];
        let mut fine_y = vec![0.0; fine.len()];
        coarse_model.process(&x, &mut coarse_y).unwrap();
        fine_model.process(&fine, &mut fine_y).unwrap();
        for (k, &i) in original_index.iter().enumerate() {
            prop_assert!((coarse_y[k] - fine_y[i]).abs() <= 1e-12);
        }
    }

    /// Wiping out: after a minor loop inside a larger excursion, once the input passes the
    /// minor loop's reversal point again the memory is as if the minor loop never happened.
    #[test]
    fn minor_loops_are_wiped_out(
        seed in any::<u64>(),
        top in 0.5f64..1.0,
        dip in 0.05f64..0.4,
        overshoot in 0.0f64..0.3,
    ) {
        let mut rng = rng(seed);
        let model = random_model(&mut rng, 10);
        let history = random_input(&mut rng, 50, 0.0, 1.0);
        let mid = top - dip;
        let ramp = |from: f64, to: f64| -> Vec<f64> {
            (1..=50).map(|i| from + (to - from) * i as f64 / 50.0).collect()
        };
        let start = *history.last().unwrap();
        let target = (top + overshoot).min(1.0);
        // Path A: history, down to 0, up to top, down to mid (minor loop), up to target.
        let mut a = history.clone();
        a.extend(ramp(start, 0.0));
        a.extend(ramp(0.0, top));
        a.extend(ramp(top, mid));
        a.extend(ramp(mid, target));
        // Path B: the same without the minor loop.
        let mut b = history.clone();
        b.extend(ramp(start, 0.0));
        b.extend(ramp(0.0, target));
        let mut ma = model.clone();
        let mut mb = model.clone();
        let ya: Vec<f64> = a.iter().map(|&x| ma.step(x)).collect();
        let yb: Vec<f64> = b.iter().map(|&x| mb.step(x)).collect();
        prop_assert!((ya.last().unwrap() - yb.last().unwrap()).abs() <= 1e-12);
        for (wa, wb) in ma.memory().iter().zip(mb.memory()) {
            prop_assert!((wa - wb).abs() <= 1e-12);
        }
    }
}

#[test]
fn one_sided_play_output_stays_in_its_band() {
    let mut rng = rng(4);
    for _ in 0..100 {
        let r = rng.random::<f64>();
        let mut op = OneSidedPlay::new(r, 0.0).unwrap();
        for x in random_input(&mut rng, 300, -1.0, 1.0) {
            let y = op.step(x);
            assert!(y <= x && y >= x - r - 1e-15, "{y} not in [{}, {x}]", x - r);
        }
    }
}

#[test]
fn symmetric_play_equals_its_literal_definition() {
    let mut rng = rng(5);
    for _ in 0..100 {
        let r = rng.random::<f64>() * 0.3;
        let w0 = rng.random::<f64>() * 0.2 - 0.1;
        let mut op = SymmetricPlay::new(r, w0).unwrap();
        let mut w = w0;
        for x in random_input(&mut rng, 300, -1.0, 1.0) {
            // F_r[x](t) = max(x - r, min(x + r, w)): output within [x - r, x + r].
            w = (x - r).max((x + r).min(w));
            let y = op.step(x);
            assert!((y - w).abs() <= 1e-15, "{y} vs {w}");
            assert!(y >= x - r - 1e-15 && y <= x + r + 1e-15);
        }
    }
}

#[test]
fn operators_refuse_bad_parameters_and_ignore_nan_input() {
    assert!(OneSidedPlay::new(-0.1, 0.0).is_err());
    assert!(OneSidedPlay::new(f64::NAN, 0.0).is_err());
    assert!(OneSidedPlay::new(0.1, f64::INFINITY).is_err());
    assert!(SymmetricPlay::new(-1.0f32, 0.0).is_err());
    let mut op = OneSidedPlay::new(0.2, 0.0).unwrap();
    op.step(0.5);
    assert_eq!(op.step(f64::NAN), 0.3);
    let mut model = table1();
    model.step(0.4);
    let memory = model.memory().to_vec();
    assert!(model.step(f64::NAN).is_nan());
    assert_eq!(model.memory(), &memory[..], "NaN must not enter the memory");
}

#[test]
fn model_builder_refuses_each_bad_parameter_with_the_reason() {
    let r = [0.0, 0.1, 0.2];
    let b = [0.1, 0.2, 0.3];
    let err = |t: &[f64], w: &[f64], a1: f64, a2: f64| {
        Mpim::<f64, Vec<f64>>::new(t, w, a1, a2)
            .unwrap_err()
            .to_string()
    };
    assert!(err(&r, &b[..2], 0.0, 1.0).contains("weights has 2 entries but 3"));
    assert!(err(&[0.0, f64::NAN, 0.2], &b, 0.0, 1.0).contains("thresholds[1]"));
    assert!(err(&r, &[0.1, 0.2, f64::INFINITY], 0.0, 1.0).contains("weights[2]"));
    assert!(err(&r, &b, f64::NAN, 1.0).contains("a1"));
    assert!(err(&r, &b, 0.0, f64::NEG_INFINITY).contains("a2"));
    assert!(err(&[-0.1, 0.1, 0.2], &b, 0.0, 1.0).contains("negative"));
    assert!(err(&[0.0, 0.3, 0.2], &b, 0.0, 1.0).contains("sort"));
    let fixed = Mpim::<f64, [f64; 4]>::new(&r, &b, 0.0, 1.0).unwrap_err();
    assert!(
        fixed.to_string().contains("fixed storage holds 4"),
        "{fixed}"
    );
}

#[test]
fn spreading_a_published_model_keeps_its_major_loop() {
    // Spreading each operator over 10 thresholds 0.01 apart changes the loop by at most the
    // spread: compare both on a major loop and a minor loop.
    let table: VecMpim = hystcomp_core::paper::TABLE1.model().unwrap();
    let mut coarse = table.clone();
    let mut fine: VecMpim = hystcomp_core::paper::TABLE1.spread(100).unwrap();
    assert_eq!(fine.len(), 100);
    let mut rng = rng(6);
    for x in random_input(&mut rng, 2000, 0.0, 1.0) {
        let (a, b) = (coarse.step(x), fine.step(x));
        assert!((a - b).abs() < 0.05 * 0.77, "{a} vs {b}");
    }
}
