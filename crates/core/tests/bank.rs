//! Banks of compensators against their oracle, the single-channel compensators: on random banks
//! (random models with operator counts and input polynomials of their own, per-channel limits,
//! trajectories with jumps, unreachable positions, NaN, infinities and 1e308), every channel's
//! output equals its own compensator's bit for bit, sample after sample, in f64 and f32, in
//! every solve mode, with blocks of 1, 3 and 8 lanes; so do the diagnostics, after a reset too.

mod common;

use common::*;
use hystcomp_core::{
    BankError, Compensator, CompensatorBank, CoreError, Dihc, DihcBank, Fixed, Heap, Ihc, IhcBank,
    InputPolynomial, MAX_INPUT_DEGREE, Mpim, OutputLimits, PLAIN_DEGREE, Real, SolveMode,
    VectorPath, Wihc, WihcBank, dihc_bank_rows, plant_bank_rows, with_vector_path,
};
use proptest::prelude::*;
use rand::{Rng, RngExt};

/// A model in another sample type (`None` when it is not valid there).
fn convert<T: Real>(model: &VecMpim) -> Option<Mpim<T, Vec<T>>> {
    let cast = |v: &[f64]| v.iter().map(|&x| T::from_f64(x)).collect::<Vec<T>>();
    let input = InputPolynomial::new(&cast(model.input_polynomial().coefficients())).ok()?;
    Mpim::with_input_polynomial(&cast(model.thresholds()), &cast(model.weights()), input).ok()
}

/// The models of a random bank: one operator count for all or a count per channel, the
/// paper's cubic or random degrees, invertible on [0, 1].
fn random_models(rng: &mut impl Rng, channels: usize) -> Vec<VecMpim> {
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
fn random_limits(rng: &mut impl Rng) -> (f64, f64) {
    match rng.random::<u32>() % 4 {
        0 | 1 => (0.0, 1.0),
        2 => (0.1 * rng.random::<f64>(), 0.7 + 0.3 * rng.random::<f64>()),
        _ => (0.05 + 0.1 * rng.random::<f64>(), 0.95),
    }
}

/// A desired trajectory for a channel: the model driven by a random walk over its limits
/// (reachable), with jumps beyond its reach and a few NaN, infinite and 1e308 samples.
fn random_desired(rng: &mut impl Rng, model: &VecMpim, len: usize) -> Vec<f64> {
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
fn assert_twins<T: Real, K: CompensatorBank<T>, C: Compensator<T>>(
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
fn each_limit<T: Copy>(limits: &[T], channels: usize) -> Vec<T> {
    (0..channels)
        .map(|c| limits[if limits.len() == 1 { 0 } else { c }])
        .collect()
}

/// Per-sample rows of every channel's desired position, in `T`.
fn rows<T: Real>(per_channel: &[Vec<f64>]) -> Vec<Vec<T>> {
    let len = per_channel.first().map_or(0, Vec::len);
    (0..len)
        .map(|k| per_channel.iter().map(|d| T::from_f64(d[k])).collect())
        .collect()
}

/// Builds IHC and WIHC banks of `W` lanes in `mode` and compares them with their twins; when
/// a channel is refused, the bank names the first refused channel with its error.
fn check_plant_banks<T: Real, const W: usize>(
    models: &[VecMpim],
    limits: &[(f64, f64)],
    desired: &[Vec<f64>],
    mode: SolveMode,
) -> Result<(), TestCaseError> {
    let Some(plants) = models.iter().map(convert::<T>).collect::<Option<Vec<_>>>() else {
        return Ok(());
    };
    let limits: Vec<OutputLimits<T>> = limits
        .iter()
        .map(|&(a, b)| OutputLimits::new(T::from_f64(a), T::from_f64(b)).unwrap())
        .collect();
    let desired = rows::<T>(desired);
    let each = each_limit(&limits, plants.len());
    // IHC.
    let singles: Vec<Result<Ihc<T, Vec<T>>, CoreError>> = plants
        .iter()
        .zip(&each)
        .map(|(p, l)| Ihc::new(p, *l, mode))
        .collect();
    let bank = IhcBank::<T, Heap, W>::new(&plants, &limits, mode);
    match singles.iter().position(Result::is_err) {
        Some(c) => {
            let expected = singles[c].clone().unwrap_err();
            prop_assert_eq!(
                bank.unwrap_err(),
                BankError::Channel {
                    channel: c,
                    error: expected
                }
            );
        }
        None => {
            let mut singles: Vec<_> = singles.into_iter().map(Result::unwrap).collect();
            let mut bank = bank.unwrap();
            prop_assert_eq!(bank.mode(), mode);
            for (c, single) in singles.iter().enumerate() {
                prop_assert_eq!(
                    bank.guard_relaxation(c).map(|mu| mu.to_f64().to_bits()),
                    Some(single.guard_relaxation().to_f64().to_bits())
                );
            }
            prop_assert_eq!(bank.guard_relaxation(singles.len()), None);
            assert_twins(&mut bank, &mut singles, &desired, "IHC")?;
        }
    }
    // WIHC.
    let singles: Vec<Result<Wihc<T, Vec<T>>, CoreError>> = plants
        .iter()
        .zip(&each)
        .map(|(p, l)| Wihc::new(p, *l, mode))
        .collect();
    let bank = WihcBank::<T, Heap, W>::new(&plants, &limits, mode);
    match singles.iter().position(Result::is_err) {
        Some(c) => {
            let expected = singles[c].clone().unwrap_err();
            prop_assert_eq!(
                bank.unwrap_err(),
                BankError::Channel {
                    channel: c,
                    error: expected
                }
            );
        }
        None => {
            let mut singles: Vec<_> = singles.into_iter().map(Result::unwrap).collect();
            let mut bank = bank.unwrap();
            prop_assert_eq!(bank.mode(), mode);
            for (c, single) in singles.iter().enumerate() {
                prop_assert_eq!(
                    bank.guard_relaxation(c).map(|mu| mu.to_f64().to_bits()),
                    Some(single.guard_relaxation().to_f64().to_bits())
                );
            }
            prop_assert_eq!(bank.guard_relaxation(singles.len()), None);
            assert_twins(&mut bank, &mut singles, &desired, "WIHC")?;
        }
    }
    Ok(())
}

/// Models, limits and per-channel trajectories of a random bank.
type RandomBank = (Vec<VecMpim>, Vec<(f64, f64)>, Vec<Vec<f64>>);

/// A random bank: models, limits and trajectories. The limits are one pair per channel, all
/// different or all the same, or one pair shared by every channel (a third each).
fn random_bank(seed: u64, channels: usize, len: usize) -> RandomBank {
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

const MODES: [SolveMode; 4] = [
    SolveMode::Exact,
    SolveMode::Delayed,
    SolveMode::DelayedGuarded,
    SolveMode::DelayedAllowUnstable,
];

proptest! {
    #![proptest_config(seeded(40, 1601))]

    /// IHC and WIHC banks of eight lanes in f64: every channel is its single twin, bit for bit.
    #[test]
    fn plant_banks_equal_their_single_channels_f64(seed in any::<u64>(), channels in 1usize..21, mode in 0usize..4) {
        let (models, limits, desired) = random_bank(seed, channels, 300);
        check_plant_banks::<f64, 8>(&models, &limits, &desired, MODES[mode])?;
    }

    /// The same in f32.
    #[test]
    fn plant_banks_equal_their_single_channels_f32(seed in any::<u64>(), channels in 1usize..21, mode in 0usize..4) {
        let (models, limits, desired) = random_bank(seed, channels, 300);
        check_plant_banks::<f32, 8>(&models, &limits, &desired, MODES[mode])?;
    }

    /// Blocks of one and of three lanes.
    #[test]
    fn plant_banks_of_other_widths_equal_their_single_channels(seed in any::<u64>(), channels in 1usize..8, mode in 0usize..4) {
        let (models, limits, desired) = random_bank(seed, channels, 200);
        check_plant_banks::<f64, 1>(&models, &limits, &desired, MODES[mode])?;
        check_plant_banks::<f32, 3>(&models, &limits, &desired, MODES[mode])?;
    }

    /// DIHC banks (inverse models on their input ranges) in f64 and f32.
    #[test]
    fn dihc_banks_equal_their_single_channels(seed in any::<u64>(), channels in 1usize..21) {
        let (models, limits, desired) = random_bank(seed, channels, 300);
        let mut rng = rng(seed ^ 0xD1);
        let ranges: Vec<(f64, f64)> = (0..channels)
            .map(|_| (0.1 * rng.random::<f64>(), 0.8 + 0.2 * rng.random::<f64>()))
            .collect();
        check_dihc_bank::<f64, 8>(&models, &ranges, &limits, &desired)?;
        check_dihc_bank::<f32, 8>(&models, &ranges, &limits, &desired)?;
        check_dihc_bank::<f64, 3>(&models, &ranges, &limits, &desired)?;
    }
}

/// The compilations of the kernels besides the default (the widest the processor has).
const PATHS: [VectorPath; 3] = [VectorPath::Baseline, VectorPath::Avx2, VectorPath::Avx512];

/// A compilation this processor cannot run is said, not passed silently.
#[test]
fn every_vector_path_runs_here_or_is_said() {
    for path in PATHS {
        if !path.available() {
            hystcomp_testkit::skip(format!(
                "bank kernels: this processor has no {path:?}, so that compilation is not compared \
                 with the single channels here"
            ));
        }
    }
    assert!(VectorPath::Baseline.available());
}

proptest! {
    #![proptest_config(seeded(24, 1603))]

    /// Every compilation of the kernels this processor can run (baseline SSE2, AVX2, AVX-512),
    /// chosen explicitly: IHC, WIHC and DIHC banks in f64 and f32 equal their single twins bit
    /// for bit (limits, clamps, NaN and infinite inputs, diagnostics), so the paths equal each
    /// other.
    #[test]
    fn every_vector_path_equals_the_single_channels(seed in any::<u64>(), channels in 1usize..21, mode in 0usize..4) {
        let (models, limits, desired) = random_bank(seed, channels, 200);
        let mut rng = rng(seed ^ 0xD2);
        let ranges: Vec<(f64, f64)> = (0..channels)
            .map(|_| (0.1 * rng.random::<f64>(), 0.8 + 0.2 * rng.random::<f64>()))
            .collect();
        for path in PATHS.into_iter().filter(|p| p.available()) {
            with_vector_path(path, || -> Result<(), TestCaseError> {
                prop_assert_eq!(VectorPath::current(), path);
                check_plant_banks::<f64, 8>(&models, &limits, &desired, MODES[mode])?;
                check_plant_banks::<f32, 8>(&models, &limits, &desired, MODES[mode])?;
                check_dihc_bank::<f64, 8>(&models, &ranges, &limits, &desired)?;
                check_dihc_bank::<f32, 8>(&models, &ranges, &limits, &desired)
            })?;
        }
    }
}

fn check_dihc_bank<T: Real, const W: usize>(
    models: &[VecMpim],
    ranges: &[(f64, f64)],
    limits: &[(f64, f64)],
    desired: &[Vec<f64>],
) -> Result<(), TestCaseError> {
    let Some(inverses) = models.iter().map(convert::<T>).collect::<Option<Vec<_>>>() else {
        return Ok(());
    };
    let limits: Vec<OutputLimits<T>> = limits
        .iter()
        .map(|&(a, b)| OutputLimits::new(T::from_f64(a), T::from_f64(b)).unwrap())
        .collect();
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
    match singles.iter().position(Result::is_err) {
        Some(c) => {
            let expected = singles[c].clone().unwrap_err();
            prop_assert_eq!(
                bank.unwrap_err(),
                BankError::Channel {
                    channel: c,
                    error: expected
                }
            );
        }
        None => {
            let mut singles: Vec<_> = singles.into_iter().map(Result::unwrap).collect();
            let mut bank = bank.unwrap();
            for (c, single) in singles.iter().enumerate() {
                let bits = |(lo, hi): (T, T)| (lo.to_f64().to_bits(), hi.to_f64().to_bits());
                prop_assert_eq!(
                    bank.input_range(c).map(bits),
                    Some(bits(single.input_range()))
                );
            }
            prop_assert_eq!(bank.input_range(singles.len()), None);
            assert_twins(&mut bank, &mut singles, &rows::<T>(desired), "DIHC")?;
        }
    }
    Ok(())
}

/// Delayed loops on models whose plain delayed loop is accepted (gain below 1), so that the
/// bank runs `SolveMode::Delayed` itself rather than naming a refused channel.
#[test]
fn accepted_delayed_loops_equal_their_single_channels() {
    let mut rng = rng(1602);
    for case in 0..12 {
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
        check_plant_banks::<f64, 8>(&models, &limits, &desired, SolveMode::Delayed).unwrap();
        check_plant_banks::<f32, 8>(&models, &limits, &desired, SolveMode::Delayed).unwrap();
    }
}

/// A refused channel is named: the bank's error is the first refused channel's own error.
#[test]
fn a_refused_channel_is_named_by_its_index() {
    let plants = vec![table1(), table1(), random_model(&mut rng(5), 8), table1()];
    let limits = [unit_limits()];
    // Table 1's delayed WIHC has a loop gain of 1.66: every channel is refused, the first named.
    let err = WihcBank::<f64, Heap>::new(&plants, &limits, SolveMode::Delayed).unwrap_err();
    assert_eq!(err.channel(), Some(0));
    assert!(matches!(err.error(), CoreError::DelayedLoopUnstable { .. }));
    assert!(err.to_string().starts_with("channel 0: "), "{err}");
    // A non-invertible model in channel 2.
    let mut bad = table1();
    bad = Mpim::new(bad.thresholds(), &[-0.5; 10], bad.a1(), bad.a2()).unwrap();
    let plants = vec![table1(), table1(), bad.clone(), table1()];
    let err = IhcBank::<f64, Heap>::new(&plants, &limits, SolveMode::Exact).unwrap_err();
    let single = Ihc::<f64, Vec<f64>>::new(&bad, unit_limits(), SolveMode::Exact).unwrap_err();
    assert_eq!(
        err,
        BankError::Channel {
            channel: 2,
            error: single
        }
    );
    assert!(err.to_string().starts_with("channel 2: "), "{err}");
    // The bank as a whole.
    let none: Vec<VecMpim> = Vec::new();
    assert!(matches!(
        IhcBank::<f64, Heap>::new(&none, &limits, SolveMode::Exact),
        Err(BankError::Bank(_))
    ));
    let two_limits = [unit_limits(), unit_limits()];
    let err = IhcBank::<f64, Heap>::new(
        &[table1(), table1(), table1()],
        &two_limits,
        SolveMode::Exact,
    )
    .unwrap_err();
    assert_eq!(err.channel(), None);
    assert!(err.to_string().contains("output limits"), "{err}");
}

/// Arrays that do not hold one value per channel are refused, the state untouched.
#[test]
fn ticks_and_signals_of_the_wrong_size_are_refused() {
    let plants = vec![table1(); 5];
    let mut bank = IhcBank::<f64, Heap>::new(&plants, &[unit_limits()], SolveMode::Exact).unwrap();
    let mut out = [0.0; 5];
    assert!(matches!(
        bank.step(&[0.3; 4], &mut out),
        Err(CoreError::ChannelCount {
            channels: 5,
            found: 4,
            ..
        })
    ));
    assert!(matches!(
        bank.step(&[0.3; 5], &mut [0.0; 6]),
        Err(CoreError::ChannelCount { found: 6, .. })
    ));
    let mut long = vec![0.0; 12];
    assert!(bank.process(&[0.3; 12], &mut long).is_err());
    assert!(bank.process(&[0.3; 10], &mut long).is_err());
    assert_eq!(bank.diagnostics(0).unwrap(), Default::default());
    // A whole signal is the ticks one after the other.
    let signal: Vec<f64> = (0..50).map(|k| 0.2 + 0.004 * k as f64).collect();
    let mut control = vec![0.0; 50];
    bank.process(&signal, &mut control).unwrap();
    let mut again = IhcBank::<f64, Heap>::new(&plants, &[unit_limits()], SolveMode::Exact).unwrap();
    for (d, c) in signal.chunks(5).zip(control.chunks(5)) {
        again.step(d, &mut out).unwrap();
        assert_eq!(out, c);
    }
}

/// Fixed storage (no allocator): a six-axis bank in f32 with two lanes per block equals the
/// heap bank, and a storage too small is refused.
#[test]
fn fixed_storage_holds_a_six_axis_stage() {
    const ROWS: [usize; 3] = plant_bank_rows(6, 10, PLAIN_DEGREE, 2);
    const DIHC_ROWS: [usize; 3] = dihc_bank_rows(6, 10, PLAIN_DEGREE, 2);
    type Six = IhcBank<f32, Fixed<{ ROWS[0] }, { ROWS[1] }, { ROWS[2] }>, 2>;
    type SixDihc = DihcBank<f32, Fixed<{ DIHC_ROWS[0] }, { DIHC_ROWS[1] }, { DIHC_ROWS[2] }>, 2>;
    let plants: Vec<Mpim<f32, [f32; 10]>> = (0..6)
        .map(|_| hystcomp_core::paper::TABLE1.model().unwrap())
        .collect();
    let limits = [OutputLimits::new(0.0f32, 1.0).unwrap()];
    let mut fixed = Six::new(&plants, &limits, SolveMode::Exact).unwrap();
    let mut heap = IhcBank::<f32, Heap>::new(&plants, &limits, SolveMode::Exact).unwrap();
    let (mut a, mut b) = ([0.0f32; 6], [0.0f32; 6]);
    for k in 0..500 {
        let d: Vec<f32> = (0..6)
            .map(|c| 0.4 + 0.3 * ((k + 40 * c) as f32 * 0.02).sin())
            .collect();
        fixed.step(&d, &mut a).unwrap();
        heap.step(&d, &mut b).unwrap();
        assert_eq!(a, b, "sample {k}");
    }
    let inverses: Vec<Mpim<f32, [f32; 10]>> = (0..6)
        .map(|_| hystcomp_core::paper::TABLE2.model().unwrap())
        .collect();
    assert!(SixDihc::new(&inverses, &[(0.0, 1.0)], &limits).is_ok());
    // Seven channels do not fit.
    let seven: Vec<Mpim<f32, [f32; 10]>> = (0..7)
        .map(|_| hystcomp_core::paper::TABLE1.model().unwrap())
        .collect();
    assert!(matches!(
        Six::new(&seven, &limits, SolveMode::Exact),
        Err(BankError::Bank(CoreError::Capacity { .. }))
    ));
}

/// Fixed storage for WIHC too: a six-axis f32 bank of random invertible models of ten
/// operators, exact and guarded delayed, equals each channel's own [`Wihc`] in fixed-size
/// buffers bit for bit, diagnostics included.
#[test]
fn fixed_storage_wihc_equals_its_single_channels() {
    const ROWS: [usize; 3] = plant_bank_rows(6, 10, PLAIN_DEGREE, 2);
    type Six = WihcBank<f32, Fixed<{ ROWS[0] }, { ROWS[1] }, { ROWS[2] }>, 2>;
    let mut rng = rng(1604);
    let cast = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    let mut plants: Vec<Mpim<f32, [f32; 10]>> = Vec::new();
    while plants.len() < 6 {
        let m = random_invertible_model(&mut rng, 10);
        let (a1, a2) = (
            m.input_polynomial().coefficients()[2],
            m.input_polynomial().coefficients()[0],
        );
        if let Ok(p) = Mpim::new(
            &cast(m.thresholds()),
            &cast(m.weights()),
            a1 as f32,
            a2 as f32,
        ) {
            plants.push(p);
        }
    }
    let limits = [OutputLimits::new(0.0f32, 1.0).unwrap()];
    for mode in [SolveMode::Exact, SolveMode::DelayedGuarded] {
        let mut bank = Six::new(&plants, &limits, mode).unwrap();
        let mut singles: Vec<Wihc<f32, [f32; 10]>> = plants
            .iter()
            .map(|p| Wihc::new(p, limits[0], mode).unwrap())
            .collect();
        let desired: Vec<Vec<f32>> = (0..600)
            .map(|k| {
                (0..6)
                    .map(|c| 0.45 + 0.5 * ((k + 37 * c) as f32 * 0.031).sin())
                    .collect()
            })
            .collect();
        assert_twins(&mut bank, &mut singles, &desired, "fixed WIHC").unwrap();
    }
}

/// The safety invariants, per channel, stated directly (they follow from the equality with the
/// single channels, which have their own invariant tests; here they are checked on the bank
/// itself): every output finite and within its own channel's limits, whatever the desired
/// positions (NaN, infinities, 1e308, subnormals), in every mode; and no channel's own loop
/// oscillates: after a jump to a constant reachable position, the guarded delayed loops of
/// Table 1-like models (WIHC loop gain 1.66, which the plain delayed loop rings at) settle.
#[test]
fn every_channel_keeps_the_safety_invariants() {
    let mut rng = rng(1603);
    for case in 0..16 {
        let channels = 1 + case * 2;
        let (models, limits, desired) = random_bank(rng.random(), channels, 200);
        let Some(plants) = models
            .iter()
            .map(convert::<f64>)
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let limits: Vec<OutputLimits<f64>> = limits
            .iter()
            .map(|&(a, b)| OutputLimits::new(a, b).unwrap())
            .collect();
        let ticks = rows::<f64>(&desired);
        for mode in MODES {
            let banks: Vec<Box<dyn CompensatorBank<f64>>> = [
                IhcBank::<f64, Heap>::new(&plants, &limits, mode)
                    .ok()
                    .map(|b| Box::new(b) as Box<dyn CompensatorBank<f64>>),
                WihcBank::<f64, Heap>::new(&plants, &limits, mode)
                    .ok()
                    .map(|b| Box::new(b) as Box<dyn CompensatorBank<f64>>),
            ]
            .into_iter()
            .flatten()
            .collect();
            for mut bank in banks {
                let mut control = vec![0.0; channels];
                for (k, d) in ticks.iter().enumerate() {
                    bank.step(d, &mut control).unwrap();
                    for (c, &v) in control.iter().enumerate() {
                        let l = bank.limits(c).unwrap();
                        assert!(
                            v.is_finite() && v >= l.min() && v <= l.max(),
                            "case {case} {mode:?} sample {k} channel {c}: {v} outside [{}, {}]",
                            l.min(),
                            l.max()
                        );
                    }
                }
            }
        }
    }
    // No oscillation of the guarded loops: jumps from rest to constant positions.
    let plants: Vec<VecMpim> = (0..12)
        .map(|c| {
            let t = table1();
            let scale = 0.9 + 0.02 * c as f64;
            let weights: Vec<f64> = t.weights().iter().map(|b| b * scale).collect();
            Mpim::new(t.thresholds(), &weights, t.a1(), t.a2()).unwrap()
        })
        .collect();
    let limits = [unit_limits()];
    let targets: Vec<f64> = (0..12)
        .map(|c| {
            let mut p = plants[c].clone();
            p.step(0.2 + 0.05 * c as f64)
        })
        .collect();
    for kind in 0..2 {
        let mut bank: Box<dyn CompensatorBank<f64>> = if kind == 0 {
            Box::new(
                IhcBank::<f64, Heap>::new(&plants, &limits, SolveMode::DelayedGuarded).unwrap(),
            )
        } else {
            Box::new(
                WihcBank::<f64, Heap>::new(&plants, &limits, SolveMode::DelayedGuarded).unwrap(),
            )
        };
        let mut control = vec![0.0; 12];
        let mut history = Vec::new();
        for _ in 0..400 {
            bank.step(&targets, &mut control).unwrap();
            history.push(control.clone());
        }
        for c in 0..12 {
            let tail: Vec<f64> = history[350..].iter().map(|t| t[c]).collect();
            let spread = tail.iter().cloned().fold(f64::MIN, f64::max)
                - tail.iter().cloned().fold(f64::MAX, f64::min);
            assert!(
                spread < 1e-9,
                "kind {kind} channel {c}: still moving by {spread}"
            );
            let mut p = plants[c].clone();
            let reached = history.iter().map(|t| p.step(t[c])).last().unwrap();
            assert!(
                (reached - targets[c]).abs() < 1e-6,
                "kind {kind} channel {c}: settled at {reached}, not {}",
                targets[c]
            );
        }
    }
}
