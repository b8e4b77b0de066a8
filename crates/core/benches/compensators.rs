//! Per-sample cost of the forward MPIM and of every compensator, for n = 10 and n = 100
//! operators, in f64 and f32. Each measurement runs a 10 000-sample trajectory with minor
//! loops; criterion reports the time per trajectory and the throughput in samples per second
//! (divide 1e9 by it for nanoseconds per sample).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use hystcomp_core::{
    ChainCompensator, Compensator, CreepInverse, Dihc, Ihc, Mpim, OutputLimits, Real, SolveMode,
    VibrationInverse, Wihc, paper,
};
use std::hint::black_box;

const SAMPLES: usize = 10_000;

/// Table 1 of the paper spread over `n` operators (invertible on [0, 1]).
fn plant<T: Real>(n: usize) -> Mpim<T, Vec<T>> {
    paper::TABLE1.spread(n).unwrap()
}

/// Table 2 of the paper spread over `n` operators.
fn inverse<T: Real>(n: usize) -> Mpim<T, Vec<T>> {
    paper::TABLE2.spread(n).unwrap()
}

/// A three-tone trajectory shape, normalised into the reachable range of the plant: a voltage
/// multisine run through the plant, so every sample is reachable. It rises smoothly from rest
/// over its first tenth, as a stage starts, so that no compensator starts with a jump (after
/// which a delayed WIHC with a loop gain above 1, as Table 1's, rings for a while).
fn desired<T: Real>(model: &Mpim<T, Vec<T>>) -> Vec<T> {
    let mut p = model.clone();
    (0..SAMPLES)
        .map(|k| {
            let t = k as f64 / SAMPLES as f64 * 10.0;
            let rise = 0.5 - 0.5 * (std::f64::consts::PI * t.min(1.0)).cos();
            let v = 0.5
                + 0.14 * (std::f64::consts::PI * t + 2.6).sin()
                + 0.14 * (1.6 * std::f64::consts::PI * t + 3.0).sin()
                + 0.2 * (2.0 * std::f64::consts::PI * t + 1.5).sin();
            p.step(T::from_f64(rise * v))
        })
        .collect()
}

fn bench_type<T: Real>(c: &mut Criterion, type_name: &str) {
    let mut group = c.benchmark_group(format!("per_sample_{type_name}"));
    group.throughput(Throughput::Elements(SAMPLES as u64));
    let limits = OutputLimits::new(T::zero(), T::one()).unwrap();
    for n in [10usize, 100] {
        let model = plant::<T>(n);
        let trajectory = desired(&model);
        let mut out = vec![T::zero(); SAMPLES];

        let mut forward = model.clone();
        let volts: Vec<T> = (0..SAMPLES)
            .map(|k| T::from_f64(0.5 + 0.4 * (k as f64 * 0.003).sin()))
            .collect();
        group.bench_with_input(BenchmarkId::new("mpim_forward", n), &n, |b, _| {
            b.iter(|| {
                forward.reset();
                forward.process(black_box(&volts), &mut out).unwrap();
            })
        });

        // The same, each input waiting for the previous output (as in a control loop, and as
        // every compensator's solve waits for its previous sample): the step's latency.
        let mut chained = model.clone();
        let tiny = T::from_f64(1e-30);
        group.bench_with_input(BenchmarkId::new("mpim_forward_chained", n), &n, |b, _| {
            b.iter(|| {
                chained.reset();
                let mut y = T::zero();
                for (x, o) in volts.iter().zip(out.iter_mut()) {
                    y = chained.step(*x + tiny * y);
                    *o = y;
                }
                black_box(&out);
            })
        });

        let mut compensators: Vec<(&str, Box<dyn Compensator<T>>)> = vec![
            (
                "ihc_exact",
                Box::new(Ihc::<T, Vec<T>>::new(&model, limits, SolveMode::Exact).unwrap()),
            ),
            (
                "ihc_delayed",
                Box::new(Ihc::<T, Vec<T>>::new(&model, limits, SolveMode::Delayed).unwrap()),
            ),
            (
                "ihc_guarded",
                Box::new(Ihc::<T, Vec<T>>::new(&model, limits, SolveMode::DelayedGuarded).unwrap()),
            ),
            (
                "wihc_exact",
                Box::new(Wihc::<T, Vec<T>>::new(&model, limits, SolveMode::Exact).unwrap()),
            ),
            (
                // Table 1's delayed WIHC loop gain is 1.66: allowed explicitly (the trajectory
                // rises from rest, so it does not ring).
                "wihc_delayed",
                Box::new(
                    Wihc::<T, Vec<T>>::new(&model, limits, SolveMode::DelayedAllowUnstable)
                        .unwrap(),
                ),
            ),
            (
                "wihc_guarded",
                Box::new(
                    Wihc::<T, Vec<T>>::new(&model, limits, SolveMode::DelayedGuarded).unwrap(),
                ),
            ),
            (
                "dihc",
                Box::new(
                    Dihc::<T, Vec<T>>::new(&inverse::<T>(n), T::zero(), T::one(), limits).unwrap(),
                ),
            ),
        ];
        for (name, compensator) in compensators.iter_mut() {
            group.bench_with_input(BenchmarkId::new(*name, n), &n, |b, _| {
                b.iter(|| {
                    compensator.reset();
                    compensator
                        .process(black_box(&trajectory), &mut out)
                        .unwrap();
                })
            });
        }
    }
    group.finish();
}

/// The set-up cost of each compensator (invertibility check, eq. (7)'s inverse, loop gains)
/// for large models: linear in the number of operators.
fn bench_set_up(c: &mut Criterion) {
    let mut group = c.benchmark_group("set_up_f64");
    let limits = OutputLimits::new(0.0, 1.0).unwrap();
    for n in [1_000usize, 10_000] {
        let model = plant::<f64>(n);
        let inverse_model = inverse::<f64>(n);
        group.bench_with_input(BenchmarkId::new("ihc_new", n), &n, |b, _| {
            b.iter(|| Ihc::<f64, Vec<f64>>::new(black_box(&model), limits, SolveMode::Exact))
        });
        group.bench_with_input(BenchmarkId::new("wihc_new", n), &n, |b, _| {
            b.iter(|| Wihc::<f64, Vec<f64>>::new(black_box(&model), limits, SolveMode::Exact))
        });
        group.bench_with_input(BenchmarkId::new("dihc_new", n), &n, |b, _| {
            b.iter(|| Dihc::<f64, Vec<f64>>::new(black_box(&inverse_model), 0.0, 1.0, limits))
        });
    }
    group.finish();
}

/// Per-sample cost of the chain's links and of the whole chain compensator (vibration inverse
/// with a preview, creep inverse, exact IHC), n = 10.
fn bench_chain<T: Real>(c: &mut Criterion, type_name: &str) {
    let mut group = c.benchmark_group(format!("chain_{type_name}"));
    group.throughput(Throughput::Elements(SAMPLES as u64));
    let model = plant::<T>(10);
    let trajectory = desired(&model);
    let mut out = vec![T::zero(); SAMPLES];
    let limits = OutputLimits::new(T::zero(), T::one()).unwrap();
    let links = hystcomp_core::reference::chain_links::<T>();
    let (taus, weights, b, a) = (
        links.time_constants_s,
        links.weights,
        links.numerator,
        links.denominator,
    );
    let period = links.period_s;
    let mut creep: CreepInverse<T, Vec<T>> =
        CreepInverse::new(&taus, &weights, T::zero(), period).unwrap();
    group.bench_function("creep_inverse", |bench| {
        bench.iter(|| {
            creep.reset();
            for (y, o) in trajectory.iter().zip(out.iter_mut()) {
                *o = creep.step(black_box(*y));
            }
        })
    });
    let needed = VibrationInverse::<T, Vec<T>>::needed_preview(&b, 1).unwrap();
    for preview in [needed.min(8), needed] {
        let mut vibration: VibrationInverse<T, Vec<T>> =
            VibrationInverse::new(&b, &a, 1, preview).unwrap();
        group.bench_with_input(
            BenchmarkId::new("vibration_inverse_preview", preview),
            &preview,
            |bench, _| {
                bench.iter(|| {
                    vibration.reset();
                    for (y, o) in trajectory.iter().zip(out.iter_mut()) {
                        *o = vibration.step(black_box(*y));
                    }
                })
            },
        );
    }
    let ihc = Ihc::<T, Vec<T>>::new(&model, limits, SolveMode::Exact).unwrap();
    let mut chain: ChainCompensator<T, Vec<T>, _> = ChainCompensator::new(
        Some(VibrationInverse::new(&b, &a, 1, needed.min(8)).unwrap()),
        Some(CreepInverse::new(&taus, &weights, T::zero(), period).unwrap()),
        ihc,
    );
    group.bench_function("chain_ihc_exact", |bench| {
        bench.iter(|| {
            chain.reset();
            chain.process(black_box(&trajectory), &mut out).unwrap();
        })
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    bench_type::<f64>(c, "f64");
    bench_type::<f32>(c, "f32");
    bench_set_up(c);
    bench_chain::<f64>(c, "f64");
    bench_chain::<f32>(c, "f32");
}

criterion_group!(compensators, benches);
criterion_main!(compensators);
