//! Diagnosis of the speed study's triangle raster (issue 11): what grows from 10 Hz to 100 Hz
//! in the `full` pipeline's error. Ablations on diagnostic copies of the stage (noise, slew,
//! amplifier bandwidth, resonance, creep switched off), an oracle vibration inverse (the
//! stage's own linear parts, diagnosis only: identification never sees them), and the
//! identified vibration link's frequency response against a held-out multisine measured on
//! the stage (voltage and displacement samples only).
//! Not part of the study; `cargo run --release -p hystcomp-experiments --example raster_diag`.

use hystcomp_experiments::signals::{Multisine, PaperTrajectory, Raster, Shape, Signal};
use hystcomp_experiments::speed::from_rest;
use hystcomp_experiments::{StudyOptions, run_study};
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

fn raster(rate: f64, fs: f64) -> (Vec<f64>, usize) {
    let signal = Signal {
        shape: Shape::Raster(Raster::triangle(rate, 0.05)),
        amplitude: 10.0,
        offset: PaperTrajectory::new().mid_range_um(),
        duration_s: 10.0 / rate,
        speed: 1.0,
        sample_rate_hz: fs,
    };
    let d = from_rest(&signal.sample().unwrap(), fs).0;
    let from = d.len() - (5.0 / rate * fs).round() as usize;
    (d, from)
}

fn command(model: &ModelFile, desired: &[f64], fs_v: f64) -> Vec<f64> {
    let mut c = ScaledCompensator::new(model, Method::Ihc, Some((0.0, fs_v))).unwrap();
    let mut out = vec![0.0; desired.len()];
    c.process(desired, &mut out).unwrap();
    out
}

fn run(stage: &StageConfig, command: &[f64]) -> (Vec<f64>, u64) {
    let r = Stage::new(stage, 2).unwrap().run(command);
    (r.measured_position_um, r.clamps.slew_limited)
}

/// The stage's mechanics sampled (zero-order hold, output at the end of the sample): the
/// oracle's linear part after the hysteresis (diagnosis only).
fn mechanics_zoh(f: f64, zeta: f64, fs: f64) -> (Vec<f64>, Vec<f64>) {
    let w = 2.0 * std::f64::consts::PI * f;
    let t = 1.0 / fs;
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let r = (-zeta * w * t).exp();
    let a1 = -2.0 * r * (wd * t).cos();
    let a2 = r * r;
    let s = (wd * t).sin();
    let c = (wd * t).cos();
    let k = zeta * w / wd;
    let b1 = 1.0 - r * (c + k * s);
    let b2 = r * r + r * (k * s - c);
    (vec![b1, b2], vec![1.0, a1, a2])
}

fn main() {
    let t = std::time::Instant::now();
    let mut options = StudyOptions::default();
    if let Ok(n) = std::env::var("OPS") {
        options.full.operators = n.parse().unwrap();
    }
    if let Ok(band) = std::env::var("BAND") {
        options.full.inverse_band_hz = Some(band.parse().unwrap());
    }
    if std::env::var("SEGGAIN").as_deref() == Ok("1") {
        options.full.dynamics.segment_gain = true;
    }
    let study = run_study(&options, &mut hystcomp_experiments::study::Silent).unwrap();
    eprintln!("study {:.1} s", t.elapsed().as_secs_f64());
    for (name, points) in [
        ("paper", &study.speed.paper),
        ("raster", &study.speed.raster),
        ("raster strong", &study.speed.raster_strong_amplifier),
    ] {
        for p in points.iter() {
            let r = p.run("full / ihc").unwrap();
            println!(
                "study {name} {:>5} Hz full/ihc e_rms {:.3} % limited {:.3}",
                p.rate_hz, r.indices.e_rms_percent, r.limited_share
            );
        }
    }
    for r in &study.full.runs {
        println!(
            "study 20 s {} e_rms {:.3} %",
            r.label, r.indices.e_rms_percent
        );
    }
    for h in &study.duration.hold {
        println!("study hold {} drift {:.3} um", h.label, h.drift_um);
    }
    for series in &study.duration.series {
        if let Some(i) = series.at(200.0) {
            println!(
                "study 200 s {} e_rms {:.3} %",
                series.label, i.e_rms_percent
            );
        }
    }
    for trajectory in [
        hystcomp_experiments::learning_study::PAPER,
        hystcomp_experiments::learning_study::RASTER,
    ] {
        if let Some(series) = study.learning.series(trajectory, "full / ihc") {
            println!(
                "study learning {trajectory} full: best within 20 {:?} first meeting (0.03, 0.3) within 10 {:?}",
                series.best_within(20).map(|p| p.indices.e_rms_percent),
                series.first_meeting(10, 0.03, 0.3)
            );
        }
    }
    if std::env::var("SHORT").is_ok() {
        return;
    }
    let plant = &study.full.plant.model;
    if let Some(d) = &study.full.plant.report.dynamics {
        println!(
            "identified D: order {:?} delay {} modes {:?}\n  b {:?}\n  a {:?}\n  rms with {:.4} without {:.4}",
            d.order,
            d.part.delay_samples,
            d.modes,
            d.part.numerator,
            d.part.denominator,
            d.rms_with,
            d.rms_without
        );
        for c in &d.candidates {
            println!("  cand d={} n={} m={} rms={:.5}", c.0, c.1, c.2, c.3);
        }
    }
    let stage = StageConfig::default();
    let fs = stage.sample_rate_hz;
    let fs_v = stage.full_scale_command_v();
    let mut quiet = stage.clone();
    quiet.sensor.noise_rms_nm = 0.0;
    let mut strong = quiet.clone();
    strong.amplifier.peak_current_ma = 1e9;
    let mut amp_ideal = strong.clone();
    amp_ideal.amplifier.bandwidth_hz = 1e9;
    let mut rigid = strong.clone();
    rigid.mechanics.rigid = true;
    let mut no_dyn = amp_ideal.clone();
    no_dyn.mechanics.rigid = true;
    let mut no_dyn_creep = no_dyn.clone();
    no_dyn_creep.creep.percent_per_decade = 0.0;
    let mut strong_noisy = stage.clone();
    strong_noisy.amplifier.peak_current_ma = 1000.0;

    let h_c = plant
        .clone()
        .with_links(fs, plant.creep.clone(), None)
        .unwrap();
    let vib = plant.vibration.clone().unwrap();
    let amp = &stage.amplifier;
    let decay = (-2.0 * std::f64::consts::PI * amp.bandwidth_hz / fs).exp();
    let (mb, ma) = mechanics_zoh(
        stage.mechanics.resonance_hz,
        stage.mechanics.damping_ratio,
        fs,
    );

    println!("\nrate | stage variant | drive | e_rms % | slew-limited samples (window)");
    for rate in [10.0, 20.0, 50.0, 100.0, 200.0] {
        let (desired, from) = raster(rate, fs);
        let span = range(&desired[from..]);
        let pct = |m: &[f64]| 100.0 * rms(&m[from..], &desired[from..]) / span;
        let full = command(plant, &desired, fs_v);
        let hc = command(&h_c, &desired, fs_v);
        // Oracle: y_d through the stage's exact mechanics inverse, the model's H and C
        // inverses, then the exact amplifier inverse (first order) on the command.
        let mut inv = hystcomp_core::VibrationInverse::<f64, Vec<f64>>::new(
            &mb,
            &ma,
            0,
            hystcomp_core::VibrationInverse::<f64, Vec<f64>>::needed_preview(&mb, 0).unwrap(),
        )
        .unwrap();
        let mut free = vec![0.0; desired.len()];
        inv.process_aligned(&desired, &mut free).unwrap();
        let c_free = command(&h_c, &free, fs_v);
        let mut oracle = c_free.clone();
        for k in 1..oracle.len() {
            oracle[k] = ((c_free[k] - decay * c_free[k - 1]) / (1.0 - decay)).clamp(0.0, fs_v);
        }
        // Oracle mechanics only (amplifier left to the model): for the split.
        let drives: Vec<(&str, &Vec<f64>)> = vec![
            ("full", &full),
            ("H+C only", &hc),
            ("oracle mech+amp", &oracle),
            ("oracle mech", &c_free),
        ];
        for (sname, s) in [
            ("real", &stage),
            ("10x slew (study)", &strong_noisy),
            ("quiet", &quiet),
            ("quiet, slew inf", &strong),
            ("quiet, amp ideal", &amp_ideal),
            ("quiet, slew inf, rigid", &rigid),
            ("quiet, no dynamics", &no_dyn),
            ("quiet, no dyn, no creep", &no_dyn_creep),
        ] {
            for (dname, d) in &drives {
                let (m, slew) = run(s, d);
                let (_, slew_before) = run(s, &d[..from]);
                println!(
                    "{rate:>5} | {sname:<24} | {dname:<16} | {:.3} | {}",
                    pct(&m),
                    slew - slew_before
                );
            }
        }
        // Peak slew asked by each drive in the window, V/s at the amplifier.
        for (dname, d) in &drives {
            let peak = d[from - 1..]
                .windows(2)
                .map(|w| (w[1] - w[0]).abs())
                .fold(0.0, f64::max)
                * amp.gain
                * fs;
            println!(
                "{rate:>5} | peak slew asked by {dname}: {:.0} V/s (limit {:.0})",
                peak,
                amp.slew_rate_v_per_s()
            );
        }
        // The model's prediction vs the quiet stage under the full drive: which link errs.
        let (q, _) = run(&quiet, &full);
        let (nd, _) = run(&no_dyn, &full);
        let pred_full = plant.predict(&full).unwrap();
        let pred_hc = h_c.predict(&full).unwrap();
        println!(
            "{rate:>5} | prediction error under the full drive: full model vs quiet stage {:.3} %, H+C vs no-dyn stage {:.3} %, D_model vs D_stage {:.3} %",
            pct_pair(&pred_full, &q, from, span),
            pct_pair(&pred_hc, &nd, from, span),
            {
                // Model dynamics applied to the no-dyn stage's output vs the quiet stage.
                let mut d = vib.link().unwrap();
                d.settle(nd[0]);
                let dx: Vec<f64> = nd.iter().map(|x| d.step(*x)).collect();
                pct_pair(&dx, &q, from, span)
            }
        );
    }

    // Band-limited inversion: the desired trajectory low-passed (zero phase) before the
    // full compensator, evaluated against the original trajectory.
    for rate in [10.0, 50.0, 100.0, 200.0] {
        let (desired, from) = raster(rate, fs);
        let span = range(&desired[from..]);
        let pct = |m: &[f64]| 100.0 * rms(&m[from..], &desired[from..]) / span;
        for fc in [0.0, 2500.0, 2000.0, 1500.0, 1200.0, 1000.0, 800.0] {
            let filtered = if fc > 0.0 {
                hystcomp_io::band_limit::zero_phase_low_pass(&desired, fc, fs)
            } else {
                desired.clone()
            };
            let c = command(plant, &filtered, fs_v);
            let peak = c[from - 1..]
                .windows(2)
                .map(|w| (w[1] - w[0]).abs())
                .fold(0.0, f64::max)
                * amp.gain
                * fs;
            let (m, slew) = run(&stage, &c);
            let (ms, _) = run(&strong_noisy, &c);
            let (mq, _) = run(&strong, &c);
            println!(
                "bandlimit {rate:>5} Hz fc {fc:>6}: real {:.3} % (slew-limited {slew}) 10x slew {:.3} % quiet inf slew {:.3} % | filtered vs desired {:.3} % | peak slew {:.0}",
                pct(&m),
                pct(&ms),
                pct(&mq),
                pct(&filtered),
                peak
            );
        }
    }
    // The hysteresis-and-creep model's error under the full drive, through the stage's
    // mechanics: what the resonance makes of it.
    {
        let (desired, from) = raster(100.0, fs);
        let span = range(&desired[from..]);
        let full = command(plant, &desired, fs_v);
        let (nd, _) = run(&no_dyn, &full);
        let pred_hc = h_c.predict(&full).unwrap();
        let e: Vec<f64> = pred_hc.iter().zip(&nd).map(|(a, b)| b - a).collect();
        let mut g = hystcomp_core::Vibration::<f64, Vec<f64>>::new(&mb, &ma, 0).unwrap();
        g.settle(0.0);
        let ge: Vec<f64> = e.iter().map(|x| g.step(*x)).collect();
        let zero = vec![0.0; e.len()];
        println!(
            "100 Hz: H+C model error (stage - model, no dynamics) {:.3} %; through the stage's resonance {:.3} %",
            pct_pair(&e, &zero, from, span),
            pct_pair(&ge, &zero, from, span)
        );
    }

    // Frequency response: the identified D against a held-out multisine on the quiet stage
    // at mid-range, x = H+C model's prediction from the voltage, y = measured.
    println!("\nfrequency response: model D vs held-out stage y / (H+C)[v] (5 Hz grid)");
    let level = 0.5 * fs_v;
    for amplitude in [0.006, 0.03] {
        let ms = Multisine::schroeder(5.0, 4, 400).unwrap();
        let sig = Signal {
            shape: Shape::Multisine(ms),
            amplitude: amplitude * fs_v,
            offset: level,
            duration_s: 4.0,
            speed: 1.0,
            sample_rate_hz: fs,
        }
        .sample()
        .unwrap();
        let mut cmd: Vec<f64> = (1..=10_000)
            .map(|k| level * 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / 10_000.0).cos()))
            .collect();
        cmd.extend(std::iter::repeat_n(level, 5000));
        let start = cmd.len();
        cmd.extend(sig);
        let (y, _) = run(&quiet, &cmd);
        let x = h_c.predict(&cmd).unwrap();
        let dm = plant.predict(&cmd).unwrap();
        // The last 2 s: 10 periods of the 5 Hz fundamental (2000 samples each).
        let n = 20_000;
        let s = start + 20_000;
        let dft = |v: &[f64], f: f64| {
            let (mut re, mut im) = (0.0, 0.0);
            for (k, val) in v[s..s + n].iter().enumerate() {
                let ph = 2.0 * std::f64::consts::PI * f * k as f64 / fs;
                re += val * ph.cos();
                im -= val * ph.sin();
            }
            (re, im)
        };
        println!("amplitude {amplitude} of full scale");
        for f in [
            20.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 750.0, 780.0, 800.0, 820.0,
            850.0, 900.0, 1000.0, 1200.0, 1500.0, 1800.0,
        ] {
            let (xr, xi) = dft(&x, f);
            let (yr, yi) = dft(&y, f);
            let (mr, mi) = dft(&dm, f);
            let div = |ar: f64, ai: f64| {
                let d = xr * xr + xi * xi;
                ((ar * xr + ai * xi) / d, (ai * xr - ar * xi) / d)
            };
            let (sr, si) = div(yr, yi);
            let (mr2, mi2) = div(mr, mi);
            println!(
                "  {f:>6} Hz: stage |G| {:.4} ph {:>7.2} deg | model |D| {:.4} ph {:>7.2} deg | |diff| {:.4}",
                (sr * sr + si * si).sqrt(),
                si.atan2(sr).to_degrees(),
                (mr2 * mr2 + mi2 * mi2).sqrt(),
                mi2.atan2(mr2).to_degrees(),
                ((sr - mr2).powi(2) + (si - mi2).powi(2)).sqrt()
            );
        }
    }
}

fn pct_pair(a: &[f64], b: &[f64], from: usize, span: f64) -> f64 {
    100.0 * rms(&a[from..], &b[from..]) / span
}
