//! A bank split over threads (`hystcomp_io::threads::ThreadedBank`, feature `parallel`, which
//! the crate's tests turn on) gives the unsplit bank's bits, limits, diagnostics and refusals.

use std::ops::Range;

use hystcomp_core::{
    CompensatorBank, DihcBank, Heap, IhcBank, Mpim, OutputLimits, SolveMode, paper,
};
use hystcomp_io::threads::ThreadedBank;

/// Channel `c`'s model: Table 1 (or 2) spread over ten operators, weights scaled by its own
/// factor.
fn model(table: &paper::PublishedMpim, c: usize) -> Mpim<f64, Vec<f64>> {
    let base: Mpim<f64, Vec<f64>> = table.spread(10).unwrap();
    let scale = 0.9 + 0.2 * ((c as f64) * 0.618_034).fract();
    let weights: Vec<f64> = base.weights().iter().map(|b| b * scale).collect();
    Mpim::new(base.thresholds(), &weights, base.a1(), base.a2()).unwrap()
}

fn signal(channels: usize, ticks: usize) -> Vec<f64> {
    (0..ticks * channels)
        .map(|i| {
            let (k, c) = (i / channels, i % channels);
            let y = 0.45 + 0.4 * (0.05 * k as f64 + 0.3 * c as f64).sin();
            // A NaN now and then: held, counted on its channel.
            if (k * 7 + c) % 211 == 0 { f64::NAN } else { y }
        })
        .collect()
}

/// A channel refused in any part is named by its index in the whole bank, as the unsplit
/// bank names it.
#[test]
fn a_refused_channel_is_named_by_its_index_in_the_whole_bank() {
    let limits = [OutputLimits::new(0.0, 1.0).unwrap()];
    let channels = 40;
    // A hysteresis model whose eq. (7) is not invertible on [0, 1] (a1 too negative).
    let base = model(&paper::TABLE1, 0);
    let refused = Mpim::new(base.thresholds(), base.weights(), -2.0, base.a2()).unwrap();
    for bad in [0, 7, 8, 23, 39] {
        let mut plants: Vec<_> = (0..channels).map(|c| model(&paper::TABLE1, c)).collect();
        plants[bad] = refused.clone();
        let whole =
            IhcBank::<f64, Heap>::new(&plants, &limits, SolveMode::Exact).expect_err("refused");
        assert_eq!(whole.channel(), Some(bad));
        for parts in 1..=5 {
            let split = ThreadedBank::new(channels, parts, |r: Range<usize>| {
                IhcBank::<f64, Heap>::new(&plants[r], &limits, SolveMode::Exact)
            })
            .expect_err("refused");
            assert_eq!(split.channel(), Some(bad), "channel {bad} in {parts} parts");
            assert_eq!(split.error(), whole.error());
        }
    }
}

/// Split into 1 to 5 parts, step by step and whole, every channel gives the unsplit
/// bank's bits, limits and diagnostics (IHC and DIHC; channel counts not a multiple of
/// the block size).
#[test]
fn a_threaded_bank_equals_the_whole_bank_bit_for_bit() {
    let limits = [OutputLimits::new(0.0, 1.0).unwrap()];
    for channels in [1, 7, 37, 100] {
        let plants: Vec<_> = (0..channels).map(|c| model(&paper::TABLE1, c)).collect();
        let inverses: Vec<_> = (0..channels).map(|c| model(&paper::TABLE2, c)).collect();
        let desired = signal(channels, 60);
        for parts in 1..=5 {
            let ihc =
                |r: Range<usize>| IhcBank::<f64, Heap>::new(&plants[r], &limits, SolveMode::Exact);
            let dihc =
                |r: Range<usize>| DihcBank::<f64, Heap>::new(&inverses[r], &[(0.0, 1.0)], &limits);
            let mut whole_banks: Vec<Box<dyn CompensatorBank<f64>>> = vec![
                Box::new(ihc(0..channels).unwrap()),
                Box::new(dihc(0..channels).unwrap()),
            ];
            let mut split_banks: Vec<Box<dyn CompensatorBank<f64>>> = vec![
                Box::new(ThreadedBank::new(channels, parts, ihc).unwrap()),
                Box::new(ThreadedBank::new(channels, parts, dihc).unwrap()),
            ];
            for (whole, split) in whole_banks.iter_mut().zip(split_banks.iter_mut()) {
                let mut expected = vec![0.0; desired.len()];
                whole.process(&desired, &mut expected).unwrap();
                let mut stepped = vec![0.0; desired.len()];
                for (d, c) in desired
                    .chunks_exact(channels)
                    .zip(stepped.chunks_exact_mut(channels))
                {
                    split.step(d, c).unwrap();
                }
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&stepped), bits(&expected), "{channels} in {parts}");
                for c in 0..=channels {
                    assert_eq!(split.limits(c), whole.limits(c));
                    assert_eq!(split.diagnostics(c), whole.diagnostics(c));
                }
                split.reset();
                let mut processed = vec![0.0; desired.len()];
                split.process(&desired, &mut processed).unwrap();
                assert_eq!(bits(&processed), bits(&expected), "{channels} in {parts}");
                // Arrays of the wrong length are refused.
                let short = channels - 1;
                assert!(
                    split
                        .step(&desired[..short], &mut processed[..short])
                        .is_err()
                );
                assert!(split.process(&desired, &mut processed[1..]).is_err());
            }
        }
    }
}
