//! Cross-validation: identify on one record, predict and replay the compensators on another.
//!
//! The **offline inverse replay** feeds the *measured* displacement of the test record to each
//! compensator as its desired position `y_d` and compares the voltage it returns with the
//! voltage that was actually applied. A perfect compensator for this device would return
//! exactly the applied voltage, so the replay error tells, before touching hardware, how each
//! compensator would do on the device the records come from.

use hystcomp_io::compensator::{Method, ScaledCompensator, UnstableDelay};
use hystcomp_io::data::{check_finite, check_min_samples, check_not_constant, check_same_length};
use hystcomp_io::model_file::{Direction, ModelFile};
use serde::{Deserialize, Serialize};

use crate::identification::{auto_warmup, min_max, minimum_fit_samples, parameter_count};
use crate::report::{DelayedGains, ErrorStats, FitReport};
use crate::{IdentifyError, IdentifyOptions, Observer, OutputOffset, Warmup, identify_observed};

/// One record: the drive voltage and the measured displacement, one pair per sample.
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Drive voltage, in the voltage unit of the options.
    pub voltage: &'a [f64],
    /// Measured displacement, in the displacement unit of the options.
    pub displacement: &'a [f64],
}

impl Record<'_> {
    fn check(&self) -> Result<(), IdentifyError> {
        check_same_length(&[
            ("voltage", self.voltage),
            ("displacement", self.displacement),
        ])?;
        check_finite("voltage", self.voltage)?;
        check_finite("displacement", self.displacement)?;
        check_not_constant("voltage", self.voltage)?;
        check_not_constant("displacement", self.displacement)?;
        Ok(())
    }
}

/// Options of [`crossval`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct CrossvalOptions {
    /// How both models are identified on the training record (the direction is ignored: a
    /// plant model and an inverse model are identified).
    pub identify: IdentifyOptions,
    /// Samples at the start of the test record left out of the errors. `Auto` (and
    /// `Estimate`): with [`TestStart::Rest`], up to the first sample whose voltage is within
    /// [`AUTO_WARMUP_LEVEL`](crate::AUTO_WARMUP_LEVEL) (5 %) of the test record's voltage range
    /// from its minimum (identification's [`Warmup::Auto`] is stricter); with
    /// [`TestStart::ContinueTraining`] none (the memory is known).
    pub test_warmup: Warmup,
    /// Where the models and compensators start on the test record: from rest, or carrying
    /// their memory from the end of the training record when the test record continues it.
    #[serde(default)]
    pub test_start: TestStart,
    /// Whether the plain delayed compensators (`ihc-delayed`, `wihc-delayed`) are replayed
    /// even when their loop gain over the limits is 1 or more (by default they are reported as
    /// not built, with the reason).
    #[serde(default)]
    pub unstable_delay: UnstableDelay,
}

/// Where the models and the compensators start on the test record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TestStart {
    /// At rest at the test record's first sample: every play operator at zero memory (eq.
    /// (1)), so that the first sample acts as if the drive had risen from the bottom of the
    /// model's input range to it (the stage at rest at its lowest drive before the record), a
    /// creep link settled at the first sample. The test warm-up leaves out the samples whose
    /// prediction depends on the unknown history. The default: right for two separate records.
    #[default]
    Rest,
    /// The test record continues the training record (consecutive spans of one record): the
    /// models and the compensators first run over the training record, from rest at its first
    /// sample, and carry their memory into the test record, whose first sample is then
    /// predicted as the whole record's prediction predicts it.
    ContinueTraining,
}

impl TestStart {
    /// The initial state in words, for reports (`warmup` test samples left out).
    pub fn describe(self, preceding: usize, warmup: usize) -> String {
        match self {
            TestStart::Rest => format!(
                "at rest at the test record's first sample (operators at zero memory, as after \
                 the drive rose from the bottom of the model's input range; creep settled \
                 there); the first {warmup} test samples left out as warm-up"
            ),
            TestStart::ContinueTraining => format!(
                "continued from the end of the training record: models and compensators ran \
                 over its {preceding} samples first (from rest) and carried their memory into \
                 the test record; {warmup} test samples left out as warm-up"
            ),
        }
    }
}

/// The replay of one compensator over the test record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Replay {
    /// `ihc`, `ihc-delayed`, `wihc`, `wihc-delayed`, `dihc`, `ihc-guarded` or `wihc-guarded`.
    pub compensator: String,
    /// Returned minus applied voltage over the evaluated span, in % of the test record's
    /// voltage range there. `None` when the compensator could not be built.
    pub error: Option<ErrorStats>,
    /// Samples of the evaluated span whose desired position could not be reached within the
    /// output limits (or lay outside a DIHC model's input range): the output was clamped.
    pub saturated: u64,
    /// Samples of the evaluated span clamped to a limit although the desired position was
    /// reachable: a one-sample-delayed loop (`ihc-delayed`, `wihc-delayed`) lagged or rang
    /// after a jump (the core's `Diagnostics::loop_saturated`). Never counted in `saturated`;
    /// the samples at a limit are `saturated + loop_saturated`.
    #[serde(default)]
    pub loop_saturated: u64,
    /// Why the compensator could not be built, if it could not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

/// What [`crossval`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrossvalReport {
    /// The plant model's fit on the training record.
    pub plant: FitReport,
    /// The inverse model's fit on the training record.
    pub inverse: FitReport,
    /// The validation on the test record.
    pub test: Validation,
}

/// The models' errors on a test record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    /// Samples in the test record.
    pub samples: usize,
    /// Samples at its start left out of the errors.
    pub warmup: usize,
    /// Where the models and compensators started (reports written before this field existed
    /// started at rest).
    #[serde(default)]
    pub start: TestStart,
    /// The samples run before the test record's first ([`TestStart::ContinueTraining`]: the
    /// training record's; 0 at rest).
    #[serde(default)]
    pub preceding_samples: usize,
    /// The initial state in words ([`TestStart::describe`]).
    #[serde(default)]
    pub initial_state: String,
    /// The denominators of every percentage: the test record's displacement and voltage
    /// ranges over the evaluated span (after the warm-up), physical units. The forward error
    /// is in % of the first, the replay errors in % of the second (the same normalisation as
    /// `identify`'s held-out error: the test span's own range).
    #[serde(default)]
    pub ranges: TestRanges,
    /// The output limits of the compensators: the voltage range the plant model was fitted on
    /// (physical; the training record after its warm-up, without its hold-out).
    pub voltage_limits: [f64; 2],
    /// The gains of the plant model's delayed IHC and WIHC loops over the voltage limits (at
    /// or above 1 the plain delayed loop can ring, and is not built unless allowed).
    #[serde(default)]
    pub delayed_loop_gains: Option<DelayedGains>,
    /// Test samples whose voltage lies outside the plant model's input range (the model
    /// extrapolates there).
    pub voltage_outside_model_range: usize,
    /// Test samples whose displacement lies outside the inverse model's input range (DIHC
    /// clamps them). For a chain (creep or vibration links), whose inverse model's input is
    /// the creep-free displacement, outside the training record's measured displacement
    /// range instead ([`crate::crossval_chain`]).
    pub displacement_outside_model_range: usize,
    /// The plant model's prediction of the measured displacement from the applied voltage, in
    /// % of the test record's displacement range over the evaluated span.
    pub forward: ErrorStats,
    /// The offline inverse replay of each compensator.
    pub replay: Vec<Replay>,
}

/// The ranges the percentages of a [`Validation`] refer to.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct TestRanges {
    /// `max - min` of the measured displacement over the evaluated span.
    pub displacement: f64,
    /// `max - min` of the applied voltage over the evaluated span.
    pub voltage: f64,
}

/// A cross-validation: the report and both identified models.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrossValidation {
    /// The report.
    pub report: CrossvalReport,
    /// The plant model (for IHC and WIHC).
    pub plant: ModelFile,
    /// The inverse model (for DIHC).
    pub inverse: ModelFile,
}

/// Identifies a plant model and an inverse model on `train` and validates both on `test`
/// (see [`validate_models`]). `observer` sees the solver's progress of both identifications,
/// each announced by [`Observer::begin`] (`plant model`, `inverse model`).
pub fn crossval(
    train: Record<'_>,
    test: Record<'_>,
    options: &CrossvalOptions,
    observer: &mut dyn Observer,
) -> Result<CrossValidation, IdentifyError> {
    train.check()?;
    test.check()?;
    let mut plant_options = options.identify.clone();
    plant_options.direction = Direction::Plant;
    let mut inverse_options = options.identify.clone();
    inverse_options.direction = Direction::Inverse;
    observer.begin("plant model");
    let plant = identify_observed(train.voltage, train.displacement, &plant_options, observer)?;
    observer.begin("inverse model");
    let inverse = identify_observed(
        train.voltage,
        train.displacement,
        &inverse_options,
        observer,
    )?;
    // The compensators' output limits: the voltage range the plant model was fitted on.
    let limits = [plant.report.input.min, plant.report.input.max];
    let test_report = validate_models_from(
        &plant.model,
        &inverse.model,
        limits,
        preceding(train, options.test_start),
        test,
        options.test_warmup,
        options.unstable_delay,
    )?;
    Ok(CrossValidation {
        report: CrossvalReport {
            plant: plant.report,
            inverse: inverse.report,
            test: test_report,
        },
        plant: plant.model,
        inverse: inverse.model,
    })
}

/// The record run before the test record: the training record when the test record
/// continues it.
pub(crate) fn preceding(train: Record<'_>, start: TestStart) -> Option<Record<'_>> {
    (start == TestStart::ContinueTraining).then_some(train)
}

/// Validates a plant model and an inverse model on a record, from rest at its first sample
/// ([`TestStart::Rest`]; see [`validate_models_from`]).
pub fn validate_models(
    plant: &ModelFile,
    inverse: &ModelFile,
    voltage_limits: [f64; 2],
    test: Record<'_>,
    warmup: Warmup,
    unstable_delay: UnstableDelay,
) -> Result<Validation, IdentifyError> {
    validate_models_from(
        plant,
        inverse,
        voltage_limits,
        None,
        test,
        warmup,
        unstable_delay,
    )
}

/// The models' predictions over the test record, as [`validate_models_from`] runs them: the
/// plant model's displacement from the applied voltage and the inverse model's voltage from
/// the measured displacement (physical units, one per test sample), each run first over
/// `preceding` when given (the memory carried into the test record) and otherwise from rest,
/// a creep link settled at the first sample run.
pub fn predict_test(
    plant: &ModelFile,
    inverse: &ModelFile,
    preceding: Option<Record<'_>>,
    test: Record<'_>,
) -> Result<(Vec<f64>, Vec<f64>), IdentifyError> {
    let (voltage, displacement) = joined(preceding, test);
    let skip = voltage.len() - test.voltage.len();
    let mut forward = plant.predict_settled(&voltage)?;
    let mut backward = inverse.predict_settled(&displacement)?;
    forward.drain(..skip);
    backward.drain(..skip);
    Ok((forward, backward))
}

/// The preceding record (if any) followed by the test record.
fn joined(preceding: Option<Record<'_>>, test: Record<'_>) -> (Vec<f64>, Vec<f64>) {
    match preceding {
        None => (test.voltage.to_vec(), test.displacement.to_vec()),
        Some(p) => (
            [p.voltage, test.voltage].concat(),
            [p.displacement, test.displacement].concat(),
        ),
    }
}

/// Validates a plant model and an inverse model on a record:
///
/// - (a) the plant model's prediction of the measured displacement from the applied voltage;
/// - (b) the offline inverse replay (see the [module documentation](self)) of IHC and WIHC
///   (exact, delayed and guarded delayed, from the plant model) and DIHC (from the inverse
///   model), with output limits `voltage_limits` (physical; the training record's voltage
///   range). A plain delayed loop whose gain over the limits is 1 or more is not built (the
///   replay says why) unless `unstable_delay` allows it.
///
/// Everything starts from its reset state at the first sample of `preceding` when given (the
/// record the test record continues: [`TestStart::ContinueTraining`], whose memory is
/// carried into the test record, and whose samples are not scored), or else of the test
/// record ([`TestStart::Rest`]). Errors are taken on the test record after the warm-up
/// (`Auto`: none after a preceding record, see [`CrossvalOptions::test_warmup`]), in % of
/// the test span's own displacement range (forward) and voltage range (replay), over at least as many samples as identifying the plant model needs
/// ([`SAMPLES_PER_PARAMETER`](crate::SAMPLES_PER_PARAMETER) per parameter, counted as
/// [`identify`](crate::identify) counts them: `a1`, `a2` and the `n` weights, less one when
/// `r_1 = 0`, plus the output offset when the plant model's report says it was fitted or the
/// model has no report; fewer give [`IdentifyError::Data`]).
pub fn validate_models_from(
    plant: &ModelFile,
    inverse: &ModelFile,
    voltage_limits: [f64; 2],
    preceding: Option<Record<'_>>,
    test: Record<'_>,
    warmup: Warmup,
    unstable_delay: UnstableDelay,
) -> Result<Validation, IdentifyError> {
    test.check()?;
    if let Some(p) = &preceding {
        p.check()?;
    }
    let start_kind = if preceding.is_some() {
        TestStart::ContinueTraining
    } else {
        TestStart::Rest
    };
    let pre = preceding.map_or(0, |p| p.voltage.len());
    let wrong = |what: &str, file: &ModelFile, expected: Direction| {
        (file.direction != expected).then(|| IdentifyError::InvalidOption {
            option: "model direction",
            value: file.direction.to_string(),
            reason: format!("the {what} model must have direction {expected}"),
        })
    };
    if let Some(e) = wrong("plant", plant, Direction::Plant) {
        return Err(e);
    }
    if let Some(e) = wrong("inverse", inverse, Direction::Inverse) {
        return Err(e);
    }
    let samples = test.voltage.len();
    let start = match (warmup, start_kind) {
        (Warmup::Auto | Warmup::Estimate, TestStart::ContinueTraining) => 0,
        // Nothing is fitted on the test record: estimating its memory means nothing there.
        (Warmup::Auto | Warmup::Estimate, TestStart::Rest) => auto_warmup(test.voltage),
        (Warmup::Samples(n), _) => n,
    };
    if start >= samples {
        return Err(IdentifyError::InvalidOption {
            option: "test warm-up",
            value: start.to_string(),
            reason: format!("the test record has only {samples} samples; give a shorter warm-up"),
        });
    }
    let parameters = parameter_count(&plant.thresholds, offset_fitted(plant));
    let needed = minimum_fit_samples(parameters);
    check_min_samples(
        needed,
        samples - start,
        &format!(
            "a validation on the test record (as many as identifying a model with {} play \
             operator(s), {parameters} parameters, needs; after a test warm-up of {start} of its {samples} samples: give \
             more rows or a shorter --test-warmup)",
            plant.thresholds.len()
        ),
    )?;
    let span = start..samples;
    let voltage_range = range_of(&test.voltage[span.clone()]);
    let displacement_range = range_of(&test.displacement[span.clone()]);

    // (a) Forward prediction (a creep link taken at rest at the record's start: a measured
    // record starts in the middle of a history), through the preceding record if any.
    let (all_voltage, all_displacement) = joined(preceding, test);
    let mut predicted = plant.predict_settled(&all_voltage)?;
    predicted.drain(..pre);
    // A prediction or an error that overflows would make the RMS inf: refused, naming the
    // sample (the values read are bounded, but arrays from the bindings need not be).
    if let Some(k) = span.clone().find(|&k| {
        let e = predicted[k] - test.displacement[k];
        !(e * e).is_finite()
    }) {
        return Err(IdentifyError::Data(
            hystcomp_io::data::DataError::NotFinite {
                path: None,
                line: None,
                row: k + 1,
                column: "the forward prediction error on the test record".to_owned(),
                value: predicted[k] - test.displacement[k],
            },
        ));
    }
    let forward = ErrorStats::new(
        &predicted[span.clone()],
        &test.displacement[span.clone()],
        displacement_range,
    )
    .expect("the evaluated span is not empty");
    let voltage_outside_model_range = plant.count_outside_input_range(test.voltage);
    let displacement_outside_model_range = inverse.count_outside_input_range(test.displacement);

    // (b) Offline inverse replay: the measured displacement as y_d, in physical units, through
    // each compensator built from its model file (the scaling is the io crate's, as everywhere).
    let mut replay = Vec::with_capacity(Method::ALL.len());
    for method in Method::ALL {
        let file = match method.needs() {
            Direction::Plant => plant,
            Direction::Inverse => inverse,
        };
        let mut compensator = match ScaledCompensator::with_unstable_delay(
            file,
            method,
            Some((voltage_limits[0], voltage_limits[1])),
            unstable_delay,
        ) {
            Ok(c) => c,
            Err(e) => {
                replay.push(Replay {
                    compensator: method.name().to_owned(),
                    error: None,
                    saturated: 0,
                    loop_saturated: 0,
                    failure: Some(e.to_string()),
                });
                continue;
            }
        };
        compensator.settle_creep(all_displacement[0]);
        let mut voltage = Vec::with_capacity(all_displacement.len());
        let mut before = compensator.diagnostics();
        if compensator.preview() > 0 {
            // A chain with a vibration link inverts over a preview: the whole record at once,
            // aligned (its clamps are counted over the whole record, warm-up included).
            voltage.resize(all_displacement.len(), 0.0);
            compensator
                .process(&all_displacement, &mut voltage)
                .map_err(|e| IdentifyError::InvalidOption {
                    option: "replay",
                    value: method.name().to_owned(),
                    reason: e.to_string(),
                })?;
        } else {
            for (k, &y_d) in all_displacement.iter().enumerate() {
                if k == pre + start {
                    before = compensator.diagnostics();
                }
                voltage.push(compensator.step(y_d));
            }
        }
        voltage.drain(..pre);
        let after = compensator.diagnostics();
        replay.push(Replay {
            compensator: method.name().to_owned(),
            error: ErrorStats::new(
                &voltage[span.clone()],
                &test.voltage[span.clone()],
                voltage_range,
            ),
            saturated: after.saturated - before.saturated,
            loop_saturated: after.loop_saturated - before.loop_saturated,
            failure: None,
        });
    }

    let delayed_loop_gains = plant.model().ok().map(|model| {
        DelayedGains::of(
            &model,
            plant.normalise_input(voltage_limits[0]),
            plant.normalise_input(voltage_limits[1]),
        )
    });
    Ok(Validation {
        samples,
        warmup: start,
        start: start_kind,
        preceding_samples: pre,
        initial_state: start_kind.describe(pre, start),
        ranges: TestRanges {
            displacement: displacement_range,
            voltage: voltage_range,
        },
        voltage_limits,
        delayed_loop_gains,
        voltage_outside_model_range,
        displacement_outside_model_range,
        forward,
        replay,
    })
}

/// Whether the plant model's output offset was fitted, from the report in its
/// `identification` field; `true` (the default of [`IdentifyOptions`], and the larger count)
/// when the model has no readable report.
fn offset_fitted(plant: &ModelFile) -> bool {
    plant
        .identification
        .as_ref()
        .and_then(|report| report.get("offset_mode"))
        .and_then(|mode| serde_json::from_value::<OutputOffset>(mode.clone()).ok())
        .is_none_or(|mode| mode == OutputOffset::Fit)
}

/// `max - min`, or 1 for a constant span (so that percentages stay finite).
pub(crate) fn range_of(values: &[f64]) -> f64 {
    let (lo, hi) = min_max(values);
    if hi > lo { hi - lo } else { 1.0 }
}
