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
    /// Swarm: particles, 2 to `HYSTCOMP_MAX_PARTICLES` (default 40).
    pub particles: usize,
    /// Swarm: iterations, 1 to `HYSTCOMP_MAX_ITERATIONS` (default 200).
    pub iterations: usize,
    /// Swarm: non-zero to polish the best particle by least squares.
    pub polish: c_int,
    /// Unit of the voltage samples, written to the model (NULL: `"V"`).
    pub voltage_unit: *const c_char,
    /// Unit of the displacement samples, written to the model (NULL: `"um"`).
    pub displacement_unit: *const c_char,
}

/// Errors of a model's prediction over a span of samples (`predicted - measured`), in the
/// output's unit and in % of the fitted output range.
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
    /// The range the percentages refer to (the fitted output range).
    pub range: f64,
    /// `rms` in % of the fitted output range.
    pub rms_percent: f64,
    /// `max` in % of the fitted output range.
    pub max_percent: f64,
    /// The RMS of the error minus its mean, in % of the fitted output range.
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
    }
}

/// Fills `*options` with the defaults: a plant model, least squares, 10 operators, automatic
/// warm-up, no hold-out, a fitted output offset, margin 0.001, poor fits refused, the swarm's
/// 40 particles x 200 iterations from seed 0, units V and um.
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
/// - `options`: NULL for the defaults (`hystcomp_identify_options_default`).
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
        let options = unsafe { library_options(&given) }?;
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
