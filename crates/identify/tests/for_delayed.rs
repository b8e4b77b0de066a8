//! Identification for delayed compensation (`IdentifyOptions::delayed_loop_bound`, the command
//! line's `--for-delayed`): both delayed loops' gains, as the core computes them over the
//! whole reachable state, stay at most the bound, with least squares and with the swarm; the
//! report says what the bound cost in fit RMS. Also: `--accept-poor-fit` lets a record whose
//! displacement does not rise with the voltage through.

mod common;

use hystcomp_core::{Ihc, OutputLimits, SolveMode, Wihc};
use hystcomp_identify::{
    DEFAULT_DELAYED_LOOP_BOUND, IdentifyError, IdentifyOptions, Method, PsoOptions, Thresholds,
    identify,
};
use hystcomp_io::model_file::Direction;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{excitation, random_plant, run};

fn seeded(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A noisy record of a random plant model, in volts and micrometres.
fn record(seed: u64, n: usize, noise: f64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let model = random_plant(&mut rng, n);
    let x = excitation(&mut rng, 30);
    let y = run(&model, &x);
    let voltage = x.iter().map(|x| 150.0 * x).collect();
    let displacement = y
        .iter()
        .map(|y| 75.0 * y + noise * (rng.random::<f64>() - 0.5))
        .collect();
    (voltage, displacement)
}

/// Both delayed loops' gains of a fit's plant model, from the core.
fn gains(fit: &hystcomp_identify::Identification) -> (f64, f64) {
    let m = fit.model.model().unwrap();
    (
        m.delayed_ihc_loop_gain(0.0, 1.0).unwrap().gain,
        m.delayed_wihc_loop_gain(0.0, 1.0).unwrap().gain,
    )
}

proptest! {
    #![proptest_config(seeded(20, 10))]

    /// Least squares with the bound: both gains at most the bound (to rounding), the plain
    /// delayed loops build, the report's figures are the unconstrained fit's, and the bound
    /// never improves the fit.
    #[test]
    fn least_squares_keeps_both_delayed_gains_within_the_bound(
        seed in any::<u64>(),
        n in 1usize..40,
        bound in 0.3f64..0.98,
        noise in 0.0f64..2.0,
    ) {
        let (voltage, displacement) = record(seed, n, noise);
        let free_options = IdentifyOptions {
            thresholds: Thresholds::Uniform(n),
            max_fit_rms_percent: None,
            max_condition: 1e14,
            ..IdentifyOptions::default()
        };
        let options = IdentifyOptions {
            delayed_loop_bound: Some(bound),
            ..free_options.clone()
        };
        let free = identify(&voltage, &displacement, &free_options).unwrap();
        let fit = identify(&voltage, &displacement, &options).unwrap();
        let (ihc, wihc) = gains(&fit);
        prop_assert!(ihc <= bound * (1.0 + 1e-9) + 1e-9, "ihc {ihc} > {bound}");
        prop_assert!(wihc <= bound * (1.0 + 1e-9) + 1e-9, "wihc {wihc} > {bound}");
        let reported = fit.report.delayed_loop_gains.unwrap();
        prop_assert!((reported.ihc - ihc).abs() < 1e-12 && (reported.wihc - wihc).abs() < 1e-12);
        let m = fit.model.model().unwrap();
        let limits = OutputLimits::new(0.0, 1.0).unwrap();
        prop_assert!(Ihc::<f64, Vec<f64>>::new(&m, limits, SolveMode::Delayed).is_ok());
        prop_assert!(Wihc::<f64, Vec<f64>>::new(&m, limits, SolveMode::Delayed).is_ok());
        let c = fit.report.delayed_constraint.expect("the constraint is reported");
        prop_assert_eq!(c.bound, bound);
        prop_assert!((c.unconstrained_fit_rms_percent - free.report.fit.rms_percent).abs()
            < 1e-6 * (1.0 + free.report.fit.rms_percent));
        let free_gains = free.report.delayed_loop_gains.unwrap();
        prop_assert!((c.unconstrained_gains.wihc - free_gains.wihc).abs() < 1e-9 * (1.0 + free_gains.wihc));
        prop_assert!(fit.report.fit.rms_percent >= c.unconstrained_fit_rms_percent - 1e-9);
        prop_assert!(free.report.delayed_constraint.is_none());
    }
}

/// The swarm gets the same rows as a penalty: it returns a model within the bound or says it
/// found none; never a model whose delayed loop can ring.
#[test]
fn the_swarm_returns_a_model_within_the_bound_or_none() {
    let mut returned = 0;
    for seed in 0..6 {
        let (voltage, displacement) = record(seed, 8, 0.5);
        let options = IdentifyOptions {
            thresholds: Thresholds::Uniform(8),
            method: Method::ParticleSwarm(
                PsoOptions::default()
                    .with_seed(seed)
                    .with_iterations(150)
                    .unwrap(),
            ),
            delayed_loop_bound: Some(DEFAULT_DELAYED_LOOP_BOUND),
            max_fit_rms_percent: None,
            ..IdentifyOptions::default()
        };
        match identify(&voltage, &displacement, &options) {
            Ok(fit) => {
                let (ihc, wihc) = gains(&fit);
                assert!(ihc < 1.0 && wihc < 1.0, "seed {seed}: {ihc} {wihc}");
                assert!(ihc <= 0.9 * (1.0 + 1e-6) && wihc <= 0.9 * (1.0 + 1e-6));
                returned += 1;
            }
            Err(IdentifyError::SwarmInfeasible { .. }) => {}
            Err(e) => panic!("seed {seed}: {e}"),
        }
    }
    assert!(
        returned >= 3,
        "the swarm found a model within the bound {returned} times of 6"
    );
}

/// Inverse models have no delayed loop: the bound changes nothing. Bounds outside (0, 1) are
/// refused, naming the option.
#[test]
fn inverse_models_ignore_the_bound_and_bad_bounds_are_refused() {
    let (voltage, displacement) = record(3, 6, 0.1);
    let inverse = IdentifyOptions {
        direction: Direction::Inverse,
        thresholds: Thresholds::Uniform(6),
        ..IdentifyOptions::default()
    };
    let a = identify(&voltage, &displacement, &inverse).unwrap();
    let b = identify(
        &voltage,
        &displacement,
        &IdentifyOptions {
            delayed_loop_bound: Some(0.5),
            ..inverse.clone()
        },
    )
    .unwrap();
    assert_eq!(a.parameters, b.parameters);
    assert!(b.report.delayed_constraint.is_none());
    for bad in [0.0, 1.0, 1.5, -0.2, f64::NAN] {
        let err = identify(
            &voltage,
            &displacement,
            &IdentifyOptions {
                delayed_loop_bound: Some(bad),
                ..IdentifyOptions::default()
            },
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("delayed loop bound"),
            "{bad}: {err}"
        );
    }
}

/// A displacement falling with the voltage is refused by default, with the override named;
/// accepted with `max_fit_rms_percent: None` (`--accept-poor-fit`). The same column twice
/// stays refused.
#[test]
fn accept_poor_fit_overrides_the_correlation_refusal() {
    let (voltage, displacement) = record(5, 6, 0.1);
    let flipped: Vec<f64> = displacement.iter().map(|d| -d).collect();
    let err = identify(&voltage, &flipped, &IdentifyOptions::default()).unwrap_err();
    assert!(matches!(err, IdentifyError::NotRising { .. }), "{err}");
    assert!(err.to_string().contains("--accept-poor-fit"), "{err}");
    let accepting = IdentifyOptions {
        max_fit_rms_percent: None,
        ..IdentifyOptions::default()
    };
    let fit = identify(&voltage, &flipped, &accepting).unwrap();
    assert!(fit.report.fit.rms_percent.is_finite());
    assert!(matches!(
        identify(&voltage, &voltage, &accepting).unwrap_err(),
        IdentifyError::SameSignal
    ));
}

/// A swarm cut short far from the optimum is said to have not converged, with the
/// least-squares figure beside it, instead of blaming the columns or the offset.
#[test]
fn a_swarm_far_from_the_optimum_says_it_did_not_converge() {
    let (voltage, displacement) = record(9, 10, 0.1);
    let ls = identify(
        &voltage,
        &displacement,
        &IdentifyOptions {
            thresholds: Thresholds::Uniform(10),
            ..IdentifyOptions::default()
        },
    )
    .unwrap();
    let mut said = 0;
    // (Thirty particles: the swarm searches the branch slopes, where a handful of random
    // particles is rarely feasible.)
    for seed in 0..12 {
        let options = IdentifyOptions {
            thresholds: Thresholds::Uniform(10),
            method: Method::ParticleSwarm(
                PsoOptions::default()
                    .with_seed(seed)
                    .with_iterations(3)
                    .unwrap()
                    .with_particles(30)
                    .unwrap(),
            ),
            ..IdentifyOptions::default()
        };
        match identify(&voltage, &displacement, &options) {
            Err(e @ IdentifyError::SwarmNotConverged { .. }) => {
                let IdentifyError::SwarmNotConverged {
                    rms_percent,
                    least_squares_rms_percent,
                    limit,
                } = e
                else {
                    unreachable!()
                };
                assert!(rms_percent > limit);
                assert!(
                    (least_squares_rms_percent - ls.report.fit.rms_percent).abs()
                        < 1e-6 * (1.0 + ls.report.fit.rms_percent)
                );
                let message = e.to_string();
                assert!(message.contains("did not converge"), "{message}");
                assert!(!message.contains("columns"), "{message}");
                said += 1;
            }
            // A swarm this short may also end infeasible (said as such) or, by chance, within
            // the limit (a usable model).
            Err(IdentifyError::SwarmInfeasible { .. }) => {}
            Ok(fit) => assert!(fit.report.fit.rms_percent <= 10.0),
            Err(e) => panic!("seed {seed}: {e}"),
        }
    }
    assert!(
        said >= 1,
        "no short swarm ended feasible but far from the optimum"
    );
}
