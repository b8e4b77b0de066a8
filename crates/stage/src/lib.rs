//! A simulated piezo nanopositioning stage, standing in for the set-up of Gu & Zhu (2014),
//! section 4.1: 16-bit DAC -> amplifier (gain 15, 0-150 V) -> preloaded piezo stack driving a
//! flexure stage (75 um nominal) -> strain gauge -> 16-bit ADC, sampled at 10 kHz.
//!
//! Each part is modelled from physics, not from the MPIM the compensators use:
//! - DAC and ADC: uniform 16-bit codes over +-10 V, clamped at the ends of the span;
//! - the amplifier: gain, rails, first-order small-signal bandwidth and a slew-rate limit
//!   `I_max / C` into the stack's capacitance, integrated exactly over each sample;
//! - rate-independent hysteresis ([`Hysteresis`]): a Preisach model with a smooth asymmetric
//!   density (default), an asymmetric Bouc-Wen model, or (for tests only) an MPIM read from a
//!   model file;
//! - creep: the logarithmic law (or a Kelvin-Voigt bank) giving a drift of about 1.5 % of
//!   the step per decade of time);
//! - mechanics: a second-order resonance (800 Hz, damping ratio 0.05) discretised exactly;
//! - sensor: white noise (5 nm RMS), an optional parabolic non-linearity, ADC quantisation.
//!
//! `STAGE.md` beside this crate gives the source of every default and how the default stage
//! was calibrated against the paper (uncompensated e_mhe about 13 %, stroke about 75 um).
//!
//! ```
//! use hystcomp_stage::{Stage, StageConfig, quasi_static_stroke_um};
//!
//! let config = StageConfig::from_toml_str("[mechanics]\nresonance_hz = 600.0").unwrap();
//! let mut stage = Stage::new(&config, 42).unwrap();
//! let measured_um = stage.step(5.0); // 5 V command -> 75 V at the stack
//! assert!(measured_um.is_finite());
//! let gain = config.full_scale_command_v() / quasi_static_stroke_um(&config).unwrap();
//! assert!(gain > 0.1 && gain < 0.2); // V per um
//! ```

#![warn(missing_docs)]

mod amplifier;
mod config;
mod converters;
mod creep;
mod error;
pub mod feasibility;
pub mod hysteresis;
mod mechanics;
mod stage;

pub use config::{
    AmplifierConfig, BoucWenConfig, ConverterConfig, CreepConfig, CreepLaw, HysteresisConfig,
    HysteresisModel, MechanicsConfig, MpimConfig, PreisachConfig, SensorConfig, StageConfig,
};
pub use error::StageError;
pub use feasibility::{Feasibility, feasibility, feasibility_held};
pub use hysteresis::{
    BoucWenHysteresis, Hysteresis, MpimHysteresis, PreisachHysteresis, RateIndependentHysteresis,
};
pub use stage::{
    ClampCounts, STROKE_RAMP_DURATION_S, Stage, StageResponse, StageSample, quasi_static_stroke_um,
    simulate,
};
