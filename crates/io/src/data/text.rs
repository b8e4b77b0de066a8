//! Delimited text: CSV, tab-, semicolon- or whitespace-separated columns of numbers (see the
//! [module documentation](super) for the rules).

use std::io;
use std::path::Path;

use super::error::column_label;
use super::{Column, Columns, DataError, Delimiter, Header, ReadOptions, check_row_range};

/// Whether a line of text is skipped: blank, or a comment starting with `#` or `%`.
fn is_skipped_line(line: &str) -> bool {
    let trimmed = line.trim_start();
    trimmed.is_empty() || trimmed.starts_with(['#', '%'])
}

/// A field's number, if it is one (`NaN` and `Inf` are numbers here).
pub(super) fn parse_number(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok()
}

/// The records of a text file's content lines, each with its line number in the file.
///
/// Blank and comment lines are left out of `content` beforehand (with `line_numbers` mapping
/// its lines back to the file's), so that one `csv` reader splits the whole content.
enum Records<'a> {
    Csv {
        reader: csv::Reader<&'a [u8]>,
        line_numbers: &'a [usize],
    },
    Whitespace {
        lines: std::iter::Zip<std::str::Lines<'a>, std::slice::Iter<'a, usize>>,
    },
}

impl<'a> Records<'a> {
    fn new(content: &'a str, line_numbers: &'a [usize], delimiter: Delimiter) -> Records<'a> {
        match delimiter.byte() {
            Some(byte) => Records::Csv {
                reader: csv::ReaderBuilder::new()
                    .delimiter(byte)
                    .has_headers(false)
                    .flexible(true)
                    .trim(csv::Trim::All)
                    .from_reader(content.as_bytes()),
                line_numbers,
            },
            None => Records::Whitespace {
                lines: content.lines().zip(line_numbers.iter()),
            },
        }
    }

    /// Reads the next record into `record`, returning the file's line number it starts on,
    /// or `None` at the end.
    fn next(&mut self, record: &mut csv::StringRecord) -> Result<Option<usize>, csv::Error> {
        match self {
            Records::Csv {
                reader,
                line_numbers,
            } => {
                if !reader.read_record(record)? {
                    return Ok(None);
                }
                // The content has no empty lines, so the csv reader's line count is exact.
                let content_line = record.position().map_or(1, |p| p.line());
                let index = usize::try_from(content_line).unwrap_or(usize::MAX);
                Ok(Some(
                    line_numbers
                        .get(index.saturating_sub(1))
                        .copied()
                        .unwrap_or(index),
                ))
            }
            Records::Whitespace { lines } => {
                let Some((line, &number)) = lines.next() else {
                    return Ok(None);
                };
                record.clear();
                for field in line.split_whitespace() {
                    record.push_field(field);
                }
                Ok(Some(number))
            }
        }
    }
}

pub(super) fn read_text(
    path: &Path,
    bytes: &[u8],
    columns: &[Column],
    options: &ReadOptions,
) -> Result<Columns, DataError> {
    let text = String::from_utf8_lossy(bytes);
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut content = String::with_capacity(text.len());
    let mut line_numbers = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if !is_skipped_line(line) {
            content.push_str(line);
            content.push('\n');
            line_numbers.push(i + 1);
        }
    }
    let Some(first_text) = content.lines().next() else {
        return Err(DataError::Empty {
            path: path.to_owned(),
        });
    };
    let delimiter = match options.delimiter {
        Delimiter::Auto => Delimiter::detect(first_text),
        given => given,
    };
    let mut records = Records::new(&content, &line_numbers, delimiter);
    let mut record = csv::StringRecord::new();
    let mut next = |record: &mut csv::StringRecord| {
        records.next(record).map_err(|error| DataError::Read {
            path: path.to_owned(),
            source: io::Error::new(io::ErrorKind::InvalidData, error.to_string()),
        })
    };

    let Some(first_line) = next(&mut record)? else {
        return Err(DataError::Empty {
            path: path.to_owned(),
        });
    };
    let expected = record.len();
    let header = match options.header {
        Header::Present => true,
        Header::Absent => false,
        Header::Auto => record
            .iter()
            .any(|field| !field.is_empty() && parse_number(field).is_none()),
    };
    let names: Vec<String> = (0..expected)
        .map(|i| match record.get(i) {
            Some(name) if header && !name.is_empty() => name.to_owned(),
            _ => format!("column {}", i + 1),
        })
        .collect();
    let selected = columns
        .iter()
        .map(|column| resolve_text_column(path, column, &names, header))
        .collect::<Result<Vec<usize>, DataError>>()?;
    let labels: Vec<String> = selected
        .iter()
        .map(|&i| column_label(&names, header, i))
        .collect();

    let (first_row, last_row) = match options.rows {
        Some(rows) => (rows.first, rows.last.unwrap_or(usize::MAX)),
        None => (1, usize::MAX),
    };
    let selected_rows = first_row..=last_row;
    // Appends the selected fields of a record (row `row`, on line `line`) to `values`.
    let take = |row: usize,
                line: usize,
                record: &csv::StringRecord,
                values: &mut [Vec<f64>]|
     -> Result<(), DataError> {
        for ((&index, label), column) in selected.iter().zip(&labels).zip(values.iter_mut()) {
            let field = record.get(index).unwrap_or("");
            let value = parse_number(field).ok_or_else(|| DataError::NotANumber {
                path: path.to_owned(),
                line,
                column: label.clone(),
                text: field.to_owned(),
            })?;
            if !value.is_finite() {
                return Err(DataError::NotFinite {
                    path: Some(path.to_owned()),
                    line: Some(line),
                    row,
                    column: label.clone(),
                    value,
                });
            }
            column.push(value);
        }
        Ok(())
    };

    let mut values: Vec<Vec<f64>> = vec![Vec::new(); selected.len()];
    let mut row = 0usize;
    if !header {
        row = 1;
        if selected_rows.contains(&row) {
            take(row, first_line, &record, &mut values)?;
        }
    }
    while let Some(line) = next(&mut record)? {
        if record.len() != expected {
            return Err(DataError::Ragged {
                path: path.to_owned(),
                line,
                found: record.len(),
                first_line,
                expected,
                delimiter,
            });
        }
        row += 1;
        if selected_rows.contains(&row) {
            take(row, line, &record, &mut values)?;
        }
    }
    if row == 0 {
        return Err(DataError::Empty {
            path: path.to_owned(),
        });
    }
    check_row_range(path, options.rows, row)?;
    Ok(Columns {
        path: path.to_owned(),
        names: selected.iter().map(|&i| names[i].clone()).collect(),
        values,
        first_row,
    })
}

/// The 0-based position of a requested column among a text file's `names`.
fn resolve_text_column(
    path: &Path,
    column: &Column,
    names: &[String],
    header: bool,
) -> Result<usize, DataError> {
    let missing = || DataError::NoSuchColumn {
        path: path.to_owned(),
        requested: column.clone(),
        available: names.to_vec(),
        header,
    };
    match column {
        Column::Index(k) => {
            if (1..=names.len()).contains(k) {
                Ok(k - 1)
            } else {
                Err(missing())
            }
        }
        Column::Name(name) => {
            if !header {
                return Err(missing());
            }
            let exact: Vec<usize> = (0..names.len()).filter(|&i| names[i] == *name).collect();
            let matches = if exact.is_empty() {
                (0..names.len())
                    .filter(|&i| names[i].to_lowercase() == name.to_lowercase())
                    .collect()
            } else {
                exact
            };
            match matches.as_slice() {
                [] => Err(missing()),
                [only] => Ok(*only),
                several => Err(DataError::AmbiguousColumn {
                    path: path.to_owned(),
                    name: name.clone(),
                    indices: several.iter().map(|i| i + 1).collect(),
                }),
            }
        }
    }
}
