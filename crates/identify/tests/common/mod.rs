//! Shared by the identification tests: excitations, running a model, feasibility.
#![allow(dead_code)]

use hystcomp_core::Mpim;
use hystcomp_identify::{FitProblem, Parameters, ProblemData};
use hystcomp_io::model_file::Direction;
use rand::{Rng, RngExt};

/// An MPIM in `f64` with its parameters on the heap.
pub type VecMpim = Mpim<f64, Vec<f64>>;

/// A normalised input in [0, 1]: a full sweep 0 -> 1, then `reversals` random reversal
/// points joined by steps of at most 0.01, so that every operator reverses at many amplitudes.
pub fn excitation(rng: &mut impl Rng, reversals: usize) -> Vec<f64> {
    let mut points = vec![0.0, 1.0];
    for _ in 0..reversals {
        points.push(rng.random::<f64>());
    }
    let mut x = vec![0.0];
    for pair in points.windows(2) {
        let steps = ((pair[1] - pair[0]).abs() / 0.01).ceil().max(1.0) as usize;
        for k in 1..=steps {
            x.push(pair[0] + (pair[1] - pair[0]) * k as f64 / steps as f64);
        }
    }
    x
}

/// The model's output for the input `x`, from its reset state.
pub fn run(model: &VecMpim, x: &[f64]) -> Vec<f64> {
    let mut m = model.clone();
    x.iter().map(|&v| m.step(v)).collect()
}

/// Whether `model` meets every constraint of the problem of `direction` on `x` with the
/// default margin, on its own thresholds (then it is the unconstrained optimum of its own
/// noise-free data, and ls must return it).
pub fn feasible(model: &VecMpim, x: &[f64], direction: Direction) -> bool {
    let y = run(model, x);
    let p = FitProblem::new(
        ProblemData {
            input: x,
            output: &y,
            fit: 0..x.len(),
        },
        model.thresholds(),
        direction,
        false,
        1e-3,
    )
    .unwrap();
    let theta = p.theta(&Parameters {
        a1: model.a1(),
        a2: model.a2(),
        weights: model.weights().to_vec(),
        offset: 0.0,
        higher: Vec::new(),
    });
    p.smallest_slack(&theta) > 0.0
}

/// Thresholds `(i - 1) / n`, `i = 1..n`.
pub fn uniform(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64 / n as f64).collect()
}

/// A random plant-like model on thresholds (i - 1)/n: mostly positive weights, a small cubic.
pub fn random_plant(rng: &mut impl Rng, n: usize) -> VecMpim {
    let weights: Vec<f64> = (0..n).map(|_| rng.random_range(-0.02..0.3)).collect();
    Mpim::new(
        &uniform(n),
        &weights,
        rng.random_range(-0.15..0.15),
        rng.random_range(0.3..1.0),
    )
    .unwrap()
}

/// Columns 1 (voltage, V) and 5 (sensor, um) of a file of the shared DBO data, or `None` (the
/// skip said by `hystcomp_testkit`) when the shared data is absent.
pub fn dbo_record(file: &str) -> Option<(Vec<f64>, Vec<f64>)> {
    use hystcomp_io::data::{Column, ReadOptions, read_columns};
    let path = hystcomp_testkit::dbo_record(file)?;
    let columns = read_columns(
        &path,
        &[Column::Index(1), Column::Index(5)],
        &ReadOptions::default(),
    )
    .expect("the DBO file reads");
    let mut values = columns.values.into_iter();
    Some((values.next().unwrap(), values.next().unwrap()))
}
