//! The bank's C ABI called from Rust as C calls it: every channel of a `HystcompBank` gives what
//! a `HystcompCompensator` made from its own model gives, bit for bit (tick by tick, a whole
//! signal, in place), with the per-channel limits and diagnostics; NaN holds a channel and is
//! reported with its tick and channel; wrong sizes, NULLs and refused channels give a status
//! and a message naming the channel.

mod common;

use std::ffi::{CString, c_int};
use std::ptr::{null, null_mut};

use common::*;
use hystcomp::*;

/// A bank of `method` over the three-axis model set, with `limits` pairs.
fn xyz_bank(method: &str, limits: &[f64]) -> *mut HystcompBank {
    let path = model_path("table1-xyz-set.json");
    let method = CString::new(method).unwrap();
    let mut bank = null_mut();
    // SAFETY: valid strings, `limits.len() / 2` pairs, a valid out-parameter.
    let status = unsafe {
        hystcomp_bank_from_model_set(
            path.as_ptr(),
            method.as_ptr(),
            if limits.is_empty() {
                null()
            } else {
                limits.as_ptr()
            },
            limits.len() / 2,
            0,
            &mut bank,
        )
    };
    assert_eq!(status, OK, "{}", last_error());
    bank
}

/// The channels' own compensators: each model of the set in a file of its own.
fn singles(method: &str, limits: &[(f64, f64)]) -> Vec<*mut HystcompCompensator> {
    let set = hystcomp_io::bank::ModelSet::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/table1-xyz-set.json"
    )))
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let method = CString::new(method).unwrap();
    (0..3)
        .map(|c| {
            let file = dir.path().join(format!("{c}.json"));
            set.channels[c].model.save(&file).unwrap();
            let path = CString::new(file.to_str().unwrap()).unwrap();
            let mut h = null_mut();
            let (lo, hi) = limits
                .get(c)
                .or(limits.first())
                .copied()
                .unwrap_or((0.0, 0.0));
            // SAFETY: valid strings and out-parameter.
            let status = unsafe {
                hystcomp_compensator_from_model_file(
                    path.as_ptr(),
                    method.as_ptr(),
                    lo,
                    hi,
                    c_int::from(!limits.is_empty()),
                    &mut h,
                )
            };
            assert_eq!(status, OK, "{}", last_error());
            h
        })
        .collect()
}

/// Desired positions of tick `k` for three channels, with a NaN now and then.
fn tick(k: usize) -> [f64; 3] {
    let t = k as f64 * 0.02;
    let mut d = [
        35.0 + 30.0 * t.sin(),
        30.0 + 25.0 * (1.3 * t).cos(),
        45.0 + 40.0 * (0.7 * t + 1.0).sin(),
    ];
    if k % 97 == 13 {
        d[k % 3] = f64::NAN;
    }
    d
}

#[test]
fn every_channel_equals_its_own_compensator_bit_for_bit() {
    for (method, limits) in [
        ("ihc", vec![]),
        ("wihc", vec![(0.5, 9.5)]),
        ("ihc-guarded", vec![(0.0, 10.0), (1.0, 9.0), (0.2, 8.0)]),
        ("wihc-guarded", vec![]),
        ("ihc-delayed", vec![]),
    ] {
        let flat: Vec<f64> = limits.iter().flat_map(|&(a, b)| [a, b]).collect();
        let bank = xyz_bank(method, &flat);
        let whole = xyz_bank(method, &flat);
        let singles = singles(method, &limits);
        let mut desired = Vec::new();
        let mut drives = Vec::new();
        for k in 0..600 {
            let d = tick(k);
            let mut v = [0.0; 3];
            // SAFETY: a live handle, three doubles each.
            let status = unsafe { hystcomp_bank_step(bank, d.as_ptr(), v.as_mut_ptr(), 3) };
            let finite = d.iter().all(|x| x.is_finite());
            assert_eq!(status, if finite { OK } else { NON_FINITE_INPUT });
            if !finite {
                assert!(
                    last_error().contains(&format!("tick 0, channel {}", k % 3)),
                    "{}",
                    last_error()
                );
            }
            for c in 0..3 {
                let mut expected = 0.0;
                // SAFETY: a live handle and an out-parameter.
                unsafe { hystcomp_compensator_step(singles[c], d[c], &mut expected) };
                assert_eq!(
                    v[c].to_bits(),
                    expected.to_bits(),
                    "{method} tick {k} channel {c}"
                );
            }
            desired.extend(d);
            drives.extend(v);
        }
        // A whole signal, out of place and in place, equals the ticks.
        let mut out = vec![0.0; desired.len()];
        // SAFETY: a live handle, 600 x 3 doubles each.
        let status =
            unsafe { hystcomp_bank_process(whole, desired.as_ptr(), out.as_mut_ptr(), 600, 3) };
        assert_eq!(status, NON_FINITE_INPUT);
        assert_eq!(out, drives);
        let mut in_place = desired.clone();
        // SAFETY: as above; the same array in and out is allowed.
        unsafe {
            hystcomp_bank_reset(whole);
            hystcomp_bank_process(whole, in_place.as_ptr(), in_place.as_mut_ptr(), 600, 3);
        }
        assert_eq!(in_place, drives);
        // Limits and diagnostics per channel.
        for (c, &single) in singles.iter().enumerate() {
            let (mut lo, mut hi, mut elo, mut ehi) = (0.0, 0.0, 0.0, 0.0);
            let (mut sat, mut loop_sat, mut nonfinite) = (0u64, 0u64, 0u64);
            let (mut esat, mut enonfinite, mut eloop) = (0u64, 0u64, 0u64);
            // SAFETY: live handles and out-parameters.
            unsafe {
                assert_eq!(hystcomp_bank_limits(bank, c, &mut lo, &mut hi), OK);
                hystcomp_compensator_limits(single, &mut elo, &mut ehi);
                assert_eq!(
                    hystcomp_bank_diagnostics(bank, c, &mut sat, &mut loop_sat, &mut nonfinite),
                    OK
                );
                hystcomp_compensator_diagnostics(single, &mut esat, &mut enonfinite);
                hystcomp_compensator_loop_saturated(single, &mut eloop);
            }
            assert_eq!((lo, hi), (elo, ehi));
            assert_eq!(
                (sat, loop_sat, nonfinite),
                (esat, eloop, enonfinite),
                "{method} {c}"
            );
            assert!(nonfinite > 0);
        }
        // SAFETY: live handles, freed once.
        unsafe {
            hystcomp_bank_free(bank);
            hystcomp_bank_free(whole);
            for s in singles {
                hystcomp_compensator_free(s);
            }
        }
    }
}

#[test]
fn bad_arguments_give_a_status_and_a_message() {
    let bank = xyz_bank("ihc", &[]);
    let mut channels = 0usize;
    let d = [1.0; 4];
    let mut v = [0.0; 4];
    // SAFETY: every call gets live handles or NULL, and arrays at least as long as stated.
    unsafe {
        assert_eq!(hystcomp_bank_channels(bank, &mut channels), OK);
        assert_eq!(channels, 3);
        assert_eq!(
            hystcomp_bank_step(bank, d.as_ptr(), v.as_mut_ptr(), 4),
            INVALID_ARGUMENT
        );
        assert!(last_error().contains("3 channels"), "{}", last_error());
        assert_eq!(
            hystcomp_bank_step(bank, null(), v.as_mut_ptr(), 3),
            NULL_POINTER
        );
        assert_eq!(
            hystcomp_bank_step(null_mut(), d.as_ptr(), v.as_mut_ptr(), 3),
            NULL_POINTER
        );
        assert_eq!(hystcomp_bank_process(bank, null(), null_mut(), 0, 3), OK);
        assert_eq!(
            hystcomp_bank_process(bank, d.as_ptr(), v.as_mut_ptr(), usize::MAX, 3),
            INVALID_ARGUMENT
        );
        let (mut lo, mut hi) = (0.0, 0.0);
        assert_eq!(
            hystcomp_bank_limits(bank, 3, &mut lo, &mut hi),
            INVALID_ARGUMENT
        );
        assert!(last_error().contains("channels 0 to 2"), "{}", last_error());
        hystcomp_bank_free(bank);
        hystcomp_bank_free(null_mut());

        // A refused channel: DIHC needs inverse models; table 1's delayed WIHC is unstable.
        let path = model_path("table1-xyz-set.json");
        let mut out = null_mut();
        let dihc = CString::new("dihc").unwrap();
        let status =
            hystcomp_bank_from_model_set(path.as_ptr(), dihc.as_ptr(), null(), 0, 0, &mut out);
        assert_eq!(status, WRONG_DIRECTION);
        assert!(
            last_error().starts_with("channel 0 (x): "),
            "{}",
            last_error()
        );
        assert!(out.is_null());
        let delayed = CString::new("wihc-delayed").unwrap();
        let status =
            hystcomp_bank_from_model_set(path.as_ptr(), delayed.as_ptr(), null(), 0, 0, &mut out);
        assert_eq!(status, UNSTABLE_DELAY);
        let status = hystcomp_bank_from_model_set(
            path.as_ptr(),
            delayed.as_ptr(),
            null(),
            0,
            HYSTCOMP_ALLOW_UNSTABLE_DELAY,
            &mut out,
        );
        assert_eq!(status, OK);
        hystcomp_bank_free(out);
        // Limits for two channels of three; a pair not increasing names channel 1.
        let ihc = CString::new("ihc").unwrap();
        let two = [0.0, 10.0, 0.0, 10.0];
        let status =
            hystcomp_bank_from_model_set(path.as_ptr(), ihc.as_ptr(), two.as_ptr(), 2, 0, &mut out);
        assert_eq!(status, INVALID_ARGUMENT);
        let bad = [0.0, 10.0, 5.0, 1.0, 0.0, 10.0];
        let status =
            hystcomp_bank_from_model_set(path.as_ptr(), ihc.as_ptr(), bad.as_ptr(), 3, 0, &mut out);
        assert_eq!(status, INVALID_ARGUMENT);
        assert!(
            last_error().starts_with("channel 1 (y): "),
            "{}",
            last_error()
        );
        // Missing files.
        let missing = model_path("no-such-set.json");
        let status =
            hystcomp_bank_from_model_set(missing.as_ptr(), ihc.as_ptr(), null(), 0, 0, &mut out);
        assert_ne!(status, OK);
        assert!(
            last_error().contains("no-such-set.json"),
            "{}",
            last_error()
        );
    }
}

#[test]
fn a_bank_from_models_in_memory_equals_one_from_the_set() {
    let plant = model_path("table1-plant.json");
    let mut model = null_mut();
    // SAFETY: a valid string and out-parameter.
    assert_eq!(
        unsafe { hystcomp_model_load(plant.as_ptr(), &mut model) },
        OK
    );
    let models = [model as *const HystcompModel; 5];
    let ihc = CString::new("ihc").unwrap();
    let mut bank = null_mut();
    let mut single = null_mut();
    // SAFETY: five live model handles, valid strings and out-parameters.
    unsafe {
        assert_eq!(
            hystcomp_bank_from_models(models.as_ptr(), 5, ihc.as_ptr(), null(), 0, 0, &mut bank),
            OK,
            "{}",
            last_error()
        );
        assert_eq!(
            hystcomp_compensator_from_model_file(
                plant.as_ptr(),
                ihc.as_ptr(),
                0.0,
                0.0,
                0,
                &mut single
            ),
            OK
        );
        hystcomp_model_free(model);
        for k in 0..300 {
            let y = 37.5 + 30.0 * (k as f64 * 0.03).sin();
            let d = [y; 5];
            let mut v = [0.0; 5];
            assert_eq!(hystcomp_bank_step(bank, d.as_ptr(), v.as_mut_ptr(), 5), OK);
            let mut expected = 0.0;
            hystcomp_compensator_step(single, y, &mut expected);
            assert!(v.iter().all(|x| x.to_bits() == expected.to_bits()));
        }
        hystcomp_bank_free(bank);
        let nulls = [null::<HystcompModel>(); 2];
        assert_eq!(
            hystcomp_bank_from_models(nulls.as_ptr(), 2, ihc.as_ptr(), null(), 0, 0, &mut bank),
            NULL_POINTER
        );
        assert!(last_error().contains("models[0]"), "{}", last_error());
        assert_eq!(
            hystcomp_bank_from_models(
                nulls.as_ptr(),
                HYSTCOMP_MAX_CHANNELS + 1,
                ihc.as_ptr(),
                null(),
                0,
                0,
                &mut bank
            ),
            INVALID_ARGUMENT
        );
        hystcomp_compensator_free(single);
    }
}

#[test]
fn a_dihc_bank_equals_its_channels_own_compensators_bit_for_bit() {
    // Table 2's inverse model on three channels, each with its own limits and desired
    // positions (beyond the model's range now and then, NaN now and then).
    let inverse = model_path("table2-inverse.json");
    let dihc = CString::new("dihc").unwrap();
    let limits = [(0.0, 10.0), (1.0, 9.0), (0.5, 8.0)];
    let flat: Vec<f64> = limits.iter().flat_map(|&(a, b)| [a, b]).collect();
    let mut model = null_mut();
    let mut bank = null_mut();
    // SAFETY: valid strings, three live model handles, three limit pairs, valid out-parameters.
    unsafe {
        assert_eq!(hystcomp_model_load(inverse.as_ptr(), &mut model), OK);
        let models = [model as *const HystcompModel; 3];
        assert_eq!(
            hystcomp_bank_from_models(
                models.as_ptr(),
                3,
                dihc.as_ptr(),
                flat.as_ptr(),
                3,
                0,
                &mut bank
            ),
            OK,
            "{}",
            last_error()
        );
        hystcomp_model_free(model);
    }
    let singles: Vec<_> = limits
        .iter()
        .map(|&(lo, hi)| {
            let mut h = null_mut();
            // SAFETY: valid strings and out-parameter.
            let status = unsafe {
                hystcomp_compensator_from_model_file(
                    inverse.as_ptr(),
                    dihc.as_ptr(),
                    lo,
                    hi,
                    1,
                    &mut h,
                )
            };
            assert_eq!(status, OK, "{}", last_error());
            h
        })
        .collect();
    for k in 0..600 {
        let d = tick(k);
        let mut v = [0.0; 3];
        // SAFETY: live handles, three doubles each, out-parameters.
        unsafe {
            let status = hystcomp_bank_step(bank, d.as_ptr(), v.as_mut_ptr(), 3);
            let finite = d.iter().all(|x| x.is_finite());
            assert_eq!(status, if finite { OK } else { NON_FINITE_INPUT });
            for c in 0..3 {
                let mut expected = 0.0;
                hystcomp_compensator_step(singles[c], d[c], &mut expected);
                assert_eq!(v[c].to_bits(), expected.to_bits(), "tick {k} channel {c}");
                assert!(v[c] >= limits[c].0 && v[c] <= limits[c].1);
            }
        }
    }
    let mut clamped = 0;
    for (c, &single) in singles.iter().enumerate() {
        let (mut sat, mut loop_sat, mut nonfinite) = (0u64, 0u64, 0u64);
        let (mut esat, mut enonfinite) = (0u64, 0u64);
        // SAFETY: live handles and out-parameters.
        unsafe {
            assert_eq!(
                hystcomp_bank_diagnostics(bank, c, &mut sat, &mut loop_sat, &mut nonfinite),
                OK
            );
            hystcomp_compensator_diagnostics(single, &mut esat, &mut enonfinite);
        }
        assert_eq!((sat, nonfinite), (esat, enonfinite), "channel {c}");
        assert_eq!(loop_sat, 0, "DIHC has no loop");
        assert!(nonfinite > 0);
        clamped += sat;
    }
    // The limits were reached: the comparison covered the clamps.
    assert!(clamped > 0);
    // SAFETY: live handles, freed once.
    unsafe {
        hystcomp_bank_free(bank);
        for s in singles {
            hystcomp_compensator_free(s);
        }
    }
}

/// A finite desired position so large that it overflows when normalised by its channel's scale
/// (here a displacement in mm, 0.075 mm per normalised unit) holds that channel's drive, as
/// NaN does, and is reported with its channel: never a silent hold. The channel's own
/// compensator reports it too, and both give the same bits.
#[test]
fn a_position_too_large_to_normalise_is_reported_with_its_channel() {
    let mut set = hystcomp_io::bank::ModelSet::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/table1-xyz-set.json"
    )))
    .unwrap();
    let output = &mut set.channels[1].model.output;
    output.unit = "mm".into();
    output.scale /= 1000.0;
    output.offset /= 1000.0;
    let dir = tempfile::tempdir().unwrap();
    let set_path = dir.path().join("set.json");
    set.save(&set_path).unwrap();
    let single_path = dir.path().join("y.json");
    set.channels[1].model.save(&single_path).unwrap();
    let method = CString::new("ihc").unwrap();
    let (set_c, single_c) = (
        CString::new(set_path.to_str().unwrap()).unwrap(),
        CString::new(single_path.to_str().unwrap()).unwrap(),
    );
    let (mut bank, mut single) = (null_mut(), null_mut());
    // SAFETY: valid strings and out-parameters; no limits (the models' own).
    unsafe {
        assert_eq!(
            hystcomp_bank_from_model_set(set_c.as_ptr(), method.as_ptr(), null(), 0, 0, &mut bank),
            OK,
            "{}",
            last_error()
        );
        assert_eq!(
            hystcomp_compensator_from_model_file(
                single_c.as_ptr(),
                method.as_ptr(),
                0.0,
                0.0,
                0,
                &mut single
            ),
            OK,
            "{}",
            last_error()
        );
    }
    for (k, (y, too_large)) in [
        (0.03, false),
        (f64::MAX, true),
        (0.04, false),
        (-1e308, true),
    ]
    .into_iter()
    .enumerate()
    {
        let d = [30.0, y, 30.0];
        let mut v = [f64::NAN; 3];
        let mut expected = f64::NAN;
        // SAFETY: live handles, three doubles each, an out-parameter.
        let (bank_status, single_status) = unsafe {
            (
                hystcomp_bank_step(bank, d.as_ptr(), v.as_mut_ptr(), 3),
                hystcomp_compensator_step(single, y, &mut expected),
            )
        };
        let status = if too_large { NON_FINITE_INPUT } else { OK };
        assert_eq!(bank_status, status, "tick {k}: {}", last_error());
        assert_eq!(single_status, status, "tick {k}");
        if too_large {
            // The single compensator's message is the last error now; ask the bank again.
            // SAFETY: as above.
            unsafe { hystcomp_bank_step(bank, d.as_ptr(), v.as_mut_ptr(), 3) };
            assert!(last_error().contains("channel 1"), "{}", last_error());
        }
        assert_eq!(v[1].to_bits(), expected.to_bits(), "tick {k}");
        assert!(v.iter().all(|x| x.is_finite()), "tick {k}: {v:?}");
    }
    // SAFETY: live handles, freed once.
    unsafe {
        hystcomp_bank_free(bank);
        hystcomp_compensator_free(single);
    }
}
