//! From (voltage, displacement) samples to a model file and a fit report.

use std::time::Instant;

use hystcomp_core::{Compensator, Ihc, OutputLimits, SolveMode, Wihc};
use hystcomp_io::data::{check_finite, check_min_samples, check_not_constant, check_same_length};
use hystcomp_io::model_file::{Direction, ModelFile, OutputMapPart, Scale};
use serde::{Deserialize, Serialize};

use crate::options::{
    AUTO_WARMUP_LEVEL, MAX_REGRESSOR_VALUES, MIN_CORRELATION, SAMPLES_PER_PARAMETER,
};
use crate::report::{
    DelayedConstraint, DelayedGains, ErrorStats, FitReport, SampleCounts, SignalRange, WarmupReport,
};
use crate::warmup::{MEMORY_TOLERANCE, estimate_history, memory_known_from};
use crate::{
    FitProblem, IdentifyError, IdentifyOptions, LeastSquares, Method, NoObserver, Observer,
    OutputOffset, Parameters, ParticleSwarm, ProblemData, Solver, Warmup,
};

/// An identified model: the model file (physical scales and normalised parameters) and how
/// well it fits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Identification {
    /// The model file, with the report in its `identification` field.
    pub model: ModelFile,
    /// The fit report.
    pub report: FitReport,
    /// The normalised parameters (with the fitted constant `c`, already moved into the model
    /// file's `output.offset`).
    pub parameters: Parameters,
}

/// Identifies an MPIM (eq. (4)) from a record of drive voltages and measured displacements
/// (same length, one pair per sample). See [`identify_observed`].
pub fn identify(
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
) -> Result<Identification, IdentifyError> {
    identify_observed(voltage, displacement, options, &mut NoObserver)
}

/// Identifies an MPIM (eq. (4)) from a record, telling `observer` about the solver's progress.
///
/// 1. The model input and output are chosen by [`IdentifyOptions::direction`]: voltage to
///    displacement for a plant model, displacement to voltage for an inverse (DIHC) model.
/// 2. The warm-up ([`Warmup`]: by default up to where the operators' memory becomes known, or
///    none with the initial memory estimated) and the hold-out are excluded from the fit; the
///    fitted samples
///    must have a displacement that rises with the voltage (Pearson correlation at least
///    [`MIN_CORRELATION`](crate::MIN_CORRELATION), and not exactly 1, which only the same
///    column given twice produces).
/// 3. Normalisation: `x = (input - min) / (max - min)` with min and max over the **fitted
///    samples** (neither the warm-up, whose transient the model is not fitted to, nor the
///    hold-out, which must not inform the model), so that the thresholds `(i - 1)/n` are
///    fractions of the fitted input range (eq. (11)) and the fit's "% of the output range"
///    refers to the fitted output range `(output - offset) / (max - min)`, with the offset of
///    [`OutputOffset`] (the held-out error to the held-out span's own range, as `crossval`'s
///    to the test span's). The operators still run over the whole record from zero memory
///    (eq. (1)), warm-up included (with [`Warmup::Estimate`], from the memory of the estimated
///    virtual history); warm-up and hold-out samples may fall outside `[0, 1]`.
/// 4. The chosen solver minimises the RMS error under the invertibility constraints of
///    [`FitProblem`]; the model is then checked by the core (`check_invertible` on `[0, 1]`,
///    and for a plant model the IHC of eq. (7) and the delayed WIHC of eq. (9) are built).
///
/// 5. The fit's RMS error must not exceed
///    [`IdentifyOptions::max_fit_rms_percent`] ([`IdentifyError::PoorFit`]).
///
/// Refuses samples that are NaN or infinite, of different lengths, constant, or too few for
/// the model ([`IdentifyError::Data`], with the number needed), a displacement that does not
/// rise with the voltage ([`IdentifyError::NotRising`], [`IdentifyError::SameSignal`]), and
/// invalid options.
pub fn identify_observed(
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
    observer: &mut dyn Observer,
) -> Result<Identification, IdentifyError> {
    let started = Instant::now();
    options.validate()?;
    check_same_length(&[("voltage", voltage), ("displacement", displacement)])?;
    check_finite("voltage", voltage)?;
    check_finite("displacement", displacement)?;
    check_not_constant("voltage", voltage)?;
    check_not_constant("displacement", displacement)?;

    let (input, output, input_quantity, output_quantity, input_unit, output_unit) =
        match options.direction {
            Direction::Plant => (
                voltage,
                displacement,
                "voltage",
                "displacement",
                &options.voltage_unit,
                &options.displacement_unit,
            ),
            Direction::Inverse => (
                displacement,
                voltage,
                "displacement",
                "voltage",
                &options.displacement_unit,
                &options.voltage_unit,
            ),
        };
    let thresholds = options.thresholds.values()?;
    let fit_offset = options.offset == OutputOffset::Fit;
    let parameters_count = parameter_count(&thresholds, fit_offset)
        + options.input_degree.saturating_sub(3) / 2
        + options.output_map_degree.saturating_sub(1);
    let total = input.len();
    if total.saturating_mul(thresholds.len()) > MAX_REGRESSOR_VALUES {
        return Err(IdentifyError::InvalidOption {
            option: "number of play operators",
            value: thresholds.len().to_string(),
            reason: format!(
                "{} operators on {total} samples take {} values, more than the \
                 {MAX_REGRESSOR_VALUES} identification may hold; use fewer operators or fewer \
                 samples (a row range, or decimate the record)",
                thresholds.len(),
                total.saturating_mul(thresholds.len())
            ),
        });
    }
    let known_from = memory_known_from(voltage);
    let warmup = match options.warmup {
        Warmup::Auto => known_from,
        Warmup::Estimate => 0,
        Warmup::Samples(n) => n.min(total),
    };
    let after_warmup = total - warmup;
    let holdout = (options.holdout * after_warmup as f64).floor() as usize;
    let fit_samples = after_warmup - holdout;
    let needed = minimum_fit_samples(parameters_count);
    check_min_samples(
        needed,
        fit_samples,
        &format!(
            "identification of a model with {} play operator(s) ({parameters_count} parameters, \
             {SAMPLES_PER_PARAMETER} samples each, after a warm-up of {warmup} and a hold-out of \
             {holdout} of the {total} samples)",
            thresholds.len()
        ),
    )?;
    let fit = warmup..warmup + fit_samples;

    // Normalisation over the fitted samples only: the warm-up is a transient the model is not
    // fitted to, and the hold-out must not inform the model (its samples may fall outside
    // [0, 1], where the model extrapolates). A span constant there is refused first: its
    // correlation is undefined, and "does not rise" would send the user to the wrong cause.
    let (x_min, x_max) = min_max(&input[fit.clone()]);
    let (y_min, y_max) = min_max(&output[fit.clone()]);
    let x_scale = x_max - x_min;
    let y_scale = y_max - y_min;
    for (quantity, scale) in [(input_quantity, x_scale), (output_quantity, y_scale)] {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(IdentifyError::InvalidOption {
                option: "fitting span",
                value: format!("samples {}..{} of {total}", fit.start + 1, fit.end),
                reason: format!(
                    "the {quantity} is constant (or overflows) over the fitted samples; \
                     give a shorter warm-up or hold-out, or check the column and its factor"
                ),
            });
        }
    }
    check_rises(
        &voltage[fit.clone()],
        &displacement[fit.clone()],
        options.max_fit_rms_percent.is_some(),
    )?;
    let y_reference = match options.offset {
        OutputOffset::Fit | OutputOffset::None => y_min,
        OutputOffset::Value(v) => v,
    };
    let x: Vec<f64> = input.iter().map(|v| (v - x_min) / x_scale).collect();
    let y: Vec<f64> = output.iter().map(|v| (v - y_reference) / y_scale).collect();

    let build = |data: ProblemData<'_>| {
        FitProblem::with_output_map(
            data,
            &thresholds,
            options.direction,
            fit_offset,
            options.margin,
            options.input_degree,
            options.output_map_degree,
            &[],
        )
    };
    // The virtual history run before the first sample: estimated with the parameters, or none
    // (zero memory, eq. (1)). Once the memory is known from the first sample, every history
    // gives the same memory: nothing to estimate.
    let history: Vec<f64> = match options.warmup {
        Warmup::Estimate if known_from > 0 => estimate_history(&x, &y, fit.clone(), &build)?.0,
        _ => Vec::new(),
    };
    let shift = history.len();
    let (x_run, y_run) = if shift == 0 {
        (x.clone(), y.clone())
    } else {
        (
            history.iter().chain(&x).copied().collect::<Vec<f64>>(),
            std::iter::repeat_n(0.0, shift)
                .chain(y.iter().copied())
                .collect::<Vec<f64>>(),
        )
    };
    let problem = build(ProblemData {
        input: &x_run,
        output: &y_run,
        fit: fit.start + shift..fit.end + shift,
    })?;
    // For delayed compensation: the same problem with both delayed loops' gains bounded, and
    // what the bound costs (the least-squares optimum without those rows, and its gains).
    let (problem, delayed_constraint) = match options.delayed_loop_bound {
        Some(bound) if options.direction == Direction::Plant => {
            let free = LeastSquares.solve(&problem, &mut NoObserver)?;
            let free_parameters = problem.parameters(&free.theta);
            let unconstrained_gains = free_parameters.model(&thresholds).map_or(
                DelayedGains {
                    ihc: f64::NAN,
                    wihc: f64::NAN,
                },
                |m| DelayedGains::of(&m, 0.0, 1.0),
            );
            let constrained = problem.with_delayed_loop_bound(bound)?;
            (
                constrained,
                Some(DelayedConstraint {
                    bound,
                    unconstrained_fit_rms_percent: 100.0 * free.cost,
                    unconstrained_gains,
                }),
            )
        }
        _ => (problem, None),
    };
    // NaN counts as ill-conditioned too.
    let condition = problem.condition_number();
    if condition.is_nan() || condition > options.max_condition {
        return Err(IdentifyError::IllConditioned {
            condition: problem.condition_number(),
            limit: options.max_condition,
        });
    }
    let (solver_name, solution) = match &options.method {
        Method::LeastSquares => {
            let solver = LeastSquares;
            (solver.name(), solver.solve(&problem, observer)?)
        }
        Method::ParticleSwarm(pso) => {
            let solver = ParticleSwarm::new(pso.clone())?;
            (solver.name(), solver.solve(&problem, observer)?)
        }
    };
    let parameters = problem.parameters(&solution.theta);

    // The core's checks: the model must be invertible on its input range, and a plant model
    // must give every compensator of the paper.
    let model = parameters.model(&thresholds)?;
    let slope = model.check_invertible(0.0, 1.0)?;
    if options.direction == Direction::Plant {
        let limits = OutputLimits::new(0.0, 1.0)?;
        // The exact and the guarded delayed loops build on every invertible model; the plain
        // delayed ones only when their loop gain is below 1 (reported, not required).
        for mode in [SolveMode::Exact, SolveMode::DelayedGuarded] {
            Ihc::<f64, Vec<f64>>::new(&model, limits, mode)?.reset();
            Wihc::<f64, Vec<f64>>::new(&model, limits, mode)?.reset();
        }
    }

    // Errors of the model itself (the core's MPIM over the whole record), physical units.
    let output_offset = y_reference + parameters.offset * y_scale;
    let output_map = (options.output_map_degree > 1)
        .then(|| {
            output_map_part(
                problem.output_map_parameters(&solution.theta),
                parameters.offset,
            )
        })
        .transpose()?;
    let map = match &output_map {
        Some(m) => m.map()?,
        None => hystcomp_core::OutputMap::identity(),
    };
    let mut run = model.clone();
    for &v in &history {
        run.step(v);
    }
    let initial_memory = run.memory().to_vec();
    let predicted: Vec<f64> = x
        .iter()
        .map(|&v| {
            let h = run.step(v);
            output_offset
                + y_scale
                    * if output_map.is_some() {
                        map.invert(h)
                    } else {
                        h
                    }
        })
        .collect();
    let fit_stats = ErrorStats::new(&predicted[fit.clone()], &output[fit.clone()], y_scale)
        .expect("the fitting span is not empty");
    // The held-out error in % of the held-out span's own output range: the test span's range,
    // as `crossval` normalises (a split of one record gives the same figure both ways).
    let holdout_stats = (fit.end < total).then(|| {
        ErrorStats::new(
            &predicted[fit.end..],
            &output[fit.end..],
            crate::crossval::range_of(&output[fit.end..]),
        )
        .expect("the held-out span is not empty")
    });
    if let Some(limit) = options.max_fit_rms_percent
        && (fit_stats.rms_percent.is_nan() || fit_stats.rms_percent > limit)
    {
        // A swarm far from the optimum is not bad data: say so, with the optimum beside it.
        if let Method::ParticleSwarm(_) = options.method
            && let Ok(ls) = LeastSquares.solve(&problem, &mut NoObserver)
            && 100.0 * ls.cost <= limit
        {
            return Err(IdentifyError::SwarmNotConverged {
                rms_percent: fit_stats.rms_percent,
                least_squares_rms_percent: 100.0 * ls.cost,
                limit,
            });
        }
        return Err(IdentifyError::PoorFit {
            rms_percent: fit_stats.rms_percent,
            limit,
        });
    }

    let input_scale = Scale {
        quantity: input_quantity.to_owned(),
        unit: input_unit.clone(),
        offset: x_min,
        scale: x_scale,
    };
    let output_scale = Scale {
        quantity: output_quantity.to_owned(),
        unit: output_unit.clone(),
        offset: output_offset,
        scale: y_scale,
    };
    let report = FitReport {
        direction: options.direction,
        solver: solver_name.to_owned(),
        detail: solution.detail.clone(),
        thresholds: thresholds.clone(),
        samples: SampleCounts {
            total,
            warmup,
            fit: fit_samples,
            holdout,
        },
        warmup: Some(warmup_report(
            options.warmup,
            warmup,
            known_from,
            voltage,
            (input_quantity, input_unit.as_str(), input[0]),
            (!history.is_empty()).then(|| {
                (
                    history.iter().map(|v| x_min + x_scale * v).collect(),
                    initial_memory,
                )
            }),
        )),
        input: SignalRange {
            quantity: input_quantity.to_owned(),
            unit: input_unit.clone(),
            min: x_min,
            max: x_max,
        },
        output: SignalRange {
            quantity: output_quantity.to_owned(),
            unit: output_unit.clone(),
            min: y_min,
            max: y_max,
        },
        offset_mode: options.offset,
        output_offset,
        fit: fit_stats,
        holdout: holdout_stats,
        condition_number: problem.condition_number(),
        constraints: problem.constraints().len(),
        active_constraints: problem.active_count(&solution.theta),
        violated_constraints: problem.violated_count(&solution.theta),
        margin: options.margin,
        min_branch_slope: slope.slope,
        delayed_loop_gains: (options.direction == Direction::Plant)
            .then(|| DelayedGains::of(&model, 0.0, 1.0)),
        delayed_constraint,
        pso: match &options.method {
            Method::ParticleSwarm(pso) => Some(pso.clone()),
            Method::LeastSquares => None,
        },
        elapsed_s: started.elapsed().as_secs_f64(),
    };
    let mut file = ModelFile::from_model(
        options.direction,
        input_scale,
        output_scale,
        [0.0, 1.0],
        &model,
    )?;
    if output_map.is_some() {
        file.output_map = output_map;
        file.validate()?;
    }
    file.description = Some(format!(
        "MPIM ({}) identified by hystcomp ({}) from {} samples: {} {} -> {} {}",
        options.direction,
        solver_name,
        total,
        input_quantity,
        input_unit,
        output_quantity,
        output_unit
    ));
    file.identification = serde_json::to_value(&report).ok();
    Ok(Identification {
        model: file,
        report,
        parameters,
    })
}

/// The model file's output map for the fitted `psi(y) = y - sum_j e_j y^j` (`e = [e_2, ...]`)
/// of the output normalised from the record's reference, `psi(y) = H + c`: in the file's
/// normalised output `w = y - c` (its offset holds `c`), `psi_w(w) = psi(w + c) - c`, expanded
/// by the binomial theorem; its range the constrained one, [`crate::problem::OUTPUT_MAP_RANGE`],
/// shifted by `-c`.
fn output_map_part(e: &[f64], c: f64) -> Result<OutputMapPart, IdentifyError> {
    let degree = e.len() + 1;
    let mut m = vec![0.0; degree + 1];
    m[1] = 1.0;
    for (q, &e_j) in e.iter().enumerate() {
        let j = q + 2;
        let mut binomial = 1.0;
        for (i, m_i) in m.iter_mut().enumerate().take(j + 1) {
            // C(j, i) c^(j - i)
            *m_i -= e_j * binomial * c.powi((j - i) as i32);
            binomial = binomial * (j - i) as f64 / (i + 1) as f64;
        }
    }
    let (lo, hi) = crate::problem::OUTPUT_MAP_RANGE;
    let part = OutputMapPart {
        coefficients: m,
        range: [lo - c, hi - c],
    };
    part.map()?;
    Ok(part)
}

/// The number of parameters the fit of a model with these `thresholds` estimates: `a1`, `a2`
/// and one weight per threshold, less one when `r_1 = 0` (then only `a2 + b_1` is determined,
/// see [`FitProblem`]), plus the output offset `c` when it is fitted.
pub(crate) fn parameter_count(thresholds: &[f64], fit_offset: bool) -> usize {
    thresholds.len() + 2 - usize::from(thresholds.first() == Some(&0.0)) + usize::from(fit_offset)
}

/// The fewest fitting samples a model with `parameters` parameters needs:
/// [`SAMPLES_PER_PARAMETER`] per parameter (and at least one more than the parameters).
pub(crate) fn minimum_fit_samples(parameters: usize) -> usize {
    (SAMPLES_PER_PARAMETER * parameters).max(parameters + 1)
}

/// Pearson's correlation coefficient of two equally long, non-empty series (NaN when one is
/// constant).
pub(crate) fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()) as f64;
    let mean_a = a.iter().sum::<f64>() / n;
    let mean_b = b.iter().sum::<f64>() / n;
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (dx, dy) = (x - mean_a, y - mean_b);
        ab += dx * dy;
        aa += dx * dx;
        bb += dy * dy;
    }
    ab / (aa.sqrt() * bb.sqrt())
}

/// Refuses fitted samples whose displacement does not rise with the voltage (Pearson
/// correlation below [`MIN_CORRELATION`]: wrong column, wrong sign, a column of noise) or is
/// an exact linear function of it (the same column given twice: a trivial fit).
/// `refuse_poor` false (`--accept-poor-fit`) lets a low correlation through; the same column
/// twice is always refused.
pub(crate) fn check_rises(
    voltage: &[f64],
    displacement: &[f64],
    refuse_poor: bool,
) -> Result<(), IdentifyError> {
    if voltage == displacement {
        return Err(IdentifyError::SameSignal);
    }
    let r = correlation(voltage, displacement);
    if refuse_poor && (r.is_nan() || r < MIN_CORRELATION) {
        return Err(IdentifyError::NotRising {
            correlation: r,
            minimum: MIN_CORRELATION,
        });
    }
    if r > 1.0 - 1e-12 {
        return Err(IdentifyError::SameSignal);
    }
    Ok(())
}

/// `crossval`'s automatic test warm-up: the first sample whose value is within
/// [`AUTO_WARMUP_LEVEL`] of the range from the minimum.
pub(crate) fn auto_warmup(voltage: &[f64]) -> usize {
    let (lo, hi) = min_max(voltage);
    voltage
        .iter()
        .position(|&v| v - lo <= AUTO_WARMUP_LEVEL * (hi - lo))
        .unwrap_or(0)
}

/// Which samples were fitted and why, for the report (`input`: the model input's quantity,
/// unit and first value; `estimated`: the virtual history in physical input units and the
/// memory it leaves, with [`Warmup::Estimate`]).
fn warmup_report(
    mode: Warmup,
    first_fitted: usize,
    known_from: usize,
    voltage: &[f64],
    input: (&str, &str, f64),
    estimated: Option<(Vec<f64>, Vec<f64>)>,
) -> WarmupReport {
    let (quantity, unit, first) = input;
    let (lo, hi) = min_max(voltage);
    let extreme = |v: f64| {
        if v - lo <= hi - v {
            "minimum"
        } else {
            "maximum"
        }
    };
    let known = if known_from == 0 {
        format!(
            "the record starts at its voltage {} (within {} % of the range), so the operators' \
             memory is known from the first sample",
            extreme(voltage[0]),
            100.0 * MEMORY_TOLERANCE
        )
    } else {
        format!(
            "the operators' memory is unknown until sample {} (voltage {}, within {} % of the \
             range from the record's {}), where it is fixed whatever came before (wiping-out)",
            known_from + 1,
            number(voltage[known_from]),
            100.0 * MEMORY_TOLERANCE,
            extreme(voltage[known_from])
        )
    };
    let (history, initial_memory) = match estimated {
        Some((h, m)) => (Some(h), Some(m)),
        None => (None, None),
    };
    let reason = match (mode, &history) {
        (Warmup::Auto, _) if known_from == 0 => format!("fitted from the first sample: {known}"),
        (Warmup::Auto, _) => format!("samples 1..{known_from} left out as warm-up: {known}"),
        (Warmup::Estimate, Some(h)) => format!(
            "fitted from the first sample: {known}; the memory at the first sample was \
             estimated with the parameters, as left by the {quantity} moving from {} to {} \
             {unit} and then to its first value, {} {unit}",
            number(h[1]),
            number(h[2]),
            number(first)
        ),
        (Warmup::Estimate, None) => {
            format!("fitted from the first sample: {known}; nothing to estimate")
        }
        (Warmup::Samples(n), _) => format!(
            "samples 1..{first_fitted} left out as asked (warm-up {n}), the operators running \
             from zero memory at the first sample; {known}"
        ),
    };
    WarmupReport {
        mode,
        first_fitted,
        memory_known_from: known_from,
        history,
        initial_memory,
        reason,
    }
}

/// A number for people, 4 significant digits or so.
fn number(v: f64) -> String {
    let text = format!("{v:.4}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_owned()
    } else {
        text.to_owned()
    }
}

/// Smallest and largest value (the samples are finite and not empty).
pub(crate) fn min_max(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}
