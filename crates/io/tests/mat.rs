//! Tests of reading MATLAB Level-5 MAT-files: files written by the tests' own writer
//! (`common/mat5.rs`) and by scipy (`fixtures/`), damaged and crafted files.

mod common;

use common::*;

use std::fs;

use hystcomp_io::data::{Column, DataError, ReadOptions, read_columns};
use mat5::{Values, Variable, var};

#[test]
fn level5_vectors_read_exactly_in_every_layout() {
    let u = [1.8, 1.856_539, -0.0, 1e-300, 3.6];
    let y = [-123.059_139, -120.0, -114.5, -100.25, -74.0];
    let dir = dir();
    for big_endian in [false, true] {
        for compressed in [false, true] {
            let path = file(
                dir.path(),
                "record.mat",
                mat5::file(
                    &[var("u", &[5, 1], &u), var("y", &[1, 5], &y)],
                    big_endian,
                    compressed,
                ),
            );
            let read = read(&path, &["y", "u"]).unwrap_or_else(|e| {
                panic!("big endian {big_endian}, compressed {compressed}: {e}")
            });
            assert_eq!(read.names, ["y", "u"]);
            assert_eq!(bits(&read.values[0]), bits(&y));
            assert_eq!(bits(&read.values[1]), bits(&u));
        }
    }
}

#[test]
fn level5_files_are_found_by_content_whatever_the_extension() {
    let dir = dir();
    let path = file(
        dir.path(),
        "record.bin",
        mat5::file(&[var("u", &[3, 1], &[1.0, 2.0, 3.0])], false, false),
    );
    let read = read(&path, &["u"]).expect("reading");
    assert_eq!(read.values, vec![vec![1.0, 2.0, 3.0]]);
}

#[test]
fn level5_matrix_columns_are_selected_as_name_colon_k() {
    // data = [t u y] with 4 rows, stored column by column.
    let data = [
        0.0, 0.005, 0.01, 0.015, // t
        1.0, 2.0, 3.0, 4.0, // u
        -1.0, -2.0, -3.0, -4.0, // y
    ];
    let dir = dir();
    let path = file(
        dir.path(),
        "data.mat",
        mat5::file(&[var("data", &[4, 3], &data)], false, false),
    );
    let read = read(&path, &["data:3", "data:1"]).expect("columns of a matrix");
    assert_eq!(read.names, ["data:3", "data:1"]);
    assert_eq!(read.values, vec![data[8..12].to_vec(), data[0..4].to_vec()]);
    // The only variable: a number picks its column.
    let read = read_columns(&path, &[Column::Index(2)], &ReadOptions::default()).expect("index");
    assert_eq!(read.values, vec![data[4..8].to_vec()]);

    let (error, message) = read_error(&path, &["data"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::UnusableVariable { .. }),
        "{error:?}"
    );
    assert_contains(
        &message,
        &["data.mat", "\"data\"", "4×3", "data:1 to data:3"],
    );
    let (error, message) = read_error(&path, &["data:4"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::UnusableVariable { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["data:4", "3 columns"]);
}

#[test]
fn level5_integers_convert_and_ranges_select_samples() {
    let dir = dir();
    let path = file(
        dir.path(),
        "ints.mat",
        mat5::file(
            &[
                Variable {
                    name: "counts",
                    dims: &[1, 5],
                    values: Values::Int16(&[-2, -1, 0, 1, 30_000]),
                },
                Variable {
                    name: "small",
                    dims: &[5, 1],
                    values: Values::DoubleAsUInt8(&[0, 1, 2, 200, 255]),
                },
                Variable {
                    name: "medium",
                    dims: &[5, 1],
                    values: Values::DoubleAsInt16(&[-300, -1, 0, 1, 300]),
                },
            ],
            true,
            false,
        ),
    );
    let read = read(&path, &["counts", "small", "medium"]).expect("reading");
    assert_eq!(
        read.values,
        vec![
            vec![-2.0, -1.0, 0.0, 1.0, 30_000.0],
            vec![0.0, 1.0, 2.0, 200.0, 255.0],
            vec![-300.0, -1.0, 0.0, 1.0, 300.0],
        ]
    );
    let options = ReadOptions {
        rows: Some("2..4".parse().expect("a range")),
        ..ReadOptions::default()
    };
    let part = read_with(&path, &["counts"], &options).expect("reading a range");
    assert_eq!(part.values, vec![vec![-1.0, 0.0, 1.0]]);
    assert_eq!(part.first_row, 2);
    let options = ReadOptions {
        rows: Some("4..6".parse().expect("a range")),
        ..ReadOptions::default()
    };
    let (error, _) = read_error(&path, &["counts"], &options);
    assert!(matches!(
        error,
        DataError::RowsOutOfRange { available: 5, .. }
    ));

    // The only variable is a vector: column 1 is the vector, column 2 does not exist.
    let path = file(
        dir.path(),
        "one.mat",
        mat5::file(&[var("u", &[1, 3], &[4.0, 5.0, 6.0])], false, true),
    );
    let all = read_columns(&path, &[Column::Index(1)], &ReadOptions::default()).expect("index");
    assert_eq!(all.values, vec![vec![4.0, 5.0, 6.0]]);
    let (error, _) = read_error(&path, &["2"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::UnusableVariable { .. }),
        "{error:?}"
    );
}

/// Every numeric class reads, in both byte orders, compressed or not (the `matfile` crate
/// refused int32 and printed "Unsupported variable type: Int8" on stdout; issue 13 item 4).
#[test]
fn level5_every_numeric_class_reads() {
    let dir = dir();
    for big_endian in [false, true] {
        for compressed in [false, true] {
            let bytes = mat5::file(
                &[
                    Variable {
                        name: "i32",
                        dims: &[3, 1],
                        values: Values::Int32(&[-7, 0, 2_000_000_000]),
                    },
                    Variable {
                        name: "i8",
                        dims: &[3, 1],
                        values: Values::Int8(&[-128, 0, 127]),
                    },
                    Variable {
                        name: "f32",
                        dims: &[1, 3],
                        values: Values::Single(&[0.1, -2.5, 3e14]),
                    },
                    Variable {
                        name: "u64",
                        dims: &[3, 1],
                        values: Values::UInt64(&[0, 1 << 49, 999_999_999_999_999]),
                    },
                ],
                big_endian,
                compressed,
            );
            let path = file(dir.path(), "classes.mat", bytes);
            let read = read(&path, &["i32", "i8", "f32", "u64"]).expect("every class");
            assert_eq!(read.values[0], [-7.0, 0.0, 2e9]);
            assert_eq!(read.values[1], [-128.0, 0.0, 127.0]);
            assert_eq!(
                read.values[2],
                [f64::from(0.1f32), -2.5, f64::from(3e14f32)]
            );
            assert_eq!(read.values[3], [0.0, 2f64.powi(49), 999_999_999_999_999.0]);
        }
    }
}

/// Values beyond 1e15 in magnitude are refused when read, as in text files (their squares
/// and sums would overflow the indices), with the variable and the sample.
#[test]
fn level5_values_beyond_the_magnitude_bound_are_refused() {
    let dir = dir();
    let path = file(
        dir.path(),
        "huge.mat",
        mat5::file(
            &[
                var("u", &[3, 1], &[1.0, 1e300, 3.0]),
                Variable {
                    name: "n",
                    dims: &[2, 1],
                    values: Values::UInt64(&[1, u64::MAX]),
                },
            ],
            false,
            true,
        ),
    );
    for (column, sample) in [("u", "sample 2"), ("n", "sample 2")] {
        let (error, message) = read_error(&path, &[column], &ReadOptions::default());
        assert!(
            matches!(error, DataError::OutOfRange { row: 2, .. }),
            "{error:?}"
        );
        assert_contains(&message, &["huge.mat", sample, "1e15"]);
    }
}

/// A Level-5 file with one variable of `dims` (written as given, negative ones too) holding
/// `values`.
fn crafted(dims: &[i64], values: &[f64], big_endian: bool, compressed: bool) -> Vec<u8> {
    mat5::file(&[var("u", dims, values)], big_endian, compressed)
}

/// Dimensions that are negative, that multiply beyond any size, or that disagree with the
/// values stored are refused with a message naming the file, never a panic (issue 13 item 2:
/// -1 read as usize::MAX made a size check wrap and a slice index panic).
#[test]
fn crafted_dimensions_are_refused_without_a_panic() {
    let dir = dir();
    let three = [1.0, 2.0, 3.0];
    let cases: [(&[i64], &[f64], &str); 7] = [
        (&[-1, 1], &three, "negative dimension (-1)"),
        (&[3, -1], &three, "negative dimension (-1)"),
        (&[-1, -3], &three, "negative dimension"),
        (&[i64::from(i32::MIN), 1], &three, "negative dimension"),
        (
            &[65_536, 65_536, 65_536, 65_536, 65_536],
            &[],
            "multiply beyond",
        ),
        (
            &[i64::from(i32::MAX), i64::from(i32::MAX)],
            &three,
            "damaged",
        ),
        (&[4, 1], &three, "damaged"),
    ];
    for (dims, values, fragment) in cases {
        for big_endian in [false, true] {
            for compressed in [false, true] {
                let path = file(
                    dir.path(),
                    "crafted.mat",
                    crafted(dims, values, big_endian, compressed),
                );
                for column in [&["u"][..], &["u:1"], &["1"]] {
                    let (error, message) = read_error(&path, column, &ReadOptions::default());
                    assert!(
                        matches!(error, DataError::MatUnreadable { .. }),
                        "{dims:?}: {error:?}"
                    );
                    assert_contains(&message, &["crafted.mat", fragment]);
                }
            }
        }
    }
}

#[test]
fn level5_problems_are_explained() {
    let dir = dir();
    let path = file(
        dir.path(),
        "several.mat",
        mat5::file(
            &[
                var("u", &[3, 1], &[1.0, 2.0, 3.0]),
                var("y", &[2, 1], &[1.0, 2.0]),
                var("bad", &[3, 1], &[1.0, f64::NAN, 3.0]),
                var("cube", &[2, 2, 2], &[0.0; 8]),
                Variable {
                    name: "z",
                    dims: &[3, 1],
                    values: Values::Complex(&[1.0, 2.0, 3.0], &[0.0, 1.0, 0.0]),
                },
            ],
            false,
            false,
        ),
    );
    let (error, message) = read_error(&path, &["voltage"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::NoSuchVariable { .. }),
        "{error:?}"
    );
    assert_contains(
        &message,
        &[
            "several.mat",
            "\"voltage\"",
            "u (3×1 double)",
            "y (2×1 double)",
        ],
    );

    let (error, message) = read_error(&path, &["1"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::NoSuchVariable { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["column 1", "variable name"]);

    let (error, message) = read_error(&path, &["u", "y"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::LengthMismatch { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["several.mat", "u: 3", "y: 2"]);

    let (error, message) = read_error(&path, &["bad"], &ReadOptions::default());
    assert!(
        matches!(
            error,
            DataError::NotFinite {
                row: 2,
                line: None,
                ..
            }
        ),
        "{error:?}"
    );
    assert_contains(&message, &["several.mat", "\"bad\"", "sample 2", "NaN"]);

    let (error, message) = read_error(&path, &["cube"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::UnusableVariable { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["2×2×2", "more than two dimensions"]);

    let (error, message) = read_error(&path, &["z"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::UnusableVariable { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["\"z\"", "complex", "real("]);
}

#[test]
fn level5_files_written_by_scipy_read_exactly() {
    // Written by scipy.io.savemat (see tests/fixtures/README.md): k = 0..9, t = k/200,
    // u = k/4 - 1 (columns), y = k/2 - 100 (a row), data = [t u y], counts = int16(-5..4),
    // plus a char and a struct variable, which are skipped.
    let k: Vec<f64> = (0..10).map(f64::from).collect();
    let t: Vec<f64> = k.iter().map(|k| k / 200.0).collect();
    let u: Vec<f64> = k.iter().map(|k| k * 0.25 - 1.0).collect();
    let y: Vec<f64> = k.iter().map(|k| -100.0 + k * 0.5).collect();
    for name in ["scipy_record.mat", "scipy_record_compressed.mat"] {
        let path = fixture(name);
        let read = read(
            &path,
            &["t", "u", "y", "data:1", "data:2", "data:3", "counts"],
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(read.len(), 10);
        for (got, expected) in read.values.iter().zip([&t, &u, &y, &t, &u, &y]) {
            assert_eq!(bits(got), bits(expected), "{name}");
        }
        assert_eq!(read.values[6], (-5..5).map(f64::from).collect::<Vec<_>>());
        let (error, message) = read_error(&path, &["note"], &ReadOptions::default());
        assert!(
            matches!(error, DataError::NoSuchVariable { .. }),
            "{error:?}"
        );
        assert_contains(
            &message,
            &["\"note\"", "t (10×1 double)", "data (10×3 double)"],
        );
    }
}

#[test]
fn v73_files_ask_to_resave_with_v7() {
    let dir = dir();
    let path = file(dir.path(), "big.mat", mat5::v73_stub());
    let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
    assert!(matches!(error, DataError::MatV73 { .. }), "{error:?}");
    assert_contains(&message, &["big.mat", "v7.3", "'-v7'"]);

    // The HDF5 signature alone (a header written by another tool) is enough.
    let mut bytes = vec![b' '; 512];
    bytes.extend_from_slice(b"\x89HDF\r\n\x1a\n");
    let path = file(dir.path(), "other.mat", bytes);
    let (error, _) = read_error(&path, &["u"], &ReadOptions::default());
    assert!(matches!(error, DataError::MatV73 { .. }), "{error:?}");
}

#[test]
fn other_mat_files_get_a_clear_message() {
    let dir = dir();
    // A Level-4 file starts with a 20-byte binary header (type, rows, cols, imag, name length).
    let mut v4 = Vec::new();
    for n in [0u32, 3, 1, 0, 2] {
        v4.extend_from_slice(&n.to_le_bytes());
    }
    v4.extend_from_slice(b"u\0");
    for x in [1.0f64, 2.0, 3.0] {
        v4.extend_from_slice(&x.to_le_bytes());
    }
    let path = file(dir.path(), "old.mat", v4);
    let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::UnsupportedFormat { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["old.mat", "v4", "'-v7'"]);

    // Text saved by MATLAB with -ascii under a .mat name is read as text.
    let path = file(
        dir.path(),
        "ascii.mat",
        "   1.0000000e+00   2.5000000e+00\n   3.0000000e+00  -4.0000000e+00\n",
    );
    let read = read(&path, &["2"]).expect("an -ascii file");
    assert_eq!(read.values, vec![vec![2.5, -4.0]]);

    // A Level-5 header followed by garbage.
    let mut damaged = mat5::file(&[var("u", &[3, 1], &[1.0, 2.0, 3.0])], false, false);
    damaged.truncate(128 + 40);
    damaged.extend_from_slice(&[0xff; 24]);
    let path = file(dir.path(), "damaged.mat", damaged);
    let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
    assert!(
        matches!(
            error,
            DataError::MatUnreadable { .. } | DataError::NoSuchVariable { .. }
        ),
        "{error:?}"
    );
    assert_contains(&message, &["damaged.mat"]);
}

/// A Level-5 file cut short anywhere after its header (a partial copy or download) says it is
/// truncated or damaged, never that it holds no variables, and never panics.
#[test]
fn truncated_level5_files_say_they_are_truncated() {
    let dir = dir();
    for name in ["scipy_record.mat", "scipy_record_compressed.mat"] {
        let bytes = fs::read(fixture(name)).expect("the fixture");
        // The element boundaries (cut there, the file is a valid file with fewer variables).
        let mut boundaries = vec![128];
        while let Some(&at) = boundaries.last().filter(|&&at| at < bytes.len()) {
            let word = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
            let (kind, size) = (word(at), word(at + 4));
            boundaries.push(
                at + 8
                    + if kind == 15 {
                        size
                    } else {
                        size.div_ceil(8) * 8
                    },
            );
        }
        assert_eq!(boundaries.last(), Some(&bytes.len()), "{name}: the walk");
        let mut lengths: Vec<usize> = (129..bytes.len()).step_by(7).collect();
        lengths.extend([129, 136, bytes.len() - 1]);
        for len in lengths.into_iter().filter(|len| !boundaries.contains(len)) {
            let path = file(dir.path(), "cut.mat", &bytes[..len]);
            let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
            assert!(
                matches!(error, DataError::MatUnreadable { .. }),
                "{name} cut at {len}: {error:?}"
            );
            assert_contains(&message, &["cut.mat", "truncated or damaged"]);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Properties on many seeded random files (the fuzz target `mat` checks the same without a seed)
// ---------------------------------------------------------------------------------------------

mod properties {
    use super::*;
    use hystcomp_io::data::read_bytes;
    use proptest::prelude::*;
    use std::path::Path;

    /// Up to 3 dimensions of 0 to 5, values to fill them, as doubles or int16.
    fn variable() -> impl Strategy<Value = (Vec<i64>, Vec<f64>, bool)> {
        (prop::collection::vec(0i64..=5, 2..=3), any::<bool>()).prop_flat_map(|(dims, ints)| {
            let n = dims.iter().product::<i64>() as usize;
            let values = if ints {
                prop::collection::vec((-30_000i32..30_000).prop_map(f64::from), n).boxed()
            } else {
                prop::collection::vec(
                    (prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO)
                        .prop_map(|mut x| {
                            // Scaled by powers of two into the magnitude a record may hold.
                            while x.abs() > 1e15 {
                                x /= 2f64.powi(64);
                            }
                            x
                        }),
                    n,
                )
                .boxed()
            };
            (Just(dims), values, Just(ints))
        })
    }

    proptest! {
        #![proptest_config(seeded(128, 0x6d61_7466_696c_6535))]

        /// What the tests' writer writes, the reader reads bit for bit: vectors by name,
        /// matrices column by column as name:k.
        #[test]
        fn random_variables_read_back_exactly(
            (dims, values, ints) in variable(),
            big_endian in any::<bool>(),
            compressed in any::<bool>(),
        ) {
            let int16: Vec<i16> = values.iter().map(|&v| v as i16).collect();
            let variable = Variable {
                name: "x",
                dims: &dims,
                values: if ints { Values::Int16(&int16) } else { Values::Double(&values) },
            };
            let bytes = mat5::file(&[variable], big_endian, compressed);
            let path = Path::new("random.mat");
            let read = |column: &str| {
                read_bytes(path, &bytes, &[column.parse().unwrap()], &ReadOptions::default())
            };
            let non_singleton = dims.iter().filter(|&&d| d != 1).count();
            if values.is_empty() {
                prop_assert!(read("x").is_err());
            } else if non_singleton <= 1 {
                prop_assert_eq!(bits(&read("x").unwrap().values[0]), bits(&values));
            } else if dims.len() == 2 {
                let rows = dims[0] as usize;
                for k in 1..=dims[1] as usize {
                    let column = read(&format!("x:{k}")).unwrap();
                    prop_assert_eq!(
                        bits(&column.values[0]),
                        bits(&values[(k - 1) * rows..k * rows])
                    );
                }
            } else {
                let unusable = matches!(read("x"), Err(DataError::UnusableVariable { .. }));
                prop_assert!(unusable, "a 3-D array is refused as unusable");
            }
        }

        /// Damaged files (bytes overwritten, cut short, inserted) give a result or an error
        /// naming the file, never a panic.
        #[test]
        fn damaged_files_never_panic(
            big_endian in any::<bool>(),
            compressed in any::<bool>(),
            edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 1..8),
        ) {
            let mut bytes = mat5::file(
                &[var("u", &[4, 1], &[1.0, 2.0, 3.0, 4.0]), var("m", &[2, 2], &[5.0, 6.0, 7.0, 8.0])],
                big_endian,
                compressed,
            );
            for (at, byte, kind) in edits {
                // Edits after the header, so that the file stays a MAT-file.
                let at = 128 + at.index(bytes.len() - 128);
                match kind {
                    0 => bytes[at] = byte,
                    1 => bytes.truncate(at.max(129)),
                    _ => bytes.insert(at, byte),
                }
            }
            for column in ["u", "m:2", "1", "m"] {
                let result = read_bytes(
                    Path::new("damaged.mat"),
                    &bytes,
                    &[column.parse().unwrap()],
                    &ReadOptions::default(),
                );
                if let Err(error) = result {
                    prop_assert!(error.to_string().contains("damaged.mat"), "{}", error);
                }
            }
        }
    }
}
