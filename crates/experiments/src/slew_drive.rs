//! A drive for a known trajectory that the amplifier can deliver: the chain's offline inverse
//! with the amplifier's slew limit as a constraint (issue 11 §3, feasibility).
//!
//! The faithful inverse `v = H^-1[C^-1[D^-1[y_d]]]` of a fast scan can ask more slew than the
//! amplifier has (the 20 um raster at 100 Hz: about three times the built-in amplifier's
//! 14.3 kV/s at its corners); the amplifier then slews at its current limit and the stage
//! rings. Here the drive is chosen instead so that the model's output is as close as it can be
//! to `y_d` in the least-squares sense while every step of the drive stays within what the
//! amplifier follows linearly:
//!
//! - `x`, the input of the vibration link `D` (the hysteresis and creep links' output), is the
//!   variable of a quadratic programme: minimise `sum_k (D[x]_k - y_d,k)^2` (plus a vanishing
//!   `1e-6 sum_k (x_k - x*_k)^2` for the samples `D` does not see, its delay) subject to
//!   `|x_k - x_(k-1)| <= s_k R`, with `D` written as its difference equation (sparse equality
//!   rows), `R` the largest drive step per sample and `s_k` the local slope `dx/dv` of the
//!   hysteresis and creep links along the drive (the slew bound mapped through them);
//! - the drive is `v = H^-1[C^-1[x]]` (the exact IHC or WIHC with the creep inverse), the slopes
//!   are re-measured along it and the programme solved again ([`SLOPE_PASSES`] in all); a final
//!   causal clamp keeps every step within `R` whatever the linearisation left.
//!
//! Only where the faithful drive is infeasible: the programme covers the record from
//! [`LEAD_SAMPLES`] before its first too-large step to its end; before that the drive is the
//! faithful one. The programme is solved by Clarabel (Goulart & Chen 2024, arXiv:2405.12762).
//! This is the slew-constrained optimal-inversion idea of preview-based feedforward (Zou &
//! Devasia 2004, doi:10.1109/TCST.2004.824339) as a convex programme on a known trajectory.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
    ZeroConeT,
};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::ModelFile;

/// How many times the slopes are measured and the programme solved.
pub const SLOPE_PASSES: usize = 3;
/// Samples before the first too-large step where the programme starts (20 ms at 10 kHz:
/// longer than the identified resonance's ring-down needs to prepare a corner).
pub const LEAD_SAMPLES: usize = 200;
/// The longest stretch the programme covers, samples (bounded before allocating).
pub const MAX_PROGRAMME_SAMPLES: usize = 50_000;

/// The drive and what it took.
#[derive(Debug, Clone)]
pub struct SlewDrive {
    /// The drive, V, one per desired sample.
    pub drive: Vec<f64>,
    /// Steps of the faithful drive larger than `R`.
    pub faithful_violations: usize,
    /// Whether the programme was solved (false: the faithful drive was feasible).
    pub constrained: bool,
    /// The model's predicted RMS error of the returned drive against `y_d`, um (whole record).
    pub predicted_rms_um: f64,
}

fn error(what: impl std::fmt::Display) -> String {
    format!("slew-constrained drive: {what}")
}

fn run(c: &mut ScaledCompensator, desired: &[f64]) -> Result<Vec<f64>, String> {
    c.reset();
    let mut out = vec![0.0; desired.len()];
    c.process(desired, &mut out).map_err(error)?;
    Ok(out)
}

/// Local slopes `dx/dv` along `(x, v)`: the ratio of steps where the drive moves, carried over
/// where it does not, and kept within a factor of 4 of their median.
fn slopes(x: &[f64], v: &[f64]) -> Vec<f64> {
    let n = x.len();
    let scale = v.iter().fold(0.0f64, |m, a| m.max(a.abs())).max(1e-12);
    let mut s = vec![f64::NAN; n];
    for k in 1..n {
        let dv = v[k] - v[k - 1];
        if dv.abs() > 1e-6 * scale {
            let r = (x[k] - x[k - 1]) / dv;
            if r.is_finite() && r > 0.0 {
                s[k] = r;
            }
        }
    }
    let mut valid: Vec<f64> = s.iter().copied().filter(|r| r.is_finite()).collect();
    if valid.is_empty() {
        return vec![1.0; n];
    }
    valid.sort_by(f64::total_cmp);
    let median = valid[valid.len() / 2];
    let mut last = median;
    for r in s.iter_mut() {
        if r.is_finite() {
            *r = r.clamp(0.25 * median, 4.0 * median);
            last = *r;
        } else {
            *r = last;
        }
    }
    s
}

/// The largest-step violations of `v` beyond `max_step` (from sample 1).
fn violations(v: &[f64], max_step: f64) -> usize {
    v.windows(2)
        .filter(|w| (w[1] - w[0]).abs() > max_step * (1.0 + 1e-9))
        .count()
}

/// The drive for `desired` (um, at the model's sample rate) through the plant chain `model`
/// with `method` (IHC or WIHC) within `limits` (V), every step at most `max_step_v` (see the
/// [module documentation](self)). A model without a vibration link, or a faithful drive
/// already within the bound, gives the faithful drive.
pub fn slew_constrained_drive(
    model: &ModelFile,
    method: Method,
    limits: (f64, f64),
    desired: &[f64],
    max_step_v: f64,
) -> Result<SlewDrive, String> {
    if !(max_step_v.is_finite() && max_step_v > 0.0) {
        return Err(error(format!(
            "the largest drive step {max_step_v} V must be positive"
        )));
    }
    let mut faithful = ScaledCompensator::new(model, method, Some(limits)).map_err(error)?;
    let v_star = run(&mut faithful, desired)?;
    let predicted = |v: &[f64]| -> Result<f64, String> {
        let y = model.predict(v).map_err(error)?;
        Ok((y
            .iter()
            .zip(desired)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / desired.len().max(1) as f64)
            .sqrt())
    };
    let faithful_violations = violations(&v_star, max_step_v);
    let (Some(vibration), Some(rate)) = (&model.vibration, model.sample_rate_hz) else {
        return Ok(SlewDrive {
            predicted_rms_um: predicted(&v_star)?,
            drive: v_star,
            faithful_violations,
            constrained: false,
        });
    };
    if faithful_violations == 0 {
        return Ok(SlewDrive {
            predicted_rms_um: predicted(&v_star)?,
            drive: v_star,
            faithful_violations,
            constrained: false,
        });
    }
    let n = desired.len();
    let first = v_star
        .windows(2)
        .position(|w| (w[1] - w[0]).abs() > max_step_v)
        .unwrap_or(0)
        + 1;
    let k0 = first.saturating_sub(LEAD_SAMPLES).max(1);
    let m = n - k0;
    if m > MAX_PROGRAMME_SAMPLES {
        return Err(error(format!(
            "the programme would cover {m} samples, more than {MAX_PROGRAMME_SAMPLES}; \
             split the trajectory"
        )));
    }
    // x* = D^-1[y_d], and the hysteresis-and-creep chain that maps x to v.
    let mut inverse = vibration
        .inverse(vibration.needed_preview().map_err(error)?)
        .map_err(error)?;
    let mut x_star = vec![0.0; n];
    inverse
        .process_aligned(desired, &mut x_star)
        .map_err(error)?;
    let hc_model = model
        .clone()
        .with_links(rate, model.creep.clone(), None)
        .map_err(error)?;
    let mut hc = ScaledCompensator::new(&hc_model, method, Some(limits)).map_err(error)?;
    // D[x*] before the programme: the history its difference equation starts from.
    let mut forward = vibration.link().map_err(error)?;
    let y_hist: Vec<f64> = x_star[..k0].iter().map(|&x| forward.step(x)).collect();
    let b = &vibration.numerator;
    let a = &vibration.denominator;
    let d = vibration.delay_samples;
    // The value of x or y at an absolute index before the programme (at rest before 0).
    let x_known = |k: isize| x_star[k.max(0) as usize];
    let y_known = |k: isize| {
        if k < 0 { x_star[0] } else { y_hist[k as usize] }
    };

    let mut x = x_star.clone();
    let mut v = v_star.clone();
    for _ in 0..SLOPE_PASSES {
        let s = slopes(&x, &v);
        // Variables: x_k0..x_n-1 (0..m), then y_k0..y_n-1 (m..2m).
        let (mut pi, mut pj, mut pv) = (Vec::new(), Vec::new(), Vec::new());
        let mut q = vec![0.0; 2 * m];
        const EPS: f64 = 1e-6;
        for i in 0..m {
            pi.push(i);
            pj.push(i);
            pv.push(EPS);
            q[i] = -EPS * x_star[k0 + i];
            pi.push(m + i);
            pj.push(m + i);
            pv.push(1.0);
            q[m + i] = -desired[k0 + i];
        }
        let big_p = CscMatrix::new_from_triplets(2 * m, 2 * m, pi, pj, pv);
        let (mut ai, mut aj, mut av) = (Vec::new(), Vec::new(), Vec::new());
        let mut rhs = Vec::with_capacity(3 * m);
        // D's difference equation: y_k + sum a_i y_(k-i) - sum b_j x_(k-d-j) = 0.
        for i in 0..m {
            let k = (k0 + i) as isize;
            let row = rhs.len();
            let mut known = 0.0;
            ai.push(row);
            aj.push(m + i);
            av.push(1.0);
            for (l, coefficient) in a.iter().enumerate().skip(1) {
                let at = k - l as isize;
                if at >= k0 as isize {
                    ai.push(row);
                    aj.push(m + (at as usize - k0));
                    av.push(*coefficient);
                } else {
                    known -= coefficient * y_known(at);
                }
            }
            for (l, coefficient) in b.iter().enumerate() {
                let at = k - (d + l) as isize;
                if at >= k0 as isize {
                    ai.push(row);
                    aj.push(at as usize - k0);
                    av.push(-coefficient);
                } else {
                    known += coefficient * x_known(at);
                }
            }
            rhs.push(known);
        }
        // |x_k - x_(k-1)| <= s_k R.
        for i in 0..m {
            let k = k0 + i;
            let bound = s[k].min(s[(k + 1).min(n - 1)]) * max_step_v;
            for sign in [1.0, -1.0] {
                let row = rhs.len();
                ai.push(row);
                aj.push(i);
                av.push(sign);
                let mut limit = bound;
                if i > 0 {
                    ai.push(row);
                    aj.push(i - 1);
                    av.push(-sign);
                } else {
                    limit += sign * x[k0 - 1];
                }
                rhs.push(limit);
            }
        }
        let big_a = CscMatrix::new_from_triplets(rhs.len(), 2 * m, ai, aj, av);
        let cones: [SupportedConeT<f64>; 2] = [ZeroConeT(m), NonnegativeConeT(2 * m)];
        let settings = DefaultSettings {
            verbose: false,
            max_iter: 200,
            ..DefaultSettings::default()
        };
        let mut solver = DefaultSolver::new(&big_p, &q, &big_a, &rhs, &cones, settings)
            .map_err(|e| error(e.to_string()))?;
        solver.solve();
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {}
            other => return Err(error(format!("Clarabel stopped with status {other:?}"))),
        }
        x[k0..].copy_from_slice(&solver.solution.x[..m]);
        v = run(&mut hc, &x)?;
        if violations(&v, max_step_v) == 0 {
            break;
        }
    }
    // Whatever the slopes' linearisation left: a causal clamp of every step.
    for k in 1..n {
        let step = (v[k] - v[k - 1]).clamp(-max_step_v, max_step_v);
        v[k] = (v[k - 1] + step).clamp(limits.0, limits.1);
    }
    Ok(SlewDrive {
        predicted_rms_um: predicted(&v)?,
        drive: v,
        faithful_violations,
        constrained: true,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::signals::{Raster, Shape, Signal};
    use hystcomp_io::model_file::VibrationPart;

    const FS: f64 = 10_000.0;

    /// Table 1's MPIM with a lightly damped 800 Hz mode (zero-order-hold sampled, unit static
    /// gain) and a one-sample delay.
    pub(crate) fn chain() -> ModelFile {
        let base = ModelFile::load(std::path::Path::new("../../models/table1-plant.json")).unwrap();
        let (f, zeta): (f64, f64) = (800.0, 0.03);
        let w = 2.0 * std::f64::consts::PI * f;
        let t = 1.0 / FS;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let r = (-zeta * w * t).exp();
        let (s, c, k) = ((wd * t).sin(), (wd * t).cos(), zeta * w / wd);
        let b = vec![1.0 - r * (c + k * s), r * r + r * (k * s - c)];
        let a = vec![1.0, -2.0 * r * c, r * r];
        base.with_links(
            FS,
            None,
            Some(VibrationPart {
                delay_samples: 1,
                numerator: b,
                denominator: a,
            }),
        )
        .unwrap()
    }

    /// A rounded triangle raster from rest (short lead-in: 0.1 s ramp, 0.1 s rest).
    fn raster(rate: f64, amplitude: f64, offset: f64) -> Vec<f64> {
        let scan = Signal {
            shape: Shape::Raster(Raster::triangle(rate, 0.05)),
            amplitude,
            offset,
            duration_s: 4.0 / rate,
            speed: 1.0,
            sample_rate_hz: FS,
        }
        .sample()
        .unwrap();
        let first = scan[0];
        let mut out: Vec<f64> = (1..=1000)
            .map(|k| first * 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / 1000.0).cos()))
            .collect();
        out.extend(std::iter::repeat_n(first, 1000));
        out.extend(scan);
        out
    }

    fn peak_step(v: &[f64]) -> f64 {
        v.windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max)
    }

    fn rms_error(model: &ModelFile, drive: &[f64], desired: &[f64]) -> f64 {
        let y = model.predict(drive).unwrap();
        (y.iter()
            .zip(desired)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / desired.len() as f64)
            .sqrt()
    }

    #[test]
    fn constrained_drives_keep_every_step_and_beat_the_clamped_faithful_drive() {
        let model = chain();
        let limits = (0.0, 10.0);
        for (rate, amplitude, offset, share) in [
            (100.0, 10.0, 37.5, 0.6),
            (130.0, 6.0, 30.0, 0.7),
            (80.0, 12.0, 40.0, 0.5),
        ] {
            let desired = raster(rate, amplitude, offset);
            let mut faithful = ScaledCompensator::new(&model, Method::Ihc, Some(limits)).unwrap();
            let mut v_star = vec![0.0; desired.len()];
            faithful.process(&desired, &mut v_star).unwrap();
            let max_step = share * peak_step(&v_star);
            let drive =
                slew_constrained_drive(&model, Method::Ihc, limits, &desired, max_step).unwrap();
            assert!(drive.constrained && drive.faithful_violations > 0);
            assert_eq!(drive.drive.len(), desired.len());
            for (k, w) in drive.drive.windows(2).enumerate() {
                assert!(
                    (w[1] - w[0]).abs() <= max_step * (1.0 + 1e-9),
                    "{rate} Hz, sample {k}: step {} > {max_step}",
                    w[1] - w[0]
                );
            }
            assert!(
                drive
                    .drive
                    .iter()
                    .all(|v| v.is_finite() && (limits.0..=limits.1).contains(v))
            );
            // The plain reference: the faithful drive with each step clamped, as a slewing
            // amplifier would make of it.
            let mut clamped = v_star.clone();
            for k in 1..clamped.len() {
                clamped[k] =
                    clamped[k - 1] + (v_star[k] - clamped[k - 1]).clamp(-max_step, max_step);
            }
            let reference = rms_error(&model, &clamped, &desired);
            let ours = rms_error(&model, &drive.drive, &desired);
            assert!((ours - drive.predicted_rms_um).abs() < 1e-9);
            assert!(
                ours < 0.5 * reference,
                "{rate} Hz: {ours} um vs clamped faithful {reference} um"
            );
        }
    }

    #[test]
    fn a_feasible_faithful_drive_is_returned_as_it_is_and_bad_bounds_are_refused() {
        let model = chain();
        let desired = raster(50.0, 5.0, 37.5);
        let mut faithful = ScaledCompensator::new(&model, Method::Ihc, Some((0.0, 10.0))).unwrap();
        let mut v_star = vec![0.0; desired.len()];
        faithful.process(&desired, &mut v_star).unwrap();
        let drive = slew_constrained_drive(
            &model,
            Method::Ihc,
            (0.0, 10.0),
            &desired,
            1.5 * peak_step(&v_star),
        )
        .unwrap();
        assert!(!drive.constrained);
        assert_eq!(drive.faithful_violations, 0);
        assert_eq!(drive.drive, v_star);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(
                slew_constrained_drive(&model, Method::Ihc, (0.0, 10.0), &desired, bad).is_err()
            );
        }
    }
}
