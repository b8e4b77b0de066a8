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
//! - **Encoding.** UTF-8 (a byte-order mark is ignored; bytes that are not UTF-8, e.g. a
//!   Latin-1 `µ` in a header, become U+FFFD and do not stop numbers from being read) or UTF-16
//!   in either byte order, as Excel's "Unicode text" and PowerShell write it (with a byte-order
//!   mark, or recognised by its zero bytes).
//! - **Lines.** Lines end in `\n` or `\r\n`. Blank lines (only spaces and tabs), comment
//!   lines, whose first non-blank character is `#` or `%`, and rows of empty fields (only
//!   commas, semicolons, tabs and spaces, as Excel writes `,,,,` for formatted empty rows) are
//!   skipped anywhere in the file; comments after numbers on the same line are not supported.
//! - **Delimiter** ([`Delimiter`]). Excel's first line `sep=;` (or `sep=,`) names it and is
//!   skipped. Otherwise `Auto` looks at the first line that is neither blank nor a comment: a
//!   tab there means tab-separated, else a semicolon means semicolon-separated, else a comma
//!   means comma-separated (unless the line is numbers with decimal commas between spaces),
//!   else fields are separated by runs of spaces or tabs. Comma, tab and semicolon files are
//!   split by the `csv` crate (double quotes allowed, spaces around fields trimmed);
//!   whitespace-separated files have no quoting.
//! - **Numbers.** Decimal points; in files not separated by commas also decimal commas
//!   (`1,5`: one comma and no point), as European locales write them. Selected values must be
//!   finite and at most [`MAX_MAGNITUDE`] (1e15) in magnitude.
//! - **Header** ([`Header`]). `Auto` takes the first non-blank, non-comment line as a header
//!   when any of its non-empty fields is not a number (`NaN`, `Inf` and `-Inf` count as
//!   numbers). Header names are trimmed; an empty name becomes `column k`. A line right under
//!   the header whose fields are all names, not numbers (units: `s,V,um`), belongs to the
//!   header.
//! - **Shape.** Every record must have as many fields as the first one (the header, if any),
//!   or the file is refused as ragged with both line numbers. Only the selected columns of the
//!   selected rows must hold finite numbers: other columns may hold text.
//! - **Rows.** A "row" is a row of data, counted from 1 after the header, skipping blank and
//!   comment lines, as a person counts rows of a table; messages also give the file's line
//!   number. [`ReadOptions::rows`] selects an inclusive range of them ([`RowRange`]).
//!
//! ## MATLAB Level-5 `.mat`
//!
//! Read by our own bounded reader (`level5.rs`, from MathWorks' published format), uncompressed
//! or compressed (`-v6`, `-v7`), either byte order. Every size in the file is checked before it
//! is used, compressed variables decompress to at most [`MAX_MAT_BYTES`] in all, and a column
//! holds at most [`MAX_MAT_VALUES`] values; the reader never panics and never prints. A
//! [`Column::Name`] picks a real numeric variable holding a vector (any class: doubles,
//! singles and integers are converted to `f64`); `name:k` picks column `k` (from 1) of a 2-D
//! matrix, as MATLAB's `name(:, k)` (a vector, stored as a row or a column, is one column:
//! `name:1`). A [`Column::Index`] `k` picks column `k` of the file's only numeric variable,
//! and is refused when the file holds several. All selected columns
//! must have the same length; the row range selects samples (elements) the same way it
//! selects rows of a text file.
//!
//! Files larger than [`MAX_FILE_BYTES`] are refused before they are read, whatever their
//! format; [`read_bytes`] reads contents already in memory.
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

mod checks;
mod error;
mod level5;
mod mat;
mod text;
mod write;

pub use checks::{
    check_finite, check_min_samples, check_not_constant, check_same_length, check_time_increasing,
    mean_time_step,
};
pub use error::DataError;
pub use level5::{MAX_MAT_BYTES, MAX_MAT_VALUES};
pub use write::{encode_csv, encode_delimited, write_csv, write_delimited};

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The largest magnitude a value of a record may have (1e15): larger values are refused when
/// the file is read ([`DataError::OutOfRange`]), so that the squares and sums of the indices
/// and fits stay finite (a sample of 1e308 turned e_rms into inf and e_mhe into 0).
pub const MAX_MAGNITUDE: f64 = 1e15;

/// The largest file [`read_columns`] reads (2 GiB); a larger one is refused before it is
/// read ([`DataError::TooLarge`]).
pub const MAX_FILE_BYTES: u64 = 2 << 30;

/// The 8-byte signature of an HDF5 file (MATLAB v7.3 files are HDF5 files).
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

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
    /// Excel's `sep=` line, else decide from the first non-blank, non-comment line: tab, else
    /// semicolon, else comma, else runs of whitespace (see the module documentation).
    #[default]
    Auto,
    /// `,` (quoted fields allowed).
    Comma,
    /// A tab character (quoted fields allowed).
    Tab,
    /// `;` (quoted fields allowed; decimal commas `1,5` read as `1.5`).
    Semicolon,
    /// One or more spaces or tabs; leading and trailing whitespace is ignored, no quoting.
    Whitespace,
}

impl Delimiter {
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

/// Reads the selected columns of a delimited text file or a MATLAB Level-5 MAT-file (see the
/// [module documentation](self) for the formats), refusing with a [`DataError`]:
///
/// - a file that is missing or unreadable ([`DataError::Read`]), larger than
///   [`MAX_FILE_BYTES`] ([`DataError::TooLarge`]), empty or without rows of data
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
    check_selection(columns, options)?;
    let read_error = |source| DataError::Read {
        path: path.to_owned(),
        source,
    };
    let bytes = match crate::bounded::read_at_most(path, MAX_FILE_BYTES).map_err(read_error)? {
        crate::bounded::Bounded::Whole(bytes) => bytes,
        crate::bounded::Bounded::TooLarge => {
            return Err(DataError::TooLarge {
                path: path.to_owned(),
            });
        }
    };
    read_bytes(path, &bytes, columns, options)
}

/// [`read_columns`] on a file's contents already in memory: `path` only names the file in
/// messages. The readers never touch the file system, print or panic, whatever the bytes
/// (the fuzz targets call this directly).
pub fn read_bytes(
    path: &Path,
    bytes: &[u8],
    columns: &[Column],
    options: &ReadOptions,
) -> Result<Columns, DataError> {
    check_selection(columns, options)?;
    if bytes.is_empty() {
        return Err(DataError::Empty {
            path: path.to_owned(),
        });
    }
    match detect_format(path, bytes) {
        Format::MatLevel5 => mat::read_mat(path, bytes, columns, options),
        Format::MatV73 => Err(DataError::MatV73 {
            path: path.to_owned(),
        }),
        Format::Unsupported(reason) => Err(DataError::UnsupportedFormat {
            path: path.to_owned(),
            reason,
        }),
        Format::Text => text::read_text(path, bytes, columns, options),
    }
}

/// Refuses an empty selection, column 0 and a backwards row range.
fn check_selection(columns: &[Column], options: &ReadOptions) -> Result<(), DataError> {
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
    Ok(())
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
    // UTF-16 text (Excel's "Unicode text", PowerShell) is text although half its bytes are 0.
    if text::utf16_order(bytes).is_some() {
        return Format::Text;
    }
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
