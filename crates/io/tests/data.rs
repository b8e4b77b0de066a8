//! Tests of reading text records, writing CSV and the checks (MAT-files: `mat.rs`; atomic
//! writes: `atomic.rs`).

mod common;

use common::*;

use std::fs;
use std::path::PathBuf;

use hystcomp_io::data::{
    Column, DataError, Delimiter, Header, MAX_MAGNITUDE, ReadOptions, RowRange, check_finite,
    check_min_samples, check_not_constant, check_same_length, check_time_increasing,
    encode_delimited, mean_time_step, read_columns, write_csv, write_delimited,
};
use proptest::prelude::*;

const ALL_DELIMITERS: [Delimiter; 4] = [
    Delimiter::Comma,
    Delimiter::Tab,
    Delimiter::Semicolon,
    Delimiter::Whitespace,
];

// ---------------------------------------------------------------------------------------------
// Round trips (property tests, fixed seed)
// ---------------------------------------------------------------------------------------------

/// `x` scaled by powers of two (which keeps its mantissa) into the magnitude a record may hold.
fn within_magnitude(mut x: f64) -> f64 {
    while x.abs() > MAX_MAGNITUDE {
        x /= 2f64.powi(64);
    }
    x
}

/// Any f64 a record may hold, from subnormals to the largest magnitude (1e15), with every
/// mantissa, plus values of everyday size.
fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        (prop::num::f64::POSITIVE
            | prop::num::f64::NEGATIVE
            | prop::num::f64::NORMAL
            | prop::num::f64::SUBNORMAL
            | prop::num::f64::ZERO)
            .prop_map(within_magnitude),
        Just(MAX_MAGNITUDE),
        Just(-MAX_MAGNITUDE),
        -1e3..1e3_f64,
        (-100_000i32..100_000).prop_map(|k| f64::from(k) / 1000.0),
    ]
}

/// 1 to 4 columns of 1 to 30 finite values each, all of one length.
fn table() -> impl Strategy<Value = Vec<Vec<f64>>> {
    (1usize..=4, 1usize..=30).prop_flat_map(|(columns, rows)| {
        prop::collection::vec(prop::collection::vec(finite(), rows), columns)
    })
}

proptest! {
    #![proptest_config(seeded(64, 0x6879_7374_636f_6d70))]

    #[test]
    fn written_columns_read_back_exactly_with_every_delimiter_and_header(
        table in table(),
        delimiter_index in 0usize..4,
        with_header in any::<bool>(),
        auto_detect in any::<bool>(),
        suffix in "[a-z]{0,6}",
    ) {
        let delimiter = ALL_DELIMITERS[delimiter_index];
        let dir = dir();
        let path = dir.path().join("round-trip.txt");
        let names: Vec<String> = (0..table.len()).map(|i| format!("c{i}_{suffix}")).collect();
        let header: Vec<&str> = if with_header {
            names.iter().map(String::as_str).collect()
        } else {
            Vec::new()
        };
        let slices: Vec<&[f64]> = table.iter().map(Vec::as_slice).collect();
        write_delimited(&path, &header, &slices, delimiter).expect("writing");
        // The encoding alone is the file's bytes, and writes nothing.
        let elsewhere = dir.path().join("encoded-only.txt");
        let encoded = encode_delimited(&elsewhere, &header, &slices, delimiter).expect("encoding");
        prop_assert_eq!(&encoded, &fs::read(&path).expect("the written file"));
        prop_assert!(!elsewhere.exists());

        let options = if auto_detect {
            ReadOptions::default()
        } else {
            ReadOptions {
                delimiter,
                header: if with_header { Header::Present } else { Header::Absent },
                rows: None,
            }
        };
        let by_index: Vec<Column> = (1..=table.len()).map(Column::Index).collect();
        let read = read_columns(&path, &by_index, &options).expect("reading back");
        prop_assert_eq!(read.values.len(), table.len());
        for (got, written) in read.values.iter().zip(&table) {
            prop_assert_eq!(bits(got), bits(written));
        }
        prop_assert_eq!(read.first_row, 1);
        prop_assert_eq!(read.len(), table[0].len());
        if with_header {
            prop_assert_eq!(&read.names, &names);
            // Selecting by name gives the same columns as selecting by index.
            let by_name: Vec<Column> = names.iter().rev().map(|n| Column::Name(n.clone())).collect();
            let read_by_name = read_columns(&path, &by_name, &options).expect("reading by name");
            for (got, expected) in read_by_name.values.iter().zip(read.values.iter().rev()) {
                prop_assert_eq!(bits(got), bits(expected));
            }
        } else {
            let expected: Vec<String> = (1..=table.len()).map(|k| format!("column {k}")).collect();
            prop_assert_eq!(&read.names, &expected);
        }
    }

    #[test]
    fn a_row_range_reads_exactly_those_rows(
        table in table(),
        a in 0usize..30,
        b in 0usize..30,
        open_end in any::<bool>(),
    ) {
        let rows = table[0].len();
        let (first, last) = (a.min(b) % rows + 1, a.max(b) % rows + 1);
        let (first, last) = (first.min(last), first.max(last));
        let dir = dir();
        let path = dir.path().join("range.csv");
        let slices: Vec<&[f64]> = table.iter().map(Vec::as_slice).collect();
        write_csv(&path, &[], &slices).expect("writing");
        let range = RowRange::new(first, if open_end { None } else { Some(last) }).expect("a range");
        let end = if open_end { rows } else { last };
        let options = ReadOptions { rows: Some(range), ..ReadOptions::default() };
        let read = read_columns(&path, &[Column::Index(1)], &options).expect("reading a range");
        prop_assert_eq!(bits(&read.values[0]), bits(&table[0][first - 1..end]));
        prop_assert_eq!(read.first_row, first);
        prop_assert_eq!(read.file_row(1), first);
    }
}

#[test]
fn write_csv_writes_the_shortest_exact_text() {
    let dir = dir();
    let path = dir.path().join("out.csv");
    write_csv(
        &path,
        &["time_s", "voltage, V"],
        &[&[0.0, 0.005, 1e-7], &[1.8, -0.0, 1e15]],
    )
    .expect("writing");
    let text = fs::read_to_string(&path).expect("reading the text");
    assert_eq!(
        text,
        "time_s,\"voltage, V\"\n0.0,1.8\n0.005,-0.0\n1e-7,1000000000000000.0\n"
    );
    let read = read(&path, &["voltage, V"]).expect("reading a quoted name back");
    assert_eq!(bits(&read.values[0]), bits(&[1.8, -0.0, 1e15]));
}

// ---------------------------------------------------------------------------------------------
// Text formats accepted
// ---------------------------------------------------------------------------------------------

#[test]
fn comments_blank_lines_bom_and_crlf_are_accepted() {
    let dir = dir();
    let path = file(
        dir.path(),
        "logger.csv",
        "\u{feff}# recorded 2024-05-01\r\n% sample rate 200 Hz\r\n\r\ntime, Voltage (V) ,\"Position, um\"\r\n0.000,1.5,-3\r\n   \r\n  # a note in the middle\r\n0.005,1.6,-2.5\r\n",
    );
    let read = read(&path, &["Position, um", "2", "time"]).expect("reading");
    assert_eq!(read.names, ["Position, um", "Voltage (V)", "time"]);
    assert_eq!(
        read.values,
        vec![vec![-3.0, -2.5], vec![1.5, 1.6], vec![0.0, 0.005]]
    );
}

#[test]
fn whitespace_aligned_columns_are_read() {
    let dir = dir();
    let path = file(
        dir.path(),
        "aligned.txt",
        "  t      u        y\n  0.0    1.0e+00  -2\n  0.5   -1.5e-01   4.25\n",
    );
    let read = read(&path, &["y", "u"]).expect("reading");
    assert_eq!(read.values, vec![vec![-2.0, 4.25], vec![1.0, -0.15]]);
}

#[test]
fn semicolon_files_and_names_ignoring_case_are_read() {
    let dir = dir();
    let path = file(dir.path(), "semi.csv", "Time;Voltage\n0;1.25\n1;2.5\n");
    let read = read(&path, &["voltage"]).expect("reading");
    assert_eq!(read.names, ["Voltage"]);
    assert_eq!(read.values, vec![vec![1.25, 2.5]]);
}

#[test]
fn text_in_columns_not_selected_is_allowed() {
    let dir = dir();
    let path = file(
        dir.path(),
        "mixed.csv",
        "when,u\n2024-05-01T10:00,1\n2024-05-01T10:01,2\n",
    );
    let read = read(&path, &["u"]).expect("reading");
    assert_eq!(read.values, vec![vec![1.0, 2.0]]);
}

#[test]
fn header_can_be_forced_present_or_absent() {
    let dir = dir();
    // Numeric names: auto-detection sees data, "present" sees names.
    let path = file(dir.path(), "numeric-names.csv", "1,2\n10,20\n11,21\n");
    let auto = read(&path, &["2"]).expect("auto");
    assert_eq!(auto.values, vec![vec![2.0, 20.0, 21.0]]);
    let present = ReadOptions {
        header: Header::Present,
        ..ReadOptions::default()
    };
    let forced = read_with(&path, &["2"], &present).expect("present");
    assert_eq!(forced.values, vec![vec![20.0, 21.0]]);
    assert_eq!(forced.names, ["2"]);

    // A header declared absent is data, and its text is not a number.
    let path = file(dir.path(), "named.csv", "u,y\n1,2\n");
    let absent = ReadOptions {
        header: Header::Absent,
        ..ReadOptions::default()
    };
    let (error, message) = read_error(&path, &["1"], &absent);
    assert!(
        matches!(error, DataError::NotANumber { line: 1, .. }),
        "{error:?}"
    );
    assert_contains(&message, &["named.csv", "line 1", "\"u\""]);
}

#[test]
fn non_utf8_header_bytes_do_not_stop_the_numbers() {
    let dir = dir();
    // "Position (µm)" in Latin-1.
    let path = file(
        dir.path(),
        "latin1.txt",
        b"u\tPosition (\xb5m)\n1\t2\n3\t4\n",
    );
    let read = read(&path, &["2"]).expect("reading");
    assert_eq!(read.values, vec![vec![2.0, 4.0]]);
    assert!(read.names[0].starts_with("Position ("));
}

/// Files Excel and European locales write (issue 13, "valid files refused today"): decimal
/// commas in semicolon, tab or space delimited files, Excel's `sep=` first line, rows of empty
/// fields (`,,,,`) at the end or between rows, a line of units under the header.
#[test]
fn excel_and_european_files_are_read() {
    let dir = dir();
    /// File name, contents, columns read, the values expected.
    type Case<'a> = (&'a str, &'a str, &'a [&'a str], Vec<Vec<f64>>);
    let cases: [Case; 7] = [
        (
            "semicolon.csv",
            "Zeit;Spannung;Weg\n0,000;1,5;-2,25\n0,001;1,75;-2,5\n",
            &["Spannung", "Weg"],
            vec![vec![1.5, 1.75], vec![-2.25, -2.5]],
        ),
        (
            "tabs.txt",
            "t\tu\n0\t1,5\n1\t2,5e-3\n",
            &["u"],
            vec![vec![1.5, 2.5e-3]],
        ),
        (
            "spaces.dat",
            "0 1,5\n1 -0,25\n",
            &["2"],
            vec![vec![1.5, -0.25]],
        ),
        (
            "sep.csv",
            "sep=;\r\nt;u\r\n0;1,5\r\n1;2\r\n",
            &["t", "u"],
            vec![vec![0.0, 1.0], vec![1.5, 2.0]],
        ),
        (
            "empty-rows.csv",
            "t,u\n0,1\n,\n1,2\n,,\n,\n;;\n",
            &["u"],
            vec![vec![1.0, 2.0]],
        ),
        (
            "units.csv",
            "time,voltage,displacement\ns,V,um\n0,1,2\n1,2,3\n",
            &["displacement"],
            vec![vec![2.0, 3.0]],
        ),
        (
            "excel.csv",
            "sep=;\r\nZeit;Spannung\r\n(s);[V]\r\n0;1,5\r\n0,1;2,5\r\n;\r\n;\r\n",
            &["Zeit", "Spannung"],
            vec![vec![0.0, 0.1], vec![1.5, 2.5]],
        ),
    ];
    for (name, text, columns, expected) in cases {
        let path = file(dir.path(), name, text);
        let read = read(&path, columns).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(read.values, expected, "{name}");
        assert_eq!(read.first_row, 1, "{name}");
    }
    // The units line is part of the header: rows count from the first line of numbers.
    let path = file(dir.path(), "units-rows.csv", "t,u\ns,V\n0,10\n1,11\n2,12\n");
    let options = ReadOptions {
        rows: Some("2..3".parse().unwrap()),
        ..ReadOptions::default()
    };
    assert_eq!(
        read_with(&path, &["u"], &options).unwrap().values,
        vec![vec![11.0, 12.0]]
    );
    // A second line that holds a number is data, and refused as such with the hint.
    let path = file(dir.path(), "half.csv", "t,u\ns,1000\n0,1\n");
    let (_, message) = read_error(&path, &["t"], &ReadOptions::default());
    assert_contains(&message, &["line 2", "\"s\"", "names or units"]);
}

/// UTF-16 text, as Excel's "Unicode text" and PowerShell write it, with or without a
/// byte-order mark, either byte order: read as text, not refused as binary.
#[test]
fn utf16_text_is_read() {
    let dir = dir();
    let text = "t\tu\r\n0\t1.5\r\n1\t-2\r\n";
    let little: Vec<u8> = text.encode_utf16().flat_map(u16::to_le_bytes).collect();
    let big: Vec<u8> = text.encode_utf16().flat_map(u16::to_be_bytes).collect();
    for (name, bom, body) in [
        ("le-bom.txt", &[0xff, 0xfe][..], &little),
        ("be-bom.txt", &[0xfe, 0xff][..], &big),
        ("le.txt", &[][..], &little),
        ("be.txt", &[][..], &big),
    ] {
        let mut bytes = bom.to_vec();
        bytes.extend_from_slice(body);
        let path = file(dir.path(), name, bytes);
        let read = read(&path, &["t", "u"]).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(read.values, vec![vec![0.0, 1.0], vec![1.5, -2.0]], "{name}");
    }
}

/// Values beyond 1e15 in magnitude are refused when read (a sample of 1e308 made e_rms inf
/// and e_mhe 0 %), naming the file, line, row and column; 1e15 itself is read.
#[test]
fn values_beyond_the_magnitude_bound_are_refused() {
    let dir = dir();
    let path = file(dir.path(), "big.csv", "t,u\n0,1e15\n1,-1e15\n");
    assert_eq!(read(&path, &["u"]).unwrap().values, vec![vec![1e15, -1e15]]);
    for value in ["1e16", "-1.0000001e15", "1e308"] {
        let path = file(dir.path(), "huge.csv", format!("t,u\n0,1\n1,{value}\n"));
        let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
        assert!(
            matches!(error, DataError::OutOfRange { row: 2, .. }),
            "{error:?}"
        );
        assert_contains(&message, &["huge.csv", "line 3", "row 2", "\"u\"", "1e15"]);
    }
}

// ---------------------------------------------------------------------------------------------
// Text formats refused
// ---------------------------------------------------------------------------------------------

#[test]
fn a_missing_file_is_named() {
    let dir = dir();
    let path = dir.path().join("no-such-file.csv");
    let (error, message) = read_error(&path, &["1"], &ReadOptions::default());
    assert!(matches!(error, DataError::Read { .. }), "{error:?}");
    assert!(std::error::Error::source(&error).is_some());
    assert_contains(&message, &["no-such-file.csv", "check the path"]);
}

#[test]
fn a_directory_is_not_a_file_to_read() {
    let dir = dir();
    let (error, message) = read_error(dir.path(), &["1"], &ReadOptions::default());
    assert!(matches!(error, DataError::Read { .. }), "{error:?}");
    assert_contains(&message, &[&dir.path().display().to_string()]);
}

#[test]
fn files_without_rows_of_data_are_empty() {
    let dir = dir();
    for (name, contents) in [
        ("zero.csv", ""),
        ("blank.csv", "\n  \n\t\n"),
        ("comments.csv", "# nothing\n% here\n"),
        ("header-only.csv", "time,voltage\n# no data\n"),
    ] {
        let path = file(dir.path(), name, contents);
        let (error, message) = read_error(&path, &["1"], &ReadOptions::default());
        assert!(
            matches!(error, DataError::Empty { .. }),
            "{name}: {error:?}"
        );
        assert_contains(&message, &[name, "no rows of data"]);
    }
}

#[test]
fn ragged_rows_give_the_line_and_both_counts() {
    let dir = dir();
    let path = file(
        dir.path(),
        "ragged.dat",
        "# comment\n1\t2\t3\n4\t5\t6\n\n7\t8\n",
    );
    let (error, message) = read_error(&path, &["1"], &ReadOptions::default());
    assert!(
        matches!(
            error,
            DataError::Ragged {
                line: 5,
                found: 2,
                first_line: 2,
                expected: 3,
                delimiter: Delimiter::Tab,
                ..
            }
        ),
        "{error:?}"
    );
    assert_contains(
        &message,
        &["ragged.dat", "line 5", "2 fields", "line 2 has 3", "tabs"],
    );
}

#[test]
fn a_field_that_is_not_a_number_is_located() {
    let dir = dir();
    let path = file(dir.path(), "bad.csv", "t,u\n0,1\n1,oops\n");
    let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::NotANumber { line: 3, .. }),
        "{error:?}"
    );
    assert_contains(
        &message,
        &["bad.csv", "line 3", "\"u\" (column 2)", "\"oops\""],
    );

    // A decimal comma where the comma separates the fields (quoted, or it would split).
    let path = file(dir.path(), "comma.csv", "t,u\n0,\"1,5\"\n");
    let (_, message) = read_error(&path, &["u"], &ReadOptions::default());
    assert_contains(&message, &["\"1,5\"", "decimal comma", "semicolons"]);

    let path = file(
        dir.path(),
        "crlf.csv",
        "# logger\r\nt,u\r\n\r\n0,1\r\n1,x\r\n",
    );
    let (error, _) = read_error(&path, &["u"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::NotANumber { line: 5, .. }),
        "{error:?}"
    );

    let path = file(dir.path(), "gap.csv", "1,2\n3,\n");
    let (_, message) = read_error(&path, &["2"], &ReadOptions::default());
    assert_contains(&message, &["line 2", "column 2", "empty"]);
}

#[test]
fn nan_and_infinite_values_are_refused_with_row_and_column() {
    let dir = dir();
    for (text, shown) in [
        ("NaN", "NaN"),
        ("-Inf", "-inf"),
        ("inf", "inf"),
        ("1e999", "inf"),
    ] {
        let path = file(
            dir.path(),
            "nan.csv",
            format!("t,u\n# a comment\n0,1\n1,{text}\n"),
        );
        let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
        assert!(
            matches!(
                error,
                DataError::NotFinite {
                    line: Some(4),
                    row: 2,
                    ..
                }
            ),
            "{text}: {error:?}"
        );
        assert_contains(&message, &["nan.csv", "line 4", "row 2", "\"u\"", shown]);
    }
}

#[test]
fn a_missing_column_lists_the_columns_that_exist() {
    let dir = dir();
    let path = file(dir.path(), "named.csv", "time,voltage,position\n0,1,2\n");
    let (error, message) = read_error(&path, &["current"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::NoSuchColumn { header: true, .. }),
        "{error:?}"
    );
    assert_contains(
        &message,
        &[
            "named.csv",
            "\"current\"",
            "3 columns",
            "1 \"time\"",
            "2 \"voltage\"",
            "3 \"position\"",
        ],
    );

    let (error, message) = read_error(&path, &["7"], &ReadOptions::default());
    assert!(matches!(error, DataError::NoSuchColumn { .. }), "{error:?}");
    assert_contains(&message, &["no column 7", "3 \"position\""]);

    let path = file(dir.path(), "plain.dat", "0\t1\n2\t3\n");
    let (error, message) = read_error(&path, &["voltage"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::NoSuchColumn { header: false, .. }),
        "{error:?}"
    );
    assert_contains(
        &message,
        &["plain.dat", "\"voltage\"", "no header", "1 to 2"],
    );
}

#[test]
fn names_match_exactly_first_then_ignoring_case_when_unique() {
    let dir = dir();
    let path = file(dir.path(), "case.csv", "u,y,U\n1,2,3\n");
    let read = read(&path, &["u", "U", "Y"]).expect("exact names, then a unique case match");
    assert_eq!(read.values, vec![vec![1.0], vec![3.0], vec![2.0]]);
    assert_eq!(read.names, ["u", "U", "y"]);

    let path = file(dir.path(), "dup.csv", "u,y,u\n1,2,3\n");
    let (error, message) = read_error(&path, &["u"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::AmbiguousColumn { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["dup.csv", "\"u\"", "1, 3", "by number"]);

    let path = file(dir.path(), "cases.csv", "Uy,uY\n1,2\n");
    let (error, message) = read_error(&path, &["uy"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::AmbiguousColumn { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["\"uy\"", "1, 2"]);
}

#[test]
fn a_row_range_outside_the_file_is_refused() {
    let dir = dir();
    let path = file(dir.path(), "short.csv", "u\n1\n2\n3\n");
    for range in ["2..4", "4..", "5..9"] {
        let options = ReadOptions {
            rows: Some(range.parse().expect("a range")),
            ..ReadOptions::default()
        };
        let (error, message) = read_error(&path, &["u"], &options);
        assert!(
            matches!(error, DataError::RowsOutOfRange { available: 3, .. }),
            "{range}: {error:?}"
        );
        assert_contains(&message, &["short.csv", range, "3 rows of data"]);
    }
    let options = ReadOptions {
        rows: Some("2..3".parse().expect("a range")),
        ..ReadOptions::default()
    };
    let read = read_with(&path, &["u"], &options).expect("an inside range");
    assert_eq!(read.values, vec![vec![2.0, 3.0]]);
    assert_eq!(read.first_row, 2);
}

#[test]
fn only_selected_rows_need_numbers_but_all_rows_need_their_fields() {
    let dir = dir();
    let path = file(dir.path(), "tail.csv", "u,y\n1,2\n3,4\nNaN,junk\n");
    let options = ReadOptions {
        rows: Some(RowRange::new(1, Some(2)).expect("a range")),
        ..ReadOptions::default()
    };
    let read = read_with(&path, &["u", "y"], &options).expect("rows before the bad one");
    assert_eq!(read.values, vec![vec![1.0, 3.0], vec![2.0, 4.0]]);

    let path = file(dir.path(), "truncated.csv", "u,y\n1,2\n3,4\n5\n");
    let (error, _) = read_error(&path, &["u"], &options);
    assert!(
        matches!(error, DataError::Ragged { line: 4, .. }),
        "{error:?}"
    );
}

#[test]
fn a_binary_file_is_not_taken_for_text() {
    let dir = dir();
    let path = file(dir.path(), "photo.png", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR");
    let (error, message) = read_error(&path, &["1"], &ReadOptions::default());
    assert!(
        matches!(error, DataError::UnsupportedFormat { .. }),
        "{error:?}"
    );
    assert_contains(&message, &["photo.png", "binary"]);
}

#[test]
fn selections_that_cannot_be_used_are_refused() {
    let dir = dir();
    let path = file(dir.path(), "ok.csv", "1,2\n");
    let error = read_columns(&path, &[], &ReadOptions::default()).expect_err("no columns");
    assert!(matches!(
        error,
        DataError::InvalidArgument {
            what: "columns",
            ..
        }
    ));
    let error =
        read_columns(&path, &[Column::Index(0)], &ReadOptions::default()).expect_err("column 0");
    assert!(matches!(
        error,
        DataError::InvalidArgument { what: "column", .. }
    ));
    assert_contains(&error.to_string(), &["counted from 1"]);
    let options = ReadOptions {
        rows: Some(RowRange {
            first: 0,
            last: None,
        }),
        ..ReadOptions::default()
    };
    let error = read_columns(&path, &[Column::Index(1)], &options).expect_err("row 0");
    assert!(matches!(
        error,
        DataError::InvalidArgument {
            what: "row range",
            ..
        }
    ));
}

// ---------------------------------------------------------------------------------------------
// Parsing selections and options
// ---------------------------------------------------------------------------------------------

#[test]
fn columns_parse_as_numbers_from_one_or_names() {
    assert_eq!("3".parse::<Column>().ok(), Some(Column::Index(3)));
    assert_eq!(" 12 ".parse::<Column>().ok(), Some(Column::Index(12)));
    assert_eq!(
        "voltage".parse::<Column>().ok(),
        Some(Column::Name("voltage".to_owned()))
    );
    assert_eq!(
        "data:2".parse::<Column>().ok(),
        Some(Column::Name("data:2".to_owned()))
    );
    for bad in ["0", "-1", "", "  ", "99999999999999999999999"] {
        let error = bad.parse::<Column>().expect_err(bad);
        assert!(
            matches!(error, DataError::InvalidArgument { what: "column", .. }),
            "{bad}"
        );
    }
    assert_contains(
        &"0".parse::<Column>().unwrap_err().to_string(),
        &["counted from 1"],
    );
    for text in ["7", "voltage"] {
        let column: Column = text.parse().expect("a column");
        assert_eq!(column.to_string(), text);
    }
}

#[test]
fn row_ranges_parse_inclusive_from_one() {
    let parse = |text: &str| text.parse::<RowRange>();
    assert_eq!(parse("101..200").ok(), RowRange::new(101, Some(200)).ok());
    assert_eq!(parse("101..=200").ok(), RowRange::new(101, Some(200)).ok());
    assert_eq!(parse("5..").ok(), RowRange::new(5, None).ok());
    assert_eq!(parse("..7").ok(), RowRange::new(1, Some(7)).ok());
    assert_eq!(parse(" 3..3 ").ok(), RowRange::new(3, Some(3)).ok());
    for bad in ["0..5", "5..3", "abc", "5", "a..b", "-1..4"] {
        let error = parse(bad).expect_err(bad);
        assert!(
            matches!(
                error,
                DataError::InvalidArgument {
                    what: "row range",
                    ..
                }
            ),
            "{bad}: {error:?}"
        );
        assert_contains(&error.to_string(), &[bad.trim()]);
    }
    assert!(RowRange::new(0, None).is_err());
    assert!(RowRange::new(4, Some(3)).is_err());
    let range = RowRange::new(101, Some(200)).expect("a range");
    assert_eq!(range.to_string().parse::<RowRange>().ok(), Some(range));
}

#[test]
fn delimiter_and_header_settings_parse() {
    for (text, delimiter) in [
        ("auto", Delimiter::Auto),
        ("Comma", Delimiter::Comma),
        (",", Delimiter::Comma),
        ("tab", Delimiter::Tab),
        ("\t", Delimiter::Tab),
        ("\\t", Delimiter::Tab),
        ("semicolon", Delimiter::Semicolon),
        ("whitespace", Delimiter::Whitespace),
        (" ", Delimiter::Whitespace),
    ] {
        assert_eq!(text.parse::<Delimiter>().ok(), Some(delimiter), "{text:?}");
        assert_eq!(
            delimiter.to_string().parse::<Delimiter>().ok(),
            Some(delimiter)
        );
    }
    assert!("pipe".parse::<Delimiter>().is_err());
    for (text, header) in [
        ("auto", Header::Auto),
        ("present", Header::Present),
        ("ABSENT", Header::Absent),
    ] {
        assert_eq!(text.parse::<Header>().ok(), Some(header));
        assert_eq!(header.to_string().parse::<Header>().ok(), Some(header));
    }
    assert_contains(
        &"maybe".parse::<Header>().unwrap_err().to_string(),
        &["maybe", "auto, present, absent"],
    );
    assert_eq!(ReadOptions::default().delimiter, Delimiter::Auto);
    assert_eq!(ReadOptions::default().header, Header::Auto);
    assert_eq!(ReadOptions::default().rows, None);
}

// ---------------------------------------------------------------------------------------------
// Writing refused
// ---------------------------------------------------------------------------------------------

#[test]
fn columns_of_different_lengths_are_not_written() {
    let dir = dir();
    let path = dir.path().join("uneven.csv");
    let error = write_csv(&path, &["u", "y"], &[&[1.0, 2.0], &[1.0]]).expect_err("uneven");
    assert!(
        matches!(error, DataError::LengthMismatch { .. }),
        "{error:?}"
    );
    assert_contains(&error.to_string(), &["uneven.csv", "u: 2", "y: 1"]);
    assert!(!path.exists(), "nothing is written");
}

#[test]
fn non_finite_values_are_not_written() {
    let dir = dir();
    let path = file(dir.path(), "keep.csv", "old\n1\n");
    let error = write_csv(&path, &["u"], &[&[1.0, f64::NAN]]).expect_err("NaN");
    assert!(
        matches!(error, DataError::NotFinite { row: 2, .. }),
        "{error:?}"
    );
    assert_contains(&error.to_string(), &["keep.csv", "u", "sample 2", "NaN"]);
    assert_eq!(fs::read_to_string(&path).expect("old file"), "old\n1\n");
}

#[test]
fn header_names_that_would_not_read_back_are_refused() {
    let dir = dir();
    let path = dir.path().join("names.csv");
    let column: &[f64] = &[1.0];
    for (header, delimiter, part) in [
        (
            vec!["a", "b"],
            Delimiter::Comma,
            "2 header names for 1 columns",
        ),
        (vec!["# u"], Delimiter::Comma, "comment"),
        (vec!["1"], Delimiter::Comma, "read as data"),
        (vec!["two words"], Delimiter::Whitespace, "spaces"),
        (vec!["line\nbreak"], Delimiter::Tab, "line break"),
    ] {
        let columns = vec![column; if header.len() == 2 { 1 } else { header.len() }];
        let error = write_delimited(&path, &header, &columns, delimiter).expect_err(part);
        assert!(matches!(error, DataError::InvalidWrite { .. }), "{error:?}");
        let encoded = encode_delimited(&path, &header, &columns, delimiter).expect_err(part);
        assert_eq!(encoded.to_string(), error.to_string());
        assert!(error.is_output());
        assert_contains(&error.to_string(), &["names.csv", part]);
    }
    let error = write_csv(&path, &[], &[]).expect_err("no columns");
    assert!(matches!(error, DataError::InvalidWrite { .. }));
    assert!(!path.exists());
}

// ---------------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------------

#[test]
fn time_must_increase_strictly() {
    assert!(check_time_increasing(&[]).is_ok());
    assert!(check_time_increasing(&[0.0]).is_ok());
    assert!(check_time_increasing(&[0.0, 0.005, 0.01]).is_ok());
    for (time, sample) in [
        (vec![0.0, 0.005, 0.005], 3),
        (vec![0.0, 0.005, 0.002, 0.01], 3),
        (vec![1.0, 0.0], 2),
    ] {
        match check_time_increasing(&time) {
            Err(DataError::TimeNotIncreasing {
                sample: s,
                previous,
                value,
            }) => {
                assert_eq!(s, sample);
                assert_eq!(previous, time[sample - 2]);
                assert_eq!(value, time[sample - 1]);
                let message = check_time_increasing(&time).unwrap_err().to_string();
                assert_contains(&message, &[&format!("sample {sample}"), "not increasing"]);
            }
            other => panic!("{time:?}: {other:?}"),
        }
    }
    let error = check_time_increasing(&[0.0, f64::NAN, 1.0]).expect_err("NaN time");
    assert!(
        matches!(error, DataError::NotFinite { row: 2, .. }),
        "{error:?}"
    );
}

proptest! {
    #![proptest_config(seeded(64, 0x6d65_616e_5f73_7465))]

    /// The mean time step against its plain reference, the mean of the sample-to-sample steps
    /// (a telescoping sum: equal up to rounding), on jittered grids of 2 to 200 samples.
    #[test]
    fn mean_time_step_is_the_mean_of_the_steps(
        start in -1e3f64..1e3,
        steps in prop::collection::vec(1e-4f64..1.0, 1..200),
    ) {
        let mut time = vec![start];
        for h in &steps {
            time.push(time[time.len() - 1] + h);
        }
        let reference = (time.windows(2).map(|w| w[1] - w[0]).sum::<f64>()) / steps.len() as f64;
        let step = mean_time_step(&time).expect("two or more samples");
        prop_assert!((step - reference).abs() <= 1e-9 * (1.0 + start.abs()), "{step} {reference}");
    }
}

#[test]
fn mean_time_step_needs_two_samples() {
    assert_eq!(mean_time_step(&[]), None);
    assert_eq!(mean_time_step(&[3.0]), None);
    assert_eq!(mean_time_step(&[1.0, 1.5]), Some(0.5));
    assert_eq!(mean_time_step(&[0.0, 0.1, 0.5]), Some(0.25));
}

#[test]
fn constant_columns_are_refused() {
    assert!(check_not_constant("u", &[1.0, 1.0, 1.5]).is_ok());
    let error = check_not_constant("input", &[1.8; 5]).expect_err("constant");
    assert!(
        matches!(error, DataError::Constant { samples: 5, value, .. } if value == 1.8),
        "{error:?}"
    );
    assert_contains(
        &error.to_string(),
        &["input", "constant", "1.8", "5 samples"],
    );
    let error = check_not_constant("output", &[2.0]).expect_err("one sample");
    assert!(matches!(
        error,
        DataError::TooFewSamples {
            needed: 2,
            got: 1,
            ..
        }
    ));
}

#[test]
fn too_few_samples_are_refused() {
    assert!(check_min_samples(10, 10, "a model").is_ok());
    let error =
        check_min_samples(10, 9, "identification of 10 play operators").expect_err("too few");
    assert!(matches!(
        error,
        DataError::TooFewSamples {
            needed: 10,
            got: 9,
            ..
        }
    ));
    assert_contains(
        &error.to_string(),
        &[
            "identification of 10 play operators",
            "9 given",
            "10 needed",
        ],
    );
}

#[test]
fn finite_and_same_length_checks_name_the_column() {
    assert!(check_finite("u", &[0.0, -1e300, 5e-324]).is_ok());
    let error = check_finite("output", &[0.0, 1.0, f64::INFINITY]).expect_err("inf");
    assert!(matches!(
        error,
        DataError::NotFinite {
            row: 3,
            path: None,
            ..
        }
    ));
    assert_contains(&error.to_string(), &["output", "sample 3", "inf"]);

    assert!(check_same_length(&[("u", &[1.0, 2.0]), ("y", &[3.0, 4.0])]).is_ok());
    assert!(check_same_length(&[]).is_ok());
    let error =
        check_same_length(&[("u", &[1.0, 2.0]), ("y", &[3.0])]).expect_err("different lengths");
    assert_contains(&error.to_string(), &["u: 2", "y: 1"]);
}

#[test]
fn errors_can_cross_threads_and_tell_input_from_output() {
    fn send_sync<T: Send + Sync + 'static>() {}
    send_sync::<DataError>();
    let input = check_min_samples(2, 1, "x").unwrap_err();
    assert!(!input.is_output());
}

/// A tab-separated file read with --delimiter comma has one column holding whole lines: the
/// message says so and points at the delimiter.
#[test]
fn a_wrong_delimiter_gets_a_hint() {
    let dir = dir();
    let path = file(dir.path(), "tabs.dat", "1.8\t0\t-123.1\n1.9\t0\t-122.0\n");
    let options = ReadOptions {
        delimiter: Delimiter::Comma,
        ..ReadOptions::default()
    };
    let (error, message) = read_error(&path, &["1", "3"], &options);
    assert!(matches!(error, DataError::NoSuchColumn { .. }), "{error:?}");
    assert_contains(&message, &["tabs.dat", "1 column", "--delimiter"]);
    // With the right delimiter there is no such hint (the column really is missing).
    let options = ReadOptions {
        delimiter: Delimiter::Tab,
        ..ReadOptions::default()
    };
    let (_, message) = read_error(&path, &["4"], &options);
    assert!(!message.contains("--delimiter"), "{message}");
}

// ---------------------------------------------------------------------------------------------
// The real micromanipulator records (read from ../shared when present)
// ---------------------------------------------------------------------------------------------

fn dbo(name: &str) -> Option<PathBuf> {
    hystcomp_testkit::dbo_record(name)
}

#[test]
fn the_real_identification_record_reads_with_its_shape() {
    let Some(path) = dbo("Model_Vi_Do.dat") else {
        return;
    };
    let read = read(&path, &["1", "5"]).expect("reading Model_Vi_Do.dat");
    assert_eq!(read.names, ["column 1", "column 5"]);
    assert_eq!(read.len(), 8027);
    let (voltage, output) = (&read.values[0], &read.values[1]);
    assert!(
        (voltage[0] - 1.8).abs() < 1e-9,
        "first voltage {}",
        voltage[0]
    );
    let (lo, hi) = voltage
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(
        lo > -0.01 && lo < 0.1 && hi > 3.5 && hi < 3.61,
        "voltage {lo}..{hi}"
    );
    assert!(output.iter().all(|&y| (-130.0..-70.0).contains(&y)));
    check_not_constant("voltage", voltage).expect("the voltage varies");
    check_not_constant("output", output).expect("the output varies");

    // Columns have no names in this file: asking for one lists the 7 numbers.
    let (error, message) = read_error(&path, &["voltage"], &ReadOptions::default());
    assert!(matches!(
        error,
        DataError::NoSuchColumn { header: false, .. }
    ));
    assert_contains(&message, &["no header", "1 to 7"]);
}

#[test]
fn the_real_tracking_record_reads_with_its_shape_and_ranges() {
    let Some(path) = dbo("Test_Vi_Do_Di.dat") else {
        return;
    };
    let read = read(&path, &["1", "5", "9"]).expect("reading Test_Vi_Do_Di.dat");
    assert_eq!(read.len(), 14155);
    assert!(read.values[2].iter().all(|d| d.abs() <= 20.5));
    let options = ReadOptions {
        rows: Some("11152..11851".parse().expect("a range")),
        ..ReadOptions::default()
    };
    let part = read_with(&path, &["1", "5", "9"], &options).expect("reading a range");
    assert_eq!(part.len(), 700);
    assert_eq!(part.first_row, 11152);
    assert_eq!(bits(&part.values[1]), bits(&read.values[1][11151..11851]));
    let (error, _) = read_error(&path, &["12"], &ReadOptions::default());
    assert!(matches!(error, DataError::NoSuchColumn { .. }));
}
