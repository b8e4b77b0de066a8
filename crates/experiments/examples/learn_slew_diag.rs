//! Diagnosis of the learning study's 100 Hz raster on the built-in amplifier (issue 12 with
//! issue 11's threshold exponent): why the learning crawls where the learned drive asks more
//! slew than the amplifier has. Not part of the study.
//!
//! `cargo run --release -p hystcomp-experiments --example learn_slew_diag -- pow=1.5 aw=1`
//!
//! Keys: `pow=p` the `full` pipeline's threshold exponent (its plant model is identified by
//! the study once and cached in `/tmp/learn-slew-full-p<p>.json`); `aw=1` the learner's state
//! is the reference of the drive the amplifier delivers (`AntiWindupLaw::Delivered`, the
//! back-calculation anti-windup); `margin=m` also every drive the slew-feasible one nearest `C[r]` at the
//! amplifier's output, steps within `m S T` (`AntiWindupLaw::Projected`); `freeze=1`
//! conditional integration instead (`AntiWindupLaw::Conditional`); `lead=m`, `gain=g`
//! the law's phase lead and gain (defaults 0 and 0.8); `trials=N` (21); `strong=1` the stage with ten times the slew rate; `phase=1`
//! the error by tenth of the period for trials 0, 1, 5, 10 and 20.
//!
//! Per trial: e_rms (% of the 20 um scan); the share of the measured period's samples in which
//! the stage's amplifier slewed for the whole sample; the share of the error's mean square on
//! those samples and the 5 after each; how much of the drive the amplifier did not deliver
//! (RMS of `v - A^-1[A[v]]`, command mV, from the stage's own amplifier monitor); the learned
//! reference's departure from the desired raster (RMS and largest, um) and its part the
//! amplifier did not deliver (RMS of `r - P[A^-1[A[v]]]`, um): the windup.

use hystcomp_experiments::full::FullOptions;
use hystcomp_experiments::learning_study::{
    RASTER_MHE_BINS, RASTER_PERIODS_PER_TRIAL, raster_period,
};
use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::amplifier::input_for_step;
use hystcomp_learn::{AmplifierSpec, AntiWindup, AntiWindupLaw, Learner, LearningOptions};
use hystcomp_stage::{Stage, StageConfig};

fn rms(a: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = a.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    (s / n.max(1) as f64).sqrt()
}

fn main() {
    let mut pow = 1.0;
    let mut aw = false;
    let mut trials = 21;
    let mut strong = false;
    let mut phase = false;
    let mut margin: Option<f64> = None;
    let mut freeze = false;
    let mut lead = 0usize;
    let mut gain_l: Option<f64> = None;
    for a in std::env::args().skip(1) {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "pow" => pow = v.parse().unwrap(),
            "aw" => aw = v == "1",
            "trials" => trials = v.parse().unwrap(),
            "strong" => strong = v == "1",
            "phase" => phase = v == "1",
            "freeze" => freeze = v == "1",
            "lead" => lead = v.parse().unwrap(),
            "gain" => gain_l = Some(v.parse().unwrap()),
            "margin" => margin = Some(v.parse().unwrap()),
            _ => panic!("unknown key {k}"),
        }
    }
    let mut stage = StageConfig::default();
    if strong {
        stage.amplifier.peak_current_ma = hystcomp_experiments::speed::STRONG_PEAK_CURRENT_MA;
    }
    let cache = format!(
        "/tmp/learn-slew-full-p{pow}{}.json",
        if strong { "-strong" } else { "" }
    );
    let model = match ModelFile::load(std::path::Path::new(&cache)) {
        Ok(m) => m,
        Err(_) => {
            let options = hystcomp_experiments::StudyOptions {
                stage: stage.clone(),
                full: FullOptions {
                    threshold_exponent: pow,
                    ..FullOptions::default()
                },
                ..Default::default()
            };
            let study =
                hystcomp_experiments::run_study(&options, &mut hystcomp_experiments::study::Silent)
                    .unwrap();
            let m = study.full.plant.model.clone();
            m.save(std::path::Path::new(&cache)).unwrap();
            m
        }
    };
    let fs = stage.sample_rate_hz;
    let gain = stage.amplifier.gain;
    let spec = AmplifierSpec {
        bandwidth_hz: stage.amplifier.bandwidth_hz,
        slew_rate_per_s: stage.amplifier.slew_rate_v_per_s() / gain,
    };
    let full_step = stage.amplifier.slew_rate_v_per_s() / fs;
    let desired = raster_period(fs).unwrap();
    let n = desired.len();
    let range = desired.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - desired.iter().copied().fold(f64::INFINITY, f64::min);
    let mut options = LearningOptions::new(fs);
    options.mhe_bins = RASTER_MHE_BINS;
    options.lead_samples = lead;
    if let Some(g) = gain_l {
        options.gain = g;
    }
    let law = match (aw, margin, freeze) {
        (_, Some(margin), _) => Some(AntiWindupLaw::Projected { margin }),
        (_, None, true) => Some(AntiWindupLaw::Conditional),
        (true, None, false) => Some(AntiWindupLaw::Delivered),
        _ => None,
    };
    options.anti_windup = law.map(|law| AntiWindup {
        amplifier: spec,
        law,
    });
    let plain = {
        let mut o = options.clone();
        o.anti_windup = None;
        o
    };
    let mut learner = Learner::new(&model, &desired, options).unwrap();
    println!(
        "pow {pow} aw {aw} margin {margin:?} freeze {freeze} strong {strong}: trial e_rms% slewing% slew-zone-ms% undelivered-mV \
         |r-yd|rms/max-um windup-um model-vs-monitor-mV"
    );
    let seed = 2; // the study's tracking seed (seed 1 + 1)
    for trial in 0..trials {
        let reference = learner.reference().to_vec();
        let drive_period = learner.drive().to_vec();
        let drive: Vec<f64> = (0..RASTER_PERIODS_PER_TRIAL)
            .flat_map(|_| drive_period.iter().copied())
            .collect();
        let response = Stage::new(&stage, seed + trial as u64).unwrap().run(&drive);
        let start = drive.len() - n;
        let amp = &response.amplifier_v;
        let measured = &response.measured_position_um[start..];
        let error: Vec<f64> = desired.iter().zip(measured).map(|(d, y)| d - y).collect();
        // Slewing samples of the measured period, from the monitor.
        let slewing: Vec<bool> = (start..drive.len())
            .map(|k| (amp[k] - amp[k - 1]).abs() >= full_step * (1.0 - 1e-9))
            .collect();
        let mut zone = vec![false; n];
        for k in 0..n {
            if slewing[k] {
                for j in 0..=5 {
                    zone[(k + j) % n] = true;
                }
            }
        }
        let ms_total: f64 = error.iter().map(|e| e * e).sum();
        let ms_zone: f64 = (0..n).filter(|&k| zone[k]).map(|k| error[k].powi(2)).sum();
        // The drive the amplifier delivered, from its monitor: A^-1[amp / gain], the least
        // input that gives each sample's output step.
        let delivered: Vec<f64> = (start..drive.len())
            .map(|k| input_for_step(&spec, 1.0 / fs, amp[k - 1] / gain, amp[k] / gain))
            .collect();
        let undelivered = rms(drive_period.iter().zip(&delivered).map(|(v, d)| v - d));
        // The learner's own model of it (the nominal specification).
        let modelled = hystcomp_learn::amplifier::delivered_drive(&spec, fs, &drive_period, true);
        let model_gap = rms(modelled.iter().zip(&delivered).map(|(a, b)| a - b));
        let (lo, hi) = learner.law().limits;
        let clamped: Vec<f64> = delivered.iter().map(|v| v.clamp(lo, hi)).collect();
        let delivered_reference = Learner::resume(&model, &desired, &clamped, plain.clone())
            .unwrap()
            .reference()
            .to_vec();
        let windup = rms(reference
            .iter()
            .zip(&delivered_reference)
            .map(|(a, b)| a - b));
        let departure = rms(reference.iter().zip(&desired).map(|(a, b)| a - b));
        let departure_max = reference
            .iter()
            .zip(&desired)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let update = learner.update(measured).unwrap();
        println!(
            "{trial:>3} {:.4} {:5.1} {:5.1} {:7.2} {:.3}/{:.3} {:.4} {:.3}",
            update.indices.e_rms_percent,
            100.0 * slewing.iter().filter(|s| **s).count() as f64 / n as f64,
            100.0 * ms_zone / ms_total,
            1e3 * undelivered,
            departure,
            departure_max,
            windup,
            1e3 * model_gap,
        );
        if phase && [0, 1, 5, 10, 20].contains(&trial) {
            let tenths: Vec<String> = (0..10)
                .map(|b| {
                    let part = &error[b * n / 10..(b + 1) * n / 10];
                    let s: String = part
                        .iter()
                        .enumerate()
                        .map(|(i, _)| if slewing[b * n / 10 + i] { '*' } else { '.' })
                        .collect();
                    format!("{:.3}{s}", 100.0 * rms(part.iter().copied()) / range)
                })
                .collect();
            println!("     by tenth (% of scan; * slewing): {}", tenths.join(" "));
        }
        if learner.is_stopped() {
            println!("stopped by the divergence guard");
            break;
        }
    }
}
