//! Choosing the number of play operators by held-out error (`-n auto`).

use serde::{Deserialize, Serialize};

use crate::{IdentifyError, IdentifyOptions, MAX_OPERATORS, Thresholds, identify};

/// The candidates `-n auto` tries: the paper's 10, fewer and more, up to 50 (the DBO record's
/// held-out error stops falling there, and the fit's cost grows with the square of `n`).
pub const AUTO_OPERATOR_CANDIDATES: [usize; 7] = [5, 10, 15, 20, 30, 40, 50];

/// The fraction of the record (after the warm-up, at its end) held out to choose `n`, when
/// the options hold out nothing themselves.
pub const AUTO_HOLDOUT: f64 = 0.25;

/// One candidate of [`select_operators`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OrderCandidate {
    /// Number of play operators (thresholds `(i - 1) / n`, eq. (11)).
    pub operators: usize,
    /// RMS error over the fitted samples, % of the fitted output range.
    pub fit_rms_percent: f64,
    /// RMS error over the held-out samples, % of their own output range (the same for every
    /// candidate; NaN when the fit failed).
    pub holdout_rms_percent: f64,
}

/// What [`select_operators`] chose and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrderSelection {
    /// The number of operators with the smallest held-out RMS error (the smaller `n` on a tie
    /// within 1 % of it).
    pub operators: usize,
    /// The fraction of the record held out to choose it.
    pub holdout: f64,
    /// Every candidate tried.
    pub candidates: Vec<OrderCandidate>,
}

/// Chooses the number of uniformly spaced play operators by the held-out RMS error: each of
/// `candidates` (at most [`MAX_OPERATORS`]) is identified with `options` on the record less
/// its last `options.holdout` (or [`AUTO_HOLDOUT`] when that is 0), and the one that predicts
/// the held-out samples best is chosen; the smallest within 1 % of the best wins a near-tie
/// (fewer parameters generalise better). Candidates the record is too short for, or whose fit
/// fails, are skipped; none left is an error.
pub fn select_operators(
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    candidates: &[usize],
) -> Result<OrderSelection, IdentifyError> {
    let holdout = if options.holdout > 0.0 {
        options.holdout
    } else {
        AUTO_HOLDOUT
    };
    let mut tried = Vec::new();
    let mut last_error = None;
    for &n in candidates
        .iter()
        .filter(|n| (1..=MAX_OPERATORS).contains(*n))
    {
        let o = IdentifyOptions {
            thresholds: Thresholds::Uniform(n),
            holdout,
            ..options.clone()
        };
        match identify(voltage, displacement, &o) {
            Ok(fit) => {
                let Some(h) = fit.report.holdout else {
                    continue;
                };
                tried.push(OrderCandidate {
                    operators: n,
                    fit_rms_percent: fit.report.fit.rms_percent,
                    holdout_rms_percent: h.rms_percent,
                });
            }
            Err(e) => last_error = Some(e),
        }
    }
    let best = tried
        .iter()
        .filter(|c| c.holdout_rms_percent.is_finite())
        .map(|c| c.holdout_rms_percent)
        .fold(f64::INFINITY, f64::min);
    let chosen = tried
        .iter()
        .filter(|c| c.holdout_rms_percent <= best * 1.01)
        .map(|c| c.operators)
        .min();
    match chosen {
        Some(operators) => Ok(OrderSelection {
            operators,
            holdout,
            candidates: tried,
        }),
        None => Err(last_error.unwrap_or(IdentifyError::InvalidOption {
            option: "number of play operators",
            value: "auto".to_owned(),
            reason: "no candidate could be identified and validated on the held-out samples"
                .to_owned(),
        })),
    }
}
