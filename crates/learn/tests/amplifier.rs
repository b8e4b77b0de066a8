//! The amplifier model of the anti-windup (`hystcomp_learn::amplifier`) against plain
//! references on seeded random drives: a fine Euler integration of its differential equation,
//! the simulated stage's own amplifier, its exact inverse; and the learner with an
//! anti-windup unchanged where the amplifier never slews.

use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::amplifier::{
    amplifier_output, delivered_drive, input_for_step, linear_output, slew_feasible_drive,
};
use hystcomp_learn::{AmplifierSpec, AntiWindup, AntiWindupLaw, Learner, LearningOptions};
use hystcomp_stage::{Stage, StageConfig};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FS: f64 = 10_000.0;

/// The built-in stage's amplifier over its gain: 2 kHz, 14.3 kV/s / 15.
fn spec() -> AmplifierSpec {
    let a = StageConfig::default().amplifier;
    AmplifierSpec {
        bandwidth_hz: a.bandwidth_hz,
        slew_rate_per_s: a.slew_rate_v_per_s() / a.gain,
    }
}

/// A drive within 0..10 V mixing holds, small steps (linear) and large ones (slewing).
fn random_drive(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    let mut v = vec![rng.random_range(2.0..8.0)];
    for _ in 1..n {
        let last = v[v.len() - 1];
        let step: f64 = match rng.random_range(0..4) {
            0 => 0.0,
            1 => rng.random_range(-0.02..0.02),
            2 => rng.random_range(-0.2..0.2),
            _ => rng.random_range(-2.0..2.0),
        };
        v.push((last + step).clamp(0.0, 10.0));
    }
    v
}

/// `du/dt = clamp(w (v - u), -S, S)` by Euler's method, `sub` steps per sample, from rest.
fn euler(spec: &AmplifierSpec, drive: &[f64], sub: usize) -> Vec<f64> {
    let w = 2.0 * std::f64::consts::PI * spec.bandwidth_hz;
    let s = spec.slew_rate_per_s;
    let h = 1.0 / FS / sub as f64;
    let mut u = 0.0;
    drive
        .iter()
        .map(|&v| {
            for _ in 0..sub {
                u += h * (w * (v - u)).clamp(-s, s);
            }
            u
        })
        .collect()
}

#[test]
fn the_exact_solution_matches_a_fine_euler_integration() {
    let spec = spec();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let full = spec.slew_rate_per_s / FS;
    for _ in 0..8 {
        let drive = random_drive(&mut rng, 300);
        let exact = amplifier_output(&spec, FS, &drive, false);
        let reference = euler(&spec, &drive, 4000);
        for (k, (a, b)) in exact.iter().zip(&reference).enumerate() {
            assert!((a - b).abs() < 1e-3 * full, "sample {k}: {a} against {b}");
        }
        // Every step within the slew rate's.
        let mut before = 0.0;
        for u in &exact {
            assert!((u - before).abs() <= full * (1.0 + 1e-12));
            before = *u;
        }
    }
}

#[test]
fn it_is_the_simulated_stages_amplifier() {
    let config = StageConfig::default();
    let gain = config.amplifier.gain;
    let spec = spec();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for _ in 0..4 {
        let drive = random_drive(&mut rng, 400);
        let monitor = Stage::new(&config, 3).unwrap().run(&drive).amplifier_v;
        let modelled = amplifier_output(&spec, FS, &drive, false);
        // The stage quantises the command (16 bits over 20 V: 0.3 mV) first.
        for (k, (m, u)) in monitor.iter().zip(&modelled).enumerate() {
            assert!(
                (m / gain - u).abs() < 1e-3,
                "sample {k}: {} against {u}",
                m / gain
            );
        }
    }
}

#[test]
fn the_inverse_of_one_sample_gives_the_step_back_and_the_least_input_when_slewing() {
    let spec = spec();
    let full = spec.slew_rate_per_s / FS;
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for _ in 0..2000 {
        let v0 = rng.random_range(2.0..8.0);
        let v1 = v0 + rng.random_range(-2.5..2.5);
        let u = amplifier_output(&spec, FS, &[v0, v1], false);
        let found = input_for_step(&spec, 1.0 / FS, u[0], u[1]);
        let again = amplifier_output(&spec, FS, &[v0, found], false);
        assert!((again[1] - u[1]).abs() < 1e-9, "{v0} {v1}: {again:?} {u:?}");
        if (u[1] - u[0]).abs() < full * (1.0 - 1e-9) {
            // Below the slew rate's step the input is unique.
            assert!((found - v1).abs() < 1e-7, "{v0} {v1}: {found}");
        } else {
            // Slewing the whole period: the least input that does.
            assert!((found - u[0]).abs() <= (v1 - u[0]).abs() + 1e-12);
        }
    }
}

#[test]
fn the_delivered_drive_delivers_the_same_and_is_the_drive_where_nothing_slews() {
    let spec = spec();
    let full = spec.slew_rate_per_s / FS;
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    for periodic in [false, true] {
        for _ in 0..6 {
            let drive = random_drive(&mut rng, 250);
            let delivered = delivered_drive(&spec, FS, &drive, periodic);
            let a = amplifier_output(&spec, FS, &drive, periodic);
            let b = amplifier_output(&spec, FS, &delivered, periodic);
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() < 1e-8 * full.max(1.0), "{x} {y}");
            }
            for (v, d) in drive.iter().zip(&delivered) {
                assert!(
                    d.is_finite() && (-1e-9..=10.0 + 1e-9).contains(d),
                    "{v} -> {d}"
                );
            }
            // A drive slow enough never to slew (from rest: it starts at 0) is its own
            // delivered drive.
            let slow: Vec<f64> = (0..250)
                .map(|k| 2.0 - 2.0 * (2.0 * std::f64::consts::PI * k as f64 / 250.0).cos())
                .collect();
            let same = delivered_drive(&spec, FS, &slow, periodic);
            for (v, d) in slow.iter().zip(&same) {
                assert!((v - d).abs() < 1e-9, "{v} {d}");
            }
        }
    }
}

#[test]
fn the_slew_feasible_drive_keeps_the_output_within_the_margin() {
    let spec = spec();
    let full = spec.slew_rate_per_s / FS;
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    // Periodic records (a finite one's first step, from rest, is not bounded).
    {
        let periodic = true;
        for _ in 0..8 {
            let drive = random_drive(&mut rng, 200);
            let margin = rng.random_range(0.5..0.98);
            let feasible = slew_feasible_drive(&spec, FS, &drive, (0.0, 10.0), periodic, margin);
            assert!(feasible.iter().all(|v| (0.0..=10.0).contains(v)));
            let u = amplifier_output(&spec, FS, &feasible, periodic);
            // The amplifier delivers the projected linear response: its steps within margin.
            let n = u.len();
            for k in 0..n {
                let before = u[(k + n - 1) % n];
                assert!(
                    (u[k] - before).abs() <= margin * full * (1.0 + 1e-6) + 1e-9,
                    "step {k}: {}",
                    u[k] - before
                );
            }
        }
    }
    // A drive whose linear response is within the margin comes back as it is.
    let slow: Vec<f64> = (0..200)
        .map(|k| 5.0 + (2.0 * std::f64::consts::PI * k as f64 / 200.0).sin())
        .collect();
    assert!(
        linear_output(&spec, FS, &slow, true)
            .windows(2)
            .all(|w| (w[1] - w[0]).abs() < full)
    );
    assert_eq!(
        slew_feasible_drive(&spec, FS, &slow, (0.0, 10.0), true, 0.9),
        slow
    );
}

fn model() -> ModelFile {
    ModelFile::load(std::path::Path::new("../../models/table1-plant.json")).unwrap()
}

#[test]
fn every_anti_windup_leaves_a_drive_that_never_slews_alone() {
    // A slow sine at 1 kHz sampling on the table-1 plant: the amplifier (at 1 kHz) never
    // slews, so every law's drives and references are the plain learner's.
    let model = model();
    let n = 500;
    let desired: Vec<f64> = (0..n)
        .map(|k| 35.0 + 15.0 * (2.0 * std::f64::consts::PI * k as f64 / n as f64).sin())
        .collect();
    let mut plant = model.clone();
    plant.output.scale *= 0.95;
    let spec = AmplifierSpec {
        bandwidth_hz: 400.0,
        slew_rate_per_s: 1e4,
    };
    let mut plain_options = LearningOptions::new(1000.0);
    plain_options.mhe_bins = 50;
    let plain = Learner::new(&model, &desired, plain_options).unwrap();
    for law in [
        AntiWindupLaw::Delivered,
        AntiWindupLaw::Projected { margin: 0.9 },
        AntiWindupLaw::Conditional,
    ] {
        let mut options = LearningOptions::new(1000.0);
        options.mhe_bins = 50;
        options.anti_windup = Some(AntiWindup {
            amplifier: spec,
            law,
        });
        let mut learner = Learner::new(&model, &desired, options).unwrap();
        assert_eq!(learner.law().anti_windup.map(|a| a.law), Some(law));
        let mut reference = plain.clone();
        for _ in 0..4 {
            for (a, b) in learner.drive().iter().zip(reference.drive()) {
                assert!((a - b).abs() < 1e-6, "{law:?}: {a} {b}");
            }
            for (a, b) in learner.reference().iter().zip(reference.reference()) {
                assert!((a - b).abs() < 1e-6, "{law:?}: {a} {b}");
            }
            let drive = learner.drive().to_vec();
            let three: Vec<f64> = drive.iter().chain(&drive).chain(&drive).copied().collect();
            let measured = plant.predict(&three).unwrap()[n..2 * n].to_vec();
            learner.update(&measured).unwrap();
            reference.update(&measured).unwrap();
        }
    }
}

#[test]
fn a_bad_amplifier_or_margin_is_refused_by_name() {
    let good = AmplifierSpec {
        bandwidth_hz: 2000.0,
        slew_rate_per_s: 950.0,
    };
    for (bandwidth_hz, slew_rate_per_s) in [
        (0.0, 1.0),
        (-1.0, 1.0),
        (f64::NAN, 1.0),
        (1.0, 0.0),
        (1.0, f64::INFINITY),
    ] {
        let mut o = LearningOptions::new(1000.0);
        o.anti_windup = Some(AntiWindup {
            amplifier: AmplifierSpec {
                bandwidth_hz,
                slew_rate_per_s,
            },
            law: AntiWindupLaw::Delivered,
        });
        assert!(o.validate().unwrap_err().to_string().contains("amplifier"));
    }
    for margin in [0.0, -0.5, 1.5, f64::NAN] {
        let mut o = LearningOptions::new(1000.0);
        o.anti_windup = Some(AntiWindup {
            amplifier: good,
            law: AntiWindupLaw::Projected { margin },
        });
        assert!(
            o.validate()
                .unwrap_err()
                .to_string()
                .contains("anti-windup margin")
        );
    }
}
