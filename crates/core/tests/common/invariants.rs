//! The safety invariants of every compensator, checked on one model and one input signal of
//! any values (NaN, infinities, 1e308, subnormals...): shared by the proptests
//! (`tests/invariants.rs`, on stable, in CI) and the fuzz target `compensators`
//! (`fuzz/fuzz_targets/compensators.rs`), so that both check the same properties.
//!
//! For every sample of every compensator (the last three for models of moderate size, see
//! [`Subject::moderate`]):
//! - the output is finite and within the limits;
//! - a NaN or infinite desired position holds the previous output and is counted as
//!   non-finite (nothing else is);
//! - exact modes (IHC, WIHC solved exactly) reproduce `y_d` through the plant, `P[v] = y_d`,
//!   unless the sample was counted as clamped: every clamp is counted;
//! - DIHC emits its inverse model's output on `y_d` clamped into the model's input range,
//!   clamped into the limits, and counts the sample whenever either clamp moved a value;
//! - every mode counts each sample whose desired position lies beyond any reachable position
//!   (e.g. 1e308) by more than rounding, since its output is then clamped.
#![allow(dead_code)]

use hystcomp_core::{Compensator, Dihc, Ihc, Mpim, OutputLimits, Real, SolveMode, Wihc};

/// One plant model (or inverse model, for DIHC) and the compensators built on it.
pub struct Subject<T: Real> {
    /// The plant (IHC, WIHC) or inverse (DIHC) model.
    pub model: Mpim<T, Vec<T>>,
    /// The output limits.
    pub limits: OutputLimits<T>,
    /// Whether the model is of the normalised form model files hold (thresholds in [0, 1),
    /// parameters and limits of moderate size), so that exact solves must reproduce `y_d` and
    /// every clamp must be counted. Any other model the constructors accept is checked for
    /// the safety invariants only (finite outputs within the limits, non-finite inputs held).
    pub moderate: bool,
}

/// What went wrong, for the test's or the fuzzer's message.
pub type Violation = String;

/// The relative tolerance of `P[v] = y_d` for exact modes in `T`.
fn tolerance<T: Real>() -> f64 {
    // 1e-9 in f64, about 1e-3 in f32 (the solves stop at a few ulps of the branch).
    (T::epsilon().to_f64() * 1e4).max(1e-9)
}

/// Checks the output of one sample against the limits and the non-finite rule; returns
/// whether the sample's desired position was finite.
fn check_common<T: Real>(
    name: &str,
    k: usize,
    desired: T,
    output: T,
    previous: T,
    limits: OutputLimits<T>,
    (non_finite_before, non_finite_after): (u64, u64),
) -> Result<bool, Violation> {
    if !output.is_finite() || output < limits.min() || output > limits.max() {
        return Err(format!(
            "{name} sample {k}: output {} outside the limits [{}, {}] for y_d = {}",
            output.to_f64(),
            limits.min().to_f64(),
            limits.max().to_f64(),
            desired.to_f64()
        ));
    }
    if desired.is_finite() {
        if non_finite_after != non_finite_before {
            return Err(format!(
                "{name} sample {k}: finite y_d {} counted as non-finite",
                desired.to_f64()
            ));
        }
        Ok(true)
    } else {
        if non_finite_after != non_finite_before + 1 {
            return Err(format!("{name} sample {k}: non-finite y_d not counted"));
        }
        if output != previous {
            return Err(format!(
                "{name} sample {k}: non-finite y_d did not hold the previous output ({} -> {})",
                previous.to_f64(),
                output.to_f64()
            ));
        }
        Ok(false)
    }
}

/// The clamped-sample count of a compensator (either reason).
fn clamps<T: Real>(c: &dyn Compensator<T>) -> u64 {
    let d = c.diagnostics();
    d.saturated + d.loop_saturated
}

/// Exact or delayed IHC and WIHC on the plant `subject.model`, over `desired`.
pub fn check_plant_compensators<T: Real>(
    subject: &Subject<T>,
    desired: &[T],
) -> Result<(), Violation> {
    let limits = subject.limits;
    let plant = &subject.model;
    let mut compensators: Vec<(&str, Box<dyn Compensator<T>>, bool)> = Vec::new();
    for (name, mode, exact) in [
        ("ihc", SolveMode::Exact, true),
        ("ihc-delayed", SolveMode::Delayed, false),
        ("ihc-guarded", SolveMode::DelayedGuarded, false),
        (
            "ihc-delayed, unchecked",
            SolveMode::DelayedAllowUnstable,
            false,
        ),
    ] {
        if let Ok(c) = Ihc::<T, Vec<T>>::new(plant, limits, mode) {
            compensators.push((name, Box::new(c), exact));
        }
    }
    for (name, mode, exact) in [
        ("wihc", SolveMode::Exact, true),
        ("wihc-delayed", SolveMode::Delayed, false),
        ("wihc-guarded", SolveMode::DelayedGuarded, false),
        (
            "wihc-delayed, unchecked",
            SolveMode::DelayedAllowUnstable,
            false,
        ),
    ] {
        if let Ok(c) = Wihc::<T, Vec<T>>::new(plant, limits, mode) {
            compensators.push((name, Box::new(c), exact));
        }
    }
    // The largest output the plant can give within the limits, from any state, bounds every
    // reachable y_d: beyond a margin of it, every sample must be clamped.
    let reach = reachable_bound(plant, limits);
    for (name, mut c, exact) in compensators {
        let mut p = plant.clone();
        let mut previous = limits_start(limits);
        for (k, &y_d) in desired.iter().enumerate() {
            let before = c.diagnostics();
            let clamped_before = clamps(c.as_ref());
            let v = c.step(y_d);
            let after = c.diagnostics();
            let finite = check_common(
                name,
                k,
                y_d,
                v,
                previous,
                limits,
                (before.non_finite, after.non_finite),
            )?;
            previous = v;
            if !finite {
                continue;
            }
            let counted = clamps(c.as_ref()) > clamped_before;
            let y = p.step(v);
            if !subject.moderate {
                continue;
            }
            let error = (y - y_d).abs().to_f64();
            // The solves work to a relative 1e-13 of the terms they add up, whose size the
            // plant's reach over the limits bounds: with a cubic of large limits the rounding
            // of a position near 0 is that of the largest term, not of the position.
            let scale = 1.0 + y_d.abs().to_f64().max(y.abs().to_f64()) + reach;
            if exact && !counted && (error.is_nan() || error > tolerance::<T>() * scale) {
                return Err(format!(
                    "{name} sample {k}: P[v] = {} for y_d = {} (v = {}), an error of {error}, \
                     and the sample was not counted as clamped",
                    y.to_f64(),
                    y_d.to_f64(),
                    v.to_f64()
                ));
            }
            // Beyond any reachable position by more than the rounding the core allows (its
            // solves work to an absolute tolerance in normalised units, where the working
            // range is of order 1), the sample must be counted as clamped.
            let beyond = y_d.abs().to_f64() - reach;
            if y_d.abs().to_f64() > 2.0 * reach && beyond > tolerance::<T>() * scale && !counted {
                return Err(format!(
                    "{name} sample {k}: y_d = {:e} is beyond any reachable position (|y| <= {reach:e}) \
                     but the clamp of v = {} was not counted",
                    y_d.to_f64(),
                    v.to_f64()
                ));
            }
        }
    }
    Ok(())
}

/// The output before the first sample: 0 clamped into the limits.
fn limits_start<T: Real>(limits: OutputLimits<T>) -> T {
    limits.clamp_or(T::zero(), T::zero())
}

/// A bound on `|P[v]|` for `v` within the limits from any state reachable within them:
/// `|a1| m^3 + |a2| m + sum |b_i| m` with `m` the largest limit magnitude (each play
/// operator's output lies within the range of its inputs and 0).
fn reachable_bound<T: Real>(plant: &Mpim<T, Vec<T>>, limits: OutputLimits<T>) -> f64 {
    let m = limits.min().abs().max(limits.max().abs()).to_f64();
    let weights: f64 = plant.weights().iter().map(|b| b.abs().to_f64()).sum();
    plant.a1().abs().to_f64() * m * m * m + plant.a2().abs().to_f64() * m + weights * m
}

/// DIHC with the inverse model `subject.model` on the input range `[lo, hi]`, over `desired`.
pub fn check_dihc<T: Real>(
    subject: &Subject<T>,
    lo: T,
    hi: T,
    desired: &[T],
) -> Result<(), Violation> {
    let limits = subject.limits;
    let Ok(mut c) = Dihc::<T, Vec<T>>::new(&subject.model, lo, hi, limits) else {
        return Ok(());
    };
    let mut reference = subject.model.clone();
    let mut previous = limits_start(limits);
    for (k, &y_d) in desired.iter().enumerate() {
        let before = c.diagnostics();
        let clamped_before = before.saturated + before.loop_saturated;
        let v = c.step(y_d);
        let after = c.diagnostics();
        let finite = check_common(
            "dihc",
            k,
            y_d,
            v,
            previous,
            limits,
            (before.non_finite, after.non_finite),
        )?;
        previous = v;
        if !finite {
            continue;
        }
        let x = y_d.max(lo).min(hi);
        let raw = reference.step(x);
        if !subject.moderate {
            continue;
        }
        let expected = limits.clamp_or(raw, v);
        let counted = after.saturated + after.loop_saturated > clamped_before;
        let rounding = T::epsilon().to_f64() * 64.0 * raw.abs().to_f64().max(1.0);
        let moved = x != y_d || !raw.is_finite() || (expected - raw).abs().to_f64() > rounding;
        if raw.is_finite() && v != expected {
            return Err(format!(
                "dihc sample {k}: emitted {} where the inverse model gives {} (clamped {})",
                v.to_f64(),
                raw.to_f64(),
                expected.to_f64()
            ));
        }
        if moved && !counted {
            return Err(format!(
                "dihc sample {k}: y_d = {} (model input {}, output {}) was clamped but not \
                 counted",
                y_d.to_f64(),
                x.to_f64(),
                raw.to_f64()
            ));
        }
    }
    Ok(())
}
