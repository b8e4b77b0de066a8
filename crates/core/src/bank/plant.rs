//! What IHC and WIHC banks share: a channel's compensator written into its lane, and a block's
//! input polynomials read back for the per-sample solve.

use super::channels::Channels;
use super::guard::GuardLanes;
use super::lanes::Lanes;
use super::root::{CubicLanes, PolynomialLanes};
use super::storage::{
    BankStorage, Block, Blocks, LOOP_SATURATED, NON_FINITE, PlantRows, SATURATED, blocks,
};
use super::{BankError, check_bank_size, limits_of};
use crate::compensator::OutputGuard;
use crate::walk::PlayBank;
use crate::{
    Buffer, CoreError, InputPolynomial, MAX_INPUT_DEGREE, Mpim, OutputLimits, Real, SolveMode,
};
use core::marker::PhantomData;
use core::ops::Range;

/// What every block of an IHC or WIHC bank shares; `M` names the method
/// ([`super::ihc::IhcMethod`], [`super::wihc::WihcMethod`]), whose kernel steps the blocks.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlantKernel<M> {
    pub rows: PlantRows,
    pub mode: SolveMode,
    /// Every channel has `rows.n` operators.
    pub uniform: bool,
    /// Every channel has the paper's odd cubic.
    pub cubic: bool,
    method: PhantomData<M>,
}

impl<M> PlantKernel<M> {
    /// The output guard of a block's lanes: their limits and previous output.
    #[inline(always)]
    pub(crate) fn guard<T: Real, const W: usize>(
        &self,
        block: &Block<'_, T, W>,
    ) -> GuardLanes<T, W> {
        let rows = &self.rows;
        GuardLanes::load(
            block,
            rows.scalar(PlantRows::LIMIT_MIN),
            rows.scalar(PlantRows::LIMIT_MAX),
            rows.scalar(PlantRows::PREVIOUS),
        )
    }
}

impl<T: Real, S: BankStorage<T, W>, M, const W: usize> Channels<T, S, PlantKernel<M>, W> {
    /// The solve mode of every channel.
    pub fn mode(&self) -> SolveMode {
        self.kernel.mode
    }

    /// The guard's under-relaxation `mu` of `channel` (`None` beyond the last channel).
    pub fn relaxation(&self, channel: usize) -> Option<T> {
        self.value(channel, self.kernel.rows.scalar(PlantRows::RELAXATION))
    }
}

/// The lanes channel `channel` of `channels` fills in `count` blocks of `W` lanes: its own,
/// and for the last channel also the padding lanes after it (they are fed NaN: held).
pub(crate) fn channel_lanes(
    channel: usize,
    channels: usize,
    count: usize,
    lanes: usize,
) -> Range<usize> {
    if channel + 1 == channels {
        channel..count * lanes
    } else {
        channel..channel + 1
    }
}

/// The channels of an IHC or WIHC bank: channel `c` is the single compensator
/// `build` makes from `plants[c]` with its limits and `mode` (a refused one named by its
/// index), written into its lanes by `write`.
pub(crate) fn plant_bank<T, S, B, C, M, const W: usize>(
    plants: &[Mpim<T, B>],
    limits: &[OutputLimits<T>],
    mode: SolveMode,
    build: impl Fn(&Mpim<T, B>, OutputLimits<T>, SolveMode) -> Result<C, CoreError>,
    write: impl Fn(&mut Blocks<T, S, W>, &PlantRows, usize, &C),
) -> Result<Channels<T, S, PlantKernel<M>, W>, BankError>
where
    T: Real,
    S: BankStorage<T, W>,
    B: Buffer<T>,
{
    check_bank_size(plants.len(), limits.len(), W)?;
    let n = plants.iter().map(Mpim::len).max().unwrap_or(0);
    let degree = plants
        .iter()
        .map(|p| p.input_polynomial().degree())
        .fold(super::PLAIN_DEGREE, usize::max);
    let rows = PlantRows::new(n, degree);
    let count = blocks(plants.len(), W);
    let mut storage =
        Blocks::<T, S, W>::new(count, rows.values, PlantRows::COUNTS).map_err(BankError::Bank)?;
    for (channel, plant) in plants.iter().enumerate() {
        let compensator = build(plant, limits_of(limits, channel)?, mode)
            .map_err(|error| BankError::Channel { channel, error })?;
        for lane in channel_lanes(channel, plants.len(), count, W) {
            write(&mut storage, &rows, lane, &compensator);
        }
    }
    let kernel = PlantKernel {
        rows,
        mode,
        uniform: plants.iter().all(|p| p.len() == n),
        cubic: plants.iter().all(|p| p.input_polynomial().is_odd_cubic()),
        method: PhantomData,
    };
    Ok(Channels {
        blocks: storage,
        kernel,
        count: plants.len(),
    })
}

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
        (PlantRows::LEAST_INVERSE_ALPHA, bank.least_inverse_alpha()),
        (PlantRows::SLOPE_SUM, bank.slope_sum()),
        (PlantRows::REACH_SUM, bank.reach_sum()),
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

/// `$step` with `$remainder` bound to the block's remainder `h`: the paper's cubic when the
/// kernel's channels all have it (`$kernel.cubic`) or this block's lanes do, else each lane's
/// own polynomial (`$rows`: the kernel's row layout, for its degree and odd-cubic count rows).
/// Each branch compiles `$step` for its own remainder type.
macro_rules! with_remainder {
    ($kernel:expr, $block:ident, $rows:ty, |$remainder:ident| $step:expr) => {{
        let first = $kernel.rows.coefficient(0);
        if $kernel.cubic || super::plant::all_odd_cubic($block, <$rows>::ODD_CUBIC) {
            let $remainder = super::plant::cubic_lanes($block, first);
            $step
        } else {
            let $remainder = super::plant::polynomial_lanes(
                $block,
                first,
                $kernel.rows.degree,
                <$rows>::DEGREE,
                <$rows>::ODD_CUBIC,
            );
            $step
        }
    }};
}
pub(crate) use with_remainder;

/// Whether every lane of the block has the paper's odd cubic.
#[inline(always)]
pub(crate) fn all_odd_cubic<T: Real, const W: usize>(block: &Block<'_, T, W>, row: usize) -> bool {
    block.count(row).test::<T>(|odd| odd != 0).all()
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
        odd_cubic: block.count(odd_row).test(|odd| odd != 0),
    }
}

/// The under-relaxed target of the guarded delayed loops (`crate::ihc::ihc_step`,
/// `crate::wihc::wihc_step`) in every lane: `previous - mu f_prev`, or with `mu = 1`,
/// `desired - h_prev` (the single compensators' arithmetic, so the same bits). `previous` is
/// IHC's `w(t - Ts)` or WIHC's `P1(t - Ts)`, `f_prev = previous + h_prev - desired`.
#[inline(always)]
pub(crate) fn guarded_target<T: Real, const W: usize>(
    block: &Block<'_, T, W>,
    rows: &PlantRows,
    previous: Lanes<T, W>,
    f_prev: Lanes<T, W>,
    desired: Lanes<T, W>,
    h_prev: Lanes<T, W>,
) -> Lanes<T, W> {
    let relaxation = block.get(rows.scalar(PlantRows::RELAXATION));
    let relaxed = relaxation.lt(Lanes::splat(T::one()));
    (previous - relaxation * f_prev).or_keep(relaxed, desired - h_prev)
}
