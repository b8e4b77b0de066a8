//! The creep link's weights from a record's holds (`hystcomp_identify::creep_holds`): on
//! records from known chains (Table 1's MPIM and a creep link with random weights) the weights
//! come back, the chain fitted that way predicts its record, the smoothness is chosen among
//! the candidates by leaving each hold out, and a record without holds is refused with the
//! reason.

use hystcomp_core::{ChainModel, Creep, paper};
use hystcomp_identify::chain::MIN_HOLD_S;
use hystcomp_identify::creep_holds::{creep_weights_from_holds, held_segments};
use hystcomp_identify::{ChainOptions, CreepOptions, IdentifyOptions, identify_chain};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const RATE: f64 = 1_000.0;

fn raised_cosine(v: &mut Vec<f64>, to: f64, samples: usize) {
    let from = v.last().copied().unwrap_or(0.0);
    for k in 1..=samples {
        let s = k as f64 / samples as f64;
        v.push(from + (to - from) * 0.5 * (1.0 - (std::f64::consts::PI * s).cos()));
    }
}

/// From rest: reversals over 0..10 V, then steps held 5 s, 20 s and 10 s.
fn excitation() -> Vec<f64> {
    let mut v = Vec::new();
    for turn in [10.0, 0.0, 10.0, 2.0, 8.0, 4.0, 6.0, 0.5, 9.0, 0.0] {
        raised_cosine(&mut v, turn, 1_000);
    }
    for (level, hold_s) in [(1.0, 5.0), (7.0, 20.0), (3.0, 10.0)] {
        raised_cosine(&mut v, level, 200);
        let last = *v.last().unwrap();
        v.extend(std::iter::repeat_n(last, (hold_s * RATE) as usize));
    }
    v
}

fn taus() -> Vec<f64> {
    CreepOptions::log_spaced(0.01, 10.0, 2).time_constants_s
}

fn record(weights: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let volts = excitation();
    let mut chain: ChainModel<f64, Vec<f64>, Vec<f64>> = ChainModel {
        hysteresis: paper::TABLE1.model().unwrap(),
        creep: Some(Creep::new(&taus(), weights, 0.0, 1.0 / RATE).unwrap()),
        vibration: None,
    };
    let um = volts.iter().map(|v| 75.0 * chain.step(v / 10.0)).collect();
    (volts, um)
}

fn random_weights(seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..taus().len())
        .map(|_| 0.002 + 0.015 * rng.random::<f64>())
        .collect()
}

#[test]
fn held_segments_find_the_three_holds() {
    let v = excitation();
    let holds = held_segments(&v, (MIN_HOLD_S * RATE) as usize);
    let lengths: Vec<usize> = holds.iter().map(|h| h.len()).collect();
    // Each hold starts at the last sample of its move (equal to the held level).
    assert_eq!(lengths, vec![5_001, 20_001, 10_001]);
}

#[test]
fn the_weights_of_a_known_creep_link_come_back_from_its_holds() {
    for seed in 0..8 {
        let truth = random_weights(seed);
        let (volts, um) = record(&truth);
        let holds = held_segments(&volts, (MIN_HOLD_S * RATE) as usize);
        let fit =
            creep_weights_from_holds(&um, 1.0 / RATE, 1, &holds, &taus(), 0.0, &[], 75.0).unwrap();
        assert_eq!(fit.smoothness, 0.0);
        assert!(fit.candidates.is_empty());
        for (i, (got, want)) in fit.weights.iter().zip(&truth).enumerate() {
            assert!(
                (got - want).abs() < 1e-3 * want.max(0.001) + 1e-6,
                "seed {seed}, element {i}: {got} vs {want} ({:?} vs {truth:?})",
                fit.weights
            );
        }
    }
}

#[test]
fn a_chain_fitted_on_holds_predicts_its_record_and_chooses_its_smoothness() {
    let truth = random_weights(42);
    let (volts, um) = record(&truth);
    let candidates = [0.0, 0.1, 10.0];
    let chain = ChainOptions {
        sample_rate_hz: RATE,
        decimation: 1,
        creep: Some(CreepOptions::log_spaced(0.01, 10.0, 2).on_holds(&candidates)),
        dynamics: None,
        output_error_iterations: 0,
    };
    let fit = identify_chain(&volts, &um, &IdentifyOptions::default(), &chain).unwrap();
    let creep = fit.report.creep.as_ref().unwrap();
    // Every candidate scored; the exact structure is predicted best with the least penalty
    // (a smooth spectrum is not the truth here), and held out it is near exact.
    assert_eq!(creep.smoothness_candidates.len(), 3);
    assert_eq!(creep.smoothness, 0.0, "{:?}", creep.smoothness_candidates);
    assert!(
        creep.smoothness_candidates[0].1 < 0.01,
        "{:?}",
        creep.smoothness_candidates
    );
    assert!(
        creep.smoothness_candidates[2].1 > creep.smoothness_candidates[0].1,
        "{:?}",
        creep.smoothness_candidates
    );
    let sum: f64 = truth.iter().sum();
    assert!(
        (creep.static_gain - 1.0 / (1.0 - sum)).abs() < 0.002,
        "{} vs {}",
        creep.static_gain,
        1.0 / (1.0 - sum)
    );
    // The hysteresis fitted on the creep-free displacement: the chain predicts the record.
    let rms: Vec<f64> = fit
        .report
        .contributions
        .iter()
        .map(|c| c.rms_percent)
        .collect();
    assert!(rms[1] < 0.05 && rms[1] < 0.1 * rms[0], "{rms:?}");
    assert!(fit.report.hysteresis.detail.contains("on 3 holds"));
}

#[test]
fn a_record_without_holds_is_refused_with_the_reason() {
    let volts: Vec<f64> = (0..20_000)
        .map(|k| 5.0 + 4.0 * (k as f64 / RATE).sin())
        .collect();
    let um: Vec<f64> = volts.iter().map(|v| 7.5 * v + 0.1 * v * v).collect();
    let chain = ChainOptions {
        sample_rate_hz: RATE,
        decimation: 1,
        creep: Some(CreepOptions::log_spaced(0.01, 10.0, 2).on_holds(&[])),
        dynamics: None,
        output_error_iterations: 0,
    };
    let error = identify_chain(&volts, &um, &IdentifyOptions::default(), &chain).unwrap_err();
    assert!(
        error.to_string().contains("holds its voltage nowhere"),
        "{error}"
    );
    // Choosing the smoothness needs two holds.
    let (volts, um) = record(&random_weights(1));
    let holds = held_segments(&volts, (MIN_HOLD_S * RATE) as usize);
    let error =
        creep_weights_from_holds(&um, 1.0 / RATE, 1, &holds[..1], &taus(), 0.0, &[1.0], 75.0)
            .unwrap_err();
    assert!(error.to_string().contains("two holds"), "{error}");
}

/// A staircase of more holds than the fit takes is refused before any row is built, naming
/// the count and the way out; as many as it takes are fitted.
#[test]
fn more_holds_than_the_fit_takes_are_refused_with_the_count() {
    use hystcomp_identify::creep_holds::MAX_HOLDS;
    let rate = 1000.0;
    let (step, hold) = (5, 100);
    let mut volts = Vec::new();
    for k in 0..=MAX_HOLDS {
        let level = k as f64 / MAX_HOLDS as f64;
        for s in 0..step {
            volts.push(level - (1.0 - s as f64 / step as f64) / MAX_HOLDS as f64);
        }
        volts.extend(std::iter::repeat_n(level, hold));
    }
    let um: Vec<f64> = volts.iter().map(|v| 75.0 * v).collect();
    let holds = held_segments(&volts, hold / 2);
    assert_eq!(holds.len(), MAX_HOLDS + 1);
    let error = creep_weights_from_holds(&um, 1.0 / rate, 1, &holds, &taus(), 0.0, &[], 75.0)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains(&format!("{} holds", MAX_HOLDS + 1))
            && error.contains(&format!("at most {MAX_HOLDS}"))
            && error.contains("fit creep jointly"),
        "{error}"
    );
    creep_weights_from_holds(
        &um,
        1.0 / rate,
        1,
        &holds[..MAX_HOLDS],
        &taus(),
        0.0,
        &[],
        75.0,
    )
    .unwrap();
}
