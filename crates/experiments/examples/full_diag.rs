//! Diagnosis of the `full` pipeline (issue 11): the model compared link by link with diagnostic
//! copies of the stage (creep, dynamics, noise switched off), on the study's runs.
//! Not part of the study; `cargo run --release -p hystcomp-experiments --example full_diag`.
//!
//! Arguments `key=value` change the pipeline (`smooth`, `first`, `last`, `per`: the creep
//! bank; `holds=1` and `auto=1`: weights on the holds, smoothness chosen; `ops`, `iops`, `oe`,
//! `res`, `delay`; the excitation's `hold`, `hold2`, `step`, `rest`, `vibamp`, `vibs`).
//! Environment: `JOINT=1` the joint creep fit; `STUDY=1` runs the whole study and prints issue
//! 11's summary (`SEED=s`: the study's seed; `STRONG=1`: on the stage with ten times the amplifier's slew rate; `SLEWLEARN=1`: the learning study's drive slew-projected, `StudyOptions::slew_aware_learning`; `FEASSTART=1`: its series start from the slew-constrained drive, `StudyOptions::feasible_learning_start`); `FLOOR=1` identifies hysteresis-only MPIMs on the creep-, dynamics- and
//! noise-free copy (`POWER=p`: thresholds `(i/n)^p`) and writes its n = 10 model to
//! `/tmp/creep-mpim-stage.json`, which `STAGEHYST=mpim` then makes the stage's hysteresis;
//! `STAGECREEP=off|log100|log1000|kv` changes the diagnostic stage's creep law; `DUMP=run`
//! writes a run's error to `/tmp`. Diagnostic copies of the stage are for diagnosis only.

#![allow(clippy::needless_range_loop)]

use hystcomp_experiments::chain_excitation::ChainExcitation;
use hystcomp_experiments::excitation::IdentificationExcitation;
use hystcomp_experiments::full::FullOptions;
use hystcomp_experiments::signals::{PaperTrajectory, Raster, Shape, Signal, Steps};
use hystcomp_experiments::speed::from_rest;
use hystcomp_identify::{
    ChainOptions, CreepOptions, DynamicsOptions, IdentifyOptions, Thresholds, Warmup,
    identify_chain, identify_inverse_chain,
};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::{Direction, ModelFile};
use hystcomp_stage::{Stage, StageConfig};

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}
fn range(a: &[f64]) -> f64 {
    a.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - a.iter().copied().fold(f64::INFINITY, f64::min)
}

struct Variants {
    real: StageConfig,
    quiet: StageConfig,
    no_dyn: StageConfig,
    no_dyn_creep: StageConfig,
}

/// The stage, or a diagnostic copy (STAGECREEP=log100: the logarithmic creep's spectrum cut
/// at 100 s; kv: a Kelvin-Voigt bank 10 ms to 100 s).
fn base_stage() -> StageConfig {
    let mut s = StageConfig::default();
    match std::env::var("STAGECREEP").as_deref() {
        Ok("log100") => s.creep.longest_time_constant_s = 100.0,
        Ok("log1000") => s.creep.longest_time_constant_s = 1000.0,
        Ok("off") => s.creep.percent_per_decade = 0.0,
        Ok("kv") => {
            s.creep.law = hystcomp_stage::CreepLaw::KelvinVoigt;
            s.creep.decades = 4;
        }
        _ => {}
    }
    if std::env::var("STAGEHYST").as_deref() == Ok("mpim") {
        s.hysteresis.model = hystcomp_stage::HysteresisModel::Mpim;
        s.hysteresis.mpim.model_file = Some("/tmp/creep-mpim-stage.json".into());
    }
    s
}

fn variants() -> Variants {
    let real = base_stage();
    let mut quiet = real.clone();
    quiet.sensor.noise_rms_nm = 0.0;
    let mut no_dyn = quiet.clone();
    no_dyn.amplifier.bandwidth_hz = 1e9;
    no_dyn.amplifier.peak_current_ma = 1e9;
    no_dyn.mechanics.rigid = true;
    let mut no_dyn_creep = no_dyn.clone();
    no_dyn_creep.creep.percent_per_decade = 0.0;
    Variants {
        real,
        quiet,
        no_dyn,
        no_dyn_creep,
    }
}

fn run(stage: &StageConfig, seed: u64, command: &[f64]) -> Vec<f64> {
    Stage::new(stage, seed)
        .unwrap()
        .run(command)
        .measured_position_um
}

fn command(model: &ModelFile, method: Method, desired: &[f64], fs_v: f64) -> Vec<f64> {
    let mut c = ScaledCompensator::new(model, method, Some((0.0, fs_v))).unwrap();
    let mut out = vec![0.0; desired.len()];
    c.process(desired, &mut out).unwrap();
    out
}

/// Link-by-link comparison on `desired[from..]`.
fn compare(name: &str, plant: &ModelFile, inverse: &ModelFile, desired: &[f64], from: usize) {
    let v = variants();
    let fs_v = 10.0;
    let rate = plant.sample_rate_hz.unwrap();
    let span = range(&desired[from..]);
    let pct = |a: &[f64], b: &[f64]| 100.0 * rms(&a[from..], &b[from..]) / span;
    for (label, model, method) in [("ihc", plant, Method::Ihc), ("dihc", inverse, Method::Dihc)] {
        let cmd = command(model, method, desired, fs_v);
        let real = run(&v.real, 2, &cmd);
        let quiet = run(&v.quiet, 2, &cmd);
        let no_dyn = run(&v.no_dyn, 2, &cmd);
        let no_dc = run(&v.no_dyn_creep, 2, &cmd);
        let err: Vec<f64> = real[from..]
            .iter()
            .zip(&desired[from..])
            .map(|(a, b)| a - b)
            .collect();
        let mean = err.iter().sum::<f64>() / err.len() as f64;
        if std::env::var("DUMP").as_deref() == Ok(name) {
            let text: String = err
                .iter()
                .zip(&desired[from..])
                .map(|(e, y)| format!("{y:.5},{e:.5}\n"))
                .collect();
            std::fs::write(format!("/tmp/creep-{name}-{label}.csv"), text).unwrap();
        }
        {
            // err ~ c0 + c1 y_d + c2 dy_d/dt (s): gain error c1, delay -c2.
            let n = err.len();
            let yd = &desired[from..];
            let rate_hz = plant.sample_rate_hz.unwrap();
            let dyd: Vec<f64> = (0..n)
                .map(|k| {
                    let a = yd[k.saturating_sub(1)];
                    let b = yd[(k + 1).min(n - 1)];
                    (b - a) * rate_hz / 2.0
                })
                .collect();
            let cols = |r: usize| [1.0, yd[r], dyd[r]];
            let mut m = [[0.0f64; 4]; 3];
            for r in 0..n {
                let c = cols(r);
                for i in 0..3 {
                    for j in 0..3 {
                        m[i][j] += c[i] * c[j];
                    }
                    m[i][3] += c[i] * err[r];
                }
            }
            for i in 0..3 {
                let p = m[i][i];
                for j in 0..4 {
                    m[i][j] /= p;
                }
                for k in 0..3 {
                    if k != i {
                        let f = m[k][i];
                        for j in 0..4 {
                            m[k][j] -= f * m[i][j];
                        }
                    }
                }
            }
            let sol = [m[0][3], m[1][3], m[2][3]];
            let resid: f64 = (0..n)
                .map(|r| {
                    let c = cols(r);
                    (err[r] - sol[0] * c[0] - sol[1] * c[1] - sol[2] * c[2]).powi(2)
                })
                .sum::<f64>();
            let resid_pct = 100.0 * (resid / n as f64).sqrt() / span;
            println!(
                "   error = {:.4} + {:.5} y_d + {:.2} us * dy_d/dt; residual {:.3} %",
                sol[0],
                sol[1],
                sol[2] * 1e6,
                resid_pct
            );
        }
        println!(
            "   error mean {:.3} % of the range, about the mean {:.3} %",
            100.0 * mean / span,
            100.0 * (err.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / err.len() as f64).sqrt()
                / span
        );
        println!(
            "{name} {label}: tracking real {:.3} quiet {:.3} | stage ablated tracking: no-dyn {:.3} no-dyn-no-creep {:.3}",
            pct(&real, desired),
            pct(&quiet, desired),
            pct(&no_dyn, desired),
            pct(&no_dc, desired)
        );
        if method == Method::Ihc {
            let delay = plant.vibration.as_ref().map_or(0, |d| d.delay_samples);
            let delayed: Vec<f64> = (0..cmd.len())
                .map(|i| cmd[i.saturating_sub(delay)])
                .collect();
            let h_only = plant.clone().with_links(rate, None, None).unwrap();
            let hc = plant
                .clone()
                .with_links(rate, plant.creep.clone(), None)
                .unwrap();
            let mh = h_only.predict(&cmd).unwrap();
            let mhc = hc.predict(&cmd).unwrap();
            let mfull = plant.predict(&cmd).unwrap();
            let _ = delayed;
            if let Some(vib) = &plant.vibration {
                let mut d = vib.link().unwrap();
                d.settle(no_dyn[0]);
                let dx: Vec<f64> = no_dyn.iter().map(|x| d.step(*x)).collect();
                let mut strong = v.quiet.clone();
                strong.amplifier.peak_current_ma = 1e9;
                let q_strong = run(&strong, 2, &cmd);
                let mut wide = strong.clone();
                wide.amplifier.bandwidth_hz = 1e9;
                let q_wide = run(&wide, 2, &cmd);
                println!(
                    "   dynamics alone: D_model[stage no-dyn] vs stage quiet {:.3} vs unlimited slew {:.3} | tracking with unlimited slew {:.3}, and infinite amp bandwidth {:.3}",
                    pct(&dx, &quiet),
                    pct(&dx, &q_strong),
                    pct(&q_strong, desired),
                    pct(&q_wide, desired)
                );
            }
            println!(
                "   model vs stage: H vs no-dyn-no-creep {:.3} | H+C vs no-dyn {:.3} | full vs quiet {:.3} | model full vs desired {:.3}",
                pct(&mh, &no_dc),
                pct(&mhc, &no_dyn),
                pct(&mfull, &quiet),
                pct(&mfull, desired)
            );
            println!(
                "   stage parts: creep (no-dyn - no-dyn-no-creep) vs model creep (H+C - H): {:.3}; dyn (quiet - no-dyn) vs model (full - H+C): {:.3}",
                100.0
                    * rms(
                        &no_dyn[from..]
                            .iter()
                            .zip(&no_dc[from..])
                            .map(|(a, b)| a - b)
                            .collect::<Vec<_>>(),
                        &mhc[from..]
                            .iter()
                            .zip(&mh[from..])
                            .map(|(a, b)| a - b)
                            .collect::<Vec<_>>()
                    )
                    / span,
                100.0
                    * rms(
                        &quiet[from..]
                            .iter()
                            .zip(&no_dyn[from..])
                            .map(|(a, b)| a - b)
                            .collect::<Vec<_>>(),
                        &mfull[from..]
                            .iter()
                            .zip(&mhc[from..])
                            .map(|(a, b)| a - b)
                            .collect::<Vec<_>>()
                    )
                    / span
            );
        }
    }
}

fn hold_drift(measured: &[f64], fs: f64) -> f64 {
    let window = (0.1 * fs) as usize;
    let avg = |s: usize| measured[s..s + window].iter().sum::<f64>() / window as f64;
    let reference = (2.1 * fs) as usize;
    let r = avg(reference);
    (reference..=measured.len() - window)
        .step_by(window)
        .map(|k| (avg(k) - r).abs())
        .fold(0.0, f64::max)
}

fn main() {
    let stage = base_stage();
    let fs = stage.sample_rate_hz;
    let full_scale = stage.full_scale_command_v();
    let args: Vec<String> = std::env::args().collect();
    let mut options = FullOptions::default();
    // Variants from the command line: key=value.
    let mut excitation = ChainExcitation::default();
    let mut per_decade = 2usize;
    let mut first_tau = 0.01;
    let mut last_tau = 100.0;
    let mut holds = false;
    let mut cands: Vec<f64> = Vec::new();
    for a in &args[1..] {
        let (k, val) = a.split_once('=').unwrap();
        let x: f64 = val.parse().unwrap();
        match k {
            "smooth" => options.creep.smoothness = x,
            "first" => first_tau = x,
            "last" => last_tau = x,
            "per" => per_decade = x as usize,
            "ops" => options.operators = x as usize,
            "iops" => options.inverse_operators = x as usize,
            "map" => options.output_map_degree = x as usize,
            "pow" => options.threshold_exponent = x,
            "seg" => options.dynamics.segment_gain = x > 0.0,
            "oe" => options.output_error_iterations = x as usize,
            "hold" => excitation.hold_s = x,
            "hold2" => excitation.second_hold_s = x,
            "step" => excitation.step_s = x,
            "rest" => excitation.rest_s = x,
            "res" => options.dynamics.max_resonances = x as usize,
            "delay" => options.dynamics.max_delay_samples = x as usize,
            "vibamp" => excitation.vibration_amplitude = x,
            "vibs" => excitation.vibration_s = x,
            "holds" => holds = x > 0.0,
            "auto" => cands = vec![0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0],
            _ => panic!("unknown {k}"),
        }
    }
    let smooth = options.creep.smoothness;
    if std::env::var("JOINT").is_ok() {
        options.creep =
            CreepOptions::log_spaced(first_tau, last_tau, per_decade).with_smoothness(smooth);
    } else if holds {
        options.creep = CreepOptions::log_spaced(first_tau, last_tau, per_decade)
            .with_smoothness(smooth)
            .on_holds(&cands);
    }
    if std::env::var("STUDY").is_ok() {
        let mut study_options = hystcomp_experiments::StudyOptions {
            full: FullOptions {
                excitation: excitation.clone(),
                ..options.clone()
            },
            slew_aware_learning: std::env::var("SLEWLEARN").as_deref() == Ok("1"),
            // FEASSTART=1: the learning study's series start from the slew-constrained drive
            // where the faithful one asks more than the slew rate.
            feasible_learning_start: std::env::var("FEASSTART").as_deref() == Ok("1"),
            ..Default::default()
        };
        // SEED=s: the study's seed (1 by default).
        if let Ok(seed) = std::env::var("SEED") {
            study_options.seed = seed.parse().unwrap();
        }
        // STRONG=1: the whole study on the stage with the speed study's stronger amplifier
        // (ten times the slew rate; diagnosis only: identification included).
        if std::env::var("STRONG").as_deref() == Ok("1") {
            study_options.stage.amplifier.peak_current_ma =
                hystcomp_experiments::speed::STRONG_PEAK_CURRENT_MA;
        }
        let t = std::time::Instant::now();
        let study = hystcomp_experiments::run_study(
            &study_options,
            &mut hystcomp_experiments::study::Silent,
        )
        .unwrap();
        println!(
            "study in {:.2} s; creep grid {:?}; weights {:?}",
            t.elapsed().as_secs_f64(),
            study.full.creep_grid,
            study.full.plant.report.creep.as_ref().map(|c| (
                &c.part.time_constants_s,
                &c.part.weights,
                c.smoothness
            ))
        );
        if let Some(d) = &study.full.plant.report.dynamics {
            // The vibration link as fitted: with `seg=1` its segment gain is the hysteresis
            // and creep links' small-signal gain error on the multisine.
            let modes: Vec<String> = d
                .modes
                .iter()
                .map(|m| format!("{:.1} Hz zeta {:.4}", m.frequency_hz, m.damping_ratio))
                .collect();
            println!(
                "vibration link: order {:?}, modes [{}], segment gain {:.4}, segment RMS without / with {:.5} / {:.5}",
                d.order,
                modes.join(", "),
                d.segment_gain,
                d.rms_without,
                d.rms_with
            );
        }
        println!("{}", hystcomp_experiments::beyond::summarize_beyond(&study));
        for s in &study.learning.series {
            let e: Vec<String> = s
                .trials
                .iter()
                .map(|t| format!("{:.4}", t.indices.e_rms_percent))
                .collect();
            println!("learning {} / {}: {}", s.trajectory, s.start, e.join(" "));
            let l: Vec<String> = s
                .trials
                .iter()
                .map(|t| format!("{:.3}", t.limited_share))
                .collect();
            println!("   limited share: {}", l.join(" "));
            if let Some(best) = s.best_within(20) {
                println!(
                    "   best within 20: {:.4} e_mhe {:.4}",
                    best.indices.e_rms_percent, best.indices.e_mhe_percent
                );
            }
        }
        return;
    }
    let hyst = IdentificationExcitation {
        full_scale_v: full_scale,
        ..Default::default()
    };
    let mut cmd = hyst.command_v(fs);
    let n0 = cmd.len();
    let (chain_part, segs) = excitation
        .command_v(full_scale, fs, *cmd.last().unwrap())
        .unwrap();
    cmd.extend(chain_part);
    let vib = segs.vibration.start + n0..segs.vibration.end + n0;
    let measured = run(&stage, 1, &cmd);
    let base = IdentifyOptions {
        thresholds: Thresholds::Uniform(options.operators),
        output_map_degree: options.output_map_degree,
        warmup: Warmup::Samples(0),
        max_fit_rms_percent: None,
        ..IdentifyOptions::default()
    };
    let chain = ChainOptions {
        sample_rate_hz: fs,
        decimation: 10,
        creep: Some(options.creep.clone()),
        dynamics: Some(DynamicsOptions {
            segment: Some(vib),
            ..options.dynamics.clone()
        }),
        output_error_iterations: options.output_error_iterations,
    };
    if std::env::var("FLOOR").is_ok() {
        // The hysteresis model's floor: MPIM identified on the creep-, dynamics- and noise-free
        // stage's record, tracking on that stage.
        let v = variants();
        let clean = run(&v.no_dyn_creep, 1, &cmd);
        let desired = Signal::paper(1.0, 20.0, fs).sample().unwrap();
        let power: f64 = std::env::var("POWER")
            .ok()
            .and_then(|p| p.parse().ok())
            .unwrap_or(1.0);
        for n in [8, 10, 12, 15, 20, 30] {
            for end in [n0, n0 + segs.vibration.start] {
                let o = IdentifyOptions {
                    thresholds: if power == 1.0 {
                        Thresholds::Uniform(n)
                    } else {
                        Thresholds::Given(
                            (0..n).map(|i| (i as f64 / n as f64).powf(power)).collect(),
                        )
                    },
                    ..base.clone()
                };
                let vv: Vec<f64> = cmd[..end].iter().step_by(10).copied().collect();
                let yy: Vec<f64> = clean[..end].iter().step_by(10).copied().collect();
                let id = hystcomp_identify::identify(&vv, &yy, &o).unwrap();
                if n == 10 && end > n0 {
                    std::fs::write("/tmp/creep-mpim-stage.json", id.model.to_json()).unwrap();
                }
                let c = command(&id.model, Method::Ihc, &desired, full_scale);
                let m = run(&v.no_dyn_creep, 2, &c);
                let h = desired.len() / 2;
                let inv = hystcomp_identify::identify(
                    &vv,
                    &yy,
                    &IdentifyOptions {
                        direction: Direction::Inverse,
                        ..o.clone()
                    },
                )
                .unwrap();
                let cd = command(&inv.model, Method::Dihc, &desired, full_scale);
                let md = run(&v.no_dyn_creep, 2, &cd);
                let signal = Signal {
                    shape: Shape::Raster(Raster::triangle(10.0, 0.05)),
                    amplitude: 10.0,
                    offset: PaperTrajectory::new().mid_range_um(),
                    duration_s: 1.0,
                    speed: 1.0,
                    sample_rate_hz: fs,
                };
                let (rd, _) = from_rest(&signal.sample().unwrap(), fs);
                let from = rd.len() - 5000;
                let cr = command(&id.model, Method::Ihc, &rd, full_scale);
                let mr = run(&v.no_dyn_creep, 2, &cr);
                println!(
                    "floor n={n} record {:.0} s: fit {:.3} % tracking IHC {:.3} % DIHC {:.3} % (inverse fit {:.3}) raster 10 Hz IHC {:.3} %",
                    end as f64 / fs,
                    id.report.fit.rms_percent,
                    100.0 * rms(&m[h..], &desired[h..]) / range(&desired[h..]),
                    100.0 * rms(&md[h..], &desired[h..]) / range(&desired[h..]),
                    inv.report.fit.rms_percent,
                    100.0 * rms(&mr[from..], &rd[from..]) / range(&rd[from..]),
                );
            }
        }
        return;
    }
    let t = std::time::Instant::now();
    let plant = identify_chain(
        &cmd,
        &measured,
        &IdentifyOptions {
            direction: Direction::Plant,
            ..base.clone()
        },
        &chain,
    )
    .unwrap();
    let inverse = identify_inverse_chain(
        &cmd,
        &measured,
        &IdentifyOptions {
            direction: Direction::Inverse,
            thresholds: Thresholds::Uniform(options.inverse_operators),
            ..base.clone()
        },
        &chain,
        &plant,
    )
    .unwrap();
    println!(
        "identified in {:.2} s; record {} s",
        t.elapsed().as_secs_f64(),
        cmd.len() as f64 / fs
    );
    let r = &plant.report;
    println!("contributions {:?}", r.contributions);
    if let Some(c) = &r.creep {
        println!(
            "creep taus {:?}\n weights {:?} static gain {:.4} smoothness {} candidates {:?}",
            c.part.time_constants_s,
            c.part.weights,
            c.static_gain,
            c.smoothness,
            c.smoothness_candidates
        );
    }
    if let Some(d) = &r.dynamics {
        println!(
            "dynamics order {:?} modes {:?} delay {} with {:.4} without {:.4}\n  candidates {:?}\n  b {:?} a {:?}",
            d.order,
            d.modes,
            d.part.delay_samples,
            d.rms_with,
            d.rms_without,
            d.candidates,
            d.part.numerator,
            d.part.denominator
        );
    }
    println!("inverse contributions {:?}", inverse.report.contributions);

    // 20 s paper trajectory, evaluated on the second period.
    let desired = Signal::paper(1.0, 20.0, fs).sample().unwrap();
    compare(
        "paper20",
        &plant.model,
        &inverse.model,
        &desired,
        desired.len() / 2,
    );
    // Raster at 10 and 100 Hz.
    let paper = PaperTrajectory::new();
    for rate in [10.0, 100.0] {
        let signal = Signal {
            shape: Shape::Raster(Raster::triangle(rate, 0.05)),
            amplitude: 10.0,
            offset: paper.mid_range_um(),
            duration_s: 10.0 / rate,
            speed: 1.0,
            sample_rate_hz: fs,
        };
        let (desired, _) = from_rest(&signal.sample().unwrap(), fs);
        let from = desired.len() - (5.0 / rate * fs).round() as usize;
        compare(
            &format!("raster{rate}"),
            &plant.model,
            &inverse.model,
            &desired,
            from,
        );
    }
    // Paper x10.
    let speed = 10.0 / paper.highest_frequency_hz();
    let traj = Signal::paper(speed, 20.0 / speed, fs).sample().unwrap();
    let per = traj.len() / 2;
    let (desired, start) = from_rest(&traj, fs);
    compare(
        "paper10x",
        &plant.model,
        &inverse.model,
        &desired,
        start + per,
    );

    // The hold.
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
    let v = variants();
    for (label, model, method) in [
        ("ihc", &plant.model, Method::Ihc),
        ("dihc", &inverse.model, Method::Dihc),
    ] {
        let c = command(model, method, &step, full_scale);
        let real = run(&v.real, 2, &c);
        let no_dyn = run(&v.no_dyn, 2, &c);
        let no_dc = run(&v.no_dyn_creep, 2, &c);
        println!(
            "hold {label}: drift real {:.3} no-dyn {:.3} no-dyn-no-creep(hysteresis of the correction) {:.3}",
            hold_drift(&real, fs),
            hold_drift(&no_dyn, fs),
            hold_drift(&no_dc, fs)
        );
        if method == Method::Ihc {
            let hc = plant
                .model
                .clone()
                .with_links(fs, plant.model.creep.clone(), None)
                .unwrap();
            let h = plant.model.clone().with_links(fs, None, None).unwrap();
            let mhc = hc.predict(&c).unwrap();
            let mh = h.predict(&c).unwrap();
            let model_creep: Vec<f64> = mhc.iter().zip(&mh).map(|(a, b)| a - b).collect();
            let stage_creep: Vec<f64> = no_dyn.iter().zip(&no_dc).map(|(a, b)| a - b).collect();
            let hdiff: Vec<f64> = mh.iter().zip(&no_dc).map(|(a, b)| a - b).collect();
            let at = |x: &[f64], t: f64| x[(t * fs) as usize];
            for t in [2.1, 5.0, 10.0, 20.0, 40.0, 63.0] {
                println!(
                    "  t={t:5.1}: model creep {:.3} stage creep {:.3} | H model - H stage {:.3} | cmd {:.4}",
                    at(&model_creep, t),
                    at(&stage_creep, t),
                    at(&hdiff, t),
                    at(&c, t)
                );
            }
        }
    }
    // Open-loop: constant step command, model prediction vs stage.
    let c: Vec<f64> = step.iter().map(|y| y / 50.0 * 6.5).collect();
    let hc = plant
        .model
        .clone()
        .with_links(fs, plant.model.creep.clone(), None)
        .unwrap();
    let m = hc.predict(&c).unwrap();
    let s = run(&v.no_dyn, 2, &c);
    let at = |x: &[f64], t: f64| x[(t * fs) as usize];
    for t in [2.1, 5.0, 10.0, 20.0, 40.0, 63.0] {
        println!(
            "  open-loop step t={t:5.1}: model {:.3} stage {:.3} (growth model {:.3} stage {:.3})",
            at(&m, t),
            at(&s, t),
            at(&m, t) - at(&m, 2.1),
            at(&s, t) - at(&s, 2.1)
        );
    }
}
