//! A bank of DIHC channels (section 3.3, eq. (10)): [`crate::Dihc`] lane by lane.

use super::channels::{Channels, compensator_bank};
use super::guard::GuardLanes;
use super::lanes::Lanes;
use super::plant::{channel_lanes, with_remainder, write_counters};
use super::play::update_memory_with;
use super::root::LaneRemainder;
use super::run::{BankKernel, BlockKernel, run};
use super::storage::{BankStorage, Block, Blocks, InverseRows, blocks};
use super::{BankError, LANES, check_bank_size, limits_of};
use crate::{Buffer, CoreError, Dihc, Mpim, OutputLimits, Real};

type L<T, const W: usize> = Lanes<T, W>;

/// DIHC for many channels at once: channel `c` is [`crate::Dihc`] built from
/// `inverse_models[c]`, its input range and its limits, and gives the same outputs, bit for
/// bit (see the [module documentation](super)).
#[derive(Debug, Clone)]
pub struct DihcBank<T: Real, S: BankStorage<T, W>, const W: usize = LANES> {
    channels: Channels<T, S, DihcKernel, W>,
}

/// What every block of a DIHC bank shares.
#[derive(Debug, Clone, Copy)]
struct DihcKernel {
    rows: InverseRows,
    uniform: bool,
    cubic: bool,
}

impl<T: Real, S: BankStorage<T, W>, const W: usize> DihcBank<T, S, W> {
    /// A bank of one DIHC per inverse model, each valid on its input range
    /// `input_ranges[c] = (min, max)` (one shared by all, or one per channel), with `limits`
    /// (one pair shared by all, or one per channel). Each channel is checked as
    /// [`crate::Dihc::new`] checks it; a refused one is named by its index.
    pub fn new<B: Buffer<T>>(
        inverse_models: &[Mpim<T, B>],
        input_ranges: &[(T, T)],
        limits: &[OutputLimits<T>],
    ) -> Result<Self, BankError> {
        let channels = inverse_models.len();
        check_bank_size(channels, limits.len(), W)?;
        check_bank_size(channels, input_ranges.len(), W).map_err(|_| {
            BankError::Bank(CoreError::ChannelCount {
                what: "input ranges (one for every channel, or one for each)",
                channels,
                found: input_ranges.len(),
                samples: false,
            })
        })?;
        let n = inverse_models.iter().map(Mpim::len).max().unwrap_or(0);
        let degree = inverse_models
            .iter()
            .map(|p| p.input_polynomial().degree())
            .fold(super::PLAIN_DEGREE, usize::max);
        let rows = InverseRows::new(n, degree);
        let count = blocks(channels, W);
        let mut storage = Blocks::<T, S, W>::new(count, rows.values, InverseRows::COUNTS)
            .map_err(BankError::Bank)?;
        for (channel, model) in inverse_models.iter().enumerate() {
            let (lo, hi) = input_ranges
                .get(channel)
                .or_else(|| input_ranges.first())
                .copied()
                .unwrap_or((T::zero(), T::one()));
            let dihc = Dihc::<T, B>::new(model, lo, hi, limits_of(limits, channel)?)
                .map_err(|error| BankError::Channel { channel, error })?;
            for lane in channel_lanes(channel, channels, count, W) {
                write_dihc_lane(&mut storage, &rows, lane, &dihc);
            }
        }
        let kernel = DihcKernel {
            rows,
            uniform: inverse_models.iter().all(|p| p.len() == n),
            cubic: inverse_models
                .iter()
                .all(|p| p.input_polynomial().is_odd_cubic()),
        };
        Ok(DihcBank {
            channels: Channels {
                blocks: storage,
                kernel,
                count: channels,
            },
        })
    }

    /// The input range `(min, max)` of desired positions `channel` accepts.
    pub fn input_range(&self, channel: usize) -> Option<(T, T)> {
        let rows = &self.channels.kernel.rows;
        let min = self
            .channels
            .value(channel, rows.scalar(InverseRows::INPUT_MIN))?;
        let max = self
            .channels
            .value(channel, rows.scalar(InverseRows::INPUT_MAX))?;
        Some((min, max))
    }
}

/// Writes one single-channel DIHC into lane `lane`.
fn write_dihc_lane<T: Real, S: BankStorage<T, W>, B: Buffer<T>, const W: usize>(
    blocks: &mut Blocks<T, S, W>,
    rows: &InverseRows,
    lane: usize,
    dihc: &Dihc<T, B>,
) {
    let model = &dihc.model;
    let operator_rows = [
        (rows.thresholds(), model.thresholds()),
        (rows.weights(), model.weights()),
        (rows.memory(), model.memory()),
    ];
    for (first, values) in operator_rows {
        for i in 0..rows.n {
            let value = values.get(i).copied().unwrap_or(T::zero());
            blocks.set_value(lane, first + i, value);
        }
    }
    let scalars = [
        (InverseRows::INPUT_MIN, dihc.input_min),
        (InverseRows::INPUT_MAX, dihc.input_max),
        (InverseRows::LIMIT_MIN, dihc.guard.limits.min()),
        (InverseRows::LIMIT_MAX, dihc.guard.limits.max()),
        (InverseRows::PREVIOUS, dihc.guard.previous),
    ];
    for (which, value) in scalars {
        blocks.set_value(lane, rows.scalar(which), value);
    }
    let input = model.input_polynomial();
    for j in 0..rows.degree {
        let c = input.coefficients().get(j).copied().unwrap_or(T::zero());
        blocks.set_value(lane, rows.coefficient(j), c);
    }
    let counts = [
        (InverseRows::OPERATORS, model.len()),
        (InverseRows::DEGREE, input.degree()),
        (InverseRows::ODD_CUBIC, usize::from(input.is_odd_cubic())),
    ];
    for (row, value) in counts {
        blocks.set_count(lane, row, u32::try_from(value).unwrap_or(u32::MAX));
    }
    write_counters(blocks, lane, &dihc.guard);
}

compensator_bank!(DihcBank);

impl DihcKernel {
    fn guard<T: Real, const W: usize>(&self, block: &Block<'_, T, W>) -> GuardLanes<T, W> {
        let rows = &self.rows;
        GuardLanes::load(
            block,
            rows.scalar(InverseRows::LIMIT_MIN),
            rows.scalar(InverseRows::LIMIT_MAX),
            rows.scalar(InverseRows::PREVIOUS),
        )
    }

    /// One sample of every lane (`Dihc::step`): the desired position clamped into the input
    /// range, eq. (10), the output guard.
    #[inline(always)]
    fn step_with<T: Real, R: LaneRemainder<T, W>, const W: usize>(
        &self,
        block: &mut Block<'_, T, W>,
        desired: L<T, W>,
        remainder: R,
    ) -> L<T, W> {
        let rows = &self.rows;
        let mut guard = self.guard(block);
        let active = guard.accept(desired);
        let input_min = block.get(rows.scalar(InverseRows::INPUT_MIN));
        let input_max = block.get(rows.scalar(InverseRows::INPUT_MAX));
        let x = desired.max(input_min).min(input_max);
        // Mpim::step: g(x) + sum b_i F_{r_i}[x].
        let g = remainder.input_function(x, block.get(rows.coefficient(0)));
        let fed = update_memory_with::<_, _, false, true>(
            block,
            rows.operators(),
            block.count(InverseRows::OPERATORS),
            x,
            active,
            self.uniform,
        );
        let v = g + fed.sum;
        let out = guard.emit(v, x.compare(desired, |a, b| a != b), active);
        guard.store(block, rows.scalar(InverseRows::PREVIOUS));
        out
    }
}

impl<T: Real, const W: usize> BlockKernel<T, W> for DihcKernel {
    const HEAD: usize = InverseRows::HEAD;
    const COUNTS: usize = InverseRows::COUNTS;

    #[inline(always)]
    fn step(&self, block: &mut Block<'_, T, W>, desired: L<T, W>) -> L<T, W> {
        with_remainder!(self, block, InverseRows, |remainder| self
            .step_with(block, desired, remainder))
    }
}

impl<T: Real, const W: usize> BankKernel<T, W> for DihcKernel {
    /// `Dihc::reset` for every lane of a block.
    fn reset_block(&self, block: &mut Block<'_, T, W>) {
        let mut guard = self.guard(block);
        for i in 0..self.rows.n {
            block.set(self.rows.memory() + i, Lanes::zero());
        }
        guard.reset();
        guard.store(block, self.rows.scalar(InverseRows::PREVIOUS));
    }

    fn limit_rows(&self) -> (usize, usize) {
        self.rows.limits()
    }

    fn run_tick<'a>(
        &self,
        blocks: impl Iterator<Item = Block<'a, T, W>>,
        desired: &[T],
        control: &mut [T],
    ) where
        T: 'a,
    {
        run(self, blocks, desired, control)
    }
}
