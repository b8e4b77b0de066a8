//! Identification and the tracking indices across the C boundary, called from Rust as C calls
//! them: the same model and fit report as the library (`hystcomp_identify::identify`) for every
//! option on seeded random records, the same indices as `hystcomp_indices`, and every NULL,
//! NaN, empty, mismatched or out-of-range argument refused with its status and a message,
//! before anything large is allocated.

use std::ffi::{CStr, c_int};
use std::ptr::{null, null_mut};

mod common;

use common::*;
use hystcomp::*;
use hystcomp_core::Mpim;
use hystcomp_core::paper::TABLE1;
use hystcomp_identify::{
    IdentifyOptions, Method, OutputOffset, PsoOptions, Thresholds, Warmup, identify,
};
use hystcomp_io::model_file::Direction;
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A record of Table 1's MPIM: a decaying 1 Hz sine from `offset_v`, 0 .. 10 V, displacement
/// in um plus seeded sensor noise of `noise_um` and a sensor offset.
fn record(seed: u64, len: usize, noise_um: f64) -> (Vec<f64>, Vec<f64>) {
    let mut plant: Mpim<f64, Vec<f64>> = TABLE1.model().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sensor_offset = rng.random::<f64>() * 20.0 - 10.0;
    let voltage: Vec<f64> = (0..len)
        .map(|k| {
            let t = k as f64 / 200.0;
            5.0 - 5.0 * (-t / 10.0).exp() * (2.0 * std::f64::consts::PI * t).cos()
        })
        .collect();
    let displacement = voltage
        .iter()
        .map(|v| {
            75.0 * plant.step(v / 10.0) + sensor_offset + noise_um * (rng.random::<f64>() - 0.5)
        })
        .collect();
    (voltage, displacement)
}

fn default_options() -> HystcompIdentifyOptions {
    // SAFETY: a zeroed struct of numbers and NULL pointers is a valid value to overwrite.
    let mut options: HystcompIdentifyOptions = unsafe { std::mem::zeroed() };
    // SAFETY: a valid out-pointer.
    assert_eq!(
        unsafe { hystcomp_identify_options_default(&mut options) },
        OK
    );
    options
}

/// Identification through the C ABI: the model's values, its report, or the status and message.
fn identify_c(
    voltage: &[f64],
    displacement: &[f64],
    options: Option<&HystcompIdentifyOptions>,
) -> Result<(*mut HystcompModel, HystcompFitReport), (c_int, String)> {
    let mut out = std::ptr::dangling_mut::<HystcompModel>();
    // SAFETY: a zeroed report is a valid value to overwrite.
    let mut report: HystcompFitReport = unsafe { std::mem::zeroed() };
    // SAFETY: arrays of the stated lengths, valid options (or NULL) and out-pointers.
    let status = unsafe {
        hystcomp_identify(
            voltage.as_ptr(),
            voltage.len(),
            displacement.as_ptr(),
            displacement.len(),
            options.map_or(null(), |o| o as *const _),
            &mut out,
            &mut report,
        )
    };
    if status == OK {
        Ok((out, report))
    } else {
        assert!(out.is_null(), "a failed identification leaves NULL in *out");
        Err((status, last_error()))
    }
}

fn values_of(m: *const HystcompModel) -> HystcompModelValues {
    // SAFETY: a zeroed struct of pointers and numbers is a valid value to overwrite.
    let mut values: HystcompModelValues = unsafe { std::mem::zeroed() };
    // SAFETY: a live handle and a valid out-pointer.
    assert_eq!(unsafe { hystcomp_model_values(m, &mut values) }, OK);
    values
}

#[test]
fn the_defaults_are_the_librarys() {
    let o = default_options();
    let library = IdentifyOptions::default();
    let pso = PsoOptions::default();
    assert_eq!(o.direction, HystcompDirection::Plant as c_int);
    assert_eq!(o.solver, HystcompSolver::LeastSquares as c_int);
    assert_eq!(library.thresholds, Thresholds::Uniform(o.operators));
    assert!(o.thresholds.is_null() && o.threshold_count == 0);
    assert_eq!(library.warmup, Warmup::Auto);
    assert_ne!(o.warmup_auto, 0);
    assert_eq!(o.holdout, library.holdout);
    assert_eq!(o.offset_mode, HystcompOffsetMode::Fit as c_int);
    assert_eq!(library.offset, OutputOffset::Fit);
    assert_eq!(
        (o.margin, o.max_condition),
        (library.margin, library.max_condition)
    );
    assert_eq!(o.accept_poor_fit, 0);
    assert_eq!(
        (o.seed, o.particles, o.iterations),
        (pso.seed, pso.particles, pso.iterations)
    );
    assert_eq!(o.polish, 0);
    assert!(o.voltage_unit.is_null() && o.displacement_unit.is_null());
    // SAFETY: the NULL pointer is the test.
    assert_eq!(
        unsafe { hystcomp_identify_options_default(null_mut()) },
        NULL_POINTER
    );
}

/// Checks a model identified through C against the library's identification of the same
/// record with the same options: every parameter and scale bit for bit, the report's figures.
fn assert_same_as_library(
    m: *const HystcompModel,
    report: &HystcompFitReport,
    voltage: &[f64],
    displacement: &[f64],
    options: &IdentifyOptions,
) {
    let reference = identify(voltage, displacement, options).expect("the library identifies");
    let v = values_of(m);
    let file = &reference.model;
    // SAFETY: the arrays point into the live model, `operators` long.
    let (thresholds, weights) = unsafe {
        (
            std::slice::from_raw_parts(v.thresholds, v.operators),
            std::slice::from_raw_parts(v.weights, v.operators),
        )
    };
    assert_eq!(thresholds, &file.thresholds[..]);
    assert_eq!(weights, &file.weights[..]);
    assert_eq!((v.a1, v.a2), (file.a1, file.a2));
    assert_eq!(
        (v.input.offset, v.input.scale),
        (file.input.offset, file.input.scale)
    );
    assert_eq!(
        (v.output.offset, v.output.scale),
        (file.output.offset, file.output.scale)
    );
    assert_eq!([v.input_range_min, v.input_range_max], file.input_range);
    assert_eq!(
        v.direction,
        match file.direction {
            Direction::Plant => 0,
            Direction::Inverse => 1,
        }
    );
    let r = &reference.report;
    assert_eq!(
        (
            report.samples_total,
            report.samples_warmup,
            report.samples_fit,
            report.samples_holdout
        ),
        (
            r.samples.total,
            r.samples.warmup,
            r.samples.fit,
            r.samples.holdout
        )
    );
    assert_eq!(
        (report.fit.rms, report.fit.max, report.fit.mean),
        (r.fit.rms, r.fit.max, r.fit.mean)
    );
    assert_eq!(report.fit.rms_percent, r.fit.rms_percent);
    match &r.holdout {
        Some(h) => assert_eq!(
            (report.holdout.samples, report.holdout.rms),
            (h.samples, h.rms)
        ),
        None => assert!(report.holdout.samples == 0 && report.holdout.rms.is_nan()),
    }
    assert_eq!(report.min_branch_slope, r.min_branch_slope);
    assert_eq!(report.condition_number, r.condition_number);
    assert_eq!(
        (
            report.constraints,
            report.active_constraints,
            report.violated_constraints
        ),
        (r.constraints, r.active_constraints, r.violated_constraints)
    );
    assert_eq!(
        (report.output_min, report.output_max),
        (r.output.min, r.output.max)
    );
    assert_eq!(report.output_offset, r.output_offset);
    // The model carries the whole report as JSON (elapsed time aside, the library's).
    // SAFETY: a NUL-terminated string owned by the live model.
    let json = unsafe { CStr::from_ptr(v.identification_json) }
        .to_str()
        .unwrap();
    let mut carried: serde_json::Value = serde_json::from_str(json).unwrap();
    let mut expected = serde_json::to_value(r).unwrap();
    carried["elapsed_s"] = 0.into();
    expected["elapsed_s"] = 0.into();
    assert_eq!(carried, expected);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn identification_equals_the_librarys_for_every_option(
        seed in 0u64..1_000_000,
        len in 600usize..2500,
        inverse in any::<bool>(),
        operators in 1usize..14,
        given_thresholds in any::<bool>(),
        warmup in prop::option::of(0usize..200),
        holdout in prop::sample::select(vec![0.0, 0.1, 0.25]),
        offset_mode in 0i32..3,
    ) {
        let (voltage, displacement) = record(seed, len, 0.2);
        let mut o = default_options();
        o.direction = c_int::from(inverse);
        o.operators = operators;
        let given = [0.0, 0.15, 0.4, 0.7];
        if given_thresholds {
            o.thresholds = given.as_ptr();
            o.threshold_count = given.len();
        }
        o.warmup_auto = c_int::from(warmup.is_none());
        o.warmup_samples = warmup.unwrap_or(0);
        o.holdout = holdout;
        o.offset_mode = offset_mode;
        o.offset_value = -3.0;
        o.accept_poor_fit = 1;
        o.voltage_unit = c"kV".as_ptr();
        let options = IdentifyOptions {
            direction: if inverse { Direction::Inverse } else { Direction::Plant },
            thresholds: if given_thresholds {
                Thresholds::Given(given.to_vec())
            } else {
                Thresholds::Uniform(operators)
            },
            warmup: warmup.map_or(Warmup::Auto, Warmup::Samples),
            holdout,
            offset: [OutputOffset::Fit, OutputOffset::None, OutputOffset::Value(-3.0)]
                [offset_mode as usize],
            max_fit_rms_percent: None,
            voltage_unit: "kV".into(),
            ..IdentifyOptions::default()
        };
        match identify(&voltage, &displacement, &options) {
            Ok(_) => {
                let (m, report) = identify_c(&voltage, &displacement, Some(&o))
                    .map_err(|e| TestCaseError::fail(format!("{e:?}")))?;
                assert_same_as_library(m, &report, &voltage, &displacement, &options);
                let unit = values_of(m).input;
                // SAFETY: NUL-terminated strings owned by the live model.
                let unit = unsafe { CStr::from_ptr(if inverse { values_of(m).output.unit } else { unit.unit }) };
                prop_assert_eq!(unit.to_str().unwrap(), "kV");
                // SAFETY: a live handle, freed once.
                unsafe { hystcomp_model_free(m) };
            }
            Err(e) => {
                // The same refusal, with the library's message.
                let (_, message) = identify_c(&voltage, &displacement, Some(&o)).unwrap_err();
                prop_assert_eq!(message, e.to_string());
            }
        }
    }
}

#[test]
fn the_particle_swarm_is_reproducible_and_the_librarys() {
    let (voltage, displacement) = record(5, 1200, 0.1);
    let mut o = default_options();
    o.solver = HystcompSolver::ParticleSwarm as c_int;
    o.particles = 12;
    o.iterations = 30;
    o.seed = 99;
    o.accept_poor_fit = 1;
    let options = IdentifyOptions {
        method: Method::ParticleSwarm(
            PsoOptions::default()
                .with_particles(12)
                .unwrap()
                .with_iterations(30)
                .unwrap()
                .with_seed(99),
        ),
        max_fit_rms_percent: None,
        ..IdentifyOptions::default()
    };
    let (m, report) = identify_c(&voltage, &displacement, Some(&o)).unwrap();
    assert_same_as_library(m, &report, &voltage, &displacement, &options);
    // SAFETY: a live handle, freed once.
    unsafe { hystcomp_model_free(m) };
}

#[test]
fn null_options_and_null_report_use_the_defaults() {
    let (voltage, displacement) = record(1, 2000, 0.0);
    let (m, report) = identify_c(&voltage, &displacement, None).unwrap();
    assert_same_as_library(
        m,
        &report,
        &voltage,
        &displacement,
        &IdentifyOptions::default(),
    );
    // Noise-free, but the thresholds lie on the fitted range, not Table 1's 0 .. 10 V.
    assert!(report.fit.rms_percent < 0.1, "{}", report.fit.rms_percent);
    let mut out = null_mut();
    // SAFETY: arrays of the stated length; a NULL report is allowed.
    let status = unsafe {
        hystcomp_identify(
            voltage.as_ptr(),
            voltage.len(),
            displacement.as_ptr(),
            displacement.len(),
            null(),
            &mut out,
            null_mut(),
        )
    };
    assert_eq!(status, OK);
    // SAFETY: live handles, freed once.
    unsafe {
        hystcomp_model_free(m);
        hystcomp_model_free(out);
    }
}

#[test]
fn bad_records_are_refused_with_the_reason() {
    let (voltage, displacement) = record(2, 1000, 0.1);
    let short = &displacement[..999];
    let (status, message) = identify_c(&voltage, short, None).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(
        message.contains("voltage has 1000 samples but displacement has 999"),
        "{message}"
    );
    let (status, message) = identify_c(&[], &[], None).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(message.contains("voltage is empty"), "{message}");
    let mut with_nan = displacement.clone();
    with_nan[321] = f64::NAN;
    let (status, message) = identify_c(&voltage, &with_nan, None).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    // The library counts samples from 1, as MATLAB does.
    assert!(
        message.contains("displacement, sample 322: NaN"),
        "{message}"
    );
    let (status, message) = identify_c(&voltage, &vec![4.0; 1000], None).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT, "{message}");
    // Too few samples for the model.
    let (status, message) = identify_c(&voltage[..20], &displacement[..20], None).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT, "{message}");
    // The displacement falls as the voltage rises: the wrong sign, no model.
    let negated: Vec<f64> = displacement.iter().map(|y| -y).collect();
    let (status, message) = identify_c(&voltage, &negated, None).unwrap_err();
    assert_eq!(status, IDENTIFICATION_FAILED, "{message}");
    // The same column twice.
    let (status, message) = identify_c(&voltage, &voltage, None).unwrap_err();
    assert_eq!(status, IDENTIFICATION_FAILED, "{message}");
    // SAFETY (the block): arrays of the stated lengths; the NULL pointers are the test.
    unsafe {
        let mut out = null_mut();
        let n = voltage.len();
        let call = |v: *const f64, y: *const f64, out| {
            hystcomp_identify(v, n, y, n, null(), out, null_mut())
        };
        assert_eq!(call(null(), displacement.as_ptr(), &mut out), NULL_POINTER);
        assert_eq!(last_error(), "voltage is NULL; pass a valid pointer");
        assert_eq!(call(voltage.as_ptr(), null(), &mut out), NULL_POINTER);
        assert_eq!(last_error(), "displacement is NULL; pass a valid pointer");
        assert_eq!(
            call(voltage.as_ptr(), displacement.as_ptr(), null_mut()),
            NULL_POINTER
        );
        assert_eq!(last_error(), "out is NULL; pass a valid pointer");
    }
}

#[test]
fn options_out_of_range_are_refused_before_allocating() {
    let (voltage, displacement) = record(3, 1000, 0.1);
    type Edit = Box<dyn Fn(&mut HystcompIdentifyOptions)>;
    let thresholds = [0.0, 0.5];
    let cases: Vec<(Edit, &str)> = vec![
        (
            Box::new(|o| o.operators = 0),
            "number of play operators \"0\": give at least 1",
        ),
        // Far beyond memory: refused by the library's bound, never allocated.
        (Box::new(|o| o.operators = usize::MAX), "give at most 1000"),
        (
            Box::new(|o| o.threshold_count = 3),
            "thresholds (threshold_count is not 0) is NULL",
        ),
        (
            Box::new(move |o| {
                o.thresholds = thresholds.as_ptr();
                o.threshold_count = 0;
            }),
            "give at least one threshold",
        ),
        (
            Box::new(move |o| {
                o.thresholds = thresholds.as_ptr();
                o.threshold_count = usize::MAX; // refused before the array is read
            }),
            "threshold_count 18446744073709551615 is more than the 1000",
        ),
        (Box::new(|o| o.operators = 1000), "more than the 50000000"),
        (
            Box::new(|o| o.solver = 2),
            "solver 2 is not a HystcompSolver",
        ),
        (
            Box::new(|o| o.direction = -1),
            "direction -1 is not a HystcompDirection",
        ),
        (
            Box::new(|o| o.offset_mode = 3),
            "offset_mode 3 is not a HystcompOffsetMode",
        ),
        (
            Box::new(|o| {
                o.offset_mode = 2;
                o.offset_value = f64::NAN
            }),
            "offset",
        ),
        (Box::new(|o| o.holdout = 1.0), "holdout"),
        (Box::new(|o| o.holdout = f64::NAN), "holdout"),
        (Box::new(|o| o.margin = 0.0), "margin"),
        (
            Box::new(|o| o.max_condition = f64::INFINITY),
            "max-condition",
        ),
        (Box::new(|o| o.voltage_unit = c" ".as_ptr()), "voltage unit"),
        (
            Box::new(|o| o.displacement_unit = c"\xff".as_ptr()),
            "displacement_unit is not valid UTF-8",
        ),
        (
            Box::new(|o| {
                o.solver = 1;
                o.particles = 1
            }),
            "a swarm has 2 to 1000 particles",
        ),
        (
            Box::new(|o| {
                o.solver = 1;
                o.particles = 1_000_000
            }),
            "particles \"1000000\"",
        ),
        (
            Box::new(|o| {
                o.solver = 1;
                o.iterations = 0
            }),
            "give 1 to 100000 iterations",
        ),
        (
            Box::new(|o| {
                o.solver = 1;
                o.iterations = usize::MAX
            }),
            "iterations",
        ),
    ];
    // 1000 samples x 1000 operators would fit; the regressor bound needs more samples.
    let long_v: Vec<f64> = voltage.iter().cycle().take(60_000).copied().collect();
    let long_y: Vec<f64> = displacement.iter().cycle().take(60_000).copied().collect();
    for (edit, needle) in cases {
        let mut o = default_options();
        edit(&mut o);
        let (v, y) = if needle == "more than the 50000000" {
            (&long_v[..], &long_y[..])
        } else {
            (&voltage[..], &displacement[..])
        };
        let result = identify_c(v, y, Some(&o));
        let (status, message) = result.map(|(m, _)| m).unwrap_err();
        assert!(
            status == INVALID_ARGUMENT || status == NULL_POINTER,
            "{needle}: {status} {message}"
        );
        assert!(message.contains(needle), "{needle}: {message}");
    }
}

/// The three indices through C, or the status and message.
fn indices_c(desired: &[f64], measured: &[f64], bins: usize) -> Result<[f64; 3], (c_int, String)> {
    let mut out = [f64::NAN; 3];
    // SAFETY: arrays of the stated lengths and valid out-pointers.
    unsafe {
        for (k, status) in [
            hystcomp_e_m(
                desired.as_ptr(),
                desired.len(),
                measured.as_ptr(),
                measured.len(),
                &mut out[0],
            ),
            hystcomp_e_rms(
                desired.as_ptr(),
                desired.len(),
                measured.as_ptr(),
                measured.len(),
                &mut out[1],
            ),
            hystcomp_e_mhe(
                desired.as_ptr(),
                desired.len(),
                measured.as_ptr(),
                measured.len(),
                bins,
                &mut out[2],
            ),
        ]
        .into_iter()
        .enumerate()
        {
            if status != OK {
                return Err((status, format!("index {k}: {}", last_error())));
            }
        }
    }
    Ok(out)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn indices_equal_the_librarys(
        desired in prop::collection::vec(-100.0f64..100.0, 2..600),
        noise in prop::collection::vec(-5.0f64..5.0, 600),
        bins in 1usize..70,
    ) {
        let measured: Vec<f64> = desired.iter().zip(&noise).map(|(d, e)| d + e).collect();
        let c = indices_c(&desired, &measured, bins);
        let library = (
            hystcomp_indices::e_m_percent(&desired, &measured),
            hystcomp_indices::e_rms_percent(&desired, &measured),
            hystcomp_indices::e_mhe_percent(&desired, &measured, bins),
        );
        match (c, library) {
            (Ok(values), (Ok(a), Ok(b), Ok(e))) => prop_assert_eq!(values, [a, b, e]),
            (Err((status, message)), (a, b, e)) => {
                prop_assert_eq!(status, INVALID_ARGUMENT);
                let first = [a.err(), b.err(), e.err()].into_iter().flatten().next();
                prop_assert!(first.is_some(), "C refused what the library accepts: {}", message);
                prop_assert!(message.ends_with(&first.unwrap().to_string()), "{}", message);
            }
            (Ok(values), library) => prop_assert!(false, "C gave {values:?}, the library {library:?}"),
        }
    }
}

#[test]
fn indices_refuse_bad_records_with_the_reason() {
    let d: Vec<f64> = (0..200).map(|k| (k as f64 * 0.1).sin()).collect();
    let y: Vec<f64> = d.iter().map(|x| x + 0.01).collect();
    let expect = |result: Result<[f64; 3], (c_int, String)>, needle: &str| {
        let (status, message) = result.unwrap_err();
        assert_eq!(status, INVALID_ARGUMENT, "{message}");
        assert!(message.contains(needle), "{needle}: {message}");
    };
    expect(
        indices_c(&d, &y[..199], 10),
        "the desired record has 200 samples but the measured record has 199",
    );
    expect(indices_c(&[], &[], 10), "desired is empty");
    expect(indices_c(&d, &[], 10), "measured is empty");
    expect(indices_c(&[1.0], &[1.0], 1), "at least 2");
    let mut with_nan = y.clone();
    with_nan[17] = f64::INFINITY;
    expect(
        indices_c(&d, &with_nan, 10),
        "measured record has a NaN or infinite value at sample 17",
    );
    expect(indices_c(&[2.0; 30], &[2.0; 30], 1), "constant");
    expect(indices_c(&d, &y, 0), "at least one bin");
    expect(indices_c(&d, &y, 21), "use at most 20 bins");
    expect(indices_c(&d, &y, usize::MAX), "use at most 20 bins");
    // SAFETY: arrays of the stated lengths; the NULL pointers are the test.
    unsafe {
        let mut out = 0.0;
        assert_eq!(
            hystcomp_e_m(null(), 200, y.as_ptr(), 200, &mut out),
            NULL_POINTER
        );
        assert_eq!(last_error(), "desired is NULL; pass a valid pointer");
        assert_eq!(
            hystcomp_e_rms(d.as_ptr(), 200, null(), 200, &mut out),
            NULL_POINTER
        );
        assert_eq!(last_error(), "measured is NULL; pass a valid pointer");
        assert_eq!(
            hystcomp_e_mhe(d.as_ptr(), 200, y.as_ptr(), 200, 10, null_mut()),
            NULL_POINTER
        );
        assert_eq!(last_error(), "percent is NULL; pass a valid pointer");
    }
    assert_eq!(
        HYSTCOMP_DEFAULT_MHE_BINS,
        hystcomp_indices::DEFAULT_MHE_BINS
    );
}
