//! Thresholds that do not start at 0, bipolar inputs, normalisation over the fitted samples
//! only, and the refusal of fits that cannot describe a piezo actuator.

mod common;

use hystcomp_core::Mpim;
use hystcomp_identify::{
    CrossvalOptions, IdentifyError, IdentifyOptions, NoObserver, OutputOffset, Record, Thresholds,
    Warmup, crossval, identify,
};
use hystcomp_io::model_file::Direction;
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{VecMpim, excitation, feasible, run};

fn random_plant(rng: &mut impl Rng, thresholds: &[f64]) -> VecMpim {
    let weights: Vec<f64> = thresholds
        .iter()
        .map(|_| rng.random_range(-0.02..0.3))
        .collect();
    Mpim::new(
        thresholds,
        &weights,
        rng.random_range(-0.1..0.1),
        rng.random_range(0.4..1.0),
    )
    .unwrap()
}

/// With thresholds r_i = (i - 0.5)/n no operator is the identity, so a1, a2 and every b_i
/// are determined separately: ls recovers each within 1e-6 on noise-free data (physical
/// units, a sensor offset fitted), over seeded random models.
#[test]
fn ls_recovers_every_parameter_with_thresholds_not_starting_at_zero() {
    let mut tested = 0;
    for seed in 0..40u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = 1 + (seed as usize % 12);
        let thresholds: Vec<f64> = (1..=n).map(|i| (i as f64 - 0.5) / n as f64).collect();
        let model = random_plant(&mut rng, &thresholds);
        let x = excitation(&mut rng, 60);
        if !feasible(&model, &x, Direction::Plant) {
            continue;
        }
        tested += 1;
        let (v_scale, y_scale, y_offset) = (120.0, 40.0, 12.5);
        let voltage: Vec<f64> = x.iter().map(|x| v_scale * x).collect();
        let displacement: Vec<f64> = run(&model, &x)
            .iter()
            .map(|y| y_offset + y_scale * y)
            .collect();
        let fit = identify(
            &voltage,
            &displacement,
            &IdentifyOptions {
                thresholds: Thresholds::Given(thresholds.clone()),
                ..IdentifyOptions::default()
            },
        )
        .unwrap();
        let m = &fit.model;
        let k = m.output.scale / y_scale;
        assert!((k * m.a1 - model.a1()).abs() < 1e-6, "seed {seed}: a1");
        assert!((k * m.a2 - model.a2()).abs() < 1e-6, "seed {seed}: a2");
        for i in 0..n {
            assert!(
                (k * m.weights[i] - model.weights()[i]).abs() < 1e-6,
                "seed {seed}: b{} {} vs {}",
                i + 1,
                k * m.weights[i],
                model.weights()[i]
            );
        }
        assert!((m.output.offset - y_offset).abs() < 1e-6 * y_scale);
        assert!(fit.report.fit.rms_percent < 1e-8);
    }
    assert!(tested >= 20, "only {tested} feasible random models");
}

/// A bipolar input (-5..5 V) from a known model: identified exactly, and the model file maps
/// -5 V to normalised 0.
#[test]
fn a_bipolar_input_is_identified_exactly() {
    let mut tested = 0;
    for seed in 0..20u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(100 + seed);
        let thresholds: Vec<f64> = (0..10).map(|i| i as f64 / 10.0).collect();
        let model = random_plant(&mut rng, &thresholds);
        let x = excitation(&mut rng, 40);
        if !feasible(&model, &x, Direction::Plant) {
            continue;
        }
        tested += 1;
        let voltage: Vec<f64> = x.iter().map(|x| -5.0 + 10.0 * x).collect();
        let displacement: Vec<f64> = run(&model, &x).iter().map(|y| -3.0 + 8.0 * y).collect();
        let fit = identify(&voltage, &displacement, &IdentifyOptions::default()).unwrap();
        assert_eq!(fit.model.input.offset, -5.0);
        assert!((fit.model.input.scale - 10.0).abs() < 1e-12);
        assert!(fit.report.fit.rms_percent < 1e-8, "seed {seed}");
        let predicted = fit.model.predict(&voltage).unwrap();
        for (p, d) in predicted.iter().zip(&displacement) {
            assert!((p - d).abs() < 1e-8, "seed {seed}: {p} vs {d}");
        }
    }
    assert!(tested >= 10, "only {tested} feasible random models");
}

/// A sensor transient in the warm-up (below the later minimum) and a drifting hold-out
/// (above the later maximum) do not enter the normalisation: the ranges, the output scale and
/// every % figure are those of the fitted samples, and the noise-free fit stays exact.
#[test]
fn ranges_are_those_of_the_fitted_samples() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let thresholds: Vec<f64> = (0..10).map(|i| i as f64 / 10.0).collect();
    let model = loop {
        let m = random_plant(&mut rng, &thresholds);
        if feasible(
            &m,
            &excitation(&mut ChaCha8Rng::seed_from_u64(8), 60),
            Direction::Plant,
        ) {
            break m;
        }
    };
    let x = excitation(&mut ChaCha8Rng::seed_from_u64(8), 60);
    // Warm-up: 30 samples at mid-range (the record starts there), then the excitation.
    let warmup = 30;
    let mut input = vec![0.5; warmup];
    input.extend(&x);
    let mut displacement: Vec<f64> = run(&model, &input).iter().map(|y| 10.0 * y).collect();
    for (k, d) in displacement.iter_mut().take(warmup).enumerate() {
        *d -= 15.0 * (-(k as f64) / 10.0).exp(); // the sensor transient
    }
    let voltage: Vec<f64> = input.iter().map(|v| 3.6 * v).collect();
    let fit = identify(
        &voltage,
        &displacement,
        &IdentifyOptions {
            warmup: Warmup::Samples(warmup),
            holdout: 0.0,
            ..IdentifyOptions::default()
        },
    )
    .unwrap();
    let min_max = |v: &[f64]| {
        v.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            })
    };
    let (y_lo, y_hi) = min_max(&displacement[warmup..]);
    let (all_lo, _) = min_max(&displacement);
    assert!(
        all_lo < y_lo - 1.0,
        "the transient lies below the fitted minimum"
    );
    assert_eq!((fit.report.output.min, fit.report.output.max), (y_lo, y_hi));
    assert_eq!(fit.model.output.scale, y_hi - y_lo);
    assert_eq!(fit.report.fit.range, y_hi - y_lo);
    assert!(fit.report.fit.rms_percent < 1e-8);

    // A hold-out that drifts above the fitted maximum does not widen the ranges either.
    let mut drifting = displacement.clone();
    let total = drifting.len();
    let holdout_start = total - ((total - warmup) as f64 * 0.25).floor() as usize;
    for d in &mut drifting[holdout_start..] {
        *d += 5.0;
    }
    let fit = identify(
        &voltage,
        &drifting,
        &IdentifyOptions {
            warmup: Warmup::Samples(warmup),
            holdout: 0.25,
            ..IdentifyOptions::default()
        },
    )
    .unwrap();
    assert_eq!(fit.report.samples.fit, holdout_start - warmup);
    let (f_lo, f_hi) = min_max(&drifting[warmup..holdout_start]);
    let (v_lo, v_hi) = min_max(&voltage[warmup..holdout_start]);
    assert_eq!((fit.report.output.min, fit.report.output.max), (f_lo, f_hi));
    assert_eq!((fit.report.input.min, fit.report.input.max), (v_lo, v_hi));
    let held = fit.report.holdout.unwrap();
    assert!(
        (held.mean - -5.0).abs() < 1e-6,
        "the drift shows in the hold-out"
    );
}

fn plant_record(seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let thresholds: Vec<f64> = (0..10).map(|i| i as f64 / 10.0).collect();
    let model = random_plant(&mut rng, &thresholds);
    let x = excitation(&mut rng, 30);
    let y: Vec<f64> = run(&model, &x)
        .iter()
        .map(|y| 20.0 * y + 0.01 * rng.random::<f64>())
        .collect();
    (x.iter().map(|x| 3.6 * x).collect(), y)
}

/// Inputs where the displacement does not rise with the voltage are refused, naming the
/// correlation and what to check; the same column twice is refused; a fit far off the data
/// is refused unless explicitly accepted.
#[test]
fn fits_that_cannot_describe_a_piezo_are_refused() {
    let (voltage, displacement) = plant_record(3);
    let options = IdentifyOptions::default();
    assert!(identify(&voltage, &displacement, &options).is_ok());

    // Sign flipped.
    let flipped: Vec<f64> = displacement.iter().map(|d| -d).collect();
    let err = identify(&voltage, &flipped, &options).unwrap_err();
    let IdentifyError::NotRising { correlation, .. } = err else {
        panic!("{err}");
    };
    assert!(correlation < -0.9, "{correlation}");
    let message = err_text(&voltage, &flipped, &options);
    assert!(
        message.contains("correlation") && message.contains("sign"),
        "{message}"
    );
    assert!(message.contains(&format!("{correlation:.3}")), "{message}");

    // A nearly constant column: a constant plus 1e-6 noise.
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let noise: Vec<f64> = voltage
        .iter()
        .map(|_| 4.2 + 1e-6 * rng.random::<f64>())
        .collect();
    for direction in [Direction::Plant, Direction::Inverse] {
        let o = IdentifyOptions {
            direction,
            ..options.clone()
        };
        let err = identify(&voltage, &noise, &o).unwrap_err();
        assert!(matches!(err, IdentifyError::NotRising { .. }), "{err}");
    }

    // The same column twice, or a scaled copy of it.
    for copy in [
        voltage.clone(),
        voltage.iter().map(|v| 15.0 * v - 2.0).collect(),
    ] {
        let err = identify(&voltage, &copy, &options).unwrap_err();
        assert!(matches!(err, IdentifyError::SameSignal), "{err}");
        assert!(err.to_string().contains("same column"), "{err}");
    }

    // An output offset far off the data: a poor fit, refused by default, accepted on request.
    let far = IdentifyOptions {
        offset: OutputOffset::Value(-100.0),
        ..options.clone()
    };
    let err = identify(&voltage, &displacement, &far).unwrap_err();
    let IdentifyError::PoorFit { rms_percent, limit } = err else {
        panic!("{err}");
    };
    assert!(rms_percent > limit && limit == 10.0);
    assert!(err_text(&voltage, &displacement, &far).contains("--accept-poor-fit"));
    let accepted = identify(
        &voltage,
        &displacement,
        &IdentifyOptions {
            max_fit_rms_percent: None,
            ..far
        },
    )
    .unwrap();
    assert_eq!(accepted.report.fit.rms_percent, rms_percent);
}

fn err_text(voltage: &[f64], displacement: &[f64], options: &IdentifyOptions) -> String {
    identify(voltage, displacement, options)
        .unwrap_err()
        .to_string()
}

/// A test record with fewer samples after its warm-up than identifying the model needs is
/// refused with the number needed, counted as identification counts the parameters; one more
/// sample is enough.
#[test]
fn crossval_needs_enough_test_samples() {
    let (voltage, displacement) = plant_record(5);
    let train = Record {
        voltage: &voltage,
        displacement: &displacement,
    };
    // 10 operators with r_1 = 0 (a2 and b_1 are one parameter): a1, a2 + b_1, b_2..b_10 and
    // the offset c when it is fitted: 12 parameters, 3 samples each; 11 without c.
    for (offset, needed) in [(OutputOffset::Fit, 36), (OutputOffset::None, 33)] {
        let mut options = CrossvalOptions {
            test_warmup: Warmup::Samples(0),
            ..CrossvalOptions::default()
        };
        options.identify.offset = offset;
        for (len, ok) in [(2, false), (needed - 1, false), (needed, true)] {
            let test = Record {
                voltage: &voltage[..len],
                displacement: &displacement[..len],
            };
            let result = crossval(train, test, &options, &mut NoObserver);
            match (result, ok) {
                (Ok(cv), true) => assert_eq!(cv.report.test.forward.samples, needed),
                (Err(e), false) => {
                    let m = e.to_string();
                    assert!(m.contains(&format!("at least {needed}")), "{m}");
                    assert!(m.contains("test record"), "{m}");
                }
                (Ok(_), false) => panic!("{offset:?}: {len} test samples accepted"),
                (Err(e), true) => panic!("{offset:?}: {len} test samples refused: {e}"),
            }
        }
    }
}

/// One observer watches both identifications of a cross-validation; each is announced, so
/// that a progress bar can label them (plant, then inverse), and each reports its iterations.
#[test]
fn crossval_announces_each_identification_to_its_observer() {
    struct Log(Vec<String>);
    impl hystcomp_identify::Observer for Log {
        fn observe(&mut self, progress: &hystcomp_identify::Progress) {
            if progress.iteration == progress.iterations {
                self.0.push(format!("done {}", progress.iterations));
            }
        }
        fn begin(&mut self, label: &str) {
            self.0.push(label.to_owned());
        }
    }
    let (voltage, displacement) = plant_record(9);
    let record = Record {
        voltage: &voltage,
        displacement: &displacement,
    };
    let options = CrossvalOptions {
        identify: IdentifyOptions {
            method: hystcomp_identify::Method::ParticleSwarm(
                hystcomp_identify::PsoOptions::default()
                    .with_iterations(5)
                    .unwrap()
                    .with_polish(true),
            ),
            ..IdentifyOptions::default()
        },
        ..CrossvalOptions::default()
    };
    let mut log = Log(Vec::new());
    crossval(record, record, &options, &mut log).unwrap();
    assert_eq!(
        log.0,
        ["plant model", "done 5", "inverse model", "done 5"],
        "{:?}",
        log.0
    );
}
