//! Diagnosis (issue 11, item 3): why the learning study's raster trial 0 (the `full` IHC's own
//! drive, 2.58 %) is worse than the speed study's 100 Hz raster (0.887 %), the same motion.
//! `cargo run --release -p hystcomp-experiments --example learn_vs_speed`.
use hystcomp_experiments::learning_study::{RASTER_PERIODS_PER_TRIAL, raster_period};
use hystcomp_experiments::{StudyOptions, run_study};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_learn::{Learner, LearningOptions};
use hystcomp_stage::{Stage, StageConfig};

fn e_rms(desired: &[f64], measured: &[f64]) -> f64 {
    let n = desired.len();
    let last = &measured[measured.len() - n..];
    let (lo, hi) = desired
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    let s = desired
        .iter()
        .zip(last)
        .map(|(d, m)| (d - m).powi(2))
        .sum::<f64>()
        / n as f64;
    100.0 * s.sqrt() / (hi - lo)
}

fn main() {
    let study = run_study(
        &StudyOptions::default(),
        &mut hystcomp_experiments::study::Silent,
    )
    .unwrap();
    let plant = &study.full.plant.model;
    let stage = StageConfig::default();
    let fs = stage.sample_rate_hz;
    let period = raster_period(fs).unwrap();
    let n = period.len();
    let periods = RASTER_PERIODS_PER_TRIAL;
    let repeated: Vec<f64> = (0..periods).flat_map(|_| period.iter().copied()).collect();
    let play = |drive: &[f64]| {
        Stage::new(&stage, 1)
            .unwrap()
            .run(drive)
            .measured_position_um
    };
    // (a) The learning study's trial 0: the learner's one-period drive played 20 times.
    let mut lo = LearningOptions::new(fs);
    lo.mhe_bins = 10;
    let learner = Learner::new(plant, &period, lo).unwrap();
    let one: Vec<f64> = (0..periods)
        .flat_map(|_| learner.drive().iter().copied())
        .collect();
    println!(
        "(a) learner's period drive x{periods} from 0 V: {:.3} %",
        e_rms(&period, &play(&one))
    );
    let limits = learner.law().limits;
    println!(
        "    learner limits {limits:?}, study's (0, {})",
        stage.full_scale_command_v()
    );
    // (b) The compensator over the whole 20 periods as played (its creep and memory follow
    // the stage's from the same abrupt start).
    let whole = |limits: (f64, f64), settle: Option<f64>| {
        let mut c = ScaledCompensator::new(plant, Method::Ihc, Some(limits)).unwrap();
        if let Some(s) = settle {
            c.settle_creep(s);
        }
        let mut out = vec![0.0; repeated.len()];
        c.process(&repeated, &mut out).unwrap();
        out
    };
    let b = whole(limits, None);
    println!(
        "(b) compensator over the 20 periods as played: {:.3} %",
        e_rms(&period, &play(&b))
    );
    // (c) Its last period repeated 20 times (a periodic drive as the learner plays it).
    let c: Vec<f64> = (0..periods)
        .flat_map(|_| b[b.len() - n..].iter().copied())
        .collect();
    println!(
        "(c) (b)'s last period x{periods}: {:.3} %",
        e_rms(&period, &play(&c))
    );
    // (d) The learner's drive with the compensator's creep settled at the period's mean.
    let mean = period.iter().sum::<f64>() / n as f64;
    let three: Vec<f64> = (0..3).flat_map(|_| period.iter().copied()).collect();
    let mut comp = ScaledCompensator::new(plant, Method::Ihc, Some(limits)).unwrap();
    comp.settle_creep(mean);
    let mut out = vec![0.0; three.len()];
    comp.process(&three, &mut out).unwrap();
    let d: Vec<f64> = (0..periods)
        .flat_map(|_| out[n..2 * n].iter().copied())
        .collect();
    println!(
        "(d) learner-style drive, creep settled at the mean, x{periods}: {:.3} %",
        e_rms(&period, &play(&d))
    );
    // (e) The speed study's protocol (1 s ramp, 1 s rest) with 20 periods, last one measured.
    let (desired, _) = hystcomp_experiments::speed::from_rest(&repeated, fs);
    let mut comp = ScaledCompensator::new(
        plant,
        Method::Ihc,
        Some((0.0, stage.full_scale_command_v())),
    )
    .unwrap();
    let mut drive = vec![0.0; desired.len()];
    comp.process(&desired, &mut drive).unwrap();
    println!(
        "(e) speed-study protocol, 20 periods: {:.3} %",
        e_rms(&period, &play(&drive))
    );
    // (f) The learner's one-period drive after the speed study's lead-in: lead-in drive, then x20.
    let lead = drive.len() - repeated.len();
    let mut f = drive[..lead].to_vec();
    f.extend_from_slice(&one);
    println!(
        "(f) speed lead-in, then the learner's period drive x{periods}: {:.3} %",
        e_rms(&period, &play(&f))
    );
}
