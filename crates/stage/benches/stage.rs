//! Per-sample cost of `Stage::step` for the built-in default stage.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use hystcomp_stage::Stage;

fn step(c: &mut Criterion) {
    // The paper's kind of signal: a slow multisine around mid-range, so the Preisach memory
    // sees many reversals, plus the DAC, amplifier, creep bank, resonance and sensor noise.
    let commands: Vec<f64> = (0..100_000)
        .map(|k| {
            let t = k as f64 * 1e-4;
            5.0 + 1.4 * (std::f64::consts::PI * t + 2.6).sin()
                + 1.4 * (1.6 * std::f64::consts::PI * t + 3.0).sin()
                + 2.1 * (2.0 * std::f64::consts::PI * t + 1.5).sin()
        })
        .collect();
    let mut stage = Stage::default_stage(1);
    let mut k = 0;
    c.bench_function("default stage step (per sample)", |b| {
        b.iter(|| {
            k = (k + 1) % commands.len();
            black_box(stage.step(black_box(commands[k])))
        })
    });
}

criterion_group!(benches, step);
criterion_main!(benches);
