//! Test signals for studies, benchmarks and the command line: the paper's trajectory
//! time-compressed by a speed factor, triangle and sawtooth rasters with rounded corners, steps
//! and holds, multisines and chirps.
//!
//! Every signal is a [`Signal`]: a [`Shape`] that runs between -1 and +1, scaled by an
//! `amplitude` about an `offset`, played `speed` times faster than its nominal time base for
//! `duration_s` seconds at `sample_rate_hz`:
//!
//! ```text
//! value(t) = offset + amplitude * shape(speed * t),   t = k / sample_rate_hz,  k = 0 .. N - 1
//! ```
//!
//! with `N = round(duration_s * sample_rate_hz)`. The unit of `amplitude` and `offset` is the
//! unit of the signal: micrometres for a desired trajectory, volts for a drive command. Every
//! shape stays within -1 ..= +1, and all but steps (which go where their levels say) reach both
//! ends over a period (a chirp, over enough cycles), so a signal spans `offset - amplitude ..=
//! offset + amplitude`: a "20 um raster" has an amplitude of 10 um. Each shape lives in its own file with its own formula and tests:
//! [`paper`], [`raster`], [`steps`], [`multisine`], [`chirp`].
//!
//! ```
//! use hystcomp_experiments::signals::{Raster, Shape, Signal};
//!
//! // A 20 um triangle raster (10 .. 30 um) at 100 Hz, corners rounded over 5 % of its period,
//! // 0.1 s at 10 kHz.
//! let raster = Signal {
//!     shape: Shape::Raster(Raster::triangle(100.0, 0.05)),
//!     amplitude: 10.0,
//!     offset: 20.0,
//!     duration_s: 0.1,
//!     speed: 1.0,
//!     sample_rate_hz: 10_000.0,
//! };
//! let y_um = raster.sample()?;
//! assert_eq!(y_um.len(), 1000);
//! assert!(y_um.iter().all(|y| (10.0 - 1e-9..=30.0 + 1e-9).contains(y)));
//! # Ok::<(), hystcomp_experiments::signals::SignalError>(())
//! ```

pub mod chirp;
pub mod multisine;
pub mod paper;
pub mod raster;
pub mod steps;

use hystcomp_core::Shown;
use std::fmt;

use serde::{Deserialize, Serialize};

pub use chirp::{Chirp, Sweep};
pub use multisine::{Multisine, Tone};
pub use paper::PaperTrajectory;
pub use raster::Raster;
pub use steps::Steps;

/// The most samples a signal may have (2e7: 2000 s at 10 kHz, 160 MB of `f64`).
pub const MAX_SAMPLES: usize = 20_000_000;
/// The highest sample rate accepted, Hz (10 MHz).
pub const MAX_SAMPLE_RATE_HZ: f64 = 1.0e7;
/// The largest speed factor accepted (10 000).
pub const MAX_SPEED: f64 = 1.0e4;

/// A signal's shape: a function of the nominal time `tau = speed * t` (seconds) between -1 and
/// +1. Serialised with a `kind` tag (`"paper"`, `"raster"`, `"steps"`, `"multisine"`,
/// `"chirp"`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Shape {
    /// The paper's trajectory (section 4.3), normalised to its range over one period.
    Paper(PaperTrajectory),
    /// A triangle or sawtooth raster with rounded corners.
    Raster(Raster),
    /// Steps between levels, each held.
    Steps(Steps),
    /// A periodic sum of harmonics of one fundamental.
    Multisine(Multisine),
    /// A sine whose frequency sweeps over the signal's duration.
    Chirp(Chirp),
}

impl Shape {
    /// Checks the shape's own parameters.
    pub fn validate(&self) -> Result<(), SignalError> {
        match self {
            Shape::Paper(_) => Ok(()),
            Shape::Raster(r) => r.validate(),
            Shape::Steps(s) => s.validate(),
            Shape::Multisine(m) => m.validate(),
            Shape::Chirp(c) => c.validate(),
        }
    }

    /// The shape at nominal time `tau_s`, between -1 and +1. `span_s` is the nominal length of
    /// the whole signal (`speed * duration_s`), over which a chirp sweeps.
    pub fn unit_value(&self, tau_s: f64, span_s: f64) -> f64 {
        match self {
            Shape::Paper(p) => p.unit_value(tau_s),
            Shape::Raster(r) => r.unit_value(tau_s),
            Shape::Steps(s) => s.unit_value(tau_s),
            Shape::Multisine(m) => m.unit_value(tau_s),
            Shape::Chirp(c) => c.unit_value(tau_s, span_s),
        }
    }

    /// The highest frequency the shape contains at speed 1, Hz (the fastest tone, the raster's
    /// fundamental, the chirp's highest frequency; 0 for steps). A signal's is `speed` times
    /// this.
    pub fn highest_frequency_hz(&self) -> f64 {
        match self {
            Shape::Paper(p) => p.highest_frequency_hz(),
            Shape::Raster(r) => r.frequency_hz,
            Shape::Steps(_) => 0.0,
            Shape::Multisine(m) => m.highest_frequency_hz(),
            Shape::Chirp(c) => c.start_hz.max(c.end_hz),
        }
    }
}

/// A shape scaled, offset, sped up and sampled (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Signal {
    /// What the signal looks like.
    pub shape: Shape,
    /// Half the peak-to-peak range, in the signal's unit (um or V); may be negative (the shape
    /// mirrored) or 0.
    pub amplitude: f64,
    /// Centre of the range, in the signal's unit.
    pub offset: f64,
    /// Length of the signal, s (real time, after the speed factor).
    pub duration_s: f64,
    /// Time compression: the shape runs `speed` times faster than its nominal time base (10
    /// plays the paper's 10 s period in 1 s). Positive, at most [`MAX_SPEED`].
    pub speed: f64,
    /// Samples per second, Hz (positive, at most [`MAX_SAMPLE_RATE_HZ`]).
    pub sample_rate_hz: f64,
}

impl Signal {
    /// The paper's trajectory (37.35 + 10.5 sin(pi t + 2.6) + 10.5 sin(1.6 pi t + 3) +
    /// 15.75 sin(2 pi t + 1.5) um), `speed` times faster, for `duration_s` at `sample_rate_hz`.
    pub fn paper(speed: f64, duration_s: f64, sample_rate_hz: f64) -> Signal {
        let paper = PaperTrajectory::new();
        Signal {
            amplitude: paper.half_range_um(),
            offset: paper.mid_range_um(),
            shape: Shape::Paper(paper),
            duration_s,
            speed,
            sample_rate_hz,
        }
    }

    /// Checks every parameter; the error names the one at fault.
    pub fn validate(&self) -> Result<(), SignalError> {
        let finite = |name: &'static str, value: f64| {
            if value.is_finite() {
                Ok(())
            } else {
                Err(SignalError::new(
                    name,
                    format!("must be finite, got {}", Shown(value)),
                ))
            }
        };
        finite("amplitude", self.amplitude)?;
        finite("offset", self.offset)?;
        if !(self.speed > 0.0 && self.speed <= MAX_SPEED) {
            return Err(SignalError::new(
                "speed",
                format!("must be in (0, {MAX_SPEED}], got {}", Shown(self.speed)),
            ));
        }
        if !(self.sample_rate_hz > 0.0 && self.sample_rate_hz <= MAX_SAMPLE_RATE_HZ) {
            return Err(SignalError::new(
                "sample_rate_hz",
                format!(
                    "must be in (0, {MAX_SAMPLE_RATE_HZ}] Hz, got {}",
                    Shown(self.sample_rate_hz)
                ),
            ));
        }
        if !(self.duration_s > 0.0 && self.duration_s.is_finite()) {
            return Err(SignalError::new(
                "duration_s",
                format!(
                    "must be positive and finite, got {} s",
                    Shown(self.duration_s)
                ),
            ));
        }
        let samples = self.duration_s * self.sample_rate_hz;
        if samples.round() < 1.0 || samples.round() > MAX_SAMPLES as f64 {
            return Err(SignalError::new(
                "duration_s",
                format!(
                    "{} s at {} Hz is {} samples; between 1 and {MAX_SAMPLES} are allowed",
                    Shown(self.duration_s),
                    Shown(self.sample_rate_hz),
                    Shown(samples.round())
                ),
            ));
        }
        self.shape.validate()
    }

    /// Number of samples, `round(duration_s * sample_rate_hz)`, after [`Signal::validate`].
    pub fn sample_count(&self) -> Result<usize, SignalError> {
        self.validate()?;
        Ok((self.duration_s * self.sample_rate_hz).round() as usize)
    }

    /// The value at real time `t_s` (seconds), in the signal's unit. Does not validate.
    pub fn value_at(&self, t_s: f64) -> f64 {
        let span = self.speed * self.duration_s;
        self.offset + self.amplitude * self.shape.unit_value(self.speed * t_s, span)
    }

    /// The sample times `k / sample_rate_hz`, s.
    pub fn time_s(&self) -> Result<Vec<f64>, SignalError> {
        let n = self.sample_count()?;
        Ok((0..n).map(|k| k as f64 / self.sample_rate_hz).collect())
    }

    /// The samples `value(k / sample_rate_hz)`, in the signal's unit.
    pub fn sample(&self) -> Result<Vec<f64>, SignalError> {
        let n = self.sample_count()?;
        Ok((0..n)
            .map(|k| self.value_at(k as f64 / self.sample_rate_hz))
            .collect())
    }

    /// The highest frequency in the signal, Hz (`speed` times the shape's).
    pub fn highest_frequency_hz(&self) -> f64 {
        self.speed * self.shape.highest_frequency_hz()
    }
}

/// A signal parameter out of its range; the message names the parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalError {
    /// The parameter at fault, as spelled in the struct (`duration_s`, `rounding`, ...).
    pub parameter: &'static str,
    /// What is wrong with it.
    pub message: String,
}

impl SignalError {
    pub(crate) fn new(parameter: &'static str, message: impl Into<String>) -> SignalError {
        SignalError {
            parameter,
            message: message.into(),
        }
    }
}

impl fmt::Display for SignalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "signal {}: {}", self.parameter, self.message)
    }
}

impl std::error::Error for SignalError {}

/// Checks that `value` is finite and within `lo ..= hi`.
pub(crate) fn check_range(
    parameter: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    unit: &str,
) -> Result<(), SignalError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(SignalError::new(
            parameter,
            format!("must be in [{lo}, {hi}]{unit}, got {}", Shown(value)),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raster() -> Signal {
        Signal {
            shape: Shape::Raster(Raster::triangle(10.0, 0.05)),
            amplitude: 10.0,
            offset: 20.0,
            duration_s: 1.0,
            speed: 1.0,
            sample_rate_hz: 1000.0,
        }
    }

    #[test]
    fn speed_compresses_time() {
        let slow = raster();
        let fast = Signal {
            speed: 4.0,
            duration_s: 0.25,
            ..slow.clone()
        };
        let a = slow.sample().unwrap();
        let b = fast.sample().unwrap();
        assert_eq!(b.len(), 250);
        for (k, y) in b.iter().enumerate() {
            assert!((y - a[4 * k]).abs() < 1e-9, "{k}");
        }
        assert_eq!(fast.highest_frequency_hz(), 40.0);
    }

    #[test]
    fn bad_parameters_are_named() {
        let cases: Vec<(Signal, &str)> = vec![
            (
                Signal {
                    speed: 0.0,
                    ..raster()
                },
                "speed",
            ),
            (
                Signal {
                    sample_rate_hz: f64::NAN,
                    ..raster()
                },
                "sample_rate_hz",
            ),
            (
                Signal {
                    duration_s: 1e9,
                    ..raster()
                },
                "duration_s",
            ),
            (
                Signal {
                    duration_s: 1e-6,
                    ..raster()
                },
                "duration_s",
            ),
            (
                Signal {
                    amplitude: f64::INFINITY,
                    ..raster()
                },
                "amplitude",
            ),
            (
                Signal {
                    shape: Shape::Raster(Raster::triangle(10.0, 0.7)),
                    ..raster()
                },
                "rounding",
            ),
        ];
        for (signal, parameter) in cases {
            let error = signal.sample().unwrap_err();
            assert_eq!(error.parameter, parameter, "{error}");
            assert!(error.to_string().contains(parameter));
        }
    }

    #[test]
    fn signals_round_trip_through_json() {
        let signal = raster();
        let text = serde_json::to_string(&signal).unwrap();
        assert!(text.contains("\"kind\":\"raster\""), "{text}");
        let back: Signal = serde_json::from_str(&text).unwrap();
        assert_eq!(back, signal);
    }
}
