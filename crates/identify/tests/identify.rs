//! Identification on seeded random synthetic records: exact recovery, optimality under the
//! constraints, the two solvers of one problem, the core's checks, reports and errors.

mod common;

use hystcomp_core::{Dihc, Ihc, Mpim, OutputLimits, SolveMode, Wihc};
use hystcomp_identify::{
    CrossvalOptions, FitProblem, IdentifyError, IdentifyOptions, LeastSquares, Method, NoObserver,
    OutputOffset, ParticleSwarm, ProblemData, PsoOptions, Record, Solver, Thresholds, Validation,
    Warmup, crossval, identify, validate_models,
};
use hystcomp_io::compensator::{Method as CompensatorMethod, ScaledCompensator, UnstableDelay};
use hystcomp_io::model_file::{Direction, ModelFile, Scale};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{VecMpim, excitation, feasible, random_plant, run, uniform};

fn seeded(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A random model, not necessarily invertible.
fn random_model(rng: &mut impl Rng, n: usize) -> VecMpim {
    let weights: Vec<f64> = (0..n).map(|_| rng.random_range(-0.8..0.8)).collect();
    Mpim::new(
        &uniform(n),
        &weights,
        rng.random_range(-1.0..1.0),
        rng.random_range(-0.5..1.0),
    )
    .unwrap()
}

/// The problem identify builds for a normalised record (all samples fitted).
fn problem(x: &[f64], y: &[f64], n: usize, direction: Direction, offset: bool) -> FitProblem {
    FitProblem::new(
        ProblemData {
            input: x,
            output: y,
            fit: 0..x.len(),
        },
        &uniform(n),
        direction,
        offset,
        1e-3,
    )
    .unwrap()
}

fn pso(seed: u64) -> PsoOptions {
    PsoOptions::default().with_seed(seed)
}

proptest! {
    #![proptest_config(seeded(24, 1))]

    /// Noise-free data from a known invertible model, scaled to physical units with a sensor
    /// offset: ls recovers a1, a2 + b1 and every other weight to 1e-6, and the fitted offset.
    #[test]
    fn ls_recovers_an_invertible_model_from_noise_free_data(seed in any::<u64>(), n in 1usize..16) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let model = random_plant(&mut rng, n);
        let x = excitation(&mut rng, 60);
        prop_assume!(feasible(&model, &x, Direction::Plant));
        let (v_scale, y_scale, y_offset) = (150.0, 75.0, -37.0);
        let voltage: Vec<f64> = x.iter().map(|x| v_scale * x).collect();
        let displacement: Vec<f64> = run(&model, &x).iter().map(|y| y_offset + y_scale * y).collect();
        let fit = identify(&voltage, &displacement, &IdentifyOptions {
            thresholds: Thresholds::Uniform(n),
            ..IdentifyOptions::default()
        }).unwrap();
        let m = &fit.model;
        // Identified parameters are relative to the identified output scale.
        let k = m.output.scale / y_scale;
        prop_assert!((m.input.scale - v_scale).abs() < 1e-9 && m.input.offset.abs() < 1e-9);
        prop_assert!((k * m.a1 - model.a1()).abs() < 1e-6, "a1 {} vs {}", k * m.a1, model.a1());
        prop_assert!((k * (m.a2 + m.weights[0]) - (model.a2() + model.weights()[0])).abs() < 1e-6);
        for i in 1..n {
            prop_assert!((k * m.weights[i] - model.weights()[i]).abs() < 1e-6,
                "b{} {} vs {}", i + 1, k * m.weights[i], model.weights()[i]);
        }
        prop_assert!((m.output.offset - y_offset).abs() < 1e-6 * y_scale);
        prop_assert!(fit.report.fit.rms_percent < 1e-8);
        prop_assert_eq!(fit.report.active_constraints, 0);
    }

    /// The same for inverse models (displacement in, voltage out, negative weights).
    #[test]
    fn ls_recovers_an_inverse_model_from_noise_free_data(seed in any::<u64>(), n in 2usize..12) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let weights: Vec<f64> = (0..n).map(|_| rng.random_range(-0.25..0.02)).collect();
        let a2 = rng.random_range(1.0..2.5);
        let model: VecMpim = Mpim::new(&uniform(n), &weights, rng.random_range(-0.1..0.3), a2).unwrap();
        let x = excitation(&mut rng, 60);
        prop_assume!(feasible(&model, &x, Direction::Inverse));
        let displacement: Vec<f64> = x.iter().map(|x| 20.0 + 60.0 * x).collect();
        let voltage: Vec<f64> = run(&model, &x).iter().map(|v| 10.0 * v).collect();
        let fit = identify(&voltage, &displacement, &IdentifyOptions {
            direction: Direction::Inverse,
            thresholds: Thresholds::Uniform(n),
            offset: OutputOffset::Value(0.0),
            ..IdentifyOptions::default()
        }).unwrap();
        let m = &fit.model;
        let k = m.output.scale / 10.0;
        prop_assert_eq!(m.direction, Direction::Inverse);
        prop_assert_eq!(m.weights[0], 0.0, "inverse models keep b1 = 0 with r1 = 0");
        prop_assert!((k * m.a1 - model.a1()).abs() < 1e-6);
        prop_assert!((k * m.a2 - (model.a2() + model.weights()[0])).abs() < 1e-6);
        for i in 1..n {
            prop_assert!((k * m.weights[i] - model.weights()[i]).abs() < 1e-6);
        }
    }

    /// Whatever the data (random, not invertible, noisy), every identified model passes the
    /// core's invertibility check on [0, 1], in both directions and with both solvers, and a
    /// plant model gives every compensator of the paper.
    #[test]
    fn every_identified_model_passes_the_core_checks(seed in any::<u64>(), n in 1usize..14) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let model = random_model(&mut rng, n);
        let x = excitation(&mut rng, 30);
        let y: Vec<f64> = run(&model, &x).iter().map(|y| y + 0.01 * rng.random::<f64>()).collect();
        prop_assume!(y.iter().any(|v| *v != y[0]));
        for direction in [Direction::Plant, Direction::Inverse] {
            for method in [Method::LeastSquares, Method::ParticleSwarm(pso(seed).with_polish(true))] {
                let options = IdentifyOptions {
                    direction,
                    method,
                    thresholds: Thresholds::Uniform(n),
                    max_condition: 1e14,
                    max_fit_rms_percent: None,
                    ..IdentifyOptions::default()
                };
                let fit = match identify(&x, &y, &options) {
                    Ok(fit) => fit,
                    // Random models may fall as the input rises: refused as such.
                    Err(IdentifyError::NotRising { .. }) => continue,
                    // A swarm may end infeasible; it must say so, never return a bad model.
                    Err(IdentifyError::SwarmInfeasible { .. }) => continue,
                    Err(IdentifyError::IllConditioned { .. }) => continue,
                    Err(e) => panic!("{direction}: {e}"),
                };
                let m = fit.model.model().unwrap();
                let slope = m.check_invertible(0.0, 1.0).unwrap();
                prop_assert!(slope.slope >= 1e-3 * (1.0 - 1e-6));
                prop_assert!((slope.slope - fit.report.min_branch_slope).abs() < 1e-12);
                // The report counts the constraints active at the final parameters: a branch
                // slope at the margin is one of them.
                if slope.slope - 1e-3 < 1e-9 {
                    prop_assert!(fit.report.active_constraints >= 1, "{}", fit.report.detail);
                }
                let limits = OutputLimits::new(0.0, 1.0).unwrap();
                if direction == Direction::Plant {
                    // The exact and guarded loops build on every invertible model; the plain
                    // delayed ones exactly when the report's gains are below 1.
                    for mode in [SolveMode::Exact, SolveMode::DelayedGuarded] {
                        prop_assert!(Ihc::<f64, Vec<f64>>::new(&m, limits, mode).is_ok());
                        prop_assert!(Wihc::<f64, Vec<f64>>::new(&m, limits, mode).is_ok());
                    }
                    let gains = fit.report.delayed_loop_gains.expect("a plant model's gains");
                    prop_assert_eq!(
                        Ihc::<f64, Vec<f64>>::new(&m, limits, SolveMode::Delayed).is_ok(),
                        gains.ihc < 1.0
                    );
                    prop_assert_eq!(
                        Wihc::<f64, Vec<f64>>::new(&m, limits, SolveMode::Delayed).is_ok(),
                        gains.wihc < 1.0
                    );
                } else {
                    prop_assert!(Dihc::<f64, Vec<f64>>::new(&m, 0.0, 1.0, limits).is_ok());
                }
            }
        }
    }

    /// When constraints bind, the least-squares answer is feasible and no feasible direction
    /// lowers the cost (for a convex problem: the global optimum), and the swarm never beats it.
    #[test]
    fn constrained_ls_is_optimal_and_no_worse_than_the_swarm(seed in any::<u64>(), n in 2usize..12) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let model = random_model(&mut rng, n);
        let x = excitation(&mut rng, 30);
        let y = run(&model, &x);
        for direction in [Direction::Plant, Direction::Inverse] {
            for offset in [false, true] {
                let p = problem(&x, &y, n, direction, offset);
                let ls = LeastSquares.solve(&p, &mut NoObserver).unwrap();
                prop_assert!(p.smallest_slack(&ls.theta) >= -1e-9 * p.margin());
                // Feasible points: a straight line, and the swarm's best.
                let mut line = vec![0.0; p.dimension()];
                line[1] = 1.0;
                prop_assert!(p.smallest_slack(&line) >= 0.0);
                let mut others = vec![line];
                if let Ok(s) = ParticleSwarm::new(pso(seed).with_iterations(60).unwrap())
                    .unwrap()
                    .solve(&p, &mut NoObserver)
                {
                    prop_assert!(ls.cost <= s.cost + 1e-12, "ls {} > pso {}", ls.cost, s.cost);
                    others.push(s.theta);
                }
                for other in others {
                    for t in [1e-4, 1e-2, 0.3, 1.0] {
                        let between: Vec<f64> = ls.theta.iter().zip(&other)
                            .map(|(a, b)| a + t * (b - a)).collect();
                        prop_assert!(p.cost(&between) >= ls.cost - 1e-12,
                            "t = {}: {} < {}", t, p.cost(&between), ls.cost);
                    }
                }
            }
        }
    }

    /// The problem's O(p^2) cost equals the RMS error of the model run sample by sample by the
    /// core over the fitting span (the one function both solvers minimise).
    #[test]
    fn cost_is_the_rms_error_of_the_model_run_by_the_core(seed in any::<u64>(), n in 1usize..20) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let truth = random_model(&mut rng, n);
        let x = excitation(&mut rng, 20);
        let y: Vec<f64> = run(&truth, &x).iter().map(|y| y + 0.05 * rng.random::<f64>()).collect();
        let warm = x.len() / 5;
        let p = FitProblem::new(
            ProblemData { input: &x, output: &y, fit: warm..x.len() },
            &uniform(n), Direction::Plant, true, 1e-3,
        ).unwrap();
        let theta: Vec<f64> = (0..p.dimension()).map(|_| rng.random_range(-1.0..1.0)).collect();
        let params = p.parameters(&theta);
        let model: VecMpim = Mpim::new(&uniform(n), &params.weights, params.a1, params.a2).unwrap();
        let predicted = run(&model, &x);
        let sum: f64 = predicted[warm..].iter().zip(&y[warm..])
            .map(|(p, y)| (p + params.offset - y).powi(2)).sum();
        let rms = (sum / (x.len() - warm) as f64).sqrt();
        prop_assert!((p.cost(&theta) - rms).abs() <= 1e-10 * (1.0 + rms), "{} vs {}", p.cost(&theta), rms);
        prop_assert_eq!(p.theta(&params).len(), theta.len());
    }
}

#[test]
fn a_record_that_folds_back_gives_a_model_on_the_constraint_boundary() {
    // A branch that turns down near the top: the unconstrained fit is not invertible.
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let x = excitation(&mut rng, 30);
    let base = random_plant(&mut rng, 10);
    let y: Vec<f64> = run(&base, &x)
        .iter()
        .zip(&x)
        .map(|(y, x)| y - 1.5 * x.powi(4))
        .collect();
    for direction in [Direction::Plant, Direction::Inverse] {
        let p = problem(&x, &y, 10, direction, true);
        let ls = LeastSquares.solve(&p, &mut NoObserver).unwrap();
        assert!(p.active_count(&ls.theta) > 0, "{direction}: {}", ls.detail);
        assert_eq!(p.violated_count(&ls.theta), 0, "{direction}: {}", ls.detail);
        assert!(ls.detail.contains("constrained optimum"), "{}", ls.detail);
        let params = p.parameters(&ls.theta);
        let model: VecMpim =
            Mpim::new(&uniform(10), &params.weights, params.a1, params.a2).unwrap();
        let slope = model.check_invertible(0.0, 1.0).unwrap().slope;
        assert!((slope - 1e-3).abs() < 1e-9, "{direction}: {slope}");
    }
}

#[test]
fn pso_is_reproducible_whatever_the_number_of_threads() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let model = random_plant(&mut rng, 8);
    let x = excitation(&mut rng, 40);
    let y: Vec<f64> = run(&model, &x)
        .iter()
        .map(|y| y + 0.01 * rng.random::<f64>())
        .collect();
    let options = IdentifyOptions {
        method: Method::ParticleSwarm(pso(42).with_iterations(80).unwrap()),
        thresholds: Thresholds::Uniform(8),
        ..IdentifyOptions::default()
    };
    let in_pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| identify(&x, &y, &options).unwrap())
    };
    let one = in_pool(1);
    let three = in_pool(3);
    let again = in_pool(3);
    assert_eq!(one.parameters, three.parameters);
    assert_eq!(three.parameters, again.parameters);
    // Another seed gives another swarm.
    let other = identify(
        &x,
        &y,
        &IdentifyOptions {
            method: Method::ParticleSwarm(pso(43).with_iterations(80).unwrap()),
            ..options.clone()
        },
    )
    .unwrap();
    assert_ne!(other.parameters, one.parameters);
    // On the same data and thresholds, ls is never worse.
    let ls = identify(
        &x,
        &y,
        &IdentifyOptions {
            method: Method::LeastSquares,
            ..options
        },
    )
    .unwrap();
    assert!(ls.report.fit.rms <= one.report.fit.rms + 1e-12);
    assert!(ls.report.fit.rms <= other.report.fit.rms + 1e-12);
}

#[test]
fn pso_reports_each_iteration_to_its_observer() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let model = random_plant(&mut rng, 5);
    let x = excitation(&mut rng, 20);
    let y = run(&model, &x);
    let p = problem(&x, &y, 5, Direction::Plant, true);
    let mut seen = Vec::new();
    let mut observer = |progress: &hystcomp_identify::Progress| seen.push(*progress);
    let solution = ParticleSwarm::new(pso(1).with_iterations(30).unwrap())
        .unwrap()
        .solve(&p, &mut observer)
        .unwrap();
    assert_eq!(seen.len(), 30);
    assert!(
        seen.iter()
            .enumerate()
            .all(|(i, s)| s.iteration == i + 1 && s.iterations == 30)
    );
    // The best never gets worse once feasible, and the last is the answer.
    for pair in seen.windows(2) {
        if pair[0].best_violation == 0.0 {
            assert_eq!(pair[1].best_violation, 0.0);
            assert!(pair[1].best_cost <= pair[0].best_cost);
        }
    }
    assert_eq!(seen.last().unwrap().best_cost, solution.cost);
}

#[test]
fn polish_brings_the_swarm_to_the_least_squares_optimum() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let model = random_plant(&mut rng, 10);
    let x = excitation(&mut rng, 50);
    let y: Vec<f64> = run(&model, &x)
        .iter()
        .map(|y| y + 0.02 * (rng.random::<f64>() - 0.5))
        .collect();
    let p = problem(&x, &y, 10, Direction::Plant, true);
    let ls = LeastSquares.solve(&p, &mut NoObserver).unwrap();
    let raw = ParticleSwarm::new(pso(3))
        .unwrap()
        .solve(&p, &mut NoObserver)
        .unwrap();
    let polished = ParticleSwarm::new(pso(3).with_polish(true))
        .unwrap()
        .solve(&p, &mut NoObserver)
        .unwrap();
    assert!(raw.cost > ls.cost);
    assert!(polished.cost <= raw.cost);
    assert!((polished.cost - ls.cost).abs() <= 1e-9 * ls.cost);
}

#[test]
fn warmup_and_holdout_split_the_record_as_documented() {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let model = random_plant(&mut rng, 6);
    // Starts mid-range: the automatic warm-up ends at the first sample within 1 % of the
    // voltage range from an end, where the memory becomes known (0.04 is not: 0.0 is).
    let mut x = vec![0.5, 0.3, 0.1, 0.04, 0.0];
    x.extend(excitation(&mut rng, 40));
    let y = run(&model, &x);
    let auto = identify(
        &x,
        &y,
        &IdentifyOptions {
            holdout: 0.25,
            thresholds: Thresholds::Uniform(6),
            ..IdentifyOptions::default()
        },
    )
    .unwrap();
    let s = auto.report.samples;
    assert_eq!(s.warmup, 4);
    assert_eq!(s.total, x.len());
    assert_eq!(s.holdout, (0.25 * (x.len() - 4) as f64).floor() as usize);
    assert_eq!(s.warmup + s.fit + s.holdout, s.total);
    assert_eq!(auto.report.holdout.unwrap().samples, s.holdout);
    assert_eq!(auto.report.fit.samples, s.fit);
    let fixed = identify(
        &x,
        &y,
        &IdentifyOptions {
            warmup: Warmup::Samples(100),
            thresholds: Thresholds::Uniform(6),
            ..IdentifyOptions::default()
        },
    )
    .unwrap();
    assert_eq!(fixed.report.samples.warmup, 100);
    assert!(fixed.report.holdout.is_none());
}

#[test]
fn output_offset_modes_set_the_model_file_offset() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let model = random_plant(&mut rng, 5);
    let x = excitation(&mut rng, 30);
    let y: Vec<f64> = run(&model, &x).iter().map(|y| 12.0 + 40.0 * y).collect();
    let y_min = y.iter().copied().fold(f64::INFINITY, f64::min);
    let with = |offset| {
        identify(
            &x,
            &y,
            &IdentifyOptions {
                offset,
                thresholds: Thresholds::Uniform(5),
                ..IdentifyOptions::default()
            },
        )
        .unwrap()
    };
    assert_eq!(with(OutputOffset::None).model.output.offset, y_min);
    assert_eq!(with(OutputOffset::Value(3.5)).model.output.offset, 3.5);
    // The model starts at 0 from zero memory at input 0, so the fitted offset is 12.
    let fit = with(OutputOffset::Fit);
    assert!((fit.model.output.offset - 12.0).abs() < 1e-8);
    assert!(fit.report.fit.rms < 1e-8);
    // The model file's prediction reproduces the record in physical units.
    let file_model = fit.model.model().unwrap();
    let predicted: Vec<f64> = run(&file_model, &x)
        .iter()
        .map(|v| fit.model.output_to_physical(*v))
        .collect();
    for (p, m) in predicted.iter().zip(&y) {
        assert!((p - m).abs() < 1e-7);
    }
}

#[test]
fn crossval_replays_the_exact_compensators_without_error_on_noise_free_data() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let model = random_plant(&mut rng, 10);
    let x_train = excitation(&mut rng, 60);
    assert!(feasible(&model, &x_train, Direction::Plant));
    let mut x_test = excitation(&mut rng, 30);
    // Stay inside the training range, start from its minimum.
    x_test.iter_mut().for_each(|x| *x = 0.05 + 0.9 * *x);
    x_test.insert(0, 0.0);
    let physical = |x: &[f64]| -> (Vec<f64>, Vec<f64>) {
        let v = x.iter().map(|x| 2.0 + 8.0 * x).collect();
        let y = run(&model, x).iter().map(|y| -50.0 + 30.0 * y).collect();
        (v, y)
    };
    let (v_train, y_train) = physical(&x_train);
    let (v_test, y_test) = physical(&x_test);
    let cv = crossval(
        Record {
            voltage: &v_train,
            displacement: &y_train,
        },
        Record {
            voltage: &v_test,
            displacement: &y_test,
        },
        &CrossvalOptions {
            test_warmup: Warmup::Samples(0),
            ..CrossvalOptions::default()
        },
        &mut NoObserver,
    )
    .unwrap();
    let t = &cv.report.test;
    assert!(t.forward.rms_percent < 1e-7, "{}", t.forward.rms_percent);
    assert_eq!(t.voltage_outside_model_range, 0);
    assert_eq!(t.replay.len(), 7);
    let gains = t
        .delayed_loop_gains
        .expect("the plant model's delayed gains");
    for r in &t.replay {
        // A plain delayed loop that can ring is not built, with the reason.
        let refused = match r.compensator.as_str() {
            "ihc-delayed" => gains.ihc >= 1.0,
            "wihc-delayed" => gains.wihc >= 1.0,
            _ => false,
        };
        if refused {
            assert!(
                r.error.is_none()
                    && r.failure
                        .as_deref()
                        .is_some_and(|f| f.contains("can oscillate")),
                "{r:?}"
            );
            continue;
        }
        let e = r.error.expect("every compensator is built");
        assert!(e.rms_percent.is_finite());
        match r.compensator.as_str() {
            // The plant model is exact, so its exact inverses return the applied voltage.
            "ihc" | "wihc" => assert!(e.max_percent < 1e-6, "{}: {}", r.compensator, e.max_percent),
            // DIHC's MPIM of the inverse is not exact, but close.
            "dihc" => assert!(
                e.rms_percent > 1e-6 && e.rms_percent < 20.0,
                "dihc: {}",
                e.rms_percent
            ),
            // The delayed ones lag a sample (and the delayed WIHC may ring while several
            // operators move: its loop gain is then (3 a1 v^2 + sum of moving b) / a2).
            _ => assert!(e.rms_percent > 1e-6, "{}: {}", r.compensator, e.rms_percent),
        }
    }
    assert_eq!(cv.plant.direction, Direction::Plant);
    assert_eq!(cv.inverse.direction, Direction::Inverse);
}

#[test]
fn bad_records_and_options_are_refused_with_a_clear_message() {
    let x: Vec<f64> = (0..200).map(|k| (k % 40) as f64 / 39.0).collect();
    let y: Vec<f64> = x.iter().map(|x| 2.0 * x).collect();
    let options = IdentifyOptions::default();
    let message =
        |v: &[f64], d: &[f64], o: &IdentifyOptions| identify(v, d, o).unwrap_err().to_string();

    let mut nan = y.clone();
    nan[7] = f64::NAN;
    assert!(message(&x, &nan, &options).contains("sample 8"));
    let mut inf = x.clone();
    inf[3] = f64::INFINITY;
    assert!(message(&inf, &y, &options).contains("not a finite number"));
    assert!(message(&x[..100], &y, &options).contains("differ in length"));
    assert!(message(&x, &vec![1.0; 200], &options).contains("constant"));
    assert!(message(&vec![1.0; 200], &y, &options).contains("voltage is constant"));
    let few = message(&x[..30], &y[..30], &options);
    assert!(few.contains("at least 36 needed"), "{few}");
    let bad = |o: IdentifyOptions, what: &str| {
        let m = message(&x, &y, &o);
        assert!(m.contains(what), "{m}");
    };
    bad(
        IdentifyOptions {
            holdout: 1.0,
            ..options.clone()
        },
        "holdout",
    );
    bad(
        IdentifyOptions {
            margin: 0.0,
            ..options.clone()
        },
        "margin",
    );
    bad(
        IdentifyOptions {
            thresholds: Thresholds::Uniform(0),
            ..options.clone()
        },
        "at least 1",
    );
    bad(
        IdentifyOptions {
            thresholds: Thresholds::Given(vec![0.0, 1.2]),
            ..options.clone()
        },
        "[0, 1)",
    );
    bad(
        IdentifyOptions {
            thresholds: Thresholds::Given(vec![0.2, 0.1]),
            ..options.clone()
        },
        "increase strictly",
    );
    assert!(PsoOptions::default().with_particles(1).is_err());
    assert!(PsoOptions::default().with_inertia(f64::NAN, 0.4).is_err());
    assert!(PsoOptions::default().with_acceleration(2.0, -1.0).is_err());
    // Two thresholds 1e-12 apart: their operators' columns are equal to 1e-12, and the data
    // cannot tell them apart. (The ranges are those of the fitted samples, so a record that
    // only wiggles after its warm-up is normalised to [0, 1] and identifies fine.)
    let mut wiggle: Vec<f64> = (0..=100).map(|k| k as f64 / 100.0).collect();
    wiggle.extend((0..50).map(|k| 1.0 - k as f64 / 100.0));
    wiggle.extend((0..400).map(|k| 0.5 + 0.05 * (k as f64 * 0.3).sin()));
    let out: Vec<f64> = wiggle.iter().map(|x| x + 0.1 * x * x).collect();
    let err = identify(
        &wiggle,
        &out,
        &IdentifyOptions {
            thresholds: Thresholds::Given(vec![0.0, 0.5, 0.5 + 1e-12]),
            warmup: Warmup::Samples(0),
            ..options.clone()
        },
    )
    .unwrap_err();
    assert!(matches!(err, IdentifyError::IllConditioned { .. }), "{err}");
    // A signal that only moves during the warm-up: constant over the fitted samples, said as
    // such (not as a displacement that "does not rise", correlation NaN).
    let mut held = x[..100].to_vec();
    held.extend(std::iter::repeat_n(0.5, 200));
    let rising: Vec<f64> = (0..300).map(|k| k as f64 / 299.0).collect();
    let after_warmup = IdentifyOptions {
        warmup: Warmup::Samples(100),
        ..options.clone()
    };
    for (v, d, quantity) in [
        (&held, &rising, "the voltage is constant"),
        (&rising, &held, "the displacement is constant"),
    ] {
        let err = identify(v, d, &after_warmup).unwrap_err();
        let text = err.to_string();
        assert!(
            matches!(
                err,
                IdentifyError::InvalidOption {
                    option: "fitting span",
                    ..
                }
            ),
            "{text}"
        );
        assert!(
            text.contains(quantity) && text.contains("warm-up"),
            "{text}"
        );
        assert!(!text.contains("rise"), "{text}");
    }
    let fit = identify(
        &wiggle,
        &out,
        &IdentifyOptions {
            warmup: Warmup::Samples(151),
            ..options
        },
    )
    .unwrap();
    let fitted = &wiggle[151..];
    let lo = fitted.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = fitted.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert_eq!((fit.report.input.min, fit.report.input.max), (lo, hi));
    assert!(
        fit.report.fit.rms_percent < 0.1,
        "{}",
        fit.report.fit.rms_percent
    );
}

/// The replay counts both kinds of clamped samples: a delayed WIHC whose full loop gain
/// exceeds 1 (Table 1: 1.66) rings after the jump at the start of a record that does not start
/// at rest, and those clamps (reachable positions) show as `loop_saturated`, not `saturated`.
#[test]
fn replay_counts_the_delayed_loops_clamps_after_a_jump() {
    let thresholds: Vec<f64> = (0..10).map(|i| i as f64 / 10.0).collect();
    let weights = [
        0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ];
    let table1: VecMpim = Mpim::new(&thresholds, &weights, -0.1569, 0.4603).unwrap();
    let gain = table1.delayed_wihc_loop_gain(0.0, 1.0).unwrap().gain;
    assert!(gain > 1.0, "{gain}");
    let scale = |quantity: &str, unit: &str, scale: f64| Scale {
        quantity: quantity.to_owned(),
        unit: unit.to_owned(),
        offset: 0.0,
        scale,
    };
    let volts = || scale("voltage", "V", 10.0);
    let um = || scale("displacement", "um", 75.0);
    let plant =
        ModelFile::from_model(Direction::Plant, volts(), um(), [0.0, 1.0], &table1).unwrap();
    let inverse =
        ModelFile::from_model(Direction::Inverse, um(), volts(), [0.0, 1.0], &table1).unwrap();
    // 1 Hz at 1 kHz, starting at 5 V: the desired position jumps from rest at the first sample.
    let voltage: Vec<f64> = (0..2000)
        .map(|k| 5.0 + 4.0 * (2.0 * std::f64::consts::PI * k as f64 / 1000.0).sin())
        .collect();
    let displacement = run(
        &table1,
        &voltage.iter().map(|v| v / 10.0).collect::<Vec<_>>(),
    )
    .iter()
    .map(|y| 75.0 * y)
    .collect::<Vec<_>>();
    let record = Record {
        voltage: &voltage,
        displacement: &displacement,
    };
    // Table 1's delayed WIHC (gain 1.66) is replayed only when allowed.
    let refused = validate_models(
        &plant,
        &inverse,
        [0.0, 10.0],
        record,
        Warmup::Samples(0),
        UnstableDelay::Refuse,
    )
    .unwrap();
    let row = refused
        .replay
        .iter()
        .find(|r| r.compensator == "wihc-delayed")
        .unwrap();
    assert!(row.error.is_none() && row.failure.is_some(), "{row:?}");
    let report = validate_models(
        &plant,
        &inverse,
        [0.0, 10.0],
        record,
        Warmup::Samples(0),
        UnstableDelay::Allow,
    )
    .unwrap();
    for r in &report.replay {
        // The same counts as a direct replay through the compensator.
        let method: CompensatorMethod = r.compensator.parse().unwrap();
        let file = if method == CompensatorMethod::Dihc {
            &inverse
        } else {
            &plant
        };
        let mut direct = ScaledCompensator::with_unstable_delay(
            file,
            method,
            Some((0.0, 10.0)),
            UnstableDelay::Allow,
        )
        .unwrap();
        displacement.iter().for_each(|&y| {
            direct.step(y);
        });
        let d = direct.diagnostics();
        assert_eq!(
            (r.saturated, r.loop_saturated),
            (d.saturated, d.loop_saturated),
            "{r:?}"
        );
        match r.compensator.as_str() {
            "wihc-delayed" => assert!(r.loop_saturated > 0, "{r:?}"),
            "ihc" | "wihc" | "ihc-guarded" | "wihc-guarded" => {
                assert_eq!(r.loop_saturated, 0, "{r:?}")
            }
            _ => {}
        }
    }
    // After a warm-up past the ringing, none of it is counted.
    let settled = validate_models(
        &plant,
        &inverse,
        [0.0, 10.0],
        record,
        Warmup::Samples(1000),
        UnstableDelay::Allow,
    )
    .unwrap();
    let wihc_delayed = |v: &Validation| {
        v.replay
            .iter()
            .find(|r| r.compensator == "wihc-delayed")
            .unwrap()
            .loop_saturated
    };
    assert!(wihc_delayed(&settled) < wihc_delayed(&report));
    // Its JSON carries both counts.
    let json = serde_json::to_value(&report).unwrap();
    assert!(
        json["replay"][3]["loop_saturated"].as_u64().unwrap() > 0,
        "{json}"
    );
}

proptest! {
    #![proptest_config(seeded(24, 11))]

    /// The creep weights' smoothness penalty (FitProblem::with_extra_smoothness) adds exactly
    /// `lambda^2 sum_j (e_j+1 - e_j)^2` to the squared cost of any parameter vector: the
    /// re-factored problem against the plain formula on the unpenalised one; lambda = 0 leaves
    /// the cost alone, and a heavy penalty makes the solved extra parameters equal.
    #[test]
    fn the_smoothness_penalty_adds_the_squared_differences_of_the_extra_parameters(
        seed in any::<u64>(), n in 1usize..12, extra in 2usize..6, lambda in 0.0f64..3.0,
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let truth = random_plant(&mut rng, n);
        let x = excitation(&mut rng, 20);
        let y: Vec<f64> = run(&truth, &x).iter().map(|y| y + 0.01 * rng.random::<f64>()).collect();
        let columns: Vec<Vec<f64>> = (0..extra)
            .map(|_| x.iter().map(|_| rng.random_range(-1.0..1.0)).collect())
            .collect();
        let refs: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
        let data = || ProblemData { input: &x, output: &y, fit: 0..x.len() };
        let plain = FitProblem::with_extra_columns(
            data(), &uniform(n), Direction::Plant, true, 1e-3, &refs,
        ).unwrap();
        let smooth = plain.clone().with_extra_smoothness(lambda).unwrap();
        prop_assert_eq!(smooth.dimension(), plain.dimension());
        for _ in 0..5 {
            let theta: Vec<f64> =
                (0..plain.dimension()).map(|_| rng.random_range(-1.0..1.0)).collect();
            let e = plain.extra_parameters(&theta);
            let penalty: f64 = e.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
            let expected = (plain.cost(&theta).powi(2) + lambda * lambda * penalty).sqrt();
            prop_assert!(
                (smooth.cost(&theta) - expected).abs() <= 1e-9 * (1.0 + expected),
                "{} vs {}", smooth.cost(&theta), expected
            );
        }
        let heavy = plain.clone().with_extra_smoothness(1e4).unwrap();
        let solved = LeastSquares.solve(&heavy, &mut NoObserver).unwrap();
        let e = heavy.extra_parameters(&solved.theta);
        let spread = e.iter().fold(f64::NEG_INFINITY, |a, b| a.max(*b))
            - e.iter().fold(f64::INFINITY, |a, b| a.min(*b));
        prop_assert!(spread <= 1e-4, "{e:?}");
    }
}

#[test]
fn the_smoothness_penalty_refuses_a_negative_or_non_finite_weight() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let x = excitation(&mut rng, 10);
    let y = run(&random_plant(&mut rng, 5), &x);
    let column: Vec<f64> = x.iter().map(|v| v * v).collect();
    let p = FitProblem::with_extra_columns(
        ProblemData {
            input: &x,
            output: &y,
            fit: 0..x.len(),
        },
        &uniform(5),
        Direction::Plant,
        true,
        1e-3,
        &[&column, &column],
    )
    .unwrap();
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let error = p.clone().with_extra_smoothness(bad).unwrap_err();
        assert!(error.to_string().contains("creep smoothness"), "{error}");
    }
}
