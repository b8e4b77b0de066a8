//! What limits issue 11's missed figures, pinned: the `full` pipeline (creep on the holds,
//! vibration from the small multisine) on a diagnostic copy of the built-in stage whose
//! hysteresis is an MPIM (identified from the creep-, dynamics- and noise-free copy's own
//! record) and whose creep, dynamics, amplifier and sensor are the built-in stage's. There the
//! figures the built-in (Preisach) stage misses are met with room: what the pipeline leaves on
//! the built-in stage is the MPIM's mismatch with the stage's hysteresis, not its creep or
//! vibration links. Diagnosis only: the study's stage is unchanged, and the identification
//! reads only (voltage, displacement) samples.

use hystcomp_experiments::chain_excitation::ChainExcitation;
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_experiments::full::FullOptions;
use hystcomp_experiments::signals::{PaperTrajectory, Raster, Shape, Signal, Steps};
use hystcomp_experiments::speed::from_rest;
use hystcomp_identify::{
    ChainOptions, DynamicsOptions, IdentifyOptions, Thresholds, Warmup, identify, identify_chain,
};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_stage::{HysteresisModel, Stage, StageConfig};

fn measured(stage: &StageConfig, seed: u64, command: &[f64]) -> Vec<f64> {
    Stage::new(stage, seed)
        .unwrap()
        .run(command)
        .measured_position_um
}

fn rms_percent(measured: &[f64], desired: &[f64]) -> f64 {
    let (lo, hi) = desired
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let sum: f64 = measured
        .iter()
        .zip(desired)
        .map(|(m, d)| (m - d).powi(2))
        .sum();
    100.0 * (sum / desired.len() as f64).sqrt() / (hi - lo)
}

#[test]
fn on_a_stage_whose_hysteresis_is_an_mpim_the_full_pipeline_meets_what_the_preisach_stage_misses() {
    let built_in = StageConfig::default();
    let fs = built_in.sample_rate_hz;
    let full_scale = built_in.full_scale_command_v();
    let hysteresis = IdentificationExcitation {
        full_scale_v: full_scale,
        ..IdentificationExcitation::default()
    };
    let mut command = hysteresis.command_v(fs);
    let start = command.len();
    let (chain_part, segments) = ChainExcitation::default()
        .command_v(full_scale, fs, *command.last().unwrap())
        .unwrap();
    command.extend(chain_part);
    let vibration = segments.vibration.start + start..segments.vibration.end + start;
    let base = IdentifyOptions {
        thresholds: Thresholds::Uniform(10),
        warmup: Warmup::Samples(0),
        max_fit_rms_percent: None,
        ..IdentifyOptions::default()
    };

    // The stage's hysteresis as an MPIM: identified on the creep-, dynamics- and noise-free
    // copy's response to the hysteresis excitation.
    let mut clean = built_in.clone();
    clean.creep.percent_per_decade = 0.0;
    clean.sensor.noise_rms_nm = 0.0;
    clean.amplifier.bandwidth_hz = 1e9;
    clean.amplifier.peak_current_ma = 1e9;
    clean.mechanics.rigid = true;
    let y = measured(&clean, 1, &command[..start]);
    let every = |x: &[f64]| -> Vec<f64> { x.iter().step_by(10).copied().collect() };
    let mpim = identify(&every(&command[..start]), &every(&y), &base).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("stage-mpim.json");
    mpim.model.save(&file).unwrap();
    let mut stage = built_in.clone();
    stage.hysteresis.model = HysteresisModel::Mpim;
    stage.hysteresis.mpim.model_file = Some(file);

    // The full pipeline's plant chain from that stage's record, with the study's creep options
    // (the weights on the holds; the bank to 100 s, the first of the study's candidates).
    let options = FullOptions::default();
    let record = measured(&stage, 1, &command);
    let chain = ChainOptions {
        sample_rate_hz: fs,
        decimation: 10,
        creep: Some(options.creep.clone()),
        dynamics: Some(DynamicsOptions {
            segment: Some(vibration),
            ..options.dynamics.clone()
        }),
        output_error_iterations: options.output_error_iterations,
    };
    let plant = identify_chain(&command, &record, &base, &chain).unwrap();
    let drive = |desired: &[f64]| -> Vec<f64> {
        let mut c =
            ScaledCompensator::new(&plant.model, Method::Ihc, Some((0.0, full_scale))).unwrap();
        let mut out = vec![0.0; desired.len()];
        c.process(desired, &mut out).unwrap();
        out
    };

    // 20 s of the paper's trajectory, the second period: <= 0.25 % (measured 0.058 %; built-in
    // stage: 0.292 %).
    let desired = Signal::paper(1.0, 20.0, fs).sample().unwrap();
    let y = measured(&stage, 2, &drive(&desired));
    let half = desired.len() / 2;
    let twenty = rms_percent(&y[half..], &desired[half..]);
    assert!(twenty <= 0.12, "20 s: {twenty} (measured 0.059 %)");

    // The 60 s hold: <= 0.1 um (measured 0.034 um).
    let step = Signal {
        shape: Shape::Steps(Steps::step(-1.0, 1.0, 1.0, 0.1)),
        amplitude: 25.0,
        offset: 25.0,
        duration_s: 63.1,
        speed: 1.0,
        sample_rate_hz: fs,
    }
    .sample()
    .unwrap();
    let y = measured(&stage, 2, &drive(&step));
    let window = (0.1 * fs) as usize;
    let average = |k: usize| y[k..k + window].iter().sum::<f64>() / window as f64;
    let reference = (2.1 * fs) as usize;
    let drift = (reference..=y.len() - window)
        .step_by(window)
        .map(|k| (average(k) - average(reference)).abs())
        .fold(0.0, f64::max);
    assert!(drift <= 0.1, "hold drift {drift} um (measured 0.034 um)");

    // The 20 um raster at 100 Hz with ten times the built-in slew rate: <= 0.5 % (built-in
    // stage: 0.795 %, where the MPIM's error at each reversal rings the 800 Hz resonance).
    let raster = Signal {
        shape: Shape::Raster(Raster::triangle(100.0, 0.05)),
        amplitude: 10.0,
        offset: PaperTrajectory::new().mid_range_um(),
        duration_s: 0.1,
        speed: 1.0,
        sample_rate_hz: fs,
    }
    .sample()
    .unwrap();
    let desired = from_rest(&raster, fs).0;
    let mut strong = stage.clone();
    strong.amplifier.peak_current_ma = 1000.0;
    let y = measured(&strong, 2, &drive(&desired));
    let from = desired.len() - 500;
    let fast = rms_percent(&y[from..], &desired[from..]);
    assert!(
        fast <= 0.25,
        "raster at 100 Hz, 10x slew: {fast} % (measured 0.143 %)"
    );
}
