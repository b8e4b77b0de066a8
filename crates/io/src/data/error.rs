//! The one error type of reading, writing and checking records.

use std::fmt;
use std::io;
use std::path::PathBuf;

use super::{Column, Delimiter, RowRange};

/// How many entries lists of available columns or variables show in a message.
const LIST_LIMIT: usize = 30;

/// Everything that can go wrong reading, writing or checking records. Each message names the
/// file, line or row, and column involved and says what to do.
#[derive(Debug)]
#[non_exhaustive]
pub enum DataError {
    /// The file could not be opened or read (missing, a directory, no permission).
    Read {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: io::Error,
    },
    /// The file is larger than [`MAX_FILE_BYTES`](super::MAX_FILE_BYTES).
    TooLarge {
        /// The file.
        path: PathBuf,
    },
    /// The file could not be written.
    Write {
        /// The file.
        path: PathBuf,
        /// What went wrong, naming the path ("could not write PATH: reason").
        source: io::Error,
    },
    /// The file holds no rows of data: it is empty, or has only blank lines, comments or a
    /// header (or, for a MAT-file, the selected variable is empty).
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A line has a different number of fields than the first line.
    Ragged {
        /// The file.
        path: PathBuf,
        /// The offending line, counted from 1.
        line: usize,
        /// Its number of fields.
        found: usize,
        /// The first non-blank, non-comment line, which sets the number of fields.
        first_line: usize,
        /// The number of fields of that first line.
        expected: usize,
        /// The delimiter used (detected or given).
        delimiter: Delimiter,
    },
    /// A selected field is not a number.
    NotANumber {
        /// The file.
        path: PathBuf,
        /// The line, counted from 1.
        line: usize,
        /// The column's name (`column k` or the header name with its index).
        column: String,
        /// The field's text.
        text: String,
    },
    /// A value is NaN or infinite.
    NotFinite {
        /// The file, when the values came from one.
        path: Option<PathBuf>,
        /// The line of a text file, counted from 1.
        line: Option<usize>,
        /// The row of data (or sample), counted from 1.
        row: usize,
        /// The column's name.
        column: String,
        /// The value.
        value: f64,
    },
    /// A value beyond [`MAX_MAGNITUDE`](super::MAX_MAGNITUDE) in magnitude.
    OutOfRange {
        /// The file.
        path: PathBuf,
        /// The line of a text file, counted from 1.
        line: Option<usize>,
        /// The row of data (or sample), counted from 1.
        row: usize,
        /// The column's name.
        column: String,
        /// The value.
        value: f64,
    },
    /// A selected column does not exist in a text file.
    NoSuchColumn {
        /// The file.
        path: PathBuf,
        /// The column asked for.
        requested: Column,
        /// The names of the file's columns, in order (`column k` without a header).
        available: Vec<String>,
        /// Whether the file has a header (without one, columns have no names).
        header: bool,
    },
    /// A column name matches several header names.
    AmbiguousColumn {
        /// The file.
        path: PathBuf,
        /// The name asked for.
        name: String,
        /// The 1-based positions of the matching columns.
        indices: Vec<usize>,
    },
    /// The row range reaches past the rows of the file.
    RowsOutOfRange {
        /// The file.
        path: PathBuf,
        /// The range asked for.
        rows: RowRange,
        /// How many rows of data (samples) the file has.
        available: usize,
    },
    /// A column, row range, delimiter or header setting (or a selection) that cannot be used.
    InvalidArgument {
        /// What it is: `column`, `row range`, `delimiter`, `header`, `columns`.
        what: &'static str,
        /// The text or value given.
        text: String,
        /// Why it cannot be used.
        reason: String,
    },
    /// A MATLAB v7.3 MAT-file (HDF5), which cannot be read: re-save it with `-v7`.
    MatV73 {
        /// The file.
        path: PathBuf,
    },
    /// A file that is neither a MATLAB Level-5 MAT-file nor text (e.g. a MATLAB v4 file).
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// What it looks like and what to do.
        reason: String,
    },
    /// A Level-5 MAT-file the reader could not parse.
    MatUnreadable {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// A MAT-file without the variable asked for.
    NoSuchVariable {
        /// The file.
        path: PathBuf,
        /// The column asked for.
        requested: Column,
        /// The numeric variables of the file, as `name (rows×cols class)`.
        available: Vec<String>,
    },
    /// A MAT-file variable that cannot be read as one column.
    UnusableVariable {
        /// The file.
        path: PathBuf,
        /// The variable (with `:k` if a column was asked for).
        variable: String,
        /// Its dimensions.
        shape: Vec<usize>,
        /// Why, and what to ask for instead.
        reason: String,
    },
    /// Columns that should have the same length do not.
    LengthMismatch {
        /// The file, when there is one.
        path: Option<PathBuf>,
        /// Each column's name and length.
        lengths: Vec<(String, usize)>,
    },
    /// A time column does not increase strictly from one sample to the next.
    TimeNotIncreasing {
        /// The sample (counted from 1) that is not after the one before it.
        sample: usize,
        /// The time of the sample before.
        previous: f64,
        /// The time of this sample.
        value: f64,
    },
    /// A column holds one value only (e.g. the input was never driven).
    Constant {
        /// The column.
        column: String,
        /// Its only value.
        value: f64,
        /// Its number of samples.
        samples: usize,
    },
    /// Fewer samples than needed.
    TooFewSamples {
        /// What needs them, e.g. `identification of a model with 10 play operators`.
        what: String,
        /// How many are needed.
        needed: usize,
        /// How many there are.
        got: usize,
    },
    /// Columns or names that cannot be written as asked.
    InvalidWrite {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

impl DataError {
    /// Whether the error happened writing output (the command line's exit code for output
    /// errors) rather than reading or checking input.
    pub fn is_output(&self) -> bool {
        matches!(
            self,
            DataError::Write { .. } | DataError::InvalidWrite { .. }
        )
    }
}

/// `name (column k)` or `column k`, how messages name a column of a text file.
pub(super) fn column_label(names: &[String], header: bool, index: usize) -> String {
    let k = index + 1;
    match names.get(index) {
        Some(name) if header && *name != format!("column {k}") => {
            format!("\"{name}\" (column {k})")
        }
        _ => format!("column {k}"),
    }
}

/// A list of at most [`LIST_LIMIT`] entries, `a, b, c and 12 more`.
fn short_list(items: impl ExactSizeIterator<Item = String>) -> String {
    let total = items.len();
    let mut shown: Vec<String> = items.take(LIST_LIMIT).collect();
    if total > LIST_LIMIT {
        shown.push(format!("and {} more", total - LIST_LIMIT));
    }
    shown.join(", ")
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DataError::Read { path, source } => {
                write!(f, "cannot read {}: {source}", path.display())?;
                match source.kind() {
                    io::ErrorKind::NotFound => f.write_str(" (check the path and file name)"),
                    io::ErrorKind::PermissionDenied => {
                        f.write_str(" (check the file's permissions)")
                    }
                    io::ErrorKind::IsADirectory => f.write_str(" (give a file, not a folder)"),
                    _ => Ok(()),
                }
            }
            DataError::TooLarge { path } => write!(
                f,
                "{} is larger than the {} MiB a record may be (or never ends); split it, or \
                 keep the columns and rows you need",
                path.display(),
                super::MAX_FILE_BYTES >> 20
            ),
            // The source already reads "could not write PATH: reason".
            DataError::Write { source, .. } => write!(f, "{source}"),
            DataError::Empty { path } => write!(
                f,
                "{} holds no rows of data (it is empty, or has only blank lines, comments or a \
                 header): give a file with measurements",
                path.display()
            ),
            DataError::Ragged {
                path,
                line,
                found,
                first_line,
                expected,
                delimiter,
            } => write!(
                f,
                "{}, line {line}: {found} field{} where line {first_line} has {expected} \
                 (fields separated by {}); every row needs the same number of fields: check \
                 the delimiter, or remove a truncated or stray line",
                path.display(),
                if *found == 1 { "" } else { "s" },
                match delimiter {
                    Delimiter::Tab => "tabs",
                    Delimiter::Comma => "commas",
                    Delimiter::Semicolon => "semicolons",
                    Delimiter::Whitespace | Delimiter::Auto => "spaces or tabs",
                }
            ),
            DataError::NotANumber {
                path,
                line,
                column,
                text,
            } => {
                write!(
                    f,
                    "{}, line {line}, {column}: \"{text}\" is not a number",
                    path.display()
                )?;
                if text.is_empty() {
                    f.write_str(" (the field is empty: a missing value?)")
                } else if text.contains(',') && text.replace(',', ".").parse::<f64>().is_ok() {
                    f.write_str(
                        " (a decimal comma in a file whose fields the comma separates: save it \
                         with semicolons between fields, as Excel does in European locales, or \
                         write 1.5)",
                    )
                } else {
                    f.write_str(
                        " (select a numeric column; if this line holds names or units, select \
                         the rows after it, or set the header option)",
                    )
                }
            }
            DataError::NotFinite {
                path,
                line,
                row,
                column,
                value,
            } => {
                match (path, line) {
                    (Some(path), Some(line)) => {
                        write!(f, "{}, line {line} (row {row}), {column}", path.display())?
                    }
                    (Some(path), None) => write!(f, "{}, {column}, sample {row}", path.display())?,
                    (None, _) => write!(f, "{column}, sample {row}")?,
                }
                write!(
                    f,
                    ": {value} is not a finite number; remove or fill in the missing or \
                     overflowed samples, or select a row range without them"
                )
            }
            DataError::OutOfRange {
                path,
                line,
                row,
                column,
                value,
            } => {
                match line {
                    Some(line) => {
                        write!(f, "{}, line {line} (row {row}), {column}", path.display())?
                    }
                    None => write!(f, "{}, {column}, sample {row}", path.display())?,
                }
                write!(
                    f,
                    ": {value:e} is beyond {:e} in magnitude, the largest a record may hold; \
                     check the column's unit (or scale factor), or select rows without it",
                    super::MAX_MAGNITUDE
                )
            }
            DataError::NoSuchColumn {
                path,
                requested,
                available,
                header,
            } => {
                let count = available.len();
                match (requested, header) {
                    (Column::Name(name), false) => write!(
                        f,
                        "{}: no column named \"{name}\": the file has no header, so select one \
                         of its {count} columns by number (1 to {count})",
                        path.display()
                    ),
                    _ => write!(
                        f,
                        "{}: no {}; the file has {count} column{}: {}",
                        path.display(),
                        match requested {
                            Column::Index(k) => format!("column {k}"),
                            Column::Name(name) => format!("column named \"{name}\""),
                        },
                        if count == 1 { "" } else { "s" },
                        short_list(available.iter().enumerate().map(|(i, name)| {
                            if *header {
                                format!("{} \"{name}\"", i + 1)
                            } else {
                                format!("{}", i + 1)
                            }
                        }))
                    ),
                }?;
                if count == 1 {
                    f.write_str(
                        ". Only one column was found: if the file has more, check --delimiter \
                         (auto, comma, tab, semicolon or whitespace)",
                    )?;
                }
                Ok(())
            }
            DataError::AmbiguousColumn {
                path,
                name,
                indices,
            } => write!(
                f,
                "{}: the name \"{name}\" matches columns {}; select one by number",
                path.display(),
                indices
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            DataError::RowsOutOfRange {
                path,
                rows,
                available,
            } => write!(
                f,
                "{}: rows {rows} asked for, but the file has {available} row{} of data (1..{}); \
                 choose a range inside it",
                path.display(),
                if *available == 1 { "" } else { "s" },
                available
            ),
            DataError::InvalidArgument { what, text, reason } => {
                write!(f, "invalid {what} \"{text}\": {reason}")
            }
            DataError::MatV73 { path } => write!(
                f,
                "{} is a MATLAB v7.3 MAT-file (HDF5), which hystcomp cannot read: re-save it in \
                 MATLAB or Octave with save('file.mat', 'variable', ..., '-v7'), or export the \
                 columns as CSV",
                path.display()
            ),
            DataError::UnsupportedFormat { path, reason } => {
                write!(f, "cannot read {}: {reason}", path.display())
            }
            DataError::MatUnreadable { path, reason } => {
                write!(f, "cannot read the MAT-file {}: {reason}", path.display())
            }
            DataError::NoSuchVariable {
                path,
                requested,
                available,
            } => {
                match requested {
                    Column::Name(name) => {
                        write!(f, "{}: no numeric variable \"{name}\"", path.display())?
                    }
                    Column::Index(k) => write!(
                        f,
                        "{}: column {k} asked for, but a MAT-file's columns are chosen by \
                         variable name (a number works only when the file holds a single \
                         numeric variable)",
                        path.display()
                    )?,
                }
                if available.is_empty() {
                    f.write_str("; the file holds no numeric variables")
                } else {
                    write!(
                        f,
                        "; the file holds {}; select a vector by name, or column k of a matrix \
                         as name:k",
                        short_list(available.iter().cloned())
                    )
                }
            }
            DataError::UnusableVariable {
                path,
                variable,
                shape,
                reason,
            } => write!(
                f,
                "{}: variable \"{variable}\" ({}) {reason}",
                path.display(),
                shape_text(shape)
            ),
            DataError::LengthMismatch { path, lengths } => {
                if let Some(path) = path {
                    write!(f, "{}: ", path.display())?;
                }
                write!(
                    f,
                    "the columns differ in length ({}); every column needs the same number of \
                     samples",
                    lengths
                        .iter()
                        .map(|(name, n)| format!("{name}: {n}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
            DataError::TimeNotIncreasing {
                sample,
                previous,
                value,
            } => write!(
                f,
                "time is not increasing at sample {sample}: {value} follows {previous}; time \
                 must increase from each sample to the next (sort the record, remove repeated \
                 samples, or select the right time column)"
            ),
            DataError::Constant {
                column,
                value,
                samples,
            } => write!(
                f,
                "{column} is constant ({value} in all {samples} samples), so it carries no \
                 information: check the column selection and that the signal was recorded"
            ),
            DataError::TooFewSamples { what, needed, got } => write!(
                f,
                "too few samples for {what}: {got} given, at least {needed} needed; use a longer \
                 record or a wider row range"
            ),
            DataError::InvalidWrite { path, reason } => {
                write!(f, "cannot write {}: {reason}", path.display())
            }
        }
    }
}

impl std::error::Error for DataError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            DataError::Read { source, .. } | DataError::Write { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// `8027×1`, how messages show a MAT-file variable's dimensions.
pub(super) fn shape_text(shape: &[usize]) -> String {
    shape
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("×")
}
