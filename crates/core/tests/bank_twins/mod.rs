//! Shared by the bank tests (`bank_f64.rs`, `bank_f32.rs`): random banks (models with operator
//! counts and input polynomials of their own, per-channel limits, trajectories with jumps,
//! unreachable positions, NaN, infinities and 1e308) and the comparison of a bank with its
//! oracle, the single-channel compensators, sample after sample.
//!
//! The bank tests are two binaries, one per sample type, so that their builds (the kernels of
//! every vector path, in every mode, for each lane count) run side by side on two cores: as
//! one binary its build was the last of the test suite's, 8 min on one core.
#![allow(dead_code)]

use crate::common::*;
use hystcomp_core::{
    BankError, Compensator, CompensatorBank, CoreError, Dihc, DihcBank, Heap, Ihc, IhcBank,
    InputPolynomial, MAX_INPUT_DEGREE, Mpim, OutputLimits, Real, SolveMode, VectorPath, Wihc,
    WihcBank, with_vector_path,
};
use proptest::prelude::*;
use rand::{Rng, RngExt};

/// A model in another sample type (`None` when it is not valid there).
pub fn convert<T: Real>(model: &VecMpim) -> Option<Mpim<T, Vec<T>>> {
    let cast = |v: &[f64]| v.iter().map(|&x| T::from_f64(x)).collect::<Vec<T>>();
    let input = InputPolynomial::new(&cast(model.input_polynomial().coefficients())).ok()?;
    Mpim::with_input_polynomial(&cast(model.thresholds()), &cast(model.weights()), input).ok()
}

/// The models of a random bank: one operator count for all or a count per channel, the
/// paper's cubic or random degrees, invertible on [0, 1].
pub fn random_models(rng: &mut impl Rng, channels: usize) -> Vec<VecMpim> {
    let mixed = rng.random::<bool>();
    let polynomials = rng.random::<f64>() < 0.3;
    // Up to 24 operators: both sides of `DIRECT_OPERATORS` (16), where the delayed and guarded
    // IHC switch from the direct evaluation to the walk.
    let shared_n = 1 + (rng.random::<u32>() as usize) % 24;
    (0..channels)
        .map(|_| {
            let n = if mixed {
                1 + (rng.random::<u32>() as usize) % 24
            } else {
                shared_n
            };
            if polynomials && rng.random::<bool>() {
                let degree = 1 + (rng.random::<u32>() as usize) % MAX_INPUT_DEGREE;
                random_polynomial_model(rng, n, degree)
            } else {
                random_invertible_model(rng, n)
            }
        })
        .collect()
}

/// Limits for each channel: mostly [0, 1], some narrower, some excluding 0 (the compensators
/// then start at a limit).
pub fn random_limits(rng: &mut impl Rng) -> (f64, f64) {
    match rng.random::<u32>() % 4 {
        0 | 1 => (0.0, 1.0),
        2 => (0.1 * rng.random::<f64>(), 0.7 + 0.3 * rng.random::<f64>()),
        _ => (0.05 + 0.1 * rng.random::<f64>(), 0.95),
    }
}

/// A desired trajectory for a channel: the model driven by a random walk over its limits
/// (reachable), with jumps beyond its reach and a few NaN, infinite and 1e308 samples.
pub fn random_desired(rng: &mut impl Rng, model: &VecMpim, len: usize) -> Vec<f64> {
    let mut p = model.clone();
    let (y0, y1) = (model.clone().step(0.0), model.clone().step(1.0));
    random_input(rng, len, 0.0, 1.0)
        .into_iter()
        .map(|v| {
            let y = p.step(v);
            let u: f64 = rng.random();
            if u < 0.005 {
                // Subnormal and zero positions (the fuzzers' favourites near a root at 0).
                [1e-310, -1e-310, 5e-324, 0.0][(u * 1e4) as usize % 4]
            } else if u < 0.02 {
                f64::NAN
            } else if u < 0.03 {
                [f64::INFINITY, f64::NEG_INFINITY, 1e308, -1e308][(u * 1e4) as usize % 4]
            } else if u < 0.06 {
                y0 + (y1 - y0) * (2.0 * rng.random::<f64>() - 0.5)
            } else {
                y
            }
        })
        .collect()
}

/// Steps the bank and the single compensators side by side over `desired[k][c]`, asserting
/// equal bits for every output and equal diagnostics at the end; then resets both and does it
/// again over the first samples.
pub fn assert_twins<T: Real, K: CompensatorBank<T>, C: Compensator<T>>(
    bank: &mut K,
    singles: &mut [C],
    desired: &[Vec<T>],
    what: &str,
) -> Result<(), TestCaseError> {
    let channels = singles.len();
    prop_assert_eq!(bank.channels(), channels);
    let mut control = vec![T::zero(); channels];
    for round in 0..2 {
        let samples = if round == 0 {
            desired.len()
        } else {
            desired.len().min(60)
        };
        for (k, d) in desired.iter().take(samples).enumerate() {
            bank.step(d, &mut control).unwrap();
            for (c, single) in singles.iter_mut().enumerate() {
                let expected = single.step(d[c]);
                prop_assert_eq!(
                    control[c].to_f64().to_bits(),
                    expected.to_f64().to_bits(),
                    "{} round {} sample {} channel {}: bank {} vs single {} (desired {})",
                    what,
                    round,
                    k,
                    c,
                    control[c],
                    expected,
                    d[c]
                );
            }
        }
        for (c, single) in singles.iter().enumerate() {
            prop_assert_eq!(
                bank.diagnostics(c),
                Some(single.diagnostics()),
                "{} channel {}",
                what,
                c
            );
            prop_assert_eq!(bank.limits(c), Some(single.limits()));
        }
        bank.reset();
        for single in singles.iter_mut() {
            single.reset();
        }
    }
    prop_assert_eq!(bank.diagnostics(channels), None);
    Ok(())
}

/// Each of `channels` channels' limits from the bank's `limits`: one pair shared by all, or one
/// per channel (as the banks read them).
pub fn each_limit<T: Copy>(limits: &[T], channels: usize) -> Vec<T> {
    (0..channels)
        .map(|c| limits[if limits.len() == 1 { 0 } else { c }])
        .collect()
}

/// Per-sample rows of every channel's desired position, in `T`.
pub fn rows<T: Real>(per_channel: &[Vec<f64>]) -> Vec<Vec<T>> {
    let len = per_channel.first().map_or(0, Vec::len);
    (0..len)
        .map(|k| per_channel.iter().map(|d| T::from_f64(d[k])).collect())
        .collect()
}

/// The bank against its single twins built from the same models: where a single compensator
/// is refused, the bank is refused naming the first refused channel with that error; otherwise
/// `accessors` compares what the bank reports of each channel, then [`assert_twins`] their
/// outputs.
pub fn refused_or_twins<T: Real, K: CompensatorBank<T>, C: Compensator<T>>(
    singles: Vec<Result<C, CoreError>>,
    bank: Result<K, BankError>,
    desired: &[Vec<T>],
    what: &str,
    accessors: impl FnOnce(&K, &[C]) -> Result<(), TestCaseError>,
) -> Result<(), TestCaseError> {
    let singles: Result<Vec<C>, (usize, CoreError)> = singles
        .into_iter()
        .enumerate()
        .map(|(c, s)| s.map_err(|e| (c, e)))
        .collect();
    match (singles, bank) {
        (Err((channel, error)), Err(refused)) => {
            prop_assert_eq!(refused, BankError::Channel { channel, error });
        }
        (Err((channel, _)), Ok(_)) => {
            prop_assert!(
                false,
                "{} bank accepted channel {} its single refuses",
                what,
                channel
            );
        }
        (Ok(_), Err(refused)) => {
            prop_assert!(
                false,
                "{} bank refused ({}) channels their singles accept",
                what,
                refused
            );
        }
        (Ok(mut singles), Ok(mut bank)) => {
            accessors(&bank, &singles)?;
            assert_twins(&mut bank, &mut singles, desired, what)?;
        }
    }
    Ok(())
}

/// A bank's models and limits in `T`.
type Typed<T> = (Vec<Mpim<T, Vec<T>>>, Vec<OutputLimits<T>>);

/// The models and limits of a random bank in `T` (`None` when a model is not valid there).
fn in_type<T: Real>(models: &[VecMpim], limits: &[(f64, f64)]) -> Option<Typed<T>> {
    let models = models
        .iter()
        .map(convert::<T>)
        .collect::<Option<Vec<_>>>()?;
    let limits = limits
        .iter()
        .map(|&(a, b)| OutputLimits::new(T::from_f64(a), T::from_f64(b)).unwrap())
        .collect();
    Some((models, limits))
}

/// Builds IHC and WIHC banks of `W` lanes in `mode` and compares them with their twins; when
/// a channel is refused, the bank names the first refused channel with its error.
pub fn check_plant_banks<T: Real, const W: usize>(
    models: &[VecMpim],
    limits: &[(f64, f64)],
    desired: &[Vec<f64>],
    mode: SolveMode,
) -> Result<(), TestCaseError> {
    let Some((plants, limits)) = in_type::<T>(models, limits) else {
        return Ok(());
    };
    let desired = rows::<T>(desired);
    let each = each_limit(&limits, plants.len());
    // IHC, then WIHC: the same checks on each kind.
    macro_rules! plant_kind {
        ($single:ident, $bank:ident, $what:literal) => {{
            let singles: Vec<Result<$single<T, Vec<T>>, CoreError>> = plants
                .iter()
                .zip(&each)
                .map(|(p, l)| $single::new(p, *l, mode))
                .collect();
            let bank = $bank::<T, Heap, W>::new(&plants, &limits, mode);
            refused_or_twins(singles, bank, &desired, $what, |bank, singles| {
                prop_assert_eq!(bank.mode(), mode);
                for (c, single) in singles.iter().enumerate() {
                    prop_assert_eq!(
                        bank.guard_relaxation(c).map(|mu| mu.to_f64().to_bits()),
                        Some(single.guard_relaxation().to_f64().to_bits())
                    );
                }
                prop_assert_eq!(bank.guard_relaxation(singles.len()), None);
                Ok(())
            })?;
        }};
    }
    plant_kind!(Ihc, IhcBank, "IHC");
    plant_kind!(Wihc, WihcBank, "WIHC");
    Ok(())
}

/// Models, limits and per-channel trajectories of a random bank.
pub type RandomBank = (Vec<VecMpim>, Vec<(f64, f64)>, Vec<Vec<f64>>);

/// A random bank: models, limits and trajectories. The limits are one pair per channel, all
/// different or all the same, or one pair shared by every channel (a third each).
pub fn random_bank(seed: u64, channels: usize, len: usize) -> RandomBank {
    let mut rng = rng(seed);
    let models = random_models(&mut rng, channels);
    let sharing = rng.random_range(0..3u8);
    let first = random_limits(&mut rng);
    let limits: Vec<(f64, f64)> = match sharing {
        0 => vec![first],
        1 => vec![first; channels],
        _ => (0..channels).map(|_| random_limits(&mut rng)).collect(),
    };
    let desired = models
        .iter()
        .map(|m| random_desired(&mut rng, m, len))
        .collect();
    (models, limits, desired)
}

pub const MODES: [SolveMode; 4] = [
    SolveMode::Exact,
    SolveMode::Delayed,
    SolveMode::DelayedGuarded,
    SolveMode::DelayedAllowUnstable,
];

/// Builds a DIHC bank of `W` lanes and compares it with its twins; when a channel is refused,
/// the bank names the first refused channel with its error.
pub fn check_dihc_bank<T: Real, const W: usize>(
    models: &[VecMpim],
    ranges: &[(f64, f64)],
    limits: &[(f64, f64)],
    desired: &[Vec<f64>],
) -> Result<(), TestCaseError> {
    let Some((inverses, limits)) = in_type::<T>(models, limits) else {
        return Ok(());
    };
    let ranges: Vec<(T, T)> = ranges
        .iter()
        .map(|&(a, b)| (T::from_f64(a), T::from_f64(b)))
        .collect();
    let singles: Vec<Result<Dihc<T, Vec<T>>, CoreError>> = inverses
        .iter()
        .zip(&ranges)
        .zip(&each_limit(&limits, inverses.len()))
        .map(|((m, r), l)| Dihc::new(m, r.0, r.1, *l))
        .collect();
    let bank = DihcBank::<T, Heap, W>::new(&inverses, &ranges, &limits);
    refused_or_twins(
        singles,
        bank,
        &rows::<T>(desired),
        "DIHC",
        |bank, singles| {
            for (c, single) in singles.iter().enumerate() {
                let bits = |(lo, hi): (T, T)| (lo.to_f64().to_bits(), hi.to_f64().to_bits());
                prop_assert_eq!(
                    bank.input_range(c).map(bits),
                    Some(bits(single.input_range()))
                );
            }
            prop_assert_eq!(bank.input_range(singles.len()), None);
            Ok(())
        },
    )
}

/// Banks whose plain delayed loop every channel accepts (gain below 1, up to 12 operators), so
/// that a bank runs `SolveMode::Delayed` itself rather than naming a refused channel: twelve
/// cases of 1 to 34 channels, the same in both bank tests.
pub fn accepted_delayed_banks() -> Vec<RandomBank> {
    let mut rng = rng(1602);
    (0..12)
        .map(|case| {
            let channels = 1 + case * 3;
            let models: Vec<VecMpim> = (0..channels)
                .map(|_| {
                    let n = 1 + (rng.random::<u32>() as usize) % 12;
                    random_model_with_gain_below(&mut rng, n, 0.9)
                })
                .collect();
            let limits = vec![(0.0, 1.0); channels];
            let desired: Vec<Vec<f64>> = models
                .iter()
                .map(|m| random_desired(&mut rng, m, 300))
                .collect();
            (models, limits, desired)
        })
        .collect()
}

/// Random per-channel input ranges of DIHC banks, `[0-0.1, 0.8-1]`.
pub fn random_ranges(seed: u64, channels: usize) -> Vec<(f64, f64)> {
    let mut rng = rng(seed);
    (0..channels)
        .map(|_| (0.1 * rng.random::<f64>(), 0.8 + 0.2 * rng.random::<f64>()))
        .collect()
}

/// The compilations of the kernels besides the default (the widest the processor has).
pub const PATHS: [VectorPath; 3] = [VectorPath::Baseline, VectorPath::Avx2, VectorPath::Avx512];

/// On every compilation of the kernels this processor can run, chosen explicitly, IHC, WIHC and
/// DIHC banks of eight lanes in `T` on a random bank equal their single twins bit for bit.
pub fn check_every_vector_path<T: Real>(
    seed: u64,
    channels: usize,
    mode: SolveMode,
) -> Result<(), TestCaseError> {
    let (models, limits, desired) = random_bank(seed, channels, 200);
    let ranges = random_ranges(seed ^ 0xD2, channels);
    for path in PATHS.into_iter().filter(|p| p.available()) {
        with_vector_path(path, || -> Result<(), TestCaseError> {
            prop_assert_eq!(VectorPath::current(), path);
            check_plant_banks::<T, 8>(&models, &limits, &desired, mode)?;
            check_dihc_bank::<T, 8>(&models, &ranges, &limits, &desired)
        })?;
    }
    Ok(())
}

/// The plain and guarded delayed loops of [`accepted_delayed_banks`] in `T`, eight lanes,
/// equal their single twins: on the random trajectories, and on [`smooth_desired`] ones.
pub fn check_accepted_delayed_loops<T: Real>() {
    for (models, limits, desired) in accepted_delayed_banks() {
        check_plant_banks::<T, 8>(&models, &limits, &desired, SolveMode::Delayed).unwrap();
        let smooth = smooth_desired(&models, desired[0].len());
        for mode in [SolveMode::Delayed, SolveMode::DelayedGuarded] {
            check_plant_banks::<T, 8>(&models, &limits, &smooth, mode).unwrap();
        }
    }
}

/// The guarded delayed loops of random banks (any loop gain: under-relaxed where it is above
/// 1; up to 24 operators, both sides of the direct evaluation's 16) in `T`, eight lanes, on
/// [`smooth_desired`] trajectories, equal their single twins: the one-pass step, the reach
/// test and the walks side by side.
pub fn check_guarded_loops_on_smooth_trajectories<T: Real>() {
    let mut rng = rng(1603);
    for case in 0..16 {
        let channels = 1 + case * 2;
        let models = random_models(&mut rng, channels);
        let limits: Vec<(f64, f64)> = (0..channels).map(|_| random_limits(&mut rng)).collect();
        let smooth = smooth_desired(&models, 300);
        check_plant_banks::<T, 8>(&models, &limits, &smooth, SolveMode::DelayedGuarded).unwrap();
    }
}

/// Trajectories without a NaN: each channel's plant driven by two tones over 0.47 +- 0.55 of
/// [0, 1], its own phase, so that most blocks of the delayed loops step in one pass and some
/// reach a limit and walk (the paths `crate::bank::within` chooses between).
pub fn smooth_desired(models: &[VecMpim], len: usize) -> Vec<Vec<f64>> {
    models
        .iter()
        .enumerate()
        .map(|(c, model)| {
            let mut plant = model.clone();
            (0..len)
                .map(|k| {
                    let t = k as f64 * 0.01 + c as f64 * 0.37;
                    plant.step(0.47 + 0.4 * (3.0 * t).sin() + 0.15 * (7.3 * t).sin())
                })
                .collect()
        })
        .collect()
}
