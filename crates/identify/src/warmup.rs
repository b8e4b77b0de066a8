//! Where the play operators' memory at the start of a record comes from (issue 10).
//!
//! A record may start anywhere: the device's operators then hold a memory left by a history
//! nobody recorded. Two facts make it manageable.
//!
//! - **Wiping-out.** A one-sided play operator (eq. (2)) always holds a memory `w` with
//!   `x - r <= w <= x`, and from any history within the input range `[lo, hi]`,
//!   `w <= hi - r`. At the input's minimum every memory is therefore `lo` (0 when normalised:
//!   the reset state of eq. (1)) and at its maximum `hi - r`, whatever came before. From the
//!   first sample where the voltage reaches the record's minimum **or** maximum on (within
//!   [`MEMORY_TOLERANCE`]), every operator's memory is fixed by the record itself (to within
//!   that tolerance), provided the unknown history stayed within the record's range (the
//!   bound assumed throughout). [`crate::Warmup::Auto`] ends the warm-up there.
//! - **A one-parameter family of histories.** Before that sample the memory is an unknown
//!   within those bounds. [`crate::Warmup::Estimate`] parameterises it by a virtual history before the
//!   first sample: the input came from one end of the range to a turning point `v0` and then
//!   to the first sample `x0`, rising (`hi -> v0 -> x0` with `v0 <= x0`) or falling
//!   (`lo -> v0 -> x0` with `v0 >= x0`). The family holds the reset state of eq. (1) (rising
//!   from the minimum, `v0 = lo`), the state of a fall from the maximum (`v0 = hi`) and every
//!   state of a last reversal in between; its memories respect the operators' ordering by
//!   construction. For each candidate `v0` the model stays linear in its parameters, so the
//!   fit is one least-squares problem: a grid of `v0` on both branches, then a golden-section
//!   refinement around the best, each scored by its constrained least-squares optimum.

use crate::identification::min_max;
use crate::{FitProblem, IdentifyError, LeastSquares, NoObserver, ProblemData, Solver};

/// How close (a fraction of the record's voltage range) the voltage must come to the record's
/// minimum or maximum for the operators' memory to count as known: each operator's memory is
/// then within this distance of its value for any history within the range (at `x` within `d`
/// of the minimum every memory lies in `[lo, x]`, near the maximum in `[x - r, hi - r]`). 1 %
/// lets a record whose cycles peak a little differently count, without the 5 % band of the
/// old heuristic, which on a real +-150 V record doubled the fit error.
pub const MEMORY_TOLERANCE: f64 = 0.01;

/// Candidates of the turning point `v0` per branch of the virtual history (plus the ends).
pub const HISTORY_GRID: usize = 16;

/// Golden-section steps refining the best candidate of the grid.
pub const HISTORY_REFINEMENT_STEPS: usize = 12;

/// The first sample (0-based) where `voltage` comes within [`MEMORY_TOLERANCE`] of the
/// record's minimum or maximum: from there on every operator's memory is determined by the
/// record (wiping-out, see the [module documentation](self)), to within that tolerance. The voltage decides in both directions: it drives the
/// device's state and is clean, while a displacement record may start with a transient.
pub(crate) fn memory_known_from(voltage: &[f64]) -> usize {
    let (lo, hi) = min_max(voltage);
    let band = MEMORY_TOLERANCE * (hi - lo);
    voltage
        .iter()
        .position(|&v| v - lo <= band || hi - v <= band)
        .unwrap_or(0)
}

/// The virtual history (normalised model inputs, run from zero memory before the first
/// sample) for the turning point `v0`: `[lo, hi, v0]` when `v0 <= x0` (down from the maximum
/// to `v0`, then up to `x0`), `[hi, lo, v0]` otherwise (up from the minimum to `v0`, then
/// down).
pub(crate) fn history(lo: f64, hi: f64, x0: f64, v0: f64) -> [f64; 3] {
    if v0 <= x0 { [lo, hi, v0] } else { [hi, lo, v0] }
}

/// The best virtual history of the one-parameter family (see the
/// [module documentation](self)) for the model input `x` and output `y` (normalised, the
/// whole record) fitted over `fit`: the prefix of normalised inputs to run before the first
/// sample, and the least-squares RMS cost (normalised) it gives. `build` makes the fitting
/// problem from the data (the caller's thresholds, direction, offset and margin).
pub(crate) fn estimate_history(
    x: &[f64],
    y: &[f64],
    fit: std::ops::Range<usize>,
    build: &dyn Fn(ProblemData<'_>) -> Result<FitProblem, IdentifyError>,
) -> Result<(Vec<f64>, f64), IdentifyError> {
    let (lo, hi) = min_max(x);
    let x0 = x[0];
    let mut input = vec![0.0; x.len() + 3];
    input[3..].copy_from_slice(x);
    let mut output = vec![0.0; y.len() + 3];
    output[3..].copy_from_slice(y);
    let span = fit.start + 3..fit.end + 3;
    let mut cost = |v0: f64| -> Result<f64, IdentifyError> {
        input[..3].copy_from_slice(&history(lo, hi, x0, v0));
        let problem = build(ProblemData {
            input: &input,
            output: &output,
            fit: span.clone(),
        })?;
        Ok(LeastSquares.solve(&problem, &mut NoObserver)?.cost)
    };
    // Both branches on one axis: rising histories over [lo, x0], falling ones over (x0, hi].
    let mut grid = Vec::with_capacity(2 * HISTORY_GRID + 1);
    for i in 0..=HISTORY_GRID {
        grid.push(lo + (x0 - lo) * i as f64 / HISTORY_GRID as f64);
    }
    for i in 1..=HISTORY_GRID {
        grid.push(x0 + (hi - x0) * i as f64 / HISTORY_GRID as f64);
    }
    let mut scored = Vec::with_capacity(grid.len());
    for &v0 in &grid {
        scored.push((v0, cost(v0)?));
    }
    let best = scored
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.1.total_cmp(&b.1.1))
        .map(|(i, _)| i)
        .unwrap_or(0);
    let (mut v_best, mut c_best) = scored[best];
    // Refine within the best candidate's branch, between its neighbours.
    let rising = v_best <= x0;
    let neighbour = |j: usize| scored[j].0;
    let mut a = if best > 0 {
        neighbour(best - 1)
    } else {
        v_best
    };
    let mut b = if best + 1 < scored.len() {
        neighbour(best + 1)
    } else {
        v_best
    };
    if rising {
        b = b.min(x0);
    } else {
        a = a.max(x0 + f64::EPSILON * (1.0 + x0.abs()));
    }
    if b > a {
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        let mut c = b - ratio * (b - a);
        let mut d = a + ratio * (b - a);
        let mut fc = cost(c)?;
        let mut fd = cost(d)?;
        for _ in 0..HISTORY_REFINEMENT_STEPS {
            if fc < fd {
                b = d;
                d = c;
                fd = fc;
                c = b - ratio * (b - a);
                fc = cost(c)?;
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + ratio * (b - a);
                fd = cost(d)?;
            }
        }
        for (v, f) in [(c, fc), (d, fd)] {
            if f < c_best {
                v_best = v;
                c_best = f;
            }
        }
    }
    Ok((history(lo, hi, x0, v_best).to_vec(), c_best))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_memory_is_known_from_the_first_extreme() {
        assert_eq!(memory_known_from(&[0.5, 0.7, 1.0, 0.0, 1.0]), 2);
        assert_eq!(memory_known_from(&[0.5, 0.7, 0.995, 0.0, 1.0]), 2);
        assert_eq!(memory_known_from(&[0.5, 0.7, 0.98, 0.0, 1.0]), 3);
        assert_eq!(memory_known_from(&[0.5, 0.2, 0.0, 1.0]), 2);
        assert_eq!(memory_known_from(&[0.0, 0.5, 1.0]), 0);
        assert_eq!(memory_known_from(&[1.0, 0.5, 0.0]), 0);
    }

    #[test]
    fn the_family_spans_the_reset_state_and_the_fall_from_the_top() {
        use hystcomp_core::OneSidedPlay;
        let run = |prefix: &[f64], r: f64, x0: f64| {
            let mut p = OneSidedPlay::new(r, 0.0).unwrap();
            for &v in prefix {
                p.step(v);
            }
            p.step(x0)
        };
        for r in [0.0, 0.1, 0.3, 0.6, 0.9] {
            let x0 = 0.4;
            // v0 = lo: the reset state of eq. (1) (rising from the minimum).
            assert_eq!(run(&history(0.0, 1.0, x0, 0.0), r, x0), run(&[], r, x0));
            // v0 = hi: fallen from the maximum.
            assert_eq!(
                run(&history(0.0, 1.0, x0, 1.0), r, x0),
                run(&[1.0], r, x0),
                "r = {r}"
            );
        }
    }
}
