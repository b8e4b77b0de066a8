//! Delimited text: CSV, tab-, semicolon- or whitespace-separated columns of numbers (see the
//! [module documentation](super) for the rules).

use std::io;
use std::path::Path;

use super::error::column_label;
use super::{
    Column, Columns, DataError, Delimiter, Header, MAX_MAGNITUDE, ReadOptions, check_row_range,
};

/// Whether a line of text is skipped: blank, a comment starting with `#` or `%`, or a row of
/// empty fields (only commas, semicolons, tabs and spaces: Excel writes `,,,,` for rows that
/// were formatted but left empty).
fn is_skipped_line(line: &str) -> bool {
    let trimmed = line.trim_start();
    trimmed.is_empty()
        || trimmed.starts_with(['#', '%'])
        || trimmed.chars().all(|c| matches!(c, ',' | ';' | '\t' | ' '))
}

/// A field's number, if it is one (`NaN` and `Inf` are numbers here).
pub(super) fn parse_number(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok()
}

/// A field's number in a file delimited by `delimiter`: as [`parse_number`], and where the
/// comma is not the delimiter, a decimal comma (`1,5`, one comma and no point) reads as `1.5`,
/// as European locales write numbers.
fn parse_field(text: &str, delimiter: Delimiter) -> Option<f64> {
    parse_number(text).or_else(|| {
        let trimmed = text.trim();
        let decimal_comma = delimiter != Delimiter::Comma
            && trimmed.matches(',').count() == 1
            && !trimmed.contains('.');
        decimal_comma
            .then(|| trimmed.replace(',', "."))
            .and_then(|t| t.parse::<f64>().ok())
    })
}

/// The byte order of UTF-16 text (as Excel's "Unicode text" and PowerShell write it): a
/// byte-order mark, or else every other byte zero in the first kilobytes of mostly ASCII text.
pub(super) fn utf16_order(bytes: &[u8]) -> Option<Utf16> {
    match bytes {
        [0xff, 0xfe, ..] => return Some(Utf16::Little),
        [0xfe, 0xff, ..] => return Some(Utf16::Big),
        _ => {}
    }
    let head = &bytes[..bytes.len().min(4096) & !1];
    if head.len() < 4 {
        return None;
    }
    let zeros_at = |parity: usize| head.iter().skip(parity).step_by(2).all(|&b| b == 0);
    let text_at = |parity: usize| {
        head.iter()
            .skip(parity)
            .step_by(2)
            .all(|&b| b == b'\t' || b == b'\n' || b == b'\r' || (0x20..0x7f).contains(&b))
    };
    if zeros_at(1) && text_at(0) {
        Some(Utf16::Little)
    } else if zeros_at(0) && text_at(1) {
        Some(Utf16::Big)
    } else {
        None
    }
}

/// The byte order of UTF-16 text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Utf16 {
    Little,
    Big,
}

/// The file's text: UTF-16 decoded, UTF-8 read with invalid bytes as U+FFFD, without a
/// byte-order mark.
fn decode(bytes: &[u8]) -> String {
    let text = match utf16_order(bytes) {
        Some(order) => {
            let units: Vec<u16> = bytes
                .chunks_exact(2)
                .map(|pair| match order {
                    Utf16::Little => u16::from_le_bytes([pair[0], pair[1]]),
                    Utf16::Big => u16::from_be_bytes([pair[0], pair[1]]),
                })
                .collect();
            String::from_utf16_lossy(&units)
        }
        None => String::from_utf8_lossy(bytes).into_owned(),
    };
    match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_owned(),
        None => text,
    }
}

/// The delimiter `Auto` chooses for a file whose first content line is `line`: a tab, else a
/// semicolon (a file delimited by semicolons writes decimal commas), else a comma, unless the
/// line is numbers with decimal commas separated by spaces (`0,5 1,25`), else whitespace.
fn detect_delimiter(line: &str) -> Delimiter {
    if line.contains('\t') {
        return Delimiter::Tab;
    }
    if line.contains(';') {
        return Delimiter::Semicolon;
    }
    if line.contains(',') {
        let words: Vec<&str> = line.split_whitespace().collect();
        let spaced_decimal_commas = words.len() > 1
            && words
                .iter()
                .all(|w| parse_field(w, Delimiter::Whitespace).is_some());
        let comma_fields_are_numbers = line.split(',').all(|f| parse_number(f).is_some());
        if spaced_decimal_commas && !comma_fields_are_numbers {
            return Delimiter::Whitespace;
        }
        return Delimiter::Comma;
    }
    Delimiter::Whitespace
}

/// Whether a record holds names rather than numbers: any non-empty field is not a number.
fn is_names(record: &csv::StringRecord, delimiter: Delimiter) -> bool {
    record
        .iter()
        .any(|field| !field.is_empty() && parse_field(field, delimiter).is_none())
}

/// Excel's delimiter line `sep=;` (any of `,` `;` tab space), if `line` is one.
fn separator_line(line: &str) -> Option<Delimiter> {
    let t = line.trim_start();
    if t.len() < 4 || !t.as_bytes()[..4].eq_ignore_ascii_case(b"sep=") {
        return None;
    }
    match &t[4..] {
        "," => Some(Delimiter::Comma),
        ";" => Some(Delimiter::Semicolon),
        "\t" => Some(Delimiter::Tab),
        " " => Some(Delimiter::Whitespace),
        _ => None,
    }
}

/// The lines of `text` that hold a header or data (see [`is_skipped_line`]), each followed by
/// a newline, with their line numbers in the file (from 1), and the delimiter of Excel's
/// `sep=` line when the first such line is one (it is left out).
fn content_lines(text: &str) -> (String, Vec<usize>, Option<Delimiter>) {
    let mut content = String::with_capacity(text.len());
    let mut line_numbers = Vec::new();
    let mut separator = None;
    for (i, line) in text.lines().enumerate() {
        if is_skipped_line(line) {
            continue;
        }
        if line_numbers.is_empty()
            && separator.is_none()
            && let Some(delimiter) = separator_line(line)
        {
            separator = Some(delimiter);
            continue;
        }
        content.push_str(line);
        content.push('\n');
        line_numbers.push(i + 1);
    }
    (content, line_numbers, separator)
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
    let text = decode(bytes);
    let (content, line_numbers, separator) = content_lines(&text);
    let Some(first_text) = content.lines().next() else {
        return Err(DataError::Empty {
            path: path.to_owned(),
        });
    };
    let delimiter = match (options.delimiter, separator) {
        (Delimiter::Auto, Some(given)) => given,
        (Delimiter::Auto, None) => detect_delimiter(first_text),
        (given, _) => given,
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
        Header::Auto => is_names(&record, delimiter),
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
            let value = parse_field(field, delimiter).ok_or_else(|| DataError::NotANumber {
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
            if value.abs() > MAX_MAGNITUDE {
                return Err(DataError::OutOfRange {
                    path: path.to_owned(),
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
    // A line of units under the header (`s,V,um`: no field a number) is part of the header.
    let mut units_possible = header;
    while let Some(line) = next(&mut record)? {
        if std::mem::take(&mut units_possible)
            && record.len() == expected
            && is_names(&record, delimiter)
            && record.iter().all(|f| parse_field(f, delimiter).is_none())
        {
            continue;
        }
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
