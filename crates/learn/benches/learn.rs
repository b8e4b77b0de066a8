//! The between-trials update: one `Learner::update` (indices, the guard, the filter's two
//! transforms, the exact IHC over three periods), per sample of the trial; and the filter
//! alone.

use std::path::Path;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::{Learner, LearningFilter, LearningOptions};

fn update(c: &mut Criterion) {
    let model = ModelFile::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/table1-plant.json"),
    )
    .expect("Table 1 model");
    let mut group = c.benchmark_group("learn");
    for n in [100usize, 100_000] {
        let desired: Vec<f64> = (0..n)
            .map(|k| 35.0 + 20.0 * (2.0 * std::f64::consts::PI * k as f64 / n as f64).sin())
            .collect();
        let measured: Vec<f64> = desired.iter().map(|y| 0.98 * y + 0.3).collect();
        let mut options = LearningOptions::new(10_000.0);
        options.divergence_factor = 100.0;
        options.mhe_bins = (n / 100).max(1);
        let learner = Learner::new(&model, &desired, options).expect("learner");
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::new("update", n), &n, |b, _| {
            b.iter_batched(
                || learner.clone(),
                |mut l| l.update(&measured).expect("update"),
                criterion::BatchSize::LargeInput,
            )
        });
        let mut filter = LearningFilter::new(n, true, 10_000.0, 0.8, 100.0, 4, 0);
        let mut out = vec![0.0; n];
        group.bench_with_input(BenchmarkId::new("filter", n), &n, |b, _| {
            b.iter(|| filter.apply(&measured, &mut out))
        });
    }
    group.finish();
}

criterion_group!(benches, update);
criterion_main!(benches);
