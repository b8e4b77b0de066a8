//! Banks of compensators in f32 against their oracle, the single-channel compensators: on
//! random banks every channel's output equals its own compensator's bit for bit, sample after
//! sample, in every solve mode and on every vector path this processor runs, with blocks of 2, 3 and 8 lanes and in fixed storage (no allocator);
//! so do the diagnostics, after a reset too. The same in f64: `bank_f64.rs`.

mod bank_twins;
mod common;

use bank_twins::*;
use common::*;
use hystcomp_core::{
    BankError, CompensatorBank, CoreError, DihcBank, Fixed, Heap, IhcBank, Mpim, OutputLimits,
    PLAIN_DEGREE, SolveMode, Wihc, WihcBank, dihc_bank_rows, plant_bank_rows,
};
use proptest::prelude::*;

proptest! {
    #![proptest_config(seeded(40, 1601))]

    /// IHC and WIHC banks of eight lanes: every channel is its single twin, bit for bit.
    #[test]
    fn plant_banks_equal_their_single_channels(seed in any::<u64>(), channels in 1usize..21, mode in 0usize..4) {
        let (models, limits, desired) = random_bank(seed, channels, 300);
        check_plant_banks::<f32, 8>(&models, &limits, &desired, MODES[mode])?;
    }

    /// Blocks of three lanes.
    #[test]
    fn plant_banks_of_three_lanes_equal_their_single_channels(seed in any::<u64>(), channels in 1usize..8, mode in 0usize..4) {
        let (models, limits, desired) = random_bank(seed, channels, 200);
        check_plant_banks::<f32, 3>(&models, &limits, &desired, MODES[mode])?;
    }

    /// DIHC banks (inverse models on their input ranges).
    #[test]
    fn dihc_banks_equal_their_single_channels(seed in any::<u64>(), channels in 1usize..21) {
        let (models, limits, desired) = random_bank(seed, channels, 300);
        let ranges = random_ranges(seed ^ 0xD1, channels);
        check_dihc_bank::<f32, 8>(&models, &ranges, &limits, &desired)?;
    }
}

proptest! {
    #![proptest_config(seeded(24, 1603))]

    /// Every compilation of the kernels this processor can run (baseline SSE2, AVX2, AVX-512),
    /// chosen explicitly: IHC, WIHC and DIHC banks equal their single twins bit for bit
    /// (limits, clamps, NaN and infinite inputs, diagnostics), so the paths equal each other.
    #[test]
    fn every_vector_path_equals_the_single_channels(seed in any::<u64>(), channels in 1usize..21, mode in 0usize..4) {
        check_every_vector_path::<f32>(seed, channels, MODES[mode])?;
    }
}

/// Delayed loops on models whose plain delayed loop is accepted (gain below 1), so that the
/// bank runs `SolveMode::Delayed` itself rather than naming a refused channel.
#[test]
fn accepted_delayed_loops_equal_their_single_channels() {
    check_accepted_delayed_loops::<f32>();
}

/// Guarded delayed loops of random banks (any loop gain) on smooth trajectories: the one-pass
/// step (`crate::bank::within`) beside the reach test and the walks.
#[test]
fn guarded_loops_on_smooth_trajectories_equal_their_single_channels() {
    check_guarded_loops_on_smooth_trajectories::<f32>();
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
