//! Bad input across the C boundary, called from Rust exactly as C calls it: every NULL pointer,
//! zero length, NaN parameter, non-invertible model and missing file gives its status and a
//! message, never a crash, and a compensator's output never leaves its limits.

use std::ffi::{CStr, CString, c_int};
use std::ptr::{null, null_mut};

mod common;

use common::*;
use hystcomp::*;
use hystcomp_core::paper::{TABLE1, TABLE2};

/// A compensator from a model file, or the status and message.
fn from_file(
    path: &CStr,
    method: &str,
    limits: Option<(f64, f64)>,
) -> Result<*mut HystcompCompensator, (c_int, String)> {
    from_file_with(path, method, limits, None)
}

/// `hystcomp_compensator_from_model_file`, or `..._with(flags)` when `flags` is given.
fn from_file_with(
    path: &CStr,
    method: &str,
    limits: Option<(f64, f64)>,
    flags: Option<c_int>,
) -> Result<*mut HystcompCompensator, (c_int, String)> {
    let method = CString::new(method).unwrap();
    let mut out = std::ptr::dangling_mut::<HystcompCompensator>(); // not NULL: must be cleared on failure
    let (lo, hi) = limits.unwrap_or((0.0, 0.0));
    let use_limits = c_int::from(limits.is_some());
    // SAFETY: valid strings and out-pointer.
    let status = unsafe {
        match flags {
            None => hystcomp_compensator_from_model_file(
                path.as_ptr(),
                method.as_ptr(),
                lo,
                hi,
                use_limits,
                &mut out,
            ),
            Some(flags) => hystcomp_compensator_from_model_file_with(
                path.as_ptr(),
                method.as_ptr(),
                lo,
                hi,
                use_limits,
                flags,
                &mut out,
            ),
        }
    };
    if status == OK {
        assert!(!out.is_null());
        Ok(out)
    } else {
        assert!(out.is_null(), "a failed constructor leaves NULL in *out");
        Err((status, last_error()))
    }
}

/// A compensator from normalised parameters, or the status and message.
fn from_parameters(
    thresholds: &[f64],
    weights: &[f64],
    a1: f64,
    a2: f64,
    method: HystcompMethod,
    limits: (f64, f64),
) -> Result<*mut HystcompCompensator, (c_int, String)> {
    assert_eq!(thresholds.len(), weights.len());
    let mut out = null_mut();
    // SAFETY: arrays of the stated length, a valid out-pointer.
    let status = unsafe {
        hystcomp_compensator_from_parameters(
            thresholds.as_ptr(),
            weights.as_ptr(),
            thresholds.len(),
            a1,
            a2,
            method as c_int,
            limits.0,
            limits.1,
            &mut out,
        )
    };
    if status == OK {
        Ok(out)
    } else {
        assert!(out.is_null());
        Err((status, last_error()))
    }
}

fn table1_ihc() -> *mut HystcompCompensator {
    from_parameters(
        &TABLE1.thresholds,
        &TABLE1.weights,
        TABLE1.a1,
        TABLE1.a2,
        HystcompMethod::Ihc,
        (0.0, 1.0),
    )
    .expect("Table 1 gives an IHC")
}

fn step(h: *mut HystcompCompensator, y_d: f64) -> (c_int, f64) {
    let mut v = f64::NAN;
    // SAFETY: a live handle (or NULL, which is checked) and a valid out-pointer.
    let status = unsafe { hystcomp_compensator_step(h, y_d, &mut v) };
    (status, v)
}

#[test]
fn every_method_builds_from_the_model_files_and_stays_within_limits() {
    for (file, methods) in [
        (
            "table1-plant.json",
            &["ihc", "IHC-delayed", "wihc", "ihc-guarded", "wihc-guarded"][..],
        ),
        ("table2-inverse.json", &["dihc"][..]),
    ] {
        for method in methods {
            let h = from_file(&model_path(file), method, Some((1.0, 9.0))).unwrap();
            for k in 0..2000 {
                // Far beyond the reachable range on both sides, and NaN now and then.
                let y_d = if k % 97 == 0 {
                    f64::NAN
                } else {
                    37.5 + 60.0 * (k as f64 * 0.01).sin()
                };
                let (status, v) = step(h, y_d);
                assert_eq!(status, if y_d.is_nan() { NON_FINITE_INPUT } else { OK });
                assert!((1.0..=9.0).contains(&v), "{method}: {v} V outside [1, 9]");
            }
            let (mut saturated, mut non_finite) = (0, 0);
            // SAFETY: a live handle and valid out-pointers.
            assert_eq!(
                unsafe { hystcomp_compensator_diagnostics(h, &mut saturated, &mut non_finite) },
                OK
            );
            assert_eq!(non_finite, 21, "{method}");
            assert!(saturated > 100, "{method}: {saturated}");
            // SAFETY: a live handle, freed once.
            unsafe { hystcomp_compensator_free(h) };
        }
    }
}

#[test]
fn null_pointers_give_null_pointer_and_name_the_argument() {
    let path = model_path("table1-plant.json");
    let ihc = c"ihc";
    let mut out = null_mut();
    // Each call is checked right after it: the message is that of the last failed call.
    let check = |status: c_int, expected: &str| {
        assert_eq!(status, NULL_POINTER, "{expected}");
        assert_eq!(
            last_error(),
            format!("{expected} is NULL; pass a valid pointer")
        );
    };
    // SAFETY (every block below): each non-NULL pointer is valid; the NULL ones are the test.
    unsafe {
        check(
            hystcomp_compensator_from_model_file(null(), ihc.as_ptr(), 0.0, 0.0, 0, &mut out),
            "path",
        );
        check(
            hystcomp_compensator_from_model_file(path.as_ptr(), null(), 0.0, 0.0, 0, &mut out),
            "method",
        );
        check(
            hystcomp_compensator_from_model_file(
                path.as_ptr(),
                ihc.as_ptr(),
                0.0,
                0.0,
                0,
                null_mut(),
            ),
            "out",
        );
        check(
            hystcomp_compensator_from_parameters(
                null(),
                TABLE1.weights.as_ptr(),
                10,
                0.0,
                1.0,
                0,
                0.0,
                1.0,
                &mut out,
            ),
            "thresholds",
        );
        check(
            hystcomp_compensator_from_parameters(
                TABLE1.thresholds.as_ptr(),
                null(),
                10,
                0.0,
                1.0,
                0,
                0.0,
                1.0,
                &mut out,
            ),
            "weights",
        );
        check(
            hystcomp_compensator_from_parameters(
                TABLE1.thresholds.as_ptr(),
                TABLE1.weights.as_ptr(),
                10,
                0.0,
                1.0,
                0,
                0.0,
                1.0,
                null_mut(),
            ),
            "out",
        );
        check(
            hystcomp_compensator_step(null_mut(), 0.5, &mut 0.0),
            "compensator handle",
        );
        check(
            hystcomp_compensator_process(null_mut(), [0.5].as_ptr(), [0.0].as_mut_ptr(), 1),
            "compensator handle",
        );
        check(hystcomp_compensator_reset(null_mut()), "compensator handle");
        check(
            hystcomp_compensator_limits(null(), &mut 0.0, &mut 0.0),
            "compensator handle",
        );
        check(
            hystcomp_compensator_diagnostics(null(), null_mut(), null_mut()),
            "compensator handle",
        );
        check(
            hystcomp_mpim_from_model_file(null(), &mut null_mut()),
            "path",
        );
        check(
            hystcomp_mpim_from_model_file(path.as_ptr(), null_mut()),
            "out",
        );
        check(
            hystcomp_mpim_from_parameters(null(), null(), 3, 0.0, 1.0, &mut null_mut()),
            "thresholds",
        );
        check(
            hystcomp_mpim_step(null_mut(), 0.5, &mut 0.0),
            "model handle",
        );
        check(
            hystcomp_mpim_process(null_mut(), null(), null_mut(), 4),
            "model handle",
        );
        check(hystcomp_mpim_reset(null_mut()), "model handle");
        check(
            hystcomp_mpim_check_invertible(null(), 0.0, 1.0, null_mut()),
            "model handle",
        );
    }
    assert!(out.is_null());

    let h = table1_ihc();
    // SAFETY: a live handle; the NULL out-pointers are what is tested.
    unsafe {
        assert_eq!(hystcomp_compensator_step(h, 0.5, null_mut()), NULL_POINTER);
        assert_eq!(last_error(), "v_out is NULL; pass a valid pointer");
        assert_eq!(
            hystcomp_compensator_process(h, null(), [0.0].as_mut_ptr(), 1),
            NULL_POINTER
        );
        assert_eq!(last_error(), "input array is NULL; pass a valid pointer");
        assert_eq!(
            hystcomp_compensator_process(h, [0.5].as_ptr(), null_mut(), 1),
            NULL_POINTER
        );
        assert_eq!(last_error(), "output array is NULL; pass a valid pointer");
        assert_eq!(
            hystcomp_compensator_limits(h, null_mut(), &mut 0.0),
            NULL_POINTER
        );
        assert_eq!(last_error(), "v_min is NULL; pass a valid pointer");
        // Diagnostics accepts NULL for counters that are not wanted.
        assert_eq!(
            hystcomp_compensator_diagnostics(h, null_mut(), null_mut()),
            OK
        );
        hystcomp_compensator_free(h);
        hystcomp_compensator_free(null_mut());
        hystcomp_mpim_free(null_mut());
    }
}

#[test]
fn each_null_pointer_message_names_its_argument() {
    let ihc = c"ihc";
    // SAFETY: NULL path on purpose; the rest valid.
    let status = unsafe {
        hystcomp_compensator_from_model_file(null(), ihc.as_ptr(), 0.0, 0.0, 0, &mut null_mut())
    };
    assert_eq!(
        (status, last_error().as_str()),
        (NULL_POINTER, "path is NULL; pass a valid pointer")
    );
    // SAFETY: NULL weights on purpose.
    let status = unsafe {
        hystcomp_mpim_from_parameters(
            TABLE1.thresholds.as_ptr(),
            null(),
            10,
            0.0,
            1.0,
            &mut null_mut(),
        )
    };
    assert_eq!(
        (status, last_error().as_str()),
        (NULL_POINTER, "weights is NULL; pass a valid pointer")
    );
}

#[test]
fn zero_operators_and_zero_length_signals() {
    let err = from_parameters(&[], &[], 0.0, 1.0, HystcompMethod::Ihc, (0.0, 1.0)).unwrap_err();
    assert_eq!(err.0, INVALID_ARGUMENT);
    assert!(err.1.contains("n = 0"), "{}", err.1);
    let mut model = null_mut();
    // SAFETY: zero-length arrays with dangling (non-NULL) pointers are never read.
    let status = unsafe {
        hystcomp_mpim_from_parameters(
            [0.0; 0].as_ptr(),
            [0.0; 0].as_ptr(),
            0,
            0.0,
            1.0,
            &mut model,
        )
    };
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(model.is_null());

    // An empty signal is nothing to do: OK, NULL arrays allowed, state untouched.
    let h = table1_ihc();
    assert_eq!(step(h, 0.6).0, OK);
    // SAFETY: a live handle; `len == 0` so the NULL arrays are never touched.
    assert_eq!(
        unsafe { hystcomp_compensator_process(h, null(), null_mut(), 0) },
        OK
    );
    let (mut saturated, mut non_finite) = (1, 1);
    // SAFETY: a live handle, valid out-pointers.
    unsafe { hystcomp_compensator_diagnostics(h, &mut saturated, &mut non_finite) };
    assert_eq!((saturated, non_finite), (0, 0));
    // SAFETY: a live handle, freed once.
    unsafe { hystcomp_compensator_free(h) };
}

/// Issue 13: every size C can pass is bounded before anything is allocated or read: at most
/// 10 000 operators (a model of 10^9 would allocate tens of GB).
#[test]
fn operator_counts_beyond_the_bound_are_refused_before_reading() {
    let n = 10_001;
    let thresholds: Vec<f64> = (0..n).map(|i| i as f64 / n as f64).collect();
    let weights = vec![1e-5; n];
    let err = from_parameters(
        &thresholds,
        &weights,
        0.0,
        1.0,
        HystcompMethod::Ihc,
        (0.0, 1.0),
    )
    .unwrap_err();
    assert_eq!(err.0, INVALID_ARGUMENT);
    assert!(
        err.1.contains("n = 10001") && err.1.contains("10000"),
        "{}",
        err.1
    );
    for n in [n, 1 << 40] {
        let mut model = null_mut();
        // SAFETY: for n = 10 001 the arrays hold n doubles; for 2^40 they do not, and the
        // function must refuse n before it reads them (what this checks).
        let status = unsafe {
            hystcomp_mpim_from_parameters(
                thresholds.as_ptr(),
                weights.as_ptr(),
                n,
                0.0,
                1.0,
                &mut model,
            )
        };
        assert_eq!(status, INVALID_ARGUMENT, "n = {n}");
        assert!(model.is_null());
        assert!(
            last_error().contains(&format!("n = {n}")),
            "{}",
            last_error()
        );
    }
}

#[test]
fn nan_and_invalid_parameters_are_refused_with_the_reason() {
    let r = TABLE1.thresholds;
    let b = TABLE1.weights;
    let ihc = HystcompMethod::Ihc;
    let mut nan_b = b;
    nan_b[3] = f64::NAN;
    let mut unsorted = r;
    unsorted.swap(4, 5);
    let mut negative = r;
    negative[0] = -0.1;
    let cases: [(Result<_, _>, &str); 8] = [
        (
            from_parameters(&r, &nan_b, TABLE1.a1, TABLE1.a2, ihc, (0.0, 1.0)),
            "weights[3] is NaN",
        ),
        (
            from_parameters(&r, &b, f64::NAN, TABLE1.a2, ihc, (0.0, 1.0)),
            "a1 is NaN",
        ),
        (
            from_parameters(&r, &b, TABLE1.a1, f64::INFINITY, ihc, (0.0, 1.0)),
            "a2 is NaN or infinite",
        ),
        (
            from_parameters(&unsorted, &b, TABLE1.a1, TABLE1.a2, ihc, (0.0, 1.0)),
            "r[5] is smaller than r[4]",
        ),
        (
            from_parameters(&negative, &b, TABLE1.a1, TABLE1.a2, ihc, (0.0, 1.0)),
            "r[0] = -0.1 is negative",
        ),
        (
            from_parameters(&r, &b, TABLE1.a1, TABLE1.a2, ihc, (f64::NAN, 1.0)),
            "output limits [NaN, 1]",
        ),
        (
            from_parameters(&r, &b, TABLE1.a1, TABLE1.a2, ihc, (1.0, 0.0)),
            "output limits [1, 0]",
        ),
        (
            // SAFETY (inside from_parameters): valid arrays; an out-of-range method number.
            {
                let mut out = null_mut();
                let status = unsafe {
                    hystcomp_compensator_from_parameters(
                        r.as_ptr(),
                        b.as_ptr(),
                        10,
                        0.0,
                        1.0,
                        9,
                        0.0,
                        1.0,
                        &mut out,
                    )
                };
                Err::<*mut HystcompCompensator, _>((status, last_error()))
            },
            "method 9 is not a HystcompMethod",
        ),
    ];
    for (result, expected) in cases {
        let (status, message) = result.expect_err(expected);
        assert_eq!(status, INVALID_ARGUMENT, "{message}");
        assert!(message.contains(expected), "{message:?} lacks {expected:?}");
    }
}

#[test]
fn non_invertible_models_are_refused_with_the_offending_slope() {
    let r = TABLE1.thresholds;
    // A strong negative cubic makes the plant fold over near x = 1.
    let err = from_parameters(
        &r,
        &TABLE1.weights,
        -2.0,
        TABLE1.a2,
        HystcompMethod::Ihc,
        (0.0, 1.0),
    )
    .unwrap_err();
    assert_eq!(err.0, NOT_INVERTIBLE);
    assert!(err.1.contains("not invertible"), "{}", err.1);
    // WIHC divides by a2.
    let err = from_parameters(
        &r,
        &TABLE1.weights,
        0.0,
        -0.5,
        HystcompMethod::Wihc,
        (0.0, 1.0),
    )
    .unwrap_err();
    assert_eq!(err.0, NOT_INVERTIBLE);
    assert!(err.1.contains("a2"), "{}", err.1);
    // DIHC with Table 2 negated is decreasing.
    let negated: Vec<f64> = TABLE2.weights.iter().map(|b| -b).collect();
    let err = from_parameters(
        &r,
        &negated,
        -TABLE2.a1,
        -TABLE2.a2,
        HystcompMethod::Dihc,
        (0.0, 1.0),
    )
    .unwrap_err();
    assert_eq!(err.0, NOT_INVERTIBLE, "{}", err.1);

    // The same check is offered on a forward model, with the slope written out.
    let mut model = null_mut();
    let mut slope = f64::NAN;
    // SAFETY: valid arrays and out-pointers.
    unsafe {
        assert_eq!(
            hystcomp_mpim_from_parameters(
                r.as_ptr(),
                TABLE1.weights.as_ptr(),
                10,
                -2.0,
                TABLE1.a2,
                &mut model
            ),
            OK
        );
        assert_eq!(
            hystcomp_mpim_check_invertible(model, 0.0, 1.0, &mut slope),
            NOT_INVERTIBLE
        );
        assert!(slope < 0.0, "{slope}");
        assert_eq!(
            hystcomp_mpim_check_invertible(model, 0.0, 0.2, &mut slope),
            OK
        );
        assert!(slope > 0.0, "{slope}");
        assert_eq!(
            hystcomp_mpim_check_invertible(model, 1.0, f64::NAN, &mut slope),
            INVALID_ARGUMENT
        );
        hystcomp_mpim_free(model);
    }
}

#[test]
fn missing_unreadable_and_invalid_files_are_refused_with_the_path() {
    let missing = CString::new("/nonexistent/model.json").unwrap();
    let (status, message) = from_file(&missing, "ihc", None).unwrap_err();
    assert_eq!(status, IO);
    assert!(
        message.contains("/nonexistent/model.json") && message.contains("No such file"),
        "{message}"
    );

    let directory = CString::new(env!("CARGO_MANIFEST_DIR")).unwrap();
    let (status, message) = from_file(&directory, "ihc", None).unwrap_err();
    assert_eq!(status, IO);
    assert!(
        message.contains(env!("CARGO_MANIFEST_DIR")) && message.contains("is a directory"),
        "{message}"
    );
    // The forward model refuses it alike.
    let mut model = null_mut();
    // SAFETY: a valid string and out-pointer.
    assert_eq!(
        unsafe { hystcomp_mpim_from_model_file(directory.as_ptr(), &mut model) },
        IO
    );
    assert!(model.is_null());
    // SAFETY: the message is a NUL-terminated string owned by the library.
    let message = unsafe { CStr::from_ptr(hystcomp_last_error_message()) }
        .to_string_lossy()
        .into_owned();
    assert!(message.contains("is a directory"), "{message}");

    let dir = tempfile::tempdir().unwrap();
    let garbage = dir.path().join("garbage.json");
    std::fs::write(&garbage, "{ not json").unwrap();
    let garbage = CString::new(garbage.to_str().unwrap()).unwrap();
    let (status, message) = from_file(&garbage, "ihc", None).unwrap_err();
    assert_eq!(status, INVALID_MODEL_FILE);
    assert!(
        message.contains("not a valid hystcomp model file"),
        "{message}"
    );
    let mut model = null_mut();
    // SAFETY: a valid string and out-pointer.
    assert_eq!(
        unsafe { hystcomp_mpim_from_model_file(garbage.as_ptr(), &mut model) },
        INVALID_MODEL_FILE
    );
    assert!(model.is_null());

    let (status, message) = from_file(&model_path("table2-inverse.json"), "ihc", None).unwrap_err();
    assert_eq!(status, WRONG_DIRECTION);
    assert!(message.contains("ihc needs a plant model"), "{message}");
    let (status, message) = from_file(&model_path("table1-plant.json"), "pid", None).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(message.contains("unknown method \"pid\""), "{message}");
    let (status, message) = from_file(
        &model_path("table1-plant.json"),
        "ihc",
        Some((f64::NAN, 10.0)),
    )
    .unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(message.contains("output limits [NaN, 10] V"), "{message}");
    // Invertibility is checked over the limits asked for: far beyond the identified range the
    // cubic term of Table 1 folds the model over.
    let (status, message) =
        from_file(&model_path("table1-plant.json"), "ihc", Some((0.0, 30.0))).unwrap_err();
    assert_eq!(status, NOT_INVERTIBLE, "{message}");
}

#[test]
fn non_finite_samples_hold_the_output_and_are_reported() {
    let h = table1_ihc();
    let (status, held) = step(h, 0.5);
    assert_eq!(status, OK);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let (status, v) = step(h, bad);
        assert_eq!(status, NON_FINITE_INPUT);
        assert_eq!(v, held, "the previous output is held");
        assert!(last_error().contains("NaN or infinite"));
    }
    let desired = [0.4, f64::NAN, 0.6, f64::NAN];
    let mut control = [f64::NAN; 4];
    // SAFETY: a live handle, arrays of 4.
    let status =
        unsafe { hystcomp_compensator_process(h, desired.as_ptr(), control.as_mut_ptr(), 4) };
    assert_eq!(status, NON_FINITE_INPUT);
    assert_eq!(
        last_error().split(" (").next(),
        Some("2 desired position sample(s) were NaN or infinite, or too large to use")
    );
    assert!(last_error().contains("the first at index 1"));
    assert_eq!(control[1], control[0]);
    assert_eq!(control[3], control[2]);
    assert!(control.iter().all(|v| (0.0..=1.0).contains(v)));
    // SAFETY: a live handle, freed once.
    unsafe { hystcomp_compensator_free(h) };

    let mut model = null_mut();
    let mut y = 0.0;
    // SAFETY: valid arrays and out-pointers.
    unsafe {
        hystcomp_mpim_from_parameters(
            TABLE1.thresholds.as_ptr(),
            TABLE1.weights.as_ptr(),
            10,
            TABLE1.a1,
            TABLE1.a2,
            &mut model,
        );
        assert_eq!(
            hystcomp_mpim_step(model, f64::NAN, &mut y),
            NON_FINITE_INPUT
        );
        assert!(y.is_nan());
        hystcomp_mpim_free(model);
    }
}

#[test]
fn process_matches_step_and_works_in_place() {
    let desired: Vec<f64> = (0..500)
        .map(|k| 0.45 + 0.4 * (k as f64 * 0.03).sin())
        .collect();
    let a = table1_ihc();
    let b = table1_ihc();
    let stepped: Vec<f64> = desired.iter().map(|&y| step(a, y).1).collect();
    let mut in_place = desired.clone();
    // SAFETY: a live handle; the same array as input and output is allowed.
    let status = unsafe {
        hystcomp_compensator_process(b, in_place.as_ptr(), in_place.as_mut_ptr(), in_place.len())
    };
    assert_eq!(status, OK);
    assert_eq!(stepped, in_place);

    // Reset gives the same outputs again.
    // SAFETY: live handles, freed once.
    unsafe {
        assert_eq!(hystcomp_compensator_reset(a), OK);
        let again: Vec<f64> = desired.iter().map(|&y| step(a, y).1).collect();
        assert_eq!(again, stepped);
        let (mut lo, mut hi) = (f64::NAN, f64::NAN);
        assert_eq!(hystcomp_compensator_limits(a, &mut lo, &mut hi), OK);
        assert_eq!((lo, hi), (0.0, 1.0));
        hystcomp_compensator_free(a);
        hystcomp_compensator_free(b);
    }
}

#[test]
fn forward_model_handles_give_the_round_trip_in_both_units() {
    // Normalised: IHC from parameters against the Table 1 model from parameters.
    let ihc = table1_ihc();
    let mut plant = null_mut();
    // SAFETY: valid arrays and out-pointer.
    unsafe {
        assert_eq!(
            hystcomp_mpim_from_parameters(
                TABLE1.thresholds.as_ptr(),
                TABLE1.weights.as_ptr(),
                10,
                TABLE1.a1,
                TABLE1.a2,
                &mut plant
            ),
            OK
        );
    }
    for k in 0..3000 {
        let y_d = 0.45 + 0.4 * (k as f64 * 0.005).sin() * (k as f64 * 0.0007).cos();
        let (_, v) = step(ihc, y_d);
        let mut y = f64::NAN;
        // SAFETY: a live handle and out-pointer.
        assert_eq!(unsafe { hystcomp_mpim_step(plant, v, &mut y) }, OK);
        assert!((y - y_d).abs() < 1e-12, "sample {k}: {y} != {y_d}");
    }
    // SAFETY: live handles, freed once.
    unsafe {
        hystcomp_compensator_free(ihc);
        hystcomp_mpim_free(plant);
    }

    // Physical: DIHC from Table 2's file; its forward model is the same map (um -> V).
    let dihc = from_file(&model_path("table2-inverse.json"), "dihc", None).unwrap();
    let mut inverse = null_mut();
    let path = model_path("table2-inverse.json");
    // SAFETY: a valid string and out-pointer.
    assert_eq!(
        unsafe { hystcomp_mpim_from_model_file(path.as_ptr(), &mut inverse) },
        OK
    );
    let desired: Vec<f64> = (0..1000)
        .map(|k| 37.5 + 30.0 * (k as f64 * 0.01).sin())
        .collect();
    let mut from_model = vec![0.0; desired.len()];
    let mut from_dihc = vec![0.0; desired.len()];
    // SAFETY: live handles, arrays of equal length.
    unsafe {
        assert_eq!(
            hystcomp_mpim_process(
                inverse,
                desired.as_ptr(),
                from_model.as_mut_ptr(),
                desired.len()
            ),
            OK
        );
        assert_eq!(
            hystcomp_compensator_process(
                dihc,
                desired.as_ptr(),
                from_dihc.as_mut_ptr(),
                desired.len()
            ),
            OK
        );
        hystcomp_compensator_free(dihc);
        hystcomp_mpim_free(inverse);
    }
    for (a, b) in from_model.iter().zip(&from_dihc) {
        assert!((a.clamp(0.0, 10.0) - b).abs() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn status_names_and_version_are_static_strings() {
    // SAFETY: static NUL-terminated strings.
    let name = |s| {
        unsafe { CStr::from_ptr(hystcomp_status_name(s)) }
            .to_str()
            .unwrap()
    };
    assert_eq!(name(OK), "ok");
    assert_eq!(name(NOT_INVERTIBLE), "model not invertible");
    assert_eq!(name(HystcompStatus::Internal as c_int), "internal error");
    assert_eq!(name(-1), "unknown status");
    assert_eq!(name(99), "unknown status");
    // SAFETY: a static NUL-terminated string.
    let version = unsafe { CStr::from_ptr(hystcomp_version()) }
        .to_str()
        .unwrap();
    assert_eq!(version, env!("CARGO_PKG_VERSION"));
}

#[test]
fn the_last_error_is_per_thread() {
    // SAFETY: NULL handle on purpose.
    assert_eq!(
        unsafe { hystcomp_compensator_reset(null_mut()) },
        NULL_POINTER
    );
    let here = last_error();
    let there = std::thread::spawn(|| {
        let fresh = last_error();
        // SAFETY: NULL handle on purpose.
        unsafe { hystcomp_mpim_reset(null_mut()) };
        (fresh, last_error())
    })
    .join()
    .unwrap();
    assert_eq!(there.0, "", "a new thread starts without a message");
    assert_eq!(there.1, "model handle is NULL; pass a valid pointer");
    assert_eq!(
        last_error(),
        here,
        "another thread's failure does not touch this one's"
    );
}

#[test]
fn delayed_wihc_reports_its_loop_gain_and_counts_its_ringing_apart() {
    let path = model_path("table1-plant.json");
    // Table 1's delayed WIHC can ring (loop gain 1.66): refused unless allowed explicitly.
    let (status, message) = from_file(&path, "wihc-delayed", None).unwrap_err();
    assert_eq!(status, UNSTABLE_DELAY, "{message}");
    assert!(
        message.contains("delayed WIHC can oscillate") && message.contains("1.659"),
        "{message}"
    );
    let (status, message) = from_file_with(&path, "wihc-delayed", None, Some(4)).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT, "{message}");
    let delayed = from_file_with(
        &path,
        "wihc-delayed",
        None,
        Some(HYSTCOMP_ALLOW_UNSTABLE_DELAY),
    )
    .unwrap();
    let exact = from_file(&path, "wihc", None).unwrap();
    let ihc = from_file(&path, "ihc", None).unwrap();
    let dihc = from_file(&model_path("table2-inverse.json"), "dihc", None).unwrap();
    // (b_1 + ... + b_10) / a2 of Table 1: all ten operators moving near 0 V.
    let expected = TABLE1.weights.iter().sum::<f64>() / TABLE1.a2;
    for h in [delayed, exact] {
        let mut gain = f64::NAN;
        // SAFETY: a live handle and a valid out-pointer.
        assert_eq!(
            unsafe { hystcomp_compensator_delayed_loop_gain(h, &mut gain) },
            OK
        );
        assert!((gain - expected).abs() < 1e-12 && gain > 1.0, "{gain}");
    }
    // IHC's delayed loop: |3 a1 x^2| / (a2 + b_1) at x = 1, 0.68 for Table 1.
    let mut gain = 0.0;
    // SAFETY: a live handle and a valid out-pointer.
    assert_eq!(
        unsafe { hystcomp_compensator_delayed_loop_gain(ihc, &mut gain) },
        OK
    );
    let expected = 3.0 * TABLE1.a1.abs() / (TABLE1.a2 + TABLE1.weights[0]);
    assert!((gain - expected).abs() < 1e-12, "{gain} vs {expected}");
    // SAFETY: a live handle and a valid out-pointer.
    assert_eq!(
        unsafe { hystcomp_compensator_delayed_loop_gain(dihc, &mut gain) },
        INVALID_ARGUMENT
    );
    assert!(
        last_error().contains("dihc has no delayed loop"),
        "{}",
        last_error()
    );
    // 35 + 20 sin(2 pi t) um from rest at 10 kHz: reachable, but the delayed loop rings.
    for k in 0..10_000 {
        let y_d = 35.0 + 20.0 * (2.0 * std::f64::consts::PI * k as f64 * 1e-4).sin();
        for h in [delayed, exact] {
            let (status, v) = step(h, y_d);
            assert_eq!(status, OK);
            assert!((0.0..=10.0).contains(&v));
        }
    }
    let counts = |h| {
        let (mut saturated, mut non_finite, mut looped) = (9, 9, 9);
        // SAFETY: a live handle and valid out-pointers.
        unsafe {
            assert_eq!(
                hystcomp_compensator_diagnostics(h, &mut saturated, &mut non_finite),
                OK
            );
            assert_eq!(hystcomp_compensator_loop_saturated(h, &mut looped), OK);
        }
        (saturated, looped, non_finite)
    };
    let (saturated, looped, non_finite) = counts(delayed);
    assert_eq!((saturated, non_finite), (0, 0));
    assert!(looped > 10, "{looped}");
    assert_eq!(counts(exact), (0, 0, 0));
    // NULL handle and NULL out-pointers are refused with the argument's name.
    // SAFETY: NULL is accepted and refused.
    unsafe {
        assert_eq!(
            hystcomp_compensator_loop_saturated(null(), &mut 0),
            NULL_POINTER
        );
        assert_eq!(
            hystcomp_compensator_loop_saturated(delayed, null_mut()),
            NULL_POINTER
        );
        assert!(last_error().contains("loop_saturated is NULL"));
        assert_eq!(
            hystcomp_compensator_delayed_loop_gain(delayed, null_mut()),
            NULL_POINTER
        );
        assert!(last_error().contains("gain is NULL"));
    }
    for h in [delayed, exact, ihc, dihc] {
        // SAFETY: live handles, freed once.
        unsafe { hystcomp_compensator_free(h) };
    }
}
