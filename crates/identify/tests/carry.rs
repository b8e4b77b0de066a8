//! Validation carries the operators' memory across a consecutive split of one record (issue
//! 10), and `identify`'s held-out error and `crossval`'s test error are normalised alike.
//!
//! The reference is the plain one: run the model (or the compensator) over the whole record
//! from rest and look only at the test span.

mod common;

use hystcomp_identify::{
    CrossvalOptions, IdentifyOptions, NoObserver, Record, TestStart, Thresholds, Warmup, crossval,
    identify, predict_test, validate_models, validate_models_from,
};
use hystcomp_io::compensator::{ScaledCompensator, UnstableDelay};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{excitation, random_plant, run};

/// A record of a random plant (0..10 V, um with an offset) driven by a random excitation,
/// with a little measurement noise so that identified models are not exact.
fn record(seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let plant = random_plant(&mut rng, 8);
    let x = excitation(&mut rng, 12);
    let voltage: Vec<f64> = x.iter().map(|v| 10.0 * v).collect();
    let displacement: Vec<f64> = run(&plant, &x)
        .iter()
        .map(|y| 3.0 + 60.0 * y + 0.05 * (rng.random::<f64>() - 0.5))
        .collect();
    (voltage, displacement)
}

fn options(holdout: f64, warmup: usize) -> IdentifyOptions {
    IdentifyOptions {
        thresholds: Thresholds::Uniform(10),
        warmup: Warmup::Samples(warmup),
        holdout,
        max_fit_rms_percent: None,
        ..IdentifyOptions::default()
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12)
}

/// For every seeded record and split point, the carried-memory prediction of the test span
/// is the whole record's prediction restricted to it (the forward model and the inverse
/// model), and the validation's errors are those of that restriction; every compensator's
/// replay equals a direct replay of the whole record restricted to the test span. Starting
/// from rest instead changes the first test samples (the carry is not vacuous).
#[test]
fn carried_memory_predicts_a_consecutive_test_span_as_the_whole_record_does() {
    let mut differs = 0;
    for seed in 0..12 {
        let (voltage, displacement) = record(seed);
        let mut rng = ChaCha8Rng::seed_from_u64(1000 + seed);
        let split = rng.random_range(voltage.len() / 3..2 * voltage.len() / 3);
        let train = Record {
            voltage: &voltage[..split],
            displacement: &displacement[..split],
        };
        let test = Record {
            voltage: &voltage[split..],
            displacement: &displacement[split..],
        };
        let cv = crossval(
            train,
            test,
            &CrossvalOptions {
                identify: options(0.0, 0),
                test_start: TestStart::ContinueTraining,
                unstable_delay: UnstableDelay::Allow,
                ..CrossvalOptions::default()
            },
            &mut NoObserver,
        )
        .unwrap();
        let (plant, inverse) = (&cv.plant, &cv.inverse);
        let v = &cv.report.test;
        assert_eq!(
            (v.start, v.preceding_samples, v.warmup),
            (TestStart::ContinueTraining, split, 0)
        );

        // The reference: the whole record from rest, restricted to the test span.
        let whole_forward = plant.predict_settled(&voltage).unwrap();
        let whole_inverse = inverse.predict_settled(&displacement).unwrap();
        let (forward, backward) = predict_test(plant, inverse, Some(train), test).unwrap();
        for (k, (a, b)) in forward.iter().zip(&whole_forward[split..]).enumerate() {
            assert!(close(*a, *b), "seed {seed}, test sample {k}: {a} vs {b}");
        }
        for (k, (a, b)) in backward.iter().zip(&whole_inverse[split..]).enumerate() {
            assert!(close(*a, *b), "seed {seed}, test sample {k}: {a} vs {b}");
        }
        let range = |s: &[f64]| {
            s.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - s.iter().copied().fold(f64::INFINITY, f64::min)
        };
        let sum_sq: f64 = whole_forward[split..]
            .iter()
            .zip(&displacement[split..])
            .map(|(p, m)| (p - m) * (p - m))
            .sum();
        let rms = (sum_sq / (voltage.len() - split) as f64).sqrt();
        let d_range = range(&displacement[split..]);
        assert!(close(v.ranges.displacement, d_range), "seed {seed}");
        assert!(close(v.forward.range, d_range), "seed {seed}");
        assert!(
            close(v.forward.rms_percent, 100.0 * rms / d_range),
            "seed {seed}: {} vs {}",
            v.forward.rms_percent,
            100.0 * rms / d_range
        );

        // Every compensator: a direct replay of the whole record, scored on the test span.
        let limits = [cv.report.plant.input.min, cv.report.plant.input.max];
        let v_range = range(&voltage[split..]);
        for r in &v.replay {
            let method = r.compensator.parse().unwrap();
            let file = match method {
                hystcomp_io::compensator::Method::Dihc => inverse,
                _ => plant,
            };
            let mut direct = ScaledCompensator::with_unstable_delay(
                file,
                method,
                Some((limits[0], limits[1])),
                UnstableDelay::Allow,
            )
            .unwrap();
            direct.settle_creep(displacement[0]);
            let out: Vec<f64> = displacement.iter().map(|&y| direct.step(y)).collect();
            let sum_sq: f64 = out[split..]
                .iter()
                .zip(&voltage[split..])
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            let rms = 100.0 * (sum_sq / (voltage.len() - split) as f64).sqrt() / v_range;
            let e = r.error.expect("every compensator is replayed when allowed");
            assert!(
                close(e.rms_percent, rms),
                "seed {seed}, {}: {} vs {rms}",
                r.compensator,
                e.rms_percent
            );
        }

        // From rest, the test record's first prediction is another one (unless the memory
        // happens to be the same).
        let (rest, _) = predict_test(plant, inverse, None, test).unwrap();
        if !close(rest[0], forward[0]) {
            differs += 1;
        }
        let at_rest = validate_models(
            plant,
            inverse,
            limits,
            test,
            Warmup::Samples(0),
            UnstableDelay::Allow,
        )
        .unwrap();
        assert_eq!(
            (at_rest.start, at_rest.preceding_samples),
            (TestStart::Rest, 0)
        );
        assert!(
            at_rest.initial_state.contains("at rest"),
            "{}",
            at_rest.initial_state
        );
    }
    assert!(
        differs >= 6,
        "the carry changed the first test sample in {differs} of 12 records"
    );
}

/// One record split once: `identify` holding out its end and `crossval` trained on the rest
/// and tested on the end (the memory carried) give the same held-out figure, both in % of the
/// test span's own displacement range.
#[test]
fn identify_holdout_and_crossval_give_the_same_figure_for_one_split() {
    for seed in 20..28 {
        let (voltage, displacement) = record(seed);
        let warmup = 5 + seed as usize;
        let fit = identify(&voltage, &displacement, &options(0.3, warmup)).unwrap();
        let h = fit.report.holdout.expect("a hold-out");
        let split = fit.report.samples.warmup + fit.report.samples.fit;
        assert_eq!(split + fit.report.samples.holdout, voltage.len());
        let train = Record {
            voltage: &voltage[..split],
            displacement: &displacement[..split],
        };
        let test = Record {
            voltage: &voltage[split..],
            displacement: &displacement[split..],
        };
        let cv = crossval(
            train,
            test,
            &CrossvalOptions {
                identify: options(0.0, warmup),
                test_start: TestStart::ContinueTraining,
                test_warmup: Warmup::Samples(0),
                ..CrossvalOptions::default()
            },
            &mut NoObserver,
        )
        .unwrap();
        let f = cv.report.test.forward;
        assert!(
            close(h.range, f.range),
            "seed {seed}: {} vs {}",
            h.range,
            f.range
        );
        assert!(
            (h.rms_percent - f.rms_percent).abs() <= 1e-9 * h.rms_percent.max(1e-9),
            "seed {seed}: identify --holdout {} % vs crossval {} %",
            h.rms_percent,
            f.rms_percent
        );
        // The denominator is the held-out span's own range, not the fitted one.
        let (lo, hi) = displacement[split..]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                (a.min(y), b.max(y))
            });
        assert!(close(h.range, hi - lo), "seed {seed}");
        // The same through validate_models_from given the training record.
        let again = validate_models_from(
            &cv.plant,
            &cv.inverse,
            [cv.report.plant.input.min, cv.report.plant.input.max],
            Some(train),
            test,
            Warmup::Auto,
            UnstableDelay::Refuse,
        )
        .unwrap();
        assert_eq!(again.warmup, 0, "no warm-up after a carried memory");
        assert!(
            close(again.forward.rms_percent, f.rms_percent),
            "seed {seed}"
        );
    }
}
