//! The learner across the C boundary, called from Rust as C calls it: every drive equal, bit
//! for bit, to `hystcomp_learn::Learner`'s on seeded random trials; within the limits whatever
//! is measured; the divergence guard's status with the last good drive; every NULL, NaN,
//! mismatched or oversized argument refused with its status before anything is read.

use std::ffi::c_int;
use std::ptr::{null, null_mut};

mod common;

use common::*;
use hystcomp::*;
use hystcomp_io::model_file::ModelFile;
use hystcomp_learn::{Learner, LearningOptions};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const LEARNING_STOPPED: c_int = HystcompStatus::LearningStopped as c_int;

fn table1() -> (ModelFile, *mut HystcompModel) {
    let path = model_path("table1-plant.json");
    let file = ModelFile::load(std::path::Path::new(path.to_str().unwrap())).unwrap();
    let mut model = null_mut();
    // SAFETY: a valid string and out-pointer.
    assert_eq!(
        unsafe { hystcomp_model_load(path.as_ptr(), &mut model) },
        OK
    );
    (file, model)
}

fn sine(n: usize, mid: f64, amplitude: f64) -> Vec<f64> {
    (0..n)
        .map(|k| mid + amplitude * (2.0 * std::f64::consts::PI * k as f64 / n as f64).sin())
        .collect()
}

fn options(fs: f64) -> HystcompLearningOptions {
    let mut o = std::mem::MaybeUninit::uninit();
    // SAFETY: a valid out-pointer.
    assert_eq!(
        unsafe { hystcomp_learning_options_default(fs, o.as_mut_ptr()) },
        OK
    );
    // SAFETY: written by the call.
    unsafe { o.assume_init() }
}

fn new_learner(
    model: *const HystcompModel,
    desired: &[f64],
    o: &HystcompLearningOptions,
) -> Result<*mut HystcompLearner, (c_int, String)> {
    let mut out = std::ptr::dangling_mut::<HystcompLearner>();
    // SAFETY: valid pointers and lengths.
    let status =
        unsafe { hystcomp_learner_new(model, desired.as_ptr(), desired.len(), o, &mut out) };
    if status == OK {
        Ok(out)
    } else {
        assert!(out.is_null(), "a failed constructor leaves NULL in *out");
        Err((status, last_error()))
    }
}

fn drive_of(h: *const HystcompLearner, n: usize) -> Vec<f64> {
    let mut drive = vec![f64::NAN; n];
    // SAFETY: a live handle, `n` writable doubles.
    assert_eq!(
        unsafe { hystcomp_learner_drive(h, drive.as_mut_ptr(), n) },
        OK
    );
    drive
}

/// Seeded random trials (lengths, gains, cut-offs, orders, leads, periodic or finite, limits,
/// measured records): the C learner's drives, indices and law are the library's, bit for bit.
#[test]
fn the_c_learner_is_the_library_learner_bit_for_bit() {
    let (file, model) = table1();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for case in 0..12 {
        let n = rng.random_range(100..800);
        let fs = 1000.0;
        let mut o = options(fs);
        o.gain = rng.random_range(0.2..1.5);
        o.bandwidth_hz = if case % 3 == 0 {
            0.0
        } else {
            rng.random_range(5.0..200.0)
        };
        o.filter_order = rng.random_range(1..6);
        o.lead_samples = rng.random_range(0..4);
        o.periodic = c_int::from(case % 2 == 0);
        o.mhe_bins = 10;
        if case % 4 == 1 {
            o.use_limits = 1;
            o.v_min = 1.0;
            o.v_max = 9.0;
        }
        let desired = sine(n, rng.random_range(30.0..40.0), rng.random_range(5.0..20.0));
        let h = new_learner(model, &desired, &o).unwrap();
        let mut reference = LearningOptions::new(fs);
        reference.gain = o.gain;
        reference.bandwidth_hz = (o.bandwidth_hz != 0.0).then_some(o.bandwidth_hz);
        reference.filter_order = o.filter_order;
        reference.lead_samples = o.lead_samples;
        reference.periodic = o.periodic != 0;
        reference.mhe_bins = 10;
        reference.limits = (o.use_limits != 0).then_some((o.v_min, o.v_max));
        let mut library = Learner::new(&file, &desired, reference).unwrap();
        assert_eq!(drive_of(h, n), library.drive(), "case {case}: trial 0");
        let mut law = HystcompLearningLaw::default();
        // SAFETY: a live handle and a valid out-pointer.
        assert_eq!(unsafe { hystcomp_learner_law(h, &mut law) }, OK);
        assert_eq!(law.bandwidth_hz, library.law().bandwidth_hz);
        assert_eq!((law.v_min, law.v_max), library.law().limits);
        for trial in 0..3 {
            let measured: Vec<f64> = desired
                .iter()
                .map(|d| d + rng.random_range(-0.5..0.5))
                .collect();
            let mut drive = vec![f64::NAN; n];
            let mut update = HystcompLearningUpdate::default();
            // SAFETY: valid pointers and lengths.
            let status = unsafe {
                hystcomp_learner_update(h, measured.as_ptr(), n, drive.as_mut_ptr(), &mut update)
            };
            let expected = library.update(&measured).unwrap();
            assert_eq!(status, OK, "{}", last_error());
            assert_eq!(drive, library.drive(), "case {case}, trial {trial}");
            assert_eq!(update.trial, expected.trial);
            assert_eq!(update.e_rms_percent, expected.indices.e_rms_percent);
            assert_eq!(
                update.predicted_e_rms_percent,
                expected.predicted.unwrap().e_rms_percent
            );
            assert_eq!(update.clamped_samples, expected.clamped_samples);
            let (lo, hi) = library.law().limits;
            assert!(drive.iter().all(|v| v.is_finite() && (lo..=hi).contains(v)));
        }
        // SAFETY: a live handle, freed once.
        unsafe { hystcomp_learner_free(h) };
    }
    // SAFETY: a live handle, freed once.
    unsafe { hystcomp_model_free(model) };
}

/// A gain far too high: the guard trips on the second trial, the call says so with
/// LEARNING_STOPPED and writes the first drive (the last good one); later updates are refused
/// and change nothing. The drive may be updated in place over the measured array.
#[test]
fn the_divergence_guard_returns_the_last_good_drive_and_then_refuses() {
    let (file, model) = table1();
    let n = 1000;
    let desired = sine(n, 35.0, 20.0);
    let mut o = options(1000.0);
    o.gain = 10.0;
    o.bandwidth_hz = 500.0;
    let h = new_learner(model, &desired, &o).unwrap();
    let first = drive_of(h, n);
    // A stage the model gets 5 % wrong, in its periodic state.
    let mut plant = file.clone();
    plant.output.scale *= 0.95;
    let respond = |drive: &[f64]| -> Vec<f64> {
        let three: Vec<f64> = drive.iter().chain(drive).chain(drive).copied().collect();
        plant.predict(&three).unwrap()[n..2 * n].to_vec()
    };
    let mut buffer = respond(&first);
    let mut update = HystcompLearningUpdate::default();
    // In place: the measured record in, the next drive out, in one array.
    // SAFETY: valid pointers and lengths.
    let status =
        unsafe { hystcomp_learner_update(h, buffer.as_ptr(), n, buffer.as_mut_ptr(), &mut update) };
    assert_eq!(status, OK, "{}", last_error());
    let mut measured = respond(&buffer);
    let mut drive = vec![0.0; n];
    // SAFETY: valid pointers and lengths.
    let status = unsafe {
        hystcomp_learner_update(h, measured.as_ptr(), n, drive.as_mut_ptr(), &mut update)
    };
    assert_eq!(status, LEARNING_STOPPED);
    assert!(last_error().contains("divergence guard stopped the learning at trial 1"));
    assert_eq!(
        (update.diverged, update.best_trial, update.has_prediction),
        (1, 0, 0)
    );
    assert_eq!(drive, first);
    measured[0] += 1.0;
    // SAFETY: valid pointers and lengths.
    let status =
        unsafe { hystcomp_learner_update(h, measured.as_ptr(), n, drive.as_mut_ptr(), null_mut()) };
    assert_eq!(status, LEARNING_STOPPED);
    assert_eq!(drive_of(h, n), first);
    // SAFETY: handles freed once.
    unsafe {
        hystcomp_learner_free(h);
        hystcomp_model_free(model);
    }
}

#[test]
fn bad_arguments_are_refused_with_their_status_before_anything_is_read() {
    let (_, model) = table1();
    let n = 200;
    let desired = sine(n, 35.0, 20.0);
    let mut o = options(1000.0);
    o.mhe_bins = 10;
    let (status, message) = new_learner(null(), &desired, &o).unwrap_err();
    assert_eq!(status, NULL_POINTER, "{message}");
    // Sizes are checked before the array is read: a 200-sample array passed as a huge trial.
    let mut out = null_mut();
    // SAFETY: the length is refused before anything is read.
    let status = unsafe {
        hystcomp_learner_new(
            model,
            desired.as_ptr(),
            HYSTCOMP_MAX_TRIAL_SAMPLES + 1,
            &o,
            &mut out,
        )
    };
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(last_error().contains("5000000"), "{}", last_error());
    // SAFETY: as above.
    let status = unsafe { hystcomp_learner_new(model, desired.as_ptr(), 1, &o, &mut out) };
    assert_eq!(status, INVALID_ARGUMENT);
    // SAFETY: options NULL.
    let status = unsafe { hystcomp_learner_new(model, desired.as_ptr(), n, null(), &mut out) };
    assert_eq!(status, NULL_POINTER);
    let mut bad = o;
    bad.gain = -1.0;
    let (status, message) = new_learner(model, &desired, &bad).unwrap_err();
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(message.starts_with("gain"), "{message}");
    bad = o;
    bad.inverse = 7;
    assert_eq!(
        new_learner(model, &desired, &bad).unwrap_err().0,
        INVALID_ARGUMENT
    );
    let mut nan = desired.clone();
    nan[3] = f64::NAN;
    let (status, message) = new_learner(model, &nan, &o).unwrap_err();
    assert_eq!(status, NON_FINITE_INPUT);
    assert!(message.contains("desired[3]"), "{message}");
    // An inverse model cannot recover the reference from a drive.
    let inverse_path = model_path("table2-inverse.json");
    let mut inverse = null_mut();
    // SAFETY: a valid string and out-pointer.
    assert_eq!(
        unsafe { hystcomp_model_load(inverse_path.as_ptr(), &mut inverse) },
        OK
    );
    let (status, message) = new_learner(inverse, &desired, &o).unwrap_err();
    assert_ne!(status, OK);
    assert!(message.contains("plant model"), "{message}");
    // A drive outside the limits cannot be resumed from; a NULL drive is refused.
    let outside = vec![50.0; n];
    // SAFETY: valid pointers and lengths.
    let status = unsafe {
        hystcomp_learner_resume(model, desired.as_ptr(), outside.as_ptr(), n, &o, &mut out)
    };
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(out.is_null());
    // SAFETY: drive NULL.
    let status =
        unsafe { hystcomp_learner_resume(model, desired.as_ptr(), null(), n, &o, &mut out) };
    assert_eq!(status, NULL_POINTER);

    let h = new_learner(model, &desired, &o).unwrap();
    let before = drive_of(h, n);
    let mut drive = vec![0.0; n];
    // SAFETY: lengths refused before reading.
    let status = unsafe {
        hystcomp_learner_update(h, desired.as_ptr(), n + 1, drive.as_mut_ptr(), null_mut())
    };
    assert_eq!(status, INVALID_ARGUMENT);
    let mut measured = desired.clone();
    measured[7] = f64::INFINITY;
    // SAFETY: valid pointers and lengths.
    let status =
        unsafe { hystcomp_learner_update(h, measured.as_ptr(), n, drive.as_mut_ptr(), null_mut()) };
    assert_eq!(status, NON_FINITE_INPUT);
    assert!(last_error().contains("measured[7]"));
    // SAFETY: NULL output and handle.
    unsafe {
        assert_eq!(
            hystcomp_learner_update(h, desired.as_ptr(), n, null_mut(), null_mut()),
            NULL_POINTER
        );
        assert_eq!(
            hystcomp_learner_update(
                null_mut(),
                desired.as_ptr(),
                n,
                drive.as_mut_ptr(),
                null_mut()
            ),
            NULL_POINTER
        );
        assert_eq!(
            hystcomp_learner_drive(h, drive.as_mut_ptr(), n - 1),
            INVALID_ARGUMENT
        );
    }
    // A misaligned drive_out is refused before the learner learns from a measured record
    // that would change its drive (it learned first, and a retry learned the trial twice).
    let off: Vec<f64> = desired.iter().map(|y| y - 1.0).collect();
    let mut bytes = vec![0u8; (n + 2) * size_of::<f64>()];
    let base = bytes.as_mut_ptr();
    let shift = if (base as usize + 1).is_multiple_of(align_of::<f64>()) {
        2
    } else {
        1
    };
    let misaligned = base.wrapping_add(shift).cast::<f64>();
    // SAFETY: valid pointers and lengths; the misaligned output is refused before any write.
    let status = unsafe { hystcomp_learner_update(h, off.as_ptr(), n, misaligned, null_mut()) };
    assert_eq!(status, INVALID_ARGUMENT);
    assert!(last_error().contains("drive_out"), "{}", last_error());
    // Refusals changed nothing.
    assert_eq!(drive_of(h, n), before);
    // The same record with a valid output does change the drive: the check above could fail.
    let twin = new_learner(model, &desired, &o).unwrap();
    // SAFETY: valid pointers and lengths.
    let status =
        unsafe { hystcomp_learner_update(twin, off.as_ptr(), n, drive.as_mut_ptr(), null_mut()) };
    assert_eq!(status, OK, "{}", last_error());
    assert_ne!(drive_of(twin, n), before);
    // SAFETY: freed once.
    unsafe { hystcomp_learner_free(twin) };
    let mut samples = 0;
    // SAFETY: a live handle and a valid out-pointer.
    assert_eq!(unsafe { hystcomp_learner_samples(h, &mut samples) }, OK);
    assert_eq!(samples, n);
    // SAFETY: handles freed once; NULL is accepted.
    unsafe {
        hystcomp_learner_free(h);
        hystcomp_learner_free(null_mut());
        hystcomp_model_free(model);
        hystcomp_model_free(inverse);
    }
    // SAFETY: a static string.
    let name = unsafe { std::ffi::CStr::from_ptr(hystcomp_status_name(LEARNING_STOPPED)) };
    assert_eq!(
        name.to_str().unwrap(),
        "learning stopped by the divergence guard"
    );
}
