//! Per channel-step cost of the compensator banks (issue 16): `C` channels of n = 10 operators,
//! each with its own model (Table 1 or Table 2 of the paper with its weights scaled by a
//! channel's own factor in [0.9, 1.1]) and its own phase of a three-tone trajectory, stepped
//! tick after tick for C = 1, 8, 64, 1 024 and 4 096, in f64 and f32.
//!
//! Criterion's throughput is in channel-steps (ticks x channels) per second: divide 1e9 by it
//! for nanoseconds per channel-step, the figure issue 16's acceptance names.
//!
//! The banks take the widest compilation of their kernels the processor has; set
//! `HYSTCOMP_BANK_PATH` to `baseline`, `avx2` or `avx512` to time another
//! ([`hystcomp_core::VectorPath`]).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use hystcomp_core::{
    CompensatorBank, DihcBank, Heap, IhcBank, Mpim, OutputLimits, Real, SolveMode, VectorPath,
    WihcBank,
    paper::{self, PublishedMpim},
    with_vector_path,
};
use std::hint::black_box;

/// Ticks per measured iteration.
const TICKS: usize = 200;
const OPERATORS: usize = 10;
const CHANNELS: [usize; 5] = [1, 8, 64, 1_024, 4_096];

/// `table` spread over [`OPERATORS`] operators, its weights scaled by `1 + 0.1 s`,
/// `s` in [-1, 1] a function of the channel (every channel its own model).
fn channel_model<T: Real>(table: &PublishedMpim, channel: usize) -> Mpim<T, Vec<T>> {
    let base: Mpim<T, Vec<T>> = table.spread(OPERATORS).unwrap();
    let s = ((channel as f64) * 0.618_034).fract() * 2.0 - 1.0;
    let scale = T::from_f64(1.0 + 0.1 * s);
    let weights: Vec<T> = base.weights().iter().map(|&b| b * scale).collect();
    Mpim::new(base.thresholds(), &weights, base.a1(), base.a2()).unwrap()
}

/// `ticks x channels` desired positions (row-major): each channel the three-tone voltage of
/// the single-channel benches at its own phase, run through its own plant (every sample
/// reachable), after a smooth rise from rest over the first quarter.
fn trajectory<T: Real>(plants: &[Mpim<T, Vec<T>>]) -> Vec<T> {
    let channels = plants.len();
    let mut out = vec![T::zero(); TICKS * channels];
    for (c, plant) in plants.iter().enumerate() {
        let mut p = plant.clone();
        let phase = (c as f64) * 0.37;
        for k in 0..TICKS {
            let t = k as f64 / TICKS as f64 * 4.0;
            let rise = 0.5 - 0.5 * (std::f64::consts::PI * t.min(1.0)).cos();
            let v = 0.5
                + 0.14 * (std::f64::consts::PI * t + 2.6 + phase).sin()
                + 0.14 * (1.6 * std::f64::consts::PI * t + 3.0 + phase).sin()
                + 0.2 * (2.0 * std::f64::consts::PI * t + 1.5 + phase).sin();
            out[k * channels + c] = p.step(T::from_f64(rise * v));
        }
    }
    out
}

/// The compilation `HYSTCOMP_BANK_PATH` names (the widest the processor has by default).
fn path() -> VectorPath {
    match std::env::var("HYSTCOMP_BANK_PATH").as_deref() {
        Ok("baseline") => VectorPath::Baseline,
        Ok("avx2") => VectorPath::Avx2,
        Ok("avx512") => VectorPath::Avx512,
        _ => VectorPath::Best,
    }
}

fn bench_type<T: Real>(c: &mut Criterion, type_name: &str) {
    let path = path();
    let mut group = c.benchmark_group(format!("bank_{type_name}"));
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(3));
    let limits = [OutputLimits::new(T::zero(), T::one()).unwrap()];
    for channels in CHANNELS {
        group.throughput(Throughput::Elements((TICKS * channels) as u64));
        // Few samples for the large banks: each iteration is already 800 000 channel-steps.
        group.sample_size(if channels >= 1_024 { 20 } else { 50 });
        let plants: Vec<Mpim<T, Vec<T>>> = (0..channels)
            .map(|k| channel_model(&paper::TABLE1, k))
            .collect();
        let inverses: Vec<Mpim<T, Vec<T>>> = (0..channels)
            .map(|k| channel_model(&paper::TABLE2, k))
            .collect();
        let desired = trajectory(&plants);
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
    bench_type::<f32>(c, "f32");
    bench_type::<f64>(c, "f64");
}

criterion_group!(bank, benches);
criterion_main!(bank);
