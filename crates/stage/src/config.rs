//! The stage file: a TOML description of every part of the simulated stage.
//!
//! Every field is optional; a missing field takes the built-in default, so an empty file is the
//! built-in stage. Unknown keys are refused (`deny_unknown_fields`) and every value is checked
//! after parsing ([`StageConfig::validate`]); an error names the field. `stages/default.toml`
//! beside this crate lists every field with its unit, default and source, and `STAGE.md`
//! explains the sources and the calibration.

use hystcomp_core::Shown;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::StageError;

/// A whole stage: converters, amplifier, hysteresis, creep, mechanics and sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StageConfig {
    /// Seed of the sensor noise for runs that do not name one (`hystcomp simulate` and
    /// `hystcomp reproduce` without `--seed`). Default 1.
    pub seed: u64,
    /// Controller sample rate, Hz. Default 10 kHz: the loop rate of this project's study on the
    /// DS1103 (the paper does not print its rate).
    pub sample_rate_hz: f64,
    /// The controller's DAC that writes the command voltage.
    pub dac: ConverterConfig,
    /// The piezo amplifier.
    pub amplifier: AmplifierConfig,
    /// Rate-independent hysteresis of the stack.
    pub hysteresis: HysteresisConfig,
    /// Creep (slow logarithmic-type drift) of the stack.
    pub creep: CreepConfig,
    /// The flexure stage's first resonance.
    pub mechanics: MechanicsConfig,
    /// The strain-gauge sensor and its signal conditioner.
    pub sensor: SensorConfig,
    /// The controller's ADC that samples the sensor voltage.
    pub adc: ConverterConfig,
}

impl Default for StageConfig {
    fn default() -> Self {
        StageConfig {
            seed: 1,
            sample_rate_hz: 10_000.0,
            dac: ConverterConfig::default(),
            amplifier: AmplifierConfig::default(),
            hysteresis: HysteresisConfig::default(),
            creep: CreepConfig::default(),
            mechanics: MechanicsConfig::default(),
            sensor: SensorConfig::default(),
            adc: ConverterConfig::default(),
        }
    }
}

/// A DAC or ADC: `bits` over the span `min_v..max_v` (DS1103: 16 bits over +-10 V).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ConverterConfig {
    /// Resolution, bits (1..=32). Default 16 (paper, section 4.1).
    pub bits: u32,
    /// Lowest voltage of the span, V. Default -10.
    pub min_v: f64,
    /// Highest voltage of the span, V. Default +10.
    pub max_v: f64,
}

impl Default for ConverterConfig {
    fn default() -> Self {
        ConverterConfig {
            bits: 16,
            min_v: -10.0,
            max_v: 10.0,
        }
    }
}

/// A linear piezo amplifier driving the stack's capacitance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AmplifierConfig {
    /// Voltage gain, V/V. Default 15 (paper, section 4.1).
    pub gain: f64,
    /// Lower output rail, V. Default 0 (paper: 0-150 V).
    pub output_min_v: f64,
    /// Upper output rail, V. Default 150 (paper: 0-150 V).
    pub output_max_v: f64,
    /// Small-signal -3 dB bandwidth of the first-order response with the stack as load, Hz.
    /// Default 2000 (a typical order of magnitude for linear amplifiers driving a few uF).
    pub bandwidth_hz: f64,
    /// Output current limit, mA; with the load capacitance it sets the slew rate
    /// `I / C`. Default 100 (an assumed, typical order of magnitude).
    pub peak_current_ma: f64,
    /// Capacitance of the stack, uF. Default 7 (estimated from the geometry of a 7 x 7 mm,
    /// ~100 mm long, 150 V stack; not a datasheet figure).
    pub load_capacitance_uf: f64,
}

impl Default for AmplifierConfig {
    fn default() -> Self {
        AmplifierConfig {
            gain: 15.0,
            output_min_v: 0.0,
            output_max_v: 150.0,
            bandwidth_hz: 2_000.0,
            peak_current_ma: 100.0,
            load_capacitance_uf: 7.0,
        }
    }
}

impl AmplifierConfig {
    /// Slew-rate limit `I / C`, V/s.
    pub fn slew_rate_v_per_s(&self) -> f64 {
        (self.peak_current_ma * 1e-3) / (self.load_capacitance_uf * 1e-6)
    }
}

/// Which rate-independent hysteresis model the stack follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum HysteresisModel {
    /// A Preisach model with a smooth, asymmetric density (the default).
    #[default]
    Preisach,
    /// An asymmetric Bouc-Wen model.
    BoucWen,
    /// An MPIM read from a model file: **for tests only** (compensating an MPIM with itself
    /// proves only that the chain is wired right, never that a compensator works on a stage).
    Mpim,
}

/// The hysteresis section: the model to use and the parameters of each model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HysteresisConfig {
    /// `"preisach"` (default), `"bouc-wen"` or `"mpim"` (tests only).
    pub model: HysteresisModel,
    /// Parameters of the Preisach model (used when `model = "preisach"`).
    pub preisach: PreisachConfig,
    /// Parameters of the Bouc-Wen model (used when `model = "bouc-wen"`).
    pub bouc_wen: BoucWenConfig,
    /// The MPIM (used when `model = "mpim"`; for tests only).
    pub mpim: MpimConfig,
}

/// An MPIM read from a hystcomp model file (`direction = "plant"`, input: the DAC command
/// voltage in V, output: displacement in um), as the stage's hysteresis. **For tests only.**
/// The stage's amplifier voltage is divided by the amplifier gain to give the model its command
/// voltage.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MpimConfig {
    /// The model file; a relative path is relative to the stage file's directory. Required when
    /// `model = "mpim"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_file: Option<std::path::PathBuf>,
}

impl Default for HysteresisConfig {
    fn default() -> Self {
        HysteresisConfig {
            model: HysteresisModel::Preisach,
            preisach: PreisachConfig::default(),
            bouc_wen: BoucWenConfig::default(),
            mpim: MpimConfig::default(),
        }
    }
}

/// A Preisach model in the voltage range `voltage_range_v`, normalised to `u` in `[0, 1]`.
///
/// Output (before creep) `x = stroke_um * (R(u) + integral of mu over the relays that are on)`:
/// - reversible part `R(u) = f (u + rho (u^2 - u))`, `f = reversible_fraction`,
///   `rho = reversible_curvature`;
/// - relay density `mu(alpha, beta) ~ exp(-(alpha - beta)^2 / (2 s^2)) (1 + t (alpha + beta - 1))`,
///   `s = relay_width_sd`, `t = density_tilt`, scaled so that the relays hold `1 - f`.
///
/// The ascending branch from rest reaches `stroke_um` at the top of the range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PreisachConfig {
    /// Creep-free displacement at the top of `voltage_range_v` reached from rest, um.
    pub stroke_um: f64,
    /// Voltage range the relays' thresholds span, V. Default 0..150 (the stack's range).
    pub voltage_range_v: [f64; 2],
    /// Share of the stroke that is reversible (anhysteretic), in `[0, 1)`.
    pub reversible_fraction: f64,
    /// `rho` in `[-1, 1]`: the reversible slope grows with voltage when positive.
    pub reversible_curvature: f64,
    /// Standard deviation of the relay width `alpha - beta`, fraction of the range, > 0.
    pub relay_width_sd: f64,
    /// `t` in `(-1, 1)`: negative puts more relays at low voltage, making the loop asymmetric.
    pub density_tilt: f64,
    /// Cells per side of the Everett-function table (16..=2048).
    pub grid_cells: u32,
}

impl Default for PreisachConfig {
    fn default() -> Self {
        PreisachConfig {
            stroke_um: 72.27,
            voltage_range_v: [0.0, 150.0],
            reversible_fraction: 0.55,
            reversible_curvature: 0.3,
            relay_width_sd: 0.23,
            density_tilt: -0.3,
            grid_cells: 256,
        }
    }
}

/// An asymmetric Bouc-Wen model, voltage `v` in volts, displacement in um:
/// `x = d_p v - (h - h_rest) + c2 u^2 + c3 u^3`, `u = v / full_scale_v`, with
/// `dh = A d_p dv - B |dv| h - Gamma dv |h|`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoucWenConfig {
    /// `A`, dimensionless. Default 0.40648 (the set issue 4 gives as a literature set for a
    /// piezo; its primary source could not be traced, see STAGE.md).
    pub a: f64,
    /// `B`, 1/V. Default 0.00833 (same set).
    pub b: f64,
    /// `Gamma`, 1/V. Default 0.00833 (same set).
    pub gamma: f64,
    /// Piezoelectric coefficient `d_p` of the stage, um/V.
    pub d_p_um_per_v: f64,
    /// Voltage that normalises the asymmetry polynomial, V. Default 150.
    pub full_scale_v: f64,
    /// `c2`: displacement of the `u^2` asymmetry term at full scale, um.
    pub quadratic_um: f64,
    /// `c3`: displacement of the `u^3` asymmetry term at full scale, um.
    pub cubic_um: f64,
}

impl Default for BoucWenConfig {
    fn default() -> Self {
        BoucWenConfig {
            a: 0.40648,
            b: 0.00833,
            gamma: 0.00833,
            d_p_um_per_v: 0.72,
            full_scale_v: 150.0,
            quadratic_um: 0.0,
            cubic_um: -8.0,
        }
    }
}

/// The stack's creep law, acting on the hysteresis output (see `STAGE.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CreepLaw {
    /// The logarithmic law of piezo creep, `x(t) = x_h (1 + gamma log10(1 + t / t0))` after a
    /// step of the creep-free displacement `x_h` (Jung & Gweon 2000, regularised at the onset
    /// time `t0`): a continuous spectrum of time constants that never stops growing. The
    /// default; no finite bank of exponentials reproduces it exactly.
    Logarithmic,
    /// A finite bank of first-order (Kelvin-Voigt) elements at log-spaced time constants,
    /// `first_time_constant_s * 10^(i / elements_per_decade)`, `i = 0..=decades *
    /// elements_per_decade`, each weighted `percent_per_decade / 100 / elements_per_decade`:
    /// the structure of Kuhnen's creep operators, which a model's creep link can copy.
    KelvinVoigt,
}

/// Creep acting on the hysteresis output: [`CreepLaw::Logarithmic`] (default) or
/// [`CreepLaw::KelvinVoigt`]. After a step the displacement grows by about
/// `percent_per_decade` % of the creep-free step per decade of time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CreepConfig {
    /// `"logarithmic"` (default) or `"kelvin-voigt"`.
    pub law: CreepLaw,
    /// Drift per decade of time, percent of the creep-free displacement, in `[0, 10]`.
    pub percent_per_decade: f64,
    /// Logarithmic law: onset time `t0`, s (the drift is `gamma log10(1 + t / t0)`).
    pub onset_time_s: f64,
    /// Logarithmic law: the longest time constant simulated, s; the drift follows the
    /// logarithm to about a tenth of it (1e6 s: eleven days).
    pub longest_time_constant_s: f64,
    /// Kelvin-Voigt law: shortest time constant, s.
    pub first_time_constant_s: f64,
    /// Kelvin-Voigt law: decades of time covered (1..=12).
    pub decades: u32,
    /// Elements per decade of time constants (1..=10): the Kelvin-Voigt bank's, or the
    /// logarithmic law's quadrature nodes.
    pub elements_per_decade: u32,
}

impl Default for CreepConfig {
    fn default() -> Self {
        CreepConfig {
            law: CreepLaw::Logarithmic,
            percent_per_decade: 1.5,
            onset_time_s: 0.01,
            longest_time_constant_s: 1.0e6,
            first_time_constant_s: 0.01,
            decades: 5,
            elements_per_decade: 4,
        }
    }
}

/// The first resonance of the stage: `x'' + 2 zeta w x' + w^2 x = w^2 x_free`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MechanicsConfig {
    /// Undamped natural frequency, Hz, below the Nyquist frequency. Default 800.
    pub resonance_hz: f64,
    /// Damping ratio, > 0 (up to 10). Default 0.05.
    pub damping_ratio: f64,
    /// `true` makes the stage rigid: the true position is the stack's free displacement at the
    /// end of each sample, with no resonance (`resonance_hz` and `damping_ratio` are then
    /// unused). Default `false`. Not a physical stage: for ablation studies (the study's
    /// "dynamics off" run) that ask what the resonance costs.
    pub rigid: bool,
}

impl Default for MechanicsConfig {
    fn default() -> Self {
        MechanicsConfig {
            resonance_hz: 800.0,
            damping_ratio: 0.05,
            rigid: false,
        }
    }
}

/// The strain-gauge sensor and its conditioner, whose output the ADC samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// RMS of the white measurement noise, nm. Default 5.
    pub noise_rms_nm: f64,
    /// Conditioner output per micrometre, V/um. Default 0.1 (10 V at 100 um).
    pub sensitivity_v_per_um: f64,
    /// Peak of a parabolic non-linearity (zero at 0 and at the ADC's full scale), percent of
    /// the full scale, in `[0, 5]`. Default 0 (off).
    pub nonlinearity_percent: f64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        SensorConfig {
            noise_rms_nm: 5.0,
            sensitivity_v_per_um: 0.1,
            nonlinearity_percent: 0.0,
        }
    }
}

fn finite(field: &'static str, x: f64) -> Result<f64, StageError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(StageError::invalid(field, "a finite number", Shown(x)))
    }
}

/// The longest stroke a stage file may give, um (a metre).
pub const MAX_STROKE_UM: f64 = 1e6;

fn positive(field: &'static str, x: f64) -> Result<(), StageError> {
    // A subnormal value is no physical quantity, and dividing by it overflows.
    if finite(field, x)? > 0.0 && x.is_normal() {
        Ok(())
    } else {
        Err(StageError::invalid(field, "> 0", Shown(x)))
    }
}

fn within(field: &'static str, x: f64, lo: f64, hi: f64, text: &str) -> Result<(), StageError> {
    if (lo..=hi).contains(&finite(field, x)?) {
        Ok(())
    } else {
        Err(StageError::invalid(field, text.to_string(), Shown(x)))
    }
}

fn ordered(field: &'static str, lo: f64, hi: f64) -> Result<(), StageError> {
    finite(field, lo)?;
    finite(field, hi)?;
    // The span must be a normal number: a subnormal one divides to infinity, an infinite one
    // (-1e308..1e308) overflows.
    if lo < hi && (hi - lo).is_normal() {
        Ok(())
    } else {
        Err(StageError::invalid(
            field,
            "increasing (lower limit below upper limit), with a span of ordinary size",
            format!("[{}, {}]", Shown(lo), Shown(hi)),
        ))
    }
}

fn count(field: &'static str, n: u32, lo: u32, hi: u32) -> Result<(), StageError> {
    if (lo..=hi).contains(&n) {
        Ok(())
    } else {
        Err(StageError::invalid(field, format!("in {lo}..={hi}"), n))
    }
}

/// The largest stage file read (1 MiB; the built-in one takes 3 KiB).
pub const MAX_STAGE_FILE_BYTES: u64 = 1 << 20;

/// The highest `sample_rate_hz` a stage file may give (1 MHz): every simulated second takes
/// this many samples of each signal.
pub const MAX_SAMPLE_RATE_HZ: f64 = 1e6;

impl StageConfig {
    /// Parses a stage file and checks every value. An empty text gives the built-in default.
    pub fn from_toml_str(text: &str) -> Result<StageConfig, StageError> {
        let config: StageConfig = toml::from_str(text).map_err(|e| StageError::Parse {
            message: e.to_string(),
        })?;
        config.validate()?;
        Ok(config)
    }

    /// Reads and parses a stage file (see [`StageConfig::from_toml_str`]).
    pub fn from_toml_file(path: &Path) -> Result<StageConfig, StageError> {
        let io = |message: String| StageError::Io {
            path: path.to_path_buf(),
            message,
        };
        let bytes = match hystcomp_io::bounded::read_at_most(path, MAX_STAGE_FILE_BYTES)
            .map_err(|e| io(e.to_string()))?
        {
            hystcomp_io::bounded::Bounded::Whole(bytes) => bytes,
            hystcomp_io::bounded::Bounded::TooLarge => {
                return Err(io(format!(
                    "it is larger than the {} MiB a stage file may be (or never ends)",
                    MAX_STAGE_FILE_BYTES >> 20
                )));
            }
        };
        let text = String::from_utf8(bytes).map_err(|e| io(format!("not UTF-8 text ({e})")))?;
        let mut config = StageConfig::from_toml_str(&text)?;
        // A model file named relative to the stage file is found beside it.
        if let (Some(file), Some(dir)) = (&config.hysteresis.mpim.model_file, path.parent())
            && file.is_relative()
        {
            config.hysteresis.mpim.model_file = Some(dir.join(file));
        }
        Ok(config)
    }

    /// The effective configuration as a stage file (every field written), for reports.
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).expect("a stage configuration always serialises to TOML")
    }

    /// The largest useful command, V: the one that drives the amplifier to its upper rail,
    /// `output_max_v / gain` (10 V for the built-in stage), or the DAC's top `dac.max_v` when
    /// the amplifier's gain cannot reach the rail from it (a 10 V DAC into a x10 amplifier with
    /// 150 V rails tops out at 100 V).
    pub fn full_scale_command_v(&self) -> f64 {
        (self.amplifier.output_max_v / self.amplifier.gain).min(self.dac.max_v)
    }

    /// Checks every value; the error names the first offending field.
    pub fn validate(&self) -> Result<(), StageError> {
        positive("sample_rate_hz", self.sample_rate_hz)?;
        within(
            "sample_rate_hz",
            self.sample_rate_hz,
            0.0,
            MAX_SAMPLE_RATE_HZ,
            "at most 1e6 Hz (a piezo stage's controller samples at 1 to 100 kHz)",
        )?;
        for (name, c) in [("dac", &self.dac), ("adc", &self.adc)] {
            let (bits, span) = if name == "dac" {
                ("dac.bits", "dac.min_v..dac.max_v")
            } else {
                ("adc.bits", "adc.min_v..adc.max_v")
            };
            count(bits, c.bits, 1, 32)?;
            ordered(span, c.min_v, c.max_v)?;
        }

        // The ADC's top is the sensor's full scale (the nonlinearity is a fraction of it).
        positive("adc.max_v", self.adc.max_v)?;

        let a = &self.amplifier;
        positive("amplifier.gain", a.gain)?;
        ordered(
            "amplifier.output_min_v..amplifier.output_max_v",
            a.output_min_v,
            a.output_max_v,
        )?;
        positive("amplifier.bandwidth_hz", a.bandwidth_hz)?;
        positive("amplifier.peak_current_ma", a.peak_current_ma)?;
        positive("amplifier.load_capacitance_uf", a.load_capacitance_uf)?;

        self.hysteresis.preisach.validate()?;
        self.hysteresis.bouc_wen.validate()?;
        if self.hysteresis.model == HysteresisModel::Mpim
            && self.hysteresis.mpim.model_file.is_none()
        {
            return Err(StageError::invalid(
                "hysteresis.mpim.model_file",
                "a model file path when hysteresis.model = \"mpim\"",
                "nothing",
            ));
        }

        let c = &self.creep;
        within(
            "creep.percent_per_decade",
            c.percent_per_decade,
            0.0,
            10.0,
            "in [0, 10]",
        )?;
        positive("creep.first_time_constant_s", c.first_time_constant_s)?;
        count("creep.decades", c.decades, 1, 12)?;
        count("creep.elements_per_decade", c.elements_per_decade, 1, 10)?;
        within(
            "creep.onset_time_s",
            c.onset_time_s,
            1e-6,
            1e3,
            "in [1e-6, 1e3] s",
        )?;
        within(
            "creep.longest_time_constant_s",
            c.longest_time_constant_s,
            c.onset_time_s * 10.0,
            1e9,
            "between 10 x creep.onset_time_s and 1e9 s",
        )?;

        let m = &self.mechanics;
        positive("mechanics.resonance_hz", m.resonance_hz)?;
        if m.resonance_hz >= self.sample_rate_hz / 2.0 {
            return Err(StageError::invalid(
                "mechanics.resonance_hz",
                format!(
                    "below the Nyquist frequency sample_rate_hz / 2 = {}",
                    self.sample_rate_hz / 2.0
                ),
                m.resonance_hz,
            ));
        }
        within(
            "mechanics.damping_ratio",
            m.damping_ratio,
            1e-6,
            10.0,
            "in (0, 10] (a negative or zero damping ratio is an unstable stage)",
        )?;

        let s = &self.sensor;
        within(
            "sensor.noise_rms_nm",
            s.noise_rms_nm,
            0.0,
            1e6,
            "in [0, 1e6]",
        )?;
        positive("sensor.sensitivity_v_per_um", s.sensitivity_v_per_um)?;
        within(
            "sensor.nonlinearity_percent",
            s.nonlinearity_percent,
            0.0,
            5.0,
            "in [0, 5]",
        )?;
        Ok(())
    }
}

impl PreisachConfig {
    /// Checks every value; the error names the first offending field.
    pub fn validate(&self) -> Result<(), StageError> {
        let p = self;
        positive("hysteresis.preisach.stroke_um", p.stroke_um)?;
        // A metre: beyond, the simulated positions leave what every reader of a record takes
        // (1e15) once multiplied out, and no piezo stage strokes that far.
        within(
            "hysteresis.preisach.stroke_um",
            p.stroke_um,
            0.0,
            MAX_STROKE_UM,
            &format!("at most {MAX_STROKE_UM} um"),
        )?;
        ordered(
            "hysteresis.preisach.voltage_range_v",
            p.voltage_range_v[0],
            p.voltage_range_v[1],
        )?;
        within(
            "hysteresis.preisach.reversible_fraction",
            p.reversible_fraction,
            0.0,
            0.999,
            "in [0, 0.999]",
        )?;
        within(
            "hysteresis.preisach.reversible_curvature",
            p.reversible_curvature,
            -1.0,
            1.0,
            "in [-1, 1]",
        )?;
        within(
            "hysteresis.preisach.relay_width_sd",
            p.relay_width_sd,
            1e-3,
            10.0,
            "in [0.001, 10]",
        )?;
        within(
            "hysteresis.preisach.density_tilt",
            p.density_tilt,
            -0.99,
            0.99,
            "in [-0.99, 0.99]",
        )?;
        count("hysteresis.preisach.grid_cells", p.grid_cells, 16, 2048)?;
        Ok(())
    }
}

impl BoucWenConfig {
    /// Checks every value; the error names the first offending field.
    pub fn validate(&self) -> Result<(), StageError> {
        let bw = self;
        within("hysteresis.bouc_wen.a", bw.a, 0.0, 1e6, "in [0, 1e6]")?;
        positive("hysteresis.bouc_wen.b", bw.b)?;
        within(
            "hysteresis.bouc_wen.gamma",
            bw.gamma,
            -bw.b,
            bw.b,
            "in [-b, b] (a bounded Bouc-Wen loop)",
        )?;
        positive("hysteresis.bouc_wen.d_p_um_per_v", bw.d_p_um_per_v)?;
        positive("hysteresis.bouc_wen.full_scale_v", bw.full_scale_v)?;
        finite("hysteresis.bouc_wen.quadratic_um", bw.quadratic_um)?;
        finite("hysteresis.bouc_wen.cubic_um", bw.cubic_um)?;
        Ok(())
    }
}
