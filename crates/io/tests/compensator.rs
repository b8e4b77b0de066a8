//! Compensators built from model files, in physical units.

use std::path::PathBuf;

use hystcomp_core::CoreError;
use hystcomp_io::compensator::{CompensatorError, Method, ScaledCompensator, UnstableDelay};
use hystcomp_io::model_file::{CreepPart, ModelFile};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn example(name: &str) -> ModelFile {
    ModelFile::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../models")
            .join(name),
    )
    .unwrap()
}

#[test]
fn plant_compensators_round_trip_in_physical_units() {
    let file = example("table1-plant.json");
    let mut plant = file.model().unwrap();
    // Desired positions (um) produced by a voltage sweep (V) through the plant.
    let volts: Vec<f64> = (0..3000)
        .map(|k| 5.0 + 4.5 * (k as f64 * 0.004).sin() * (k as f64 * 0.0007).cos())
        .collect();
    let desired: Vec<f64> = volts
        .iter()
        .map(|&v| file.output_to_physical(plant.step(file.normalise_input(v))))
        .collect();
    for method in [Method::Ihc, Method::Wihc] {
        let mut c = ScaledCompensator::new(&file, method, None).unwrap();
        assert_eq!(c.limits(), (0.0, 10.0));
        assert_eq!((c.desired_unit(), c.control_unit()), ("um", "V"));
        let mut out = vec![0.0; desired.len()];
        c.process(&desired, &mut out).unwrap();
        for (k, (v, v_true)) in out.iter().zip(&volts).enumerate() {
            assert!(
                (v - v_true).abs() < 1e-8,
                "{method} sample {k}: {v} V vs {v_true} V"
            );
        }
        assert_eq!(c.diagnostics().saturated, 0);
    }
}

#[test]
fn each_method_needs_its_direction_of_model() {
    let plant = example("table1-plant.json");
    let inverse = example("table2-inverse.json");
    let err = ScaledCompensator::new(&plant, Method::Dihc, None).unwrap_err();
    assert!(matches!(err, CompensatorError::WrongDirection { .. }));
    assert!(
        err.to_string().contains("dihc needs an inverse model"),
        "{err}"
    );
    let err = ScaledCompensator::new(&inverse, Method::Ihc, None).unwrap_err();
    assert!(err.to_string().contains("ihc needs a plant model"), "{err}");
    assert!(ScaledCompensator::new(&inverse, Method::Dihc, None).is_ok());
}

#[test]
fn methods_parse_by_name_and_bad_limits_are_refused() {
    for m in Method::ALL {
        assert_eq!(m.name().parse::<Method>().unwrap(), m);
    }
    assert!(
        "ihc_exact"
            .parse::<Method>()
            .unwrap_err()
            .to_string()
            .contains("choose one of")
    );
    let plant = example("table1-plant.json");
    for limits in [(5.0, 1.0), (0.0, f64::NAN), (f64::NEG_INFINITY, 1.0)] {
        let err = ScaledCompensator::new(&plant, Method::Ihc, Some(limits)).unwrap_err();
        assert!(
            matches!(err, CompensatorError::InvalidLimits { .. }),
            "{err:?}"
        );
    }
}

proptest! {
    #![proptest_config(Config { cases: 64, rng_seed: RngSeed::Fixed(7), failure_persistence: None, ..Config::default() })]

    /// The physical drive never leaves the limits and is never NaN, whatever is fed.
    #[test]
    fn physical_output_stays_within_the_limits(
        desired in prop::collection::vec(prop_oneof![
            4 => -50.0f64..150.0,
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
            1 => any::<f64>(),
        ], 1..200),
        lo in 0.0f64..4.0,
        width in 0.1f64..6.0,
    ) {
        let plant = example("table1-plant.json");
        let inverse = example("table2-inverse.json");
        let limits = (lo, lo + width);
        for method in Method::ALL {
            let file = if method == Method::Dihc { &inverse } else { &plant };
            // Table 1's delayed WIHC can ring: allowed explicitly, its drive must stay within
            // the limits too.
            let mut c = ScaledCompensator::with_unstable_delay(file, method, Some(limits), UnstableDelay::Allow).unwrap();
            for &d in &desired {
                let v = c.step(d);
                prop_assert!(v >= limits.0 && v <= limits.1, "{} gave {} for {}", method, v, d);
            }
        }
    }
}

#[test]
fn plant_methods_report_their_delayed_loop_gain_and_dihc_its_desired_range() {
    let plant = example("table1-plant.json");
    let inverse = example("table2-inverse.json");
    // Table 1 over 0..10 V: all ten operators moving near 0 V, (b_1 + ... + b_10) / a2.
    let wihc_gain = plant.weights.iter().sum::<f64>() / plant.a2;
    // IHC: |3 a1 x^2| / (a2 + b_1) at x = 1.
    let ihc_gain = 3.0 * plant.a1.abs() / (plant.a2 + plant.weights[0]);
    for (method, expected) in [
        (Method::Wihc, wihc_gain),
        (Method::WihcGuarded, wihc_gain),
        (Method::Ihc, ihc_gain),
        (Method::IhcDelayed, ihc_gain),
        (Method::IhcGuarded, ihc_gain),
    ] {
        let c = ScaledCompensator::new(&plant, method, None).unwrap();
        let gain = c.delayed_loop_gain().unwrap();
        assert!((gain - expected).abs() < 1e-12, "{method}: {gain}");
        assert_eq!(c.desired_range(), None);
        let relaxation = c.guard_relaxation().unwrap();
        assert!(
            relaxation > 0.0 && relaxation <= 1.0,
            "{method}: {relaxation}"
        );
    }
    // The plain delayed WIHC (gain 1.66) is refused unless allowed.
    let err = ScaledCompensator::new(&plant, Method::WihcDelayed, None).unwrap_err();
    assert!(
        matches!(
            err,
            CompensatorError::Core(CoreError::DelayedLoopUnstable { .. })
        ),
        "{err:?}"
    );
    let allowed = ScaledCompensator::with_unstable_delay(
        &plant,
        Method::WihcDelayed,
        None,
        UnstableDelay::Allow,
    )
    .unwrap();
    assert!((allowed.delayed_loop_gain().unwrap() - wihc_gain).abs() < 1e-12);
    let dihc = ScaledCompensator::new(&inverse, Method::Dihc, None).unwrap();
    let lo = inverse.input.to_physical(inverse.input_range[0]);
    let hi = inverse.input.to_physical(inverse.input_range[1]);
    assert_eq!(dihc.desired_range(), Some((lo.min(hi), lo.max(hi))));
    assert_eq!(dihc.delayed_loop_gain(), None);
    assert_eq!(dihc.guard_relaxation(), None);
    // An inverse chain's hysteresis link takes the creep-free displacement: no range of
    // desired positions is claimed for it.
    let mut chain = inverse.clone();
    chain.format_version = 2;
    chain.sample_rate_hz = Some(1000.0);
    chain.creep = Some(CreepPart {
        origin: 0.0,
        time_constants_s: vec![0.1, 1.0],
        weights: vec![0.02, 0.03],
    });
    chain.validate().unwrap();
    let dihc = ScaledCompensator::new(&chain, Method::Dihc, None).unwrap();
    assert_eq!(dihc.desired_range(), None);
}

#[test]
fn delayed_wihc_ringing_on_table1_is_a_loop_saturation_not_an_unreachable_position() {
    let plant = example("table1-plant.json");
    let mut delayed = ScaledCompensator::with_unstable_delay(
        &plant,
        Method::WihcDelayed,
        None,
        UnstableDelay::Allow,
    )
    .unwrap();
    let mut exact = ScaledCompensator::new(&plant, Method::Wihc, None).unwrap();
    let mut guarded = ScaledCompensator::new(&plant, Method::WihcGuarded, None).unwrap();
    // 35 + 20 sin(2 pi t) um from rest at 10 kHz: reachable all along (the exact WIHC says so).
    for k in 0..10_000 {
        let y = 35.0 + 20.0 * (2.0 * std::f64::consts::PI * k as f64 * 1e-4).sin();
        for c in [&mut delayed, &mut exact, &mut guarded] {
            let v = c.step(y);
            assert!((0.0..=10.0).contains(&v));
        }
    }
    assert_eq!(exact.diagnostics(), Default::default());
    // The guarded loop does not ring.
    assert_eq!(guarded.diagnostics(), Default::default());
    let d = delayed.diagnostics();
    assert_eq!(d.saturated, 0, "{d:?}");
    assert!(d.loop_saturated > 10, "{d:?}");
}
