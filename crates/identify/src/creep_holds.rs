//! The creep link's weights from the record's holds (step-and-hold tests, as creep is measured
//! on hardware: Jung & Gweon 2000, doi:10.1063/1.1150570; Croft, Shed & Devasia 2001,
//! doi:10.1115/1.1341197).
//!
//! While the voltage is held the hysteresis output `h` is constant (a rate-independent
//! operator does not move on a constant input), so over a hold `j` the chain's creep link in
//! its inverse parameterisation (`hystcomp_core::Creep`: `h = y - sum_i c_i (z_i[y] - origin)`)
//! gives
//!
//! `y(k) = b_j + sum_i c_i z_i[y](k)`,
//!
//! linear in the weights `c_i` and one constant `b_j` per hold, whatever the hysteresis is.
//! The elements `z_i` filter the whole measured record from its start (so each hold's history
//! is accounted for), only the held samples are fitted. The joint fit of hysteresis and creep
//! over the whole record ([`crate::chain`]) instead lets the creep elements absorb the
//! hysteresis model's mismatch on the moving samples (a slow first-order element is a lag,
//! and so is a hysteresis loop): measured on the built-in stage, that joint fit's creep grows
//! 11 % more than the stage's over a held step, and 15-18 % more on a copy of the stage
//! whose creep the bank represents (a Kelvin-Voigt bank within the model's time constants).
//! Fitted on the holds alone, the weights see creep and nothing else; the hysteresis is then
//! fitted to the creep-free displacement `C^-1[y]` over the whole record.
//!
//! The weights are non-negative (creep only adds to a step, as in the joint fit), found by
//! an active-set least squares (Lawson & Hanson 1974, *Solving Least Squares Problems*,
//! ch. 23), with the same smoothness penalty on neighbouring weights as the joint fit
//! ([`crate::FitProblem::with_extra_smoothness`]).

use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use crate::IdentifyError;

/// The most holds a record may have for the holds fit: 64 (the study's excitation has three).
/// Each hold is a column of the fit's least squares beside the creep weights, and choosing
/// the smoothness refits it once per hold left out for every candidate, so its cost grows
/// steeply with their number; checked before any row is built.
pub const MAX_HOLDS: usize = 64;

/// Samples after the voltage stops moving that a hold skips, s: the stage's fast dynamics
/// (amplifier, resonance) settle within them.
pub const HOLD_SETTLE_S: f64 = 0.02;

/// The smoothness penalties a fit on holds chooses among by default (by leaving each hold
/// out), from nearly none to a flat spectrum.
pub const DEFAULT_SMOOTHNESS_CANDIDATES: [f64; 7] = [0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0];

/// The maximal runs of at least `min_samples` samples over which `voltage` does not change
/// (consecutive samples equal to within `1e-9` of the record's range), as ranges of sample
/// indices.
pub fn held_segments(voltage: &[f64], min_samples: usize) -> Vec<Range<usize>> {
    let (lo, hi) = voltage
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let tolerance = 1e-9 * (hi - lo).max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    let mut start = 0;
    for k in 1..=voltage.len() {
        let moved = k == voltage.len() || (voltage[k] - voltage[k - 1]).abs() > tolerance;
        if moved {
            if k - start >= min_samples.max(2) {
                out.push(start..k);
            }
            start = k;
        }
    }
    out
}

/// The creep weights fitted on `holds`, and the held-out score of each smoothness candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct HoldFit {
    /// The weights `c_i`, non-negative.
    pub weights: Vec<f64>,
    /// The smoothness they were fitted with.
    pub smoothness: f64,
    /// `(smoothness, held-out RMS error %)` of each candidate tried (empty when one was given):
    /// each hold left out in turn, its drift predicted by the weights fitted on the others,
    /// the RMS of the error about its mean over the left-out hold's samples, % of the output
    /// range.
    pub candidates: Vec<(f64, f64)>,
}

/// One hold's rows of the least squares, compressed: with `A_j = Q_j R_j` over its indicator
/// and element columns, `||b_j - A_j x||^2 = ||d_j - R_j x||^2 + rest_j` (`d_j = Q_j^T b_j`),
/// so that any set of holds is fitted, and any hold scored, on a few rows.
struct HoldBlock {
    r: DMatrix<f64>,
    d: DVector<f64>,
    rest: f64,
    rows: usize,
}

/// The least-squares rows of the hold fit, normalised by the output range, one compressed
/// block per hold: its indicator column, then one per element.
struct HoldRows {
    blocks: Vec<HoldBlock>,
    elements: usize,
}

impl HoldRows {
    fn new(
        displacement: &[f64],
        period_s: f64,
        decimation: usize,
        holds: &[Range<usize>],
        time_constants_s: &[f64],
        y_scale: f64,
    ) -> Result<HoldRows, IdentifyError> {
        let settle = (HOLD_SETTLE_S / period_s).ceil() as usize;
        let holds: Vec<Range<usize>> = holds
            .iter()
            .map(|h| (h.start + settle).min(h.end)..h.end.min(displacement.len()))
            .filter(|h| h.len() >= 2 * decimation.max(1))
            .collect();
        if holds.len() > MAX_HOLDS {
            return Err(IdentifyError::InvalidOption {
                option: "creep holds",
                value: format!("{} holds", holds.len()),
                reason: format!(
                    "the holds fit takes at most {MAX_HOLDS} holds (each one a column of its \
                     least squares, refitted once per hold left out): select a row range \
                     with fewer, or fit creep jointly"
                ),
            });
        }
        let m = time_constants_s.len();
        if holds.is_empty() || m == 0 || displacement.is_empty() {
            return Err(IdentifyError::InvalidOption {
                option: "creep holds",
                value: format!("{} holds", holds.len()),
                reason: "the record holds its voltage nowhere long enough to see creep; give a \
                         record with step-and-hold segments or fit creep jointly"
                    .to_owned(),
            });
        }
        let scale = if y_scale.is_finite() && y_scale > 0.0 {
            y_scale
        } else {
            1.0
        };
        // The elements at the full rate, from rest at the first displacement.
        let first = displacement[0];
        let columns: Vec<Vec<f64>> = time_constants_s
            .iter()
            .map(|tau| {
                let g = 1.0 - (-period_s / tau).exp();
                let mut z = first;
                displacement
                    .iter()
                    .map(|&y| {
                        z += g * (y - z);
                        (z - first) / scale
                    })
                    .collect()
            })
            .collect();
        let blocks = holds
            .iter()
            .map(|h| {
                let samples: Vec<usize> = h.clone().step_by(decimation.max(1)).collect();
                let n = samples.len();
                let a = DMatrix::<f64>::from_fn(n, m + 1, |r, c| {
                    if c == 0 {
                        1.0
                    } else {
                        columns[c - 1][samples[r]]
                    }
                });
                let b = DVector::<f64>::from_iterator(
                    n,
                    samples.iter().map(|&k| (displacement[k] - first) / scale),
                );
                let qr = a.qr();
                let d = qr.q().transpose() * &b;
                let rest = (b.norm_squared() - d.norm_squared()).max(0.0);
                HoldBlock {
                    r: qr.r(),
                    d,
                    rest,
                    rows: n,
                }
            })
            .collect();
        Ok(HoldRows {
            blocks,
            elements: m,
        })
    }

    /// The weights fitted on every hold but `left_out`, with `smoothness`.
    fn solve(&self, smoothness: f64, left_out: Option<usize>) -> Result<Vec<f64>, IdentifyError> {
        let holds = self.blocks.len();
        let m = self.elements;
        let used: Vec<usize> = (0..holds).filter(|&j| Some(j) != left_out).collect();
        let n: usize = used.iter().map(|&j| self.blocks[j].rows).sum();
        let penalties = if smoothness > 0.0 { m - 1 } else { 0 };
        let p = holds + m;
        let block_rows: usize = used.iter().map(|&j| self.blocks[j].r.nrows()).sum();
        let mut a = DMatrix::<f64>::zeros(block_rows + penalties, p);
        let mut b = DVector::<f64>::zeros(block_rows + penalties);
        let mut row = 0;
        for &j in &used {
            let block = &self.blocks[j];
            for r in 0..block.r.nrows() {
                a[(row, j)] = block.r[(r, 0)];
                for i in 0..m {
                    a[(row, holds + i)] = block.r[(r, i + 1)];
                }
                b[row] = block.d[r];
                row += 1;
            }
        }
        let weight = smoothness * (n as f64).sqrt();
        for i in 0..penalties {
            a[(row + i, holds + i)] = -weight;
            a[(row + i, holds + i + 1)] = weight;
        }
        // Active set: the weights that would come out negative are held at zero, one at a
        // time; a left-out hold's indicator column is all zero and left out too.
        let mut free: Vec<bool> = (0..p).map(|c| Some(c) != left_out).collect();
        loop {
            let keep: Vec<usize> = (0..p).filter(|&c| free[c]).collect();
            let solution = a
                .select_columns(&keep)
                .svd(true, true)
                .solve(&b, 1e-12)
                .map_err(|reason| IdentifyError::InvalidOption {
                    option: "creep holds",
                    value: format!("{holds} holds"),
                    reason: reason.to_owned(),
                })?;
            let mut theta = vec![0.0; p];
            for (s, &c) in keep.iter().enumerate() {
                theta[c] = solution[s];
            }
            let most_negative = (holds..p)
                .filter(|&c| free[c] && theta[c] < 0.0)
                .min_by(|&x, &y| theta[x].total_cmp(&theta[y]));
            match most_negative {
                Some(c) => free[c] = false,
                None => return Ok(theta[holds..].to_vec()),
            }
        }
    }

    /// Leave-one-hold-out RMS error (about each left-out hold's mean), % of the output range.
    fn held_out_percent(&self, smoothness: f64) -> Result<f64, IdentifyError> {
        let (mut sum, mut count) = (0.0, 0usize);
        for (j, block) in self.blocks.iter().enumerate() {
            let weights = self.solve(smoothness, Some(j))?;
            // u = d - R [0; c], then the best level beta along R's first column.
            let c = DVector::from_iterator(
                self.elements + 1,
                std::iter::once(0.0).chain(weights.iter().copied()),
            );
            let u = &block.d - &block.r * c;
            let r0 = block.r.column(0);
            let beta = r0.dot(&u) / r0.norm_squared().max(f64::MIN_POSITIVE);
            sum += (u - r0 * beta).norm_squared() + block.rest;
            count += block.rows;
        }
        Ok(100.0 * (sum / count.max(1) as f64).sqrt())
    }
}

/// The creep weights fitted on `holds` (see the [module documentation](self)).
///
/// `displacement` is the full-rate record, `period_s` its sample period, `decimation` keeps
/// every so-many held sample, `time_constants_s` are the elements', `y_scale` the output
/// range that normalises the rows. The smoothness penalty's weight (in normalised output
/// units, as the joint fit's) is `smoothness` when `candidates` is empty; otherwise the
/// candidate with the least leave-one-hold-out error (at least two holds are needed), the
/// largest within 1 % of it (the smoothest that predicts as well). Each hold skips its first
/// [`HOLD_SETTLE_S`].
#[allow(clippy::too_many_arguments)]
pub fn creep_weights_from_holds(
    displacement: &[f64],
    period_s: f64,
    decimation: usize,
    holds: &[Range<usize>],
    time_constants_s: &[f64],
    smoothness: f64,
    candidates: &[f64],
    y_scale: f64,
) -> Result<HoldFit, IdentifyError> {
    let rows = HoldRows::new(
        displacement,
        period_s,
        decimation,
        holds,
        time_constants_s,
        y_scale,
    )?;
    let mut scores = Vec::new();
    let chosen = if candidates.is_empty() {
        smoothness
    } else {
        if rows.blocks.len() < 2 {
            return Err(IdentifyError::InvalidOption {
                option: "creep smoothness candidates",
                value: format!("{candidates:?}"),
                reason: format!(
                    "choosing the smoothness by leaving a hold out needs two holds or more; the \
                     record has {}",
                    rows.blocks.len()
                ),
            });
        }
        for &lambda in candidates {
            scores.push((lambda, rows.held_out_percent(lambda)?));
        }
        let best = scores.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
        scores
            .iter()
            .filter(|s| s.1 <= best * 1.01)
            .map(|s| s.0)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    Ok(HoldFit {
        weights: rows.solve(chosen, None)?,
        smoothness: chosen,
        candidates: scores,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_segments_are_the_runs_of_equal_voltage() {
        let v = [0.0, 1.0, 1.0, 1.0, 2.0, 3.0, 3.0, 3.0, 3.0];
        assert_eq!(held_segments(&v, 3), vec![1..4, 5..9]);
        assert_eq!(held_segments(&v, 4), vec![5..9]);
        assert!(held_segments(&[1.0; 1], 1).is_empty());
    }
}
