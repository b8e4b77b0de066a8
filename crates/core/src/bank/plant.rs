//! What IHC and WIHC banks share: a channel's compensator written into its lane, and a block's
//! input polynomials read back for the per-sample solve.

use super::lanes::{Lanes, Mask};
use super::root::{CubicLanes, PolynomialLanes};
use super::storage::{
    BankStorage, Block, Blocks, LOOP_SATURATED, NON_FINITE, PlantRows, SATURATED,
};
use crate::compensator::OutputGuard;
use crate::walk::PlayBank;
use crate::{Buffer, InputPolynomial, MAX_INPUT_DEGREE, Real};

/// Writes the state of one single-channel IHC or WIHC (its play-operator bank, input
/// polynomial, guard relaxation and output guard) into lane `lane` of `blocks`: the bank then
/// continues exactly where the single compensator is.
pub(crate) fn write_lane<T: Real, S: BankStorage<T, W>, B: Buffer<T>, const W: usize>(
    blocks: &mut Blocks<T, S, W>,
    rows: &PlantRows,
    lane: usize,
    bank: &PlayBank<T, B>,
    input: &InputPolynomial<T>,
    relaxation: T,
    guard: &OutputGuard<T>,
) {
    let n = bank.thresholds().len();
    let operator_rows = [
        (rows.thresholds(), bank.thresholds.as_ref()),
        (rows.weights(), bank.weights.as_ref()),
        (rows.prefix(), bank.prefix.as_ref()),
        (rows.inverse_alpha(), bank.inverse_alpha.as_ref()),
        (rows.memory(), bank.memory.as_ref()),
    ];
    for (first, values) in operator_rows {
        for i in 0..rows.n {
            let value = values.get(i).copied().unwrap_or(T::zero());
            blocks.set_value(lane, first + i, value);
        }
    }
    let scalars = [
        (PlantRows::A, bank.a),
        (PlantRows::INVERSE_A, bank.inverse_a),
        (PlantRows::INPUT, bank.input),
        (PlantRows::MEMORY_SUM, bank.memory_sum),
        (PlantRows::RELAXATION, relaxation),
        (PlantRows::LIMIT_MIN, guard.limits.min()),
        (PlantRows::LIMIT_MAX, guard.limits.max()),
        (PlantRows::PREVIOUS, guard.previous),
    ];
    for (which, value) in scalars {
        blocks.set_value(lane, rows.scalar(which), value);
    }
    for j in 0..rows.degree {
        let c = input.coefficients().get(j).copied().unwrap_or(T::zero());
        blocks.set_value(lane, rows.coefficient(j), c);
    }
    // Counts are at most the operator count (bounded by the storage) and the degree (<= 9).
    let counts = [
        (PlantRows::OPERATORS, n),
        (PlantRows::RISING, bank.rising_active),
        (PlantRows::FALLING, bank.falling_active),
        (PlantRows::ALWAYS, bank.always_active),
        (PlantRows::SINCE_SYNC, bank.since_sync as usize),
        (PlantRows::DEGREE, input.degree()),
        (PlantRows::ODD_CUBIC, usize::from(input.is_odd_cubic())),
    ];
    for (row, value) in counts {
        blocks.set_count(lane, row, u32::try_from(value).unwrap_or(u32::MAX));
    }
    write_counters(blocks, lane, guard);
}

/// Writes a guard's counters into lane `lane`.
pub(crate) fn write_counters<T: Real, S: BankStorage<T, W>, const W: usize>(
    blocks: &mut Blocks<T, S, W>,
    lane: usize,
    guard: &OutputGuard<T>,
) {
    let d = guard.diagnostics;
    blocks.set_counter(lane, SATURATED, d.saturated);
    blocks.set_counter(lane, LOOP_SATURATED, d.loop_saturated);
    blocks.set_counter(lane, NON_FINITE, d.non_finite);
}

/// Whether every lane of the block has the paper's odd cubic.
#[inline(always)]
pub(crate) fn all_odd_cubic<T: Real, const W: usize>(block: &Block<'_, T, W>, row: usize) -> bool {
    block.count(row).test(|odd| odd != 0).all()
}

/// The block's cubic coefficients `a1` (row of `c_3`).
#[inline(always)]
pub(crate) fn cubic_lanes<T: Real, const W: usize>(
    block: &Block<'_, T, W>,
    first_coefficient: usize,
) -> CubicLanes<T, W> {
    CubicLanes(block.get(first_coefficient + 2))
}

/// The block's input polynomials: `rows` coefficient rows from `first_coefficient`, each
/// lane's degree and whether it is the odd cubic.
#[inline(always)]
pub(crate) fn polynomial_lanes<T: Real, const W: usize>(
    block: &Block<'_, T, W>,
    first_coefficient: usize,
    rows: usize,
    degree_row: usize,
    odd_row: usize,
) -> PolynomialLanes<T, W> {
    let mut coefficients = [Lanes::zero(); MAX_INPUT_DEGREE];
    for (j, c) in coefficients.iter_mut().enumerate().take(rows) {
        *c = block.get(first_coefficient + j);
    }
    PolynomialLanes {
        coefficients,
        rows,
        degree: block.count(degree_row),
        odd_cubic: Mask(block.count(odd_row).test(|odd| odd != 0).0),
    }
}
