//! Format version 2: the optional creep and vibration links, read, written, refused, predicted
//! with and compensated, against the core's chain as the reference.

use std::path::PathBuf;

use hystcomp_core::{ChainModel, Creep, Vibration};
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::{CreepPart, ModelFile, VibrationPart};

fn table1() -> ModelFile {
    ModelFile::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../models")
            .join("table1-plant.json"),
    )
    .unwrap()
}

fn creep() -> CreepPart {
    CreepPart {
        origin: 0.0,
        time_constants_s: vec![0.01, 0.1, 1.0, 10.0],
        weights: vec![0.01, 0.02, 0.02, 0.03],
    }
}

/// A resonance at 0.05 of the sample rate with a zero outside the unit circle (as sampling a
/// stage gives), unit static gain.
fn vibration() -> VibrationPart {
    let a = [1.0, -2.0 * 0.97 * (0.3f64).cos(), 0.97 * 0.97];
    let shape = [1.0, 2.5];
    let gain = a.iter().sum::<f64>() / shape.iter().sum::<f64>();
    VibrationPart {
        delay_samples: 1,
        numerator: shape.iter().map(|b| b * gain).collect(),
        denominator: a.to_vec(),
    }
}

fn full() -> ModelFile {
    table1()
        .with_links(1000.0, Some(creep()), Some(vibration()))
        .unwrap()
}

#[test]
fn version_1_files_load_and_are_written_as_version_2_with_the_links() {
    let v1 = table1();
    assert_eq!(v1.format_version, 1);
    assert!(!v1.has_links());
    let text = v1.to_json();
    assert!(text.contains("\"format_version\": 2"), "{text}");
    assert!(!text.contains("creep") && !text.contains("sample_rate_hz"));
    let file = full();
    let back = ModelFile::from_json(&file.to_json()).unwrap();
    assert_eq!(back, file);
    assert!(back.to_json().contains("\"time_constants_s\""));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("full.json");
    file.save(&path).unwrap();
    assert_eq!(ModelFile::load(&path).unwrap(), file);
}

#[test]
fn bad_links_are_refused_naming_the_part() {
    let text = full().to_json();
    let refuse = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
        edit(&mut value);
        ModelFile::from_json(&value.to_string())
            .unwrap_err()
            .to_string()
    };
    assert!(refuse(&|v| v["format_version"] = 1.into()).contains("format_version 2"));
    assert!(
        refuse(&|v| {
            v.as_object_mut().unwrap().remove("sample_rate_hz");
        })
        .contains("sample_rate_hz")
    );
    assert!(refuse(&|v| v["sample_rate_hz"] = (-3.0).into()).contains("sample_rate_hz"));
    assert!(refuse(&|v| v["creep"]["weights"][0] = 0.99.into()).contains("creep"));
    assert!(refuse(&|v| v["creep"]["time_constants_s"][1] = 0.0.into()).contains("creep"));
    assert!(refuse(&|v| v["creep"]["weights"] = serde_json::json!([0.1])).contains("creep"));
    assert!(refuse(&|v| v["vibration"]["numerator"][0] = 5.0.into()).contains("static gain"));
    assert!(refuse(&|v| v["vibration"]["denominator"][2] = 1.5.into()).contains("vibration"));
    assert!(refuse(&|v| v["vibration"]["colour"] = "red".into()).contains("colour"));
}

#[test]
fn predict_runs_the_core_chain_in_physical_units() {
    let file = full();
    let volts: Vec<f64> = (0..4000)
        .map(|k| 5.0 + 4.0 * (k as f64 * 0.01).sin())
        .collect();
    let predicted = file.predict(&volts).unwrap();
    // The reference: the core's chain, scaled by hand.
    let c = creep();
    let v = vibration();
    let mut chain: ChainModel<f64, Vec<f64>, Vec<f64>> = ChainModel {
        hysteresis: file.model().unwrap(),
        creep: None,
        vibration: None,
    };
    let mut creep_link: Creep<f64, Vec<f64>> =
        Creep::new(&c.time_constants_s, &c.weights, c.origin, 1e-3).unwrap();
    let mut vibration_link: Vibration<f64, Vec<f64>> =
        Vibration::new(&v.numerator, &v.denominator, v.delay_samples).unwrap();
    for (k, volt) in volts.iter().enumerate() {
        let h = file.output_to_physical(chain.step(file.normalise_input(*volt)));
        let y = vibration_link.step(creep_link.step(h));
        assert!((predicted[k] - y).abs() < 1e-9, "{k}");
    }
    // Creep is there: a held voltage keeps moving the prediction.
    let held = file.predict(&vec![6.0; 20_000]).unwrap();
    assert!(
        held[19_999] - held[2000] > 0.01 * 75.0 * 0.1,
        "{}",
        held[19_999] - held[2000]
    );
}

#[test]
fn the_full_compensator_inverts_the_predicted_chain() {
    let file = full();
    // A reachable desired trajectory: the chain's own output for a slow drive from rest.
    let volts: Vec<f64> = (0..6000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            let rise = 0.5 - 0.5 * (std::f64::consts::PI * (t / 0.5).min(1.0)).cos();
            rise * (5.0 + 3.5 * (2.0 * std::f64::consts::PI * 0.7 * t).sin())
        })
        .collect();
    let desired = file.predict(&volts).unwrap();
    for method in [Method::Ihc, Method::Wihc] {
        let mut compensator = ScaledCompensator::new(&file, method, None).unwrap();
        assert!(compensator.preview() >= 2);
        let mut drive = vec![0.0; desired.len()];
        compensator.process(&desired, &mut drive).unwrap();
        let reached = file.predict(&drive).unwrap();
        let worst = reached
            .iter()
            .zip(&desired)
            .skip(1)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{method}: {worst} um");
    }
    // Streaming with a short preview: the same drive, late by the preview, close to it.
    let minimum = vibration().minimum_preview().unwrap();
    let mut streaming =
        ScaledCompensator::with_preview(&file, Method::Ihc, None, Some(minimum + 4)).unwrap();
    assert_eq!(streaming.preview(), minimum + 4);
    let mut offline = ScaledCompensator::new(&file, Method::Ihc, None).unwrap();
    let mut aligned = vec![0.0; desired.len()];
    offline.process(&desired, &mut aligned).unwrap();
    let lag = streaming.preview();
    let late: Vec<f64> = desired.iter().map(|d| streaming.step(*d)).collect();
    for k in 200..desired.len() {
        assert!((late[k] - aligned[k - lag]).abs() < 1e-3, "{k}");
    }
}

#[test]
fn a_settled_prediction_and_compensator_start_at_rest_where_the_record_starts() {
    let file = table1().with_links(1000.0, Some(creep()), None).unwrap();
    // Held at 6 V from the first sample: relaxed at the origin the model creeps, settled it
    // does not.
    let held = vec![6.0; 5000];
    let relaxed = file.predict(&held).unwrap();
    let settled = file.predict_settled(&held).unwrap();
    assert!((relaxed[4999] - relaxed[0]).abs() > 0.1);
    assert!((settled[4999] - settled[0]).abs() < 1e-9);
    // The compensator settled at a held desired position asks a constant drive.
    let mut c = ScaledCompensator::new(&file, Method::Ihc, None).unwrap();
    c.settle_creep(40.0);
    let drive: Vec<f64> = (0..3000).map(|_| c.step(40.0)).collect();
    assert!((drive[2999] - drive[0]).abs() < 1e-9);
    let mut relaxed = ScaledCompensator::new(&file, Method::Ihc, None).unwrap();
    let drive: Vec<f64> = (0..3000).map(|_| relaxed.step(40.0)).collect();
    assert!((drive[2999] - drive[0]).abs() > 1e-3);
}

#[test]
fn the_band_limited_inversion_inverts_the_trajectory_low_passed_and_nothing_else() {
    // On random reachable trajectories with content above the band: the drive is the whole
    // inversion of the trajectory low-passed with zero phase, the prediction of that drive
    // follows the low-passed trajectory (not the original), and the band is refused outside
    // (0, Nyquist) and ignored without a vibration link.
    let file = full();
    // A seeded stream of numbers in [0, 1) (splitmix64).
    let mut state = 5u64;
    let mut random = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    };
    for case in 0..4 {
        let f1 = 0.5 + random();
        let f2 = 150.0 + 200.0 * random();
        let volts: Vec<f64> = (0..3000)
            .map(|k| {
                let t = k as f64 * 1e-3;
                let rise = 0.5 - 0.5 * (std::f64::consts::PI * (t / 0.5).min(1.0)).cos();
                rise * (5.0
                    + 3.0 * (2.0 * std::f64::consts::PI * f1 * t).sin()
                    + 0.3 * (2.0 * std::f64::consts::PI * f2 * t).sin())
            })
            .collect();
        let desired = file.predict(&volts).unwrap();
        let band = 40.0 + 60.0 * random();
        let mut limited = ScaledCompensator::new(&file, Method::Ihc, None)
            .unwrap()
            .with_inverse_band(Some(band))
            .unwrap();
        assert_eq!(limited.inverse_band_hz(), Some(band));
        let filtered = limited.band_limited(&desired);
        assert_eq!(
            filtered,
            hystcomp_io::band_limit::zero_phase_low_pass(&desired, band, 1000.0)
        );
        let mut drive = vec![0.0; desired.len()];
        limited.process(&desired, &mut drive).unwrap();
        let mut whole = ScaledCompensator::new(&file, Method::Ihc, None).unwrap();
        let mut reference = vec![0.0; desired.len()];
        whole.process(&filtered, &mut reference).unwrap();
        assert_eq!(drive, reference, "case {case}");
        let reached = file.predict(&drive).unwrap();
        let off_filtered = reached
            .iter()
            .zip(&filtered)
            .skip(1)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let off_desired = reached
            .iter()
            .zip(&desired)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // Up to the drive limits' clamping where the low-passed trajectory leaves the reach
        // (about 32 samples at its start, counted as saturated).
        assert!(
            off_filtered < 0.01 && off_desired > 10.0 * off_filtered,
            "case {case}: {off_filtered} {off_desired}"
        );
    }
    for bad in [0.0, -5.0, 500.0, 800.0, f64::NAN, f64::INFINITY] {
        let refused = ScaledCompensator::new(&file, Method::Ihc, None)
            .unwrap()
            .with_inverse_band(Some(bad));
        assert!(
            refused
                .as_ref()
                .is_err_and(|e| e.to_string().contains("Nyquist frequency 500 Hz")),
            "{bad}: {:?}",
            refused.map(|c| c.inverse_band_hz())
        );
    }
    let creep_only = table1().with_links(1000.0, Some(creep()), None).unwrap();
    let plain = ScaledCompensator::new(&creep_only, Method::Ihc, None)
        .unwrap()
        .with_inverse_band(Some(50.0))
        .unwrap();
    assert_eq!(plain.inverse_band_hz(), None);
    let x = vec![1.0, 2.0, 30.0, 2.0];
    assert_eq!(plain.band_limited(&x), x);
}

/// Table 1 with the output map `coefficients` on `range` (format version 2), as JSON text.
fn with_map(coefficients: &[f64], range: [f64; 2]) -> String {
    let mut value: serde_json::Value = serde_json::from_str(&table1().to_json()).unwrap();
    value["output_map"] = serde_json::json!({ "coefficients": coefficients, "range": range });
    value.to_string()
}

#[test]
fn output_maps_out_of_range_are_refused_naming_the_field() {
    // A map as `identify --output-map-degree 5` fits on the real record: accepted.
    let fitted = [-0.00295, 0.7295, -5.771, 19.32, -23.32, 9.406];
    let file = ModelFile::from_json(&with_map(&fitted, [-0.121, 1.079])).unwrap();
    assert!(file.output_map.is_some());
    for (coefficients, range, fragments) in [
        (
            &[0.5][..],
            [0.0, 1.0],
            &["output_map.coefficients", "2 to 6"][..],
        ),
        (
            &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0][..],
            [0.0, 1.0],
            &["output_map.coefficients", "2 to 6"],
        ),
        (
            &[0.0, 2e6][..],
            [0.0, 1.0],
            &["output_map.coefficients[1]", "1e6"],
        ),
        (&[0.0, 1.0][..], [-2e3, 1.0], &["output_map.range", "1e3"]),
        (
            &[0.0, 1.0][..],
            [1.0, 0.0],
            &["output_map.range", "increasing"],
        ),
        // Rising, but so flat that psi^-1 of an ordinary output overflows (1e-300: predict
        // gave 3.6e299 um before the check).
        (
            &[0.0, 1e-300][..],
            [0.0, 1.0],
            &["output_map", "slope", "1e-300"],
        ),
        // Rising and of ordinary size on average, but flat at its high end (2e-10), where it
        // continues linearly.
        (
            &[0.0, 1.0, -0.4999999999][..],
            [0.0, 1.0],
            &["output_map", "slope", "high end"],
        ),
        // Steep: the whole stroke squeezed into a millionth of the MPIM's output.
        (
            &[0.0, 1.0, 0.0, 0.0, 0.0, 3e5][..],
            [0.0, 1.0],
            &["output_map", "slope"],
        ),
    ] {
        let message = ModelFile::from_json(&with_map(coefficients, range))
            .unwrap_err()
            .to_string();
        for fragment in fragments {
            assert!(
                message.contains(fragment),
                "{coefficients:?} {range:?}: {message}"
            );
        }
    }
}

#[test]
fn every_accepted_output_map_predicts_finite_outputs_far_beyond_its_range() {
    // Seeded random maps of every degree, of every size; those the file accepts must give a
    // finite prediction of ordinary size for inputs far outside the identified range (the
    // continuation's slopes bounded), and a refused one must name the output map.
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut accepted, mut refused) = (0, 0);
    for _ in 0..400 {
        let degree = 1 + (uniform() * 5.0) as usize;
        // Half of ordinary size, half anywhere a JSON number may be.
        let size = if uniform() < 0.5 {
            10f64.powf(-8.0 + 16.0 * uniform())
        } else {
            10f64.powf(-300.0 + 600.0 * uniform())
        };
        let mut coefficients: Vec<f64> = (0..=degree)
            .map(|_| size * (2.0 * uniform() - 1.0))
            .collect();
        coefficients[1] = coefficients[1].abs();
        let lo = 10f64.powf(-3.0 + 6.5 * uniform()) * (uniform() - 0.5);
        let hi = lo + 10f64.powf(-3.0 + 6.0 * uniform());
        match ModelFile::from_json(&with_map(&coefficients, [lo, hi])) {
            Ok(file) => {
                accepted += 1;
                let input: Vec<f64> = [-100.0, -10.0, 0.0, 3.0, 7.0, 10.0, 100.0, 0.0].to_vec();
                let output = file.predict(&input).unwrap();
                // Finite and no larger than a record's values may be (1e15), 100 V being ten
                // times the model's input scale.
                assert!(
                    output.iter().all(|y| y.abs() <= 1e15),
                    "{coefficients:?} on [{lo}, {hi}]: {output:?}"
                );
            }
            Err(e) => {
                refused += 1;
                assert!(e.to_string().contains("output_map"), "{e}");
            }
        }
    }
    assert!(
        accepted > 20 && refused > 20,
        "{accepted} accepted, {refused} refused"
    );
}
