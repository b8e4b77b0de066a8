//! The chain's links (creep, vibration) and the chain compensator, each checked against a plain
//! reference on many seeded random inputs: the literal difference equations, a fixed-point
//! solve of the creep feedback, and the forward chain as the oracle of its inverse.

mod common;

use common::{random_input, random_invertible_model, rng, seeded, unit_limits};
use hystcomp_core::{
    Bounded, ChainCompensator, ChainModel, Compensator, CoreError, Creep, CreepInverse, Ihc,
    SolveMode, Vibration, VibrationInverse,
};
use proptest::prelude::*;
use rand::{Rng, RngExt};

/// Random creep elements: log-spaced time constants, weights of both signs, `sum |c| < 0.6`.
fn random_creep(rng: &mut impl Rng) -> (Vec<f64>, Vec<f64>) {
    let n = 1 + (rng.random::<f64>() * 10.0) as usize;
    let first = 1e-3 * 10f64.powf(rng.random::<f64>() * 2.0);
    let taus: Vec<f64> = (0..n).map(|i| first * 10f64.powf(i as f64 * 0.5)).collect();
    let raw: Vec<f64> = (0..n).map(|_| rng.random::<f64>() - 0.2).collect();
    let total: f64 = raw.iter().map(|c| c.abs()).sum();
    let budget = 0.6 * rng.random::<f64>();
    let weights = raw.iter().map(|c| c / total * budget).collect();
    (taus, weights)
}

/// The creep link's forward step solved literally: iterate `x = h + sum c_i z_i(x)` to a fixed
/// point, with `z_i(x) = z_i + g_i (x - z_i)` (origin 0).
fn literal_creep(taus: &[f64], weights: &[f64], period: f64, h: &[f64]) -> Vec<f64> {
    let mut z = vec![0.0; taus.len()];
    let g: Vec<f64> = taus.iter().map(|t| 1.0 - (-period / t).exp()).collect();
    h.iter()
        .map(|&h| {
            let mut x = h;
            for _ in 0..200 {
                x = h
                    + (0..taus.len())
                        .map(|i| weights[i] * (z[i] + g[i] * (x - z[i])))
                        .sum::<f64>();
            }
            for i in 0..taus.len() {
                z[i] += g[i] * (x - z[i]);
            }
            x
        })
        .collect()
}

/// Multiplies out `prod (1 - rho w)` for real roots and conjugate pairs: coefficients of
/// `w^0, w^1, ...`.
fn poly(real: &[f64], pairs: &[(f64, f64)]) -> Vec<f64> {
    let mut p = vec![1.0];
    let mut times = |q: &[f64]| {
        let mut out = vec![0.0; p.len() + q.len() - 1];
        for (i, a) in p.iter().enumerate() {
            for (j, b) in q.iter().enumerate() {
                out[i + j] += a * b;
            }
        }
        p = out;
    };
    for &r in real {
        times(&[1.0, -r]);
    }
    for &(m, angle) in pairs {
        times(&[1.0, -2.0 * m * angle.cos(), m * m]);
    }
    p
}

/// A random stable vibration model with unit static gain: a resonance (and maybe a real pole),
/// zeros inside and outside the unit circle, a delay.
fn random_vibration(rng: &mut impl Rng) -> (Vec<f64>, Vec<f64>, usize) {
    let resonance = (
        0.6 + 0.39 * rng.random::<f64>(),
        0.05 + 0.6 * rng.random::<f64>(),
    );
    let mut real_poles = vec![];
    if rng.random::<bool>() {
        real_poles.push(rng.random::<f64>() * 0.9);
    }
    let a = poly(&real_poles, &[resonance]);
    let mut zeros = vec![];
    for _ in 0..(rng.random::<f64>() * 3.0) as usize {
        let magnitude = if rng.random::<bool>() {
            1.2 + 3.0 * rng.random::<f64>()
        } else {
            0.8 * rng.random::<f64>()
        };
        zeros.push(if rng.random::<bool>() {
            -magnitude
        } else {
            magnitude
        });
    }
    let b_shape = poly(&zeros, &[]);
    let gain = a.iter().sum::<f64>() / b_shape.iter().sum::<f64>();
    let b: Vec<f64> = b_shape.iter().map(|c| c * gain).collect();
    let delay = (rng.random::<f64>() * 4.0) as usize;
    (b, a, delay)
}

/// The difference equation written literally, from rest at `x[0]`.
fn literal_vibration(b: &[f64], a: &[f64], delay: usize, x: &[f64]) -> Vec<f64> {
    let mut y: Vec<f64> = Vec::with_capacity(x.len());
    let xa = |k: isize| if k < 0 { x[0] } else { x[k as usize] };
    for k in 0..x.len() as isize {
        let mut v = 0.0;
        for (j, bj) in b.iter().enumerate() {
            v += bj * xa(k - delay as isize - j as isize);
        }
        for (i, ai) in a.iter().enumerate().skip(1) {
            let past = k - i as isize;
            v -= ai * if past < 0 { x[0] } else { y[past as usize] };
        }
        y.push(v);
    }
    y
}

proptest! {
    #![proptest_config(seeded(48, 11))]

    #[test]
    fn creep_forward_solves_its_feedback_and_its_inverse_undoes_it(seed in any::<u64>()) {
        let mut r = rng(seed);
        let (taus, weights) = random_creep(&mut r);
        let period = 1e-3;
        let h = random_input(&mut r, 3000, -1.0, 1.0);
        let mut creep: Creep<f64, Vec<f64>> = Creep::new(&taus, &weights, 0.0, period).unwrap();
        let mut inverse = creep.inverse();
        let reference = literal_creep(&taus, &weights, period, &h);
        for (k, &hk) in h.iter().enumerate() {
            let x = creep.step(hk);
            prop_assert!((x - reference[k]).abs() < 1e-10, "{k}: {x} vs {}", reference[k]);
            let back = inverse.step(x);
            prop_assert!((back - hk).abs() < 1e-12, "{k}: {back} vs {hk}");
        }
    }

    #[test]
    fn vibration_forward_is_the_literal_difference_equation(seed in any::<u64>()) {
        let mut r = rng(seed);
        let (b, a, delay) = random_vibration(&mut r);
        let x = random_input(&mut r, 500, 0.0, 1.0);
        let mut link: Vibration<f64, Vec<f64>> = Vibration::new(&b, &a, delay).unwrap();
        let reference = literal_vibration(&b, &a, delay, &x);
        for (k, &xk) in x.iter().enumerate() {
            let y = link.step(xk);
            prop_assert!((y - reference[k]).abs() < 1e-10, "{k}");
        }
    }

    #[test]
    fn vibration_inverse_offline_is_undone_by_the_forward_link(seed in any::<u64>()) {
        let mut r = rng(seed);
        let (b, a, delay) = random_vibration(&mut r);
        // At rest long enough before it moves that the inverse's pre-actuation (it moves
        // before the trajectory does) lies within the record.
        let walk = random_input(&mut r, 800, 0.0, 1.0);
        let desired: Vec<f64> = std::iter::repeat_n(walk[0], 300).chain(walk).collect();
        let preview = VibrationInverse::<f64, Vec<f64>>::needed_preview(&b, delay).unwrap();
        let mut inverse: VibrationInverse<f64, Vec<f64>> =
            VibrationInverse::new(&b, &a, delay, preview).unwrap();
        prop_assert!(inverse.truncation() < 1e-11);
        let mut x = vec![0.0; desired.len()];
        inverse.process_aligned(&desired, &mut x).unwrap();
        // The inverse takes the trajectory at rest at its first sample before it starts.
        let mut forward: Vibration<f64, Vec<f64>> = Vibration::new(&b, &a, delay).unwrap();
        forward.settle(desired[0]);
        for (k, xk) in x.iter().enumerate() {
            let y = forward.step(*xk);
            prop_assert!((y - desired[k]).abs() < 1e-8, "{k}: {y} vs {}", desired[k]);
        }
    }

    #[test]
    fn a_short_preview_keeps_the_static_gain_and_errs_by_its_cut_tail(seed in any::<u64>()) {
        let mut r = rng(seed);
        let (b, a, delay) = random_vibration(&mut r);
        let minimum = VibrationInverse::<f64, Vec<f64>>::minimum_preview(&b, delay).unwrap();
        let mut inverse: VibrationInverse<f64, Vec<f64>> =
            VibrationInverse::new(&b, &a, delay, minimum + 2).unwrap();
        // A constant passes unchanged (unit static gain, tail folded into the last tap).
        for _ in 0..2000 {
            let x = inverse.step(0.3);
            prop_assert!((x - 0.3).abs() < 1e-9);
        }
        prop_assert!(inverse.truncation() >= 0.0 && inverse.truncation() <= 1.0);
    }

    #[test]
    fn the_chain_compensator_inverts_the_chain_model(seed in any::<u64>()) {
        let mut r = rng(seed);
        let n = 1 + (r.random::<f64>() * 10.0) as usize;
        let plant = random_invertible_model(&mut r, n);
        let (taus, weights) = random_creep(&mut r);
        let (b, a, delay) = random_vibration(&mut r);
        let period = 1e-3;
        // A smooth desired trajectory the plant reaches: the chain model's output for a slow
        // drive within the limits.
        // At rest for 300 samples (room for the inverse's pre-actuation), then a smooth rise.
        let drive: Vec<f64> = (0..1800usize)
            .map(|k| {
                let t = k.saturating_sub(300) as f64;
                let rise = 0.5 - 0.5 * (std::f64::consts::PI * (t / 300.0).min(1.0)).cos();
                rise * (0.5 + 0.35 * (t * 0.004).sin() * (t * 0.0011).cos())
            })
            .collect();
        let mut model: ChainModel<f64, Vec<f64>, Vec<f64>> = ChainModel {
            hysteresis: plant.clone(),
            creep: Some(Creep::new(&taus, &weights, 0.0, period).unwrap()),
            vibration: Some(Vibration::new(&b, &a, delay).unwrap()),
        };
        let mut desired = vec![0.0; drive.len()];
        model.process(&drive, &mut desired).unwrap();
        let preview = VibrationInverse::<f64, Vec<f64>>::needed_preview(&b, delay).unwrap();
        let ihc: Ihc<f64, Vec<f64>> = Ihc::new(&plant, unit_limits(), SolveMode::Exact).unwrap();
        let mut chain: ChainCompensator<f64, Vec<f64>, _> = ChainCompensator::new(
            Some(VibrationInverse::new(&b, &a, delay, preview).unwrap()),
            Some(CreepInverse::new(&taus, &weights, 0.0, period).unwrap()),
            ihc,
        );
        let mut control = vec![0.0; desired.len()];
        chain.process_aligned(&desired, &mut control).unwrap();
        // The model, from the chain's assumptions (vibration at rest at the first sample).
        model.reset();
        if let Some(v) = &mut model.vibration {
            v.settle(desired[0]);
        }
        let mut worst: f64 = 0.0;
        for (k, v) in control.iter().enumerate() {
            prop_assert!((0.0..=1.0).contains(v));
            let y = model.step(*v);
            if k > 0 {
                worst = worst.max((y - desired[k]).abs());
            }
        }
        prop_assert!(worst < 1e-6, "worst {worst}");
    }

    #[test]
    fn the_chain_never_leaves_its_limits_nor_emits_nan(
        seed in any::<u64>(),
        wild in proptest::collection::vec(
            prop_oneof![Just(f64::NAN), Just(f64::INFINITY), -1e6f64..1e6, -2.0f64..3.0],
            1..400,
        ),
    ) {
        let mut r = rng(seed);
        let plant = random_invertible_model(&mut r, 6);
        let (taus, weights) = random_creep(&mut r);
        let (b, a, delay) = random_vibration(&mut r);
        let preview = VibrationInverse::<f64, Vec<f64>>::minimum_preview(&b, delay).unwrap() + 3;
        let ihc: Ihc<f64, Vec<f64>> = Ihc::new(&plant, unit_limits(), SolveMode::Exact).unwrap();
        let mut chain: ChainCompensator<f64, Vec<f64>, _> = ChainCompensator::new(
            Some(VibrationInverse::new(&b, &a, delay, preview).unwrap()),
            Some(CreepInverse::new(&taus, &weights, 0.0, 1e-3).unwrap()),
            ihc,
        );
        let mut non_finite = 0;
        for y in wild {
            if !y.is_finite() {
                non_finite += 1;
            }
            let v = chain.step(y);
            prop_assert!(v.is_finite() && (0.0..=1.0).contains(&v), "{v}");
        }
        prop_assert_eq!(chain.diagnostics().non_finite, non_finite);
    }

    /// Samples the creep and vibration links cannot follow (finite but beyond the square
    /// root of the largest value, e.g. `f64::MAX` then `-f64::MAX`, whose difference
    /// overflows) are taken as not finite: the chain gives the same bits and diagnostics as on
    /// the trajectory with NaN in their place, never leaves its limits, and keeps following
    /// the samples after them (before, `f64::MAX` then `-f64::MAX` left the creep link's
    /// states NaN and the drive held at a limit for good).
    #[test]
    fn samples_too_large_to_follow_count_as_not_finite(
        seed in any::<u64>(),
        wild in proptest::collection::vec(
            prop_oneof![
                4 => -2.0f64..3.0,
                1 => prop_oneof![Just(f64::MAX), Just(-f64::MAX), Just(1e308), Just(-1e300), Just(2e154)],
                1 => Just(f64::NAN),
            ],
            1..300,
        ),
    ) {
        let mut r = rng(seed);
        let plant = random_invertible_model(&mut r, 6);
        let (taus, weights) = random_creep(&mut r);
        let (b, a, delay) = random_vibration(&mut r);
        let preview = VibrationInverse::<f64, Vec<f64>>::minimum_preview(&b, delay).unwrap() + 3;
        let with_links = r.random::<u32>() % 3;
        let chain = || {
            let ihc: Ihc<f64, Vec<f64>> = Ihc::new(&plant, unit_limits(), SolveMode::Exact).unwrap();
            let vibration = (with_links != 1).then(|| VibrationInverse::new(&b, &a, delay, preview).unwrap());
            let creep = (with_links != 2).then(|| CreepInverse::new(&taus, &weights, 0.0, 1e-3).unwrap());
            ChainCompensator::<f64, Vec<f64>, _>::new(vibration, creep, ihc)
        };
        let (mut wild_chain, mut nan_chain) = (chain(), chain());
        for y in &wild {
            let replaced = if y.abs() > 1.3e154 { f64::NAN } else { *y };
            let v = wild_chain.step(*y);
            prop_assert!(v.is_finite() && (0.0..=1.0).contains(&v), "{v}");
            prop_assert_eq!(v.to_bits(), nan_chain.step(replaced).to_bits());
        }
        prop_assert_eq!(wild_chain.diagnostics(), nan_chain.diagnostics());
        prop_assert_eq!(
            wild_chain.diagnostics().non_finite,
            wild.iter().filter(|y| y.is_nan() || y.abs() > 1.3e154).count() as u64
        );
    }
}

/// Each link alone: a sample it cannot follow (beyond the square root of the largest value,
/// or not finite) gives NaN (creep) or the previous sample (vibration) and leaves the state
/// as it was, so that what follows is what follows without it, bit for bit.
#[test]
fn each_link_passes_over_a_sample_it_cannot_follow() {
    let mut r = rng(17);
    for _ in 0..50 {
        let (taus, weights) = random_creep(&mut r);
        let (b, a, delay) = random_vibration(&mut r);
        let preview = VibrationInverse::<f64, Vec<f64>>::minimum_preview(&b, delay).unwrap() + 2;
        let desired = random_input(&mut r, 200, -2.0, 3.0);
        let at = 1 + r.random::<u32>() as usize % 150;
        let huge = [f64::MAX, -f64::MAX, 1e200, f64::INFINITY][r.random::<u32>() as usize % 4];
        let mut creep: CreepInverse<f64, Vec<f64>> =
            CreepInverse::new(&taus, &weights, 0.0, 1e-3).unwrap();
        let mut creep_twin = creep.clone();
        let mut vibration: VibrationInverse<f64, Vec<f64>> =
            VibrationInverse::new(&b, &a, delay, preview).unwrap();
        let mut vibration_twin = vibration.clone();
        for (k, y) in desired.iter().enumerate() {
            if k == at {
                assert!(creep.step(huge).is_nan());
                // The previous desired sample in its place.
                assert_eq!(
                    vibration.step(huge).to_bits(),
                    vibration_twin.step(desired[k - 1]).to_bits()
                );
                continue;
            }
            assert_eq!(creep.step(*y).to_bits(), creep_twin.step(*y).to_bits());
            assert_eq!(
                vibration.step(*y).to_bits(),
                vibration_twin.step(*y).to_bits()
            );
        }
    }
}

#[test]
fn fixed_storage_chain_matches_the_vec_chain() {
    let mut r = rng(5);
    let (taus, weights) = random_creep(&mut r);
    let (b, a, delay) = random_vibration(&mut r);
    let desired = random_input(&mut r, 2000, 0.1, 0.9);
    let mut vec_link: CreepInverse<f64, Vec<f64>> =
        CreepInverse::new(&taus, &weights, 0.0, 1e-3).unwrap();
    let mut fixed_link: CreepInverse<f64, Bounded<f64, 16>> =
        CreepInverse::new(&taus, &weights, 0.0, 1e-3).unwrap();
    let preview = VibrationInverse::<f64, Vec<f64>>::minimum_preview(&b, delay).unwrap() + 10;
    let mut vec_inv: VibrationInverse<f64, Vec<f64>> =
        VibrationInverse::new(&b, &a, delay, preview).unwrap();
    let mut fixed_inv: VibrationInverse<f64, Bounded<f64, 32>> =
        VibrationInverse::new(&b, &a, delay, preview).unwrap();
    for y in desired {
        assert_eq!(vec_link.step(y), fixed_link.step(y));
        assert_eq!(vec_inv.step(y), fixed_inv.step(y));
    }
    assert!(matches!(
        VibrationInverse::<f64, Bounded<f64, 4>>::new(&b, &a, delay, 40),
        Err(CoreError::Capacity { .. })
    ));
}

#[test]
fn creep_settles_at_its_static_gain() {
    let taus = [0.01, 0.1, 1.0];
    let weights = [0.02, 0.03, 0.05];
    let mut creep: Creep<f64, Vec<f64>> = Creep::new(&taus, &weights, 0.0, 1e-3).unwrap();
    let mut x = 0.0;
    for _ in 0..30_000 {
        x = creep.step(1.0);
    }
    assert!((x - creep.static_gain()).abs() < 1e-9);
    assert!((creep.static_gain() - 1.0 / 0.9).abs() < 1e-12);
    // The first sample moves only by the direct feedthrough: creep takes time.
    creep.reset();
    assert!(creep.step(1.0) < 1.01);
}

#[test]
fn bad_links_are_refused_with_the_reason() {
    let unstable_creep = Creep::<f64, Vec<f64>>::new(&[0.1, 1.0], &[0.6, -0.5], 0.0, 1e-3);
    assert!(matches!(
        unstable_creep,
        Err(CoreError::CreepUnstable { .. })
    ));
    let bad_tau = Creep::<f64, Vec<f64>>::new(&[0.1, 0.0], &[0.1, 0.1], 0.0, 1e-3);
    assert!(matches!(
        bad_tau,
        Err(CoreError::NotPositive { index: Some(1), .. })
    ));
    let bad_period = CreepInverse::<f64, Vec<f64>>::new(&[0.1], &[0.1], 0.0, 0.0);
    assert!(matches!(
        bad_period,
        Err(CoreError::NotPositive { index: None, .. })
    ));
    // Gain 2, an unstable pole, a zero on the unit circle, a leading zero.
    let cases: [(&[f64], &[f64]); 4] = [
        (&[0.2], &[1.0, -0.9]),
        (&[-0.1], &[1.0, -1.1]),
        (&[0.5, 0.5], &[1.0, 0.0]),
        (&[0.0, 1.0], &[1.0, 0.0]),
    ];
    for (k, (b, a)) in cases.into_iter().enumerate() {
        let inverse = VibrationInverse::<f64, Vec<f64>>::new(b, a, 0, 10).unwrap_err();
        assert!(
            matches!(inverse, CoreError::VibrationModel { .. }),
            "{inverse}"
        );
        // The forward link needs no inverse: a zero on the unit circle is its own business.
        if k != 2 {
            let error = Vibration::<f64, Vec<f64>>::new(b, a, 0).unwrap_err();
            assert!(matches!(error, CoreError::VibrationModel { .. }), "{error}");
        }
    }
    // A zero outside the unit circle needs one sample of preview beyond the delay.
    let (b, a) = (poly(&[-2.0], &[]), vec![1.0, -0.5]);
    let gain = a.iter().sum::<f64>() / b.iter().sum::<f64>();
    let b: Vec<f64> = b.iter().map(|c| c * gain).collect();
    let error = VibrationInverse::<f64, Vec<f64>>::new(&b, &a, 2, 2).unwrap_err();
    assert!(
        matches!(error, CoreError::Preview { minimum: 3, .. }),
        "{error}"
    );
    assert!(error.to_string().contains("between 3"));
}

#[test]
fn the_benchmarks_reference_chain_is_a_stable_resonance_with_a_zero_outside_the_circle() {
    let links = hystcomp_core::reference::chain_links::<f64>();
    assert_eq!(links.time_constants_s.len(), links.weights.len());
    assert!((links.time_constants_s[0] - 0.01).abs() < 1e-15);
    assert!((links.time_constants_s[10] - 1000.0).abs() < 1e-9);
    // Unit static gain; poles inside the unit circle (r^2 = a_2 < 1).
    let (b, a) = (&links.numerator, &links.denominator);
    let gain = b.iter().sum::<f64>() / a.iter().sum::<f64>();
    assert!((gain - 1.0).abs() < 1e-12, "{gain}");
    assert!(a[2] > 0.0 && a[2] < 1.0);
    // The zero at -2.5 makes the inverse anti-causal: more than the minimum preview is needed
    // for a negligible cut, and a preview of 8 (the bench's) inverts it at all.
    let minimum = VibrationInverse::<f64, Vec<f64>>::minimum_preview(b, links.delay).unwrap();
    let needed = VibrationInverse::<f64, Vec<f64>>::needed_preview(b, links.delay).unwrap();
    assert!(needed > minimum && minimum <= 8, "{minimum} {needed}");
    // The forward links undo the chain of inverses (creep and vibration, preview as needed),
    // in f64 and with the f32 links agreeing to single precision.
    let mut r = rng(11);
    let walk = random_input(&mut r, 3000, 0.2, 0.8);
    let desired: Vec<f64> = std::iter::repeat_n(walk[0], 200).chain(walk).collect();
    let mut inverse: VibrationInverse<f64, Vec<f64>> =
        VibrationInverse::new(b, a, links.delay, needed).unwrap();
    let mut x = vec![0.0; desired.len()];
    inverse.process_aligned(&desired, &mut x).unwrap();
    let mut creep_inverse: CreepInverse<f64, Vec<f64>> =
        CreepInverse::new(&links.time_constants_s, &links.weights, 0.0, links.period_s).unwrap();
    let h: Vec<f64> = x.iter().map(|&v| creep_inverse.step(v)).collect();
    let mut creep: Creep<f64, Vec<f64>> =
        Creep::new(&links.time_constants_s, &links.weights, 0.0, links.period_s).unwrap();
    let mut vibration: Vibration<f64, Vec<f64>> = Vibration::new(b, a, links.delay).unwrap();
    vibration.settle(desired[0]);
    for (k, hk) in h.iter().enumerate() {
        let y = vibration.step(creep.step(*hk));
        assert!((y - desired[k]).abs() < 1e-7, "{k}: {y} vs {}", desired[k]);
    }
    let single = hystcomp_core::reference::chain_links::<f32>();
    for (s, d) in single.numerator.iter().zip(b) {
        assert!((f64::from(*s) - d).abs() < 1e-6 * d.abs().max(1.0));
    }
}

/// A zero just outside the unit circle (at -1.0005) makes the anti-causal series converge
/// over tens of thousands of samples: the needed preview is the longest one allowed, the
/// inverse builds there (a model that loads can always be inverted without a preview given),
/// says how much of the series it cut, and keeps the static gain.
#[test]
fn a_slowly_converging_inverse_takes_the_longest_preview_and_says_what_it_cut() {
    use hystcomp_core::vibration::{MAX_PREVIEW_SAMPLES, TAIL_TOLERANCE};
    let b0 = 0.5 / 2.0005;
    let numerator = [b0, b0 * 1.0005];
    let denominator = [1.0, -0.5];
    let preview = VibrationInverse::<f64, Vec<f64>>::needed_preview(&numerator, 0).unwrap();
    assert_eq!(preview, MAX_PREVIEW_SAMPLES);
    let mut inverse =
        VibrationInverse::<f64, Vec<f64>>::new(&numerator, &denominator, 0, preview).unwrap();
    assert!(
        inverse.truncation() > TAIL_TOLERANCE,
        "{}",
        inverse.truncation()
    );
    assert!(inverse.truncation() < 1.0);
    // A constant input comes out unchanged once the preview has filled (unit static gain).
    let mut last = f64::NAN;
    for _ in 0..3 * preview {
        last = inverse.step(0.25);
    }
    assert!((last - 0.25).abs() < 1e-9, "{last}");
}
