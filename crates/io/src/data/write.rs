//! Columns of numbers written as delimited text, atomically and exactly.

use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::text::parse_number;
use super::{DataError, Delimiter, check_finite};

/// Writes columns of numbers as comma-separated text, atomically (see [`write_delimited`]).
///
/// `header` holds one name per column, or is empty for a file without header line.
///
/// # Example
///
/// ```
/// use hystcomp_io::data::{Column, ReadOptions, read_columns, write_csv};
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("response.csv");
/// let time = [0.0, 0.005, 0.01];
/// let position = [0.1, -2.5e-7, 1e15];
/// write_csv(&path, &["time_s", "position_um"], &[&time, &position])?;
/// let read = read_columns(&path, &[Column::Name("position_um".into())], &ReadOptions::default())?;
/// assert_eq!(read.values[0], position); // exactly, bit for bit
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_csv(path: &Path, header: &[&str], columns: &[&[f64]]) -> Result<(), DataError> {
    write_delimited(path, header, columns, Delimiter::Comma)
}

/// Writes columns of numbers as delimited text (`Auto` writes commas, `Whitespace` one space),
/// atomically: the file at `path` is replaced whole or not at all.
///
/// Each number is written in the shortest form that reads back to the same `f64` (e.g. `0.1`,
/// `1e-7`, `-0.0`), so [`read_columns`](super::read_columns) returns exactly what was written. Lines end in `\n`.
/// Refused before anything is written: no columns, columns of different lengths
/// ([`DataError::LengthMismatch`]), NaN or infinite values ([`DataError::NotFinite`]), and
/// header names that would not read back ([`DataError::InvalidWrite`]): a count different
/// from the columns', a line break, a first name starting with `#` or `%` (a comment), names
/// that are all empty or all numbers (the header would be taken for data), and, with
/// whitespace delimiting, names that are empty or contain spaces.
pub fn write_delimited(
    path: &Path,
    header: &[&str],
    columns: &[&[f64]],
    delimiter: Delimiter,
) -> Result<(), DataError> {
    let contents = encode_delimited(path, header, columns, delimiter)?;
    crate::atomic::write_atomic(path, &contents).map_err(|source| DataError::Write {
        path: path.to_owned(),
        source,
    })
}

/// The bytes [`write_csv`] would write to `path`, with every check it makes, and nothing
/// written (`path` only names the errors): for a command that writes two files and must
/// know both can be written before it replaces the first.
pub fn encode_csv(path: &Path, header: &[&str], columns: &[&[f64]]) -> Result<Vec<u8>, DataError> {
    encode_delimited(path, header, columns, Delimiter::Comma)
}

/// The bytes [`write_delimited`] would write to `path`, with every check it makes (`path`
/// only names the errors).
pub fn encode_delimited(
    path: &Path,
    header: &[&str],
    columns: &[&[f64]],
    delimiter: Delimiter,
) -> Result<Vec<u8>, DataError> {
    let invalid = |reason: String| DataError::InvalidWrite {
        path: path.to_owned(),
        reason,
    };
    if columns.is_empty() {
        return Err(invalid("there are no columns to write".to_owned()));
    }
    check_header_names(header, columns.len(), delimiter).map_err(invalid)?;
    let names: Vec<String> = (0..columns.len())
        .map(|i| match header.get(i) {
            Some(name) if !name.is_empty() => (*name).to_owned(),
            _ => format!("column {}", i + 1),
        })
        .collect();
    let lengths: Vec<(String, usize)> = names
        .iter()
        .cloned()
        .zip(columns.iter().map(|c| c.len()))
        .collect();
    if lengths.iter().any(|(_, n)| *n != lengths[0].1) {
        return Err(DataError::LengthMismatch {
            path: Some(path.to_owned()),
            lengths,
        });
    }
    for (name, column) in names.iter().zip(columns) {
        check_finite(name, column).map_err(|error| match error {
            DataError::NotFinite {
                row, column, value, ..
            } => DataError::NotFinite {
                path: Some(path.to_owned()),
                line: None,
                row,
                column,
                value,
            },
            other => other,
        })?;
    }

    let byte = match delimiter {
        Delimiter::Auto | Delimiter::Comma => b',',
        Delimiter::Tab => b'\t',
        Delimiter::Semicolon => b';',
        Delimiter::Whitespace => b' ',
    };
    let mut writer = csv::WriterBuilder::new()
        .delimiter(byte)
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // The source names the path, as the errors of write_atomic do.
    let write_error = |error: csv::Error| DataError::Write {
        path: path.to_owned(),
        source: io::Error::other(format!("could not write {}: {error}", path.display())),
    };
    if !header.is_empty() {
        writer.write_record(header).map_err(write_error)?;
    }
    let rows = lengths[0].1;
    let mut fields: Vec<String> = vec![String::new(); columns.len()];
    for r in 0..rows {
        for (field, column) in fields.iter_mut().zip(columns) {
            field.clear();
            // Debug formatting of f64 is the shortest text that parses back to the same
            // value, with an exponent for very large or small magnitudes. Writing to a
            // String cannot fail.
            let _ = write!(field, "{:?}", column[r]);
        }
        writer.write_record(&fields).map_err(write_error)?;
    }
    writer
        .into_inner()
        .map_err(|error| write_error(error.into_error().into()))
}

/// Why header names would not read back, if they would not.
fn check_header_names(header: &[&str], columns: usize, delimiter: Delimiter) -> Result<(), String> {
    if header.is_empty() {
        return Ok(());
    }
    if header.len() != columns {
        return Err(format!(
            "{} header names for {columns} columns; give one name per column, or none",
            header.len()
        ));
    }
    if let Some(name) = header.iter().find(|n| n.contains(['\n', '\r'])) {
        return Err(format!("the column name {name:?} contains a line break"));
    }
    if header[0].trim_start().starts_with(['#', '%']) {
        return Err(format!(
            "the first column name \"{}\" starts with # or %, which marks a comment line",
            header[0]
        ));
    }
    if delimiter == Delimiter::Whitespace
        && let Some(name) = header
            .iter()
            .find(|n| n.is_empty() || n.contains(char::is_whitespace) || n.contains('"'))
    {
        return Err(format!(
            "the column name \"{name}\" is empty or contains spaces or quotes, which \
                 whitespace-separated files cannot hold; use another delimiter or name"
        ));
    }
    if header
        .iter()
        .all(|n| n.trim().is_empty() || parse_number(n).is_some())
    {
        return Err(
            "every column name is empty or a number, so the header would be read as data; \
             give at least one name that is not a number"
                .to_owned(),
        );
    }
    Ok(())
}
