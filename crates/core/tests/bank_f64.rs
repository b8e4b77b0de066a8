//! Banks of compensators in f64 against their oracle, the single-channel compensators: on
//! random banks every channel's output equals its own compensator's bit for bit, sample after
//! sample, in every solve mode and on every vector path this processor runs, with blocks of 3
//! (DIHC) and 8 lanes; so do the diagnostics, after a reset too. The same in f32, with blocks
//! of 2, 3 and 8 lanes: `bank_f32.rs`. (IHC and WIHC in blocks of one lane were tested too,
//! until CI came to 30 minutes on the project's AMD machine: their kernels, every mode on three
//! vector paths, were compiled for that test alone; blocks of 2 and 3 lanes still check the
//! kernels at widths other than 8.)

mod bank_twins;
mod common;

use bank_twins::*;
use common::*;
use hystcomp_core::{
    BankError, CompensatorBank, CoreError, DihcBank, Heap, Ihc, IhcBank, Mpim, OutputLimits,
    SolveMode, VectorPath, WihcBank,
};
use proptest::prelude::*;
use rand::RngExt;

proptest! {
    #![proptest_config(seeded(40, 1601))]

    /// IHC and WIHC banks of eight lanes: every channel is its single twin, bit for bit.
    #[test]
    fn plant_banks_equal_their_single_channels(seed in any::<u64>(), channels in 1usize..21, mode in 0usize..4) {
        let (models, limits, desired) = random_bank(seed, channels, 300);
        check_plant_banks::<f64, 8>(&models, &limits, &desired, MODES[mode])?;
    }

    /// DIHC banks (inverse models on their input ranges), blocks of eight and of three lanes.
    #[test]
    fn dihc_banks_equal_their_single_channels(seed in any::<u64>(), channels in 1usize..21) {
        let (models, limits, desired) = random_bank(seed, channels, 300);
        let ranges = random_ranges(seed ^ 0xD1, channels);
        check_dihc_bank::<f64, 8>(&models, &ranges, &limits, &desired)?;
        check_dihc_bank::<f64, 3>(&models, &ranges, &limits, &desired)?;
    }
}

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
    /// chosen explicitly: IHC, WIHC and DIHC banks equal their single twins bit for bit
    /// (limits, clamps, NaN and infinite inputs, diagnostics), so the paths equal each other.
    #[test]
    fn every_vector_path_equals_the_single_channels(seed in any::<u64>(), channels in 1usize..21, mode in 0usize..4) {
        check_every_vector_path::<f64>(seed, channels, MODES[mode])?;
    }
}

/// Delayed loops on models whose plain delayed loop is accepted (gain below 1), so that the
/// bank runs `SolveMode::Delayed` itself rather than naming a refused channel.
#[test]
fn accepted_delayed_loops_equal_their_single_channels() {
    check_accepted_delayed_loops::<f64>();
}

/// Guarded delayed loops of random banks (any loop gain) on smooth trajectories: the one-pass
/// step (`crate::bank::within`) beside the reach test and the walks.
#[test]
fn guarded_loops_on_smooth_trajectories_equal_their_single_channels() {
    check_guarded_loops_on_smooth_trajectories::<f64>();
}

/// A bank of zero lanes per block (`W = 0`) is refused, whatever its channels, by every kind
/// of bank, instead of dividing by its lane count later.
#[test]
fn a_bank_of_zero_lanes_is_refused() {
    let limits = [unit_limits()];
    for channels in [1, 2, 9] {
        let plants = vec![table1(); channels];
        let lanes_refused = |err: BankError| {
            assert!(err.channel().is_none(), "{err}");
            assert!(err.to_string().contains("lanes per block"), "{err}");
        };
        for mode in MODES {
            lanes_refused(IhcBank::<f64, Heap, 0>::new(&plants, &limits, mode).unwrap_err());
            lanes_refused(WihcBank::<f64, Heap, 0>::new(&plants, &limits, mode).unwrap_err());
        }
        // Any MPIM serves as a DIHC's inverse model.
        let ranges = [(0.0, 0.9)];
        lanes_refused(DihcBank::<f64, Heap, 0>::new(&plants, &ranges, &limits).unwrap_err());
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
