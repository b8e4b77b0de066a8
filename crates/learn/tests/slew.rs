//! The slew-feasible projection (`hystcomp_learn::slew`) against its definition on seeded
//! random drives, and the learner's drive kept within the largest step when asked.

use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::slew::{project_slew, slew_violations};
use hystcomp_learn::{Learner, LearningOptions};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn steps_within(v: &[f64], r: f64, periodic: bool, slack: f64) -> bool {
    slew_violations(v, r * (1.0 + slack), periodic) == 0
}

/// A random point of the set: a random walk of steps within `r`, inside the limits, and (for a
/// periodic record) closed within `r`.
fn feasible(
    rng: &mut ChaCha8Rng,
    n: usize,
    r: f64,
    limits: (f64, f64),
    periodic: bool,
) -> Vec<f64> {
    loop {
        let mut v = vec![rng.random_range(limits.0..limits.1)];
        for _ in 1..n {
            let last = v[v.len() - 1];
            let lo = (last - r).max(limits.0);
            let hi = (last + r).min(limits.1);
            v.push(rng.random_range(lo..=hi));
        }
        if steps_within(&v, r, periodic, 0.0) {
            return v;
        }
    }
}

/// Projection onto a closed convex set `K` is characterised by `(w - p) . (u - p) <= 0` for
/// every `u` in `K` (the variational inequality); checked against random points of `K`, with
/// the projection feasible and a feasible input returned unchanged.
#[test]
fn the_projection_is_the_nearest_feasible_drive() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for case in 0..200usize {
        let n = rng.random_range(2..40usize);
        let periodic = case.is_multiple_of(2);
        let r = rng.random_range(0.05..0.5);
        let limits = (-1.0, 1.0);
        let w: Vec<f64> = (0..n).map(|_| rng.random_range(-1.5..1.5)).collect();
        let p = project_slew(&w, r, limits, periodic);
        assert!(
            steps_within(&p.drive, r, periodic, 1e-6),
            "case {case}: {p:?}"
        );
        assert!(p.drive.iter().all(|v| (limits.0..=limits.1).contains(v)));
        let scale: f64 = w.iter().map(|x| x * x).sum::<f64>().max(1.0);
        for _ in 0..50 {
            let u = feasible(&mut rng, n, r, limits, periodic);
            let vi: f64 = w
                .iter()
                .zip(&p.drive)
                .zip(&u)
                .map(|((w, p), u)| (w - p) * (u - p))
                .sum();
            assert!(vi <= 1e-6 * scale, "case {case}: (w - p).(u - p) = {vi}");
        }
        // Feasible input: unchanged.
        let u = feasible(&mut rng, n, r, limits, periodic);
        assert_eq!(project_slew(&u, r, limits, periodic).drive, u);
    }
}

/// Two samples: the projection splits the excess step evenly (closed form).
#[test]
fn two_samples_meet_halfway() {
    let p = project_slew(&[0.0, 1.0], 0.2, (-5.0, 5.0), false);
    assert!((p.drive[0] - 0.4).abs() < 1e-9 && (p.drive[1] - 0.6).abs() < 1e-9);
    assert_eq!(p.violations, 1);
}

/// The learner with a largest drive step: every drive within it (wrap-around included) and the
/// limits, never NaN, trial after trial on a plant the model gets wrong; without it, the same
/// record asks more.
#[test]
fn the_learned_drive_stays_within_the_slew_bound() {
    let model = ModelFile::load(std::path::Path::new("../../models/table1-plant.json")).unwrap();
    let n = 1000;
    // A triangle with sharp corners: its exact inverse steps hardest at the reversals.
    let desired: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 / n as f64;
            35.0 + 40.0 * (if t < 0.5 { t } else { 1.0 - t })
        })
        .collect();
    let mut plant = model.clone();
    plant.output.scale *= 0.93;
    let free = Learner::new(&model, &desired, LearningOptions::new(1000.0)).unwrap();
    let largest = free
        .drive()
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0f64, f64::max);
    let r = 0.8 * largest;
    let mut options = LearningOptions::new(1000.0);
    options.max_drive_step = Some(r);
    let mut learner = Learner::new(&model, &desired, options).unwrap();
    assert_eq!(learner.law().max_drive_step, Some(r));
    let mut e = Vec::new();
    for _ in 0..8 {
        let drive = learner.drive().to_vec();
        assert!(drive.iter().all(|v| v.is_finite()));
        assert!(steps_within(&drive, r, true, 1e-6));
        let (lo, hi) = learner.law().limits;
        assert!(drive.iter().all(|v| (lo..=hi).contains(v)));
        let three: Vec<f64> = drive.iter().chain(&drive).chain(&drive).copied().collect();
        let measured = plant.predict(&three).unwrap()[n..2 * n].to_vec();
        e.push(learner.update(&measured).unwrap().indices.e_rms_percent);
    }
    // It still learns what the slew bound leaves to learn.
    assert!(e[7] < 0.5 * e[0], "{e:?}");
}

#[test]
fn a_bad_largest_step_is_refused() {
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut o = LearningOptions::new(1000.0);
        o.max_drive_step = Some(bad);
        assert!(
            o.validate()
                .unwrap_err()
                .to_string()
                .contains("largest drive step")
        );
    }
}
