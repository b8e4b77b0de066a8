//! Diagnosis of the 20 um raster's minor-loop error (issue 11) at 10 Hz, where the resonance
//! plays no part. The `full` pipeline's plant chain is identified from the study's record (as
//! the study does, seed 1, creep bank to 1000 s: `LAST` changes it) for each operator count
//! (`OPS=10,15,20`), output-map degree (`MAP=1,3`) and threshold exponent (`POW=1,1.5`:
//! thresholds `((i-1)/n)^p`), then for each model:
//!
//! - `fit`: the chain's fit RMS on its record (% of the record's range);
//! - `held-out`: its prediction of a second record measured on the stage (seed 2; voltage and
//!   displacement samples only): 10 s logarithmic chirps 1-30 Hz about mid-range at `HELD`
//!   (fraction of the full scale, 0.1 by default), minor loops smaller than any the
//!   identification record repeats, with its split (mean / gain / loop shape);
//! - the 10 Hz raster tracked by the hysteresis+creep inverse (vibration link left out) on a
//!   rigid, quiet copy of the stage with an ideal amplifier (`rigid`): the static minor-loop
//!   error, split into its mean, its gain part (proportional to the scan) and the rest (the
//!   loop's shape); `pred`: the model's prediction error of that copy's response to the same
//!   drive (equal to `rigid` when the whole static error is the model's);
//! - the full model's 10 Hz raster on the real stage and its 100 Hz raster with ten times the
//!   amplifier's slew rate (the speed study's faithful drive), and the 20 s paper trajectory
//!   (second half; `rigid` and real).
//!
//! `EXC=minor` inserts logarithmic chirps 1-30 Hz about mid-range (`MINOR=0.05,0.15`:
//! amplitudes, fraction of the full scale, 5 s each) between the hysteresis and the chain
//! excitation: minor loops in the identification record. `PRE=s` holds the raster's first
//! value `s` s before it (the study: 1 s). `SEGGAIN=1` fits the vibration link with the
//! segment gain. Diagnostic copies of the stage are for diagnosis only: identification never
//! sees them. Not part of the study;
//! `cargo run --release -p hystcomp-experiments --example minor_loop_diag`.

use hystcomp_experiments::chain_excitation::ChainExcitation;
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_experiments::full::FullOptions;
use hystcomp_experiments::signals::{Chirp, PaperTrajectory, Raster, Shape, Signal, Sweep};
use hystcomp_experiments::speed::from_rest;
use hystcomp_identify::{
    ChainOptions, DynamicsOptions, IdentifyOptions, Thresholds, Warmup, identify_chain,
};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::ModelFile;
use hystcomp_stage::{Stage, StageConfig};

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}
fn range(a: &[f64]) -> f64 {
    a.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - a.iter().copied().fold(f64::INFINITY, f64::min)
}
fn run(stage: &StageConfig, seed: u64, command: &[f64]) -> Vec<f64> {
    Stage::new(stage, seed)
        .unwrap()
        .run(command)
        .measured_position_um
}
fn command(model: &ModelFile, desired: &[f64], fs_v: f64) -> Vec<f64> {
    let mut c = ScaledCompensator::new(model, Method::Ihc, Some((0.0, fs_v))).unwrap();
    let mut out = vec![0.0; desired.len()];
    c.process(desired, &mut out).unwrap();
    out
}
fn raster(rate: f64, fs: f64) -> (Vec<f64>, usize) {
    let signal = Signal {
        shape: Shape::Raster(Raster::triangle(rate, 0.05)),
        amplitude: 10.0,
        offset: PaperTrajectory::new().mid_range_um(),
        duration_s: 10.0 / rate,
        speed: 1.0,
        sample_rate_hz: fs,
    };
    let mut d = from_rest(&signal.sample().unwrap(), fs).0;
    // PRE: seconds held at the first value before the raster (the study: 1).
    let pre: f64 = std::env::var("PRE").map_or(1.0, |s| s.parse().unwrap());
    if pre > 1.0 {
        let at = fs as usize;
        let first = d[at];
        let extra = ((pre - 1.0) * fs).round() as usize;
        d.splice(at..at, std::iter::repeat_n(first, extra));
    }
    let from = d.len() - (5.0 / rate * fs).round() as usize;
    (d, from)
}
/// The error `y - d` on `d`'s window split into a mean, a gain part (proportional to `d`
/// about its mean) and the rest (the loop's shape), each RMS in % of `span`.
fn split(y: &[f64], d: &[f64], span: f64) -> (f64, f64, f64) {
    let n = d.len() as f64;
    let md = d.iter().sum::<f64>() / n;
    let e: Vec<f64> = y.iter().zip(d).map(|(a, b)| a - b).collect();
    let me = e.iter().sum::<f64>() / n;
    let sdd: f64 = d.iter().map(|x| (x - md).powi(2)).sum();
    let sde: f64 = d.iter().zip(&e).map(|(x, e)| (x - md) * (e - me)).sum();
    let g = sde / sdd;
    let rest: Vec<f64> = d
        .iter()
        .zip(&e)
        .map(|(x, e)| e - me - g * (x - md))
        .collect();
    let gain_rms = g * (sdd / n).sqrt();
    let rest_rms = (rest.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
    (
        100.0 * me / span,
        100.0 * gain_rms / span,
        100.0 * rest_rms / span,
    )
}
fn list(name: &str, default: &str) -> Vec<f64> {
    std::env::var(name)
        .unwrap_or_else(|_| default.to_owned())
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect()
}

/// Minor loops about mid-range: for each amplitude, a logarithmic chirp 1 -> 30 Hz over
/// `seconds`, reached and left by raised cosines (what `EXC=minor` appends).
fn minor_loops(fs_v: f64, fs: f64, from: f64, amplitudes: &[f64], seconds: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut last = from;
    let lead = fs as usize;
    for &a in amplitudes {
        let to = 0.5 * fs_v;
        out.extend((1..=lead).map(|k| {
            let s = k as f64 / lead as f64;
            last + (to - last) * 0.5 * (1.0 - (std::f64::consts::PI * s).cos())
        }));
        let sweep = Signal {
            shape: Shape::Chirp(Chirp {
                start_hz: 1.0,
                end_hz: 30.0,
                sweep: Sweep::Logarithmic,
            }),
            amplitude: a * fs_v,
            offset: 0.5 * fs_v,
            duration_s: seconds,
            speed: 1.0,
            sample_rate_hz: fs,
        }
        .sample()
        .unwrap();
        last = *sweep.last().unwrap();
        out.extend(sweep);
    }
    out
}

fn main() {
    let stage = StageConfig::default();
    let fs = stage.sample_rate_hz;
    let fs_v = stage.full_scale_command_v();
    let mut options = FullOptions::default();
    // The bank the study chooses (to 1000 s; `LAST` changes it).
    let last: f64 = std::env::var("LAST").map_or(1000.0, |s| s.parse().unwrap());
    options.creep.time_constants_s =
        hystcomp_identify::CreepOptions::log_spaced(0.01, last, 2).time_constants_s;
    let excitation = ChainExcitation::default();
    let hyst = IdentificationExcitation {
        full_scale_v: fs_v,
        ..Default::default()
    };
    let mut cmd = hyst.command_v(fs);
    let n0 = cmd.len();
    if std::env::var("EXC").as_deref() == Ok("minor") {
        let extra = minor_loops(
            fs_v,
            fs,
            *cmd.last().unwrap(),
            &list("MINOR", "0.1,0.2"),
            5.0,
        );
        cmd.extend(extra);
    }
    let n1 = cmd.len();
    let (chain_part, segs) = excitation
        .command_v(fs_v, fs, *cmd.last().unwrap())
        .unwrap();
    cmd.extend(chain_part);
    let vib = segs.vibration.start + n1..segs.vibration.end + n1;
    let measured = run(&stage, 1, &cmd);
    let record_span = range(&measured);
    eprintln!(
        "record {:.1} s (hysteresis part {:.1} s)",
        cmd.len() as f64 / fs,
        n0 as f64 / fs
    );

    // Held-out record (seed 2): rate sweeps about mid-range at smaller amplitudes.
    let held_amps = list("HELD", "0.1");
    let mut held_cmd: Vec<f64> = Vec::new();
    held_cmd.extend(minor_loops(fs_v, fs, 0.0, &held_amps, 10.0));
    let held = run(&stage, 2, &held_cmd);
    let held_from = fs as usize; // after the first lead-in
    let held_span = range(&held[held_from..]);

    let mut rigid = stage.clone();
    rigid.sensor.noise_rms_nm = 0.0;
    rigid.amplifier.bandwidth_hz = 1e9;
    rigid.amplifier.peak_current_ma = 1e9;
    rigid.mechanics.rigid = true;
    let mut strong = stage.clone();
    strong.amplifier.peak_current_ma = 1000.0;

    let (r10, from10) = raster(10.0, fs);
    let span10 = range(&r10[from10..]);
    let (r100, from100) = raster(100.0, fs);
    let span100 = range(&r100[from100..]);
    let paper = Signal::paper(1.0, 20.0, fs).sample().unwrap();
    let paper_from = paper.len() / 2;
    let paper_span = range(&paper[paper_from..]);

    println!(
        "ops map | fit % | held-out % | 10 Hz H+C: rigid / pred | 10 Hz full real | 100 Hz full 10x slew | 20 s paper (2nd half) H+C rigid / full real"
    );
    for ops in list("OPS", "10,15,20") {
        for (map, power) in list("MAP", "1,3")
            .into_iter()
            .flat_map(|m| list("POW", "1").into_iter().map(move |p| (m, p)))
        {
            let ops = ops as usize;
            let map = map as usize;
            let base = IdentifyOptions {
                thresholds: if power == 1.0 {
                    Thresholds::Uniform(ops)
                } else {
                    Thresholds::Given(
                        (0..ops)
                            .map(|i| (i as f64 / ops as f64).powf(power))
                            .collect(),
                    )
                },
                output_map_degree: map,
                warmup: Warmup::Samples(0),
                max_fit_rms_percent: None,
                ..IdentifyOptions::default()
            };
            let chain = ChainOptions {
                sample_rate_hz: fs,
                decimation: 10,
                creep: Some(options.creep.clone()),
                dynamics: Some(DynamicsOptions {
                    segment: Some(vib.clone()),
                    segment_gain: std::env::var("SEGGAIN").as_deref() == Ok("1"),
                    ..options.dynamics.clone()
                }),
                output_error_iterations: 0,
            };
            let id = identify_chain(&cmd, &measured, &base, &chain).unwrap();
            let plant = id.model;
            let hc = plant
                .clone()
                .with_links(fs, plant.creep.clone(), None)
                .unwrap();
            let fit = {
                let p = plant.predict(&cmd).unwrap();
                100.0 * rms(&p, &measured) / record_span
            };
            let held_out = {
                let p = plant.predict(&held_cmd).unwrap();
                100.0 * rms(&p[held_from..], &held[held_from..]) / held_span
            };
            let c10 = command(&hc, &r10, fs_v);
            let y_rigid = run(&rigid, 2, &c10);
            let pred = hc.predict(&c10).unwrap();
            let pct10 = |y: &[f64]| 100.0 * rms(&y[from10..], &r10[from10..]) / span10;
            let f10 = command(&plant, &r10, fs_v);
            let y10 = run(&stage, 2, &f10);
            let f100 = command(&plant, &r100, fs_v);
            let y100 = run(&strong, 2, &f100);
            let cp = command(&hc, &paper, fs_v);
            let yp = run(&rigid, 2, &cp);
            let fp = command(&plant, &paper, fs_v);
            let ypr = run(&stage, 2, &fp);
            let pctp = |y: &[f64]| 100.0 * rms(&y[paper_from..], &paper[paper_from..]) / paper_span;
            let (m, g, r) = split(&y_rigid[from10..], &r10[from10..], span10);
            let (hm, hg, hr) = split(
                &plant.predict(&held_cmd).unwrap()[held_from..],
                &held[held_from..],
                held_span,
            );
            println!(
                "      split of the 10 Hz rigid error: mean {m:.3} gain {g:.3} shape {r:.3}; of the held-out prediction error: mean {hm:.3} gain {hg:.3} shape {hr:.3}"
            );
            println!(
                "{ops:>3} {map} p{power} | {fit:.3} | {held_out:.3} | {:.3} / {:.3} | {:.3} | {:.3} | {:.3} / {:.3}",
                pct10(&y_rigid),
                100.0 * rms(&pred[from10..], &y_rigid[from10..]) / span10,
                pct10(&y10),
                100.0 * rms(&y100[from100..], &r100[from100..]) / span100,
                pctp(&yp),
                pctp(&ypr),
            );
        }
    }
}
