//! Identification from arrays: (voltage, displacement) samples in, a model and its fit report
//! out, by `hystcomp_identify::identify` (constrained least squares or the paper's particle
//! swarm, section 4.2), with the options of `hystcomp identify`.

use std::ffi::{c_char, c_int};

use hystcomp_identify::{
    ErrorStats, FitReport, IdentifyOptions, Method, OutputOffset, PsoOptions, Thresholds, Warmup,
};

use crate::args::{clear_out, doubles, put_handle, signal, str_arg};
use crate::boundary::{Failure, boundary};
use crate::model::{HystcompDirection, HystcompModel, direction_arg};

// The library's bounds (`hystcomp_identify`), checked there before anything is allocated;
// repeated here as literals for the header (cbindgen), and held equal by the assertions.

/// The most play operators `hystcomp_identify` accepts (`operators`, or `threshold_count`).
pub const HYSTCOMP_MAX_OPERATORS: usize = 1000;
const _: () = assert!(HYSTCOMP_MAX_OPERATORS == hystcomp_identify::MAX_OPERATORS);

/// The most particles of the swarm `hystcomp_identify` accepts.
pub const HYSTCOMP_MAX_PARTICLES: usize = 1000;
const _: () = assert!(HYSTCOMP_MAX_PARTICLES == hystcomp_identify::MAX_PARTICLES);

/// The most iterations of the swarm `hystcomp_identify` accepts.
pub const HYSTCOMP_MAX_ITERATIONS: usize = 100000;
const _: () = assert!(HYSTCOMP_MAX_ITERATIONS == hystcomp_identify::MAX_ITERATIONS);

/// The most values the operators' outputs over a record may take in `hystcomp_identify`:
/// samples times operators (5e7, 400 MB of doubles).
pub const HYSTCOMP_MAX_REGRESSOR_VALUES: usize = 50000000;
const _: () = assert!(HYSTCOMP_MAX_REGRESSOR_VALUES == hystcomp_identify::MAX_REGRESSOR_VALUES);

/// The solver of `hystcomp_identify` (passed as an `int`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HystcompSolver {
    /// Constrained linear least squares: the global optimum for the thresholds (the default).
    LeastSquares = 0,
    /// The particle swarm of the paper (its ref. [39]), seeded and reproducible.
    ParticleSwarm = 1,
}

/// How the model output relates to the measured output (passed as an `int`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HystcompOffsetMode {
    /// A fitted constant, for sensors with an arbitrary zero (the default).
    Fit = 0,
    /// None: the output is at its minimum when the input is (the paper's normalisation).
    None = 1,
    /// The physical output offset `offset_value` (e.g. 0 for a calibrated sensor).
    Value = 2,
}

/// The options of `hystcomp_identify`. Start from `hystcomp_identify_options_default` and
/// change what you need; the defaults are those of the library (and of `hystcomp identify`,
/// except `holdout`, which the command line sets to 0.2).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct HystcompIdentifyOptions {
    /// A `HystcompDirection`: plant (voltage to displacement, for IHC and WIHC; the default) or
    /// inverse (displacement to voltage, for DIHC).
    pub direction: c_int,
    /// A `HystcompSolver` (default least squares).
    pub solver: c_int,
    /// Play operators `n` at thresholds `(i - 1)/n` of the input range (eq. (11)); default 10,
    /// at most `HYSTCOMP_MAX_OPERATORS`, and samples times operators at most
    /// `HYSTCOMP_MAX_REGRESSOR_VALUES`. Ignored when `thresholds` is given.
    pub operators: usize,
    /// `threshold_count` thresholds given explicitly (fractions of the input range in
    /// `[0, 1)`, strictly increasing), or NULL for `operators` uniform ones. Read during the
    /// call only.
    pub thresholds: *const f64,
    /// The number of `thresholds` (at most `HYSTCOMP_MAX_OPERATORS`).
    pub threshold_count: usize,
    /// Non-zero (the default): the warm-up ends at the first sample within 5 % of the voltage
    /// range from its minimum. Zero: `warmup_samples` leading samples are excluded from the fit.
    pub warmup_auto: c_int,
    /// Leading samples excluded from the fit when `warmup_auto` is 0.
    pub warmup_samples: usize,
    /// The fraction of the samples after the warm-up, at the end, held out of the fit and
    /// reported separately, in `[0, 1)` (default 0).
    pub holdout: f64,
    /// A `HystcompOffsetMode` (default fit).
    pub offset_mode: c_int,
    /// The physical output offset for `HYSTCOMP_OFFSET_MODE_VALUE`.
    pub offset_value: f64,
    /// The smallest branch slope the model keeps (normalised, in `(0, 1)`; default 0.001).
    pub margin: f64,
    /// The largest condition number of the column-scaled regressors (default 1e10).
    pub max_condition: f64,
    /// Non-zero: return the model even when its RMS fit error exceeds 10 % of the output range
    /// (refused by default with `HYSTCOMP_STATUS_IDENTIFICATION_FAILED`).
    pub accept_poor_fit: c_int,
    /// Swarm: the seed of its random numbers (default 0).
    pub seed: u64,
    /// Swarm: particles, 2 to `HYSTCOMP_MAX_PARTICLES` (default 50).
    pub particles: usize,
    /// Swarm: iterations, 1 to `HYSTCOMP_MAX_ITERATIONS` (default 10000).
    pub iterations: usize,
    /// Swarm: non-zero to polish the best particle by least squares.
    pub polish: c_int,
    /// Unit of the voltage samples, written to the model (NULL: `"V"`).
    pub voltage_unit: *const c_char,
    /// Unit of the displacement samples, written to the model (NULL: `"um"`).
    pub displacement_unit: *const c_char,
    /// Non-zero: fit a plant model meant for the one-sample-delayed compensators
    /// (`ihc-delayed`, `wihc-delayed`): both delayed loops' gains, over every number of moving
    /// operators and every drive in the fitted range, held to at most `delayed_loop_bound`, so
    /// that neither loop can oscillate (`hystcomp identify --for-delayed`); the report's
    /// `unconstrained_fit_rms_percent` says what it cost. Inverse models ignore it. Default 0.
    pub for_delayed: c_int,
    /// The bound on both delayed loops' gains with `for_delayed`, in `(0, 1)` (default 0.9).
    pub delayed_loop_bound: f64,
    /// Non-zero: choose the number of play operators among 5, 10, 15, 20, 30, 40 and 50 by the
    /// held-out RMS error, as `hystcomp identify -n auto` (each fitted on the record less its
    /// last `holdout`, or 25 % when `holdout` is 0; the smallest within 1 % of the best);
    /// `operators` is then ignored and the report's `operators` holds the choice. Ignored when
    /// `thresholds` is given. Default 0.
    pub operators_auto: c_int,
}

/// Errors of a model's prediction over a span of samples (`predicted - measured`), in the
/// output's unit and in % of `range`: the fitted output range for the fit, the held-out span's
/// own output range for the hold-out (as `hystcomp crossval` normalises a test span), the
/// measured output's range for `hystcomp_predict`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HystcompErrorStats {
    /// Samples in the span (0 when there is none, and every other field NaN).
    pub samples: usize,
    /// Root mean square error.
    pub rms: f64,
    /// Largest absolute error.
    pub max: f64,
    /// Mean error (a bias or offset drift).
    pub mean: f64,
    /// The range the percentages refer to.
    pub range: f64,
    /// `rms` in % of `range`.
    pub rms_percent: f64,
    /// `max` in % of `range`.
    pub max_percent: f64,
    /// The RMS of the error minus its mean, in % of `range`.
    pub std_percent: f64,
}

/// What `hystcomp_identify` did and how well the model fits (the numbers of the fit report the
/// model also holds, as JSON, in its `identification_json`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HystcompFitReport {
    /// Samples in the record (the operators run over all of them).
    pub samples_total: usize,
    /// Samples at the start excluded as warm-up.
    pub samples_warmup: usize,
    /// Samples the error was minimised over.
    pub samples_fit: usize,
    /// Samples at the end held out of the fit.
    pub samples_holdout: usize,
    /// The model input's smallest fitted value (physical; normalised to 0).
    pub input_min: f64,
    /// The model input's largest fitted value (physical; normalised to 1).
    pub input_max: f64,
    /// The model output's smallest fitted value (physical).
    pub output_min: f64,
    /// The model output's largest fitted value (physical).
    pub output_max: f64,
    /// The model's output offset: the physical output at normalised output 0.
    pub output_offset: f64,
    /// Errors over the fitted samples.
    pub fit: HystcompErrorStats,
    /// Errors over the held-out samples (`samples` 0 without a hold-out).
    pub holdout: HystcompErrorStats,
    /// The condition number of the column-scaled regressor matrix.
    pub condition_number: f64,
    /// The number of linear constraints of the fit.
    pub constraints: usize,
    /// The constraints holding with equality at the answer.
    pub active_constraints: usize,
    /// The constraints the answer violates (0 for least squares).
    pub violated_constraints: usize,
    /// The smallest branch slope of the model over its input range (normalised).
    pub min_branch_slope: f64,
    /// Wall-clock time of the identification, s.
    pub elapsed_s: f64,
    /// The number of play operators of the model (the choice with `operators_auto`).
    pub operators: usize,
    /// With `for_delayed` (plant models): the bound both delayed loops' gains were held to;
    /// NaN otherwise.
    pub delayed_loop_bound: f64,
    /// With `for_delayed` (plant models): the fit's RMS error without the bound, in % of the
    /// fitted output range (the bound's cost is `fit.rms_percent` minus this); NaN otherwise.
    pub unconstrained_fit_rms_percent: f64,
}

impl From<&ErrorStats> for HystcompErrorStats {
    fn from(e: &ErrorStats) -> Self {
        HystcompErrorStats {
            samples: e.samples,
            rms: e.rms,
            max: e.max,
            mean: e.mean,
            range: e.range,
            rms_percent: e.rms_percent,
            max_percent: e.max_percent,
            std_percent: e.std_percent,
        }
    }
}

impl HystcompErrorStats {
    const NONE: HystcompErrorStats = HystcompErrorStats {
        samples: 0,
        rms: f64::NAN,
        max: f64::NAN,
        mean: f64::NAN,
        range: f64::NAN,
        rms_percent: f64::NAN,
        max_percent: f64::NAN,
        std_percent: f64::NAN,
    };
}

impl From<&FitReport> for HystcompFitReport {
    fn from(r: &FitReport) -> Self {
        HystcompFitReport {
            samples_total: r.samples.total,
            samples_warmup: r.samples.warmup,
            samples_fit: r.samples.fit,
            samples_holdout: r.samples.holdout,
            input_min: r.input.min,
            input_max: r.input.max,
            output_min: r.output.min,
            output_max: r.output.max,
            output_offset: r.output_offset,
            fit: (&r.fit).into(),
            holdout: r
                .holdout
                .as_ref()
                .map_or(HystcompErrorStats::NONE, Into::into),
            condition_number: r.condition_number,
            constraints: r.constraints,
            active_constraints: r.active_constraints,
            violated_constraints: r.violated_constraints,
            min_branch_slope: r.min_branch_slope,
            elapsed_s: r.elapsed_s,
            operators: r.thresholds.len(),
            delayed_loop_bound: r.delayed_constraint.map_or(f64::NAN, |c| c.bound),
            unconstrained_fit_rms_percent: r
                .delayed_constraint
                .map_or(f64::NAN, |c| c.unconstrained_fit_rms_percent),
        }
    }
}

fn default_options() -> HystcompIdentifyOptions {
    let library = IdentifyOptions::default();
    let pso = PsoOptions::default();
    HystcompIdentifyOptions {
        direction: HystcompDirection::Plant as c_int,
        solver: HystcompSolver::LeastSquares as c_int,
        operators: match library.thresholds {
            Thresholds::Uniform(n) => n,
            Thresholds::Given(ref t) => t.len(),
        },
        thresholds: std::ptr::null(),
        threshold_count: 0,
        warmup_auto: c_int::from(library.warmup == Warmup::Auto),
        warmup_samples: 0,
        holdout: library.holdout,
        offset_mode: HystcompOffsetMode::Fit as c_int,
        offset_value: 0.0,
        margin: library.margin,
        max_condition: library.max_condition,
        accept_poor_fit: c_int::from(library.max_fit_rms_percent.is_none()),
        seed: pso.seed,
        particles: pso.particles,
        iterations: pso.iterations,
        polish: c_int::from(pso.polish),
        voltage_unit: std::ptr::null(),
        displacement_unit: std::ptr::null(),
        for_delayed: 0,
        delayed_loop_bound: hystcomp_identify::DEFAULT_DELAYED_LOOP_BOUND,
        operators_auto: 0,
    }
}

/// Fills `*options` with the defaults: a plant model, least squares, 10 operators, automatic
/// warm-up, no hold-out, a fitted output offset, margin 0.001, poor fits refused, the swarm's
/// 50 particles on a ring x 10000 iterations from seed 0, units V and um, no delayed-loop
/// bound (`for_delayed` 0, bound 0.9), `operators` as given (`operators_auto` 0).
///
/// Fails with `NULL_POINTER`.
///
/// # Safety
/// `options` must be valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_identify_options_default(
    options: *mut HystcompIdentifyOptions,
) -> c_int {
    boundary(|| {
        if options.is_null() {
            return Err(Failure::null("options"));
        }
        // SAFETY: non-NULL, valid for a write (the caller's contract).
        unsafe { options.write(default_options()) };
        Ok(())
    })
}

/// The library's options for `o` (the library bounds every size before allocating; the given
/// thresholds are counted here before they are copied).
///
/// # Safety
/// The pointers of `o` must be valid as documented on `HystcompIdentifyOptions`.
unsafe fn library_options(o: &HystcompIdentifyOptions) -> Result<IdentifyOptions, Failure> {
    let thresholds = if o.thresholds.is_null() {
        if o.threshold_count != 0 {
            return Err(Failure::null("thresholds (threshold_count is not 0)"));
        }
        Thresholds::Uniform(o.operators)
    } else {
        if o.threshold_count > HYSTCOMP_MAX_OPERATORS {
            return Err(Failure::invalid(format!(
                "threshold_count {} is more than the {HYSTCOMP_MAX_OPERATORS} play operators \
                 identification fits",
                o.threshold_count
            )));
        }
        // SAFETY: `threshold_count` doubles (the caller's contract).
        let given = unsafe { doubles(o.thresholds, o.threshold_count, "thresholds") }?;
        Thresholds::Given(given.to_vec())
    };
    let method = match o.solver {
        0 => Method::LeastSquares,
        1 => Method::ParticleSwarm(
            PsoOptions::default()
                .with_particles(o.particles)?
                .with_iterations(o.iterations)?
                .with_seed(o.seed)
                .with_polish(o.polish != 0),
        ),
        other => {
            return Err(Failure::invalid(format!(
                "solver {other} is not a HystcompSolver (0 = least squares, 1 = particle swarm)"
            )));
        }
    };
    let offset = match o.offset_mode {
        0 => OutputOffset::Fit,
        1 => OutputOffset::None,
        2 => OutputOffset::Value(o.offset_value),
        other => {
            return Err(Failure::invalid(format!(
                "offset_mode {other} is not a HystcompOffsetMode (0 = fit, 1 = none, 2 = value)"
            )));
        }
    };
    let unit = |ptr: *const c_char, what: &'static str, default: &str| -> Result<String, Failure> {
        if ptr.is_null() {
            Ok(default.to_owned())
        } else {
            // SAFETY: NUL-terminated (the caller's contract).
            Ok(unsafe { str_arg(ptr, what) }?.to_owned())
        }
    };
    let library = IdentifyOptions::default();
    // `..library`: options the library gains later keep their defaults here.
    #[allow(clippy::needless_update)]
    let options = IdentifyOptions {
        direction: direction_arg(o.direction)?,
        method,
        thresholds,
        warmup: if o.warmup_auto != 0 {
            Warmup::Auto
        } else {
            Warmup::Samples(o.warmup_samples)
        },
        holdout: o.holdout,
        offset,
        margin: o.margin,
        max_condition: o.max_condition,
        max_fit_rms_percent: if o.accept_poor_fit != 0 {
            None
        } else {
            library.max_fit_rms_percent
        },
        delayed_loop_bound: (o.for_delayed != 0).then_some(o.delayed_loop_bound),
        voltage_unit: unit(o.voltage_unit, "voltage_unit", "V")?,
        displacement_unit: unit(o.displacement_unit, "displacement_unit", "um")?,
        ..library
    };
    options.validate()?;
    Ok(options)
}

/// Identifies a modified Prandtl-Ishlinskii model (eq. (4)) from a record of drive voltages and
/// measured displacements, as `hystcomp identify` does (`crates/identify`): the thresholds of
/// eq. (11) on the fitted input range, the RMS error minimised under the constraints that keep
/// the model invertible, the fit checked.
///
/// - `voltage`, `voltage_len`, `displacement`, `displacement_len`: the record, one pair per
///   sample: equal lengths, not empty, finite, not constant. The model's input is the voltage
///   for a plant model and the displacement for an inverse one.
/// - `options`: NULL for the defaults (`hystcomp_identify_options_default`); with
///   `for_delayed` both delayed loops' gains are bounded, with `operators_auto` the number of
///   play operators is chosen by held-out error.
/// - `out`: receives the model (NULL on failure); its `identification_json` holds the whole fit
///   report. Free it with `hystcomp_model_free`.
/// - `report`: receives the fit report's numbers, or NULL when not wanted.
///
/// Fails with `NULL_POINTER`, `INVALID_ARGUMENT` (lengths differ, empty, NaN, constant, too few
/// samples for the model, an option out of range; the message names it) or
/// `IDENTIFICATION_FAILED` (no model fits; the message says what to change).
///
/// # Safety
/// `voltage` and `displacement` must point to `voltage_len` and `displacement_len` readable
/// doubles (or be NULL); `options` to a `HystcompIdentifyOptions` (or be NULL); `out` and
/// `report` be valid for one write (or NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_identify(
    voltage: *const f64,
    voltage_len: usize,
    displacement: *const f64,
    displacement_len: usize,
    options: *const HystcompIdentifyOptions,
    out: *mut *mut HystcompModel,
    report: *mut HystcompFitReport,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: `voltage_len` doubles or NULL (the caller's contract).
        let voltage = unsafe { signal(voltage, voltage_len, "voltage") }?;
        // SAFETY: `displacement_len` doubles or NULL (the caller's contract).
        let displacement = unsafe { signal(displacement, displacement_len, "displacement") }?;
        if voltage.len() != displacement.len() {
            return Err(Failure::invalid(format!(
                "voltage has {} samples but displacement has {}; give one displacement per \
                 voltage sample",
                voltage.len(),
                displacement.len()
            )));
        }
        // SAFETY: a valid options struct or NULL (the caller's contract).
        let given = unsafe { options.as_ref() }
            .copied()
            .unwrap_or_else(default_options);
        // SAFETY: the struct's pointers are valid as documented (the caller's contract).
        let mut options = unsafe { library_options(&given) }?;
        if given.operators_auto != 0 && given.thresholds.is_null() {
            let selection = hystcomp_identify::select_operators(
                voltage,
                displacement,
                &options,
                &hystcomp_identify::AUTO_OPERATOR_CANDIDATES,
            )?;
            options.thresholds = Thresholds::Uniform(selection.operators);
        }
        let identification = hystcomp_identify::identify(voltage, displacement, &options)?;
        if !report.is_null() {
            // SAFETY: non-NULL, valid for a write (the caller's contract).
            unsafe { report.write((&identification.report).into()) };
        }
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, HystcompModel::new(identification.model)) };
        Ok(())
    })
}

/// What `hystcomp_predict` found besides the per-sample values.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HystcompPrediction {
    /// The errors over every sample (`predicted - measured`), in the model's output unit and in
    /// % of the measured output's range over the record.
    pub error: HystcompErrorStats,
    /// Samples whose input lies outside the range the model was identified on (it
    /// extrapolates there).
    pub outside_input_range: usize,
}

/// A model's prediction of a record, as `hystcomp predict` does: the model runs from its reset
/// state (zero operator memory, eq. (1); with `settled` non-zero a creep link taken as having
/// rested long at the first sample) over its input, a plant model over `voltage`, an inverse
/// model over `displacement`, and is compared with the other signal.
///
/// - `voltage`, `displacement`: the record, `len` samples each, finite;
/// - `predicted`, `error`: receive the predicted output and `predicted - measured`, `len`
///   doubles each (either may be NULL when not wanted);
/// - `summary`: receives the errors' statistics and the count of inputs outside the model's
///   range (or NULL).
///
/// Fails with `NULL_POINTER` or `INVALID_ARGUMENT` (`len` 0, a NaN or infinite sample, a
/// prediction that is not finite: the message names the sample); nothing is written then.
///
/// # Safety
/// `model` must be a live model handle or NULL; `voltage` and `displacement` must point to
/// `len` readable doubles (or be NULL); `predicted` and `error` to `len` writable doubles (or
/// be NULL); `summary` be valid for one write (or NULL).
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn hystcomp_predict(
    model: *const HystcompModel,
    voltage: *const f64,
    displacement: *const f64,
    len: usize,
    settled: c_int,
    predicted: *mut f64,
    error: *mut f64,
    summary: *mut HystcompPrediction,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let model = unsafe { crate::model::model_arg(model) }?;
        // SAFETY: `len` doubles or NULL (the caller's contract).
        let voltage = unsafe { signal(voltage, len, "voltage") }?;
        // SAFETY: `len` doubles or NULL (the caller's contract).
        let displacement = unsafe { signal(displacement, len, "displacement") }?;
        for (ptr, what) in [(predicted, "predicted"), (error, "error")] {
            if !ptr.is_null() {
                crate::args::check_array(ptr, len, what)?;
            }
        }
        let prediction = hystcomp_identify::predict(
            &model.file,
            hystcomp_identify::Record {
                voltage,
                displacement,
            },
            settled != 0,
        )?;
        for (ptr, values) in [
            (predicted, &prediction.predicted),
            (error, &prediction.error),
        ] {
            if !ptr.is_null() {
                // SAFETY: `ptr` is valid for `len == values.len()` writes (the caller's
                // contract), non-NULL and aligned (checked).
                unsafe { std::ptr::copy_nonoverlapping(values.as_ptr(), ptr, values.len()) };
            }
        }
        if !summary.is_null() {
            // SAFETY: non-NULL, valid for a write (the caller's contract).
            unsafe {
                summary.write(HystcompPrediction {
                    error: (&prediction.stats).into(),
                    outside_input_range: prediction.outside_input_range,
                })
            };
        }
        Ok(())
    })
}
