//! Per channel-step cost of the compensator banks (issue 16): `C` channels of n = 10 operators,
//! each with its own model (Table 1 or Table 2 of the paper with its weights scaled by a
//! channel's own factor in [0.9, 1.1]) and its own phase of a three-tone trajectory, stepped
//! tick after tick for C = 1, 8, 64, 1 024 and 4 096, in f64 and f32.
//!
//! A second set of groups, `bank_f32_n100` and `bank_f64_n100`, times the same banks with 100
//! operators per channel (the paper's tables spread) at C = 64 and 1 024: the delayed and
//! guarded IHC then walk the inverse's segments instead of evaluating it directly
//! ([`hystcomp_core::DIRECT_OPERATORS`]).
//!
//! Criterion's throughput is in channel-steps (ticks x channels) per second: divide 1e9 by it
//! for nanoseconds per channel-step, the figure issue 16's acceptance names.
//!
//! The banks take the widest compilation of their kernels the processor has; set
//! `HYSTCOMP_BANK_PATH` to `baseline`, `avx2` or `avx512` to time another
//! ([`hystcomp_core::VectorPath`]).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use hystcomp_core::{
    CompensatorBank, DihcBank, Heap, IhcBank, OutputLimits, Real, SolveMode, VectorPath, WihcBank,
    with_vector_path,
};
use std::hint::black_box;

use hystcomp_core::paper::bank_workload::{channel_models_of, signal};

/// Ticks per measured iteration.
const TICKS: usize = 200;
const CHANNELS: [usize; 5] = [1, 8, 64, 1_024, 4_096];

/// The compilation `HYSTCOMP_BANK_PATH` names (the widest the processor has by default).
fn path() -> VectorPath {
    match std::env::var("HYSTCOMP_BANK_PATH").as_deref() {
        Ok("baseline") => VectorPath::Baseline,
        Ok("avx2") => VectorPath::Avx2,
        Ok("avx512") => VectorPath::Avx512,
        _ => VectorPath::Best,
    }
}

/// The channel counts of the 100-operator groups.
const CHANNELS_N100: [usize; 2] = [64, 1_024];

fn bench_type<T: Real>(c: &mut Criterion, type_name: &str, operators: usize) {
    let path = path();
    let (name, counts) = match operators {
        10 => (format!("bank_{type_name}"), &CHANNELS[..]),
        n => (format!("bank_{type_name}_n{n}"), &CHANNELS_N100[..]),
    };
    let mut group = c.benchmark_group(name);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(3));
    let limits = [OutputLimits::new(T::zero(), T::one()).unwrap()];
    for &channels in counts {
        group.throughput(Throughput::Elements((TICKS * channels) as u64));
        // Few samples for the large banks: each iteration is already 800 000 channel-steps.
        group.sample_size(if channels * operators >= 10_240 {
            20
        } else {
            50
        });
        let (plants, inverses) =
            channel_models_of::<T>(channels, operators).expect("the paper's tables");
        let desired = signal(&plants, TICKS).expect("a bounded workload");
        let mut control = vec![T::zero(); desired.len()];
        let mut banks: Vec<(&str, Box<dyn CompensatorBank<T>>)> = vec![
            (
                "ihc_exact",
                Box::new(IhcBank::<T, Heap>::new(&plants, &limits, SolveMode::Exact).unwrap()),
            ),
            (
                "ihc_delayed",
                Box::new(IhcBank::<T, Heap>::new(&plants, &limits, SolveMode::Delayed).unwrap()),
            ),
            (
                "ihc_guarded",
                Box::new(
                    IhcBank::<T, Heap>::new(&plants, &limits, SolveMode::DelayedGuarded).unwrap(),
                ),
            ),
            (
                "wihc_exact",
                Box::new(WihcBank::<T, Heap>::new(&plants, &limits, SolveMode::Exact).unwrap()),
            ),
            (
                // Table 1's delayed WIHC loop gain is 1.66: allowed explicitly, as in the
                // single-channel benches (the trajectory rises from rest).
                "wihc_delayed",
                Box::new(
                    WihcBank::<T, Heap>::new(&plants, &limits, SolveMode::DelayedAllowUnstable)
                        .unwrap(),
                ),
            ),
            (
                "wihc_guarded",
                Box::new(
                    WihcBank::<T, Heap>::new(&plants, &limits, SolveMode::DelayedGuarded).unwrap(),
                ),
            ),
            (
                "dihc",
                Box::new(
                    DihcBank::<T, Heap>::new(&inverses, &[(T::zero(), T::one())], &limits).unwrap(),
                ),
            ),
        ];
        for (name, bank) in banks.iter_mut() {
            group.bench_with_input(BenchmarkId::new(*name, channels), &channels, |b, _| {
                b.iter(|| {
                    with_vector_path(path, || {
                        bank.reset();
                        bank.process(black_box(&desired), &mut control).unwrap();
                    })
                })
            });
        }
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    for operators in [10, 100] {
        bench_type::<f32>(c, "f32", operators);
        bench_type::<f64>(c, "f64", operators);
    }
}

criterion_group!(bank, benches);
criterion_main!(bank);
