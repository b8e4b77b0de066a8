//! MATLAB Level-5 MAT-files (see the [module documentation](super) for what is read): the
//! columns asked for, taken from the variables [`level5`](super::level5) parses.

use std::path::Path;

use super::error::shape_text;
use super::level5::{self, MAX_MAT_VALUES, Variable};
use super::{Column, Columns, DataError, MAX_MAGNITUDE, ReadOptions, check_row_range};

/// Reads the selected columns of a Level-5 MAT-file held in `bytes` (`path` names it in
/// messages).
pub(super) fn read_mat(
    path: &Path,
    bytes: &[u8],
    columns: &[Column],
    options: &ReadOptions,
) -> Result<Columns, DataError> {
    let variables = level5::parse(bytes).map_err(|reason| DataError::MatUnreadable {
        path: path.to_owned(),
        reason,
    })?;
    // Variables without a name (MATLAB's subsystem data) are not the user's.
    let variables: Vec<Variable<'_>> = variables
        .into_iter()
        .filter(|v| !v.name.is_empty())
        .collect();
    let available: Vec<String> = variables
        .iter()
        .map(|v| format!("{} ({} {})", v.name, shape_text(&v.dims), v.class))
        .collect();
    let find = |name: &str| variables.iter().find(|v| v.name == name);

    let mut names = Vec::with_capacity(columns.len());
    let mut values = Vec::with_capacity(columns.len());
    for column in columns {
        let no_such = || DataError::NoSuchVariable {
            path: path.to_owned(),
            requested: column.clone(),
            available: available.clone(),
        };
        let (variable, column_k) = match column {
            Column::Name(name) => match find(name) {
                Some(variable) => (variable, None),
                None => {
                    let (base, k) = name.rsplit_once(':').ok_or_else(no_such)?;
                    let k = k.trim().parse::<usize>().map_err(|_| no_such())?;
                    (find(base.trim()).ok_or_else(no_such)?, Some(k))
                }
            },
            Column::Index(k) => match variables.as_slice() {
                [only] => (only, Some(*k)),
                _ => return Err(no_such()),
            },
        };
        let (name, column_values) = mat_column(path, variable, column_k)?;
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
        if let Some(i) = column.iter().position(|v| v.abs() > MAX_MAGNITUDE) {
            return Err(DataError::OutOfRange {
                path: path.to_owned(),
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
    variable: &Variable<'_>,
    k: Option<usize>,
) -> Result<(String, Vec<f64>), DataError> {
    let shape = variable.dims.clone();
    let unusable = |variable: String, reason: String| DataError::UnusableVariable {
        path: path.to_owned(),
        variable,
        shape: shape.clone(),
        reason,
    };
    let name = variable.name.clone();
    if variable.complex {
        return Err(unusable(
            name,
            "is complex; save its real part, e.g. x = real(x)".to_owned(),
        ));
    }
    if variable.len() > MAX_MAT_VALUES {
        return Err(unusable(
            name,
            format!(
                "holds {} values, more than the {MAX_MAT_VALUES} a column may hold here; save \
                 the samples you need in a smaller variable, or export them as CSV",
                variable.len()
            ),
        ));
    }
    let mut all = variable.values();
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
