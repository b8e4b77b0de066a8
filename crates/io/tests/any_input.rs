//! The readers' promises (`common/properties.rs`) on many seeded random inputs: bytes of
//! every kind, mutations of valid text records, MAT-files and model files. The stable
//! counterpart of the fuzz targets `text`, `mat` and `model`, so that CI always checks the
//! same properties.

mod common;

use common::properties::{check_model_text, check_record};
use common::*;

use std::path::Path;

use hystcomp_io::data::{Column, Delimiter, Header, ReadOptions, read_bytes};
use proptest::prelude::*;

/// The selections the fuzz targets try on every input.
fn selections() -> Vec<Vec<Column>> {
    vec![
        vec![Column::Index(1)],
        vec![Column::Index(2), Column::Index(1)],
        vec![Column::Name("u".into())],
        vec![Column::Name("x:2".into()), Column::Index(1)],
    ]
}

fn options(selector: u8) -> ReadOptions {
    ReadOptions {
        delimiter: [
            Delimiter::Auto,
            Delimiter::Comma,
            Delimiter::Semicolon,
            Delimiter::Whitespace,
        ][usize::from(selector % 4)],
        header: [Header::Auto, Header::Present, Header::Absent][usize::from(selector / 4 % 3)],
        rows: (selector >= 128).then(|| "2..4".parse().unwrap()),
    }
}

/// Reads `bytes` as `name` with every selection and checks each result.
fn check_all(name: &str, bytes: &[u8], selector: u8) -> Result<(), String> {
    for columns in selections() {
        let result = read_bytes(Path::new(name), bytes, &columns, &options(selector));
        check_record(&result, name, columns.len())?;
    }
    Ok(())
}

const TEXT_SEEDS: [&str; 6] = [
    "t,u\n0,1\n1,2\n2,3\n3,4\n",
    "sep=;\r\nZeit;u\r\ns;V\r\n0;1,5\r\n0,1;2,5\r\n;\r\n",
    "# comment\n0.0 1.8 -123.1\n0.005 1.85 -120.2\n\n0.01 1.9 -119\n",
    "x\ty\tu\n1\t2\t3\n4\t5\tNaN\n",
    "a,b\n1e15,-1e15\n1e16,2\n",
    "\u{feff}t,u\n0,\"1,5\"\n",
];

/// Mutations of `seed`: bytes overwritten, cut short, inserted.
fn mutated(seed: &[u8], edits: &[(prop::sample::Index, u8, u8)]) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for (at, byte, kind) in edits {
        if bytes.is_empty() {
            bytes.push(*byte);
            continue;
        }
        let at = at.index(bytes.len());
        match kind % 3 {
            0 => bytes[at] = *byte,
            1 => bytes.truncate(at),
            _ => bytes.insert(at, *byte),
        }
    }
    bytes
}

fn edits() -> impl Strategy<Value = Vec<(prop::sample::Index, u8, u8)>> {
    prop::collection::vec(
        (any::<prop::sample::Index>(), any::<u8>(), any::<u8>()),
        0..12,
    )
}

proptest! {
    #![proptest_config(seeded(256, 0x616e_7969_6e70_7574))]

    /// Arbitrary bytes, as text or as a MAT-file.
    #[test]
    fn any_bytes_read_or_are_refused_with_the_file_named(
        bytes in prop::collection::vec(any::<u8>(), 0..300),
        selector in any::<u8>(),
    ) {
        prop_assert_eq!(check_all("any.csv", &bytes, selector), Ok(()));
        prop_assert_eq!(check_all("any.mat", &bytes, selector), Ok(()));
    }

    /// Mutations of text records of every accepted kind.
    #[test]
    fn mutated_text_records_keep_the_promises(
        seed in 0usize..TEXT_SEEDS.len(),
        edits in edits(),
        selector in any::<u8>(),
    ) {
        let bytes = mutated(TEXT_SEEDS[seed].as_bytes(), &edits);
        prop_assert_eq!(check_all("mutated.csv", &bytes, selector), Ok(()));
    }

    /// Mutations of MAT-files written by scipy (compressed and not).
    #[test]
    fn mutated_mat_files_keep_the_promises(
        seed in 0usize..3,
        edits in edits(),
        selector in any::<u8>(),
    ) {
        let name = ["scipy_record.mat", "scipy_record_compressed.mat", "scipy_int32.mat"][seed];
        let bytes = mutated(&std::fs::read(fixture(name)).unwrap(), &edits);
        prop_assert_eq!(check_all("mutated.mat", &bytes, selector), Ok(()));
    }

    /// Mutations of the shipped model files: refused with a message, or loaded, reloaded bit for
    /// bit, and every compensator safe on any desired position.
    #[test]
    fn mutated_model_files_keep_the_promises(seed in 0usize..2, edits in edits()) {
        let name = ["table1-plant.json", "table2-inverse.json"][seed];
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models").join(name);
        let bytes = mutated(&std::fs::read(path).unwrap(), &edits);
        prop_assert_eq!(check_model_text(&String::from_utf8_lossy(&bytes)), Ok(()));
    }
}

/// Numbers in model files are edited into every magnitude: the properties still hold.
#[test]
fn model_files_with_extreme_numbers_keep_the_promises() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/table1-plant.json"),
    )
    .unwrap();
    for (from, to) in [
        ("0.4603", "1e308"),
        ("0.4603", "5e-324"),
        ("-0.1569", "-1e300"),
        ("0.2313", "1e-310"),
        ("\"scale\": 75.0", "\"scale\": 1e-12"),
        ("\"scale\": 75.0", "\"scale\": 1e12"),
        ("\"offset\": 0.0", "\"offset\": 1e15"),
    ] {
        let edited = text.replacen(from, to, 1);
        assert_ne!(edited, text, "{from}");
        check_model_text(&edited).unwrap_or_else(|e| panic!("{from} -> {to}: {e}"));
    }
}
