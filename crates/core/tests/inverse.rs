//! Eq. (7), the analytic inverse of the PI part, and the invertibility check.

mod common;

use common::*;
use hystcomp_core::{CoreError, Mpim};
use rand::RngExt;

/// A decaying sine with minor loops: 0.5 + 0.5 e^{-t/3} sin(2 pi t) + 0.05 sin(2 pi 7 t).
fn decaying_sine_with_minor_loops(samples: usize) -> Vec<f64> {
    (0..samples)
        .map(|k| {
            let t = k as f64 / samples as f64 * 10.0;
            let x = 0.5
                + 0.42 * (-t / 3.0).exp() * (2.0 * std::f64::consts::PI * t).sin()
                + 0.05 * (2.0 * std::f64::consts::PI * 7.0 * t).sin();
            x.clamp(0.0, 1.0)
        })
        .collect()
}

#[test]
fn eq7_inverts_the_table1_pi_part_to_1e_12() {
    // P1[v] = a2 v + sum b_i F_ri[v] with Table 1 (ERRATA item 3).
    let mut p1: Mpim<f64, Vec<f64>> = Mpim::new(&TABLE1_R, &TABLE1_B, 0.0, TABLE1_A2).unwrap();
    let mut inverse = p1.pi_part_inverse().unwrap();
    assert_eq!(inverse.a1(), 0.0);
    assert_eq!(inverse.thresholds()[0], 0.0, "r_hat_1 = 0 since r_1 = 0");
    assert!((inverse.a2() - 1.0 / TABLE1_A2).abs() < 1e-15);
    let v = decaying_sine_with_minor_loops(20_000);
    let mut worst: f64 = 0.0;
    for &vk in &v {
        let w = p1.step(vk);
        worst = worst.max((inverse.step(w) - vk).abs());
    }
    assert!(worst <= 1e-12, "max |P1^-1[P1[v]] - v| = {worst}");
}

#[test]
fn eq7_inverts_random_pi_parts_both_ways() {
    let mut rng = rng(11);
    for case in 0..200 {
        let n = 1 + (rng.random::<u32>() % 15) as usize;
        let m = random_model(&mut rng, n);
        let mut p1: Mpim<f64, Vec<f64>> =
            Mpim::new(m.thresholds(), m.weights(), 0.0, m.a2()).unwrap();
        let Ok(mut inverse) = p1.pi_part_inverse() else {
            continue;
        };
        let mut inverse_of_inverse = inverse.pi_part_inverse().unwrap();
        let v = random_input(&mut rng, 1000, 0.0, 1.0);
        for (k, &vk) in v.iter().enumerate() {
            let w = p1.step(vk);
            let back = inverse.step(w);
            assert!(
                (back - vk).abs() <= 1e-9,
                "case {case} sample {k}: {back} vs {vk}"
            );
            // The inverse of the inverse is P1 again.
            assert!((inverse_of_inverse.step(back) - w).abs() <= 1e-9);
        }
    }
}

#[test]
fn eq7_refuses_a_pi_part_with_a_non_positive_slope() {
    // a2 + b1 + b2 = 0.5 - 0.3 - 0.4 < 0.
    let m: Mpim<f64, Vec<f64>> = Mpim::new(&[0.0, 0.1, 0.2], &[-0.3, -0.4, 0.1], 0.0, 0.5).unwrap();
    let err = m.pi_part_inverse().unwrap_err();
    assert!(
        matches!(
            err,
            CoreError::PiPartNotInvertible {
                active_operators: 2,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("eq. (7)"));
}

#[test]
fn table1_and_table2_are_invertible_on_the_unit_range() {
    let t1 = table1().check_invertible(0.0, 1.0).unwrap();
    assert!(t1.slope > 0.0);
    let t2 = table2().check_invertible(0.0, 1.0).unwrap();
    assert!(t2.slope > 0.0);
}

#[test]
fn table1_with_b1_zero_and_a1_minus_0_3_is_refused_with_the_reason() {
    let mut b = TABLE1_B;
    b[0] = 0.0;
    let m: Mpim<f64, Vec<f64>> = Mpim::new(&TABLE1_R, &b, -0.3, TABLE1_A2).unwrap();
    let err = m.check_invertible(0.0, 1.0).unwrap_err();
    match &err {
        CoreError::NotInvertible {
            slope,
            input,
            active_operators,
            ..
        } => {
            // Falling from the top, only the r = 0 operator (weight 0) moves:
            // slope = a2 + 3 a1 x^2 = 0.4603 - 0.9 at x = 1.
            assert!((slope - (TABLE1_A2 - 0.9)).abs() < 1e-12, "{slope}");
            assert_eq!(*input, 1.0);
            assert_eq!(*active_operators, 1);
        }
        other => panic!("unexpected {other:?}"),
    }
    let text = err.to_string();
    assert!(
        text.contains("not invertible") && text.contains("x = 1"),
        "{text}"
    );
}

/// `a2 + 3 a1 x^2 + b_1 + ... + b_k`, the slope of the branch with the first `k` operators moving.
fn branch_slope_formula(model: &VecMpim, k: usize, x: f64) -> f64 {
    model.a2() + 3.0 * model.a1() * x * x + model.weights()[..k].iter().sum::<f64>()
}

/// Numerical slopes of the branch with exactly the first `k` operators moving, at inputs `x'`
/// near `x` (moved up to 2e-3 into the interior of where that branch is reachable in [0, 1]),
/// reached from reset by an explicit path: `(x', numeric slope)` for each direction that works.
fn reachable_slopes_near(model: &VecMpim, k: usize, x: f64) -> Vec<(f64, f64)> {
    let r = model.thresholds();
    let r_k = if k == 0 { 0.0 } else { r[k - 1] };
    let r_next = r.get(k).copied().unwrap_or(r_k + 4e-3);
    // Travel between r_k and r_{k+1} since the last reversal: exactly the first k move.
    let travel = 0.5 * (r_k + r_next);
    let h = 1e-7;
    let ramp = |m: &mut VecMpim, from: f64, to: f64| {
        for i in 1..=200 {
            m.step(from + (to - from) * i as f64 / 200.0);
        }
    };
    let mut found = Vec::new();
    // Rising: from 1 down to x' - travel, then up to just below x'.
    let xr = x
        .clamp(travel.min(1.0), 1.0)
        .clamp(0.0, 1.0 - 2e-3)
        .max(travel + 2e-3);
    if xr <= 1.0 && xr - travel >= 0.0 && (xr - x).abs() <= 2e-3 + 1e-12 {
        let mut m = model.clone();
        ramp(&mut m, 0.0, 1.0);
        ramp(&mut m, 1.0, xr - travel);
        ramp(&mut m, xr - travel, xr - h);
        found.push((xr, (m.branch_output(xr) - m.branch_output(xr - h)) / h));
    }
    // Falling: from reset up to x' + travel, then down to just above x'.
    let xf = x.min(1.0 - travel - 2e-3).max(2e-3);
    if xf >= 0.0 && xf + travel <= 1.0 && (xf - x).abs() <= 2e-3 + 1e-12 {
        let mut m = model.clone();
        ramp(&mut m, 0.0, xf + travel);
        ramp(&mut m, xf + travel, xf + h);
        found.push((xf, (m.branch_output(xf + h) - m.branch_output(xf)) / h));
    }
    found
}

#[test]
fn reported_worst_slope_is_real_and_no_reachable_branch_is_steeper_down() {
    let mut rng = rng(12);
    let mut refused = 0;
    for case in 0..300 {
        let n = 1 + (rng.random::<u32>() % 12) as usize;
        let model = random_model(&mut rng, n);
        let worst = model.min_branch_slope(0.0, 1.0).unwrap();
        // (a) The reported slope is the branch formula, and that branch is reachable near the
        //     reported input: an explicit path gets there and its numerical slope agrees.
        let formula = branch_slope_formula(&model, worst.active_operators, worst.input);
        assert!(
            (formula - worst.slope).abs() < 1e-12,
            "case {case}: {worst:?} vs {formula}"
        );
        let near = reachable_slopes_near(&model, worst.active_operators, worst.input);
        assert!(!near.is_empty(), "case {case}: no path reaches {worst:?}");
        for (x, numeric) in near {
            let expected = branch_slope_formula(&model, worst.active_operators, x);
            assert!(
                (numeric - expected).abs() < 1e-5,
                "case {case}: at x = {x} numeric slope {numeric} vs {expected} ({worst:?})"
            );
        }
        // (b) On random paths, no branch slope is below the reported minimum.
        let mut m = model.clone();
        for x in random_input(&mut rng, 300, 0.0, 1.0) {
            m.step(x);
            for dx in [1e-6, -1e-6] {
                let xn = x + dx;
                if (0.0..=1.0).contains(&xn) {
                    let s = (m.branch_output(xn) - m.branch_output(x)) / dx;
                    assert!(
                        s >= worst.slope - 1e-6,
                        "case {case}: slope {s} < {worst:?}"
                    );
                }
            }
        }
        if model.check_invertible(0.0, 1.0).is_err() {
            refused += 1;
        }
    }
    assert!(
        refused > 10 && refused < 290,
        "the random models should mix verdicts: {refused}"
    );
}

#[test]
fn ranges_must_be_finite_and_ordered() {
    let m = table1();
    assert!(matches!(
        m.check_invertible(1.0, 0.0),
        Err(CoreError::InvalidRange { .. })
    ));
    assert!(matches!(
        m.check_invertible(0.0, f64::NAN),
        Err(CoreError::InvalidRange { .. })
    ));
}

/// Eq. (7)'s thresholds and weights, computed in one pass (linear set-up cost, so that a model
/// of 10^5 operators builds in milliseconds), agree with the literal double sums
/// `r_hat_j = a2 r_j + sum_{i<j} b_i (r_j - r_i)` and `b_hat_j = 1/s_j - 1/s_{j-1}` on random
/// models, many with hundreds of operators.
#[test]
fn eq7_in_one_pass_matches_the_literal_sums() {
    let mut rng = rng(29);
    for case in 0..100 {
        let n = 1 + (rng.random::<u32>() % 400) as usize;
        let m = random_model(&mut rng, n);
        let p1: Mpim<f64, Vec<f64>> = Mpim::new(m.thresholds(), m.weights(), 0.0, m.a2()).unwrap();
        let Ok(inverse) = p1.pi_part_inverse() else {
            continue;
        };
        let (r, b, a2) = (m.thresholds(), m.weights(), m.a2());
        // Only models whose zero-threshold operators keep every slope positive use the literal
        // b_hat for all j; the others fold them into a2_hat (and are compared from there on).
        let always = r.iter().take_while(|r| **r <= 0.0).count();
        for j in 0..n {
            let r_hat: f64 = a2 * r[j] + (0..j).map(|i| b[i] * (r[j] - r[i])).sum::<f64>();
            let tolerance = 1e-12 * (1.0 + r_hat.abs());
            assert!(
                (inverse.thresholds()[j] - r_hat).abs() <= tolerance,
                "case {case}, n {n}, j {j}: {} vs {r_hat}",
                inverse.thresholds()[j]
            );
            if j >= always {
                let slope = |k: usize| a2 + b[..k].iter().sum::<f64>();
                let b_hat = 1.0 / slope(j + 1) - 1.0 / slope(j);
                let got = inverse.weights()[j];
                assert!(
                    (got - b_hat).abs() <= 1e-9 * (1.0 + b_hat.abs()),
                    "case {case}, j {j}: b_hat {got} vs {b_hat}"
                );
            }
        }
    }
}
