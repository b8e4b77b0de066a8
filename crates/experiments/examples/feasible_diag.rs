//! Diagnosis of the speed study's 100 Hz raster on the built-in amplifier (issue 11): the
//! faithful drive against the slew-constrained one (`hystcomp_experiments::slew_drive`) at
//! shares KAPPA (comma-separated, default 0.57,0.8,1.0) of the amplifier's slew rate, on the
//! built-in amplifier and on one with ten times its slew rate. Env OPS (plant operators) and
//! SEGGAIN=1 (the vibration fit's free segment gain) change the study's `full` model.
//! Not part of the study; `cargo run --release -p hystcomp-experiments --example feasible_diag`.
use hystcomp_experiments::signals::{PaperTrajectory, Raster, Shape, Signal};
use hystcomp_experiments::speed::from_rest;
use hystcomp_experiments::{StudyOptions, run_study};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::ModelFile;
use hystcomp_stage::{Stage, StageConfig};

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

fn command(model: &ModelFile, desired: &[f64], fs_v: f64) -> Vec<f64> {
    let mut c = ScaledCompensator::new(model, Method::Ihc, Some((0.0, fs_v))).unwrap();
    let mut out = vec![0.0; desired.len()];
    c.process(desired, &mut out).unwrap();
    out
}

fn main() {
    let mut options = StudyOptions::default();
    if let Ok(n) = std::env::var("OPS") {
        options.full.operators = n.parse().unwrap();
    }
    if std::env::var("SEGGAIN").as_deref() == Ok("1") {
        options.full.dynamics.segment_gain = true;
    }
    let study = run_study(&options, &mut hystcomp_experiments::study::Silent).unwrap();
    let plant = &study.full.plant.model;
    let stage = StageConfig::default();
    let mut strong = stage.clone();
    strong.amplifier.peak_current_ma = 1000.0;
    let fs = stage.sample_rate_hz;
    let fs_v = stage.full_scale_command_v();
    let kappas: Vec<f64> = std::env::var("KAPPA")
        .unwrap_or("0.57,0.8,1.0".into())
        .split(',')
        .map(|k| k.parse().unwrap())
        .collect();
    for rate in [100.0] {
        let signal = Signal {
            shape: Shape::Raster(Raster::triangle(rate, 0.05)),
            amplitude: 10.0,
            offset: PaperTrajectory::new().mid_range_um(),
            duration_s: 10.0 / rate,
            speed: 1.0,
            sample_rate_hz: fs,
        };
        let (desired, _) = from_rest(&signal.sample().unwrap(), fs);
        let from = desired.len() - (5.0 / rate * fs).round() as usize;
        let span = 20.0;
        let track = |cfg: &StageConfig, v: &[f64]| {
            let m = Stage::new(cfg, 1).unwrap().run(v).measured_position_um;
            100.0 * rms(&m[from..], &desired[from..]) / span
        };
        let faithful = command(plant, &desired, fs_v);
        println!(
            "{rate} Hz faithful: built-in {:.3} strong {:.3}",
            track(&stage, &faithful),
            track(&strong, &faithful)
        );
        for kappa in kappas.iter() {
            let t = std::time::Instant::now();
            let r = stage.amplifier.slew_rate_v_per_s() * kappa / stage.amplifier.gain / fs;
            let sd = hystcomp_experiments::slew_drive::slew_constrained_drive(
                plant,
                Method::Ihc,
                (0.0, fs_v),
                &desired,
                r,
            )
            .unwrap();
            println!(
                "  kappa {kappa}: {} violations, constrained {}, predicted {:.4} um ({:.2} s): built-in {:.3} strong {:.3}",
                sd.faithful_violations,
                sd.constrained,
                sd.predicted_rms_um,
                t.elapsed().as_secs_f64(),
                track(&stage, &sd.drive),
                track(&strong, &sd.drive)
            );
        }
    }
}
