//! The learner's invariants on a model-made "stage": drives within the limits and finite for
//! any gain, bandwidth and measurement; the divergence guard; the reference recovered from a
//! drive; convergence when the model is wrong.

use std::path::Path;

use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::{LearnError, Learner, LearningOptions, Status};
use proptest::prelude::*;

fn table1() -> ModelFile {
    ModelFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/table1-plant.json"))
        .expect("Table 1 model")
}

fn sine(n: usize, mid: f64, amplitude: f64) -> Vec<f64> {
    (0..n)
        .map(|k| mid + amplitude * (2.0 * std::f64::consts::PI * k as f64 / n as f64).sin())
        .collect()
}

/// The periodic state of `plant` driven by `drive` (the middle of three periods).
fn periodic_response(plant: &ModelFile, drive: &[f64]) -> Vec<f64> {
    let n = drive.len();
    let three: Vec<f64> = drive.iter().chain(drive).chain(drive).copied().collect();
    plant.predict(&three).unwrap()[n..2 * n].to_vec()
}

/// A plant the model gets wrong: output scaled by `k` about 0.
fn wrong_plant(k: f64) -> ModelFile {
    let mut plant = table1();
    plant.output.scale *= k;
    plant.output.offset *= k;
    plant
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Whatever is measured (even nonsense far outside the range) and whatever the gain and
    /// bandwidth, the next drive stays within the limits and is finite.
    #[test]
    fn drives_stay_within_the_limits(
        gain in 0.01f64..10.0,
        bandwidth in 1.0f64..500.0,
        order in 1usize..5,
        periodic in any::<bool>(),
        mid in 5.0f64..60.0,
        amplitude in 0.0f64..40.0,
        wild in prop::collection::vec(-1e4f64..1e4, 64),
        lo in 0.0f64..3.0,
        width in 1.0f64..7.0,
    ) {
        let model = table1();
        let desired = sine(64, mid, amplitude);
        let mut options = LearningOptions::new(1000.0);
        options.gain = gain;
        options.bandwidth_hz = Some(bandwidth);
        options.filter_order = order;
        options.periodic = periodic;
        options.limits = Some((lo, lo + width));
        options.divergence_factor = 100.0;
        options.mhe_bins = 6;
        let mut learner = Learner::new(&model, &desired, options).unwrap();
        for trial in 0..4 {
            let measured: Vec<f64> = if trial % 2 == 0 {
                wild.clone()
            } else {
                periodic_response(&model, learner.drive())
            };
            let _ = learner.update(&measured);
            prop_assert!(learner
                .drive()
                .iter()
                .all(|v| v.is_finite() && *v >= lo && *v <= lo + width));
        }
    }
}

#[test]
fn converges_when_the_model_is_wrong_by_thirty_percent() {
    for k in [0.7, 1.3] {
        let plant = wrong_plant(k);
        let desired = sine(500, 30.0, 15.0); // within reach of the 0.7 plant
        let mut options = LearningOptions::new(500.0);
        options.mhe_bins = 10;
        let mut learner = Learner::new(&table1(), &desired, options).unwrap();
        let mut e = Vec::new();
        for _ in 0..10 {
            let measured = periodic_response(&plant, learner.drive());
            e.push(learner.update(&measured).unwrap().indices.e_rms_percent);
        }
        assert!(e[9] < 1e-3 * e[0], "k = {k}: {e:?}");
    }
}

#[test]
fn divergence_guard_stops_a_gain_too_high_and_keeps_the_last_good_drive() {
    let plant = wrong_plant(1.1);
    let desired = sine(400, 35.0, 20.0);
    let mut options = LearningOptions::new(400.0);
    options.gain = 4.0;
    options.mhe_bins = 10;
    let mut learner = Learner::new(&table1(), &desired, options).unwrap();
    let first = learner.drive().to_vec();
    let mut stopped = None;
    for _ in 0..10 {
        let measured = periodic_response(&plant, learner.drive());
        let update = learner.update(&measured).unwrap();
        if let Status::Diverged { best_trial, .. } = update.status {
            stopped = Some((update.trial, best_trial));
            break;
        }
    }
    let (trial, best) = stopped.expect("the guard trips");
    assert_eq!((trial, best), (1, 0));
    assert_eq!(
        learner.drive(),
        first.as_slice(),
        "the last good drive is kept"
    );
    let again = learner.update(&desired).unwrap_err();
    assert!(matches!(
        again,
        LearnError::Stopped {
            trial: 1,
            best_trial: 0
        }
    ));
    assert!(again.to_string().contains("lower gain"), "{again}");
}

/// The reference is recoverable from the drive alone: resuming from a learner's drive gives
/// back its reference (the model maps the exact inverse's drive onto it).
#[test]
fn resume_recovers_the_reference_from_the_drive() {
    let plant = wrong_plant(0.9);
    let desired = sine(300, 35.0, 25.0);
    let mut options = LearningOptions::new(300.0);
    options.mhe_bins = 10;
    let mut learner = Learner::new(&table1(), &desired, options.clone()).unwrap();
    for _ in 0..3 {
        let measured = periodic_response(&plant, learner.drive());
        learner.update(&measured).unwrap();
    }
    let resumed = Learner::resume(&table1(), &desired, learner.drive(), options).unwrap();
    let worst = resumed
        .reference()
        .iter()
        .zip(learner.reference())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "{worst}");
    assert_eq!(resumed.drive(), learner.drive());
}

/// The defaults at 100 Hz with e_mhe over 10 bins (a 100-sample trial holds no more).
fn options() -> LearningOptions {
    let mut options = LearningOptions::new(100.0);
    options.mhe_bins = 10;
    options
}

#[test]
fn bad_records_and_options_are_refused_with_their_names() {
    let desired = sine(100, 35.0, 20.0);
    let mut learner = Learner::new(&table1(), &desired, options()).unwrap();
    let short = learner.update(&desired[..50]).unwrap_err();
    assert!(short.to_string().contains("50 samples"), "{short}");
    let mut nan = desired.clone();
    nan[7] = f64::NAN;
    assert!(matches!(
        learner.update(&nan),
        Err(LearnError::NonFinite {
            what: "measured",
            index: 7
        })
    ));
    for (set, name) in [
        (
            Box::new(|o: &mut LearningOptions| o.gain = 0.0) as Box<dyn Fn(&mut LearningOptions)>,
            "gain",
        ),
        (
            Box::new(|o: &mut LearningOptions| o.bandwidth_hz = Some(60.0)),
            "bandwidth",
        ),
        (
            Box::new(|o: &mut LearningOptions| o.divergence_factor = 1.0),
            "divergence factor",
        ),
        (
            Box::new(|o: &mut LearningOptions| o.filter_order = 0),
            "filter order",
        ),
        (
            // 100 samples hold 10 bins of 10 samples: 11 would read e_mhe low.
            Box::new(|o: &mut LearningOptions| o.mhe_bins = 11),
            "e_mhe bins",
        ),
    ] {
        let mut options = options();
        set(&mut options);
        let e = Learner::new(&table1(), &desired, options).unwrap_err();
        assert!(e.to_string().starts_with(name), "{e}");
    }
    let mut inverse = table1();
    inverse.direction = hystcomp_io::model_file::Direction::Inverse;
    let e = Learner::new(&inverse, &desired, options()).unwrap_err();
    assert!(e.to_string().contains("plant model"), "{e}");
    let e = Learner::resume(&table1(), &desired, &vec![11.0; 100], options()).unwrap_err();
    assert!(e.to_string().contains("leaves the limits"), "{e}");
}
