//! The stage's physics, each property on seeded random configurations where it makes sense.

use hystcomp_stage::{
    CreepLaw, HysteresisModel, RateIndependentHysteresis, Stage, StageConfig,
    quasi_static_stroke_um, simulate,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn without_creep(mut config: StageConfig) -> StageConfig {
    config.creep.percent_per_decade = 0.0;
    config
}

fn random_commands(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    // A random walk within (and sometimes beyond) the command range.
    let mut x = 5.0;
    (0..n)
        .map(|_| {
            x = (x + 0.05 * (rng.random::<f64>() - 0.5)).clamp(-0.5, 10.5);
            x
        })
        .collect()
}

#[test]
fn same_seed_gives_identical_runs_and_other_seeds_change_only_the_noise() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let commands = random_commands(&mut rng, 20_000);
    for seed in [0, 7, rng.random::<u64>()] {
        let a = simulate(&StageConfig::default(), seed, &commands).unwrap();
        let b = simulate(&StageConfig::default(), seed, &commands).unwrap();
        assert_eq!(a, b);
        let c = simulate(&StageConfig::default(), seed + 1, &commands).unwrap();
        assert_eq!(a.true_position_um, c.true_position_um);
        assert_ne!(a.measured_position_um, c.measured_position_um);
        // A reset stage repeats its first run.
        let mut stage = Stage::default_stage(seed);
        let first = stage.run(&commands);
        stage.reset();
        assert_eq!(stage.run(&commands), first);
    }
}

#[test]
fn starts_at_rest_at_zero_volts() {
    let mut stage = Stage::default_stage(3);
    for _ in 0..1000 {
        let s = stage.step_detailed(0.0);
        assert_eq!(s.amplifier_v, 0.0);
        assert_eq!(s.true_position_um, 0.0);
        // Only noise, within 6 sigma and a code.
        assert!(s.measured_position_um.abs() < 0.035);
    }
}

#[test]
fn hysteresis_part_is_rate_independent_quasi_statically() {
    // Without creep, a slow triangle at two speeds traces the same loop (position against the
    // amplifier voltage): the remaining differences are the dynamic lags of amplifier and
    // resonance, a few nanometres at these rates.
    for model in [HysteresisModel::Preisach, HysteresisModel::BoucWen] {
        let mut config = without_creep(StageConfig::default());
        config.hysteresis.model = model;
        let loop_at = |period_s: f64| {
            let n = (period_s * 10_000.0) as usize;
            let commands: Vec<f64> = (0..n)
                .map(|k| {
                    let phase = k as f64 / n as f64;
                    10.0 * (1.0 - (2.0 * phase - 1.0).abs()) * 0.9 + 0.5
                })
                .collect();
            let r = simulate(&config, 0, &commands).unwrap();
            // Sample the loop at 200 points of the cycle.
            (0..200)
                .map(|i| {
                    let k = i * n / 200;
                    (r.amplifier_v[k], r.true_position_um[k])
                })
                .collect::<Vec<_>>()
        };
        let slow = loop_at(40.0);
        let fast = loop_at(4.0);
        for ((v1, x1), (v2, x2)) in slow.iter().zip(&fast) {
            assert!((v1 - v2).abs() < 0.05, "{model:?}: {v1} vs {v2}");
            assert!((x1 - x2).abs() < 0.05, "{model:?}: {x1} vs {x2} at {v1} V");
        }
        // ...and the loop is a real loop: the two branches differ by micrometres.
        let mid = slow.len() / 4;
        assert!((slow[mid].1 - slow[slow.len() - mid].1).abs() > 3.0);
    }
}

#[test]
fn creep_after_a_step_grows_by_the_configured_percentage_per_decade() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for _ in 0..3 {
        let mut config = StageConfig::default();
        let gamma_percent = 0.5 + 2.5 * rng.random::<f64>();
        config.creep.law = CreepLaw::KelvinVoigt;
        config.creep.elements_per_decade = 2;
        config.creep.percent_per_decade = gamma_percent;
        config.creep.first_time_constant_s = 0.001;
        config.creep.decades = 5;
        let mut stage = Stage::new(&config, 0).unwrap();
        let command = 3.0 + 5.0 * rng.random::<f64>();
        // Record the true position at t = 0.1, 0.316, 1, 3.16, 10 s after the step.
        let marks = [1_000usize, 3_162, 10_000, 31_623, 100_000];
        let mut at = Vec::new();
        let mut hysteresis_um = 0.0;
        for k in 1..=100_000usize {
            let s = stage.step_detailed(command);
            hysteresis_um = s.hysteresis_um;
            if marks.contains(&k) {
                at.push(s.true_position_um);
            }
        }
        // x(t) = x_h (1 + gamma log10(t / t0)) between 10 tau_min and tau_max / 10:
        // x(10 t) - x(t) = gamma x_h.
        let expected = gamma_percent / 100.0 * hysteresis_um;
        for (early, late) in [(0, 2), (1, 3), (2, 4)] {
            let per_decade = at[late] - at[early];
            assert!(
                (per_decade / expected - 1.0).abs() < 0.03,
                "{gamma_percent} %/decade: {per_decade} um vs {expected} um"
            );
        }
        // ...and the half-decade steps agree with a logarithm, not a line or an exponential.
        let half = (at[1] - at[0]) / (at[2] - at[1]);
        assert!((half - 1.0).abs() < 0.05, "{half}");
    }
}

#[test]
fn default_creep_after_a_step_follows_the_logarithmic_law() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    for _ in 0..3 {
        let mut config = StageConfig::default();
        let gamma_percent = 0.5 + 2.5 * rng.random::<f64>();
        config.creep.percent_per_decade = gamma_percent;
        config.creep.onset_time_s = 0.005 + 0.05 * rng.random::<f64>();
        config.mechanics.rigid = true;
        config.sensor.noise_rms_nm = 0.0;
        let mut stage = Stage::new(&config, 0).unwrap();
        let command = 3.0 + 5.0 * rng.random::<f64>();
        // The true position after the step against x_h (1 + gamma log10(1 + t / t0)), from
        // 0.3 s on (the slew-limited amplifier takes up to 9 ms to make the step).
        let marks = [3_162usize, 10_000, 31_623, 100_000];
        let t0 = config.creep.onset_time_s;
        let gamma = gamma_percent / 100.0;
        for k in 1..=100_000usize {
            let s = stage.step_detailed(command);
            if marks.contains(&k) {
                let t = k as f64 / config.sample_rate_hz;
                let expected = s.hysteresis_um * (1.0 + gamma * (1.0 + t / t0).log10());
                assert!(
                    (s.true_position_um - expected).abs() < 0.02 * gamma * s.hysteresis_um,
                    "t = {t} s: {} vs {expected} um",
                    s.true_position_um
                );
            }
        }
    }
}

/// Poles of the best affine second-order recurrence `x[k+2] = a x[k+1] + b x[k] + c` through
/// `x` (least squares; `c` absorbs the constant input): natural frequency (Hz) and damping ratio.
fn fitted_resonance(x: &[f64], period_s: f64) -> (f64, f64) {
    let mut m = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for w in x.windows(3) {
        let row = [w[1], w[0], 1.0];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += row[i] * row[j];
            }
            r[i] += row[i] * w[2];
        }
    }
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let solve = |col: usize| {
        let mut mc = m;
        for i in 0..3 {
            mc[i][col] = r[i];
        }
        det(&mc) / det(&m)
    };
    let (a, b) = (solve(0), solve(1));
    // z^2 - a z - b = 0: complex pair r e^(+-i theta), r^2 = -b, 2 r cos(theta) = a.
    let radius = (-b).sqrt();
    let theta = (a / (2.0 * radius)).acos();
    let sigma = -radius.ln() / period_s;
    let omega_d = theta / period_s;
    let omega_n = (sigma * sigma + omega_d * omega_d).sqrt();
    (omega_n / (2.0 * std::f64::consts::PI), sigma / omega_n)
}

#[test]
fn step_response_rings_at_the_configured_resonance_and_damping() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for _ in 0..4 {
        let mut config = without_creep(StageConfig::default());
        config.mechanics.resonance_hz = 300.0 + 1500.0 * rng.random::<f64>();
        config.mechanics.damping_ratio = 0.02 + 0.2 * rng.random::<f64>();
        // A fast amplifier without slew limit, so that the stack's displacement is a clean step
        // and what follows is the free ringing of the resonance.
        config.amplifier.bandwidth_hz = 100_000.0;
        config.amplifier.peak_current_ma = 1e9;
        let mut stage = Stage::new(&config, 0).unwrap();
        stage.step(0.0);
        let x: Vec<f64> = (0..400)
            .map(|_| stage.step_detailed(4.0).true_position_um)
            .collect();
        let (f0, z0) = (
            config.mechanics.resonance_hz,
            config.mechanics.damping_ratio,
        );
        // Fit while the ringing is well above rounding.
        let decay_samples = (1.0 / (z0 * 2.0 * std::f64::consts::PI * f0) * 10_000.0) as usize;
        let end = (3 + 8 * decay_samples).min(x.len());
        let (f, zeta) = fitted_resonance(&x[3..end], stage.period_s());
        assert!((f / f0 - 1.0).abs() < 1e-4, "{f} Hz vs {f0} Hz");
        assert!((zeta / z0 - 1.0).abs() < 1e-3, "{zeta} vs {z0}");
        // The overshoot of a second-order step response, exp(-pi zeta / sqrt(1 - zeta^2)).
        let settled = x[end - 1];
        let peak = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let overshoot = (peak - settled) / settled;
        let expected = (-std::f64::consts::PI * z0 / (1.0 - z0 * z0).sqrt()).exp();
        assert!(
            (overshoot / expected - 1.0).abs() < 0.1,
            "{overshoot} vs {expected}"
        );
    }
}

#[test]
fn measurement_noise_has_the_configured_statistics() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for seed in 0..3u64 {
        let mut config = without_creep(StageConfig::default());
        let sigma_nm = 1.0 + 19.0 * rng.random::<f64>();
        config.sensor.noise_rms_nm = sigma_nm;
        let mut stage = Stage::new(&config, seed).unwrap();
        for _ in 0..2_000 {
            stage.step(6.0);
        }
        let n = 50_000;
        let errors: Vec<f64> = (0..n)
            .map(|_| {
                let s = stage.step_detailed(6.0);
                (s.measured_position_um - s.true_position_um) * 1e3
            })
            .collect();
        let mean = errors.iter().sum::<f64>() / n as f64;
        let var = errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        // ADC: 20 V / 2^16 per code over 0.1 V/um = 3.05 nm, adding lsb^2 / 12.
        let lsb_nm = 20.0 / 65_536.0 / 0.1 * 1e3;
        let expected = (sigma_nm * sigma_nm + lsb_nm * lsb_nm / 12.0).sqrt();
        assert!(
            mean.abs() < 5.0 * expected / (n as f64).sqrt() + 0.05,
            "mean {mean} nm"
        );
        assert!(
            (var.sqrt() / expected - 1.0).abs() < 0.03,
            "{} vs {expected}",
            var.sqrt()
        );
        let lag1 = errors
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>()
            / (n as f64 * var);
        assert!(lag1.abs() < 0.02, "lag-1 autocorrelation {lag1}");
    }
}

#[test]
fn sensor_nonlinearity_bows_the_reading_by_the_configured_percentage() {
    let mut config = without_creep(StageConfig::default());
    config.sensor.noise_rms_nm = 0.0;
    config.sensor.nonlinearity_percent = 0.5;
    let mut stage = Stage::new(&config, 0).unwrap();
    let mut s = stage.step_detailed(0.0);
    // Find the command that puts the stage at mid full scale (50 um) roughly, then compare.
    for k in 0..60_000 {
        s = stage.step_detailed(9.0 * k as f64 / 60_000.0);
    }
    let x = s.true_position_um / 100.0;
    let expected = 0.005 * 100.0 * 4.0 * x * (1.0 - x);
    let lsb_um = 20.0 / 65_536.0 / 0.1;
    assert!(
        (s.measured_position_um - s.true_position_um - expected).abs() <= 0.5 * lsb_um + 1e-9,
        "{} vs {expected}",
        s.measured_position_um - s.true_position_um
    );
}

/// Points per volt of the sampled major branches.
const PER_VOLT: usize = 100;

/// Branches of the major loop (0 -> 150 -> 0 V) at `150 * PER_VOLT + 1` voltages.
fn major_branches(h: &mut impl RateIndependentHysteresis) -> (Vec<f64>, Vec<f64>) {
    let n = 150 * PER_VOLT;
    let volts = |i: usize| i as f64 / PER_VOLT as f64;
    let up: Vec<f64> = (0..=n).map(|i| h.displacement_um(volts(i))).collect();
    let mut down: Vec<f64> = (0..=n).rev().map(|i| h.displacement_um(volts(i))).collect();
    down.reverse();
    (up, down)
}

/// A sampled branch at any voltage (linear interpolation; the branches are smooth, so the
/// error is far below the tolerances used).
fn interpolate(branch: &[f64], v: f64) -> f64 {
    let x = v * PER_VOLT as f64;
    let i = (x.floor() as usize).min(branch.len() - 2);
    branch[i] + (branch[i + 1] - branch[i]) * (x - i as f64)
}

#[test]
fn closed_major_loops_preisach_minor_loops_inside_bouc_wen_minor_loops_stray_a_bounded_10_percent()
{
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for model in [HysteresisModel::Preisach, HysteresisModel::BoucWen] {
        let mut config = StageConfig::default();
        config.hysteresis.model = model;
        let mut h =
            hystcomp_stage::Hysteresis::from_config(&config.hysteresis, config.amplifier.gain)
                .unwrap();
        let (up, down) = major_branches(&mut h);
        // Closed: a second major cycle retraces the first.
        let (up2, down2) = major_branches(&mut h);
        let top = up.len() - 1;
        for i in 0..=top {
            assert!((up[i] - up2[i]).abs() < 1e-9 && (down[i] - down2[i]).abs() < 1e-9);
        }
        assert!(up[0].abs() < 1e-9 && (up[top] - down[top]).abs() < 1e-9);
        // A genuine loop: the descending branch lies above the ascending one.
        let width = (0..=top).map(|i| down[i] - up[i]).fold(0.0, f64::max);
        assert!(width > 0.05 * up[top], "{model:?}: width {width}");
        for i in 1..top {
            assert!(down[i] > up[i], "{model:?} at sample {i}");
        }
        // Minor loops between random voltages, entered from the ascending major branch, stay
        // within the major loop. The Preisach model's minor loops close after one cycle and
        // repeat exactly (return-point memory): three cycles, all within a tight bound (the
        // bilinear interpolation of the Everett table, far below a nanometre). The Bouc-Wen
        // model has no return-point memory and its loop region is not closed under reversals:
        // a curve rising from the descending branch where h > 0 rises with a slope larger by
        // 2 B h than the branch it left (B = Gamma), so it crosses the major loop, and likewise
        // for a curve falling from the ascending branch where h < 0; repeated minor loops drift
        // towards h = 0. This known artefact of the model is documented in STAGE.md. The issue
        // asks for minor loops inside the major loop: Bouc-Wen does not give that, and this test
        // says so instead of hiding it under a loose bound. It pins the size of the artefact for
        // the default set and these 30 seeded loops: 7.11 um (9.9 % of the stroke) is reached;
        // the bound is 11 % of the stroke, and a stray of at least 5 % must be seen (so that a
        // change of the model that removes or enlarges the artefact is noticed).
        let fresh = h.clone();
        let mut stray: f64 = 0.0;
        for _ in 0..30 {
            let a = 140.0 * rng.random::<f64>();
            let b = a + (150.0 - a) * rng.random::<f64>();
            let inside = |x: f64, v: f64, tolerance: f64| {
                let (low, high) = (interpolate(&up, v), interpolate(&down, v));
                assert!(
                    x >= low - tolerance && x <= high + tolerance,
                    "{model:?} loop {a}..{b} V at {v} V: {x} not in [{low}, {high}]"
                );
                (low - x).max(x - high)
            };
            let down_leg = || (0..=40).map(|k| b - (b - a) * k as f64 / 40.0);
            let up_leg = || (0..=40).map(|k| a + (b - a) * k as f64 / 40.0);
            // First-order reversal curves, from either major branch.
            let mut g = fresh.clone();
            g.reset();
            g.displacement_um(b);
            for v in down_leg() {
                let x = g.displacement_um(v);
                match model {
                    HysteresisModel::Preisach | HysteresisModel::Mpim => {
                        inside(x, v, 1e-4);
                    }
                    HysteresisModel::BoucWen => stray = stray.max(inside(x, v, 0.11 * up[top])),
                }
            }
            let mut g = fresh.clone();
            g.reset();
            g.displacement_um(150.0);
            g.displacement_um(a);
            for v in up_leg() {
                let x = g.displacement_um(v);
                match model {
                    HysteresisModel::Preisach | HysteresisModel::Mpim => {
                        inside(x, v, 1e-4);
                    }
                    HysteresisModel::BoucWen => stray = stray.max(inside(x, v, 0.11 * up[top])),
                }
            }
            // Cycled minor loops.
            let mut g = fresh.clone();
            g.reset();
            let at_b = g.displacement_um(b);
            for _ in 0..3 {
                for v in down_leg().chain(up_leg()) {
                    let x = g.displacement_um(v);
                    match model {
                        HysteresisModel::Preisach | HysteresisModel::Mpim => {
                            inside(x, v, 1e-4);
                        }
                        HysteresisModel::BoucWen => stray = stray.max(inside(x, v, 0.11 * up[top])),
                    }
                }
                if model == HysteresisModel::Preisach {
                    // Closed: back at b, the output is where the loop started.
                    assert!((g.displacement_um(b) - at_b).abs() < 1e-9);
                }
            }
        }
        if model == HysteresisModel::BoucWen {
            eprintln!("Bouc-Wen: cycled minor loops stray up to {stray} um outside the major loop");
            assert!(
                stray > 0.05 * up[top],
                "Bouc-Wen minor loops stray only {stray} um: update STAGE.md and this test"
            );
        }
    }
}

#[test]
fn non_finite_commands_hold_the_dac_and_never_give_nan() {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let clean = random_commands(&mut rng, 5_000);
    let mut dirty = clean.clone();
    let mut held = clean.clone();
    let mut spoiled = 0;
    for k in 1..dirty.len() {
        if rng.random::<f64>() < 0.02 {
            dirty[k] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][k % 3];
            held[k] = held[k - 1];
            spoiled += 1;
        }
    }
    let a = simulate(&StageConfig::default(), 5, &dirty).unwrap();
    let b = simulate(&StageConfig::default(), 5, &held).unwrap();
    assert_eq!(a.true_position_um, b.true_position_um);
    assert_eq!(a.measured_position_um, b.measured_position_um);
    assert_eq!(a.clamps.non_finite, spoiled);
    assert!(a.measured_position_um.iter().all(|x| x.is_finite()));
}

#[test]
fn wild_commands_are_clamped_counted_and_stay_finite() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let commands: Vec<f64> = (0..20_000)
        .map(|_| 1e3 * (rng.random::<f64>() - 0.5))
        .collect();
    let r = simulate(&StageConfig::default(), 1, &commands).unwrap();
    let outside_dac = commands.iter().filter(|c| c.abs() > 10.0).count() as u64;
    let outside_amp = commands
        .iter()
        .filter(|&&c| {
            let q = c.clamp(-10.0, 10.0);
            q < 0.0 || 15.0 * q > 150.0
        })
        .count() as u64;
    assert_eq!(r.clamps.dac_clamped, outside_dac);
    assert_eq!(r.clamps.amplifier_clamped, outside_amp);
    // The sensor's 100 um span holds the whole stroke: the ADC never saturates.
    assert_eq!(r.clamps.adc_clamped, 0);
    assert!(r.amplifier_v.iter().all(|v| (0.0..=150.0).contains(v)));
    assert!(r.true_position_um.iter().all(|x| x.is_finite()));
    assert!(r.measured_position_um.iter().all(|x| x.is_finite()));
}

#[test]
fn a_rigid_stage_has_no_resonance() {
    let mut config = StageConfig::default();
    config.mechanics.rigid = true;
    let mut rigid = Stage::new(&config, 1).unwrap();
    let mut flexible = Stage::new(&StageConfig::default(), 1).unwrap();
    let mut rang = false;
    for k in 0..2_000 {
        let command = if k < 10 { 0.0 } else { 5.0 };
        let r = rigid.step_detailed(command);
        assert_eq!(r.true_position_um, r.free_position_um, "sample {k}");
        let f = flexible.step_detailed(command);
        rang |= (f.true_position_um - f.free_position_um).abs() > 0.1;
    }
    assert!(
        rang,
        "the default stage rings after a step; the rigid one must not"
    );
}

#[test]
fn an_adc_span_below_the_stroke_saturates_the_reading_and_is_counted() {
    // 5 V at 0.1 V/um: the ADC reads at most 50 um of the 75 um stroke.
    let mut config = StageConfig::default();
    config.adc.max_v = 5.0;
    config.sensor.noise_rms_nm = 0.0;
    let ramp: Vec<f64> = (0..20_000).map(|k| 10.0 * k as f64 / 19_999.0).collect();
    let r = simulate(&config, 1, &ramp).unwrap();
    let above = r
        .true_position_um
        .iter()
        .filter(|&&x| x * 0.1 > 5.0)
        .count() as u64;
    assert!(above > 1000, "the ramp should pass 50 um: {above}");
    assert_eq!(r.clamps.adc_clamped, above);
    let top = r
        .measured_position_um
        .iter()
        .copied()
        .fold(f64::MIN, f64::max);
    assert!(top < 50.0 && top > 49.9, "saturated reading {top}");
}

#[test]
fn quasi_static_stroke_is_the_top_of_a_slow_ramp() {
    let config = StageConfig::default();
    let stroke = quasi_static_stroke_um(&config).unwrap();
    assert!((stroke - 75.0).abs() < 7.5, "{stroke}");
    // More creep, larger stroke; a stiffer reversible part does not change the top.
    let mut creepy = config.clone();
    creepy.creep.percent_per_decade = 3.0;
    assert!(quasi_static_stroke_um(&creepy).unwrap() > stroke);
    let no_creep = quasi_static_stroke_um(&without_creep(config.clone())).unwrap();
    assert!((no_creep - config.hysteresis.preisach.stroke_um).abs() < 0.01);
}

#[test]
fn response_time_axis_follows_the_sample_rate() {
    let config = StageConfig {
        sample_rate_hz: 5_000.0,
        ..StageConfig::default()
    };
    let mut stage = Stage::new(&config, 0).unwrap();
    let first = stage.run(&[1.0; 10]);
    let second = stage.run(&[1.0; 10]);
    for (k, t) in first.time_s.iter().chain(&second.time_s).enumerate() {
        assert!((t - k as f64 / 5_000.0).abs() < 1e-12);
    }
    assert_eq!(stage.samples(), 20);
}

/// Commands that reach every drive limit: holds, jumps across the whole range (slew), values
/// beyond the DAC's span and the rails, and NaN.
fn commands_at_the_limits(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    let mut x = 0.0;
    (0..n)
        .map(|_| {
            let u = rng.random::<f64>();
            x = if u < 0.02 {
                f64::NAN
            } else if u < 0.1 {
                // Jump anywhere in -15..15 V: beyond the DAC's +-10 V and, amplified, the rails.
                30.0 * rng.random::<f64>() - 15.0
            } else if u < 0.6 {
                x
            } else {
                let step = 0.2 * (rng.random::<f64>() - 0.5);
                if x.is_finite() { x + step } else { step }
            };
            x
        })
        .collect()
}

#[test]
fn each_sample_at_a_drive_limit_counts_once_and_the_prediction_agrees_with_the_stage() {
    // Reference: step the stage sample by sample and count the samples in which any of the
    // DAC, rail or slew counters rose.
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let config = StageConfig::default();
    let mut several = 0;
    for case in 0..12 {
        let commands = commands_at_the_limits(&mut rng, 2_000 + 500 * case);
        let mut stage = Stage::new(&config, case as u64).unwrap();
        let mut reference = 0u64;
        let mut at_two = 0u64;
        for &c in &commands {
            let before = stage.clamps();
            stage.step(c);
            let after = stage.clamps();
            let rose = [
                after.dac_clamped > before.dac_clamped,
                after.amplifier_clamped > before.amplifier_clamped,
                after.slew_limited > before.slew_limited,
            ];
            let n = rose.iter().filter(|&&r| r).count() as u64;
            reference += u64::from(n > 0);
            at_two += u64::from(n > 1);
            assert_eq!(
                after.limited - before.limited,
                u64::from(n > 0),
                "case {case}: a sample counts once"
            );
        }
        assert_eq!(stage.clamps().limited, reference, "case {case}");
        several += u64::from(at_two > 0);
        // The whole-signal run and the prediction from the command alone count the same.
        let response = simulate(&config, case as u64, &commands).unwrap();
        assert_eq!(response.clamps.limited, reference, "case {case}");
        let predicted = hystcomp_stage::feasibility(&config, &commands).unwrap();
        assert_eq!(predicted.limited_samples() as u64, reference, "case {case}");
        assert_eq!(predicted.slew_limited as u64, response.clamps.slew_limited);
        assert_eq!(
            predicted.rail_limited as u64,
            response.clamps.amplifier_clamped
        );
        assert_eq!(predicted.dac_limited as u64, response.clamps.dac_clamped);
        assert!(predicted.limited_share() <= 1.0);
    }
    // The property means something only if some samples reach two limits at once.
    assert!(several > 0, "no case reached two limits in one sample");
}
