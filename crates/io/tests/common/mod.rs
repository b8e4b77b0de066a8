//! Shared by the tests of hystcomp-io: files in temporary folders, reading them, messages.
#![allow(dead_code)]

pub mod mat5;
pub mod properties;

use std::fs;
use std::path::{Path, PathBuf};

use hystcomp_io::data::{Column, Columns, DataError, ReadOptions, read_columns};
use proptest::test_runner::{Config, RngSeed};

pub fn dir() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary directory")
}

pub fn file(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    fs::write(&path, contents).expect("writing a test file");
    path
}

pub fn read(path: &Path, columns: &[&str]) -> Result<Columns, DataError> {
    read_with(path, columns, &ReadOptions::default())
}

pub fn read_with(
    path: &Path,
    columns: &[&str],
    options: &ReadOptions,
) -> Result<Columns, DataError> {
    let columns: Vec<Column> = columns
        .iter()
        .map(|c| c.parse().expect("a valid column"))
        .collect();
    read_columns(path, &columns, options)
}

/// The error of a read that must fail, and its message.
pub fn read_error(path: &Path, columns: &[&str], options: &ReadOptions) -> (DataError, String) {
    match read_with(path, columns, options) {
        Ok(columns) => panic!("reading {columns:?} should have failed"),
        Err(error) => {
            let message = error.to_string();
            (error, message)
        }
    }
}

pub fn assert_contains(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(
            message.contains(part),
            "message {message:?} should mention {part:?}"
        );
    }
}

/// The names of the entries of a directory, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .expect("listing a directory")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

pub fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

/// A proptest configuration with a fixed seed and no persistence file.
pub fn seeded(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A fixture file of these tests.
pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}
