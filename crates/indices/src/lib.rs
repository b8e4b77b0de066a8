//! Tracking indices of section 4.3: the maximum error e_m (D1, corrected as in ERRATA item 2),
//! the RMS error e_rms (D2) and the maximum hysteresis error e_mhe (eq. (12), made precise as in
//! ERRATA item 6). All three are in percent of the desired range `max y_d - min y_d`.
//!
//! G.-Y. Gu and L.-M. Zhu, *Smart Mater. Struct.* **23** (2014) 095029,
//! doi:10.1088/0964-1726/23/9/095029. A crate of its own (serde its only dependency) so that
//! the C library and the bindings over it compute the indices without the study's plotting
//! and simulation; `hystcomp_experiments::indices` re-exports it.
#![warn(missing_docs)]

use core::fmt;

/// Default number of bins across the `y_d` range used by [`e_mhe_percent`].
///
/// With 100 bins the slope of the map inside one bin adds at most about 1 % of the range to a
/// perfectly single-valued map; the report states the bin count beside every e_mhe figure.
pub const DEFAULT_MHE_BINS: usize = 100;

/// The fewest samples per e_mhe bin, on average, that [`e_mhe_percent`] accepts: with fewer,
/// many bins hold one sample or none and e_mhe (the widest spread inside a bin)
/// underestimates the loop.
pub const MIN_SAMPLES_PER_BIN: usize = 10;

/// The most e_mhe bins `samples` samples support at [`MIN_SAMPLES_PER_BIN`] per bin (one bin
/// at least: the whole loop's width).
pub fn max_mhe_bins(samples: usize) -> usize {
    (samples / MIN_SAMPLES_PER_BIN).max(1)
}

/// Checks that `bins` e_mhe bins suit `samples` samples: at least one bin, and at least
/// [`MIN_SAMPLES_PER_BIN`] samples per bin on average. [`e_mhe_percent`] applies it; callers
/// that know the sample count before a long computation can apply it first.
pub fn check_mhe_bins(bins: usize, samples: usize) -> Result<(), IndexError> {
    if bins == 0 {
        return Err(IndexError::NoBins);
    }
    if bins > max_mhe_bins(samples) {
        return Err(IndexError::TooManyBins { bins, samples });
    }
    Ok(())
}

/// Why the indices of a pair of records could not be computed.
#[derive(Debug, Clone, PartialEq)]
pub enum IndexError {
    /// The two records have different lengths.
    LengthMismatch {
        /// Samples in the desired record.
        desired: usize,
        /// Samples in the measured record.
        measured: usize,
    },
    /// Fewer than two samples.
    TooFewSamples(usize),
    /// A sample is NaN or infinite.
    NonFinite {
        /// `desired` or `measured`.
        record: &'static str,
        /// The sample, 0-based.
        index: usize,
    },
    /// `max y_d - min y_d` is zero, so no percentage can be formed.
    ConstantDesired,
    /// An intermediate result (a difference, a square, a sum, the range) overflows to
    /// infinity: the values are finite but too large for the indices.
    Overflow {
        /// What overflowed, e.g. `y - y_d`.
        what: &'static str,
        /// The sample where it did (0-based), when one sample decides it.
        index: Option<usize>,
    },
    /// An index (a percentage of the desired range) overflows to infinity: the error is too
    /// large next to the range (a range too small, or values too large).
    PercentOverflow {
        /// Which index, e.g. `e_m`.
        what: &'static str,
        /// The desired range `max y_d - min y_d`.
        range: f64,
    },
    /// Fewer than one bin asked for.
    NoBins,
    /// More bins than the samples support ([`max_mhe_bins`]).
    TooManyBins {
        /// Bins asked for.
        bins: usize,
        /// Samples in the records.
        samples: usize,
    },
}

impl fmt::Display for IndexError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IndexError::LengthMismatch { desired, measured } => write!(
                f,
                "the desired record has {desired} samples but the measured record has {measured}; \
                 the indices compare them sample by sample, so give records of equal length"
            ),
            IndexError::TooFewSamples(n) => {
                write!(f, "{n} sample(s) given; the indices need at least 2")
            }
            IndexError::NonFinite { record, index } => write!(
                f,
                "the {record} record has a NaN or infinite value at sample {index} (0-based)"
            ),
            IndexError::ConstantDesired => write!(
                f,
                "the desired trajectory is constant, so its range is zero and the indices \
                 (percent of the desired range) are undefined"
            ),
            IndexError::Overflow { what, index } => {
                write!(f, "{what} overflows")?;
                if let Some(index) = index {
                    write!(f, " at sample {index} (0-based)")?;
                }
                f.write_str(
                    ": the values are too large for the indices; give the records in a unit \
                     that keeps them within 1e15",
                )
            }
            IndexError::PercentOverflow { what, range } => write!(
                f,
                "{what} overflows: the error is too large next to the desired range {range:e} \
                 for a percentage of it; check the records' columns and units"
            ),
            IndexError::NoBins => write!(f, "e_mhe needs at least one bin"),
            IndexError::TooManyBins { bins, samples } => write!(
                f,
                "{bins} e_mhe bins for {samples} samples: with fewer than {} samples per bin \
                 on average many bins hold one sample or none and e_mhe underestimates the \
                 loop; use at most {} bins",
                MIN_SAMPLES_PER_BIN,
                max_mhe_bins(*samples)
            ),
        }
    }
}

impl std::error::Error for IndexError {}

/// The three indices of Table 3, in percent of the desired range.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrackingIndices {
    /// Maximum hysteresis error, eq. (12) (ERRATA item 6), %.
    pub e_mhe_percent: f64,
    /// Maximum tracking error, (D1) (ERRATA item 2), %.
    pub e_m_percent: f64,
    /// RMS tracking error, (D2), %.
    pub e_rms_percent: f64,
    /// Number of `y_d` bins used for e_mhe.
    pub mhe_bins: usize,
}

impl TrackingIndices {
    /// Computes all three indices of `measured` (`y`) against `desired` (`y_d`), with
    /// `mhe_bins` bins for e_mhe.
    pub fn compute(desired: &[f64], measured: &[f64], mhe_bins: usize) -> Result<Self, IndexError> {
        Ok(TrackingIndices {
            e_mhe_percent: e_mhe_percent(desired, measured, mhe_bins)?,
            e_m_percent: e_m_percent(desired, measured)?,
            e_rms_percent: e_rms_percent(desired, measured)?,
            mhe_bins,
        })
    }
}

/// Checks the pair and returns `(min y_d, max y_d)`.
fn desired_range(desired: &[f64], measured: &[f64]) -> Result<(f64, f64), IndexError> {
    if desired.len() != measured.len() {
        return Err(IndexError::LengthMismatch {
            desired: desired.len(),
            measured: measured.len(),
        });
    }
    if desired.len() < 2 {
        return Err(IndexError::TooFewSamples(desired.len()));
    }
    for (record, values) in [("desired", desired), ("measured", measured)] {
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(IndexError::NonFinite { record, index });
        }
    }
    let lo = desired.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = desired.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi - lo <= 0.0 {
        return Err(IndexError::ConstantDesired);
    }
    if !(hi - lo).is_finite() {
        return Err(IndexError::Overflow {
            what: "the desired range max y_d - min y_d",
            index: None,
        });
    }
    Ok((lo, hi))
}

/// `value / range * 100 %`, refused when it overflows: an error so large next to the desired
/// range (or a range so small, a subnormal span, say) that the index is not a number one
/// could print.
fn percent(value: f64, range: f64, what: &'static str) -> Result<f64, IndexError> {
    let p = value / range * 100.0;
    if p.is_finite() {
        Ok(p)
    } else {
        Err(IndexError::PercentOverflow { what, range })
    }
}

/// The first sample whose `y - y_d` (or its square, with `squared`) overflows.
fn first_overflow(desired: &[f64], measured: &[f64], squared: bool) -> Option<usize> {
    desired.iter().zip(measured).position(|(d, y)| {
        let e = y - d;
        !(if squared { e * e } else { e }).is_finite()
    })
}

/// (D1), corrected (ERRATA item 2): `max |y - y_d| / (max y_d - min y_d) * 100 %`.
pub fn e_m_percent(desired: &[f64], measured: &[f64]) -> Result<f64, IndexError> {
    let (lo, hi) = desired_range(desired, measured)?;
    if let Some(index) = first_overflow(desired, measured, false) {
        return Err(IndexError::Overflow {
            what: "the error y - y_d",
            index: Some(index),
        });
    }
    let max = desired
        .iter()
        .zip(measured)
        .map(|(d, y)| (y - d).abs())
        .fold(0.0, f64::max);
    percent(max, hi - lo, "e_m")
}

/// (D2): `sqrt(mean (y - y_d)^2) / (max y_d - min y_d) * 100 %` (uniform sampling, so the
/// time integral is the sample mean).
pub fn e_rms_percent(desired: &[f64], measured: &[f64]) -> Result<f64, IndexError> {
    let (lo, hi) = desired_range(desired, measured)?;
    if let Some(index) = first_overflow(desired, measured, true) {
        return Err(IndexError::Overflow {
            what: "the squared error (y - y_d)^2",
            index: Some(index),
        });
    }
    let sum: f64 = desired
        .iter()
        .zip(measured)
        .map(|(d, y)| (y - d) * (y - d))
        .sum();
    if !sum.is_finite() {
        return Err(IndexError::Overflow {
            what: "the sum of squared errors",
            index: None,
        });
    }
    percent((sum / desired.len() as f64).sqrt(), hi - lo, "e_rms")
}

/// Eq. (12) as made precise in ERRATA item 6: the largest vertical width of the `y` versus
/// `y_d` map. The `y_d` range is cut into `bins` equal bins; in each bin with at least two
/// samples the width is `max y - min y`; the largest width is divided by `max y_d - min y_d`.
pub fn e_mhe_percent(desired: &[f64], measured: &[f64], bins: usize) -> Result<f64, IndexError> {
    let (lo, hi) = desired_range(desired, measured)?;
    check_mhe_bins(bins, desired.len())?;
    let mut low = vec![f64::INFINITY; bins];
    let mut high = vec![f64::NEG_INFINITY; bins];
    let mut count = vec![0usize; bins];
    let width = (hi - lo) / bins as f64;
    for (&d, &y) in desired.iter().zip(measured) {
        let bin = (((d - lo) / width) as usize).min(bins - 1);
        low[bin] = low[bin].min(y);
        high[bin] = high[bin].max(y);
        count[bin] += 1;
    }
    let widest = (0..bins)
        .filter(|&b| count[b] >= 2)
        .map(|b| high[b] - low[b])
        .fold(0.0, f64::max);
    if !widest.is_finite() {
        return Err(IndexError::Overflow {
            what: "the width max y - min y of a y_d bin",
            index: None,
        });
    }
    percent(widest, hi - lo, "e_mhe")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A desired range so small next to the error that the percentage overflows (a subnormal
    /// span) is an error naming the index and the range, never an index of `inf`.
    #[test]
    fn a_desired_range_too_small_for_a_percentage_is_an_error() {
        let desired = [0.0, 1e-310, 0.0, 1e-310];
        let measured = [1.0, 1.0, 0.5, 1.0];
        let errors = [
            e_m_percent(&desired, &measured).unwrap_err(),
            e_rms_percent(&desired, &measured).unwrap_err(),
            e_mhe_percent(&desired, &measured, 1).unwrap_err(),
        ];
        for (error, what) in errors.iter().zip(["e_m", "e_rms", "e_mhe"]) {
            assert_eq!(
                *error,
                IndexError::PercentOverflow {
                    what,
                    range: 1e-310
                }
            );
            assert!(error.to_string().starts_with(what), "{error}");
        }
        // A small range that still gives a finite percentage is an index.
        let small = [0.0, 1e-9, 0.0, 1e-9];
        assert!(e_m_percent(&small, &measured).unwrap().is_finite());
    }

    /// Finite records whose differences, squares or range overflow give an error naming the
    /// sample, never inf or a silent 0 % (issue 13: one 1e308 sample gave e_mhe = 0 %).
    #[test]
    fn overflowing_intermediate_results_are_errors() {
        let d = ramp(100);
        let mut y = d.clone();
        y[37] = 1e308;
        let mut below = d.clone();
        below[37] = -1e308;
        for (measured, index) in [(&y, Some(37)), (&below, Some(37))] {
            let mut far = measured.clone();
            far[38] = -measured[37]; // the same y_d bin: its width overflows
            let e = e_rms_percent(&d, measured).unwrap_err();
            assert_eq!(
                e,
                IndexError::Overflow {
                    what: "the squared error (y - y_d)^2",
                    index
                }
            );
            assert!(e.to_string().contains("sample 37"), "{e}");
            assert!(matches!(
                e_mhe_percent(&d, &far, 10),
                Err(IndexError::Overflow { .. })
            ));
            // Every index of the pair is an error, never inf (e_mhe and e_m were inf).
            assert!(matches!(
                TrackingIndices::compute(&d, measured, 10),
                Err(IndexError::PercentOverflow { what: "e_mhe", .. })
            ));
            assert!(matches!(
                e_m_percent(&d, measured),
                Err(IndexError::PercentOverflow { what: "e_m", .. })
            ));
        }
        let huge = [-1e308, 1e308];
        assert!(matches!(
            e_m_percent(&huge, &[0.0, 0.0]),
            Err(IndexError::Overflow { index: None, .. })
        ));
        // Large but representable values are fine.
        let big: Vec<f64> = d.iter().map(|v| v * 1e14).collect();
        assert!(TrackingIndices::compute(&big, &big, 10).is_ok());
    }

    fn ramp(n: usize) -> Vec<f64> {
        (0..n).map(|i| i as f64 / (n - 1) as f64 * 10.0).collect()
    }

    #[test]
    fn perfect_tracking_has_zero_error() {
        let d = ramp(1000);
        let t = TrackingIndices::compute(&d, &d, 100).unwrap();
        assert_eq!(t.e_m_percent, 0.0);
        assert_eq!(t.e_rms_percent, 0.0);
        // A single-valued map has only the in-bin slope as width: at most one bin of the range.
        assert!(t.e_mhe_percent <= 1.0 + 1e-9, "{}", t.e_mhe_percent);
    }

    #[test]
    fn constant_offset_gives_offset_over_range() {
        let d = ramp(500);
        let y: Vec<f64> = d.iter().map(|v| v + 0.5).collect();
        assert!((e_m_percent(&d, &y).unwrap() - 5.0).abs() < 1e-12);
        assert!((e_rms_percent(&d, &y).unwrap() - 5.0).abs() < 1e-12);
    }

    #[test]
    fn loop_width_is_found() {
        // Up along y = y_d, down along y = y_d + 2: a loop 2 wide on a range of 10 -> 20 %.
        let up = ramp(1000);
        let down: Vec<f64> = up.iter().rev().copied().collect();
        let mut d = up.clone();
        d.extend(&down);
        let mut y = up.clone();
        y.extend(down.iter().map(|v| v + 2.0));
        let e = e_mhe_percent(&d, &y, 100).unwrap();
        assert!((20.0..=21.0 + 1e-9).contains(&e), "{e}");
    }

    #[test]
    fn bad_inputs_are_refused() {
        let d = ramp(10);
        assert!(matches!(
            e_m_percent(&d, &d[..5]),
            Err(IndexError::LengthMismatch { .. })
        ));
        let mut y = d.clone();
        y[3] = f64::NAN;
        assert_eq!(
            e_rms_percent(&d, &y),
            Err(IndexError::NonFinite {
                record: "measured",
                index: 3
            })
        );
        assert_eq!(
            e_mhe_percent(&[1.0; 4], &[1.0; 4], 10),
            Err(IndexError::ConstantDesired)
        );
        assert_eq!(
            e_m_percent(&[1.0], &[1.0]),
            Err(IndexError::TooFewSamples(1))
        );
        assert_eq!(e_mhe_percent(&d, &d, 0), Err(IndexError::NoBins));
        // More bins than samples: refused, not a huge allocation or a silently wrong e_mhe.
        let err = e_mhe_percent(&d, &d, 100_000_000_000_000).unwrap_err();
        assert_eq!(
            err,
            IndexError::TooManyBins {
                bins: 100_000_000_000_000,
                samples: 10
            }
        );
        assert!(err.to_string().contains("use at most 1 bins"), "{err}");
        assert_eq!(max_mhe_bins(1000), 100);
    }
}
