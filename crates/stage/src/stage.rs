//! The whole stage: DAC -> amplifier -> hysteresis -> creep -> mechanics -> sensor -> ADC.

use hystcomp_core::Shown;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::amplifier::Amplifier;
use crate::config::StageConfig;
use crate::converters::Quantiser;
use crate::creep::Creep;
use crate::error::StageError;
use crate::hysteresis::{Hysteresis, RateIndependentHysteresis};
use crate::mechanics::Mechanics;

/// Duration of the slow ramp of [`quasi_static_stroke_um`], s.
pub const STROKE_RAMP_DURATION_S: f64 = 10.0;

/// Everything one sample of the stage produced.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageSample {
    /// The command given to [`Stage::step`], V (may be non-finite).
    pub command_v: f64,
    /// The voltage the DAC held during the sample, V.
    pub dac_v: f64,
    /// The amplifier's output at the end of the sample, V.
    pub amplifier_v: f64,
    /// The hysteresis output (creep-free, quasi-static), um.
    pub hysteresis_um: f64,
    /// The displacement the stack imposes (hysteresis and creep), um.
    pub free_position_um: f64,
    /// The stage's true position at the end of the sample, um.
    pub true_position_um: f64,
    /// What the controller reads through sensor and ADC, um.
    pub measured_position_um: f64,
}

/// How many commands the stage could not follow as given, since it was built or reset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ClampCounts {
    /// Commands outside the DAC's span (clamped to it).
    pub dac_clamped: u64,
    /// Commands whose amplified value lay outside the amplifier's rails (clamped to them).
    pub amplifier_clamped: u64,
    /// Samples during which the amplifier's output slewed at its current limit
    /// (`peak_current / load_capacitance`) for the whole sample: the drive asked for a faster
    /// change than the amplifier can deliver into the stack.
    pub slew_limited: u64,
    /// Samples at any of the drive's limits above (DAC span, rails, slew), each sample counted
    /// once however many it reached.
    pub limited: u64,
    /// NaN or infinite commands (the DAC held its previous value).
    pub non_finite: u64,
    /// Sensor readings outside the ADC's span (the measured position saturated at the end of
    /// the span: `adc.min_v / sensitivity` or `adc.max_v / sensitivity` um).
    pub adc_clamped: u64,
}

/// The response of a whole-signal run (python-control style): one entry per command sample.
///
/// `time_s[k] = t0 + k / sample_rate_hz` is when command `k` was written; the other outputs are
/// read at the end of that sample period, i.e. at `time_s[k] + 1 / sample_rate_hz`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StageResponse {
    /// Time at which each command was written, s.
    pub time_s: Vec<f64>,
    /// The commands, V.
    pub command_v: Vec<f64>,
    /// Amplifier output, V.
    pub amplifier_v: Vec<f64>,
    /// True position, um.
    pub true_position_um: Vec<f64>,
    /// Measured position, um.
    pub measured_position_um: Vec<f64>,
    /// Commands the stage clamped or ignored during this run.
    pub clamps: ClampCounts,
}

/// A simulated piezo nanopositioning stage (see the crate documentation for the chain).
///
/// Sans-IO and deterministic: [`Stage::step`] reads no clock, file or global random source;
/// the noise comes from a ChaCha8 generator seeded with the `seed` given to [`Stage::new`].
/// The stage starts at rest, fully relaxed, at 0 V.
#[derive(Debug, Clone)]
pub struct Stage {
    config: StageConfig,
    seed: u64,
    period_s: f64,
    dac: Quantiser,
    amplifier: Amplifier,
    hysteresis: Hysteresis,
    creep: Creep,
    mechanics: Mechanics,
    adc: Quantiser,
    noise: Option<Normal<f64>>,
    nonlinearity_um: f64,
    full_scale_um: f64,
    sensitivity_v_per_um: f64,
    rng: ChaCha8Rng,
    samples: u64,
    dac_v: f64,
    clamps: ClampCounts,
}

impl Stage {
    /// Builds a stage from a (validated here) configuration and a noise seed.
    pub fn new(config: &StageConfig, seed: u64) -> Result<Stage, StageError> {
        config.validate()?;
        let period_s = 1.0 / config.sample_rate_hz;
        let sensor = &config.sensor;
        let sigma_um = sensor.noise_rms_nm * 1e-3;
        let noise = if sigma_um > 0.0 {
            Some(Normal::new(0.0, sigma_um).map_err(|_| {
                StageError::invalid(
                    "sensor.noise_rms_nm",
                    "a valid RMS",
                    Shown(sensor.noise_rms_nm),
                )
            })?)
        } else {
            None
        };
        let full_scale_um = config.adc.max_v / sensor.sensitivity_v_per_um;
        let dac = Quantiser::new(&config.dac);
        let dac_v = dac.quantise(0.0).0;
        Ok(Stage {
            config: config.clone(),
            seed,
            period_s,
            dac,
            amplifier: Amplifier::new(&config.amplifier, period_s),
            hysteresis: Hysteresis::from_config(&config.hysteresis, config.amplifier.gain)?,
            creep: Creep::new(&config.creep, period_s),
            mechanics: Mechanics::new(&config.mechanics, period_s),
            adc: Quantiser::new(&config.adc),
            noise,
            nonlinearity_um: sensor.nonlinearity_percent / 100.0 * full_scale_um,
            full_scale_um,
            sensitivity_v_per_um: sensor.sensitivity_v_per_um,
            rng: ChaCha8Rng::seed_from_u64(seed),
            samples: 0,
            dac_v,
            clamps: ClampCounts::default(),
        })
    }

    /// The built-in default stage (the same as an empty stage file).
    pub fn default_stage(seed: u64) -> Stage {
        Stage::new(&StageConfig::default(), seed)
            .expect("the built-in configuration is valid (unit-tested)")
    }

    /// The configuration the stage was built from.
    pub fn config(&self) -> &StageConfig {
        &self.config
    }

    /// The noise seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Sample rate, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.config.sample_rate_hz
    }

    /// Sample period, s.
    pub fn period_s(&self) -> f64 {
        self.period_s
    }

    /// Samples run since the stage was built or reset.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Time of the next command, s: `samples() / sample_rate_hz`.
    pub fn time_s(&self) -> f64 {
        self.samples as f64 * self.period_s
    }

    /// Commands clamped or ignored since the stage was built or reset.
    pub fn clamps(&self) -> ClampCounts {
        self.clamps
    }

    /// The hysteresis model (e.g. to inspect its state).
    pub fn hysteresis(&self) -> &Hysteresis {
        &self.hysteresis
    }

    /// Back to rest, fully relaxed at 0 V, with the noise generator re-seeded: a reset stage
    /// repeats its first run exactly.
    pub fn reset(&mut self) {
        self.amplifier.reset();
        self.hysteresis.reset();
        self.creep.reset();
        self.mechanics.reset();
        self.rng = ChaCha8Rng::seed_from_u64(self.seed);
        self.samples = 0;
        self.dac_v = self.dac.quantise(0.0).0;
        self.clamps = ClampCounts::default();
    }

    /// Writes `command_v` to the DAC, holds it for one sample period and returns the measured
    /// position at the end of the period, um. Never panics and never returns NaN: a NaN or
    /// infinite command is ignored (the DAC holds its previous value, as a DAC does when no new
    /// code is written) and counted in [`ClampCounts::non_finite`].
    pub fn step(&mut self, command_v: f64) -> f64 {
        self.step_detailed(command_v).measured_position_um
    }

    /// As [`Stage::step`], returning every intermediate signal.
    pub fn step_detailed(&mut self, command_v: f64) -> StageSample {
        let mut dac_clamped = false;
        if command_v.is_finite() {
            let (dac_v, clamped) = self.dac.quantise(command_v);
            self.dac_v = dac_v;
            dac_clamped = clamped;
            self.clamps.dac_clamped += u64::from(clamped);
        } else {
            self.clamps.non_finite += 1;
        }
        let (amplifier_v, clamped, slewing) = self.amplifier.step_limits(self.dac_v);
        self.clamps.amplifier_clamped += u64::from(clamped);
        self.clamps.slew_limited += u64::from(slewing);
        self.clamps.limited += u64::from(dac_clamped || clamped || slewing);
        let hysteresis_um = self.hysteresis.displacement_um(amplifier_v);
        let free_position_um = self.creep.step(hysteresis_um);
        let true_position_um = self.mechanics.step(free_position_um);
        let measured_position_um = self.measure(true_position_um);
        self.samples += 1;
        StageSample {
            command_v,
            dac_v: self.dac_v,
            amplifier_v,
            hysteresis_um,
            free_position_um,
            true_position_um,
            measured_position_um,
        }
    }

    /// Strain gauge, conditioner and ADC.
    fn measure(&mut self, position_um: f64) -> f64 {
        let x = position_um / self.full_scale_um;
        let mut reading_um = position_um + self.nonlinearity_um * 4.0 * x * (1.0 - x);
        if let Some(noise) = &self.noise {
            reading_um += noise.sample(&mut self.rng);
        }
        let (adc_v, clamped) = self.adc.quantise(reading_um * self.sensitivity_v_per_um);
        self.clamps.adc_clamped += u64::from(clamped);
        adc_v / self.sensitivity_v_per_um
    }

    /// Runs a whole command signal (one value per sample) from the current state.
    pub fn run(&mut self, command_v: &[f64]) -> StageResponse {
        let n = command_v.len();
        let before = self.clamps;
        let mut response = StageResponse {
            time_s: Vec::with_capacity(n),
            command_v: command_v.to_vec(),
            amplifier_v: Vec::with_capacity(n),
            true_position_um: Vec::with_capacity(n),
            measured_position_um: Vec::with_capacity(n),
            clamps: ClampCounts::default(),
        };
        for &command in command_v {
            response.time_s.push(self.time_s());
            let sample = self.step_detailed(command);
            response.amplifier_v.push(sample.amplifier_v);
            response.true_position_um.push(sample.true_position_um);
            response
                .measured_position_um
                .push(sample.measured_position_um);
        }
        response.clamps = ClampCounts {
            dac_clamped: self.clamps.dac_clamped - before.dac_clamped,
            amplifier_clamped: self.clamps.amplifier_clamped - before.amplifier_clamped,
            slew_limited: self.clamps.slew_limited - before.slew_limited,
            limited: self.clamps.limited - before.limited,
            non_finite: self.clamps.non_finite - before.non_finite,
            adc_clamped: self.clamps.adc_clamped - before.adc_clamped,
        };
        response
    }
}

/// Simulates a fresh stage (at rest, relaxed, 0 V) driven by `command_v`.
pub fn simulate(
    config: &StageConfig,
    seed: u64,
    command_v: &[f64],
) -> Result<StageResponse, StageError> {
    Ok(Stage::new(config, seed)?.run(command_v))
}

/// The quasi-static stroke at full command: from rest, a slow linear ramp of the command from
/// 0 V to [`StageConfig::full_scale_command_v`] (10 V, i.e. 150 V at the amplifier) over
/// [`STROKE_RAMP_DURATION_S`]; the true position at the top, um.
///
/// The study's "linear feedforward gain" (section 4.3.1 of the paper) is
/// `full_scale_command_v / quasi_static_stroke_um`: `command_v(t) = y_d(t) * gain`.
pub fn quasi_static_stroke_um(config: &StageConfig) -> Result<f64, StageError> {
    let mut stage = Stage::new(config, 0)?;
    let samples = (STROKE_RAMP_DURATION_S * config.sample_rate_hz)
        .round()
        .max(1.0) as u64;
    let top = config.full_scale_command_v();
    let mut position = 0.0;
    for k in 1..=samples {
        position = stage
            .step_detailed(top * k as f64 / samples as f64)
            .true_position_um;
    }
    Ok(position)
}
