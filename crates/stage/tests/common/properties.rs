//! What a stage file and the stage built from it promise on any input: shared by the
//! proptests (`tests/any_input.rs`, on stable, in CI) and the fuzz target `stage` (`fuzz/`).
//!
//! - A stage file is refused with a message, or loads into a configuration that validates
//!   and writes back to a stage file that loads again;
//! - a stage built from it, driven by any commands (NaN, infinities, 1e308 among them),
//!   answers every sample with finite positions, an amplifier voltage within its rails and
//!   increasing times, and counts the non-finite commands.
#![allow(dead_code)]

use hystcomp_stage::{HysteresisModel, Stage, StageConfig};

/// The commands every stage is driven with, V.
pub const COMMANDS: [f64; 16] = [
    0.0,
    2.5,
    5.0,
    10.0,
    7.5,
    1.0,
    -1.0,
    12.0,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1e308,
    -1e308,
    5e-324,
    4.0,
    6.0,
];

/// Checks a stage file's text.
pub fn check_stage_text(text: &str, seed: u64) -> Result<(), String> {
    let mut config = match StageConfig::from_toml_str(text) {
        Ok(config) => config,
        Err(error) => {
            return if error.to_string().trim().is_empty() {
                Err(format!("an empty message for {error:?}"))
            } else {
                Ok(())
            };
        }
    };
    config
        .validate()
        .map_err(|e| format!("a loaded stage file does not validate: {e}"))?;
    let written = config.to_toml_string();
    StageConfig::from_toml_str(&written)
        .map_err(|e| format!("a stage file does not reload from its own text: {e}\n{written}"))?;
    // No file is read here: a stage naming a model file is left out.
    if config.hysteresis.model == HysteresisModel::Mpim {
        return Ok(());
    }
    config.hysteresis.mpim.model_file = None;
    let mut stage = match Stage::new(&config, seed) {
        Ok(stage) => stage,
        Err(error) if !error.to_string().trim().is_empty() => return Ok(()),
        Err(error) => return Err(format!("an empty message for {error:?}")),
    };
    let response = stage.run(&COMMANDS);
    let n = COMMANDS.len();
    for (name, values) in [
        ("time_s", &response.time_s),
        ("amplifier_v", &response.amplifier_v),
        ("true_position_um", &response.true_position_um),
        ("measured_position_um", &response.measured_position_um),
    ] {
        if values.len() != n {
            return Err(format!("{name}: {} samples for {n} commands", values.len()));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "{name}[{k}] = {} for command {}",
                values[k], COMMANDS[k]
            ));
        }
    }
    let (lo, hi) = (config.amplifier.output_min_v, config.amplifier.output_max_v);
    if let Some(k) = response
        .amplifier_v
        .iter()
        .position(|&v| v < lo - 1e-9 * lo.abs().max(1.0) || v > hi + 1e-9 * hi.abs().max(1.0))
    {
        return Err(format!(
            "amplifier_v[{k}] = {} outside the rails [{lo}, {hi}]",
            response.amplifier_v[k]
        ));
    }
    if response.time_s.windows(2).any(|w| w[1] <= w[0]) {
        return Err("time does not increase".to_owned());
    }
    let non_finite = COMMANDS.iter().filter(|c| !c.is_finite()).count() as u64;
    if response.clamps.non_finite != non_finite {
        return Err(format!(
            "{} non-finite commands counted, {non_finite} given",
            response.clamps.non_finite
        ));
    }
    Ok(())
}
