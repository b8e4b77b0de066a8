//! The model file: a JSON document holding one identified MPIM (eq. (4)) in the paper's
//! normalised units (eq. (11)), the physical scales and units that map it to the real world,
//! the direction it maps, and (format_version 2) optionally the creep and vibration links of
//! the chain `hysteresis -> creep -> vibration` (Croft, Shed & Devasia 2001,
//! doi:10.1115/1.1341197; see `hystcomp_core::ChainModel`).
//!
//! ```json
//! {
//!   "format_version": 2,
//!   "direction": "plant",
//!   "description": "Table 1 of Gu & Zhu (2014)",
//!   "input":  { "quantity": "voltage",      "unit": "V",  "offset": 0.0, "scale": 10.0 },
//!   "output": { "quantity": "displacement", "unit": "um", "offset": 0.0, "scale": 75.0 },
//!   "input_range": [0.0, 1.0],
//!   "thresholds": [0.0, 0.1, ...],
//!   "weights": [0.2313, 0.3059, ...],
//!   "a1": -0.1569,
//!   "a2": 0.4603,
//!   "identification": { "solver": "ls", "...": "free-form metadata" }
//! }
//! ```
//!
//! - `direction`: `plant` maps the drive voltage `v` to the displacement `y` (used by IHC and
//!   WIHC); `inverse` maps the desired displacement `y_d` to the voltage `v` (used by DIHC,
//!   section 3.3).
//! - `input` and `output`: `physical = offset + scale * normalised`, so the normalised input is
//!   `(physical - offset) / scale`. `scale > 0`. For a plant the input is a voltage and the
//!   output a displacement; for an inverse model the other way round.
//! - `input_range`: the normalised input range the model was identified on and is invertible on
//!   (`[0, 1]` when the thresholds are fractions of the input range, eq. (11)).
//! - `thresholds`, `weights`, `a1`, `a2`: the normalised MPIM parameters of eq. (4).
//! - `input_polynomial` (optional, format 2): the input function `g(x) = c_1 x + c_2 x^2 + ...
//!   + c_D x^D` as `[c_1, ..., c_D]` when it is not the paper's cubic `a1 x^3 + a2 x` (at most
//!   degree [`hystcomp_core::MAX_INPUT_DEGREE`]); `a2` must equal `c_1` and `a1` must equal
//!   `c_3` (0 below degree 3), so that readers that know only `a1` and `a2` read them right.
//! - `identification`: optional free-form JSON (solver, fit errors, data source...).
//!
//! # Format version 2: a higher-degree input polynomial, creep and vibration (optional)
//! Version 1 files hold the MPIM alone and still load (they are written back as version 2,
//! which differs only by the optional parts below). A file without `creep` and `vibration` is
//! the hysteresis-only model of version 1.
//!
//! ```json
//!   "sample_rate_hz": 10000.0,
//!   "creep": { "origin": 0.0, "time_constants_s": [0.01, 0.0316, ...], "weights": [0.004, ...] },
//!   "vibration": { "delay_samples": 0, "numerator": [0.02, 0.05, ...], "denominator": [1.0, -1.7, ...] }
//! ```
//!
//! - `sample_rate_hz`: the rate the record was sampled at, Hz; required with either part. The
//!   creep link is discretised for whatever rate it runs at; the vibration link is a
//!   discrete-time model at this rate and only runs at it.
//! - `creep`: the link `h = x - sum_i c_i (z_i[x] - origin)`, `tau_i dz_i/dt = x - z_i`
//!   (`hystcomp_core::Creep`, written through its inverse) acting on the **displacement** in
//!   the file's displacement unit: the plant's hysteresis output `h` creeps to the
//!   displacement `x`. `origin` is the relaxed displacement (the displacement at rest), in
//!   that unit; `weights` are dimensionless (`sum |c_i| < 1`).
//! - `vibration`: `y(k) = sum_j b_j x(k - d - j) - sum_{i>=1} a_i y(k - i)` with `numerator`
//!   `b_0..b_m`, `denominator` `1, a_1..a_n`, `delay_samples` `d`, unit static gain
//!   (`hystcomp_core::Vibration`), on the displacement.
//!
//! In a **plant** file the model is `y = D[C[H[v]]]`. In an **inverse** file (DIHC) the same
//! two links are the plant's, and the compensator is `v = H^-1[C^-1[D^-1[y_d]]]`, where the
//! file's MPIM `H^-1` maps the creep-free displacement `C^-1[D^-1[y]]` to the voltage.

use std::fmt;
use std::path::Path;

use hystcomp_core::{
    CoreError, Creep, CreepInverse, InputPolynomial, Mpim, OutputMap, Shown, Vibration,
    VibrationInverse,
};
use serde::{Deserialize, Serialize};

use crate::atomic::write_atomic;

/// The `format_version` this crate writes.
pub const FORMAT_VERSION: u32 = 2;

/// Every `format_version` this crate reads: 1 (the MPIM alone) and 2 (optionally with creep
/// and vibration).
pub const READABLE_VERSIONS: [u32; 2] = [1, 2];

/// The most creep elements a file may hold (the core's limit).
pub const MAX_CREEP_ELEMENTS: usize = hystcomp_core::MAX_CREEP_ELEMENTS;

/// The largest magnitude of an output map coefficient `m_j` (`1e6`). The map acts on the
/// normalised output (about `[0, 1]`), where identified maps have coefficients of order 1 to
/// 100; beyond this a coefficient is a unit mistake, not a model.
pub const MAX_OUTPUT_MAP_COEFFICIENT: f64 = 1e6;

/// The largest magnitude of either end of an output map's `range` (`1e3` normalised units:
/// a thousand times the model's identified output span).
pub const MAX_OUTPUT_MAP_RANGE: f64 = 1e3;

/// The smallest and largest slope an output map may have at either end of its range (where it
/// continues linearly) and on average over it (`1e-9` to `1e6`; identified maps have slopes
/// near 1, at least identification's `--margin`): the model's output is `psi^-1` of the
/// MPIM's, so a flatter map multiplies every output beyond its range (up to overflow), and a
/// steeper one squeezes the whole stroke into nothing.
pub const OUTPUT_MAP_SLOPE_RANGE: [f64; 2] = [1e-9, 1e6];

/// The hysteresis link's output map (format version 2, optional): the MPIM's output equals
/// `psi(w) = m_0 + m_1 w + ... + m_K w^K` of the model's normalised output
/// `w = (output - output.offset) / output.scale` on `range` (continued linearly beyond it), so
/// the model's output is `output.offset + output.scale * psi^-1(H[x])`
/// (`hystcomp_core::OutputMap`; Kuhnen 2003, doi:10.3166/ejc.9.407-418). A plant file's IHC
/// and WIHC solve for `psi(w_d)`; an inverse (DIHC) file's voltage is `psi^-1` of its MPIM's
/// output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputMapPart {
    /// `[m_0, m_1, ..., m_K]`, 2 to 6 of them, each at most [`MAX_OUTPUT_MAP_COEFFICIENT`] in
    /// magnitude.
    pub coefficients: Vec<f64>,
    /// The normalised outputs `[lo, hi]` on which `psi` is the polynomial, strictly increasing,
    /// each at most [`MAX_OUTPUT_MAP_RANGE`] in magnitude.
    pub range: [f64; 2],
}

impl OutputMapPart {
    /// The core's map (validated: strictly increasing on its range).
    pub fn map(&self) -> Result<OutputMap<f64>, CoreError> {
        OutputMap::new(&self.coefficients, self.range[0], self.range[1])
    }

    /// The map, checked as a model file's: the number of coefficients, each finite and within
    /// [`MAX_OUTPUT_MAP_COEFFICIENT`], the range finite, increasing and within
    /// [`MAX_OUTPUT_MAP_RANGE`], rising on it ([`OutputMapPart::map`]), and its slopes at the
    /// range's ends and on average within [`OUTPUT_MAP_SLOPE_RANGE`]. The message names the
    /// field.
    pub fn checked(&self) -> Result<OutputMap<f64>, String> {
        let count = self.coefficients.len();
        let most = hystcomp_core::MAX_OUTPUT_MAP_DEGREE + 1;
        if !(2..=most).contains(&count) {
            return Err(format!(
                "output_map.coefficients holds {count} coefficients: give 2 to {most} \
                 ([m_0, m_1, ..., m_K], degree K from 1 to {})",
                most - 1
            ));
        }
        if let Some((j, m)) = self
            .coefficients
            .iter()
            .enumerate()
            .find(|(_, m)| !(m.is_finite() && m.abs() <= MAX_OUTPUT_MAP_COEFFICIENT))
        {
            return Err(format!(
                "output_map.coefficients[{j}] = {m:e} must be finite and at most \
                 {MAX_OUTPUT_MAP_COEFFICIENT:e} in magnitude (the map acts on the normalised \
                 output, about 0 to 1)"
            ));
        }
        let [lo, hi] = self.range;
        if !(lo.is_finite()
            && hi.is_finite()
            && lo < hi
            && lo.abs() <= MAX_OUTPUT_MAP_RANGE
            && hi.abs() <= MAX_OUTPUT_MAP_RANGE)
        {
            return Err(format!(
                "output_map.range [{lo:e}, {hi:e}] must be finite and increasing, each end at \
                 most {MAX_OUTPUT_MAP_RANGE:e} in magnitude (normalised output)"
            ));
        }
        let map = self.map().map_err(|e| format!("output_map: {e}"))?;
        // psi continues linearly beyond the range, so these differences are its end slopes.
        let width = hi - lo;
        let slopes = [
            (
                "at the range's low end",
                (map.apply(lo) - map.apply(lo - width)) / width,
            ),
            (
                "at the range's high end",
                (map.apply(hi + width) - map.apply(hi)) / width,
            ),
            (
                "on average over the range",
                (map.apply(hi) - map.apply(lo)) / width,
            ),
        ];
        let [least, most] = OUTPUT_MAP_SLOPE_RANGE;
        if let Some((where_, slope)) = slopes
            .iter()
            .find(|(_, slope)| !(*slope >= least && *slope <= most))
        {
            return Err(format!(
                "output_map: its slope {where_} is {slope:e}, outside [{least:e}, {most:e}]: \
                 the model's output is psi^-1 of the MPIM's, so such a map overflows or \
                 flattens every output; re-identify the model (with a larger --margin)"
            ));
        }
        Ok(map)
    }
}

/// The creep link of a format-version-2 file (see the [module documentation](self)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CreepPart {
    /// The relaxed displacement (at rest), in the file's displacement unit.
    pub origin: f64,
    /// Time constants `tau_i`, s, positive.
    pub time_constants_s: Vec<f64>,
    /// Weights `c_i` of the inverse parameterisation, dimensionless, `sum |c_i| < 1`.
    pub weights: Vec<f64>,
}

impl CreepPart {
    /// The forward link, discretised for `sample_rate_hz`, in physical units.
    pub fn link(&self, sample_rate_hz: f64) -> Result<Creep<f64, Vec<f64>>, CoreError> {
        Creep::new(
            &self.time_constants_s,
            &self.weights,
            self.origin,
            1.0 / sample_rate_hz,
        )
    }

    /// The same link in the normalised units of `scale` (`origin` mapped; the weights are
    /// dimensionless).
    pub fn normalised(&self, scale: &Scale) -> CreepPart {
        CreepPart {
            origin: scale.normalise(self.origin),
            ..self.clone()
        }
    }
}

/// The vibration link of a format-version-2 file (see the [module documentation](self)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VibrationPart {
    /// Pure delay `d`, samples of the file's `sample_rate_hz`.
    pub delay_samples: usize,
    /// `b_0..b_m`.
    pub numerator: Vec<f64>,
    /// `1, a_1..a_n`.
    pub denominator: Vec<f64>,
}

impl VibrationPart {
    /// The forward link.
    pub fn link(&self) -> Result<Vibration<f64, Vec<f64>>, CoreError> {
        Vibration::new(&self.numerator, &self.denominator, self.delay_samples)
    }

    /// Its stable inverse with a preview of `preview` samples.
    pub fn inverse(&self, preview: usize) -> Result<VibrationInverse<f64, Vec<f64>>, CoreError> {
        VibrationInverse::new(
            &self.numerator,
            &self.denominator,
            self.delay_samples,
            preview,
        )
    }

    /// The preview for an inverse whose cut tail is negligible (offline inversion).
    pub fn needed_preview(&self) -> Result<usize, CoreError> {
        VibrationInverse::<f64, Vec<f64>>::needed_preview(&self.numerator, self.delay_samples)
    }

    /// The shortest preview that inverts it at all.
    pub fn minimum_preview(&self) -> Result<usize, CoreError> {
        VibrationInverse::<f64, Vec<f64>>::minimum_preview(&self.numerator, self.delay_samples)
    }
}

/// The most play operators a model file may hold (10 000): compensators build in time linear
/// in the operators and step in time linear in them (about 25 us per sample at 10 000), so
/// larger files are refused before a model is built.
pub const MAX_OPERATORS: usize = 10_000;

/// The largest model file read (16 MiB; a model of [`MAX_OPERATORS`] operators takes about
/// 0.5 MiB): a larger file is refused before it is read.
pub const MAX_MODEL_FILE_BYTES: u64 = 16 << 20;

/// The smallest and largest `scale` of an input or output (`1e-12` to `1e12` physical units per
/// normalised unit): beyond them, normalising a physical value loses it (a subnormal scale
/// turned every desired position into the same drive) or overflows.
pub const SCALE_RANGE: [f64; 2] = [1e-12, 1e12];

/// The largest magnitude of an `offset` (`1e15`, as for the values of a record).
pub const MAX_OFFSET: f64 = 1e15;

/// The largest magnitude of a model's normalised parameter (thresholds, weights, `a1`, `a2`,
/// the input polynomial, the input range): `1e15`, as for an offset.
pub const MAX_PARAMETER: f64 = 1e15;

/// What a model maps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Voltage in, displacement out: the plant's hysteresis (IHC, WIHC).
    Plant,
    /// Desired displacement in, voltage out: the inverse hysteresis (DIHC).
    Inverse,
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Direction::Plant => "plant",
            Direction::Inverse => "inverse",
        })
    }
}

/// The physical meaning of a normalised signal: `physical = offset + scale * normalised`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scale {
    /// What the signal is, e.g. `voltage` or `displacement`.
    pub quantity: String,
    /// Its unit, e.g. `V` or `um`.
    pub unit: String,
    /// Physical value at normalised 0, in `unit`.
    pub offset: f64,
    /// Physical span of one normalised unit, in `unit` (> 0).
    pub scale: f64,
}

impl Scale {
    /// `(physical - offset) / scale`.
    pub fn normalise(&self, physical: f64) -> f64 {
        (physical - self.offset) / self.scale
    }

    /// `offset + scale * normalised`.
    pub fn to_physical(&self, normalised: f64) -> f64 {
        self.offset + self.scale * normalised
    }
}

/// One model file. Build it with [`ModelFile::new`] (which validates) or read it with
/// [`ModelFile::load`]; the fields are public for reading and serialisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// One of [`READABLE_VERSIONS`] (as read; [`ModelFile::to_json`] writes
    /// [`FORMAT_VERSION`]).
    pub format_version: u32,
    /// What the model maps.
    pub direction: Direction,
    /// A line for people.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Physical meaning of the model input.
    pub input: Scale,
    /// Physical meaning of the model output.
    pub output: Scale,
    /// Normalised input range the model is valid (and invertible) on.
    pub input_range: [f64; 2],
    /// Thresholds `r_i`, normalised, increasing.
    pub thresholds: Vec<f64>,
    /// Weights `b_i`, normalised.
    pub weights: Vec<f64>,
    /// Cubic coefficient `a1`.
    pub a1: f64,
    /// Linear coefficient `a2`.
    pub a2: f64,
    /// The whole input polynomial `[c_1, ..., c_D]` when it is not the paper's cubic
    /// (`c_1 = a2`, `c_3 = a1`); absent for the cubic. Format version 2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_polynomial: Option<Vec<f64>>,
    /// The hysteresis link's output map (format version 2), if any: see [`OutputMapPart`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_map: Option<OutputMapPart>,
    /// The sample rate of the record the time-dependent parts were identified on, Hz
    /// (format version 2; required with `creep` or `vibration`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_rate_hz: Option<f64>,
    /// The creep link (format version 2), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub creep: Option<CreepPart>,
    /// The vibration link (format version 2), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vibration: Option<VibrationPart>,
    /// Free-form metadata: how the model was obtained.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identification: Option<serde_json::Value>,
}

/// Why a model file could not be read, written or used.
#[derive(Debug)]
pub enum ModelFileError {
    /// The file could not be read.
    Io {
        /// The file.
        path: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The file could not be written; the error names the path
    /// (see [`crate::atomic::write_atomic`]).
    Write(std::io::Error),
    /// The file is not valid JSON, or not of this format.
    Parse {
        /// The file.
        path: String,
        /// What serde_json found (with line and column).
        message: String,
    },
    /// A `format_version` this build does not read.
    UnknownVersion {
        /// The file.
        path: String,
        /// The version found.
        found: u64,
    },
    /// A scale, a unit or the input range is unusable.
    Invalid {
        /// What is wrong and how to mend it.
        message: String,
    },
    /// The MPIM parameters are refused by the core.
    Model(CoreError),
}

impl fmt::Display for ModelFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModelFileError::Io { path, source } => {
                if source.kind() == std::io::ErrorKind::IsADirectory {
                    write!(
                        f,
                        "cannot read {path}: it is a directory; give a model file (.json)"
                    )
                } else if source.kind() == std::io::ErrorKind::NotFound {
                    write!(
                        f,
                        "cannot read {path}: {source} (check the path and file name)"
                    )
                } else if source.kind() == std::io::ErrorKind::InvalidData {
                    write!(
                        f,
                        "cannot read {path}: it is not UTF-8 text ({source}); a model file is JSON"
                    )
                } else {
                    write!(f, "cannot read {path}: {source}")
                }
            }
            ModelFileError::Write(source) => write!(f, "{source}"),
            ModelFileError::Parse { path, message } => {
                write!(
                    f,
                    "{} is not a valid hystcomp model file: {message}",
                    source_name(path)
                )
            }
            ModelFileError::UnknownVersion { path, found } => write!(
                f,
                "{} has format_version {found}, but this hystcomp reads format_version 1 \
                 and 2; update hystcomp or re-identify the model",
                source_name(path)
            ),
            ModelFileError::Invalid { message } => f.write_str(message),
            ModelFileError::Model(e) => write!(f, "the model parameters are refused: {e}"),
        }
    }
}

impl std::error::Error for ModelFileError {}

/// What a parse error names: the file's path, or "the JSON text" for
/// [`ModelFile::from_json`], which has none.
fn source_name(path: &str) -> &str {
    if path.is_empty() {
        "the JSON text"
    } else {
        path
    }
}

impl From<CoreError> for ModelFileError {
    fn from(e: CoreError) -> Self {
        ModelFileError::Model(e)
    }
}

/// The non-finite token (`NaN`, `Infinity`, `-Infinity`) where serde_json stopped, if that is
/// what stopped it.
fn non_json_number(text: &str, error: &serde_json::Error) -> Option<&'static str> {
    if !error.is_syntax() {
        return None;
    }
    let line = text.lines().nth(error.line().checked_sub(1)?)?;
    // serde_json's column is 1-based and points at (or just past) the offending character.
    let start = error.column().saturating_sub(1).min(line.len());
    let rest = line.get(start.saturating_sub(1)..).unwrap_or("");
    let rest =
        rest.trim_start_matches(|c: char| c == ':' || c == ',' || c == '[' || c.is_whitespace());
    ["-Infinity", "Infinity", "NaN", "-NaN"]
        .into_iter()
        .find(|token| rest.starts_with(token))
}

impl ModelFile {
    /// A validated model file (see [`ModelFile::validate`]).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        direction: Direction,
        input: Scale,
        output: Scale,
        input_range: [f64; 2],
        thresholds: Vec<f64>,
        weights: Vec<f64>,
        a1: f64,
        a2: f64,
    ) -> Result<Self, ModelFileError> {
        let file = ModelFile {
            format_version: FORMAT_VERSION,
            direction,
            description: None,
            input,
            output,
            input_range,
            thresholds,
            weights,
            a1,
            a2,
            input_polynomial: None,
            output_map: None,
            sample_rate_hz: None,
            creep: None,
            vibration: None,
            identification: None,
        };
        file.validate()?;
        Ok(file)
    }

    /// The same model with the creep and vibration links `creep` and `vibration` (either may
    /// be `None`) for records sampled at `sample_rate_hz`; validated.
    pub fn with_links(
        mut self,
        sample_rate_hz: f64,
        creep: Option<CreepPart>,
        vibration: Option<VibrationPart>,
    ) -> Result<Self, ModelFileError> {
        self.format_version = FORMAT_VERSION;
        self.sample_rate_hz = Some(sample_rate_hz);
        self.creep = creep;
        self.vibration = vibration;
        if self.creep.is_none() && self.vibration.is_none() {
            self.sample_rate_hz = None;
        }
        self.validate()?;
        Ok(self)
    }

    /// `true` when the file holds a creep or a vibration link (a chain beyond hysteresis).
    pub fn has_links(&self) -> bool {
        self.creep.is_some() || self.vibration.is_some()
    }

    /// A model file for `model` (its parameters, input polynomial included; not its memory).
    pub fn from_model(
        direction: Direction,
        input: Scale,
        output: Scale,
        input_range: [f64; 2],
        model: &Mpim<f64, Vec<f64>>,
    ) -> Result<Self, ModelFileError> {
        let mut file = ModelFile::new(
            direction,
            input,
            output,
            input_range,
            model.thresholds().to_vec(),
            model.weights().to_vec(),
            model.a1(),
            model.a2(),
        )?;
        let polynomial = model.input_polynomial();
        if !polynomial.is_odd_cubic() {
            file.input_polynomial = Some(polynomial.coefficients().to_vec());
            file.validate()?;
        }
        Ok(file)
    }

    /// Checks the version, the scales (finite, `scale` in [`SCALE_RANGE`], `|offset|` at most
    /// [`MAX_OFFSET`], units named), the input range (finite, `lo < hi`), the number of
    /// operators (at most [`MAX_OPERATORS`]) and the MPIM parameters (see [`Mpim::new`]). Invertibility is
    /// checked where the model is used (a compensator), with the limits it is used with.
    /// With creep or vibration: version 2, a positive finite `sample_rate_hz`, and links the
    /// core accepts (`hystcomp_core::Creep::new`, `hystcomp_core::Vibration::new`). With an
    /// output map: version 2 and [`OutputMapPart::checked`].
    pub fn validate(&self) -> Result<(), ModelFileError> {
        if !READABLE_VERSIONS.contains(&self.format_version) {
            return Err(ModelFileError::UnknownVersion {
                path: "the model".into(),
                found: self.format_version.into(),
            });
        }
        self.validate_links()?;
        for (name, s) in [("input", &self.input), ("output", &self.output)] {
            if !(s.offset.is_finite() && s.scale.is_finite() && s.scale > 0.0) {
                return Err(ModelFileError::Invalid {
                    message: format!(
                        "{name}.offset and {name}.scale must be finite with {name}.scale > 0 \
                         (got offset {}, scale {})",
                        s.offset, s.scale
                    ),
                });
            }
            let [lo, hi] = SCALE_RANGE;
            if !(lo..=hi).contains(&s.scale) || s.offset.abs() > MAX_OFFSET {
                return Err(ModelFileError::Invalid {
                    message: format!(
                        "{name}.scale must lie in [{lo:e}, {hi:e}] and |{name}.offset| be at \
                         most {MAX_OFFSET:e} (got offset {}, scale {}): normalising with such \
                         a scale loses or overflows every value; express the {name} in a unit \
                         of everyday size",
                        s.offset, s.scale
                    ),
                });
            }
            if s.unit.trim().is_empty() {
                return Err(ModelFileError::Invalid {
                    message: format!("{name}.unit is empty; name the unit, e.g. \"V\" or \"um\""),
                });
            }
        }
        let [lo, hi] = self.input_range;
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(ModelFileError::Invalid {
                message: format!(
                    "input_range [{lo}, {hi}] must be finite and increasing (normalised units)"
                ),
            });
        }
        // Normalised parameters are of order 1; a finite one beyond MAX_PARAMETER overflows
        // the compensators' arithmetic (a drive stuck at a limit) before any check sees it
        // (the model's own checks below refuse the non-finite ones, each with its reason).
        let parameters = [
            ("input_range", &self.input_range[..]),
            ("thresholds", &self.thresholds[..]),
            ("weights", &self.weights[..]),
            ("a1", std::slice::from_ref(&self.a1)),
            ("a2", std::slice::from_ref(&self.a2)),
            (
                "input_polynomial",
                self.input_polynomial.as_deref().unwrap_or(&[]),
            ),
        ];
        for (what, values) in parameters {
            if let Some((i, v)) = values
                .iter()
                .enumerate()
                .find(|(_, v)| v.is_finite() && v.abs() > MAX_PARAMETER)
            {
                return Err(ModelFileError::Invalid {
                    message: format!(
                        "{what}[{i}] = {} is beyond {MAX_PARAMETER:e} in magnitude (normalised \
                         units, of order 1 in an identified model)",
                        Shown(*v)
                    ),
                });
            }
        }
        if self.thresholds.len() > MAX_OPERATORS {
            return Err(ModelFileError::Invalid {
                message: format!(
                    "thresholds holds {} play operators, more than the {MAX_OPERATORS} a model \
                     file may hold; identify a model with fewer operators",
                    self.thresholds.len()
                ),
            });
        }
        if let Some(c) = &self.input_polynomial {
            if self.format_version < 2 {
                return Err(ModelFileError::Invalid {
                    message: "input_polynomial needs format_version 2".to_owned(),
                });
            }
            let c1 = c.first().copied().unwrap_or(f64::NAN);
            let c3 = c.get(2).copied().unwrap_or(0.0);
            if c1 != self.a2 || c3 != self.a1 {
                return Err(ModelFileError::Invalid {
                    message: format!(
                        "input_polynomial [c_1, c_2, ...] must agree with a2 = c_1 and a1 = c_3 \
                         (got a2 = {}, c_1 = {c1}, a1 = {}, c_3 = {c3})",
                        self.a2, self.a1
                    ),
                });
            }
        }
        if let Some(map) = &self.output_map {
            if self.format_version < 2 {
                return Err(ModelFileError::Invalid {
                    message: "output_map needs format_version 2".to_owned(),
                });
            }
            map.checked()
                .map_err(|message| ModelFileError::Invalid { message })?;
        }
        self.model()?;
        Ok(())
    }

    /// The output map's core form, the identity when the file has none.
    pub fn core_output_map(&self) -> Result<OutputMap<f64>, CoreError> {
        match &self.output_map {
            Some(m) => m.map(),
            None => Ok(OutputMap::identity()),
        }
    }

    /// Refuses a file with an `output_map` for a user of the MPIM alone (`what` says who),
    /// which would silently leave the map out.
    pub fn refuse_output_map(&self, what: &str) -> Result<(), ModelFileError> {
        if self.output_map.is_some() {
            return Err(ModelFileError::Invalid {
                message: format!(
                    "the model has an output_map (its hysteresis link is psi^-1 of the MPIM), \
                     which {what} would leave out; identify the model without an output map \
                     (output map degree 1)"
                ),
            });
        }
        Ok(())
    }

    /// The physical output for the MPIM's output `h` (normalised): through the output map's
    /// inverse when there is one.
    pub fn hysteresis_output_to_physical(&self, map: &OutputMap<f64>, h: f64) -> f64 {
        self.output_to_physical(if self.output_map.is_some() {
            map.invert(h)
        } else {
            h
        })
    }

    fn validate_links(&self) -> Result<(), ModelFileError> {
        if !self.has_links() {
            return Ok(());
        }
        if self.format_version < 2 {
            return Err(ModelFileError::Invalid {
                message: "creep and vibration need format_version 2".into(),
            });
        }
        let rate = match self.sample_rate_hz {
            Some(rate) if rate.is_finite() && rate > 0.0 => rate,
            other => {
                return Err(ModelFileError::Invalid {
                    message: format!(
                        "sample_rate_hz must be given, positive and finite with creep or \
                         vibration (got {other:?})"
                    ),
                });
            }
        };
        if let Some(creep) = &self.creep {
            creep.link(rate).map_err(|e| ModelFileError::Invalid {
                message: format!("creep: {e}"),
            })?;
        }
        if let Some(vibration) = &self.vibration {
            vibration.link().map_err(|e| ModelFileError::Invalid {
                message: format!("vibration: {e}"),
            })?;
        }
        Ok(())
    }

    /// The input polynomial `g` of this file: `input_polynomial` when present, else the paper's
    /// cubic `a1 x^3 + a2 x`.
    pub fn input_function(&self) -> Result<InputPolynomial<f64>, CoreError> {
        match &self.input_polynomial {
            Some(c) => InputPolynomial::new(c),
            None => InputPolynomial::cubic(self.a1, self.a2),
        }
    }

    /// The MPIM of this file, with zero memory, as the core accepts or refuses it.
    pub fn core_model(&self) -> Result<Mpim<f64, Vec<f64>>, CoreError> {
        Mpim::with_input_polynomial(&self.thresholds, &self.weights, self.input_function()?)
    }

    /// The MPIM of this file, with zero memory.
    pub fn model(&self) -> Result<Mpim<f64, Vec<f64>>, ModelFileError> {
        Ok(self.core_model()?)
    }

    /// Reads and validates a model file.
    pub fn load(path: &Path) -> Result<Self, ModelFileError> {
        let shown = path.display().to_string();
        let io_error = |source| ModelFileError::Io {
            path: shown.clone(),
            source,
        };
        let bytes =
            match crate::bounded::read_at_most(path, MAX_MODEL_FILE_BYTES).map_err(io_error)? {
                crate::bounded::Bounded::Whole(bytes) => bytes,
                crate::bounded::Bounded::TooLarge => {
                    return Err(ModelFileError::Invalid {
                        message: format!(
                            "{shown} is larger than the {} MiB a model file may be (a model of \
                         {MAX_OPERATORS} operators takes about 0.5 MiB); is it a model file?",
                            MAX_MODEL_FILE_BYTES >> 20
                        ),
                    });
                }
            };
        let text = String::from_utf8(bytes).map_err(|e| {
            io_error(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                e.utf8_error(),
            ))
        })?;
        Self::from_json(&text).map_err(|e| match e {
            ModelFileError::Parse { message, .. } => ModelFileError::Parse {
                path: shown,
                message,
            },
            ModelFileError::UnknownVersion { found, .. } => {
                ModelFileError::UnknownVersion { path: shown, found }
            }
            ModelFileError::Invalid { message } => ModelFileError::Invalid {
                message: format!("{shown}: {message}"),
            },
            other => other,
        })
    }

    /// Parses and validates a model file's text.
    pub fn from_json(text: &str) -> Result<Self, ModelFileError> {
        // A UTF-8 byte-order mark (some Windows editors write one) is no part of the JSON.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Look at the version first, so that a future format gets the right message rather than
        // a complaint about fields this build does not know.
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| ModelFileError::Parse {
                path: String::new(),
                message: match non_json_number(text, &e) {
                    Some(token) => format!(
                        "{e}: the value there is a bare {token}, which JSON has no word for \
                         (Python's json.dump writes it for float('{}')); a model's \
                         parameters and scales must be finite numbers: re-identify the model, \
                         or replace {token} with a number",
                        if token.contains("NaN") { "nan" } else { "inf" }
                    ),
                    None => e.to_string(),
                },
            })?;
        match value.get("format_version").and_then(|v| v.as_u64()) {
            Some(v) if READABLE_VERSIONS.iter().any(|r| u64::from(*r) == v) => {}
            Some(found) => {
                return Err(ModelFileError::UnknownVersion {
                    path: String::new(),
                    found,
                });
            }
            None => {
                return Err(ModelFileError::Parse {
                    path: String::new(),
                    message: "no integer \"format_version\" field".into(),
                });
            }
        }
        // serde_path_to_error names the offending field (`a2: invalid type: ...`).
        let file: ModelFile =
            serde_path_to_error::deserialize(value).map_err(|e| ModelFileError::Parse {
                path: String::new(),
                message: e.to_string(),
            })?;
        file.validate()?;
        Ok(file)
    }

    /// The file's text: pretty-printed JSON with a final newline, as [`FORMAT_VERSION`] (a
    /// version-1 file read is written back as version 2, which only adds optional parts).
    pub fn to_json(&self) -> String {
        let current = ModelFile {
            format_version: FORMAT_VERSION,
            ..self.clone()
        };
        let mut text =
            serde_json::to_string_pretty(&current).expect("a model file always serialises to JSON");
        text.push('\n');
        text
    }

    /// Writes the file atomically (temporary file, then rename).
    ///
    /// A file larger than [`MAX_MODEL_FILE_BYTES`] (a description of many MiB) is refused
    /// before anything is written: [`ModelFile::load`] would refuse to read it back.
    pub fn save(&self, path: &Path) -> Result<(), ModelFileError> {
        self.validate()?;
        let text = self.to_json();
        if text.len() as u64 > MAX_MODEL_FILE_BYTES {
            return Err(ModelFileError::Invalid {
                message: format!(
                    "{}: the model file would take {:.1} MiB, more than the {} MiB a model file \
                     may be (and be read back); shorten its description",
                    path.display(),
                    text.len() as f64 / f64::from(1 << 20),
                    MAX_MODEL_FILE_BYTES >> 20
                ),
            });
        }
        // The error of write_atomic already reads "could not write PATH: reason".
        write_atomic(path, text.as_bytes()).map_err(ModelFileError::Write)
    }

    /// Runs the model over a whole record in physical units, from zero memory (eq. (1)):
    /// `output[k] = output.offset + output.scale * P[(input[k] - input.offset) / input.scale]`.
    ///
    /// With creep and vibration (sampled at the file's `sample_rate_hz`): a plant file runs
    /// the chain `D[C[H[v]]]`, creep starting relaxed at `origin` and the vibration link at
    /// rest at its first input; an inverse file runs `H^-1[C^-1[D^-1[y]]]`, the vibration
    /// inverse non-causally over the whole record (the record taken at rest at its first
    /// value before it starts and at its last after it ends).
    pub fn predict(&self, input: &[f64]) -> Result<Vec<f64>, ModelFileError> {
        self.predict_from(input, false)
    }

    /// As [`ModelFile::predict`], the creep link taken as having rested long at the record's
    /// start (settled at the equilibrium of its first input for a plant, at the first
    /// displacement for an inverse model) instead of relaxed at its origin: for a measured
    /// record that starts in the middle of a history.
    pub fn predict_settled(&self, input: &[f64]) -> Result<Vec<f64>, ModelFileError> {
        self.predict_from(input, true)
    }

    fn predict_from(&self, input: &[f64], settled: bool) -> Result<Vec<f64>, ModelFileError> {
        let mut model = self.model()?;
        let map = self.core_output_map()?;
        let rate = self.sample_rate_hz.unwrap_or(1.0);
        match self.direction {
            Direction::Plant => {
                let mut creep = self.creep.as_ref().map(|c| c.link(rate)).transpose()?;
                let mut vibration = self.vibration.as_ref().map(|v| v.link()).transpose()?;
                let mut first = settled;
                Ok(input
                    .iter()
                    .map(|&x| {
                        let mut y = self.hysteresis_output_to_physical(
                            &map,
                            model.step(self.normalise_input(x)),
                        );
                        if let Some(c) = &mut creep {
                            if first {
                                // At rest with input y: output origin + (y - origin) * gain.
                                let origin = c.origin();
                                c.settle(origin + (y - origin) * c.static_gain());
                                first = false;
                            }
                            y = c.step(y);
                        }
                        if let Some(d) = &mut vibration {
                            y = d.step(y);
                        }
                        y
                    })
                    .collect())
            }
            Direction::Inverse => {
                let mut x = input.to_vec();
                if let Some(v) = &self.vibration {
                    let mut inverse = v.inverse(v.needed_preview()?)?;
                    inverse.process_aligned(input, &mut x)?;
                }
                if let Some(c) = &self.creep {
                    let mut inverse: CreepInverse<f64, Vec<f64>> = c.link(rate)?.inverse();
                    if let (true, Some(&first)) = (settled, x.first()) {
                        inverse.settle(first);
                    }
                    x.iter_mut().for_each(|x| *x = inverse.step(*x));
                }
                Ok(x.iter()
                    .map(|&x| {
                        self.hysteresis_output_to_physical(
                            &map,
                            model.step(self.normalise_input(x)),
                        )
                    })
                    .collect())
            }
        }
    }

    /// How many of the physical `inputs` lie outside the range the model was identified on
    /// (`input_range`, normalised).
    pub fn count_outside_input_range(&self, inputs: &[f64]) -> usize {
        let [lo, hi] = self.input_range;
        inputs
            .iter()
            .map(|&x| self.normalise_input(x))
            .filter(|x| *x < lo || *x > hi)
            .count()
    }

    /// The normalised value of a physical model input.
    pub fn normalise_input(&self, physical: f64) -> f64 {
        self.input.normalise(physical)
    }

    /// The physical value of a normalised model output.
    pub fn output_to_physical(&self, normalised: f64) -> f64 {
        self.output.to_physical(normalised)
    }
}
