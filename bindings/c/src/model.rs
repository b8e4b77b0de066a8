//! Models in memory: a model file (`hystcomp_io::model_file::ModelFile`) as a handle, read
//! from and written to disk, and taken apart into values (numbers and strings) or built from
//! them, so that a caller can keep a model in its own data structures (a MATLAB struct, a
//! firmware's parameter table) and give it back, and run forward over a record.
//!
//! A model is the MPIM of eq. (4) and, in format version 2, optionally the creep and vibration
//! links of the chain `hysteresis -> creep -> vibration` (see `crates/io/src/model_file.rs`).

use std::ffi::{CString, c_char, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

use hystcomp_core::{MAX_CREEP_ELEMENTS, MAX_VIBRATION_ORDER};
use hystcomp_io::model_file::{
    CreepPart, Direction, ModelFile, ModelFileError, Scale, VibrationPart,
};

use crate::HystcompMpim;
use crate::args::{
    check_array, clear_out, doubles, parameters, path_arg, put_handle, signal, str_arg,
};
use crate::boundary::{Failure, boundary};

/// What a model maps (passed as an `int`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HystcompDirection {
    /// Drive voltage in, displacement out: the plant's hysteresis (IHC, WIHC).
    Plant = 0,
    /// Desired displacement in, drive voltage out: the inverse hysteresis (DIHC, section 3.3).
    Inverse = 1,
}

/// The physical meaning of a model's normalised input or output (eq. (11)):
/// `physical = offset + scale * normalised`.
///
/// In `HystcompModelValues` given to `hystcomp_model_from_values`, the strings are read during
/// the call only. Filled in by `hystcomp_model_values`, they point into the model and stay valid
/// until it is freed.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct HystcompScale {
    /// What the signal is, e.g. `"voltage"` (UTF-8, NUL-terminated; may be empty).
    pub quantity: *const c_char,
    /// Its unit, e.g. `"V"` or `"um"` (UTF-8, NUL-terminated, not blank).
    pub unit: *const c_char,
    /// The physical value at normalised 0, in `unit` (finite).
    pub offset: f64,
    /// The physical span of one normalised unit, in `unit` (finite, > 0).
    pub scale: f64,
}

/// A model as values: everything a model file holds (see `crates/io/src/model_file.rs`).
///
/// The MPIM of eq. (4) in normalised units, `y = a1 x^3 + a2 x + sum b_i F_{r_i}[x]`, plus the
/// physical scales of its input and output and the direction it maps, and optionally the creep
/// and vibration links (format version 2; a model without them has `sample_rate_hz` 0,
/// `creep_elements` 0 and `vibration_numerator_len` 0).
///
/// Filled in by `hystcomp_model_values` (every pointer then points into the model and stays
/// valid until it is freed), read by `hystcomp_model_from_values` (every pointer read during the
/// call only).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct HystcompModelValues {
    /// A `HystcompDirection`.
    pub direction: c_int,
    /// The model input's physical meaning (a voltage for a plant model).
    pub input: HystcompScale,
    /// The model output's physical meaning (a displacement for a plant model).
    pub output: HystcompScale,
    /// The normalised input range the model was identified on and is invertible on
    /// (`[0, 1]` when the thresholds are fractions of the input range): its lower end.
    pub input_range_min: f64,
    /// The upper end of the normalised input range (`> input_range_min`).
    pub input_range_max: f64,
    /// `operators` thresholds `r_i` (normalised, `>= 0`, increasing).
    pub thresholds: *const f64,
    /// `operators` weights `b_i` (normalised).
    pub weights: *const f64,
    /// The number of play operators `n` (>= 1).
    pub operators: usize,
    /// The cubic coefficient `a1` of the input function.
    pub a1: f64,
    /// The linear coefficient `a2` of the input function.
    pub a2: f64,
    /// A line for people, or NULL.
    pub description: *const c_char,
    /// How the model was obtained, as JSON text (the model file's `identification` field; for
    /// an identified model the fit report of `hystcomp_identify`), or NULL. An empty string is
    /// read as NULL.
    pub identification_json: *const c_char,
    /// The rate the creep and vibration links run at, Hz (> 0 with either link); 0 without
    /// links.
    pub sample_rate_hz: f64,
    /// The creep link's elements (at most 64); 0: no creep link.
    pub creep_elements: usize,
    /// The relaxed displacement (at rest), in the displacement unit.
    pub creep_origin: f64,
    /// `creep_elements` time constants `tau_i`, s, positive.
    pub creep_time_constants_s: *const f64,
    /// `creep_elements` dimensionless weights `c_i`, `sum |c_i| < 1`.
    pub creep_weights: *const f64,
    /// The vibration link's pure delay `d`, samples.
    pub vibration_delay_samples: usize,
    /// The length of `vibration_numerator` (at most 17); 0: no vibration link.
    pub vibration_numerator_len: usize,
    /// `b_0 .. b_m`.
    pub vibration_numerator: *const f64,
    /// The length of `vibration_denominator` (at most 17).
    pub vibration_denominator_len: usize,
    /// `1, a_1 .. a_n` (unit static gain with the numerator).
    pub vibration_denominator: *const f64,
}

/// A model file in memory (opaque): the MPIM's normalised parameters, the physical scales, the
/// direction and how it was identified.
///
/// Created by `hystcomp_model_load`, `hystcomp_model_from_values` or `hystcomp_identify`,
/// released by `hystcomp_model_free`. It never changes once created, so it may be read by
/// several threads at once.
pub struct HystcompModel {
    pub(crate) file: ModelFile,
    /// The file's strings, NUL-terminated, for `hystcomp_model_values`.
    texts: Texts,
}

/// NUL-terminated copies of a model file's strings.
struct Texts {
    input_quantity: CString,
    input_unit: CString,
    output_quantity: CString,
    output_unit: CString,
    description: Option<CString>,
    identification: Option<CString>,
}

/// A C string of `text`; a NUL inside (possible in JSON, `"\u0000"`) becomes `?` so that C
/// sees the whole text.
fn c_string(text: &str) -> CString {
    CString::new(text.replace('\0', "?")).unwrap_or_default()
}

impl HystcompModel {
    /// The handle's object for a validated model file.
    pub(crate) fn new(file: ModelFile) -> Self {
        let texts = Texts {
            input_quantity: c_string(&file.input.quantity),
            input_unit: c_string(&file.input.unit),
            output_quantity: c_string(&file.output.quantity),
            output_unit: c_string(&file.output.unit),
            description: file.description.as_deref().map(c_string),
            identification: file
                .identification
                .as_ref()
                .map(|value| c_string(&value.to_string())),
        };
        HystcompModel { file, texts }
    }
}

/// The direction of a `HystcompDirection` value.
pub(crate) fn direction_arg(direction: c_int) -> Result<Direction, Failure> {
    match direction {
        0 => Ok(Direction::Plant),
        1 => Ok(Direction::Inverse),
        other => Err(Failure::invalid(format!(
            "direction {other} is not a HystcompDirection (0 = plant: voltage to displacement, \
             1 = inverse: displacement to voltage)"
        ))),
    }
}

/// The model behind a handle, only read.
///
/// # Safety
/// When `m` is not NULL it must be a live model handle.
pub(crate) unsafe fn model_arg<'a>(m: *const HystcompModel) -> Result<&'a HystcompModel, Failure> {
    // SAFETY: a live handle or NULL (the caller's contract); models are never written.
    unsafe { m.as_ref() }.ok_or_else(|| Failure::null("model handle"))
}

/// Reads a model file and validates it (see `crates/io/src/model_file.rs`).
///
/// Fails with `NULL_POINTER`, `IO` (missing file, a directory, no permission) or
/// `INVALID_MODEL_FILE` (not JSON, another format version, a field missing or invalid).
///
/// # Safety
/// `path` must be a NUL-terminated string or NULL; `out` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_model_load(
    path: *const c_char,
    out: *mut *mut HystcompModel,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let path = unsafe { path_arg(path, "path") }?;
        let file = ModelFile::load(&path)?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, HystcompModel::new(file)) };
        Ok(())
    })
}

/// Writes the model to `path` as a JSON model file, atomically (a temporary file in the same
/// directory, then a rename): an existing file at `path` is replaced whole or not at all.
///
/// Fails with `NULL_POINTER` or `IO` (the directory does not exist, no permission; the message
/// names the path).
///
/// # Safety
/// `m` must be a live model handle or NULL; `path` a NUL-terminated string or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_model_save(
    m: *const HystcompModel,
    path: *const c_char,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let model = unsafe { model_arg(m) }?;
        // SAFETY: NUL-terminated or NULL (the caller's contract).
        let path = unsafe { path_arg(path, "path") }?;
        model.file.save(&path)?;
        Ok(())
    })
}

/// The scale described by `s`, its strings checked.
///
/// # Safety
/// The strings of `s` must be NUL-terminated or NULL.
unsafe fn scale_arg(s: &HystcompScale, which: &'static str) -> Result<Scale, Failure> {
    let (quantity_what, unit_what) = match which {
        "input" => ("input.quantity", "input.unit"),
        _ => ("output.quantity", "output.unit"),
    };
    // SAFETY: NUL-terminated or NULL (the caller's contract).
    let quantity = unsafe { str_arg(s.quantity, quantity_what) }?;
    // SAFETY: as above.
    let unit = unsafe { str_arg(s.unit, unit_what) }?;
    Ok(Scale {
        quantity: quantity.to_owned(),
        unit: unit.to_owned(),
        offset: s.offset,
        scale: s.scale,
    })
}

/// Creates a model from its values (see `HystcompModelValues`), validated as a model file is:
/// finite offsets and scales with `scale > 0`, units not blank, a finite increasing input range,
/// `operators >= 1` finite thresholds (`>= 0`, increasing) and weights, finite `a1` and `a2`,
/// the identification (when given) valid JSON. Invertibility is checked where the model is used
/// (a compensator over its limits).
///
/// Fails with `NULL_POINTER` (the values, a string other than `description` and
/// `identification_json`, or an array) or `INVALID_ARGUMENT` (the message names the value).
///
/// # Safety
/// `values` must point to a `HystcompModelValues` whose strings are NUL-terminated (or NULL)
/// and whose arrays hold `operators` doubles (or are NULL), or be NULL; `out` valid for one
/// write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_model_from_values(
    values: *const HystcompModelValues,
    out: *mut *mut HystcompModel,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: a valid `HystcompModelValues` or NULL (the caller's contract).
        let v = unsafe { values.as_ref() }.ok_or_else(|| Failure::null("values"))?;
        let direction = direction_arg(v.direction)?;
        // SAFETY: the strings are NUL-terminated or NULL (the caller's contract).
        let input = unsafe { scale_arg(&v.input, "input") }?;
        // SAFETY: as above.
        let output = unsafe { scale_arg(&v.output, "output") }?;
        // SAFETY: `operators` doubles each or NULL (the caller's contract).
        let (thresholds, weights) = unsafe { parameters(v.thresholds, v.weights, v.operators) }?;
        let mut file = ModelFile::new(
            direction,
            input,
            output,
            [v.input_range_min, v.input_range_max],
            thresholds.to_vec(),
            weights.to_vec(),
            v.a1,
            v.a2,
        )
        .map_err(|e| {
            // Values, not a file: report them as arguments.
            let message = match &e {
                ModelFileError::Model(core) => format!("the model parameters are refused: {core}"),
                other => other.to_string(),
            };
            Failure::invalid(message)
        })?;
        if !v.description.is_null() {
            // SAFETY: NUL-terminated (the caller's contract).
            file.description = Some(unsafe { str_arg(v.description, "description") }?.to_owned());
        }
        if !v.identification_json.is_null() {
            // SAFETY: NUL-terminated (the caller's contract).
            let text = unsafe { str_arg(v.identification_json, "identification_json") }?;
            if !text.trim().is_empty() {
                let value: serde_json::Value = serde_json::from_str(text).map_err(|e| {
                    Failure::invalid(format!("identification_json is not valid JSON: {e}"))
                })?;
                file.identification = Some(value);
            }
        }
        // SAFETY: the link arrays hold their stated lengths (the caller's contract).
        unsafe { links_arg(v, &mut file) }?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, HystcompModel::new(file)) };
        Ok(())
    })
}

/// Reads the creep and vibration links of `v` into `file` and validates it again; their
/// lengths are bounded before the arrays are read.
///
/// # Safety
/// The link arrays of `v` must hold their stated lengths or be NULL.
unsafe fn links_arg(v: &HystcompModelValues, file: &mut ModelFile) -> Result<(), Failure> {
    if v.creep_elements > MAX_CREEP_ELEMENTS {
        return Err(Failure::invalid(format!(
            "creep_elements {} is more than the {MAX_CREEP_ELEMENTS} a creep link holds",
            v.creep_elements
        )));
    }
    for (what, len) in [
        ("vibration_numerator_len", v.vibration_numerator_len),
        ("vibration_denominator_len", v.vibration_denominator_len),
    ] {
        if len > MAX_VIBRATION_ORDER + 1 {
            return Err(Failure::invalid(format!(
                "{what} {len} is more than the {} coefficients of a vibration link of order \
                 {MAX_VIBRATION_ORDER}",
                MAX_VIBRATION_ORDER + 1
            )));
        }
    }
    if v.creep_elements > 0 {
        // SAFETY: `creep_elements` doubles each (the caller's contract).
        let (time_constants_s, weights) = unsafe {
            (
                doubles(
                    v.creep_time_constants_s,
                    v.creep_elements,
                    "creep_time_constants_s",
                )?,
                doubles(v.creep_weights, v.creep_elements, "creep_weights")?,
            )
        };
        file.creep = Some(CreepPart {
            origin: v.creep_origin,
            time_constants_s: time_constants_s.to_vec(),
            weights: weights.to_vec(),
        });
    }
    if v.vibration_numerator_len > 0 {
        // SAFETY: the stated lengths (the caller's contract).
        let (numerator, denominator) = unsafe {
            (
                doubles(
                    v.vibration_numerator,
                    v.vibration_numerator_len,
                    "vibration_numerator",
                )?,
                doubles(
                    v.vibration_denominator,
                    v.vibration_denominator_len,
                    "vibration_denominator",
                )?,
            )
        };
        file.vibration = Some(VibrationPart {
            delay_samples: v.vibration_delay_samples,
            numerator: numerator.to_vec(),
            denominator: denominator.to_vec(),
        });
    }
    if v.sample_rate_hz != 0.0 {
        if !(v.sample_rate_hz.is_finite() && v.sample_rate_hz > 0.0) {
            return Err(Failure::invalid(format!(
                "sample_rate_hz {} is not a rate: give a positive, finite rate in Hz, or 0 for a \
                 model without creep and vibration",
                v.sample_rate_hz
            )));
        }
        file.sample_rate_hz = Some(v.sample_rate_hz);
    }
    file.validate().map_err(|e| Failure::invalid(e.to_string()))
}

/// Fills `*values` with the model's values. Every pointer written (strings, `thresholds`,
/// `weights`) points into the model and stays valid until `hystcomp_model_free`; copy what you
/// keep longer. `description` and `identification_json` are NULL when the model has none.
///
/// Fails with `NULL_POINTER`.
///
/// # Safety
/// `m` must be a live model handle or NULL; `values` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_model_values(
    m: *const HystcompModel,
    values: *mut HystcompModelValues,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let model = unsafe { model_arg(m) }?;
        if values.is_null() {
            return Err(Failure::null("values"));
        }
        let (file, texts) = (&model.file, &model.texts);
        let filled = HystcompModelValues {
            direction: match file.direction {
                Direction::Plant => HystcompDirection::Plant as c_int,
                Direction::Inverse => HystcompDirection::Inverse as c_int,
            },
            input: HystcompScale {
                quantity: texts.input_quantity.as_ptr(),
                unit: texts.input_unit.as_ptr(),
                offset: file.input.offset,
                scale: file.input.scale,
            },
            output: HystcompScale {
                quantity: texts.output_quantity.as_ptr(),
                unit: texts.output_unit.as_ptr(),
                offset: file.output.offset,
                scale: file.output.scale,
            },
            input_range_min: file.input_range[0],
            input_range_max: file.input_range[1],
            thresholds: file.thresholds.as_ptr(),
            weights: file.weights.as_ptr(),
            operators: file.thresholds.len(),
            a1: file.a1,
            a2: file.a2,
            description: texts
                .description
                .as_ref()
                .map_or(std::ptr::null(), |s| s.as_ptr()),
            identification_json: texts
                .identification
                .as_ref()
                .map_or(std::ptr::null(), |s| s.as_ptr()),
            sample_rate_hz: file.sample_rate_hz.unwrap_or(0.0),
            creep_elements: file.creep.as_ref().map_or(0, |c| c.weights.len()),
            creep_origin: file.creep.as_ref().map_or(0.0, |c| c.origin),
            creep_time_constants_s: file
                .creep
                .as_ref()
                .map_or(std::ptr::null(), |c| c.time_constants_s.as_ptr()),
            creep_weights: file
                .creep
                .as_ref()
                .map_or(std::ptr::null(), |c| c.weights.as_ptr()),
            vibration_delay_samples: file.vibration.as_ref().map_or(0, |d| d.delay_samples),
            vibration_numerator_len: file.vibration.as_ref().map_or(0, |d| d.numerator.len()),
            vibration_numerator: file
                .vibration
                .as_ref()
                .map_or(std::ptr::null(), |d| d.numerator.as_ptr()),
            vibration_denominator_len: file.vibration.as_ref().map_or(0, |d| d.denominator.len()),
            vibration_denominator: file
                .vibration
                .as_ref()
                .map_or(std::ptr::null(), |d| d.denominator.as_ptr()),
        };
        // SAFETY: non-NULL, valid for a write (the caller's contract).
        unsafe { values.write(filled) };
        Ok(())
    })
}

/// Creates the forward MPIM of a model in memory, in its physical units (as
/// `hystcomp_mpim_from_model_file` does for a file): for a plant model, drive voltage in and
/// displacement out. The memory starts at zero (eq. (1)); the model handle may be freed after.
/// A model with creep or vibration links is refused: this handle runs the hysteresis alone,
/// `hystcomp_model_predict` runs the whole chain.
///
/// Fails with `NULL_POINTER` or `INVALID_ARGUMENT` (a model with links).
///
/// # Safety
/// `m` must be a live model handle or NULL; `out` valid for one write or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_mpim_from_model(
    m: *const HystcompModel,
    out: *mut *mut HystcompMpim,
) -> c_int {
    boundary(|| {
        // SAFETY: `out` is valid or NULL (the caller's contract).
        unsafe { clear_out(out) }?;
        // SAFETY: a live handle or NULL (the caller's contract).
        let model = unsafe { model_arg(m) }?;
        let mpim = HystcompMpim::of_file(&model.file)?;
        // SAFETY: `out` was checked non-NULL by `clear_out` and is valid for a write.
        unsafe { put_handle(out, mpim) };
        Ok(())
    })
}

/// Runs the model forward over a record, from rest (zero operator memory, eq. (1)), in its
/// physical units: `y[k]` for `x[k]`. A plant model maps drive voltage to displacement through
/// the whole chain (hysteresis, then creep and vibration when the model has them); an inverse
/// model maps desired displacement to voltage (the vibration inverse non-causally over the
/// whole record). `x` and `y` may be the same array.
///
/// Fails with `NULL_POINTER` or `INVALID_ARGUMENT` (lengths differ or 0, a NaN or infinite
/// input: nothing is written then).
///
/// # Safety
/// `m` must be a live model handle or NULL; `x` must point to `x_len` readable doubles and `y`
/// to `y_len` writable doubles (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_model_predict(
    m: *const HystcompModel,
    x: *const f64,
    x_len: usize,
    y: *mut f64,
    y_len: usize,
) -> c_int {
    boundary(|| {
        // SAFETY: a live handle or NULL (the caller's contract).
        let model = unsafe { model_arg(m) }?;
        if y.is_null() {
            return Err(Failure::null("y"));
        }
        // SAFETY: `x_len` readable doubles or NULL (the caller's contract); copied before `y`
        // is written, so the two may be the same array.
        let input = unsafe { signal(x, x_len, "x") }?.to_vec();
        if y_len != x_len {
            return Err(Failure::invalid(format!(
                "x has {x_len} samples but y has room for {y_len}; give arrays of equal length"
            )));
        }
        if let Some(k) = input.iter().position(|v| !v.is_finite()) {
            return Err(Failure::invalid(format!(
                "x[{k}] is NaN or infinite; the model runs on finite inputs"
            )));
        }
        check_array(y, y_len, "y")?;
        let output = model.file.predict(&input)?;
        // SAFETY: `y` is valid for `y_len == output.len()` writes (the caller's contract),
        // non-NULL and aligned (checked); `input` is a copy, so `x == y` is fine.
        unsafe { std::ptr::copy_nonoverlapping(output.as_ptr(), y, output.len()) };
        Ok(())
    })
}

/// Releases a model. NULL is accepted (and ignored); a handle must not be used after, nor freed
/// twice. Compensators and forward models made from it do not depend on it.
///
/// # Safety
/// `m` must be a live model handle from this library or NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hystcomp_model_free(m: *mut HystcompModel) {
    if m.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a live handle made by `Box::into_raw` in this library, freed once (the
        // caller's contract).
        drop(unsafe { Box::from_raw(m) });
    }));
}
