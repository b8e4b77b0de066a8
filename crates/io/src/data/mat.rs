//! MATLAB Level-5 MAT-files (see the [module documentation](super) for what is read).

use std::path::Path;

use super::error::shape_text;
use super::{Column, Columns, DataError, ReadOptions, check_row_range};

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

pub(super) fn read_mat(
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
