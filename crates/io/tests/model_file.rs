//! The model file format: round trips, the shipped examples, and every refusal.

use std::path::PathBuf;

use hystcomp_io::model_file::{Direction, ModelFile, ModelFileError, Scale};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(name)
}

fn volts() -> Scale {
    Scale {
        quantity: "command voltage".into(),
        unit: "V".into(),
        offset: 0.0,
        scale: 10.0,
    }
}

fn microns() -> Scale {
    Scale {
        quantity: "displacement".into(),
        unit: "um".into(),
        offset: -3.5,
        scale: 75.0,
    }
}

#[test]
fn shipped_table_files_load_and_match_the_paper() {
    use hystcomp_core::paper::{TABLE1, TABLE2};
    let t1 = ModelFile::load(&example("table1-plant.json")).unwrap();
    assert_eq!(t1.direction, Direction::Plant);
    assert_eq!(t1.thresholds, TABLE1.thresholds);
    assert_eq!(t1.weights, TABLE1.weights);
    assert_eq!((t1.a1, t1.a2), (TABLE1.a1, TABLE1.a2));
    t1.model().unwrap().check_invertible(0.0, 1.0).unwrap();
    let t2 = ModelFile::load(&example("table2-inverse.json")).unwrap();
    assert_eq!(t2.direction, Direction::Inverse);
    assert_eq!(t2.thresholds, TABLE2.thresholds);
    assert_eq!(t2.weights, TABLE2.weights);
    assert_eq!((t2.a1, t2.a2), (TABLE2.a1, TABLE2.a2));
    assert_eq!(t2.input.unit, "um");
    t2.model().unwrap().check_invertible(0.0, 1.0).unwrap();
}

#[test]
fn a_saved_file_loads_back_identically_and_atomically() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    let mut file = ModelFile::new(
        Direction::Inverse,
        microns(),
        volts(),
        [0.0, 1.0],
        vec![0.0, 0.25, 0.5],
        vec![0.1, -0.2, 1.0 / 3.0],
        0.05,
        0.9,
    )
    .unwrap();
    file.identification = Some(serde_json::json!({"solver": "ls", "rms_percent": 0.42}));
    file.save(&path).unwrap();
    let back = ModelFile::load(&path).unwrap();
    assert_eq!(back, file);
    // Only the model file is left in the directory: no temporary file.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // Scales map both ways.
    let x = back.input.to_physical(0.4);
    assert!((back.normalise_input(x) - 0.4).abs() < 1e-15);
    assert!((back.output_to_physical(0.5) - 5.0).abs() < 1e-15);
}

/// A format-1 file (the shipped tables) loads; a higher-degree model is written as format 2 with
/// its whole polynomial and loads back to the same model; a cubic one has no polynomial field.
#[test]
fn higher_degree_input_polynomials_round_trip_in_format_2() {
    use hystcomp_core::{InputPolynomial, Mpim};
    let t1 = ModelFile::load(&example("table1-plant.json")).unwrap();
    assert_eq!(t1.format_version, 1);
    assert_eq!(t1.input_polynomial, None);
    let cubic = ModelFile::from_model(
        Direction::Plant,
        volts(),
        microns(),
        [0.0, 1.0],
        &t1.model().unwrap(),
    )
    .unwrap();
    assert_eq!(cubic.format_version, 2);
    assert!(!cubic.to_json().contains("input_polynomial"));
    let c = [0.46, 0.05, -0.1569, 0.02, -0.01, 0.003, 0.001];
    let model: Mpim<f64, Vec<f64>> = Mpim::with_input_polynomial(
        &t1.thresholds,
        &t1.weights,
        InputPolynomial::new(&c).unwrap(),
    )
    .unwrap();
    let file =
        ModelFile::from_model(Direction::Plant, volts(), microns(), [0.0, 1.0], &model).unwrap();
    assert_eq!(file.input_polynomial.as_deref(), Some(&c[..]));
    assert_eq!((file.a1, file.a2), (-0.1569, 0.46));
    let back = ModelFile::from_json(&file.to_json()).unwrap();
    assert_eq!(back, file);
    let mut a = back.model().unwrap();
    let mut b = model.clone();
    for k in 0..200 {
        let x = 0.5 + 0.45 * (k as f64 * 0.07).sin();
        assert_eq!(a.step(x), b.step(x));
    }
}

fn refusal(edit: impl Fn(&mut serde_json::Value)) -> String {
    let text = std::fs::read_to_string(example("table1-plant.json")).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut value);
    ModelFile::from_json(&value.to_string())
        .unwrap_err()
        .to_string()
}

#[test]
fn each_bad_file_is_refused_with_a_message_naming_the_problem() {
    assert!(refusal(|v| v["format_version"] = 3.into()).contains("format_version 3"));
    // The input polynomial: format 2 only, agreeing with a1 and a2, at most degree 9.
    let table1_polynomial = serde_json::json!([0.4603, 0.0, -0.1569, 0.01]);
    assert!(
        refusal(|v| v["input_polynomial"] = table1_polynomial.clone())
            .contains("input_polynomial needs format_version 2")
    );
    assert!(
        refusal(|v| {
            v["format_version"] = 2.into();
            v["input_polynomial"] = serde_json::json!([0.5, 0.0, -0.1569]);
        })
        .contains("must agree with a2 = c_1")
    );
    assert!(
        refusal(|v| {
            v["format_version"] = 2.into();
            v["input_polynomial"] = serde_json::json!([0.4603, 0.0, -0.1569, 0, 0, 0, 0, 0, 0, 1]);
        })
        .contains("between 1 and 9")
    );
    assert!(
        refusal(|v| {
            v.as_object_mut().unwrap().remove("format_version");
        })
        .contains("format_version")
    );
    assert!(
        refusal(|v| v["direction"] = "sideways".into()).contains("expected `plant` or `inverse`")
    );
    assert!(refusal(|v| v["input"]["scale"] = 0.0.into()).contains("input.scale"));
    assert!(refusal(|v| v["output"]["scale"] = (-1.0).into()).contains("output.scale"));
    assert!(refusal(|v| v["output"]["unit"] = " ".into()).contains("output.unit"));
    assert!(refusal(|v| v["input_range"] = serde_json::json!([1.0, 0.0])).contains("input_range"));
    assert!(refusal(|v| v["weights"] = serde_json::json!([0.1])).contains("weights has 1"));
    assert!(refusal(|v| v["thresholds"][3] = (-0.2).into()).contains("negative"));
    assert!(refusal(|v| v["a2"] = "x".into()).contains("a2"));
    assert!(refusal(|v| v["colour"] = "blue".into()).contains("colour"));
    assert!(
        refusal(|v| {
            v.as_object_mut().unwrap().remove("a1");
        })
        .contains("a1")
    );
}

#[test]
fn unreadable_and_malformed_files_name_the_path() {
    let missing = PathBuf::from("/nonexistent/dir/model.json");
    let err = ModelFile::load(&missing).unwrap_err();
    assert!(matches!(err, ModelFileError::Io { .. }));
    assert!(err.to_string().contains("/nonexistent/dir/model.json"));
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{ not json").unwrap();
    let err = ModelFile::load(&bad).unwrap_err().to_string();
    assert!(
        err.contains("bad.json") && err.contains("not a valid"),
        "{err}"
    );
    let future = dir.path().join("future.json");
    std::fs::write(&future, r#"{"format_version": 7, "whatever": true}"#).unwrap();
    let err = ModelFile::load(&future).unwrap_err().to_string();
    assert!(
        err.contains("future.json") && err.contains("format_version 7"),
        "{err}"
    );
}

#[test]
fn predict_runs_the_model_in_physical_units_from_zero_memory() {
    let file = ModelFile::load(&example("table1-plant.json")).unwrap();
    let volts: Vec<f64> = (0..500)
        .map(|k| 5.0 + 4.9 * (k as f64 * 0.03).sin())
        .collect();
    let predicted = file.predict(&volts).unwrap();
    let mut model = file.model().unwrap();
    for (v, y) in volts.iter().zip(&predicted) {
        // physical = offset + scale * P[(v - offset) / scale]
        let expected = file.output.offset
            + file.output.scale * model.step((v - file.input.offset) / file.input.scale);
        assert_eq!(*y, expected);
    }
    // The model was identified on 0..10 V (normalised 0..1).
    assert_eq!(
        file.count_outside_input_range(&[-0.1, 0.0, 5.0, 10.0, 10.5]),
        2
    );
    // From rest, a rise to full scale ends on the major loop's top: 75 um x P[1].
    let top = file.predict(&[2.5, 5.0, 7.5, 10.0]).unwrap()[3];
    assert!(
        (top - 75.0
            * hystcomp_core::paper::TABLE1
                .model::<f64, Vec<f64>>()
                .unwrap()
                .step(1.0))
        .abs()
            < 1e-9
    );
}

/// How many times `needle` occurs in `text`.
fn occurrences(text: &str, needle: &str) -> usize {
    text.matches(needle).count()
}

#[test]
fn a_directory_or_a_missing_folder_is_refused_naming_the_path_once() {
    let dir = tempfile::tempdir().unwrap();
    // A directory where the model file should be.
    let err = ModelFile::load(dir.path()).unwrap_err();
    assert!(matches!(err, ModelFileError::Io { .. }), "{err:?}");
    let text = err.to_string();
    let shown = dir.path().display().to_string();
    assert!(text.contains("is a directory"), "{text}");
    assert_eq!(occurrences(&text, &shown), 1, "{text}");
    // Saving into a folder that does not exist: the path once, the reason in plain words, and
    // no temporary file name.
    let file = ModelFile::load(&example("table1-plant.json")).unwrap();
    let target = dir.path().join("missing").join("model.json");
    let err = file.save(&target).unwrap_err();
    let text = err.to_string();
    assert_eq!(
        occurrences(&text, &target.display().to_string()),
        1,
        "{text}"
    );
    assert!(text.contains("does not exist"), "{text}");
    assert!(
        !text.contains(".model.json.") && !text.contains("at path"),
        "{text}"
    );
    // Saving over a directory.
    let err = file.save(dir.path()).unwrap_err().to_string();
    assert_eq!(occurrences(&err, &shown), 1, "{err}");
    assert!(err.contains("directory"), "{err}");
}

/// Issue 13 item 8: a saved model reloads bit for bit (serde_json's `float_roundtrip`): random
/// parameters and scales of every magnitude a model file accepts, through `to_json` and
/// `from_json` and through a file.
mod round_trip {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngSeed};

    /// Any normal or zero f64 within `[-bound, bound]`, with every mantissa pattern.
    fn within(bound: f64) -> impl Strategy<Value = f64> {
        (prop::num::f64::NORMAL | prop::num::f64::ZERO).prop_map(move |x| {
            if x.abs() <= bound {
                x
            } else {
                // Keep the mantissa, move the exponent into range.
                let scaled =
                    x / 2f64.powi(x.abs().log2().ceil() as i32 - bound.log2().floor() as i32);
                scaled.clamp(-bound, bound)
            }
        })
    }

    fn model() -> impl Strategy<Value = ModelFile> {
        (1usize..30).prop_flat_map(|n| {
            (
                prop::collection::vec(within(1.0).prop_map(f64::abs), n),
                prop::collection::vec(within(0.01), n),
                within(0.05),
                (0.5f64..2.0, within(1.0)).prop_map(|(a, b)| a + b.abs()),
                (within(1e6), 1e-3f64..1e6),
                (within(1e6), 1e-3f64..1e6),
            )
                .prop_map(|(mut r, b, a1, a2, (oi, si), (oo, so))| {
                    r.sort_by(f64::total_cmp);
                    r.dedup();
                    r[0] = 0.0;
                    let n = r.len();
                    let s = |unit: &str, offset, scale| Scale {
                        quantity: unit.into(),
                        unit: unit.into(),
                        offset,
                        scale,
                    };
                    ModelFile::new(
                        Direction::Plant,
                        s("V", oi, si),
                        s("um", oo, so),
                        [0.0, 1.0],
                        r,
                        b[..n].to_vec(),
                        a1,
                        a2,
                    )
                    .expect("a valid random model")
                })
        })
    }

    fn bits(file: &ModelFile) -> Vec<u64> {
        let mut all = vec![
            file.input.offset,
            file.input.scale,
            file.output.offset,
            file.output.scale,
            file.a1,
            file.a2,
        ];
        all.extend(&file.thresholds);
        all.extend(&file.weights);
        all.iter().map(|x| x.to_bits()).collect()
    }

    proptest! {
        #![proptest_config(Config {
            cases: 256,
            rng_seed: RngSeed::Fixed(0x726f_756e_6474_7269),
            failure_persistence: None,
            ..Config::default()
        })]

        #[test]
        fn a_saved_model_reloads_bit_for_bit(file in model()) {
            let back = ModelFile::from_json(&file.to_json()).unwrap();
            prop_assert_eq!(bits(&back), bits(&file));
        }
    }

    #[test]
    fn through_a_file_too() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        let mut runner = proptest::test_runner::TestRunner::new(Config {
            rng_seed: RngSeed::Fixed(7),
            ..Config::default()
        });
        for _ in 0..20 {
            let file =
                proptest::strategy::ValueTree::current(&model().new_tree(&mut runner).unwrap());
            file.save(&path).unwrap();
            assert_eq!(bits(&ModelFile::load(&path).unwrap()), bits(&file));
        }
    }
}

/// Python's `json.dump` writes `NaN`, `Infinity` and `-Infinity` for non-finite floats: the
/// message says what the token is and what to do, with the line.
#[test]
fn a_bare_nan_token_is_named() {
    let text = std::fs::read_to_string(example("table1-plant.json")).unwrap();
    for (token, python) in [("NaN", "nan"), ("Infinity", "inf"), ("-Infinity", "inf")] {
        let edited = text.replacen("\"a1\": -0.1569", &format!("\"a1\": {token}"), 1);
        assert_ne!(edited, text, "the example's a1 line");
        let err = ModelFile::from_json(&edited).unwrap_err().to_string();
        // Text has no path: the message names the JSON text, not an empty path.
        assert!(
            err.starts_with("the JSON text is not a valid hystcomp model file"),
            "{err}"
        );
        for fragment in [
            format!("bare {token}"),
            "json.dump".to_owned(),
            format!("float('{python}')"),
            "line ".to_owned(),
        ] {
            assert!(err.contains(&fragment), "{fragment:?} not in {err}");
        }
        let in_list = text.replacen("0.2313", token, 1);
        let err = ModelFile::from_json(&in_list).unwrap_err().to_string();
        assert!(err.contains(&format!("bare {token}")), "{err}");
    }
    // Other syntax errors keep serde_json's own message.
    let err = ModelFile::from_json("{ \"a1\": nope }")
        .unwrap_err()
        .to_string();
    assert!(!err.contains("bare"), "{err}");
}

/// Sizes and scales a model file may not have (issue 13 items 3 and 5): too many operators,
/// scales that lose or overflow every value, a file too large to be a model.
#[test]
fn sizes_and_scales_are_bounded() {
    use hystcomp_io::model_file::{MAX_MODEL_FILE_BYTES, MAX_OPERATORS};
    let many = refusal(|v| {
        let n = MAX_OPERATORS + 1;
        v["thresholds"] = (0..n)
            .map(|i| i as f64 / n as f64)
            .collect::<Vec<_>>()
            .into();
        v["weights"] = vec![1e-6; n].into();
    });
    assert!(
        many.contains("10001 play operators") && many.contains("10000"),
        "{many}"
    );
    for (field, value, fragment) in [
        ("scale", 5e-324, "output.scale must lie in [1e-12, 1e12]"),
        ("scale", 1e-13, "output.scale"),
        ("scale", 1e13, "output.scale"),
        ("offset", 1e16, "|output.offset|"),
    ] {
        let err = refusal(|v| v["output"][field] = value.into());
        assert!(err.contains(fragment), "{field} {value}: {err}");
    }
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.json");
    let file = std::fs::File::create(&big).unwrap();
    file.set_len(MAX_MODEL_FILE_BYTES + 1).unwrap();
    let err = ModelFile::load(&big).unwrap_err().to_string();
    assert!(err.contains("big.json") && err.contains("16 MiB"), "{err}");
    // Nor is such a file written: a description of 17 MiB is refused before writing, so no
    // saved model is one that cannot be loaded back (and an old file there stays as it was).
    let mut file = ModelFile::load(&example("table1-plant.json")).unwrap();
    let path = dir.path().join("described.json");
    std::fs::write(&path, "old").unwrap();
    file.description = Some("x".repeat(17 << 20));
    let err = file.save(&path).unwrap_err().to_string();
    assert!(
        err.contains("described.json") && err.contains("16 MiB") && err.contains("description"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
    // Just below the bound it is written and reads back.
    let room = (MAX_MODEL_FILE_BYTES as usize) + (17 << 20) - 1 - file.to_json().len();
    file.description = Some("x".repeat(room));
    file.save(&path).unwrap();
    assert_eq!(ModelFile::load(&path).unwrap(), file_with_version(file));
}

/// `file` as it reads back: written as the current format version.
fn file_with_version(file: ModelFile) -> ModelFile {
    ModelFile {
        format_version: hystcomp_io::model_file::FORMAT_VERSION,
        ..file
    }
}

/// A normalised parameter beyond 1e15 in magnitude is refused, named by field and index (a
/// weight of 1e300 made the compensators drive a flat 0 V); 1e15 itself loads.
#[test]
fn parameters_beyond_1e15_are_refused() {
    for (field, index) in [("weights", 3), ("thresholds", 9), ("input_range", 1)] {
        let message = refusal(|v| v[field][index] = 1e300.into());
        assert!(message.contains(&format!("{field}[{index}]")), "{message}");
        assert!(message.contains("1e15"), "{message}");
    }
    assert!(refusal(|v| v["a1"] = (-2e15).into()).contains("a1[0]"));
    let text = std::fs::read_to_string(example("table1-plant.json")).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value["a2"] = 1e15.into();
    // Loads as far as the bound goes (the model may be refused for other reasons, not this).
    if let Err(e) = ModelFile::from_json(&value.to_string()) {
        assert!(!e.to_string().contains("beyond 1e15"), "{e}");
    }
}

/// A file beginning with a UTF-8 byte-order mark (as some Windows editors save) loads as the
/// same model.
#[test]
fn a_byte_order_mark_is_not_part_of_the_json() {
    let text = std::fs::read_to_string(example("table1-plant.json")).unwrap();
    let plain = ModelFile::from_json(&text).unwrap();
    let marked = ModelFile::from_json(&format!("\u{feff}{text}")).unwrap();
    assert_eq!(plain, marked);
}
