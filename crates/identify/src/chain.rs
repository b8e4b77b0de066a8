//! Identification of the whole chain `hysteresis -> creep -> vibration` (Croft, Shed & Devasia
//! 2001, doi:10.1115/1.1341197) from (voltage, displacement) samples only.
//!
//! 1. **Hysteresis alone**: the MPIM of [`crate::identify`] on the (decimated) record, as a
//!    reference for what the other links contribute.
//! 2. **Hysteresis and creep jointly**, by one linear least-squares fit under the same
//!    invertibility constraints. The creep link is written through its inverse
//!    (`hystcomp_core::Creep`): `h = y - sum_i c_i (z_i[y] - origin)` with first-order
//!    elements `z_i` at fixed log-spaced time constants (Kuhnen's creep operators, Kuhnen 2005;
//!    Krejci & Kuhnen 2001 and Kuhnen & Krejci 2009, the paper's refs. \[25\] and \[8\]),
//!    so that the measured displacement obeys
//!
//!    `y(k) = H[v](k) + c + sum_i c_i z_i[y](k)`,
//!
//!    linear in the MPIM's parameters, the offset and the weights `c_i` together: the filtered
//!    measurements `z_i[y]` are extra regressors of the [`FitProblem`] (an equation-error fit;
//!    the filters average the sensor noise away, so its bias is negligible). With the creep
//!    link in the forward form after the hysteresis the same fit would be bilinear and need
//!    alternating least squares. The elements start at rest at the record's first
//!    displacement, which is taken as the relaxed position (`origin`): records should start
//!    from rest.
//!    When the vibration segment lies in the second half of the record, the hysteresis and
//!    creep are fitted on the samples before it.
//! 3. **Vibration** ([`crate::dynamics`]): the hysteresis and creep links predict their output
//!    from the voltage at the record's full rate, and the vibration link is fitted between that
//!    prediction and the measured displacement on a segment with high-frequency content.
//!
//! An **inverse** (DIHC) chain uses the plant's creep and vibration links and fits its MPIM
//! from the creep-free displacement `C^-1[y]` to the voltage ([`crate::identify`] with
//! `Direction::Inverse`).
//!
//! The report gives each link's contribution: the RMS error of the hysteresis alone, with
//! creep, and with vibration, over the fitted samples and over the vibration segment.

use std::time::Instant;

use hystcomp_core::{Ihc, Mpim, OutputLimits, SolveMode, Wihc};
use hystcomp_io::model_file::{CreepPart, Direction, ModelFile, Scale};
use serde::{Deserialize, Serialize};

use crate::dynamics::{DynamicsFit, DynamicsOptions, fit_dynamics};
use crate::report::ErrorStats;
use crate::{
    FitProblem, FitReport, Identification, IdentifyError, IdentifyOptions, LeastSquares, Method,
    NoObserver, ProblemData, Solver, identify,
};

/// The shortest hold the creep fit on holds uses, s.
pub const MIN_HOLD_S: f64 = 1.0;

/// The most creep time constants.
pub const MAX_CREEP_ELEMENTS: usize = hystcomp_core::MAX_CREEP_ELEMENTS;
/// The largest decimation of the hysteresis-and-creep fit.
pub const MAX_DECIMATION: usize = 1000;

/// The creep link's time constants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CreepOptions {
    /// Time constants `tau_i`, s: positive, increasing, at most [`MAX_CREEP_ELEMENTS`].
    pub time_constants_s: Vec<f64>,
    /// Weight of the smoothness penalty on neighbouring creep weights (0: none; see
    /// [`FitProblem::with_extra_smoothness`]).
    #[serde(default)]
    pub smoothness: f64,
    /// Fit the weights on the record's holds alone (where the voltage stays constant for at
    /// least [`MIN_HOLD_S`]), then the hysteresis on the creep-free displacement, instead of
    /// both jointly over the whole record (see [`crate::creep_holds`]).
    #[serde(default)]
    pub from_holds: bool,
    /// With [`CreepOptions::from_holds`]: when not empty, the smoothness is chosen among these
    /// by leaving each hold out in turn (see
    /// [`crate::creep_holds::creep_weights_from_holds`]), and `smoothness` is ignored. At most
    /// [`MAX_SMOOTHNESS_CANDIDATES`].
    #[serde(default)]
    pub hold_smoothness_candidates: Vec<f64>,
}

/// The most smoothness candidates of the creep fit on holds.
pub const MAX_SMOOTHNESS_CANDIDATES: usize = 20;

impl CreepOptions {
    /// `per_decade` time constants per decade from `first_s` to `last_s` (both included when
    /// they lie on the grid).
    pub fn log_spaced(first_s: f64, last_s: f64, per_decade: usize) -> CreepOptions {
        let step = 10f64.powf(1.0 / per_decade.max(1) as f64);
        let mut time_constants_s = Vec::new();
        let mut tau = first_s;
        while tau <= last_s * (1.0 + 1e-9) && time_constants_s.len() < MAX_CREEP_ELEMENTS {
            time_constants_s.push(tau);
            tau *= step;
        }
        CreepOptions {
            time_constants_s,
            smoothness: 0.0,
            from_holds: false,
            hold_smoothness_candidates: Vec::new(),
        }
    }

    /// The same time constants with the weights fitted on the record's holds (see
    /// [`CreepOptions::from_holds`]), the smoothness chosen among `candidates` by leaving each
    /// hold out (none: `smoothness` as given).
    pub fn on_holds(self, candidates: &[f64]) -> CreepOptions {
        CreepOptions {
            from_holds: true,
            hold_smoothness_candidates: candidates.to_vec(),
            ..self
        }
    }

    /// The same time constants with the creep weights' smoothness penalty `lambda`.
    pub fn with_smoothness(self, lambda: f64) -> CreepOptions {
        CreepOptions {
            smoothness: lambda,
            ..self
        }
    }

    fn validate(&self, period_s: f64) -> Result<(), IdentifyError> {
        let t = &self.time_constants_s;
        let invalid = |reason: String| IdentifyError::InvalidOption {
            option: "creep time constants",
            value: format!("{t:?}"),
            reason,
        };
        if t.is_empty() || t.len() > MAX_CREEP_ELEMENTS {
            return Err(invalid(format!(
                "give 1 to {MAX_CREEP_ELEMENTS} time constants"
            )));
        }
        if t.iter().any(|v| !(v.is_finite() && *v > 0.0)) || t.windows(2).any(|w| w[1] <= w[0]) {
            return Err(invalid(
                "time constants must be positive and increase".to_owned(),
            ));
        }
        let c = &self.hold_smoothness_candidates;
        if c.len() > MAX_SMOOTHNESS_CANDIDATES || c.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(IdentifyError::InvalidOption {
                option: "creep smoothness candidates",
                value: format!("{c:?}"),
                reason: format!(
                    "give at most {MAX_SMOOTHNESS_CANDIDATES} finite, non-negative weights"
                ),
            });
        }
        if !(self.smoothness.is_finite() && self.smoothness >= 0.0) {
            return Err(IdentifyError::InvalidOption {
                option: "creep smoothness",
                value: self.smoothness.to_string(),
                reason: "give a finite, non-negative weight".to_owned(),
            });
        }
        if t[0] < 2.0 * period_s {
            return Err(invalid(format!(
                "the shortest must be at least two sample periods of the decimated record ({} s)",
                2.0 * period_s
            )));
        }
        Ok(())
    }
}

impl Default for CreepOptions {
    /// Two per decade from 10 ms to 100 s.
    fn default() -> Self {
        CreepOptions::log_spaced(0.01, 100.0, 2)
    }
}

/// What the chain's identification adds to [`IdentifyOptions`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainOptions {
    /// The record's sample rate, Hz.
    pub sample_rate_hz: f64,
    /// The hysteresis and creep links are fitted on every `decimation`-th sample (1: all; the
    /// hysteresis is rate independent and creep slow, so a 1 kHz record suffices); the
    /// vibration link always on the full rate.
    pub decimation: usize,
    /// The creep link, if any.
    pub creep: Option<CreepOptions>,
    /// The vibration link, if any.
    pub dynamics: Option<DynamicsOptions>,
    /// Output-error refinements of the joint hysteresis-and-creep fit at most (see
    /// [`identify_chain`]; 0 keeps the equation-error fit).
    pub output_error_iterations: usize,
}

impl ChainOptions {
    fn validate(&self) -> Result<(), IdentifyError> {
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(IdentifyError::InvalidOption {
                option: "sample rate",
                value: self.sample_rate_hz.to_string(),
                reason: "give the record's sample rate in Hz (positive)".to_owned(),
            });
        }
        if !(1..=MAX_DECIMATION).contains(&self.decimation) {
            return Err(IdentifyError::InvalidOption {
                option: "decimation",
                value: self.decimation.to_string(),
                reason: format!("give 1 to {MAX_DECIMATION}"),
            });
        }
        if let Some(c) = &self.creep {
            c.validate(self.decimation as f64 / self.sample_rate_hz)?;
        }
        if let Some(d) = &self.dynamics {
            d.validate()?;
        }
        Ok(())
    }
}

/// The identified creep link.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CreepFit {
    /// The link as written to the model file.
    pub part: CreepPart,
    /// `1 / (1 - sum c_i)`: how far a held step creeps in the end.
    pub static_gain: f64,
    /// The condition number of the joint fit's column-scaled regressors (of the hysteresis
    /// fit when the weights come from the holds).
    pub condition_number: f64,
    /// The smoothness the weights were fitted with.
    #[serde(default)]
    pub smoothness: f64,
    /// Fitted on the record's holds: `(smoothness, leave-one-hold-out RMS %)` of each
    /// candidate tried (empty otherwise).
    #[serde(default)]
    pub smoothness_candidates: Vec<(f64, f64)>,
}

/// RMS errors of the chain with its links added one by one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contribution {
    /// `hysteresis`, `+ creep` or `+ vibration`.
    pub model: String,
    /// RMS error over the fitted samples, % of the fitted output range.
    pub rms_percent: f64,
    /// RMS error over the vibration segment, same unit (when there is one).
    pub segment_rms_percent: Option<f64>,
}

impl Contribution {
    /// The row of `model` whose `predicted` output is judged against `target` over `span`
    /// and over `segment` when there is one, in % of `scale` (NaN where a range is empty).
    fn measured(
        model: &str,
        predicted: &[f64],
        target: &[f64],
        scale: f64,
        span: &std::ops::Range<usize>,
        segment: Option<&std::ops::Range<usize>>,
    ) -> Self {
        let rms = |range: &std::ops::Range<usize>| {
            ErrorStats::new(&predicted[range.clone()], &target[range.clone()], scale)
                .map_or(f64::NAN, |s| s.rms_percent)
        };
        Contribution {
            model: model.to_owned(),
            rms_percent: rms(span),
            segment_rms_percent: segment.map(rms),
        }
    }
}

/// How the chain was identified and how well it fits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainReport {
    /// The MPIM's own fit report (the chain's hysteresis link; for an inverse chain, the fit
    /// from the creep-free displacement to the voltage).
    pub hysteresis: FitReport,
    /// The creep link, if identified.
    pub creep: Option<CreepFit>,
    /// The vibration link, if identified.
    pub dynamics: Option<DynamicsFit>,
    /// Each link's contribution (RMS with and without it).
    pub contributions: Vec<Contribution>,
    /// The whole chain's errors over the fitted samples at the full rate (physical units; %
    /// of the fitted output range).
    pub fit: ErrorStats,
    /// Wall-clock time, s.
    pub elapsed_s: f64,
    /// Which samples of the record each link was fitted on.
    #[serde(default)]
    pub span: FittedSpan,
}

/// Which samples of the record a chain was identified on: the hysteresis (and its report's
/// sample counts) and the creep on every `decimation`-th of the first `hysteresis_end`, the
/// vibration link on its segment at the full rate.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FittedSpan {
    /// The record's samples.
    pub record: usize,
    /// The hysteresis and creep fit ends here (at the vibration segment when it lies in the
    /// record's second half, else at its end).
    pub hysteresis_end: usize,
    /// Every this many samples fitted for the hysteresis and creep.
    pub decimation: usize,
}

impl FittedSpan {
    fn of(chain: &ChainOptions, record: usize) -> Self {
        FittedSpan {
            record,
            hysteresis_end: fitted_end(chain, record),
            decimation: chain.decimation,
        }
    }
}

/// An identified chain: the model file (format version 2 when it has links) and its report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainIdentification {
    /// The model file, with the report in its `identification` field.
    pub model: ModelFile,
    /// The report.
    pub report: ChainReport,
}

/// Identifies the chain from a record (see the [module documentation](self)). `options`
/// are the MPIM's (the direction decides plant or inverse; the solver must be least squares
/// when creep is fitted); `chain` adds the links.
pub fn identify_chain(
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    chain: &ChainOptions,
) -> Result<ChainIdentification, IdentifyError> {
    let started = Instant::now();
    chain.validate()?;
    if chain.creep.is_some() && options.method != Method::LeastSquares {
        return Err(IdentifyError::InvalidOption {
            option: "method",
            value: "pso".to_owned(),
            reason: "creep is identified jointly with the hysteresis by least squares; use ls"
                .to_owned(),
        });
    }
    hystcomp_io::data::check_same_length(&[("voltage", voltage), ("displacement", displacement)])?;
    if options.output_map_degree > 1 && chain.creep.as_ref().is_some_and(|c| !c.from_holds) {
        return Err(IdentifyError::InvalidOption {
            option: "output map degree",
            value: options.output_map_degree.to_string(),
            reason: "the joint fit of creep and hysteresis fits the MPIM alone; fit the creep \
                     on the record's holds (--creep-fit holds) to add an output map"
                .to_owned(),
        });
    }
    let plant_options = IdentifyOptions {
        direction: Direction::Plant,
        ..options.clone()
    };
    let plant = plant_chain(voltage, displacement, &plant_options, chain)?;
    let (model, report) = match options.direction {
        Direction::Plant => (plant.model, plant.report),
        Direction::Inverse => inverse_chain(voltage, displacement, options, chain, &plant)?,
    };
    let report = ChainReport {
        elapsed_s: started.elapsed().as_secs_f64(),
        span: FittedSpan::of(chain, voltage.len()),
        ..report
    };
    let mut model = model;
    model.identification = serde_json::to_value(&report).ok();
    Ok(ChainIdentification { model, report })
}

/// The pure delay (samples of the full rate, up to `max_delay`) that lets the hysteresis alone
/// fit the decimated displacement `y` best from the delayed voltage.
fn record_delay(
    voltage: &[f64],
    y: &[f64],
    options: &IdentifyOptions,
    decimation: usize,
    max_delay: usize,
) -> Result<usize, IdentifyError> {
    let mut best = (0, f64::INFINITY);
    for d in 0..=max_delay {
        let v: Vec<f64> = (0..voltage.len())
            .step_by(decimation)
            .map(|i| voltage[i.saturating_sub(d)])
            .collect();
        let rms = identify(&v, y, options)?.report.fit.rms_percent;
        if rms < best.1 {
            best = (d, rms);
        }
    }
    Ok(best.0)
}

/// Where the hysteresis and creep fit ends: at the vibration segment when it lies in the
/// second half of the record (its fast content, decimated, would alias into their fit), else
/// at the record's end.
fn fitted_end(chain: &ChainOptions, len: usize) -> usize {
    match chain.dynamics.as_ref().and_then(|d| d.segment.clone()) {
        Some(segment) if segment.start >= len / 2 && segment.start < len => segment.start,
        _ => len,
    }
}

/// The inverse (DIHC) chain for a plant chain identified on the same record with the same
/// `chain` options (saves identifying the plant again): the plant's creep and vibration
/// links, and an MPIM from the creep-free displacement to the voltage fitted with `options`
/// (direction inverse).
pub fn identify_inverse_chain(
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    chain: &ChainOptions,
    plant: &ChainIdentification,
) -> Result<ChainIdentification, IdentifyError> {
    let started = Instant::now();
    chain.validate()?;
    hystcomp_io::data::check_same_length(&[("voltage", voltage), ("displacement", displacement)])?;
    let options = IdentifyOptions {
        direction: Direction::Inverse,
        ..options.clone()
    };
    let plant = Plant {
        model: plant.model.clone(),
        report: plant.report.clone(),
    };
    let (mut model, report) = inverse_chain(voltage, displacement, &options, chain, &plant)?;
    let report = ChainReport {
        elapsed_s: started.elapsed().as_secs_f64(),
        span: FittedSpan::of(chain, voltage.len()),
        ..report
    };
    model.identification = serde_json::to_value(&report).ok();
    Ok(ChainIdentification { model, report })
}

/// Every `k`-th sample.
fn decimate(values: &[f64], k: usize) -> Vec<f64> {
    values.iter().step_by(k).copied().collect()
}

/// The fitted span of a report, in samples of the full-rate record.
fn full_rate_span(report: &FitReport, decimation: usize, len: usize) -> std::ops::Range<usize> {
    let start = (report.samples.warmup * decimation).min(len);
    let end = ((report.samples.warmup + report.samples.fit) * decimation).min(len);
    start..end
}

struct Plant {
    model: ModelFile,
    report: ChainReport,
}

fn plant_chain(
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    chain: &ChainOptions,
) -> Result<Plant, IdentifyError> {
    let k = chain.decimation;
    let end = fitted_end(chain, voltage.len());
    let y = decimate(&displacement[..end], k);
    // With a vibration link, the record's pure delay first: the hysteresis and creep are
    // fitted on the voltage it delays, so that a lag does not pass for creep (the vibration
    // link takes the delay back).
    let delay = match &chain.dynamics {
        Some(d) => record_delay(&voltage[..end], &y, options, k, d.max_delay_samples)?,
        None => 0,
    };
    let delayed: Vec<f64> = (0..end).map(|i| voltage[i.saturating_sub(delay)]).collect();
    let v = decimate(&delayed, k);
    let base: Identification = identify(&v, &y, options)?;
    let rate = chain.sample_rate_hz;
    let (mut model, creep_fit, mut hysteresis_report) = match &chain.creep {
        None => (base.model.clone(), None, base.report.clone()),
        Some(creep) if creep.from_holds => {
            let (model, fit, report) = hold_creep_fit(
                &v,
                &delayed,
                &displacement[..end],
                options,
                &base,
                creep,
                rate,
                k,
            )?;
            (model, Some(fit), report)
        }
        Some(creep) => {
            let (model, fit, report) = joint_creep_fit(
                &v,
                &delayed,
                &displacement[..end],
                options,
                &base,
                creep,
                rate,
                k,
                chain.output_error_iterations,
            )?;
            (model, Some(fit), report)
        }
    };
    let span = full_rate_span(&base.report, k, voltage.len());
    let y_scale = base.report.output.max - base.report.output.min;
    let mut dynamics_fit = None;
    let mut segment = None;
    if let Some(dynamics) = &chain.dynamics {
        let x = model.predict(voltage)?;
        let fit = fit_dynamics(&x, displacement, rate, dynamics)?;
        segment = Some(dynamics.segment.clone().unwrap_or(0..voltage.len()));
        let creep = model.creep.clone();
        model = model.with_links(rate, creep, Some(fit.part.clone()))?;
        dynamics_fit = Some(fit);
    }
    // Contributions: the hysteresis alone, with creep, with vibration.
    let mut contributions = Vec::new();
    // The hysteresis and creep links alone run on the delayed voltage (the vibration link holds
    // the delay).
    let delayed_full: Vec<f64> = (0..voltage.len())
        .map(|i| voltage[i.saturating_sub(delay)])
        .collect();
    // Each prediction (a pass over the whole record at the full rate) once: `add` returns it.
    let mut add =
        |name: &str, file: &ModelFile, input: &[f64]| -> Result<Vec<f64>, IdentifyError> {
            let predicted = file.predict(input)?;
            contributions.push(Contribution::measured(
                name,
                &predicted,
                displacement,
                y_scale,
                &span,
                segment.as_ref(),
            ));
            Ok(predicted)
        };
    add("hysteresis", &base.model, &delayed_full)?;
    if creep_fit.is_some() {
        let creep_only = model.clone().with_links(rate, model.creep.clone(), None)?;
        // The joint fit's own errors (hysteresis and creep), fitted and held-out samples.
        let predicted = add("+ creep", &creep_only, &delayed_full)?;
        let stats = |range: std::ops::Range<usize>| {
            ErrorStats::new(&predicted[range.clone()], &displacement[range], y_scale)
        };
        if let Some(fit) = stats(span.clone()) {
            hysteresis_report.fit = fit;
        }
        hysteresis_report.holdout = stats(span.end..end);
    }
    let predicted = if dynamics_fit.is_some() {
        add("+ vibration", &model, voltage)?
    } else {
        model.predict(voltage)?
    };
    let fit = ErrorStats::new(&predicted[span.clone()], &displacement[span], y_scale).ok_or_else(
        || IdentifyError::InvalidOption {
            option: "fitting span",
            value: "empty".to_owned(),
            reason: "no fitted samples".to_owned(),
        },
    )?;
    model.description = Some(format!(
        "MPIM (plant){}{} identified by hystcomp (ls) from {} samples at {} Hz",
        if creep_fit.is_some() { " + creep" } else { "" },
        if dynamics_fit.is_some() {
            " + vibration"
        } else {
            ""
        },
        voltage.len(),
        rate
    ));
    Ok(Plant {
        model,
        report: ChainReport {
            hysteresis: hysteresis_report,
            creep: creep_fit,
            dynamics: dynamics_fit,
            contributions,
            fit,
            elapsed_s: 0.0,
            span: FittedSpan::default(),
        },
    })
}

/// The default number of output-error refinements of the joint fit at most.
pub const OUTPUT_ERROR_ITERATIONS: usize = 4;

/// Step 2 of the module documentation, on the decimated voltage `v` and the full-rate
/// record (`voltage`, `displacement`; the creep elements filter at the full rate, the rate the
/// model's link runs at, and are then decimated), with the normalisation and fitted span of
/// the hysteresis-only fit `base`.
///
/// The equation-error fit filters the measured displacement. It is then refined towards the
/// output error (as Steiglitz and McBride refine a transfer function): the elements filter the
/// displacement the current model simulates from the voltage instead, and the joint fit is
/// solved again, as long as the simulated model's RMS error over the fitted samples falls
/// (at most `iterations` times). On records where a lag or sensor drift lets
/// the equation error buy its fit with large creep weights (the forward link then amplifies
/// the model's errors), the simulated error decides.
#[allow(clippy::too_many_arguments)]
fn joint_creep_fit(
    v: &[f64],
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    base: &Identification,
    creep: &CreepOptions,
    rate: f64,
    decimation: usize,
    iterations: usize,
) -> Result<(ModelFile, CreepFit, FitReport), IdentifyError> {
    let report = &base.report;
    let (y_ref, y_scale) = (report.output.min, report.output.max - report.output.min);
    let span = full_rate_span(report, decimation, voltage.len());
    let simulated_rms = |file: &ModelFile| -> Result<f64, IdentifyError> {
        let predicted = file.predict(voltage)?;
        Ok(ErrorStats::new(
            &predicted[span.clone()],
            &displacement[span.clone()],
            y_scale,
        )
        .map_or(f64::INFINITY, |s| s.rms_percent))
    };
    let normalised =
        |values: &[f64]| -> Vec<f64> { values.iter().map(|y| (y - y_ref) / y_scale).collect() };
    let mut best = joint_creep_solve(
        v,
        displacement,
        &normalised(displacement),
        options,
        base,
        creep,
        rate,
        decimation,
    )?;
    let mut best_rms = simulated_rms(&best.0)?;
    let mut refinements = 0;
    for _ in 0..iterations {
        let simulated = best.0.predict(voltage)?;
        let Ok(next) = joint_creep_solve(
            v,
            displacement,
            &normalised(&simulated),
            options,
            base,
            creep,
            rate,
            decimation,
        ) else {
            break;
        };
        let rms = simulated_rms(&next.0)?;
        if rms.is_nan() || rms >= best_rms {
            break;
        }
        best = next;
        best_rms = rms;
        refinements += 1;
    }
    best.2.detail = format!(
        "{}; {refinements} output-error refinement(s)",
        best.2.detail
    );
    Ok(best)
}

/// The creep weights from the record's holds, then the hysteresis from the creep-free
/// displacement (see [`crate::creep_holds`]); `v` is the decimated voltage, `voltage` and
/// `displacement` the full-rate record (the voltage delayed by the record's delay).
#[allow(clippy::too_many_arguments)]
fn hold_creep_fit(
    v: &[f64],
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    base: &Identification,
    creep: &CreepOptions,
    rate: f64,
    decimation: usize,
) -> Result<(ModelFile, CreepFit, FitReport), IdentifyError> {
    let period = 1.0 / rate;
    let holds = crate::creep_holds::held_segments(voltage, (MIN_HOLD_S * rate).round() as usize);
    let y_scale = base.report.output.max - base.report.output.min;
    let fit = crate::creep_holds::creep_weights_from_holds(
        displacement,
        period,
        decimation,
        &holds,
        &creep.time_constants_s,
        creep.smoothness,
        &creep.hold_smoothness_candidates,
        y_scale,
    )?;
    let weights = fit.weights;
    let weight_sum: f64 = weights.iter().sum();
    let part = CreepPart {
        origin: displacement[0],
        time_constants_s: creep.time_constants_s.clone(),
        weights,
    };
    let unusable = |e: String| IdentifyError::InvalidOption {
        option: "creep time constants",
        value: format!("{:?}", creep.time_constants_s),
        reason: format!("the creep fit is unusable ({e}); give fewer or longer time constants"),
    };
    let mut inverse = part
        .link(rate)
        .map_err(|e| unusable(e.to_string()))?
        .inverse();
    let creep_free: Vec<f64> = displacement.iter().map(|y| inverse.step(*y)).collect();
    let h = decimate(&creep_free, decimation);
    let hysteresis = identify(v, &h, options)?;
    let file = hysteresis
        .model
        .clone()
        .with_links(rate, Some(part.clone()), None)
        .map_err(|e| unusable(e.to_string()))?;
    let mut report = hysteresis.report.clone();
    report.detail = format!(
        "creep ({} elements) on {} holds, then the hysteresis on the creep-free displacement: {}",
        part.weights.len(),
        holds.len(),
        hysteresis.report.detail
    );
    Ok((
        file,
        CreepFit {
            part,
            static_gain: 1.0 / (1.0 - weight_sum),
            condition_number: hysteresis.report.condition_number,
            smoothness: fit.smoothness,
            smoothness_candidates: fit.candidates,
        },
        report,
    ))
}

/// One joint least-squares fit, the creep elements filtering `source` (normalised, full
/// rate): the measured displacement, or the model's simulation of it.
#[allow(clippy::too_many_arguments)]
fn joint_creep_solve(
    v: &[f64],
    displacement: &[f64],
    source: &[f64],
    options: &IdentifyOptions,
    base: &Identification,
    creep: &CreepOptions,
    rate: f64,
    decimation: usize,
) -> Result<(ModelFile, CreepFit, FitReport), IdentifyError> {
    let report = &base.report;
    let (x_min, x_scale) = (report.input.min, report.input.max - report.input.min);
    let (y_ref, y_scale) = (report.output.min, report.output.max - report.output.min);
    let origin = displacement[0];
    let x: Vec<f64> = v.iter().map(|v| (v - x_min) / x_scale).collect();
    let full: Vec<f64> = displacement.iter().map(|y| (y - y_ref) / y_scale).collect();
    let yn = decimate(&full, decimation);
    let period = 1.0 / rate;
    // The creep elements' outputs at the full rate, at rest at the first sample, decimated.
    let columns: Vec<Vec<f64>> = creep
        .time_constants_s
        .iter()
        .map(|tau| {
            let g = 1.0 - (-period / tau).exp();
            let mut z = source[0];
            let filtered: Vec<f64> = source
                .iter()
                .map(|&value| {
                    z += g * (value - z);
                    z
                })
                .collect();
            decimate(&filtered, decimation)
        })
        .collect();
    let column_refs: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
    let fit = report.samples.warmup..report.samples.warmup + report.samples.fit;
    let thresholds = report.thresholds.clone();
    let problem = FitProblem::with_extra_columns(
        ProblemData {
            input: &x,
            output: &yn,
            fit,
        },
        &thresholds,
        Direction::Plant,
        true,
        options.margin,
        &column_refs,
    )?
    .with_extra_smoothness(creep.smoothness)?;
    let condition = problem.condition_number();
    if condition.is_nan() || condition > options.max_condition {
        return Err(IdentifyError::IllConditioned {
            condition,
            limit: options.max_condition,
        });
    }
    let solution = LeastSquares.solve(&problem, &mut NoObserver)?;
    let parameters = problem.parameters(&solution.theta);
    let weights = problem.extra_parameters(&solution.theta).to_vec();
    let weight_sum: f64 = weights.iter().sum();
    let mpim = Mpim::<f64, Vec<f64>>::new(
        &thresholds,
        &parameters.weights,
        parameters.a1,
        parameters.a2,
    )?;
    let slope = mpim.check_invertible(0.0, 1.0)?;
    let limits = OutputLimits::new(0.0, 1.0)?;
    // The exact and the guarded delayed loops build on every invertible model; the plain
    // delayed ones only when their loop gain is below 1 (reported, not required).
    for mode in [SolveMode::Exact, SolveMode::DelayedGuarded] {
        Ihc::<f64, Vec<f64>>::new(&mpim, limits, mode)?;
        Wihc::<f64, Vec<f64>>::new(&mpim, limits, mode)?;
    }
    // y - o - sum c_i (z_i[y] - o) = h - o with h = offset + s H: see the derivation in the
    // module documentation of hystcomp_io::model_file.
    let offset = (y_ref - origin) * (1.0 - weight_sum) + y_scale * parameters.offset + origin;
    let part = CreepPart {
        origin,
        time_constants_s: creep.time_constants_s.clone(),
        weights,
    };
    let input = base.model.input.clone();
    let output = Scale {
        offset,
        ..base.model.output.clone()
    };
    let file = ModelFile::from_model(Direction::Plant, input, output, [0.0, 1.0], &mpim)?
        .with_links(rate, Some(part.clone()), None)
        .map_err(|e| IdentifyError::InvalidOption {
            option: "creep time constants",
            value: format!("{:?}", creep.time_constants_s),
            reason: format!("the creep fit is unusable ({e}); give fewer or longer time constants"),
        })?;
    let mut hysteresis = report.clone();
    hysteresis.detail = format!(
        "joint fit with {} creep elements: {}",
        part.weights.len(),
        solution.detail
    );
    hysteresis.output_offset = offset;
    hysteresis.condition_number = condition;
    hysteresis.constraints = problem.constraints().len();
    hysteresis.active_constraints = problem.active_count(&solution.theta);
    hysteresis.violated_constraints = problem.violated_count(&solution.theta);
    hysteresis.min_branch_slope = slope.slope;
    Ok((
        file,
        CreepFit {
            part,
            static_gain: 1.0 / (1.0 - weight_sum),
            condition_number: condition,
            smoothness: creep.smoothness,
            smoothness_candidates: Vec::new(),
        },
        hysteresis,
    ))
}

fn inverse_chain(
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    chain: &ChainOptions,
    plant: &Plant,
) -> Result<(ModelFile, ChainReport), IdentifyError> {
    let k = chain.decimation;
    let rate = chain.sample_rate_hz;
    // The displacement advanced by the vibration link's pure delay (its fast dynamics are left
    // alone: inverting them would amplify the sensor noise the inverse model reads), then
    // creep-free, C^-1[y], creep relaxed at the record's start.
    let delay = plant
        .model
        .vibration
        .as_ref()
        .map_or(0, |v| v.delay_samples);
    let n = displacement.len();
    let advanced: Vec<f64> = (0..n)
        .map(|i| displacement[(i + delay).min(n - 1)])
        .collect();
    let without_creep = |y: &[f64]| -> Result<Vec<f64>, IdentifyError> {
        Ok(match &plant.model.creep {
            Some(c) => {
                let mut inverse = c.link(rate)?.inverse();
                y.iter().map(|y| inverse.step(*y)).collect()
            }
            None => y.to_vec(),
        })
    };
    let creep_free = without_creep(&advanced)?;
    let v = decimate(voltage, k);
    let h = decimate(&creep_free, k);
    let end = fitted_end(chain, voltage.len()) / k;
    let inverse = identify(&v[..end], &h[..end], options)?;
    let base = identify(&v[..end], &decimate(displacement, k)[..end], options)?;
    let model = inverse.model.clone().with_links(
        rate,
        plant.model.creep.clone(),
        plant.model.vibration.clone(),
    )?;
    let span = full_rate_span(&inverse.report, k, voltage.len());
    let v_scale = inverse.report.output.max - inverse.report.output.min;
    let segment = chain
        .dynamics
        .as_ref()
        .map(|d| d.segment.clone().unwrap_or(0..voltage.len()));
    let mut contributions = Vec::new();
    let mut add = |name: &str, file: &ModelFile| -> Result<(), IdentifyError> {
        let predicted = file.predict(displacement)?;
        contributions.push(Contribution::measured(
            name,
            &predicted,
            voltage,
            v_scale,
            &span,
            segment.as_ref(),
        ));
        Ok(())
    };
    add("hysteresis", &base.model)?;
    if model.creep.is_some() {
        // Creep without the delay taken back: an MPIM fitted to the creep-free displacement as
        // measured (the chain's own MPIM reads it advanced by the delay, and would be judged
        // against a misaligned record here).
        let creep_only = if delay == 0 {
            model.clone().with_links(rate, model.creep.clone(), None)?
        } else {
            let h = decimate(&without_creep(displacement)?, k);
            identify(&v[..end], &h[..end], options)?.model.with_links(
                rate,
                model.creep.clone(),
                None,
            )?
        };
        add("+ creep", &creep_only)?;
    }
    if model.vibration.is_some() {
        add("+ vibration", &model)?;
    }
    let predicted = model.predict(displacement)?;
    let fit =
        ErrorStats::new(&predicted[span.clone()], &voltage[span], v_scale).ok_or_else(|| {
            IdentifyError::InvalidOption {
                option: "fitting span",
                value: "empty".to_owned(),
                reason: "no fitted samples".to_owned(),
            }
        })?;
    Ok((
        model,
        ChainReport {
            hysteresis: inverse.report,
            creep: plant.report.creep.clone(),
            dynamics: plant.report.dynamics.clone(),
            contributions,
            fit,
            elapsed_s: 0.0,
            span: FittedSpan::default(),
        },
    ))
}
