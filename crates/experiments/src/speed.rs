//! The speed study (issue 11): does compensation hold at speed?
//!
//! - **The paper's trajectory time-compressed** so that its fastest tone is each of
//!   [`PAPER_RATES_HZ`] (1 to 100 Hz; the paper's is 1 Hz). Where the amplifier requires it,
//!   the amplitude is reduced about the trajectory's mid-range: the `full` pipeline's drive
//!   for the full amplitude is checked against the amplifier (`hystcomp_stage::feasibility`)
//!   and, while any sample of the evaluated period reaches the slew or rail limit, the
//!   amplitude is scaled by [`SLEW_MARGIN`] (0.9) x the ratio of the slew limit to the peak slew that period
//!   asks (at most [`MAX_REDUCTIONS`] times); every approach then tracks the same reduced
//!   trajectory. (The start from rest may be slew-limited; it is not evaluated.)
//! - **A triangle raster** of [`RASTER_UM`] (20 um peak to peak about the trajectory's
//!   mid-range) with corners rounded over [`RASTER_ROUNDING`] (5 %) of its period, at each of
//!   [`RASTER_RATES_HZ`] (10 to 200 Hz), on the built-in amplifier and on a stronger one
//!   ([`STRONG_PEAK_CURRENT_MA`]: ten times the slew rate), to tell the amplifier's slew limit
//!   from the compensation. Where the faithful drive of a chain with a vibration link asks
//!   more than the amplifier's slew rate (the built-in amplifier from 100 Hz), the raster is
//!   driven instead by the slew-constrained drive of [`crate::slew_drive`], every step within
//!   [`SLEW_MARGIN`] of the amplifier's slew rate ([`SpeedRun::slew_constrained`] says so);
//!   where the faithful drive is within it, nothing changes.
//!
//! Each run starts from rest: a raised cosine of 1 s to the first desired position, 1 s there,
//! then two periods of the trajectory (indices on the last) or [`RASTER_PERIODS`] periods of
//! the raster (indices on the last five). The models are the study's, identified once from
//! its excitation.

use hystcomp_io::compensator::Method;
use hystcomp_stage::{StageConfig, feasibility};
use rayon::prelude::*;
use serde::Serialize;

use crate::TrackingIndices;
use crate::signals::{PaperTrajectory, Raster, Shape, Signal};
use crate::study::{Approach, StudyError, track};

/// The fastest tone of the time-compressed paper trajectory, Hz.
pub const PAPER_RATES_HZ: [f64; 7] = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0];
/// The raster rates, Hz.
pub const RASTER_RATES_HZ: [f64; 5] = [10.0, 20.0, 50.0, 100.0, 200.0];
/// The raster's peak-to-peak amplitude, um.
pub const RASTER_UM: f64 = 20.0;
/// The share of the raster's period over which each corner is rounded.
pub const RASTER_ROUNDING: f64 = 0.05;
/// Raster periods after the lead-in.
pub const RASTER_PERIODS: usize = 10;
/// The stronger amplifier's peak current, mA (the built-in one has 100 mA).
pub const STRONG_PEAK_CURRENT_MA: f64 = 1000.0;
/// The most amplitude reductions at one rate.
pub const MAX_REDUCTIONS: usize = 6;
/// The share of the amplifier's slew rate a drive may use: the paper trajectory's amplitude
/// is reduced to, and the raster's slew-constrained drive kept within, this share (a margin
/// for the amplifier's own first-order lag, which a drive at the full slew rate runs into).
pub const SLEW_MARGIN: f64 = 0.9;

/// One approach at one rate.
#[derive(Debug, Clone, Serialize)]
pub struct SpeedRun {
    /// The approach.
    pub label: String,
    /// The indices on the evaluated window, % of its `y_d` range.
    pub indices: TrackingIndices,
    /// Share of the evaluated samples at the amplifier's slew or rail limit.
    pub limited_share: f64,
    /// Whether the drive is the slew-constrained one ([`crate::slew_drive`]) because the
    /// faithful inverse asked more than the amplifier's slew rate.
    pub slew_constrained: bool,
}

/// Every approach at one rate.
#[derive(Debug, Clone, Serialize)]
pub struct SpeedPoint {
    /// The fastest tone (paper) or the raster's frequency, Hz.
    pub rate_hz: f64,
    /// The amplitude tracked, as a fraction of the nominal one (1: not reduced).
    pub amplitude_scale: f64,
    /// One per approach.
    pub runs: Vec<SpeedRun>,
}

impl SpeedPoint {
    /// The run of the approach labelled `label`.
    pub fn run(&self, label: &str) -> Option<&SpeedRun> {
        self.runs.iter().find(|r| r.label == label)
    }
}

/// Everything the speed study measured.
#[derive(Debug, Clone, Serialize)]
pub struct SpeedStudy {
    /// The paper's trajectory at each rate.
    pub paper: Vec<SpeedPoint>,
    /// The raster on the built-in amplifier.
    pub raster: Vec<SpeedPoint>,
    /// The raster on the stronger amplifier.
    pub raster_strong_amplifier: Vec<SpeedPoint>,
    /// The stronger amplifier's slew rate, V/s.
    pub strong_slew_v_per_s: f64,
}

/// A trajectory from rest: 1 s raised cosine to its first value, 1 s there, then itself.
/// Returns it and where the trajectory starts (the speed study's runs, and the diagnosis
/// examples' and tests' that compare with them).
pub fn from_rest(trajectory: &[f64], sample_rate_hz: f64) -> (Vec<f64>, usize) {
    let second = sample_rate_hz.round() as usize;
    let first = trajectory[0];
    let mut out: Vec<f64> = (1..=second)
        .map(|k| first * 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / second as f64).cos()))
        .collect();
    out.extend(std::iter::repeat_n(first, second));
    let start = out.len();
    out.extend_from_slice(trajectory);
    (out, start)
}

/// Indices on `from..`, with e_mhe bins the window supports (10 samples each, at most 100).
fn indices(
    desired: &[f64],
    measured: &[f64],
    from: usize,
    label: &str,
) -> Result<TrackingIndices, StudyError> {
    let bins = ((desired.len() - from) / 10).clamp(1, 100);
    crate::study::evaluate(desired, measured, from, bins, label)
}

/// Share of the samples of `command[from..]` at the amplifier's slew or rail limit (the
/// amplifier run over the whole command, from rest).
fn window_limited_share(
    stage: &StageConfig,
    command: &[f64],
    from: usize,
) -> Result<f64, StudyError> {
    let whole = feasibility(stage, command)?.limited_samples();
    let before = feasibility(stage, &command[..from])?.limited_samples();
    Ok((whole - before) as f64 / (command.len() - from).max(1) as f64)
}

/// The largest drive step per sample `stage`'s amplifier follows within [`SLEW_MARGIN`] of its
/// slew rate, in command volts.
pub fn max_drive_step_v(stage: &StageConfig) -> f64 {
    SLEW_MARGIN * stage.amplifier.slew_rate_v_per_s() / stage.amplifier.gain / stage.sample_rate_hz
}

/// Each approach's drive for `desired`: the faithful one, or with `slew_limited` the
/// slew-constrained one where a chain with a vibration link asks more than the amplifier's
/// slew rate (see [`crate::slew_drive`]); whether it was constrained.
fn drive_for(
    stage: &StageConfig,
    approach: &Approach<'_>,
    full_scale: f64,
    band_hz: Option<f64>,
    desired: &[f64],
    slew_limited: bool,
) -> Result<(Vec<f64>, bool), StudyError> {
    if let (true, None, Some((model, method))) = (slew_limited, band_hz, approach.model)
        && model.vibration.is_some()
        && matches!(method, Method::Ihc | Method::Wihc)
    {
        // A programme the solver could not finish (or too long) leaves the faithful drive:
        // the run is then reported as not slew-constrained, never lost.
        if let Ok(drive) = crate::slew_drive::slew_constrained_drive(
            model,
            method,
            (0.0, full_scale),
            desired,
            max_drive_step_v(stage),
        ) {
            return Ok((drive.drive, drive.constrained));
        }
    }
    let (command, _) = approach.command_in_band(desired, full_scale, band_hz)?;
    Ok((command, false))
}

#[allow(clippy::too_many_arguments)]
fn runs(
    stage: &StageConfig,
    seed: u64,
    approaches: &[Approach<'_>],
    full_scale: f64,
    band_hz: Option<f64>,
    desired: &[f64],
    from: usize,
    slew_limited: bool,
) -> Result<Vec<SpeedRun>, StudyError> {
    approaches
        .par_iter()
        .map(|approach| {
            let (command, slew_constrained) =
                drive_for(stage, approach, full_scale, band_hz, desired, slew_limited)?;
            let limited_share = window_limited_share(stage, &command, from)?;
            let measured = track(stage, seed, &command)?;
            Ok(SpeedRun {
                label: approach.label.clone(),
                indices: indices(desired, &measured, from, &approach.label)?,
                limited_share,
                slew_constrained,
            })
        })
        .collect()
}

/// Runs the speed study for `approaches` (the last is the one whose drive sets the amplitude
/// reductions: the `full` pipeline's IHC), chains with a vibration link inverting the
/// trajectory low-passed at `band_hz` when given. See the [module documentation](self).
pub(crate) fn run_speed(
    stage: &StageConfig,
    seed: u64,
    approaches: &[Approach<'_>],
    full_scale: f64,
    band_hz: Option<f64>,
) -> Result<SpeedStudy, StudyError> {
    let fs = stage.sample_rate_hz;
    let option = |e: crate::signals::SignalError| StudyError::Option(e.to_string());
    let paper = PaperTrajectory::new();
    let judge = approaches
        .last()
        .ok_or_else(|| StudyError::Option("the speed study needs an approach".into()))?;
    let paper_points: Vec<SpeedPoint> = PAPER_RATES_HZ
        .par_iter()
        .map(|&rate| -> Result<SpeedPoint, StudyError> {
            let speed = rate / paper.highest_frequency_hz();
            let mut scale = 1.0;
            let make = |scale: f64| -> Result<(Vec<f64>, usize, usize), StudyError> {
                let signal = Signal {
                    amplitude: paper.half_range_um() * scale,
                    ..Signal::paper(speed, 20.0 / speed, fs)
                };
                let trajectory = signal.sample().map_err(option)?;
                let per_period = trajectory.len() / 2;
                let (desired, start) = from_rest(&trajectory, fs);
                Ok((desired, start, start + per_period))
            };
            for _ in 0..MAX_REDUCTIONS {
                let (desired, _, from) = make(scale)?;
                let (command, _) = judge.command_in_band(&desired, full_scale, band_hz)?;
                if window_limited_share(stage, &command, from)? == 0.0 {
                    break;
                }
                // The peak slew the evaluated period asks at the amplifier's output.
                let peak = command[from - 1..]
                    .windows(2)
                    .map(|w| (w[1] - w[0]).abs())
                    .fold(0.0, f64::max)
                    * stage.amplifier.gain
                    * fs;
                if peak <= 0.0 {
                    break;
                }
                let limit = stage.amplifier.slew_rate_v_per_s();
                scale *= (SLEW_MARGIN * limit / peak).min(SLEW_MARGIN);
            }
            let (desired, _, from) = make(scale)?;
            Ok(SpeedPoint {
                rate_hz: rate,
                amplitude_scale: scale,
                runs: runs(
                    stage, seed, approaches, full_scale, band_hz, &desired, from, false,
                )?,
            })
        })
        .collect::<Result<_, _>>()?;
    let mut strong = stage.clone();
    strong.amplifier.peak_current_ma = STRONG_PEAK_CURRENT_MA;
    let raster_on = |config: &StageConfig| -> Result<Vec<SpeedPoint>, StudyError> {
        RASTER_RATES_HZ
            .par_iter()
            .map(|&rate| {
                let periods_s = RASTER_PERIODS as f64 / rate;
                let signal = Signal {
                    shape: Shape::Raster(Raster::triangle(rate, RASTER_ROUNDING)),
                    amplitude: RASTER_UM / 2.0,
                    offset: paper.mid_range_um(),
                    duration_s: periods_s,
                    speed: 1.0,
                    sample_rate_hz: fs,
                };
                let trajectory = signal.sample().map_err(option)?;
                let (desired, _) = from_rest(&trajectory, fs);
                let from = desired.len() - (5.0 / rate * fs).round() as usize;
                Ok(SpeedPoint {
                    rate_hz: rate,
                    amplitude_scale: 1.0,
                    runs: runs(
                        config, seed, approaches, full_scale, band_hz, &desired, from, true,
                    )?,
                })
            })
            .collect()
    };
    Ok(SpeedStudy {
        paper: paper_points,
        raster: raster_on(stage)?,
        raster_strong_amplifier: raster_on(&strong)?,
        strong_slew_v_per_s: strong.amplifier.slew_rate_v_per_s(),
    })
}
