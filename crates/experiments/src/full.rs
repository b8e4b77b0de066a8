//! The `full` pipeline: the chain hysteresis -> creep -> vibration (Croft, Shed & Devasia
//! 2001, doi:10.1115/1.1341197) identified by least squares from the study's whole
//! identification record (the hysteresis excitation, then the [`ChainExcitation`]'s rate
//! sweep, holds and vibration segment), and inverted in reverse order: the vibration link
//! non-causally over the known trajectory, then the creep link, then the exact IHC and WIHC
//! (plant chain) or DIHC (inverse chain). See `hystcomp_identify::chain` and
//! `hystcomp_core::ChainCompensator`.
//!
//! The `paper` and `exact` pipelines identify on the hysteresis excitation alone, as before
//! this pipeline existed: their first 43 s of the record are the same samples.

use std::ops::Range;
use std::time::Instant;

use hystcomp_identify::{
    ChainIdentification, ChainOptions, CreepOptions, DynamicsOptions, IdentifyOptions, Thresholds,
    identify_chain, identify_inverse_chain,
};
use hystcomp_io::model_file::Direction;
use serde::Serialize;

use crate::chain_excitation::ChainExcitation;
use crate::study::{StudyError, TrackingRun};

/// How the `full` pipeline is identified.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FullOptions {
    /// The creep link's time constants and how its weights are fitted (by default two per
    /// decade from 10 ms to 100 s, two thirds of the 154 s record, the weights on the
    /// record's holds with the smoothness chosen among [`HOLD_SMOOTHNESS_CANDIDATES`]; see
    /// [`FullOptions::default`]).
    pub creep: CreepOptions,
    /// When not empty, the creep link's time constants end at the one of these, s, whose bank
    /// (two per decade from the first time constant of `creep`) predicts the record's holds
    /// best, each hold left out in turn (`hystcomp_identify::creep_holds`); `creep`'s own
    /// list is then only its start. Used with `creep.from_holds` and its smoothness
    /// candidates (each bank is scored with its best smoothness).
    pub creep_longest_candidates_s: Vec<f64>,
    /// The vibration link's identification (its segment is the excitation's).
    pub dynamics: DynamicsOptions,
    /// What the identification excitation gains for the chain.
    pub excitation: ChainExcitation,
    /// Output-error refinements of the joint hysteresis-and-creep fit (see
    /// `hystcomp_identify::identify_chain`). None by default: on the study's record they move
    /// its numbers by less than 0.01 points of e_rms and cost about a second.
    pub output_error_iterations: usize,
    /// The plant chain's play operators (eq. (11); spaced by
    /// [`FullOptions::threshold_exponent`]).
    pub operators: usize,
    /// The inverse (DIHC) chain's play operators.
    pub inverse_operators: usize,
    /// Both chains' thresholds are `((i - 1) / n)^p` of the normalised input range for this
    /// exponent `p` (see [`THRESHOLD_EXPONENT`]); 1 is the paper's uniform spacing, eq. (11).
    pub threshold_exponent: f64,
    /// The degree of both chains' output map (`IdentifyOptions::output_map_degree`: the
    /// hysteresis link `psi^-1(H[v])`, Kuhnen's modified Prandtl-Ishlinskii structure; 1:
    /// none, the MPIM alone).
    pub output_map_degree: usize,
    /// In the speed study, the chain's vibration inverse is limited to this band, Hz
    /// (`hystcomp_io::compensator::ScaledCompensator::with_inverse_band`: the known trajectory
    /// low-passed with zero phase before it is inverted; indices against the trajectory
    /// itself); `None` inverts it whole. Meant as the top of the band the vibration link was
    /// identified on.
    pub inverse_band_hz: Option<f64>,
}

/// The degree of the `full` pipeline's output map (`IdentifyOptions::output_map_degree`), in
/// both chains. Chosen by held-out error on a creep-, dynamics- and noise-free copy of the
/// stage (`examples/hyst_class_diag.rs`: the MPIM fitted on the hysteresis excitation, its
/// prediction of the chain excitation's rate sweep and holds): degree 1 (none) 0.399 %, 2
/// 0.279 %, 3 0.078 %, 4 0.081 %, 5 0.078 % of the range, so 3, the least within the noise of
/// the best. The stage's Preisach density is tilted, its loops asymmetric: the MPIM alone
/// cannot follow them, `psi^-1(H[v])` can (Kuhnen 2003, doi:10.3166/ejc.9.407-418).
pub const OUTPUT_MAP_DEGREE: usize = 3;

/// The exponent of the `full` pipeline's threshold spacing (see
/// [`FullOptions::threshold_exponent`]): 1.75, thresholds crowded towards zero, with
/// [`OPERATORS`] play operators in both chains.
///
/// A minor loop of amplitude `a` (normalised) is shaped only by the play operators with
/// `2 r_i < a`: with ten uniform thresholds, the speed study's 20 um raster (0.27 of the
/// range) sees two of them, and its static error is the model's minor-loop error (measured by
/// `examples/minor_loop_diag.rs`, seed 1, 10 Hz, rigid quiet copy: 0.525 % of the scan, of
/// which 0.448 the loop's mean, hung from its top reversal at the wrong width).
///
/// Chosen jointly with the operator count by a rule fixed before looking at the raster (least
/// plant-chain held-out error on the creep-, dynamics- and noise-free copy,
/// `examples/hyst_class_diag.rs`, over 10, 12, 15, 20 operators and p = 1 to 2; the simplest
/// point within 1 % of the least): 12 operators at p = 1.75 (0.0549 %; 10 at 1.75 0.0558 %).
/// Crowded thresholds fix the hysteresis link's small-signal gain on the vibration segment
/// (0.89 -> 1.00) and with it the vibration fit, and the 100 Hz raster meets 0.5 % on the
/// built-in amplifier (0.444 %, against 0.774 % with ten uniform thresholds). The correct
/// vibration inverse of that raster asks more than the amplifier's slew at its corners, and
/// the learning study's raster, started from the faithful drive, then crawls (best of 20
/// trials 0.135 %, issue 12: 0.1); started from the slew-constrained drive
/// (`StudyOptions::feasible_learning_start`, on by default) it reaches 0.080 % (seeds 1-3:
/// 0.080-0.083 %). README, `full` pipeline (the raster bullet's grid) and learning sections.
pub const THRESHOLD_EXPONENT: f64 = 1.75;

/// The `full` pipeline's play operators in each chain (see [`THRESHOLD_EXPONENT`] for how
/// they were chosen with the spacing).
pub const OPERATORS: usize = 12;

/// The default smoothness penalty on the `full` pipeline's creep weights
/// (`hystcomp_identify::FitProblem::with_extra_smoothness`) when they are fitted jointly
/// with the hysteresis (not the default: see [`FullOptions::default`]).
pub const CREEP_SMOOTHNESS: f64 = 1.0;

/// The longest creep time constants the `full` pipeline chooses among, s: the record's
/// longest hold (60 s) and a decade or two beyond it.
pub const CREEP_LONGEST_CANDIDATES_S: [f64; 3] = [100.0, 1000.0, 10_000.0];

/// The smoothness penalties the creep fit on the record's holds chooses among, by leaving
/// each hold out in turn (`hystcomp_identify::creep_holds`).
pub const HOLD_SMOOTHNESS_CANDIDATES: [f64; 7] =
    hystcomp_identify::creep_holds::DEFAULT_SMOOTHNESS_CANDIDATES;

impl Default for FullOptions {
    /// The creep link's time constants end at 100 s: the record (154 s) holds a step for 60 s
    /// at most, and a bank reaching 1000 s left three of its eleven weights at their floor and
    /// made the model's creep outrun the stage's after a step (measured in the README's
    /// section on the `full` pipeline). The weights are fitted on the record's holds, where
    /// the hysteresis does not move (`hystcomp_identify::creep_holds`), then the hysteresis on
    /// the creep-free displacement: fitted jointly over the whole record, the creep elements
    /// absorbed part of the hysteresis model's mismatch and their creep grew 11 % more than
    /// the stage's over a held step (0.179 um of drift against 0.050 um now). Neighbouring
    /// weights are smoothed (Tikhonov), which pulls the weights towards the flat spectrum of
    /// logarithmic creep where the holds cannot tell neighbouring time constants apart; the
    /// penalty is chosen among [`HOLD_SMOOTHNESS_CANDIDATES`] by leaving each hold out. The
    /// chains have [`OPERATORS`] operators at the spacing [`THRESHOLD_EXPONENT`] (chosen
    /// jointly by held-out error; uniform 12-20 bend the vibration fit with an extra pole, 20
    /// or 40 fit the record better but track worse).
    fn default() -> Self {
        FullOptions {
            creep: CreepOptions::log_spaced(0.01, 100.0, 2)
                .with_smoothness(CREEP_SMOOTHNESS)
                .on_holds(&HOLD_SMOOTHNESS_CANDIDATES),
            creep_longest_candidates_s: CREEP_LONGEST_CANDIDATES_S.to_vec(),
            dynamics: DynamicsOptions::default(),
            excitation: ChainExcitation::default(),
            output_error_iterations: 0,
            operators: OPERATORS,
            inverse_operators: OPERATORS,
            threshold_exponent: THRESHOLD_EXPONENT,
            output_map_degree: OUTPUT_MAP_DEGREE,
            inverse_band_hz: None,
        }
    }
}

/// The `full` pipeline's models and runs.
#[derive(Debug, Clone, Serialize)]
pub struct FullPipeline {
    /// The plant chain (IHC, WIHC).
    pub plant: ChainIdentification,
    /// The inverse chain (DIHC).
    pub inverse: ChainIdentification,
    /// IHC, WIHC and DIHC on the paper's trajectory, in that order.
    pub runs: Vec<TrackingRun>,
    /// Wall-clock time of the two identifications, s.
    pub identification_s: f64,
    /// The creep banks tried: `(longest time constant s, leave-one-hold-out RMS %)`, the
    /// chosen one least (empty when the bank was given).
    pub creep_grid: Vec<(f64, f64)>,
    /// Length of the identification record, s.
    pub record_s: f64,
}

/// Identifies the plant and the inverse chain from the whole record (`command_v`,
/// `measured_um` at `sample_rate_hz`), the vibration link on `vibration` (sample indices).
pub(crate) fn identify_full(
    command_v: &[f64],
    measured_um: &[f64],
    sample_rate_hz: f64,
    decimation: usize,
    vibration: Range<usize>,
    base: &IdentifyOptions,
    options: &FullOptions,
) -> Result<FullIdentification, StudyError> {
    let started = Instant::now();
    let (creep, creep_grid) =
        choose_creep_grid(measured_um, command_v, sample_rate_hz, decimation, options)?;
    let chain = ChainOptions {
        sample_rate_hz,
        decimation,
        creep: Some(creep),
        dynamics: Some(DynamicsOptions {
            segment: Some(vibration),
            ..options.dynamics.clone()
        }),
        output_error_iterations: options.output_error_iterations,
    };
    let error = |model: &str| {
        let model = model.to_owned();
        move |error| StudyError::Identify { model, error }
    };
    let plant_options = IdentifyOptions {
        direction: Direction::Plant,
        thresholds: thresholds(options.operators, options.threshold_exponent)?,
        output_map_degree: options.output_map_degree,
        ..base.clone()
    };
    let plant = identify_chain(command_v, measured_um, &plant_options, &chain)
        .map_err(error("full plant (chain)"))?;
    let inverse_options = IdentifyOptions {
        direction: Direction::Inverse,
        thresholds: thresholds(options.inverse_operators, options.threshold_exponent)?,
        output_map_degree: options.output_map_degree,
        ..base.clone()
    };
    let inverse = identify_inverse_chain(command_v, measured_um, &inverse_options, &chain, &plant)
        .map_err(error("full inverse (chain)"))?;
    Ok(FullIdentification {
        plant,
        inverse,
        seconds: started.elapsed().as_secs_f64(),
        creep_grid,
    })
}

/// `n` thresholds `((i - 1) / n)^p`, `i = 1..n` (uniform, eq. (11), for `p = 1`).
pub(crate) fn thresholds(n: usize, p: f64) -> Result<Thresholds, StudyError> {
    if !(p.is_finite() && (0.25..=4.0).contains(&p)) {
        return Err(StudyError::Option(format!(
            "the full pipeline's threshold exponent is 0.25 to 4, not {p}"
        )));
    }
    Ok(if p == 1.0 {
        Thresholds::Uniform(n)
    } else {
        Thresholds::Given((0..n).map(|i| (i as f64 / n as f64).powf(p)).collect())
    })
}

/// What [`identify_full`] returns.
pub(crate) struct FullIdentification {
    pub plant: ChainIdentification,
    pub inverse: ChainIdentification,
    pub seconds: f64,
    pub creep_grid: Vec<(f64, f64)>,
}

/// The creep link's options: `options.creep` with its bank ending at the candidate of
/// `options.creep_longest_candidates_s` whose weights, fitted on the record's holds with the
/// smoothness chosen, predict each left-out hold best; and every candidate's score.
fn choose_creep_grid(
    measured_um: &[f64],
    command_v: &[f64],
    sample_rate_hz: f64,
    decimation: usize,
    options: &FullOptions,
) -> Result<(CreepOptions, Vec<(f64, f64)>), StudyError> {
    let base = &options.creep;
    let first = base.time_constants_s.first().copied().unwrap_or(0.01);
    if options.creep_longest_candidates_s.is_empty()
        || !base.from_holds
        || base.hold_smoothness_candidates.is_empty()
    {
        return Ok((base.clone(), Vec::new()));
    }
    let error = |error| StudyError::Identify {
        model: "full plant (creep bank)".to_owned(),
        error,
    };
    let holds = hystcomp_identify::creep_holds::held_segments(
        command_v,
        (hystcomp_identify::chain::MIN_HOLD_S * sample_rate_hz).round() as usize,
    );
    let (lo, hi) = measured_um
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    let mut scores = Vec::new();
    let mut best: Option<(f64, CreepOptions)> = None;
    for &last in &options.creep_longest_candidates_s {
        let creep = CreepOptions {
            time_constants_s: CreepOptions::log_spaced(first, last, 2).time_constants_s,
            ..base.clone()
        };
        let fit = hystcomp_identify::creep_holds::creep_weights_from_holds(
            measured_um,
            1.0 / sample_rate_hz,
            decimation,
            &holds,
            &creep.time_constants_s,
            creep.smoothness,
            &creep.hold_smoothness_candidates,
            hi - lo,
        )
        .map_err(error)?;
        let score = fit
            .candidates
            .iter()
            .map(|c| c.1)
            .fold(f64::INFINITY, f64::min);
        scores.push((last, score));
        if best.as_ref().is_none_or(|b| score < b.0) {
            best = Some((score, creep));
        }
    }
    let chosen = best.map_or_else(|| base.clone(), |b| b.1);
    Ok((chosen, scores))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_are_the_papers_for_exponent_one_and_crowd_towards_zero_above_it() {
        assert_eq!(thresholds(10, 1.0).unwrap(), Thresholds::Uniform(10));
        let uniform = Thresholds::Uniform(10).values().unwrap();
        for p in [0.5, 1.5, 2.0, 3.7] {
            let given = thresholds(10, p).unwrap().values().unwrap();
            assert_eq!(given.len(), 10);
            assert_eq!(given[0], 0.0);
            for (g, u) in given.iter().zip(&uniform).skip(1) {
                assert!((g - u.powf(p)).abs() < 1e-15);
                // Above 1 every threshold moves towards zero, below 1 away from it.
                assert_eq!(*g < *u, p > 1.0, "p {p}: {g} against {u}");
            }
        }
        for p in [0.0, 0.2, 4.5, f64::NAN, f64::INFINITY] {
            assert!(thresholds(10, p).is_err(), "{p}");
        }
    }
}
