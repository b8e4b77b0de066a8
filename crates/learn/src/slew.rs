//! The slew-feasible drive: the Euclidean projection of a drive onto the drives the amplifier
//! follows linearly (every step within a largest step `R`, every sample within the limits).
//!
//! # Why the learner projects its drive
//! A learned drive that asks more slew than the amplifier has is clipped by the amplifier, not
//! by the learner: the stage then answers a different drive than the one the update assumed,
//! the learned reference winds up where the amplifier clips (the error there does not move,
//! so the correction keeps growing), and the learning, linear between trials, crawls. The
//! constrained-ILC remedy is to keep every trial's input inside the input constraint set by
//! a projection and to learn from the input actually applied: "successive projection" ILC
//! (B. Chu, D. H. Owens, "Iterative learning control for constrained linear systems",
//! Int. J. Control 83(7) (2010) 1397-1413, doi:10.1080/00207179.2010.483691) and the
//! optimisation-based constrained ILC of S. Mishra, U. Topcu, M. Tomizuka ("Optimization-based
//! constrained iterative learning control", IEEE Trans. Control Syst. Technol. 19(6) (2011)
//! 1613-1621, doi:10.1109/TCST.2010.2095503), whose constraint sets include rate bounds.
//! With [`crate::LearningOptions::max_drive_step`] the learner's drive is the projection of
//! `C[r]` onto that set, and its reference, the learner's state, is the model run forward
//! over the projected drive (`r = P[v]`, as [`crate::Learner::resume`] recovers it): the
//! correction the amplifier could not follow is dropped instead of accumulated, the
//! anti-windup the reference's clamp into the reachable range already is for the rails.
//!
//! # The projection
//! `min_v sum_k (v_k - w_k)^2` subject to `|v_k - v_(k-1)| <= R` (and, for a periodic record,
//! `|v_0 - v_(n-1)| <= R`: the drive is played period after period) and `lo <= v_k <= hi`.
//! The set is the intersection of a few sets each of which is a product of independent
//! constraints on disjoint pairs (the steps from an even sample, the steps from an odd one,
//! the wrap-around step when it shares a sample with both) and the box; the projection onto
//! each is closed-form, and Dykstra's alternating projection algorithm (J. P. Boyle,
//! R. L. Dykstra, "A method for finding projections onto the intersection of convex sets in
//! Hilbert spaces", Lecture Notes in Statistics 37 (1986) 28-47,
//! doi:10.1007/978-1-4613-9940-7_3) converges to the projection onto their intersection. A
//! drive already in the set is returned unchanged. A last causal pass keeps every step within
//! `R` and every sample within the limits whatever the iteration left (the wrap-around step
//! of a periodic record then within `R` to the iteration's tolerance).

/// The most sweeps of Dykstra's algorithm.
pub const MAX_SWEEPS: usize = 20_000;
/// Stop when no sample moved by more than this times `R` in a sweep and no step exceeds `R`
/// by more than it.
pub const TOLERANCE: f64 = 1e-10;

/// The most rounds of the final causal pass over a periodic record.
pub const CYCLIC_PASSES: usize = 4;

/// A projected drive and what it took.
#[derive(Debug, Clone, PartialEq)]
pub struct SlewProjection {
    /// The drive, within the limits, every step within `R`.
    pub drive: Vec<f64>,
    /// Steps of the input larger than `R` (0: returned unchanged).
    pub violations: usize,
    /// Dykstra sweeps made.
    pub sweeps: usize,
}

/// The steps of `v` (with the wrap-around step if `periodic`) larger than `max_step`.
pub fn slew_violations(v: &[f64], max_step: f64, periodic: bool) -> usize {
    let inner = v
        .windows(2)
        .filter(|w| (w[1] - w[0]).abs() > max_step)
        .count();
    let wrap = periodic && v.len() > 1 && (v[0] - v[v.len() - 1]).abs() > max_step;
    inner + usize::from(wrap)
}

/// Projects the pair `(a, b)` onto `|b - a| <= r`.
fn pair(v: &mut [f64], a: usize, b: usize, r: f64) {
    let d = v[b] - v[a];
    if d > r {
        let s = 0.5 * (d - r);
        v[a] += s;
        v[b] -= s;
    } else if d < -r {
        let s = 0.5 * (-d - r);
        v[a] -= s;
        v[b] += s;
    }
}

/// The Euclidean projection of `drive` onto the drives within `limits` whose every step
/// (and, if `periodic`, the step from the last sample back to the first) is at most
/// `max_step` (see the [module documentation](self)). `max_step` must be positive and finite,
/// `limits` finite and ordered, `drive` finite (the learner checks them).
pub fn project_slew(
    drive: &[f64],
    max_step: f64,
    limits: (f64, f64),
    periodic: bool,
) -> SlewProjection {
    let n = drive.len();
    let (lo, hi) = limits;
    let clamped: Vec<f64> = drive.iter().map(|v| v.clamp(lo, hi)).collect();
    let violations = slew_violations(&clamped, max_step, periodic);
    if violations == 0 || n < 2 {
        return SlewProjection {
            drive: clamped,
            violations,
            sweeps: 0,
        };
    }
    // The pair sets: steps (k, k+1) from even k, from odd k, and the wrap-around step (n-1, 0)
    // of a periodic record (with the odd steps when n is even: it then shares no sample with
    // them; alone when n is odd).
    let wrap = periodic && n > 2;
    let sets = if wrap && !n.is_multiple_of(2) { 4 } else { 3 };
    let project = |set: usize, v: &mut [f64]| match set {
        0 => (0..n - 1)
            .step_by(2)
            .for_each(|k| pair(v, k, k + 1, max_step)),
        1 => {
            (1..n - 1)
                .step_by(2)
                .for_each(|k| pair(v, k, k + 1, max_step));
            if wrap && n.is_multiple_of(2) {
                pair(v, n - 1, 0, max_step);
            }
        }
        s if s == sets - 1 => v.iter_mut().for_each(|x| *x = x.clamp(lo, hi)),
        _ => pair(v, n - 1, 0, max_step),
    };
    let mut x = drive.to_vec();
    let mut increments = vec![vec![0.0; n]; sets];
    let mut y = vec![0.0; n];
    let tolerance = TOLERANCE * max_step;
    let mut sweeps = 0;
    while sweeps < MAX_SWEEPS {
        sweeps += 1;
        let mut moved = 0.0f64;
        for (set, p) in increments.iter_mut().enumerate() {
            for k in 0..n {
                y[k] = x[k] + p[k];
            }
            project(set, &mut y);
            for k in 0..n {
                let before = x[k] + p[k];
                p[k] = before - y[k];
                moved = moved.max((y[k] - x[k]).abs());
                x[k] = y[k];
            }
        }
        let excess = x
            .windows(2)
            .map(|w| (w[1] - w[0]).abs() - max_step)
            .chain(wrap.then(|| (x[0] - x[n - 1]).abs() - max_step))
            .fold(0.0f64, f64::max);
        if moved <= tolerance && excess <= tolerance {
            break;
        }
    }
    // The causal pass: every step within R and every sample within the limits, exactly; a
    // periodic record goes round again (up to [`CYCLIC_PASSES`] times) for its wrap-around step.
    x[0] = x[0].clamp(lo, hi);
    for pass in 0..if wrap { CYCLIC_PASSES } else { 1 } {
        for k in usize::from(pass == 0)..n {
            let prev = x[(k + n - 1) % n];
            let (a, b) = ((prev - max_step).max(lo), (prev + max_step).min(hi));
            x[k] = x[k].clamp(a, b);
        }
        if !wrap || (x[0] - x[n - 1]).abs() <= max_step {
            break;
        }
    }
    SlewProjection {
        drive: x,
        violations,
        sweeps,
    }
}
