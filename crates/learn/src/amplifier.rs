//! The drive the amplifier actually delivers: anti-windup of the learned reference against
//! the amplifier's slew-rate limit.
//!
//! # Why
//! A piezo amplifier drives the stack's capacitance through a current limit: its output
//! follows its input with a first-order small-signal response (bandwidth `f_bw`) and never
//! faster than its slew rate `S = I_max / C`. The plant model's vibration link was identified
//! from the command, through the amplifier's linear response: the model already holds the
//! bandwidth, not the slew limit. When a learned drive asks more slew than the amplifier has
//! (the corners of a fast raster, where the vibration inverse puts its pulses), the stage
//! answers the drive the amplifier delivered, not the one the learner sent; the error there
//! cannot move, the update keeps adding to the reference, and the reference winds up.
//!
//! # The laws tried ([`AntiWindupLaw`])
//! - **Delivered** (back-calculation: the integrator's state re-set from the actuator's actual
//!   output, K. J. Astrom, T. Hagglund, "Advanced PID control", ISA 2006, on integrator
//!   windup; the reference's clamp into the reachable range is the same for the rails): the
//!   learner's state is the reference of the drive the amplifier DELIVERS,
//!   `r_k = P[A^-1[A[v_k]]]`, with `A` the amplifier's large-signal response over its gain
//!   (bandwidth and slew, from its nominal specification, [`AmplifierSpec`]) and `A^-1` its
//!   exact inverse sample by sample ([`input_for_step`]; where it slews the whole period, the
//!   least input that does): [`delivered_drive`] is the least drive that gives the same
//!   output, so the state re-sent delivers the same again. Where the amplifier does not slew
//!   it is `v` exactly and nothing changes; where it slews, the correction it could not
//!   deliver is dropped instead of accumulated. The drive sent is still `C[r]`.
//! - **Projected**: as Delivered, and the drive is the slew-feasible drive nearest `C[r]` at
//!   the amplifier's OUTPUT (after its bandwidth, where its limit is; not a bound on the
//!   command's steps, which the vibration inverse's corner pulses exceed while the amplifier
//!   follows them): [`slew_feasible_drive`].
//! - **Conditional** integration: the state stays `r`; the error is not learned from at the
//!   samples where the amplifier slews the way the error asks.
//!
//! # Measured: none of them helps (examples/learn_slew_diag.rs, README)
//! On the learning study's 100 Hz raster (seed 1), the `full` plant model with thresholds
//! `((i-1)/n)^1.5`: without anti-windup the learning is monotone and slow (best of 20 trials
//! 0.120 %, 13-16 % of the samples slewing), and the reference's part the amplifier does not
//! deliver grows from 0.21 to 0.86 um RMS (2.7 um at the corners): it does wind up. With an
//! anti-windup it gets worse: Delivered 2.93, 0.93, 0.76, 1.05, 1.63 % and stopped by the
//! divergence guard; Projected best 0.31 % (margin 0.95, then drifting to 0.46 %) or 0.37 %
//! (0.98, stopped at trial 10); Conditional stalls at 0.44 %. With uniform thresholds, where
//! the plain learning reaches 0.057 %, Delivered and Projected diverge too and Conditional
//! changes nothing. With Delivered the slewing share climbs back (11 to 18 %) and most of the
//! error sits at the corners when it stops; neither half the gain nor a phase lead of 1, 2 or
//! 4 samples keeps it from diverging. With Conditional, 99 % of the error left is at the
//! slewing corners. So the windup is not what limits the plain learner: its wound-up ask
//! changes nothing in the trial (the least drive [`delivered_drive`] gives the same output),
//! it only absorbs the part of each correction that falls on the slewing samples, while `Q`
//! spreads the corner's error onto the neighbouring samples, where the drive still acts:
//! slow but stable. Conditional removes the corner's
//! error from the learning, and that is lost. Our reading of the divergence of Delivered and
//! Projected, not isolated further: re-set to the edge of the limit, a correction is no
//! longer absorbed, and a larger ask lengthens the ramp (its effect appears where the ramp
//! ends), a response the update, which assumes `P[C[r]] = r`, does not know. So these laws
//! stay off; the cure would be a learning update that knows the amplifier's response (its gradient
//! through the slew limit), not an anti-windup.
//!
//! # The amplifier's response
//! `du/dt = clamp(w (v - u), -S, S)` (`w = 2 pi f_bw`, all in the drive's voltage unit: the
//! amplifier's output over its gain), with the input `v` held over each sample period `T`.
//! The solution over one period is exact: a straight line at the slew rate while the error
//! exceeds `S / w`, then the first-order exponential. The linear response alone (`S`
//! unbounded) is `u_k = v_k - (v_k - u_(k-1)) d`, `d = exp(-w T)`, whose inverse is
//! `v_k = (u_k - d u_(k-1)) / (1 - d)`.

use serde::{Deserialize, Serialize};

/// Periods a periodic drive is run through the amplifier before the one returned (its state
/// at the period's start is then the periodic one).
const PERIODIC_WARMUP_PASSES: usize = 2;

/// The amplifier's nominal large-signal specification, in the drive's voltage unit (the
/// amplifier's output divided by its gain).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AmplifierSpec {
    /// Small-signal -3 dB bandwidth of its first-order response with the stack as load, Hz.
    pub bandwidth_hz: f64,
    /// Slew-rate limit, drive volts per second (the amplifier's `I_max / C` over its gain).
    pub slew_rate_per_s: f64,
}

impl AmplifierSpec {
    /// Whether both figures are finite and above 0.
    pub fn is_valid(&self) -> bool {
        self.bandwidth_hz.is_finite()
            && self.bandwidth_hz > 0.0
            && self.slew_rate_per_s.is_finite()
            && self.slew_rate_per_s > 0.0
    }
}

/// Which anti-windup the learner applies against the amplifier's slew limit (see the
/// [module documentation](self)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "kebab-case")]
pub enum AntiWindupLaw {
    /// Back-calculation: the learner's state is the reference of the drive the amplifier
    /// delivers, `P[A^-1[A[v]]]` ([`delivered_drive`]); the drive sent is `C[r]`.
    Delivered,
    /// As [`AntiWindupLaw::Delivered`], and every drive is the slew-feasible drive nearest
    /// `C[r]` at the amplifier's output, its steps within `margin` (0 to 1) times the slew
    /// rate's ([`slew_feasible_drive`]).
    Projected {
        /// The share of the slew rate the output's steps are kept within.
        margin: f64,
    },
    /// Conditional integration: the state stays `r`, and the error is not learned from
    /// (set to zero before the filter `Q`) at a sample where the amplifier slews in the
    /// direction the error asks.
    Conditional,
}

/// The learner's anti-windup against the amplifier's slew limit
/// ([`crate::LearningOptions::anti_windup`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AntiWindup {
    /// The amplifier's nominal specification.
    pub amplifier: AmplifierSpec,
    /// The law.
    pub law: AntiWindupLaw,
}

impl AntiWindup {
    /// Whether the learner's state is reset to the delivered drive's reference.
    pub fn resets_state(&self) -> bool {
        !matches!(self.law, AntiWindupLaw::Conditional)
    }
}

/// One sample of the amplifier: the output at the end of a period `period_s` over which the
/// input `v` is held, from the output `u` at its start.
fn step(spec: &AmplifierSpec, period_s: f64, u: f64, v: f64) -> f64 {
    let omega = 2.0 * std::f64::consts::PI * spec.bandwidth_hz;
    let s = spec.slew_rate_per_s;
    let error = v - u;
    let linear_error = s / omega;
    if error.abs() <= linear_error {
        v - error * (-omega * period_s).exp()
    } else {
        let sign = error.signum();
        let slewing_s = (error.abs() - linear_error) / s;
        if slewing_s >= period_s {
            u + sign * s * period_s
        } else {
            v - sign * linear_error * (-omega * (period_s - slewing_s)).exp()
        }
    }
}

/// The amplifier's output (over its gain) at the end of each sample of `drive`, sampled at
/// `sample_rate_hz`: from rest at `0` for a finite record; in its periodic state for a
/// `periodic` one (the drive played period after period).
pub fn amplifier_output(
    spec: &AmplifierSpec,
    sample_rate_hz: f64,
    drive: &[f64],
    periodic: bool,
) -> Vec<f64> {
    let period_s = 1.0 / sample_rate_hz;
    let mut u = if periodic {
        drive.last().copied().unwrap_or(0.0)
    } else {
        0.0
    };
    if periodic {
        for _ in 0..PERIODIC_WARMUP_PASSES {
            for &v in drive {
                u = step(spec, period_s, u, v);
            }
        }
    }
    drive
        .iter()
        .map(|&v| {
            u = step(spec, period_s, u, v);
            u
        })
        .collect()
}

/// `A^-1[A[drive]]`: the least drive that makes the amplifier deliver what it delivers for
/// `drive` (sample by sample [`input_for_step`]; see the [module documentation](self)). Equal
/// to `drive` (to rounding) wherever the amplifier never slews the whole period.
pub fn delivered_drive(
    spec: &AmplifierSpec,
    sample_rate_hz: f64,
    drive: &[f64],
    periodic: bool,
) -> Vec<f64> {
    let output = amplifier_output(spec, sample_rate_hz, drive, periodic);
    inputs_for_outputs(spec, 1.0 / sample_rate_hz, &output, periodic)
}

/// The drive that makes the amplifier deliver `output` sample by sample ([`input_for_step`]),
/// each step from the previous output (the last one for a periodic record, else rest at 0 V).
fn inputs_for_outputs(
    spec: &AmplifierSpec,
    period_s: f64,
    output: &[f64],
    periodic: bool,
) -> Vec<f64> {
    let n = output.len();
    (0..n)
        .map(|k| {
            let before = if k > 0 {
                output[k - 1]
            } else if periodic {
                output[n - 1]
            } else {
                0.0
            };
            input_for_step(spec, period_s, before, output[k])
        })
        .collect()
}

/// Samples of `drive` over which the amplifier slews for the whole period (same start as
/// [`amplifier_output`]).
pub fn slewing_samples(
    spec: &AmplifierSpec,
    sample_rate_hz: f64,
    drive: &[f64],
    periodic: bool,
) -> usize {
    let output = amplifier_output(spec, sample_rate_hz, drive, periodic);
    let full = spec.slew_rate_per_s / sample_rate_hz;
    let n = output.len();
    (0..n)
        .filter(|&k| {
            let before = if k > 0 {
                output[k - 1]
            } else if periodic {
                output[n - 1]
            } else {
                0.0
            };
            (output[k] - before).abs() >= full * (1.0 - 1e-9)
        })
        .count()
}

/// The amplifier's linear (small-signal) response to `drive`, `u_k = v_k - (v_k - u_(k-1)) d`
/// (same start as [`amplifier_output`]): the output a slew-unlimited amplifier delivers.
pub fn linear_output(
    spec: &AmplifierSpec,
    sample_rate_hz: f64,
    drive: &[f64],
    periodic: bool,
) -> Vec<f64> {
    let unlimited = AmplifierSpec {
        slew_rate_per_s: f64::INFINITY,
        ..*spec
    };
    let d = (-2.0 * std::f64::consts::PI * unlimited.bandwidth_hz / sample_rate_hz).exp();
    let mut u = if periodic {
        drive.last().copied().unwrap_or(0.0)
    } else {
        0.0
    };
    if periodic {
        for _ in 0..PERIODIC_WARMUP_PASSES {
            for &v in drive {
                u = v - (v - u) * d;
            }
        }
    }
    drive
        .iter()
        .map(|&v| {
            u = v - (v - u) * d;
            u
        })
        .collect()
}

/// The held input that takes the amplifier's output from `before` to `after` in one period,
/// when the step is below the slew rate's `S T` (the exact inverse of one sample of
/// [`amplifier_output`]'s law: linear below `(1 - d) S / w`, else the slew-then-exponential
/// solution, monotone in the input, solved by bisection); a step at or beyond `S T` gets the
/// input that slews the whole period.
pub fn input_for_step(spec: &AmplifierSpec, period_s: f64, before: f64, after: f64) -> f64 {
    let omega = 2.0 * std::f64::consts::PI * spec.bandwidth_hz;
    let s = spec.slew_rate_per_s;
    let d = (-omega * period_s).exp();
    let step = after - before;
    let linear_error = s / omega;
    if step.abs() <= (1.0 - d) * linear_error {
        return before + step / (1.0 - d);
    }
    let sign = step.signum();
    let wanted = step.abs().min(s * period_s);
    // The output step for an input error e in [S/w, S/w + S T].
    let reached = |e: f64| {
        let slewing_s = (e - linear_error) / s;
        e - linear_error * (-omega * (period_s - slewing_s)).exp()
    };
    let (mut lo, mut hi) = (linear_error, linear_error + s * period_s);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if reached(mid) < wanted {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    before + sign * 0.5 * (lo + hi)
}

/// The slew-feasible drive nearest `drive` at the amplifier's OUTPUT: the linear response to
/// `drive` ([`linear_output`]) projected (Euclidean, [`crate::slew::project_slew`]) onto the
/// outputs within `limits` whose every step is within `margin S T`, then the input that makes
/// the amplifier deliver it sample by sample ([`input_for_step`]), clamped to `limits`. Where
/// the linear response is already within the bound, the drive comes back unchanged (to
/// rounding): the bound is the amplifier's own, after its bandwidth, not a bound on the
/// command's steps (which the vibration inverse's corner pulses exceed while the amplifier
/// follows them). For a finite record the first step, from rest, is not bounded.
pub fn slew_feasible_drive(
    spec: &AmplifierSpec,
    sample_rate_hz: f64,
    drive: &[f64],
    limits: (f64, f64),
    periodic: bool,
    margin: f64,
) -> Vec<f64> {
    let period_s = 1.0 / sample_rate_hz;
    let wanted = linear_output(spec, sample_rate_hz, drive, periodic);
    let max_step = margin * spec.slew_rate_per_s * period_s;
    let projection = crate::slew::project_slew(&wanted, max_step, limits, periodic);
    if projection.violations == 0 {
        return drive.iter().map(|v| v.clamp(limits.0, limits.1)).collect();
    }
    inputs_for_outputs(spec, period_s, &projection.drive, periodic)
        .into_iter()
        .map(|v| v.clamp(limits.0, limits.1))
        .collect()
}
