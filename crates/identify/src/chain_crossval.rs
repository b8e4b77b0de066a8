//! Cross-validation of the chain (hysteresis -> creep -> vibration): the plant and inverse
//! chains identified on one record ([`crate::chain`]), validated on another exactly as the
//! MPIM alone is ([`crate::validate_models`]: the forward prediction and the offline inverse
//! replay of every compensator, the chain inverted in reverse order).

use serde::{Deserialize, Serialize};

use crate::{
    ChainOptions, ChainReport, CrossValidation, CrossvalOptions, CrossvalReport, IdentifyError,
    Record, identify_chain, identify_inverse_chain, validate_models_from,
};
use hystcomp_io::model_file::Direction;

/// A cross-validation of the chain: the usual report (its fit reports are the chains'
/// hysteresis links') and the two chains' own reports.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainCrossValidation {
    /// Models, fits and the validation on the test record.
    pub crossval: CrossValidation,
    /// The plant chain's report (each link's contribution).
    pub plant_chain: ChainReport,
    /// The inverse chain's report.
    pub inverse_chain: ChainReport,
}

/// Identifies the plant and inverse chains on `train` and validates them on `test` (both
/// sampled at `chain.sample_rate_hz`).
pub fn crossval_chain(
    train: Record<'_>,
    test: Record<'_>,
    options: &CrossvalOptions,
    chain: &ChainOptions,
) -> Result<ChainCrossValidation, IdentifyError> {
    let plant_options = crate::IdentifyOptions {
        direction: Direction::Plant,
        ..options.identify.clone()
    };
    let plant = identify_chain(train.voltage, train.displacement, &plant_options, chain)?;
    let inverse = identify_inverse_chain(
        train.voltage,
        train.displacement,
        &options.identify,
        chain,
        &plant,
    )?;
    let limits = [
        plant.report.hysteresis.input.min,
        plant.report.hysteresis.input.max,
    ];
    let mut test_report = validate_models_from(
        &plant.model,
        &inverse.model,
        limits,
        crate::crossval::preceding(train, options.test_start),
        test,
        options.test_warmup,
        options.unstable_delay,
    )?;
    // The inverse chain's hysteresis link takes the creep-free displacement, not the
    // measured one: the test record is compared with the training record's measured range.
    let (lo, hi) = crate::identification::min_max(train.displacement);
    test_report.displacement_outside_model_range = test
        .displacement
        .iter()
        .filter(|&&y| y < lo || y > hi)
        .count();
    Ok(ChainCrossValidation {
        crossval: CrossValidation {
            report: CrossvalReport {
                plant: plant.report.hysteresis.clone(),
                inverse: inverse.report.hysteresis.clone(),
                test: test_report,
            },
            plant: plant.model,
            inverse: inverse.model,
        },
        plant_chain: plant.report,
        inverse_chain: inverse.report,
    })
}
