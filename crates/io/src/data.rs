//! Measured and desired records: columns of numbers read from delimited text files and from
//! MATLAB Level-5 `.mat` files, CSV written back, and the checks identification needs.
//!
//! # Reading
//!
//! [`read_columns`] reads the selected [`Column`]s of one file into a [`Columns`] record.
//! The format is chosen by the file's content (its magic bytes), whatever its extension: a
//! file whose 128-byte header marks a MATLAB Level-5 MAT-file is read as one, a MATLAB v7.3
//! (HDF5) file is refused with a message to re-save it with `-v7`, other binary files (a
//! MATLAB v4 `.mat` among them) are refused, and text is read as text (also a `.mat` file
//! that MATLAB wrote with `save -ascii`).
//!
//! ## Delimited text
//!
//! - **Lines.** Lines end in `\n` or `\r\n`. Blank lines (only spaces and tabs) and comment
//!   lines, whose first non-blank character is `#` or `%`, are skipped anywhere in the file;
//!   comments after numbers on the same line are not supported. A UTF-8 byte-order mark is
//!   ignored; bytes that are not UTF-8 (e.g. a Latin-1 `µ` in a header) become U+FFFD and do
//!   not stop numbers from being read.
//! - **Delimiter** ([`Delimiter`]). `Auto` looks at the first line that is neither blank nor a
//!   comment: a tab there means tab-separated, else a comma means comma-separated, else a
//!   semicolon means semicolon-separated, else fields are separated by runs of spaces or tabs.
//!   Comma, tab and semicolon files are split by the `csv` crate (double quotes allowed, spaces
//!   around fields trimmed); whitespace-separated files have no quoting.
//! - **Header** ([`Header`]). `Auto` takes the first non-blank, non-comment line as a header
//!   when any of its non-empty fields is not a number (`NaN`, `Inf` and `-Inf` count as
//!   numbers). Header names are trimmed; an empty name becomes `column k`.
//! - **Shape.** Every record must have as many fields as the first one (the header, if any),
//!   or the file is refused as ragged with both line numbers. Only the selected columns of the
//!   selected rows must hold finite numbers: other columns may hold text.
//! - **Rows.** A "row" is a row of data, counted from 1 after the header, skipping blank and
//!   comment lines, as a person counts rows of a table; messages also give the file's line
//!   number. [`ReadOptions::rows`] selects an inclusive range of them ([`RowRange`]).
//!
//! ## MATLAB Level-5 `.mat`
//!
//! Read with the `matfile` crate, uncompressed or compressed (`-v6`, `-v7`). A
//! [`Column::Name`] picks a real numeric variable holding a vector (any class: doubles,
//! singles and integers are converted to `f64`); `name:k` picks column `k` (from 1) of a 2-D
//! matrix, as MATLAB's `name(:, k)` (a vector, stored as a row or a column, is one column:
//! `name:1`). A [`Column::Index`] `k` picks column `k` of the file's only numeric variable,
//! and is refused when the file holds several. All selected columns
//! must have the same length; the row range selects samples (elements) the same way it
//! selects rows of a text file.
//!
//! # Writing
//!
//! [`write_csv`] (comma) and [`write_delimited`] write columns atomically (see
//! [`crate::atomic`]) with each number in the shortest form that reads back to the same `f64`,
//! so what is written reads back bit for bit.
//!
//! # Checks
//!
//! [`check_finite`], [`check_time_increasing`], [`check_not_constant`], [`check_min_samples`]
//! and [`check_same_length`] are the checks the command line and identification run on the
//! columns they use; each returns a [`DataError`] whose message says what to do.

use std::fmt::{self, Write as _};
use std::io;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// How many entries lists of available columns or variables show in a message.
const LIST_LIMIT: usize = 30;

/// The 8-byte signature of an HDF5 file (MATLAB v7.3 files are HDF5 files).
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

// ---------------------------------------------------------------------------------------------
// Selections and options
// ---------------------------------------------------------------------------------------------

/// One column to read: by its 1-based position or by its name.
///
/// Parsing (`"3".parse::<Column>()`) gives [`Column::Index`] for text of decimal digits and
/// [`Column::Name`] for anything else (surrounding spaces are trimmed); `"0"`, negative
/// numbers and empty text are refused, since columns are counted from 1.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Column {
    /// The column's position, counted from 1 as people count columns.
    Index(usize),
    /// The column's header name (text files) or the variable's name, optionally with `:k`
    /// for column `k` of a matrix (MAT-files). Text headers are matched exactly first, then
    /// ignoring letter case when that match is unique.
    Name(String),
}

impl FromStr for Column {
    type Err = DataError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let trimmed = text.trim();
        let invalid = |reason: &str| DataError::InvalidArgument {
            what: "column",
            text: text.to_owned(),
            reason: reason.to_owned(),
        };
        if trimmed.is_empty() {
            return Err(invalid(
                "it is empty: give a column number (from 1) or a column name",
            ));
        }
        let unsigned = trimmed.strip_prefix(['-', '+']).unwrap_or(trimmed);
        if !unsigned.is_empty() && unsigned.bytes().all(|b| b.is_ascii_digit()) {
            if trimmed.starts_with('-') {
                return Err(invalid("columns are counted from 1"));
            }
            return match unsigned.parse::<usize>() {
                Ok(0) => Err(invalid("columns are counted from 1: the first column is 1")),
                Ok(k) => Ok(Column::Index(k)),
                Err(_) => Err(invalid("the column number is too large")),
            };
        }
        Ok(Column::Name(trimmed.to_owned()))
    }
}

impl fmt::Display for Column {
    /// The text that parses back to this column: `3` or `voltage`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Column::Index(k) => write!(f, "{k}"),
            Column::Name(name) => f.write_str(name),
        }
    }
}

/// What separates the fields of a text file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Delimiter {
    /// Decide from the first non-blank, non-comment line: tab, else comma, else semicolon,
    /// else runs of whitespace.
    #[default]
    Auto,
    /// `,` (quoted fields allowed).
    Comma,
    /// A tab character (quoted fields allowed).
    Tab,
    /// `;` (quoted fields allowed; decimal commas are not supported).
    Semicolon,
    /// One or more spaces or tabs; leading and trailing whitespace is ignored, no quoting.
    Whitespace,
}

impl Delimiter {
    /// The delimiter `Auto` chooses for a file whose first content line is `line`.
    fn detect(line: &str) -> Delimiter {
        if line.contains('\t') {
            Delimiter::Tab
        } else if line.contains(',') {
            Delimiter::Comma
        } else if line.contains(';') {
            Delimiter::Semicolon
        } else {
            Delimiter::Whitespace
        }
    }

    /// The single byte the `csv` crate splits on, `None` for whitespace (and auto).
    fn byte(self) -> Option<u8> {
        match self {
            Delimiter::Comma => Some(b','),
            Delimiter::Tab => Some(b'\t'),
            Delimiter::Semicolon => Some(b';'),
            Delimiter::Auto | Delimiter::Whitespace => None,
        }
    }
}

impl FromStr for Delimiter {
    type Err = DataError;

    /// Accepts `auto`, `comma` or `,`, `tab` or `\t`, `semicolon` or `;`, `whitespace` or
    /// `space` (any letter case).
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        // A lone tab or space character given literally.
        let word = match text {
            "\t" => "tab",
            " " => "whitespace",
            other => other.trim(),
        };
        match word.to_ascii_lowercase().as_str() {
            "auto" => Ok(Delimiter::Auto),
            "comma" | "," => Ok(Delimiter::Comma),
            "tab" | "\\t" => Ok(Delimiter::Tab),
            "semicolon" | ";" => Ok(Delimiter::Semicolon),
            "whitespace" | "space" | "spaces" => Ok(Delimiter::Whitespace),
            _ => Err(DataError::InvalidArgument {
                what: "delimiter",
                text: text.to_owned(),
                reason: "expected one of auto, comma, tab, semicolon, whitespace".to_owned(),
            }),
        }
    }
}

impl fmt::Display for Delimiter {
    /// The word [`Delimiter::from_str`] accepts: `auto`, `comma`, `tab`, `semicolon`,
    /// `whitespace`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Delimiter::Auto => "auto",
            Delimiter::Comma => "comma",
            Delimiter::Tab => "tab",
            Delimiter::Semicolon => "semicolon",
            Delimiter::Whitespace => "whitespace",
        })
    }
}

/// Whether the first non-blank, non-comment line of a text file holds column names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Header {
    /// A header when any non-empty field of that line is not a number.
    #[default]
    Auto,
    /// The line is a header (even if its names look like numbers).
    Present,
    /// The line is data: columns are named `column 1`, `column 2`, ...
    Absent,
}

impl FromStr for Header {
    type Err = DataError;

    /// Accepts `auto`, `present` (or `yes`), `absent` (or `no`, `none`), any letter case.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Header::Auto),
            "present" | "yes" => Ok(Header::Present),
            "absent" | "no" | "none" => Ok(Header::Absent),
            _ => Err(DataError::InvalidArgument {
                what: "header",
                text: text.to_owned(),
                reason: "expected one of auto, present, absent".to_owned(),
            }),
        }
    }
}

impl fmt::Display for Header {
    /// The word [`Header::from_str`] accepts: `auto`, `present`, `absent`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Header::Auto => "auto",
            Header::Present => "present",
            Header::Absent => "absent",
        })
    }
}

/// An inclusive range of rows of data (or samples of a MAT-file variable), counted from 1:
/// `RowRange { first: 101, last: Some(200) }` is the 100 rows 101 to 200.
///
/// As text (`"101..200".parse()`): `first..last` (both inclusive), `first..` (to the end) or
/// `..last` (from row 1). Note that, unlike a Rust range, `last` is included.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RowRange {
    /// The first row read, counted from 1.
    pub first: usize,
    /// The last row read (inclusive); `None` reads to the end of the file.
    pub last: Option<usize>,
}

impl RowRange {
    /// A checked range: `first` at least 1 and `last`, if given, not before `first`.
    pub fn new(first: usize, last: Option<usize>) -> Result<Self, DataError> {
        let range = RowRange { first, last };
        range.validate()?;
        Ok(range)
    }

    fn validate(&self) -> Result<(), DataError> {
        let invalid = |reason: &str| DataError::InvalidArgument {
            what: "row range",
            text: self.to_string(),
            reason: reason.to_owned(),
        };
        if self.first == 0 {
            return Err(invalid("rows are counted from 1: the first row is 1"));
        }
        match self.last {
            Some(last) if last < self.first => {
                Err(invalid("the last row comes before the first row"))
            }
            _ => Ok(()),
        }
    }
}

impl FromStr for RowRange {
    type Err = DataError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let invalid = |reason: &str| DataError::InvalidArgument {
            what: "row range",
            text: text.to_owned(),
            reason: reason.to_owned(),
        };
        let Some((first, last)) = text.trim().split_once("..") else {
            return Err(invalid(
                "expected first..last (inclusive, from 1), first.. or ..last",
            ));
        };
        let number = |part: &str| -> Result<Option<usize>, DataError> {
            let part = part.trim();
            if part.is_empty() {
                return Ok(None);
            }
            part.parse::<usize>()
                .map(Some)
                .map_err(|_| invalid(&format!("\"{part}\" is not a row number")))
        };
        let first = number(first)?.unwrap_or(1);
        let last = number(last.strip_prefix('=').unwrap_or(last))?;
        let range = RowRange { first, last };
        range.validate().map_err(|error| match error {
            DataError::InvalidArgument { reason, .. } => invalid(&reason),
            other => other,
        })?;
        Ok(range)
    }
}

impl fmt::Display for RowRange {
    /// `first..last` or `first..`, the text [`RowRange::from_str`] reads back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.last {
            Some(last) => write!(f, "{}..{}", self.first, last),
            None => write!(f, "{}..", self.first),
        }
    }
}

/// How [`read_columns`] reads a file. The default reads the whole file and detects the
/// delimiter and the header. Delimiter and header apply to text files only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ReadOptions {
    /// What separates fields in a text file.
    pub delimiter: Delimiter,
    /// Whether a text file starts with a line of column names.
    pub header: Header,
    /// The rows (samples) to read, 1-based and inclusive; `None` reads them all. A range
    /// reaching past the end of the file is refused, not shortened.
    pub rows: Option<RowRange>,
}

/// The columns [`read_columns`] read: one name and one vector of values per selected column,
/// all of the same length, in the order they were asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Columns {
    /// The file they were read from.
    pub path: PathBuf,
    /// One name per column: the header name, `column k` for a file without header (or an
    /// empty header name), the variable name or `name:k` for a MAT-file.
    pub names: Vec<String>,
    /// One vector of finite values per column, all of the same length.
    pub values: Vec<Vec<f64>>,
    /// The row (sample) of the file, counted from 1, that `values[c][0]` comes from: 1
    /// unless a row range was given.
    pub first_row: usize,
}

impl Columns {
    /// The number of samples (rows) in each column.
    pub fn len(&self) -> usize {
        self.values.first().map_or(0, Vec::len)
    }

    /// Whether the columns hold no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values of the `c`-th selected column (from 0, in the order asked for).
    pub fn column(&self, c: usize) -> Option<&[f64]> {
        self.values.get(c).map(Vec::as_slice)
    }

    /// The row of the file (counted from 1) that sample `sample` (counted from 1, as the
    /// checks report it) of these columns comes from.
    pub fn file_row(&self, sample: usize) -> usize {
        self.first_row + sample.saturating_sub(1)
    }
}

// ---------------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------------

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
fn column_label(names: &[String], header: bool, index: usize) -> String {
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
                    f.write_str(" (decimal commas are not supported: write 1.5, not 1,5)")
                } else {
                    f.write_str(
                        " (select a numeric column, or set the header option if this line \
                         holds names)",
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
fn shape_text(shape: &[usize]) -> String {
    shape
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("×")
}

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------

/// Reads the selected columns of a delimited text file or a MATLAB Level-5 MAT-file (see the
/// [module documentation](self) for the formats), refusing with a [`DataError`]:
///
/// - a file that is missing or unreadable ([`DataError::Read`]), empty or without rows of data
///   ([`DataError::Empty`]), a MATLAB v7.3 file ([`DataError::MatV73`]) or another binary
///   format ([`DataError::UnsupportedFormat`], [`DataError::MatUnreadable`]);
/// - an empty selection or `Column::Index(0)` ([`DataError::InvalidArgument`]);
/// - a line with a different number of fields ([`DataError::Ragged`]);
/// - a selected field that is not a number ([`DataError::NotANumber`]) or is NaN or infinite
///   ([`DataError::NotFinite`]);
/// - a column or variable that does not exist ([`DataError::NoSuchColumn`],
///   [`DataError::NoSuchVariable`], [`DataError::AmbiguousColumn`],
///   [`DataError::UnusableVariable`]), or MAT-file variables of different lengths
///   ([`DataError::LengthMismatch`]);
/// - a row range reaching past the file's rows ([`DataError::RowsOutOfRange`]).
///
/// Checks that depend on what a column means (time increasing, input not constant, enough
/// samples for a model) are the caller's: see [`check_time_increasing`] and the other checks.
///
/// # Example
///
/// ```
/// use hystcomp_io::data::{Column, ReadOptions, read_columns};
/// # let dir = tempfile::tempdir()?;
/// # let path = dir.path().join("record.dat");
/// # std::fs::write(&path, "0.000\t1.80\t-123.1\n0.005\t1.85\t-120.2\n")?;
/// // A tab-separated record without header, like the micromanipulator files.
/// let columns: Vec<Column> = ["2", "3"].iter().map(|c| c.parse()).collect::<Result<_, _>>()?;
/// let record = read_columns(&path, &columns, &ReadOptions::default())?;
/// assert_eq!(record.names, ["column 2", "column 3"]);
/// assert_eq!(record.values[0], [1.8, 1.85]);
/// assert_eq!(record.len(), 2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_columns(
    path: &Path,
    columns: &[Column],
    options: &ReadOptions,
) -> Result<Columns, DataError> {
    if columns.is_empty() {
        return Err(DataError::InvalidArgument {
            what: "columns",
            text: String::new(),
            reason: "select at least one column".to_owned(),
        });
    }
    if columns.contains(&Column::Index(0)) {
        return Err(DataError::InvalidArgument {
            what: "column",
            text: "0".to_owned(),
            reason: "columns are counted from 1: the first column is 1".to_owned(),
        });
    }
    if let Some(rows) = &options.rows {
        rows.validate()?;
    }
    let bytes = std::fs::read(path).map_err(|source| DataError::Read {
        path: path.to_owned(),
        source,
    })?;
    if bytes.is_empty() {
        return Err(DataError::Empty {
            path: path.to_owned(),
        });
    }
    match detect_format(path, &bytes) {
        Format::MatLevel5 => read_mat(path, &bytes, columns, options),
        Format::MatV73 => Err(DataError::MatV73 {
            path: path.to_owned(),
        }),
        Format::Unsupported(reason) => Err(DataError::UnsupportedFormat {
            path: path.to_owned(),
            reason,
        }),
        Format::Text => read_text(path, &bytes, columns, options),
    }
}

/// What a file is, judged from its first bytes and its extension.
enum Format {
    Text,
    MatLevel5,
    MatV73,
    Unsupported(String),
}

fn detect_format(path: &Path, bytes: &[u8]) -> Format {
    let hdf5_at = |offset: usize| bytes.get(offset..offset + 8) == Some(HDF5_SIGNATURE);
    if bytes.starts_with(b"MATLAB 7.3 MAT-file") || hdf5_at(512) {
        return Format::MatV73;
    }
    // The Level-5 header: 116 bytes of text, 8 bytes of subsystem offset, a 2-byte version
    // (0x0100; 0x0200 in v7.3 files) and the endian indicator "IM" (little-endian) or "MI".
    if let Some(flags) = bytes.get(124..128) {
        let version = match &flags[2..4] {
            b"IM" => Some(u16::from_le_bytes([flags[0], flags[1]])),
            b"MI" => Some(u16::from_be_bytes([flags[0], flags[1]])),
            _ => None,
        };
        match version {
            Some(0x0100) if bytes[..4].iter().all(|&b| b != 0) => return Format::MatLevel5,
            Some(0x0200) => return Format::MatV73,
            _ => {}
        }
    }
    if hdf5_at(0) {
        return Format::Unsupported(
            "it is an HDF5 file, not a table of numbers; if it is a MATLAB v7.3 file, re-save \
             it with save(..., '-v7')"
                .to_owned(),
        );
    }
    let is_mat = path
        .extension()
        .is_some_and(|ext| ext.eq_ignore_ascii_case("mat"));
    // Text has no NUL bytes; binary formats (MATLAB v4 headers among them) almost always do.
    let head = &bytes[..bytes.len().min(8192)];
    let binary = head.contains(&0);
    if is_mat && binary {
        return Format::Unsupported(
            "it ends in .mat but has no MATLAB Level-5 header (it may be a MATLAB v4 file); \
             re-save it in MATLAB with save(..., '-v7')"
                .to_owned(),
        );
    }
    if binary {
        return Format::Unsupported(
            "it is a binary file; give delimited text (CSV, tab- or space-separated) or a \
             MATLAB Level-5 .mat file"
                .to_owned(),
        );
    }
    Format::Text
}

/// Whether a line of text is skipped: blank, or a comment starting with `#` or `%`.
fn is_skipped_line(line: &str) -> bool {
    let trimmed = line.trim_start();
    trimmed.is_empty() || trimmed.starts_with(['#', '%'])
}

/// A field's number, if it is one (`NaN` and `Inf` are numbers here).
fn parse_number(text: &str) -> Option<f64> {
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

fn read_text(
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

/// Refuses a row range that reaches past `available` rows.
fn check_row_range(path: &Path, rows: Option<RowRange>, available: usize) -> Result<(), DataError> {
    match rows {
        Some(range) if range.first > available || range.last.is_some_and(|l| l > available) => {
            Err(DataError::RowsOutOfRange {
                path: path.to_owned(),
                rows: range,
                available,
            })
        }
        _ => Ok(()),
    }
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

// ---------------------------------------------------------------------------------------------
// MAT-files
// ---------------------------------------------------------------------------------------------

/// A MAT-file variable's class, as MATLAB names it.
fn class_name(data: &matfile::NumericData) -> &'static str {
    use matfile::NumericData as D;
    match data {
        D::Double { .. } => "double",
        D::Single { .. } => "single",
        D::Int8 { .. } => "int8",
        D::UInt8 { .. } => "uint8",
        D::Int16 { .. } => "int16",
        D::UInt16 { .. } => "uint16",
        D::Int32 { .. } => "int32",
        D::UInt32 { .. } => "uint32",
        D::Int64 { .. } => "int64",
        D::UInt64 { .. } => "uint64",
    }
}

/// A real variable's values as `f64`, in MATLAB's column-major order; `None` when complex.
/// Integers above 2^53 in magnitude are rounded to the nearest `f64`.
fn real_values(data: &matfile::NumericData) -> Option<Vec<f64>> {
    use matfile::NumericData as D;
    fn convert<T: Copy>(real: &[T], imag: &Option<Vec<T>>, f: fn(T) -> f64) -> Option<Vec<f64>> {
        match imag {
            Some(_) => None,
            None => Some(real.iter().map(|&x| f(x)).collect()),
        }
    }
    match data {
        D::Double { real, imag } => convert(real, imag, |x| x),
        D::Single { real, imag } => convert(real, imag, f64::from),
        D::Int8 { real, imag } => convert(real, imag, f64::from),
        D::UInt8 { real, imag } => convert(real, imag, f64::from),
        D::Int16 { real, imag } => convert(real, imag, f64::from),
        D::UInt16 { real, imag } => convert(real, imag, f64::from),
        D::Int32 { real, imag } => convert(real, imag, f64::from),
        D::UInt32 { real, imag } => convert(real, imag, f64::from),
        // Precision beyond 2^53 is lost, as MATLAB's double() loses it.
        D::Int64 { real, imag } => convert(real, imag, |x| x as f64),
        D::UInt64 { real, imag } => convert(real, imag, |x| x as f64),
    }
}

/// Why a Level-5 MAT-file is cut short, if it is: walks the data elements' tags after the
/// 128-byte header (each tag gives its element's type and size) and reports the first element
/// that reaches past the end of the file. The MAT-file reader itself stops silently there, and
/// the file would seem to hold fewer (or no) variables.
fn mat_truncation(bytes: &[u8]) -> Option<String> {
    const HEADER: usize = 128;
    let little = match bytes.get(126..HEADER) {
        Some(b"IM") => true,
        Some(b"MI") => false,
        _ => return None,
    };
    let word = |at: usize| -> Option<u32> {
        let b: [u8; 4] = bytes.get(at..at + 4)?.try_into().ok()?;
        Some(if little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    };
    let damaged = |at: usize, needed: usize| {
        Some(format!(
            "the file is truncated or damaged: the variable stored at byte {at} needs {needed} \
             bytes but the file ends after {}; copy it again from its source, or save it again \
             with save(..., '-v7')",
            bytes.len() - at
        ))
    };
    let mut at = HEADER;
    while at < bytes.len() {
        let Some(kind) = word(at) else {
            return damaged(at, 8);
        };
        if kind >> 16 != 0 {
            // Small data element: tag and data in 8 bytes.
            if at + 8 > bytes.len() {
                return damaged(at, 8);
            }
            at += 8;
            continue;
        }
        let Some(size) = word(at + 4) else {
            return damaged(at, 8);
        };
        let size = size as usize;
        // miCOMPRESSED (15) elements are not padded; the others are, to a multiple of 8 bytes
        // (the padding of the last element included: MATLAB and SciPy write it).
        let padded = if kind == 15 {
            size
        } else {
            size.div_ceil(8) * 8
        };
        let needed = 8 + padded;
        if at + needed > bytes.len() {
            return damaged(at, needed);
        }
        at += needed;
    }
    None
}

fn read_mat(
    path: &Path,
    bytes: &[u8],
    columns: &[Column],
    options: &ReadOptions,
) -> Result<Columns, DataError> {
    if let Some(reason) = mat_truncation(bytes) {
        return Err(DataError::MatUnreadable {
            path: path.to_owned(),
            reason,
        });
    }
    // The reader is third-party code given untrusted bytes: a panic inside it becomes an error.
    let parsed = std::panic::catch_unwind(|| matfile::MatFile::parse(bytes)).map_err(|_| {
        DataError::MatUnreadable {
            path: path.to_owned(),
            reason: "the file is damaged (the MAT-file reader failed on it); save it again with \
                     save(..., '-v7'), or export the columns as CSV"
                .to_owned(),
        }
    })?;
    let mat = parsed.map_err(|error| DataError::MatUnreadable {
        path: path.to_owned(),
        reason: match error {
            matfile::Error::IOError(error) => error.to_string(),
            matfile::Error::ParseError(_) => "the file is damaged, or holds a variable the \
                 reader does not support (int32 arrays, for one: convert them with double(x) \
                 and save again with save(..., '-v7'))"
                .to_owned(),
            matfile::Error::ConversionError => "a variable's stored number type does not \
                 match its class; save it again with save(..., '-v7'), or export the columns \
                 as CSV"
                .to_owned(),
            matfile::Error::InternalError => "the MAT-file reader failed; save the file again \
                 with save(..., '-v7'), or export the columns as CSV"
                .to_owned(),
        },
    })?;
    let arrays = mat.arrays();
    let available: Vec<String> = arrays
        .iter()
        .map(|a| {
            format!(
                "{} ({} {})",
                a.name(),
                shape_text(a.size()),
                class_name(a.data())
            )
        })
        .collect();

    let mut names = Vec::with_capacity(columns.len());
    let mut values = Vec::with_capacity(columns.len());
    for column in columns {
        let no_such = || DataError::NoSuchVariable {
            path: path.to_owned(),
            requested: column.clone(),
            available: available.clone(),
        };
        let (array, column_k) = match column {
            Column::Name(name) => match mat.find_by_name(name) {
                Some(array) => (array, None),
                None => {
                    let (base, k) = name.rsplit_once(':').ok_or_else(no_such)?;
                    let k = k.trim().parse::<usize>().map_err(|_| no_such())?;
                    (mat.find_by_name(base.trim()).ok_or_else(no_such)?, Some(k))
                }
            },
            Column::Index(k) => match arrays.as_slice() {
                [only] => (only, Some(*k)),
                _ => return Err(no_such()),
            },
        };
        let (name, column_values) = mat_column(path, array, column_k)?;
        names.push(name);
        values.push(column_values);
    }

    let lengths: Vec<(String, usize)> = names
        .iter()
        .cloned()
        .zip(values.iter().map(Vec::len))
        .collect();
    if lengths.iter().any(|(_, n)| *n != lengths[0].1) {
        return Err(DataError::LengthMismatch {
            path: Some(path.to_owned()),
            lengths,
        });
    }
    let available_rows = lengths[0].1;
    if available_rows == 0 {
        return Err(DataError::Empty {
            path: path.to_owned(),
        });
    }
    check_row_range(path, options.rows, available_rows)?;
    let (first, last) = match options.rows {
        Some(rows) => (rows.first, rows.last.unwrap_or(available_rows)),
        None => (1, available_rows),
    };
    for (name, column) in names.iter().zip(&mut values) {
        column.truncate(last);
        column.drain(..first - 1);
        if let Some(i) = column.iter().position(|v| !v.is_finite()) {
            return Err(DataError::NotFinite {
                path: Some(path.to_owned()),
                line: None,
                row: first + i,
                column: format!("variable \"{name}\""),
                value: column[i],
            });
        }
    }
    Ok(Columns {
        path: path.to_owned(),
        names,
        values,
        first_row: first,
    })
}

/// The name and values of a vector variable, or of column `k` (from 1) of a 2-D matrix; a
/// vector (row or column) counts as a single column.
fn mat_column(
    path: &Path,
    array: &matfile::Array,
    k: Option<usize>,
) -> Result<(String, Vec<f64>), DataError> {
    let shape = array.size().clone();
    let unusable = |variable: String, reason: String| DataError::UnusableVariable {
        path: path.to_owned(),
        variable,
        shape: shape.clone(),
        reason,
    };
    let name = array.name().to_owned();
    let mut all = real_values(array.data()).ok_or_else(|| {
        unusable(
            name.clone(),
            "is complex; save its real part, e.g. x = real(x)".to_owned(),
        )
    })?;
    let elements: usize = shape.iter().product();
    if all.len() != elements {
        return Err(DataError::MatUnreadable {
            path: path.to_owned(),
            reason: format!(
                "variable \"{name}\" has {} values for dimensions {}, so the file is \
                 damaged; save it again with save(..., '-v7')",
                all.len(),
                shape_text(&shape)
            ),
        });
    }
    let non_singleton = shape.iter().filter(|&&d| d != 1).count();
    let is_vector = non_singleton <= 1;
    match k {
        None if is_vector => Ok((name, all)),
        // A vector is its own (only) column, whether stored as a row or a column.
        Some(1) if is_vector => Ok((name, all)),
        Some(k) if is_vector => Err(unusable(
            format!("{name}:{k}"),
            format!("is a vector, so it has no column {k}; select it as {name}"),
        )),
        None if shape.len() == 2 => Err(unusable(
            name.clone(),
            format!(
                "is a matrix, not a vector; select one of its columns as {name}:1 to {name}:{}",
                shape[1]
            ),
        )),
        None => Err(unusable(
            name,
            "has more than two dimensions; only vectors and columns of 2-D matrices can be read"
                .to_owned(),
        )),
        Some(k) => {
            let label = format!("{name}:{k}");
            if shape.len() != 2 {
                return Err(unusable(
                    label,
                    "is not a 2-D matrix, so it has no columns to select".to_owned(),
                ));
            }
            let (rows, cols) = (shape[0], shape[1]);
            if k == 0 || k > cols {
                return Err(unusable(
                    label,
                    format!(
                        "has no column {k}: it has {cols} column{} (counted from 1)",
                        if cols == 1 { "" } else { "s" }
                    ),
                ));
            }
            all.truncate(k * rows);
            all.drain(..(k - 1) * rows);
            Ok((label, all))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------

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
/// let position = [0.1, -2.5e-7, 1e300];
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
/// `1e-7`, `-0.0`), so [`read_columns`] returns exactly what was written. Lines end in `\n`.
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
    let contents = writer
        .into_inner()
        .map_err(|error| write_error(error.into_error().into()))?;
    crate::atomic::write_atomic(path, &contents).map_err(|source| DataError::Write {
        path: path.to_owned(),
        source,
    })
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
    if delimiter == Delimiter::Whitespace {
        if let Some(name) = header
            .iter()
            .find(|n| n.is_empty() || n.contains(char::is_whitespace) || n.contains('"'))
        {
            return Err(format!(
                "the column name \"{name}\" is empty or contains spaces or quotes, which \
                 whitespace-separated files cannot hold; use another delimiter or name"
            ));
        }
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

// ---------------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------------

/// Refuses NaN or infinite values, naming the column and the first bad sample (counted from
/// 1) with [`DataError::NotFinite`].
pub fn check_finite(name: &str, values: &[f64]) -> Result<(), DataError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(DataError::NotFinite {
            path: None,
            line: None,
            row: i + 1,
            column: name.to_owned(),
            value: values[i],
        }),
        None => Ok(()),
    }
}

/// Refuses a time column that does not increase strictly from each sample to the next (a
/// repeated or earlier time), with [`DataError::TimeNotIncreasing`] naming the first
/// offending sample (counted from 1), and NaN or infinite times with
/// [`DataError::NotFinite`]. Fewer than two samples pass.
pub fn check_time_increasing(time: &[f64]) -> Result<(), DataError> {
    check_finite("time", time)?;
    for (i, pair) in time.windows(2).enumerate() {
        let increasing = pair[0] < pair[1];
        if !increasing {
            return Err(DataError::TimeNotIncreasing {
                sample: i + 2,
                previous: pair[0],
                value: pair[1],
            });
        }
    }
    Ok(())
}

/// Refuses a column whose samples are all equal (e.g. an input that was never driven or a
/// sensor that was not connected) with [`DataError::Constant`], and a column of fewer than
/// two samples with [`DataError::TooFewSamples`].
pub fn check_not_constant(name: &str, values: &[f64]) -> Result<(), DataError> {
    match values {
        [] | [_] => Err(DataError::TooFewSamples {
            what: format!("{name} to vary"),
            needed: 2,
            got: values.len(),
        }),
        [first, rest @ ..] => {
            if rest.iter().all(|v| v == first) {
                Err(DataError::Constant {
                    column: name.to_owned(),
                    value: *first,
                    samples: values.len(),
                })
            } else {
                Ok(())
            }
        }
    }
}

/// Refuses `got` samples when `what` (e.g. `identification of a model with 10 play
/// operators`) needs at least `needed`, with [`DataError::TooFewSamples`].
pub fn check_min_samples(needed: usize, got: usize, what: &str) -> Result<(), DataError> {
    if got < needed {
        Err(DataError::TooFewSamples {
            what: what.to_owned(),
            needed,
            got,
        })
    } else {
        Ok(())
    }
}

/// Refuses named columns of different lengths (e.g. an input and an output recorded
/// separately) with [`DataError::LengthMismatch`] listing every length.
pub fn check_same_length(columns: &[(&str, &[f64])]) -> Result<(), DataError> {
    match columns.first() {
        Some((_, first)) if columns.iter().any(|(_, c)| c.len() != first.len()) => {
            Err(DataError::LengthMismatch {
                path: None,
                lengths: columns
                    .iter()
                    .map(|(name, c)| ((*name).to_owned(), c.len()))
                    .collect(),
            })
        }
        _ => Ok(()),
    }
}
