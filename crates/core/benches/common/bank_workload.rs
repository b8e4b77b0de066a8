//! The channels and the desired positions the bank benches time (`benches/bank.rs`, the
//! criterion bench, and `benches/bank_probe.rs`); `hystcomp bench --channels`
//! (`crates/cli/src/commands/bench_bank.rs`) times the same.

use hystcomp_core::{Mpim, Real, paper, paper::PublishedMpim};

/// Operators per channel.
pub const OPERATORS: usize = 10;

/// `table` spread over [`OPERATORS`] operators, its weights scaled by `1 + 0.1 s`, `s` in
/// [-1, 1] a function of the channel (every channel its own model).
pub fn channel_model<T: Real>(table: &PublishedMpim, channel: usize) -> Mpim<T, Vec<T>> {
    let base: Mpim<T, Vec<T>> = table.spread(OPERATORS).expect("the paper's table");
    let s = ((channel as f64) * 0.618_034).fract() * 2.0 - 1.0;
    let scale = T::from_f64(1.0 + 0.1 * s);
    let weights: Vec<T> = base.weights().iter().map(|&b| b * scale).collect();
    Mpim::new(base.thresholds(), &weights, base.a1(), base.a2()).expect("scaled weights")
}

/// One model per channel.
pub type Models<T> = Vec<Mpim<T, Vec<T>>>;

/// The plants (Table 1) and the inverse models (Table 2, for DIHC) of `channels` channels, each
/// channel's [`channel_model`].
pub fn channel_models<T: Real>(channels: usize) -> (Models<T>, Models<T>) {
    let models = |table: &PublishedMpim| (0..channels).map(|c| channel_model(table, c)).collect();
    (models(&paper::TABLE1), models(&paper::TABLE2))
}

/// `ticks x channels` desired positions (row-major): each channel the three-tone voltage of
/// the single-channel benches at its own phase, run through its own plant (every sample
/// reachable), after a smooth rise from rest over the first quarter.
pub fn signal<T: Real>(plants: &[Mpim<T, Vec<T>>], ticks: usize) -> Vec<T> {
    let channels = plants.len();
    let mut out = vec![T::zero(); ticks * channels];
    for (c, plant) in plants.iter().enumerate() {
        let mut p = plant.clone();
        let phase = c as f64 * 0.37;
        for k in 0..ticks {
            let t = k as f64 / ticks as f64 * 4.0;
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
