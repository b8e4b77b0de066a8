//! Models in memory across the C boundary, called from Rust as C calls them: a model file taken
//! apart into values and rebuilt bit for bit, saved and loaded, turned into compensators and
//! forward models; the one-shot compensation equal to a compensator run sample by sample; and
//! every NULL, NaN, empty or mismatched argument refused with its status and a message.

use std::ffi::{CStr, CString, c_char, c_int};
use std::ptr::{null, null_mut};

mod common;

use common::*;
use hystcomp::*;
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::{CreepPart, ModelFile, VibrationPart};
use proptest::prelude::*;

/// Turns a status into a result with the message.
fn check(status: c_int) -> Result<(), (c_int, String)> {
    if status == OK {
        Ok(())
    } else {
        Err((status, last_error()))
    }
}

fn load(path: &CStr) -> Result<*mut HystcompModel, (c_int, String)> {
    let mut out = std::ptr::dangling_mut::<HystcompModel>();
    // SAFETY: a valid string and out-pointer.
    let result = check(unsafe { hystcomp_model_load(path.as_ptr(), &mut out) });
    match result {
        Ok(()) => Ok(out),
        Err(e) => {
            assert!(out.is_null(), "a failed constructor leaves NULL in *out");
            Err(e)
        }
    }
}

fn from_values(values: &HystcompModelValues) -> Result<*mut HystcompModel, (c_int, String)> {
    let mut out = std::ptr::dangling_mut::<HystcompModel>();
    // SAFETY: valid values (the test's) and out-pointer.
    let result = check(unsafe { hystcomp_model_from_values(values, &mut out) });
    result.map(|()| out).inspect_err(|_| assert!(out.is_null()))
}

fn values_of(m: *const HystcompModel) -> HystcompModelValues {
    // SAFETY: a zeroed struct of pointers and numbers is a valid value to overwrite.
    let mut values: HystcompModelValues = unsafe { std::mem::zeroed() };
    // SAFETY: a live handle and a valid out-pointer.
    check(unsafe { hystcomp_model_values(m, &mut values) }).expect("values of a live model");
    values
}

fn text(ptr: *const c_char) -> Option<String> {
    // SAFETY: NULL or a NUL-terminated string owned by a live model.
    (!ptr.is_null()).then(|| unsafe { CStr::from_ptr(ptr) }.to_str().unwrap().to_owned())
}

/// The model file a handle holds, rebuilt from its values as a C caller would see them.
fn file_of(m: *const HystcompModel) -> ModelFile {
    let v = values_of(m);
    // SAFETY: the arrays point into the live model, `operators` long.
    let (thresholds, weights) = unsafe {
        (
            std::slice::from_raw_parts(v.thresholds, v.operators).to_vec(),
            std::slice::from_raw_parts(v.weights, v.operators).to_vec(),
        )
    };
    let scale = |s: &HystcompScale| hystcomp_io::model_file::Scale {
        quantity: text(s.quantity).unwrap(),
        unit: text(s.unit).unwrap(),
        offset: s.offset,
        scale: s.scale,
    };
    let mut file = ModelFile::new(
        if v.direction == HystcompDirection::Plant as c_int {
            hystcomp_io::model_file::Direction::Plant
        } else {
            hystcomp_io::model_file::Direction::Inverse
        },
        scale(&v.input),
        scale(&v.output),
        [v.input_range_min, v.input_range_max],
        thresholds,
        weights,
        v.a1,
        v.a2,
    )
    .unwrap();
    file.description = text(v.description);
    file.identification = text(v.identification_json).map(|t| serde_json::from_str(&t).unwrap());
    // SAFETY (the links): the arrays point into the live model, of their stated lengths.
    if v.creep_elements > 0 {
        file.creep = Some(CreepPart {
            origin: v.creep_origin,
            time_constants_s: unsafe {
                std::slice::from_raw_parts(v.creep_time_constants_s, v.creep_elements)
            }
            .to_vec(),
            weights: unsafe { std::slice::from_raw_parts(v.creep_weights, v.creep_elements) }
                .to_vec(),
        });
    }
    if v.vibration_numerator_len > 0 {
        file.vibration = Some(VibrationPart {
            delay_samples: v.vibration_delay_samples,
            numerator: unsafe {
                std::slice::from_raw_parts(v.vibration_numerator, v.vibration_numerator_len)
            }
            .to_vec(),
            denominator: unsafe {
                std::slice::from_raw_parts(v.vibration_denominator, v.vibration_denominator_len)
            }
            .to_vec(),
        });
    }
    file.sample_rate_hz = (v.sample_rate_hz != 0.0).then_some(v.sample_rate_hz);
    file
}

/// `file` as this build writes it (format version 2: a version-1 file differs only by that).
fn current(mut file: ModelFile) -> ModelFile {
    file.format_version = hystcomp_io::model_file::FORMAT_VERSION;
    file
}

/// Table 1 with creep and vibration links (format version 2): creep of 1.5 % over two time
/// constants, a first-order vibration link of unit static gain, two samples of delay.
fn chained_file() -> ModelFile {
    let mut file = ModelFile::load(std::path::Path::new(
        model_path("table1-plant.json").to_str().unwrap(),
    ))
    .unwrap();
    file.format_version = hystcomp_io::model_file::FORMAT_VERSION;
    file.sample_rate_hz = Some(10_000.0);
    file.creep = Some(CreepPart {
        origin: 0.0,
        time_constants_s: vec![0.01, 0.1],
        weights: vec![0.01, 0.005],
    });
    file.vibration = Some(VibrationPart {
        delay_samples: 2,
        numerator: vec![0.3],
        denominator: vec![1.0, -0.7],
    });
    file.validate().expect("a valid chained model");
    file
}

fn free(m: *mut HystcompModel) {
    // SAFETY: a live handle (or NULL), freed once.
    unsafe { hystcomp_model_free(m) };
}

fn table1() -> *mut HystcompModel {
    load(&model_path("table1-plant.json")).expect("Table 1 loads")
}

#[test]
fn a_loaded_model_gives_the_files_values_and_rebuilds_bit_for_bit() {
    for name in ["table1-plant.json", "table2-inverse.json"] {
        let path = model_path(name);
        let reference = ModelFile::load(std::path::Path::new(path.to_str().unwrap())).unwrap();
        let reference = current(reference);
        let m = load(&path).unwrap();
        assert_eq!(file_of(m), reference, "{name}");
        // Built again from its own values: the same model, another handle.
        let again = from_values(&values_of(m)).unwrap();
        assert_ne!(again, m);
        assert_eq!(file_of(again), reference, "{name}");
        free(m);
        // The copy does not depend on the first handle.
        assert_eq!(file_of(again), reference, "{name}");
        free(again);
    }
}

#[test]
fn save_then_load_keeps_everything_and_the_identification() {
    let dir = tempfile::tempdir().unwrap();
    let m = table1();
    let mut values = values_of(m);
    let report = c"{\"solver\":\"ls\",\"fit\":{\"rms\":0.125},\"nested\":[1,2.5,null]}";
    values.identification_json = report.as_ptr();
    let with_report = from_values(&values).unwrap();
    let path = CString::new(dir.path().join("saved.json").to_str().unwrap()).unwrap();
    // SAFETY: a live handle and a valid path.
    check(unsafe { hystcomp_model_save(with_report, path.as_ptr()) }).unwrap();
    let loaded = load(&path).unwrap();
    assert_eq!(file_of(loaded), file_of(with_report));
    let json = text(values_of(loaded).identification_json).unwrap();
    assert_eq!(
        serde_json::from_str::<serde_json::Value>(&json).unwrap(),
        serde_json::from_str::<serde_json::Value>(report.to_str().unwrap()).unwrap()
    );
    // An empty identification is none.
    values.identification_json = c"  ".as_ptr();
    let without = from_values(&values).unwrap();
    assert!(values_of(without).identification_json.is_null());
    // Saving into a directory that does not exist: IO, the path named, nothing left behind.
    let missing = CString::new(dir.path().join("no/such/dir/m.json").to_str().unwrap()).unwrap();
    // SAFETY: a live handle and a valid path.
    let (status, message) = check(unsafe { hystcomp_model_save(m, missing.as_ptr()) }).unwrap_err();
    assert_eq!(status, IO, "{message}");
    assert!(message.contains("no/such/dir"), "{message}");
    for handle in [m, with_report, loaded, without] {
        free(handle);
    }
}

#[test]
fn load_refuses_missing_and_invalid_files_with_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let missing = CString::new(dir.path().join("absent.json").to_str().unwrap()).unwrap();
    let (status, message) = load(&missing).unwrap_err();
    assert_eq!(status, IO);
    assert!(message.contains("absent.json"), "{message}");
    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, "{\"format_version\": 1, \"a1\": ").unwrap();
    let (status, message) = load(&CString::new(broken.to_str().unwrap()).unwrap()).unwrap_err();
    assert_eq!(status, INVALID_MODEL_FILE);
    assert!(message.contains("broken.json"), "{message}");
    // SAFETY: the NULL pointers are the test.
    unsafe {
        let mut out = null_mut();
        assert_eq!(hystcomp_model_load(null(), &mut out), NULL_POINTER);
        assert_eq!(last_error(), "path is NULL; pass a valid pointer");
        assert_eq!(
            hystcomp_model_load(missing.as_ptr(), null_mut()),
            NULL_POINTER
        );
        assert_eq!(hystcomp_model_save(null(), missing.as_ptr()), NULL_POINTER);
        assert_eq!(last_error(), "model handle is NULL; pass a valid pointer");
        let m = table1();
        assert_eq!(hystcomp_model_save(m, null()), NULL_POINTER);
        assert_eq!(hystcomp_model_values(m, null_mut()), NULL_POINTER);
        assert_eq!(last_error(), "values is NULL; pass a valid pointer");
        let mut values = values_of(m);
        assert_eq!(hystcomp_model_values(null(), &mut values), NULL_POINTER);
        assert_eq!(hystcomp_model_from_values(null(), &mut out), NULL_POINTER);
        assert_eq!(
            hystcomp_model_from_values(&values, null_mut()),
            NULL_POINTER
        );
        hystcomp_model_free(null_mut());
        free(m);
    }
}

#[test]
fn from_values_refuses_each_bad_value_with_its_name() {
    let m = table1();
    let good = values_of(m);
    let unsorted = [0.0, 0.5, 0.3];
    let weights = [0.1, 0.1, 0.1];
    type Edit = Box<dyn Fn(&mut HystcompModelValues)>;
    let cases: Vec<(Edit, c_int, &str)> = vec![
        (
            Box::new(|v| v.direction = 2),
            INVALID_ARGUMENT,
            "direction 2",
        ),
        (
            Box::new(|v| v.input.scale = 0.0),
            INVALID_ARGUMENT,
            "input.scale",
        ),
        (
            Box::new(|v| v.output.offset = f64::NAN),
            INVALID_ARGUMENT,
            "output.offset",
        ),
        (
            Box::new(|v| v.input.unit = c" ".as_ptr()),
            INVALID_ARGUMENT,
            "input.unit",
        ),
        (
            Box::new(|v| v.output.unit = null()),
            NULL_POINTER,
            "output.unit",
        ),
        (
            Box::new(|v| v.input.quantity = null()),
            NULL_POINTER,
            "input.quantity",
        ),
        (
            Box::new(|v| v.input_range_max = v.input_range_min),
            INVALID_ARGUMENT,
            "input_range",
        ),
        (Box::new(|v| v.operators = 0), INVALID_ARGUMENT, "n = 0"),
        (
            Box::new(|v| v.thresholds = null()),
            NULL_POINTER,
            "thresholds",
        ),
        (Box::new(|v| v.weights = null()), NULL_POINTER, "weights"),
        (
            Box::new(|v| v.a2 = f64::INFINITY),
            INVALID_ARGUMENT,
            "refused",
        ),
        (
            Box::new(move |v| {
                v.thresholds = unsorted.as_ptr();
                v.weights = weights.as_ptr();
                v.operators = 3;
            }),
            INVALID_ARGUMENT,
            "refused",
        ),
        (
            Box::new(|v| v.identification_json = c"{not json".as_ptr()),
            INVALID_ARGUMENT,
            "identification_json is not valid JSON",
        ),
        (
            Box::new(|v| v.description = c"\xff\xfe".as_ptr()),
            INVALID_ARGUMENT,
            "description is not valid UTF-8",
        ),
    ];
    for (edit, status, needle) in cases {
        let mut values = good;
        edit(&mut values);
        let (found, message) = from_values(&values).unwrap_err();
        assert_eq!(found, status, "{needle}: {message}");
        assert!(message.contains(needle), "{needle}: {message}");
    }
    free(m);
}

/// The one-shot compensation of `y_d`, its status and diagnostics.
fn compensate(
    m: *const HystcompModel,
    method: &CStr,
    limits: Option<(f64, f64)>,
    y_d: &[f64],
) -> (c_int, Vec<f64>, HystcompDiagnostics) {
    let mut v = vec![f64::NAN; y_d.len()];
    let mut d = HystcompDiagnostics {
        saturated: u64::MAX,
        loop_saturated: u64::MAX,
        non_finite: u64::MAX,
        v_min: f64::NAN,
        v_max: f64::NAN,
    };
    let (lo, hi) = limits.unwrap_or((0.0, 0.0));
    // SAFETY: a live handle, a valid string and arrays of the stated lengths.
    let status = unsafe {
        hystcomp_compensate(
            m,
            method.as_ptr(),
            lo,
            hi,
            c_int::from(limits.is_some()),
            y_d.as_ptr(),
            y_d.len(),
            v.as_mut_ptr(),
            v.len(),
            &mut d,
        )
    };
    (status, v, d)
}

fn trajectory(seed: u64, len: usize) -> Vec<f64> {
    // A smooth random multisine around mid-stroke with occasional excursions beyond the stroke.
    let phase = (seed % 1000) as f64 * 0.001;
    (0..len)
        .map(|k| {
            let t = k as f64 * 1e-3;
            37.5 + 30.0 * (6.3 * t + phase).sin() + 12.0 * (17.0 * t + 3.0 * phase).sin()
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// One-shot compensation equals the library's compensator run sample by sample, and the
    /// compensator made from the model in memory equals the one made from the file.
    #[test]
    fn one_shot_equals_the_compensator_sample_by_sample(
        seed in 0u64..1_000_000,
        len in 1usize..3000,
        method_index in 0usize..5,
        limits in prop::option::of((0.0f64..3.0, 7.0f64..10.0)),
    ) {
        // Table 1's plain delayed WIHC can ring and is refused (see below); its guarded loop
        // and the others run.
        let methods = [c"ihc", c"ihc-delayed", c"wihc", c"wihc-guarded", c"ihc-guarded"];
        let method = methods[method_index];
        let path = model_path("table1-plant.json");
        let m = table1();
        let y_d = trajectory(seed, len);
        let (status, v, d) = compensate(m, method, limits, &y_d);
        prop_assert_eq!(status, OK, "{}", last_error());
        let file = ModelFile::load(std::path::Path::new(path.to_str().unwrap())).unwrap();
        let parsed: Method = method.to_str().unwrap().parse().unwrap();
        let mut reference = ScaledCompensator::new(&file, parsed, limits).unwrap();
        let expected: Vec<f64> = y_d.iter().map(|&x| reference.step(x)).collect();
        prop_assert_eq!(&v, &expected);
        let r = reference.diagnostics();
        prop_assert_eq!((d.saturated, d.loop_saturated, d.non_finite), (r.saturated, r.loop_saturated, 0));
        prop_assert_eq!((d.v_min, d.v_max), reference.limits());
        // The handle from the model in memory, and from the file, give the same signal.
        let mut from_model = null_mut();
        let mut from_file = null_mut();
        let (lo, hi) = limits.unwrap_or((0.0, 0.0));
        let use_limits = c_int::from(limits.is_some());
        // SAFETY: live handles, valid strings and arrays of the stated lengths.
        unsafe {
            prop_assert_eq!(hystcomp_compensator_from_model(m, method.as_ptr(), lo, hi, use_limits, &mut from_model), OK);
            prop_assert_eq!(hystcomp_compensator_from_model_file(path.as_ptr(), method.as_ptr(), lo, hi, use_limits, &mut from_file), OK);
            let mut a = vec![0.0; len];
            let mut b = vec![0.0; len];
            prop_assert_eq!(hystcomp_compensator_process(from_model, y_d.as_ptr(), a.as_mut_ptr(), len), OK);
            prop_assert_eq!(hystcomp_compensator_process(from_file, y_d.as_ptr(), b.as_mut_ptr(), len), OK);
            prop_assert_eq!(&a, &expected);
            prop_assert_eq!(&b, &expected);
            hystcomp_compensator_free(from_model);
            hystcomp_compensator_free(from_file);
        }
        free(m);
    }
}

/// Table 1's delayed WIHC (loop gain 1.66: it can ring) is refused by every constructor with
/// `HYSTCOMP_STATUS_UNSTABLE_DELAY` and the gain in the message.
#[test]
fn a_delayed_loop_that_can_ring_is_refused_from_memory_too() {
    let m = table1();
    let y_d = trajectory(3, 100);
    let (status, _, _) = compensate(m, c"wihc-delayed", None, &y_d);
    assert_eq!(status, HystcompStatus::UnstableDelay as c_int);
    assert!(last_error().contains("1.659"), "{}", last_error());
    let mut out = std::ptr::dangling_mut();
    // SAFETY: a live handle, a valid string and out-pointer.
    let status = unsafe {
        hystcomp_compensator_from_model(m, c"wihc-delayed".as_ptr(), 0.0, 0.0, 0, &mut out)
    };
    assert_eq!(status, HystcompStatus::UnstableDelay as c_int);
    assert!(out.is_null());
    // The explicit override builds it; the drive still stays within the limits. Unknown
    // flags are refused.
    // SAFETY: a live handle, a valid string and out-pointer.
    let status = unsafe {
        hystcomp_compensator_from_model_with(
            m,
            c"wihc-delayed".as_ptr(),
            0.0,
            0.0,
            0,
            HYSTCOMP_ALLOW_UNSTABLE_DELAY,
            &mut out,
        )
    };
    assert_eq!(status, OK, "{}", last_error());
    assert!(!out.is_null());
    let mut v = vec![0.0; y_d.len()];
    // SAFETY: a live handle and arrays of the stated length.
    check(unsafe { hystcomp_compensator_process(out, y_d.as_ptr(), v.as_mut_ptr(), v.len()) })
        .unwrap();
    assert!(v.iter().all(|v| (0.0..=10.0).contains(v)), "{v:?}");
    // SAFETY: a live handle, freed once.
    unsafe { hystcomp_compensator_free(out) };
    let mut refused = std::ptr::dangling_mut();
    // SAFETY: a live handle, a valid string and out-pointer.
    let status = unsafe {
        hystcomp_compensator_from_model_with(
            m,
            c"wihc-delayed".as_ptr(),
            0.0,
            0.0,
            0,
            2,
            &mut refused,
        )
    };
    assert_eq!(status, HystcompStatus::InvalidArgument as c_int);
    assert!(refused.is_null());
    assert!(last_error().contains("flags"), "{}", last_error());
    free(m);
}

#[test]
fn the_forward_model_of_a_model_in_memory_closes_the_round_trip() {
    for (method, name) in [(c"ihc", "ihc"), (c"wihc", "wihc")] {
        let m = table1();
        // Within the stroke (0 .. 75 um): 10 .. 65 um.
        let y_d: Vec<f64> = trajectory(7, 5000)
            .iter()
            .map(|y| 37.5 + 0.65 * (y - 37.5))
            .collect();
        let (status, v, d) = compensate(m, method, None, &y_d);
        assert_eq!(status, OK, "{name}: {}", last_error());
        assert_eq!(
            d.saturated, 0,
            "{name}: the trajectory stays within the stroke"
        );
        let mut plant = null_mut();
        // SAFETY: a live handle and a valid out-pointer.
        check(unsafe { hystcomp_mpim_from_model(m, &mut plant) }).unwrap();
        free(m); // the forward model does not depend on the model handle
        let mut y = vec![0.0; v.len()];
        // SAFETY: a live handle and arrays of the stated length.
        check(unsafe { hystcomp_mpim_process(plant, v.as_ptr(), y.as_mut_ptr(), v.len()) })
            .unwrap();
        let worst = y
            .iter()
            .zip(&y_d)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{name}: P[C[y_d]] - y_d up to {worst} um");
        // SAFETY: a live handle, freed once.
        unsafe { hystcomp_mpim_free(plant) };
    }
    let mut out = std::ptr::dangling_mut::<HystcompMpim>();
    // SAFETY: the NULL model is the test.
    assert_eq!(
        unsafe { hystcomp_mpim_from_model(null(), &mut out) },
        NULL_POINTER
    );
    assert!(out.is_null());
}

#[test]
fn one_shot_compensation_refuses_bad_arguments_and_reports_nan() {
    let m = table1();
    let inverse = load(&model_path("table2-inverse.json")).unwrap();
    let y_d = trajectory(3, 100);
    let (status, message) = {
        let (s, _, _) = compensate(inverse, c"ihc", None, &y_d);
        (s, last_error())
    };
    assert_eq!(status, WRONG_DIRECTION, "{message}");
    let (status, _, _) = compensate(m, c"dihc", None, &y_d);
    assert_eq!(status, WRONG_DIRECTION);
    let (status, _, _) = compensate(m, c"best", None, &y_d);
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(last_error().contains("best"), "{}", last_error());
    let (status, _, _) = compensate(m, c"ihc", Some((5.0, 5.0)), &y_d);
    assert_eq!(status, INVALID_ARGUMENT);
    // Limits far beyond the identified range: Table 1's model bends back there.
    let (status, _, _) = compensate(m, c"ihc", Some((-40.0, 40.0)), &y_d);
    assert_eq!(status, NOT_INVERTIBLE, "{}", last_error());
    // NaN: the whole signal is processed, the previous output held, the count reported.
    let mut with_nan = y_d.clone();
    with_nan[10] = f64::NAN;
    with_nan[50] = f64::NEG_INFINITY;
    let (status, v, d) = compensate(m, c"ihc", None, &with_nan);
    assert_eq!(status, NON_FINITE_INPUT);
    assert!(
        last_error().contains("2 desired position sample(s)"),
        "{}",
        last_error()
    );
    assert!(last_error().contains("index 10"), "{}", last_error());
    assert_eq!(d.non_finite, 2);
    assert_eq!(v[10], v[9]);
    assert_eq!(v[50], v[49]);
    assert!(v.iter().all(|x| (0.0..=10.0).contains(x)));
    // Lengths, emptiness, NULL pointers.
    let mut out = vec![0.0; 99];
    // SAFETY: arrays of the stated lengths; the NULL pointers and the mismatch are the test.
    unsafe {
        let ihc = c"ihc".as_ptr();
        let call = |m, method, y: *const f64, ny, v: *mut f64, nv| {
            hystcomp_compensate(m, method, 0.0, 0.0, 0, y, ny, v, nv, null_mut())
        };
        assert_eq!(
            call(m, ihc, y_d.as_ptr(), 100, out.as_mut_ptr(), 99),
            INVALID_ARGUMENT
        );
        assert!(last_error().contains("100 samples but v has room for 99"));
        assert_eq!(
            call(m, ihc, y_d.as_ptr(), 0, out.as_mut_ptr(), 0),
            INVALID_ARGUMENT
        );
        assert!(last_error().contains("empty"));
        assert_eq!(
            call(null(), ihc, y_d.as_ptr(), 99, out.as_mut_ptr(), 99),
            NULL_POINTER
        );
        assert_eq!(
            call(m, null(), y_d.as_ptr(), 99, out.as_mut_ptr(), 99),
            NULL_POINTER
        );
        assert_eq!(call(m, ihc, null(), 99, out.as_mut_ptr(), 99), NULL_POINTER);
        assert_eq!(last_error(), "y_d is NULL; pass a valid pointer");
        assert_eq!(call(m, ihc, y_d.as_ptr(), 99, null_mut(), 99), NULL_POINTER);
        // In place: y_d and v the same array.
        let mut in_place = y_d.clone();
        let p = in_place.as_mut_ptr();
        assert_eq!(call(m, ihc, p, 100, p, 100), OK);
        let (_, expected, _) = compensate(m, c"ihc", None, &y_d);
        assert_eq!(in_place, expected);
        let mut compensator = std::ptr::dangling_mut::<HystcompCompensator>();
        assert_eq!(
            hystcomp_compensator_from_model(null(), ihc, 0.0, 0.0, 0, &mut compensator),
            NULL_POINTER
        );
        assert!(compensator.is_null());
    }
    free(m);
    free(inverse);
}

#[test]
fn a_model_with_creep_and_vibration_keeps_its_links_and_runs_its_chain() {
    let dir = tempfile::tempdir().unwrap();
    let file = chained_file();
    let path = dir.path().join("chained.json");
    file.save(&path).unwrap();
    let m = load(&CString::new(path.to_str().unwrap()).unwrap()).unwrap();
    assert_eq!(file_of(m), file);
    let again = from_values(&values_of(m)).unwrap();
    assert_eq!(file_of(again), file);
    // Predicted through the whole chain, as the library predicts.
    let x: Vec<f64> = (0..4000)
        .map(|k| 5.0 + 4.0 * (k as f64 * 3e-3).sin())
        .collect();
    let mut y = vec![0.0; x.len()];
    // SAFETY: a live handle and arrays of the stated lengths.
    check(unsafe { hystcomp_model_predict(again, x.as_ptr(), x.len(), y.as_mut_ptr(), y.len()) })
        .unwrap();
    assert_eq!(y, file.predict(&x).unwrap());
    // In place.
    let mut in_place = x.clone();
    let p = in_place.as_mut_ptr();
    // SAFETY: the same array as input and output, of the stated length.
    check(unsafe { hystcomp_model_predict(again, p, x.len(), p, x.len()) }).unwrap();
    assert_eq!(in_place, y);
    // The one-shot compensation is the library's aligned process: it inverts the chain.
    let (status, v, _) = compensate(again, c"ihc", None, &y);
    assert_eq!(status, OK, "{}", last_error());
    let mut reference = ScaledCompensator::new(&file, Method::Ihc, None).unwrap();
    let mut expected = vec![0.0; y.len()];
    reference.process(&y, &mut expected).unwrap();
    assert_eq!(v, expected);
    let mut compensator = null_mut();
    let mut preview = usize::MAX;
    // SAFETY: live handles and valid out-pointers.
    unsafe {
        check(hystcomp_compensator_from_model(
            again,
            c"ihc".as_ptr(),
            0.0,
            0.0,
            0,
            &mut compensator,
        ))
        .unwrap();
        check(hystcomp_compensator_preview(compensator, &mut preview)).unwrap();
        assert_eq!(preview, reference.preview());
        assert!(preview >= 2, "the delay needs a preview: {preview}");
        assert_eq!(
            hystcomp_compensator_preview(compensator, null_mut()),
            NULL_POINTER
        );
        hystcomp_compensator_free(compensator);
    }
    // A forward MPIM handle would leave the links out: refused.
    let mut mpim = std::ptr::dangling_mut::<HystcompMpim>();
    // SAFETY: a live handle and a valid out-pointer.
    let (status, message) =
        check(unsafe { hystcomp_mpim_from_model(again, &mut mpim) }).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(message.contains("hystcomp_model_predict"), "{message}");
    assert!(mpim.is_null());
    // So would one made from the file.
    let mut mpim = std::ptr::dangling_mut::<HystcompMpim>();
    let c_path = CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path and a valid out-pointer.
    let (status, message) =
        check(unsafe { hystcomp_mpim_from_model_file(c_path.as_ptr(), &mut mpim) }).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(message.contains("hystcomp_model_load"), "{message}");
    assert!(mpim.is_null());
    // Bad links, each refused with its name, before any array is read when a length is wrong.
    let good = values_of(m);
    // NaN time constants, as many as the link's elements: the array must hold the stated
    // length (a one-element array here was read past its end, which valgrind reported).
    let nothing = vec![f64::NAN; good.creep_elements];
    type Edit = Box<dyn Fn(&mut HystcompModelValues)>;
    let cases: Vec<(Edit, c_int, &str)> = vec![
        (
            Box::new(|v| v.creep_elements = 65),
            INVALID_ARGUMENT,
            "creep_elements 65",
        ),
        (
            Box::new(|v| v.creep_elements = usize::MAX),
            INVALID_ARGUMENT,
            "creep_elements",
        ),
        (
            Box::new(|v| v.vibration_numerator_len = 18),
            INVALID_ARGUMENT,
            "vibration_numerator_len 18",
        ),
        (
            Box::new(|v| v.vibration_denominator_len = usize::MAX),
            INVALID_ARGUMENT,
            "vibration_denominator_len",
        ),
        (
            Box::new(|v| v.creep_weights = null()),
            NULL_POINTER,
            "creep_weights",
        ),
        (
            Box::new(|v| v.vibration_denominator = null()),
            NULL_POINTER,
            "vibration_denominator",
        ),
        (
            Box::new(|v| v.sample_rate_hz = 0.0),
            INVALID_ARGUMENT,
            "sample_rate_hz",
        ),
        (
            Box::new(|v| v.sample_rate_hz = f64::NAN),
            INVALID_ARGUMENT,
            "sample_rate_hz NaN",
        ),
        (
            Box::new(move |v| v.creep_time_constants_s = nothing.as_ptr()),
            INVALID_ARGUMENT,
            "creep",
        ),
        (
            Box::new(|v| v.vibration_denominator_len = 1),
            INVALID_ARGUMENT,
            "vibration",
        ),
    ];
    for (edit, status, needle) in cases {
        let mut values = good;
        edit(&mut values);
        let (found, message) = from_values(&values).unwrap_err();
        assert_eq!(found, status, "{needle}: {message}");
        assert!(message.contains(needle), "{needle}: {message}");
    }
    // SAFETY: the NULL pointers are the test.
    unsafe {
        assert_eq!(
            hystcomp_model_predict(null(), x.as_ptr(), 3, y.as_mut_ptr(), 3),
            NULL_POINTER
        );
        assert_eq!(
            hystcomp_model_predict(m, null(), 3, y.as_mut_ptr(), 3),
            NULL_POINTER
        );
        assert_eq!(
            hystcomp_model_predict(m, x.as_ptr(), 3, null_mut(), 3),
            NULL_POINTER
        );
        assert_eq!(
            hystcomp_model_predict(m, x.as_ptr(), 3, y.as_mut_ptr(), 2),
            INVALID_ARGUMENT
        );
        assert_eq!(
            hystcomp_model_predict(m, x.as_ptr(), 0, y.as_mut_ptr(), 0),
            INVALID_ARGUMENT
        );
        let bad = [1.0, f64::NAN, 2.0];
        assert_eq!(
            hystcomp_model_predict(m, bad.as_ptr(), 3, y.as_mut_ptr(), 3),
            INVALID_ARGUMENT
        );
        assert!(last_error().contains("x[1] is NaN"), "{}", last_error());
    }
    free(m);
    free(again);
}
