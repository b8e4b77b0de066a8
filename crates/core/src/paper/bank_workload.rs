//! The many-channel workload the bank benchmarks time: the criterion benches of the core
//! (`benches/bank.rs`, `benches/bank_probe.rs`) and `hystcomp bench --channels`, one definition
//! for all, so that their figures compare.
//!
//! Every channel has its own model, the published table spread over [`OPERATORS`] operators
//! ([`PublishedMpim::spread`]) with its weights scaled by `1 + 0.1 s`, `s` in `[-1, 1]` a
//! function of the channel; its desired positions are a three-tone voltage at the channel's own
//! phase run through its own plant, so that every sample is reachable.

use std::f64::consts::PI;
use std::vec::Vec;

use super::{PublishedMpim, TABLE1, TABLE2};
use crate::{CoreError, MAX_BANK_VALUES, Mpim, Real};

/// Operators per channel.
pub const OPERATORS: usize = 10;

/// One model per channel.
pub type Models<T> = Vec<Mpim<T, Vec<T>>>;

/// Channel `channel`'s model: `table` spread over [`OPERATORS`] operators, its weights scaled
/// by `1 + 0.1 s` with `s = 2 frac(0.618034 channel) - 1`.
pub fn channel_model<T: Real>(
    table: &PublishedMpim,
    channel: usize,
) -> Result<Mpim<T, Vec<T>>, CoreError> {
    channel_model_of(table, channel, OPERATORS)
}

/// [`channel_model`] spread over `operators` operators (a multiple of 10) instead of
/// [`OPERATORS`]: the same hysteresis, for timing larger models.
pub fn channel_model_of<T: Real>(
    table: &PublishedMpim,
    channel: usize,
    operators: usize,
) -> Result<Mpim<T, Vec<T>>, CoreError> {
    let base: Mpim<T, Vec<T>> = table.spread(operators)?;
    let s = ((channel as f64) * 0.618_034).fract() * 2.0 - 1.0;
    let scale = T::from_f64(1.0 + 0.1 * s);
    let weights: Vec<T> = base.weights().iter().map(|&b| b * scale).collect();
    Mpim::new(base.thresholds(), &weights, base.a1(), base.a2())
}

/// The plants (Table 1, for IHC and WIHC) and the inverse models (Table 2, for DIHC) of
/// `channels` channels, each channel's [`channel_model`].
pub fn channel_models<T: Real>(channels: usize) -> Result<(Models<T>, Models<T>), CoreError> {
    channel_models_of(channels, OPERATORS)
}

/// [`channel_models`] of `operators` operators each ([`channel_model_of`]).
pub fn channel_models_of<T: Real>(
    channels: usize,
    operators: usize,
) -> Result<(Models<T>, Models<T>), CoreError> {
    let models = |table: &PublishedMpim| -> Result<Models<T>, CoreError> {
        (0..channels)
            .map(|c| channel_model_of(table, c, operators))
            .collect()
    };
    Ok((models(&TABLE1)?, models(&TABLE2)?))
}

/// `ticks x channels` desired positions, row-major (tick by tick): each channel the voltage
/// `0.5 + 0.14 sin(pi t + 2.6 + p) + 0.14 sin(1.6 pi t + 3 + p) + 0.2 sin(2 pi t + 1.5 + p)`
/// (`t` from 0 to 4 over the ticks, phase `p = 0.37 c`), rising smoothly from rest over the
/// first quarter, run through the channel's own plant. Refuses more than
/// [`MAX_BANK_VALUES`] values with [`CoreError::TooLarge`].
pub fn signal<T: Real>(plants: &[Mpim<T, Vec<T>>], ticks: usize) -> Result<Vec<T>, CoreError> {
    let channels = plants.len();
    let values = ticks
        .checked_mul(channels)
        .filter(|&n| n <= MAX_BANK_VALUES)
        .ok_or(CoreError::TooLarge {
            what: "workload values (ticks x channels)",
            found: ticks.saturating_mul(channels),
            max: MAX_BANK_VALUES,
        })?;
    let mut out = std::vec![T::zero(); values];
    for (c, plant) in plants.iter().enumerate() {
        let mut p = plant.clone();
        let phase = c as f64 * 0.37;
        for k in 0..ticks {
            let t = k as f64 / ticks as f64 * 4.0;
            let rise = 0.5 - 0.5 * (PI * t.min(1.0)).cos();
            let v = 0.5
                + 0.14 * (PI * t + 2.6 + phase).sin()
                + 0.14 * (1.6 * PI * t + 3.0 + phase).sin()
                + 0.2 * (2.0 * PI * t + 1.5 + phase).sin();
            out[k * channels + c] = p.step(T::from_f64(rise * v));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every channel's model differs from the next and keeps the table's thresholds; the
    /// signal is the plant's output (within the plant's reach, finite), laid out tick by tick.
    #[test]
    fn channels_differ_and_the_signal_is_each_plants_output() {
        let (plants, inverses) = channel_models::<f64>(5).unwrap();
        assert_eq!((plants.len(), inverses.len()), (5, 5));
        for pair in plants.windows(2) {
            assert_eq!(pair[0].thresholds(), pair[1].thresholds());
            assert_ne!(pair[0].weights(), pair[1].weights());
        }
        let ticks = 40;
        let desired = signal(&plants, ticks).unwrap();
        assert_eq!(desired.len(), ticks * 5);
        let mut plant = plants[3].clone();
        plant.reset();
        let t = 1.0f64 / ticks as f64 * 4.0;
        let rise = 0.5 - 0.5 * (PI * t).cos();
        let v = 0.5
            + 0.14 * (PI * t + 2.6 + 3.0 * 0.37).sin()
            + 0.14 * (1.6 * PI * t + 3.0 + 3.0 * 0.37).sin()
            + 0.2 * (2.0 * PI * t + 1.5 + 3.0 * 0.37).sin();
        plant.step(0.0);
        assert_eq!(desired[5 + 3], plant.step(rise * v));
        assert!(desired.iter().all(|y| y.is_finite()));
        assert!(matches!(
            signal(&plants, usize::MAX),
            Err(CoreError::TooLarge { .. })
        ));
    }
}
