//! Identification of 100 000 samples: least squares with n = 10 and n = 50 play operators, and
//! the particle swarm (its defaults, `PsoOptions::default()`) on the same data.
//!
//! The record: Table 1 of the paper driven by 50 decaying 1 Hz cycles at 2 kHz (so that every
//! operator reverses at many amplitudes), 0..10 V -> 0..75 um, plus Gaussian sensor noise of
//! 0.1 % of the range (seeded).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use hystcomp_core::Mpim;
use hystcomp_identify::{IdentifyOptions, Method, PsoOptions, Thresholds, identify};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const SAMPLES: usize = 100_000;

fn record() -> (Vec<f64>, Vec<f64>) {
    let thresholds = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
    let weights = [
        0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ];
    let mut plant: Mpim<f64, Vec<f64>> =
        Mpim::new(&thresholds, &weights, -0.1569, 0.4603).expect("Table 1 is a valid model");
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let noise = Normal::new(0.0, 0.001 * 75.0).expect("valid noise");
    let rate = 2000.0;
    let voltage: Vec<f64> = (0..SAMPLES)
        .map(|k| {
            let t = k as f64 / rate;
            let envelope = 0.5 * (1.0 - 0.9 * t / (SAMPLES as f64 / rate));
            10.0 * (0.5 - envelope * (2.0 * std::f64::consts::PI * t).cos())
        })
        .collect();
    let displacement = voltage
        .iter()
        .map(|v| 75.0 * plant.step(v / 10.0) + noise.sample(&mut rng))
        .collect();
    (voltage, displacement)
}

fn bench(c: &mut Criterion) {
    let (voltage, displacement) = record();
    let ls = |n| IdentifyOptions {
        thresholds: Thresholds::Uniform(n),
        ..IdentifyOptions::default()
    };
    let pso = IdentifyOptions {
        method: Method::ParticleSwarm(PsoOptions::default()),
        ..IdentifyOptions::default()
    };
    for (name, options) in [
        ("ls n=10", ls(10)),
        ("ls n=50", ls(50)),
        ("pso n=10", pso.clone()),
    ] {
        let fit = identify(&voltage, &displacement, &options).expect("identifies");
        eprintln!(
            "{name}: fit RMS {:.4} % of range, max {:.4} %, {}",
            fit.report.fit.rms_percent, fit.report.fit.max_percent, fit.report.detail
        );
    }
    let mut group = c.benchmark_group("identify 100k samples");
    group.sample_size(10);
    for n in [10, 50] {
        let options = ls(n);
        group.bench_function(format!("ls n={n}"), |b| {
            b.iter(|| identify(black_box(&voltage), black_box(&displacement), &options))
        });
    }
    group.bench_function("pso defaults n=10", |b| {
        b.iter(|| identify(black_box(&voltage), black_box(&displacement), &pso))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
