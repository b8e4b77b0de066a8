//! `IdentifyOptions::input_degree` (the command line's `--input-degree`): an odd input
//! polynomial of degree 5, 7 or 9 fitted by least squares under the same invertibility
//! constraints as the paper's cubic (issue 10).

mod common;

use hystcomp_core::{Compensator, Ihc, InputPolynomial, Mpim, OutputLimits, SolveMode};
use hystcomp_identify::{IdentifyError, IdentifyOptions, Method, PsoOptions, Warmup, identify};
use hystcomp_io::model_file::ModelFile;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn options(degree: usize) -> IdentifyOptions {
    IdentifyOptions {
        input_degree: degree,
        ..IdentifyOptions::default()
    }
}

/// A record from a known model with a degree-7 odd input polynomial: least squares with
/// degree 7 recovers it exactly, the cubic cannot, and every degree gives an invertible model.
#[test]
fn a_degree7_model_is_recovered_and_every_degree_is_invertible() {
    let thresholds: Vec<f64> = (0..10).map(|i| i as f64 / 10.0).collect();
    let weights = [
        0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ];
    // g(x) = 0.46 x - 0.16 x^3 + 0.3 x^5 - 0.2 x^7: g' > 0 on [0, 1] with the weights.
    let g = InputPolynomial::new(&[0.4603, 0.0, -0.1569, 0.0, 0.3, 0.0, -0.2]).unwrap();
    let mut truth: Mpim<f64, Vec<f64>> =
        Mpim::with_input_polynomial(&thresholds, &weights, g).unwrap();
    let v: Vec<f64> = (0..3000)
        .map(|k| {
            let t = k as f64 / 200.0;
            5.0 - 5.0 * (-t / 10.0).exp() * (2.0 * std::f64::consts::PI * t).cos()
        })
        .collect();
    let (lo, hi) = v
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let y: Vec<f64> = v
        .iter()
        .map(|x| 75.0 * truth.step((x - lo) / (hi - lo)))
        .collect();
    let mut previous = f64::INFINITY;
    let mut cubic = f64::NAN;
    for degree in [3, 5, 7, 9] {
        let fit = identify(&v, &y, &options(degree)).unwrap();
        let rms = fit.report.fit.rms_percent;
        eprintln!("degree {degree}: fit RMS {rms:.3e} %");
        // A higher degree holds the lower ones: never worse (to rounding).
        assert!(
            rms <= previous * (1.0 + 1e-6) + 1e-9,
            "degree {degree}: {rms} > {previous}"
        );
        previous = rms;
        if degree == 3 {
            cubic = rms;
        }
        if degree >= 7 {
            assert!(rms < 1e-5, "degree {degree} recovers the model: {rms}");
            assert!(
                rms < cubic / 100.0,
                "the cubic cannot: {cubic} against {rms}"
            );
        }
        let model = fit.model.model().unwrap();
        assert_eq!(
            model.input_polynomial().degree(),
            degree,
            "the model file holds the polynomial"
        );
        assert!(model.check_invertible(0.0, 1.0).is_ok());
        assert_eq!(fit.parameters.higher.len(), (degree - 3) / 2);
    }
}

#[test]
fn unusable_degrees_and_the_swarm_are_refused() {
    let v: Vec<f64> = (0..400).map(|k| (k as f64 * 0.05).sin()).collect();
    let y = v.clone();
    for degree in [0, 1, 2, 4, 11] {
        match identify(&v, &y, &options(degree)) {
            Err(IdentifyError::InvalidOption { option, .. }) => {
                assert_eq!(option, "input degree")
            }
            other => panic!("degree {degree}: {other:?}"),
        }
    }
    let swarm = IdentifyOptions {
        method: Method::ParticleSwarm(PsoOptions::default()),
        ..options(7)
    };
    match identify(&v, &y, &swarm) {
        Err(IdentifyError::InvalidOption { option, reason, .. }) => {
            assert_eq!(option, "input degree");
            assert!(reason.contains("least squares"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

/// The shared DBO record: degree 7 fits no worse than the cubic, the model file round-trips,
/// and IHC built on the degree-7 model keeps its invariants (within its limits, finite, and
/// the model replaying its drive tracks every reachable desired position).
#[test]
fn dbo_degree7_fits_no_worse_round_trips_and_compensates() {
    let Some((v, y)) = common::dbo_record("Model_Vi_Do.dat") else {
        return;
    };
    let (v, y) = (&v, &y);
    let fit = |degree| {
        identify(
            v,
            y,
            &IdentifyOptions {
                holdout: 0.2,
                warmup: Warmup::Auto,
                ..options(degree)
            },
        )
        .unwrap()
    };
    let cubic = fit(3);
    let seventh = fit(7);
    for (name, f) in [("degree 3", &cubic), ("degree 7", &seventh)] {
        eprintln!(
            "DBO n=10 {name}: fit RMS {:.4} %, hold-out RMS {:.4} %, smallest branch slope \
             {:.4}, {}/{} constraints active",
            f.report.fit.rms_percent,
            f.report.holdout.as_ref().unwrap().rms_percent,
            f.report.min_branch_slope,
            f.report.active_constraints,
            f.report.constraints
        );
    }
    assert!(seventh.report.fit.rms_percent <= cubic.report.fit.rms_percent * (1.0 + 1e-9));
    assert_eq!(seventh.report.samples, cubic.report.samples);

    // The model file round-trips, polynomial included.
    let text = seventh.model.to_json();
    let back = ModelFile::from_json(&text).unwrap();
    assert_eq!(back, seventh.model);
    assert_eq!(back.input_polynomial.as_ref().unwrap().len(), 7);
    let model = back.model().unwrap();
    assert_eq!(model.input_polynomial().degree(), 7);

    // IHC (exact solve) on the degree-7 model, desired positions over and beyond the range.
    let limits = OutputLimits::new(0.0, 1.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for run in 0..20 {
        let mut ihc = Ihc::<f64, Vec<f64>>::new(&model, limits, SolveMode::Exact).unwrap();
        let mut plant = model.clone();
        plant.reset();
        let (low, high) = (plant.clone().step(0.0), {
            let mut p = model.clone();
            p.reset();
            p.step(1.0)
        });
        let mut desired = 0.5 * (low + high);
        for k in 0..2000 {
            desired += 0.05 * (rng.random::<f64>() - 0.5);
            desired = desired.clamp(low - 0.1, high + 0.1);
            let drive = ihc.step(desired);
            assert!(drive.is_finite(), "run {run}, sample {k}: NaN drive");
            assert!(
                (0.0..=1.0).contains(&drive),
                "run {run}, sample {k}: {drive}"
            );
            let reached = plant.step(drive);
            if drive > 1e-9 && drive < 1.0 - 1e-9 {
                assert!(
                    (reached - desired).abs() < 1e-9,
                    "run {run}, sample {k}: the model reaches {reached}, desired {desired}"
                );
            }
        }
    }
}
