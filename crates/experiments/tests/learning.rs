//! Learning from repetition on the built-in stage (issue 12's acceptance): the exact
//! pipeline's plant model (least squares on the study's identification record), its IHC as
//! trial 0, trials from rest with a fresh noise seed each.

use hystcomp_experiments::learning::{SimulatedTrial, exact_plant_model, run_trials};
use hystcomp_experiments::signals::{Raster, Shape, Signal};
use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::{Learner, LearningOptions, Status};
use hystcomp_stage::StageConfig;

/// The study's `exact` plant model on `stage`.
fn exact_plant(stage: &StageConfig) -> ModelFile {
    exact_plant_model(stage, 1, 10).unwrap()
}

fn learn(
    stage: &StageConfig,
    model: &ModelFile,
    desired: &[f64],
    options: LearningOptions,
    trials: usize,
    periods: usize,
) -> Vec<SimulatedTrial> {
    let mut learner = Learner::new(model, desired, options).unwrap();
    run_trials(stage, 2, &mut learner, trials, periods, &mut |_| {}).unwrap()
}

fn e_rms(trials: &[SimulatedTrial]) -> Vec<f64> {
    trials
        .iter()
        .map(|t| t.update.indices.e_rms_percent)
        .collect()
}

/// Paper trajectory, one 10 s period played twice from rest, the second measured (the
/// study's protocol): e_rms <= 0.03 % and e_mhe <= 0.3 % within 10 trials. e_mhe over 1000
/// bins: with the default 100 a perfect tracker reads 1 % (the bin's own width).
#[test]
fn paper_trajectory_reaches_the_noise_floor_within_ten_trials() {
    let stage = StageConfig::default();
    let model = exact_plant(&stage);
    let desired = Signal::paper(1.0, 10.0, stage.sample_rate_hz)
        .sample()
        .unwrap();
    let mut options = LearningOptions::new(stage.sample_rate_hz);
    options.mhe_bins = 1000;
    let trials = learn(&stage, &model, &desired, options, 11, 2);
    let e = e_rms(&trials);
    assert!(
        (0.25..0.45).contains(&e[0]),
        "trial 0 is the exact IHC: {e:?}"
    );
    let met = trials.iter().position(|t| {
        t.update.indices.e_rms_percent <= 0.03 && t.update.indices.e_mhe_percent <= 0.3
    });
    let met = met.unwrap_or_else(|| panic!("not met: {e:?}"));
    assert!(met <= 10, "met at trial {met}: {e:?}");
    // Once met, it stays at the noise floor.
    let last = trials.last().unwrap();
    assert!(
        last.update.indices.e_rms_percent < 1.5 * last.noise_floor_percent,
        "{e:?}"
    );
}

/// The model deliberately wrong (its weights scaled by 0.7 and 1.3): the loop still
/// converges, to the noise floor, within the same 10 trials as the right model. (On the
/// trajectory time-compressed ten times, the 0.7 model's error still creeps down from 0.03 %
/// after 11 trials: its hysteresis harmonics then reach the 100 Hz cut-off of Q.)
#[test]
fn converges_with_the_weights_scaled_by_0_7_and_1_3() {
    let stage = StageConfig::default();
    let exact = exact_plant(&stage);
    let desired = Signal::paper(1.0, 10.0, stage.sample_rate_hz)
        .sample()
        .unwrap();
    for k in [0.7, 1.3] {
        let mut model = exact.clone();
        model.weights.iter_mut().for_each(|w| *w *= k);
        let options = LearningOptions::new(stage.sample_rate_hz);
        let trials = learn(&stage, &model, &desired, options, 11, 2);
        let e = e_rms(&trials);
        assert!(e[0] > 2.0, "a wrong model tracks badly at first: {e:?}");
        let floor = trials.last().unwrap().noise_floor_percent;
        assert!(
            e[10] <= 0.03 && e[10] < 2.0 * floor,
            "k = {k}: {e:?}, floor {floor}"
        );
    }
}

/// A gain set too high: the guard stops at the first trial that grew by more than 1.5 times,
/// says so, and keeps the last good drive.
#[test]
fn divergence_guard_stops_a_gain_too_high_on_the_stage() {
    let stage = StageConfig::default();
    let model = exact_plant(&stage);
    let desired = Signal::paper(10.0, 1.0, stage.sample_rate_hz)
        .sample()
        .unwrap();
    let mut options = LearningOptions::new(stage.sample_rate_hz);
    options.gain = 3.0;
    let mut learner = Learner::new(&model, &desired, options).unwrap();
    let first = learner.drive().to_vec();
    let trials = run_trials(&stage, 2, &mut learner, 10, 2, &mut |_| {}).unwrap();
    let last = trials.last().unwrap();
    let Status::Diverged {
        best_trial,
        e_rms_percent,
        best_e_rms_percent,
        ..
    } = last.update.status
    else {
        panic!("not stopped: {:?}", e_rms(&trials));
    };
    assert_eq!((trials.len(), best_trial), (2, 0));
    assert!(e_rms_percent > 1.5 * best_e_rms_percent);
    assert_eq!(learner.drive(), first.as_slice());
}

/// Sensor noise five times the default: the converged error stays within 3 times the noise
/// floor and does not grow over 50 further trials (the mean of the last ten within 5 % of the
/// mean of trials 10-19).
#[test]
fn noise_five_times_the_default_is_not_amplified_over_fifty_trials() {
    let mut stage = StageConfig::default();
    let model = exact_plant(&stage);
    stage.sensor.noise_rms_nm *= 5.0;
    let desired = Signal::paper(10.0, 1.0, stage.sample_rate_hz)
        .sample()
        .unwrap();
    let options = LearningOptions::new(stage.sample_rate_hz);
    let trials = learn(&stage, &model, &desired, options, 60, 2);
    let e = e_rms(&trials);
    for t in &trials[10..] {
        assert!(
            t.update.indices.e_rms_percent <= 3.0 * t.noise_floor_percent,
            "trial {}: {} vs floor {}",
            t.update.trial,
            t.update.indices.e_rms_percent,
            t.noise_floor_percent
        );
    }
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    assert!(mean(&e[50..]) <= 1.05 * mean(&e[10..20]), "{e:?}");
}

/// The 20 um triangle raster at 100 Hz (corners rounded over 5 % of the period), 20 periods
/// per trial from rest, the last measured. Without a vibration link the learning stays below
/// the 800 Hz resonance (Q's default cut-off, 100 Hz), so the triangle's harmonics are not
/// learned: the 0.1 % is not reached from this model (measured, README and report;
/// from the full pipeline's model it is, see the study's test).
/// Asserted: it learns what it can (e_rms below half of trial 0's) and stays stable.
#[test]
fn raster_at_100_hz_improves_and_stays_stable() {
    let stage = StageConfig::default();
    let model = exact_plant(&stage);
    let desired = Signal {
        shape: Shape::Raster(Raster::triangle(100.0, 0.05)),
        amplitude: 10.0,
        offset: 20.0,
        duration_s: 0.01,
        speed: 1.0,
        sample_rate_hz: stage.sample_rate_hz,
    }
    .sample()
    .unwrap();
    let mut options = LearningOptions::new(stage.sample_rate_hz);
    options.mhe_bins = 10;
    let trials = learn(&stage, &model, &desired, options, 20, 20);
    let e = e_rms(&trials);
    assert_eq!(trials.len(), 20, "{e:?}");
    assert!(e[19] < 0.5 * e[0], "{e:?}");
    eprintln!("raster e_rms by trial: {e:?}");
}
