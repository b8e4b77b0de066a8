//! Many channels in physical units: a model set (one model file per channel, in one JSON file
//! or a directory) and the compensator bank built from it (issue 16).
//!
//! A [`ModelSet`] is read from
//! - a **model-set file**: one JSON object
//!   `{"format": "hystcomp-model-set", "format_version": 1, "description": "...",
//!   "channels": [{"name": "x", "model": {...}}, ...]}` where each `model` is a whole model
//!   file's object (see [`crate::model_file`]) and `name` is optional (default `channel_K`);
//! - a **directory** of model files (`*.json`, in the order of their file names, each named by
//!   its file stem);
//! - a single **model file**: a set of one channel.
//!
//! A [`ScaledBank`] is the core's bank ([`hystcomp_core::IhcBank`], [`hystcomp_core::WihcBank`],
//! [`hystcomp_core::DihcBank`]) of one method over every channel of a set, with each channel's
//! scales and drive limits: desired positions in (each channel's displacement unit), drive
//! voltages out (each channel's voltage unit), one value per channel per tick. Channel `c`
//! gives what a [`ScaledCompensator`](crate::compensator::ScaledCompensator) built from its
//! model file gives, bit for bit (the same normalisation, the same core arithmetic, the same
//! final clamp).

use std::fmt;
use std::path::Path;

use hystcomp_core::{
    BankError, CompensatorBank, CoreError, Diagnostics, DihcBank, Heap, IhcBank, Mpim,
    OutputLimits, SolveMode, WihcBank,
};
use serde_json::Value;
use serde_json::value::RawValue;

use crate::atomic::write_atomic;
use crate::compensator::{CompensatorError, Method, UnstableDelay};
use crate::model_file::{Direction, MAX_MODEL_FILE_BYTES, ModelFile, ModelFileError, Scale};

/// The `format` field of a model-set file.
pub const MODEL_SET_FORMAT: &str = "hystcomp-model-set";

/// The `format_version` of model-set files this build reads and writes.
pub const MODEL_SET_VERSION: u32 = 1;

/// The most channels a model set may hold: 65 536 (a deformable mirror has a few thousand
/// actuators), checked before the channels are read.
pub const MAX_CHANNELS: usize = 1 << 16;

/// The largest model-set file read, and the most a directory set's model files may add up
/// to: 256 MiB (4 096 channels of 10 operators take about
/// 6 MiB, [`MAX_CHANNELS`] of them about 100 MiB), checked while reading. Reading keeps the
/// text and each channel's text (the channels are parsed one at a time), about three times
/// the file's size, besides the models.
pub const MAX_MODEL_SET_BYTES: u64 = 1 << 28;

/// The fields of a JSON object, each kept as its text: a set's channels are parsed one at a
/// time, never held as one tree of values (about twenty times the text's size).
type RawFields = std::collections::BTreeMap<String, Box<RawValue>>;

/// `text`'s top-level object, its fields as text; the message says what is wrong.
fn raw_fields(text: &str) -> Result<RawFields, String> {
    // A UTF-8 byte-order mark (some Windows editors write one) is no part of the JSON.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    serde_json::from_str::<RawFields>(text).map_err(|e| {
        match serde_json::from_str::<serde::de::IgnoredAny>(text) {
            Ok(_) => format!(
                "is not a JSON object; a model set is {{\"format\": \"{MODEL_SET_FORMAT}\", \
                 \"format_version\": 1, \"channels\": [...]}}"
            ),
            Err(_) => format!("is not valid JSON: {e}"),
        }
    })
}

/// Why a set's `channels` field could not be listed.
enum ChannelListError {
    /// Not a JSON array.
    NotArray,
    /// More than [`MAX_CHANNELS`] entries (found while reading, before the one beyond it).
    TooMany,
}

/// The entries of a set's `channels` array, each kept as its text, refused as soon as it
/// holds more than [`MAX_CHANNELS`]: a file of millions of tiny entries is never listed whole.
fn channel_list(raw: &RawValue) -> Result<Vec<Box<RawValue>>, ChannelListError> {
    use serde::de::{Deserializer, Error, SeqAccess, Visitor};
    use std::cell::Cell;

    struct Bounded<'a>(&'a Cell<bool>);
    impl<'de> Visitor<'de> for Bounded<'_> {
        type Value = Vec<Box<RawValue>>;
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("an array of channels")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut list = Vec::new();
            while let Some(entry) = seq.next_element::<Box<RawValue>>()? {
                if list.len() == MAX_CHANNELS {
                    self.0.set(true);
                    return Err(A::Error::custom("too many channels"));
                }
                list.push(entry);
            }
            Ok(list)
        }
    }
    let too_many = Cell::new(false);
    let mut reader = serde_json::Deserializer::from_str(raw.get());
    reader
        .deserialize_seq(Bounded(&too_many))
        .map_err(|_| match too_many.get() {
            true => ChannelListError::TooMany,
            false => ChannelListError::NotArray,
        })
}

/// A small field's value (a name, a version): the text is valid JSON, parsed already once.
fn small(raw: &RawValue) -> Value {
    serde_json::from_str(raw.get()).unwrap_or(Value::Null)
}

/// One channel of a set: its name and its model file.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// The channel's name (a column name on the command line: `x`, `actuator_17`, ...).
    pub name: String,
    /// Its model.
    pub model: ModelFile,
}

/// The models of many channels (see the [module documentation](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSet {
    /// A line for people.
    pub description: Option<String>,
    /// The channels, in order.
    pub channels: Vec<Channel>,
}

/// Why a model set could not be read, written or used, or a bank not built.
#[derive(Debug)]
pub enum ModelSetError {
    /// The set itself (a file that cannot be read, is not a model set, holds no channel or too
    /// many).
    Set {
        /// The file or directory.
        path: String,
        /// What is wrong and how to mend it.
        message: String,
    },
    /// One channel's model file is refused.
    File {
        /// The file holding the channel's model: the model-set file, the channel's own file
        /// in a directory set, or the single model file (`"model set"` for
        /// [`ModelSet::from_json`]'s text). The message names it once: before the channel,
        /// unless `error` already names it.
        path: String,
        /// The channel's index (0-based).
        channel: usize,
        /// Its name.
        name: String,
        /// Why.
        error: ModelFileError,
    },
    /// One channel's compensator is refused (wrong direction, limits, not invertible, ...).
    Channel {
        /// The channel's index (0-based).
        channel: usize,
        /// Its name.
        name: String,
        /// Why.
        error: CompensatorError,
    },
    /// The set could not be written.
    Write(std::io::Error),
    /// Arrays of the wrong size, limits for another number of channels.
    Bank(CoreError),
}

impl fmt::Display for ModelSetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModelSetError::Set { path, message } => write!(f, "{path}: {message}"),
            ModelSetError::File {
                path,
                channel,
                name,
                error,
            } => {
                let error = error.to_string();
                if error.contains(path.as_str()) {
                    write!(f, "channel {channel} ({name}): {error}")
                } else {
                    write!(f, "{path}: channel {channel} ({name}): {error}")
                }
            }
            ModelSetError::Channel {
                channel,
                name,
                error,
            } => write!(f, "channel {channel} ({name}): {error}"),
            ModelSetError::Write(e) => write!(f, "{e}"),
            ModelSetError::Bank(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ModelSetError {}

impl ModelSet {
    /// A set of the given channels; refuses none, more than [`MAX_CHANNELS`] and names used
    /// twice.
    pub fn new(description: Option<String>, channels: Vec<Channel>) -> Result<Self, ModelSetError> {
        let set_error = |message: String| ModelSetError::Set {
            path: "model set".into(),
            message,
        };
        if channels.is_empty() {
            return Err(set_error(
                "holds no channel; give at least one model".into(),
            ));
        }
        if channels.len() > MAX_CHANNELS {
            return Err(set_error(format!(
                "holds {} channels, more than the {MAX_CHANNELS} a model set may hold",
                channels.len()
            )));
        }
        let mut names: Vec<&str> = channels.iter().map(|c| c.name.as_str()).collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(set_error(format!(
                "the channel name {:?} is used twice; give every channel its own name",
                w[0]
            )));
        }
        Ok(ModelSet {
            description,
            channels,
        })
    }

    /// The number of channels.
    pub fn len(&self) -> usize {
        self.channels.len()
    }

    /// Whether the set has no channel (never, for a set built by [`ModelSet::new`]).
    pub fn is_empty(&self) -> bool {
        self.channels.is_empty()
    }

    /// The channels' names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.channels.iter().map(|c| c.name.as_str()).collect()
    }

    /// Reads a model-set file, a directory of model files or a single model file (see the
    /// [module documentation](self)).
    pub fn load(path: &Path) -> Result<Self, ModelSetError> {
        let shown = path.display().to_string();
        let set_error = |message: String| ModelSetError::Set {
            path: shown.clone(),
            message,
        };
        if path.is_dir() {
            return Self::load_directory(path);
        }
        let bytes = match crate::bounded::read_at_most(path, MAX_MODEL_SET_BYTES) {
            Ok(crate::bounded::Bounded::Whole(bytes)) => bytes,
            Ok(crate::bounded::Bounded::TooLarge) => {
                return Err(set_error(format!(
                    "is larger than the {} MiB a model set may be",
                    MAX_MODEL_SET_BYTES >> 20
                )));
            }
            Err(e) => return Err(set_error(format!("cannot read it: {e}"))),
        };
        let text = String::from_utf8(bytes)
            .map_err(|_| set_error("is not UTF-8 text; a model set is JSON".into()))?;
        let fields = raw_fields(&text).map_err(set_error)?;
        if fields.contains_key("format_version") && !fields.contains_key("format") {
            // One model file: a set of one channel, named by the file's stem.
            if u64::try_from(text.len()).unwrap_or(u64::MAX) > MAX_MODEL_FILE_BYTES {
                return Err(set_error(format!(
                    "is larger than the {} MiB a model file may be",
                    MAX_MODEL_FILE_BYTES >> 20
                )));
            }
            let model = ModelFile::load(path).map_err(|error| ModelSetError::File {
                path: shown.clone(),
                channel: 0,
                name: stem(path),
                error,
            })?;
            return Self::new(
                None,
                vec![Channel {
                    name: stem(path),
                    model,
                }],
            )
            .map_err(|e| with_path(e, &shown));
        }
        drop(text);
        Self::from_fields(&fields).map_err(|e| with_path(e, &shown))
    }

    /// Parses a model-set file's text.
    pub fn from_json(text: &str) -> Result<Self, ModelSetError> {
        let fields = raw_fields(text).map_err(|message| ModelSetError::Set {
            path: "model set".into(),
            message,
        })?;
        Self::from_fields(&fields)
    }

    fn from_fields(fields: &RawFields) -> Result<Self, ModelSetError> {
        let set_error = |message: String| ModelSetError::Set {
            path: "model set".into(),
            message,
        };
        let field = |name: &str| fields.get(name).map(|raw| small(raw));
        match field("format").as_ref().and_then(Value::as_str) {
            Some(MODEL_SET_FORMAT) => {}
            Some(other) => {
                return Err(set_error(format!(
                    "has format {other:?}, not {MODEL_SET_FORMAT:?}"
                )));
            }
            None => {
                return Err(set_error(format!(
                    "has no \"format\": \"{MODEL_SET_FORMAT}\" field; a model set is \
                     {{\"format\": \"{MODEL_SET_FORMAT}\", \"format_version\": 1, \
                     \"channels\": [{{\"name\": ..., \"model\": {{...}}}}, ...]}}"
                )));
            }
        }
        match field("format_version").as_ref().and_then(Value::as_u64) {
            Some(v) if v == u64::from(MODEL_SET_VERSION) => {}
            Some(v) => {
                return Err(set_error(format!(
                    "has format_version {v}, but this hystcomp reads model sets of version \
                     {MODEL_SET_VERSION}; update hystcomp"
                )));
            }
            None => return Err(set_error("has no integer \"format_version\" field".into())),
        }
        let known = ["format", "format_version", "description", "channels"];
        if let Some(unknown) = fields.keys().find(|k| !known.contains(&k.as_str())) {
            return Err(set_error(format!(
                "has an unknown field {unknown:?} (known: {})",
                known.join(", ")
            )));
        }
        let description = match field("description") {
            None | Some(Value::Null) => None,
            Some(Value::String(s)) => Some(s),
            Some(_) => return Err(set_error("\"description\" is not a string".into())),
        };
        let list = match fields.get("channels").map(|raw| channel_list(raw)) {
            Some(Ok(list)) => list,
            None | Some(Err(ChannelListError::NotArray)) => {
                return Err(set_error("has no \"channels\" array".into()));
            }
            Some(Err(ChannelListError::TooMany)) => {
                return Err(set_error(format!(
                    "holds more than the {MAX_CHANNELS} channels a model set may hold"
                )));
            }
        };
        let mut channels = Vec::with_capacity(list.len());
        for (k, raw) in list.iter().enumerate() {
            let entry: RawFields = serde_json::from_str(raw.get()).map_err(|_| {
                set_error(format!(
                    "channel {k}: not an object (a channel is {{\"name\": ..., \"model\": \
                     {{...}}}})"
                ))
            })?;
            let name = match entry.get("name").map(|raw| small(raw)) {
                None | Some(Value::Null) => format!("channel_{k}"),
                Some(Value::String(s)) if !s.trim().is_empty() => s,
                Some(_) => {
                    return Err(set_error(format!(
                        "channel {k}: \"name\" is not a non-empty string"
                    )));
                }
            };
            // A name becomes a column header of the drive file: no line break or other control
            // character (refused here, not when the drives are written).
            if name.chars().any(char::is_control) {
                return Err(set_error(format!(
                    "channel {k}: \"name\" {name:?} holds a line break or another control \
                     character, which a column header cannot"
                )));
            }
            if let Some(unknown) = entry.keys().find(|k| *k != "name" && *k != "model") {
                return Err(set_error(format!(
                    "channel {k} ({name}): unknown field {unknown:?} (a channel is {{\"name\": \
                     ..., \"model\": {{...}}}})"
                )));
            }
            let Some(model) = entry.get("model") else {
                return Err(set_error(format!(
                    "channel {k} ({name}): no \"model\" object (a whole model file's object)"
                )));
            };
            if u64::try_from(model.get().len()).unwrap_or(u64::MAX) > MAX_MODEL_FILE_BYTES {
                return Err(set_error(format!(
                    "channel {k} ({name}): its model is larger than the {} MiB a model file \
                     may be",
                    MAX_MODEL_FILE_BYTES >> 20
                )));
            }
            let model = ModelFile::from_json(model.get()).map_err(|error| ModelSetError::File {
                path: "model set".into(),
                channel: k,
                name: name.clone(),
                error,
            })?;
            channels.push(Channel { name, model });
        }
        Self::new(description, channels)
    }

    /// Every `*.json` file of `dir`, in the order of their names, a channel each.
    fn load_directory(dir: &Path) -> Result<Self, ModelSetError> {
        let shown = dir.display().to_string();
        let set_error = |message: String| ModelSetError::Set {
            path: shown.clone(),
            message,
        };
        let entries =
            std::fs::read_dir(dir).map_err(|e| set_error(format!("cannot list it: {e}")))?;
        let mut files = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|e| set_error(format!("cannot list it: {e}")))?;
            let path = entry.path();
            if path.extension().and_then(|e| e.to_str()) == Some("json") && path.is_file() {
                files.push(path);
                if files.len() > MAX_CHANNELS {
                    return Err(set_error(format!(
                        "holds more than the {MAX_CHANNELS} model files a model set may hold"
                    )));
                }
            }
        }
        if files.is_empty() {
            return Err(set_error(
                "holds no model file (*.json); a directory set is one model file per channel"
                    .into(),
            ));
        }
        files.sort();
        // The files together are bounded as one set file is, before any is parsed (each alone
        // by the model file's bound, which its reader checks while reading).
        let mut total = 0u64;
        for (k, file) in files.iter().enumerate() {
            total = total.saturating_add(std::fs::metadata(file).map_or(0, |m| m.len()));
            if total > MAX_MODEL_SET_BYTES {
                return Err(set_error(format!(
                    "its model files add up to more than the {} MiB a model set may hold (at \
                     {}, channel {k})",
                    MAX_MODEL_SET_BYTES >> 20,
                    file.display()
                )));
            }
        }
        let mut channels = Vec::with_capacity(files.len());
        for (k, file) in files.iter().enumerate() {
            let name = stem(file);
            let model = ModelFile::load(file).map_err(|error| ModelSetError::File {
                path: file.display().to_string(),
                channel: k,
                name: name.clone(),
                error,
            })?;
            channels.push(Channel { name, model });
        }
        Self::new(None, channels).map_err(|e| with_path(e, &shown))
    }

    /// The set's text: a model-set file, pretty-printed JSON with a final newline.
    pub fn to_json(&self) -> String {
        let channels: Vec<Value> = self
            .channels
            .iter()
            .map(|c| {
                let model: Value =
                    serde_json::from_str(&c.model.to_json()).expect("a model file's text is JSON");
                serde_json::json!({ "name": c.name, "model": model })
            })
            .collect();
        let mut set = serde_json::json!({
            "format": MODEL_SET_FORMAT,
            "format_version": MODEL_SET_VERSION,
        });
        if let Some(d) = &self.description {
            set["description"] = Value::String(d.clone());
        }
        set["channels"] = Value::Array(channels);
        let mut text = serde_json::to_string_pretty(&set).expect("a model set serialises");
        text.push('\n');
        text
    }

    /// Writes the set as a model-set file, atomically.
    pub fn save(&self, path: &Path) -> Result<(), ModelSetError> {
        write_atomic(path, self.to_json().as_bytes()).map_err(ModelSetError::Write)
    }
}

/// Whether `path` names a model set rather than one model file: a directory, or a JSON file
/// whose `format` is [`MODEL_SET_FORMAT`]. Anything unreadable is not (its own reader then says
/// why).
pub fn is_model_set(path: &Path) -> bool {
    if path.is_dir() {
        return true;
    }
    /// The one field looked at; every other is skipped unparsed (no tree of the whole file).
    #[derive(serde::Deserialize)]
    struct Format {
        format: Option<String>,
    }
    match crate::bounded::read_at_most(path, MAX_MODEL_SET_BYTES) {
        Ok(crate::bounded::Bounded::Whole(bytes)) => serde_json::from_slice::<Format>(&bytes)
            .ok()
            .and_then(|f| f.format)
            .is_some_and(|f| f == MODEL_SET_FORMAT),
        _ => false,
    }
}

/// A file's stem, for a channel's name.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "channel_0".into())
}

/// A set-level error, or a channel's error in the set's own text, with the set file's path.
fn with_path(e: ModelSetError, path: &str) -> ModelSetError {
    match e {
        ModelSetError::Set { message, .. } => ModelSetError::Set {
            path: path.to_string(),
            message,
        },
        ModelSetError::File {
            path: placeholder,
            channel,
            name,
            error,
        } if placeholder == "model set" => ModelSetError::File {
            path: path.to_string(),
            channel,
            name,
            error,
        },
        other => other,
    }
}

/// The core's bank of any kind, in `f64`.
type AnyBank = Box<dyn CompensatorBank<f64> + Send>;

/// A bank of compensators over a model set, in physical units (see the
/// [module documentation](self)).
///
/// `step(desired, control)` takes one desired position per channel (each in its channel's
/// displacement unit) and writes one drive per channel (each in its voltage unit), always
/// within the channel's [`ScaledBank::limits`], never NaN; it never allocates.
pub struct ScaledBank {
    bank: AnyBank,
    method: Method,
    names: Vec<String>,
    /// `(offset, scale)` of every channel's desired position.
    desired: Vec<(f64, f64)>,
    /// `(offset, scale)` of every channel's drive.
    control: Vec<(f64, f64)>,
    desired_units: Vec<String>,
    control_units: Vec<String>,
    /// Physical drive limits of every channel.
    limits: Vec<(f64, f64)>,
    /// One tick's normalised desired positions and controls.
    scratch_desired: Vec<f64>,
    scratch_control: Vec<f64>,
}

impl fmt::Debug for ScaledBank {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ScaledBank")
            .field("method", &self.method)
            .field("channels", &self.names.len())
            .finish()
    }
}

impl ScaledBank {
    /// A bank of `method` over every channel of `set`. `limits` are the drive limits in each
    /// channel's voltage unit: none (each channel's identified range, as
    /// [`ScaledCompensator::new`](crate::compensator::ScaledCompensator::new) takes), one pair
    /// for every channel, or one pair per channel. A plain delayed method whose loop can
    /// oscillate on a channel is refused unless `unstable` allows it. A refused channel is
    /// named by its index and name; a model with creep or vibration links is refused (a bank
    /// compensates the hysteresis only).
    pub fn new(
        set: &ModelSet,
        method: Method,
        limits: Option<&[(f64, f64)]>,
        unstable: UnstableDelay,
    ) -> Result<Self, ModelSetError> {
        let channels = set.len();
        if let Some(l) = limits
            && l.len() != 1
            && l.len() != channels
        {
            return Err(ModelSetError::Bank(CoreError::ChannelCount {
                what: "drive limits (one pair for every channel, or one for each)",
                channels,
                found: l.len(),
                samples: false,
            }));
        }
        let mode = match (method.solve_mode(), unstable) {
            (SolveMode::Delayed, UnstableDelay::Allow) => SolveMode::DelayedAllowUnstable,
            (mode, _) => mode,
        };
        let mut models = Vec::with_capacity(channels);
        let mut normalised = Vec::with_capacity(channels);
        let mut ranges = Vec::with_capacity(channels);
        let (mut desired, mut control) = (Vec::new(), Vec::new());
        let (mut desired_units, mut control_units) = (Vec::new(), Vec::new());
        let mut physical = Vec::with_capacity(channels);
        for (k, c) in set.channels.iter().enumerate() {
            let refuse = |error: CompensatorError| ModelSetError::Channel {
                channel: k,
                name: c.name.clone(),
                error,
            };
            let file = &c.model;
            if file.direction != method.needs() {
                return Err(refuse(CompensatorError::WrongDirection {
                    method,
                    found: file.direction,
                }));
            }
            if file.has_links() {
                return Err(ModelSetError::Set {
                    path: format!("channel {k} ({})", c.name),
                    message: "the model has creep or vibration links, but a bank compensates \
                              the hysteresis only; give a hysteresis model (identify \
                              --model-structure hysteresis) or compensate this channel alone"
                        .into(),
                });
            }
            if let Err(e) = file.refuse_output_map("a bank (the MPIM alone on every channel)") {
                return Err(ModelSetError::Set {
                    path: format!("channel {k} ({})", c.name),
                    message: e.to_string(),
                });
            }
            let (d, v): (&Scale, &Scale) = match file.direction {
                Direction::Plant => (&file.output, &file.input),
                Direction::Inverse => (&file.input, &file.output),
            };
            let default = match file.direction {
                Direction::Plant => (file.input_range[0], file.input_range[1]),
                Direction::Inverse => (0.0, 1.0),
            };
            let (min, max) = match limits {
                Some(l) => l.get(k).or_else(|| l.first()).copied().unwrap_or_default(),
                None => (v.to_physical(default.0), v.to_physical(default.1)),
            };
            if !(min.is_finite() && max.is_finite() && min < max) {
                return Err(refuse(CompensatorError::InvalidLimits {
                    min,
                    max,
                    unit: v.unit.clone(),
                }));
            }
            let limit = OutputLimits::new(v.normalise(min), v.normalise(max))
                .map_err(|e| refuse(e.into()))?;
            let model: Mpim<f64, Vec<f64>> = file.core_model().map_err(|e| refuse(e.into()))?;
            models.push(model);
            normalised.push(limit);
            ranges.push((file.input_range[0], file.input_range[1]));
            desired.push((d.offset, d.scale));
            control.push((v.offset, v.scale));
            desired_units.push(d.unit.clone());
            control_units.push(v.unit.clone());
            physical.push((min, max));
        }
        let named = |e: BankError| match e {
            BankError::Channel { channel, error } => ModelSetError::Channel {
                channel,
                name: set.channels[channel].name.clone(),
                error: error.into(),
            },
            BankError::Bank(e) => ModelSetError::Bank(e),
        };
        let bank: AnyBank = match method {
            Method::Ihc | Method::IhcDelayed | Method::IhcGuarded => {
                Box::new(IhcBank::<f64, Heap>::new(&models, &normalised, mode).map_err(named)?)
            }
            Method::Wihc | Method::WihcDelayed | Method::WihcGuarded => {
                Box::new(WihcBank::<f64, Heap>::new(&models, &normalised, mode).map_err(named)?)
            }
            Method::Dihc => {
                Box::new(DihcBank::<f64, Heap>::new(&models, &ranges, &normalised).map_err(named)?)
            }
        };
        Ok(ScaledBank {
            bank,
            method,
            names: set.channels.iter().map(|c| c.name.clone()).collect(),
            desired,
            control,
            desired_units,
            control_units,
            limits: physical,
            scratch_desired: vec![0.0; channels],
            scratch_control: vec![0.0; channels],
        })
    }

    /// The number of channels.
    pub fn channels(&self) -> usize {
        self.names.len()
    }

    /// The method of every channel.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The channels' names, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The unit of `channel`'s desired position.
    pub fn desired_unit(&self, channel: usize) -> Option<&str> {
        self.desired_units.get(channel).map(String::as_str)
    }

    /// The unit of `channel`'s drive.
    pub fn control_unit(&self, channel: usize) -> Option<&str> {
        self.control_units.get(channel).map(String::as_str)
    }

    /// The drive limits `(min, max)` of `channel`, in its voltage unit.
    pub fn limits(&self, channel: usize) -> Option<(f64, f64)> {
        self.limits.get(channel).copied()
    }

    /// The diagnostics of `channel` since the last reset.
    pub fn diagnostics(&self, channel: usize) -> Option<Diagnostics> {
        self.bank.diagnostics(channel)
    }

    /// Every channel back to its initial state.
    pub fn reset(&mut self) {
        self.bank.reset();
    }

    /// The channels whose drive the last tick held (its desired position's normalised value
    /// not finite: NaN or infinite, or finite but too large for the channel's scale): how
    /// many, and the first one's index (0 when none).
    pub fn held(&self) -> (usize, usize) {
        let mut held = self
            .scratch_desired
            .iter()
            .enumerate()
            .filter(|(_, y)| !y.is_finite());
        match held.next() {
            Some((first, _)) => (1 + held.count(), first),
            None => (0, 0),
        }
    }

    /// One control tick: `control[c]` is the drive for `desired[c]`, every channel (physical
    /// units). Refuses arrays that do not hold one value per channel. Never allocates.
    pub fn step(&mut self, desired: &[f64], control: &mut [f64]) -> Result<(), CoreError> {
        self.check_tick(desired.len(), control.len())?;
        self.normalise(desired);
        self.bank
            .step(&self.scratch_desired, &mut self.scratch_control)?;
        self.to_physical(control);
        Ok(())
    }

    /// [`ScaledBank::step`] in place: `values` holds the desired positions and receives the
    /// drives.
    pub fn step_in_place(&mut self, values: &mut [f64]) -> Result<(), CoreError> {
        self.check_tick(values.len(), values.len())?;
        self.normalise(values);
        self.bank
            .step(&self.scratch_desired, &mut self.scratch_control)?;
        self.to_physical(values);
        Ok(())
    }

    fn check_tick(&self, desired: usize, control: usize) -> Result<(), CoreError> {
        hystcomp_core::check_tick(self.channels(), desired, control, "drives")
    }

    /// Every channel's desired position, normalised into the scratch row.
    fn normalise(&mut self, desired: &[f64]) {
        for ((n, &y), &(offset, scale)) in self
            .scratch_desired
            .iter_mut()
            .zip(desired)
            .zip(&self.desired)
        {
            *n = (y - offset) / scale;
        }
    }

    /// The scratch row's controls in physical units, clamped into each channel's limits.
    fn to_physical(&self, control: &mut [f64]) {
        for (((out, &v), &(offset, scale)), &(min, max)) in control
            .iter_mut()
            .zip(&self.scratch_control)
            .zip(&self.control)
            .zip(&self.limits)
        {
            // As `ScaledCompensator::step`: the normalised limits map onto the physical ones
            // up to rounding; clamp once more.
            *out = (offset + scale * v).clamp(min, max);
        }
    }

    /// A whole signal, `samples x channels` row-major (`desired[k * channels + c]`), tick
    /// after tick; refuses arrays of different lengths or not a multiple of the channel count.
    pub fn process(&mut self, desired: &[f64], control: &mut [f64]) -> Result<(), CoreError> {
        let channels = self.channels();
        hystcomp_core::check_signal(channels, desired.len(), control.len(), "drives")?;
        for (d, c) in desired
            .chunks_exact(channels)
            .zip(control.chunks_exact_mut(channels))
        {
            self.step(d, c)?;
        }
        Ok(())
    }
}
