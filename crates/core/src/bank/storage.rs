//! Where a bank keeps its channels: blocks of `W` lanes, each block a run of rows (one value per
//! lane), on the heap or in fixed arrays.

use super::lanes::Lanes;
use crate::buffer::filled;
use crate::{Bounded, Buffer, CoreError, Real};

/// The storage of a bank: rows of `W` values (`[T; W]`), of operator counts (`[u32; W]`) and of
/// diagnostic counters (`[u64; W]`).
///
/// [`Heap`] (feature `alloc`) holds any number of channels; [`Fixed`] holds a number known at
/// compile time without an allocator (see [`plant_bank_rows`] and [`dihc_bank_rows`] for the
/// sizes).
pub trait BankStorage<T: Real, const W: usize> {
    /// Rows of sample values.
    type Values: Buffer<[T; W]> + core::fmt::Debug;
    /// Rows of counts (operators, moving operators, degrees).
    type Counts: Buffer<[u32; W]> + core::fmt::Debug;
    /// Rows of diagnostic counters.
    type Counters: Buffer<[u64; W]> + core::fmt::Debug;
}

/// Heap storage (`Vec`s), for any number of channels.
#[cfg(feature = "alloc")]
#[derive(Debug, Clone, Copy, Default)]
pub struct Heap;

#[cfg(feature = "alloc")]
impl<T: Real, const W: usize> BankStorage<T, W> for Heap {
    type Values = alloc::vec::Vec<[T; W]>;
    type Counts = alloc::vec::Vec<[u32; W]>;
    type Counters = alloc::vec::Vec<[u64; W]>;
}

/// Fixed storage without an allocator: up to `VALUES` rows of values, `COUNTS` rows of counts
/// and `COUNTERS` rows of counters (each row `W` lanes). [`plant_bank_rows`] and
/// [`dihc_bank_rows`] compute them for a number of channels and operators:
///
/// ```
/// use hystcomp_core::{Fixed, IhcBank, PLAIN_DEGREE, plant_bank_rows};
///
/// // Six axes, ten operators each, the paper's cubic, two lanes per block.
/// const ROWS: [usize; 3] = plant_bank_rows(6, 10, PLAIN_DEGREE, 2);
/// type SixAxes = IhcBank<f32, Fixed<{ ROWS[0] }, { ROWS[1] }, { ROWS[2] }>, 2>;
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct Fixed<const VALUES: usize, const COUNTS: usize, const COUNTERS: usize>;

impl<T: Real, const W: usize, const VALUES: usize, const COUNTS: usize, const COUNTERS: usize>
    BankStorage<T, W> for Fixed<VALUES, COUNTS, COUNTERS>
{
    type Values = Bounded<[T; W], VALUES>;
    type Counts = Bounded<[u32; W], COUNTS>;
    type Counters = Bounded<[u64; W], COUNTERS>;
}

/// The number of coefficient rows a bank of models with the paper's cubic input function
/// stores (`c_1, c_2, c_3`).
pub const PLAIN_DEGREE: usize = 3;

/// The rows `[values, counts, counters]` an IHC or WIHC bank of `channels` channels needs, in
/// blocks of `lanes`, for models of at most `operators` play operators and input polynomials of
/// at most `degree` coefficients ([`PLAIN_DEGREE`] for the paper's cubic): the sizes of
/// [`Fixed`].
pub const fn plant_bank_rows(
    channels: usize,
    operators: usize,
    degree: usize,
    lanes: usize,
) -> [usize; 3] {
    let blocks = blocks(channels, lanes);
    let rows = PlantRows::new(operators, degree);
    [
        blocks * rows.values,
        blocks * PlantRows::COUNTS,
        blocks * COUNTERS,
    ]
}

/// The rows `[values, counts, counters]` a DIHC bank needs (see [`plant_bank_rows`]).
pub const fn dihc_bank_rows(
    channels: usize,
    operators: usize,
    degree: usize,
    lanes: usize,
) -> [usize; 3] {
    let blocks = blocks(channels, lanes);
    let rows = InverseRows::new(operators, degree);
    [
        blocks * rows.values,
        blocks * InverseRows::COUNTS,
        blocks * COUNTERS,
    ]
}

/// Blocks of `lanes` channels needed for `channels`.
pub(crate) const fn blocks(channels: usize, lanes: usize) -> usize {
    if lanes == 0 {
        0
    } else {
        channels.div_ceil(lanes)
    }
}

/// `rows`, or one more when it is a multiple of 32: a block of 32 or 64 rows of eight lanes
/// is 1, 2 or 4 KB, so the same row of neighbouring blocks lies a multiple of 4 KB apart, and
/// a processor that tells a load from an earlier store by the address's low 12 bits alone
/// (4K aliasing) makes the next block's reads wait on this block's writes. Measured with the
/// probe on an AVX-512 machine, 4 096 channels of 10 operators (64 rows of an IHC bank
/// against 65), f32 ns per channel-step: exact IHC 14.4-14.6 -> 14.0-14.1, delayed IHC
/// 4.0-4.3 -> 3.9.
pub(crate) const fn unaliased(rows: usize) -> usize {
    if rows.is_multiple_of(32) {
        rows + 1
    } else {
        rows
    }
}

/// Diagnostic counter rows of every block: saturated, loop-saturated, non-finite.
pub(crate) const COUNTERS: usize = 3;
pub(crate) const SATURATED: usize = 0;
pub(crate) const LOOP_SATURATED: usize = 1;
pub(crate) const NON_FINITE: usize = 2;

/// Where a block's play operators are: the first rows of their thresholds, weights and memory,
/// and how many operator rows each table has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct OperatorTables {
    pub thresholds: usize,
    pub weights: usize,
    pub memory: usize,
    pub n: usize,
}

/// The rows of one block of an IHC or WIHC bank: the lanes' play-operator bank (the inverse
/// PI part of eq. (7) for IHC, the plant's PI part for WIHC) with its tables and state, the
/// output guard and the input polynomial.
///
/// The scalar rows come first and then the coefficients, at offsets known when the code is
/// compiled (so that a kernel's reads of them need no bounds check after one check of the
/// block's length against [`PlantRows::HEAD`]), then the operator tables, `n` rows each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PlantRows {
    /// Operator rows (the largest operator count among the channels).
    pub n: usize,
    /// Coefficient rows of the input polynomials (at least [`PLAIN_DEGREE`]).
    pub degree: usize,
    /// Value rows per block.
    pub values: usize,
}

impl PlantRows {
    pub const fn new(n: usize, degree: usize) -> Self {
        PlantRows {
            n,
            degree,
            values: unaliased(5 * n + Self::SCALARS + degree),
        }
    }
    /// The first row of the operator tables.
    const fn tables(&self) -> usize {
        Self::SCALARS + self.degree
    }
    pub const fn thresholds(&self) -> usize {
        self.tables()
    }
    pub const fn weights(&self) -> usize {
        self.tables() + self.n
    }
    /// `b_1 + ... + b_{k+1}`.
    pub const fn prefix(&self) -> usize {
        self.tables() + 2 * self.n
    }
    /// `1 / (a + b_1 + ... + b_{k+1})`.
    pub const fn inverse_alpha(&self) -> usize {
        self.tables() + 3 * self.n
    }
    pub const fn memory(&self) -> usize {
        self.tables() + 4 * self.n
    }
    /// The operators' thresholds, weights and memory.
    pub const fn operators(&self) -> OperatorTables {
        OperatorTables {
            thresholds: self.thresholds(),
            weights: self.weights(),
            memory: self.memory(),
            n: self.n,
        }
    }
    pub const fn scalar(&self, which: usize) -> usize {
        which
    }
    /// The rows of the output limits `(min, max)`.
    pub const fn limits(&self) -> (usize, usize) {
        (self.scalar(Self::LIMIT_MIN), self.scalar(Self::LIMIT_MAX))
    }
    /// Row of `c_{j + 1}`.
    pub const fn coefficient(&self, j: usize) -> usize {
        Self::SCALARS + j
    }
    pub const A: usize = 0;
    pub const INVERSE_A: usize = 1;
    pub const INPUT: usize = 2;
    pub const MEMORY_SUM: usize = 3;
    pub const RELAXATION: usize = 4;
    pub const LIMIT_MIN: usize = 5;
    pub const LIMIT_MAX: usize = 6;
    pub const PREVIOUS: usize = 7;
    /// `crate::walk::PlayBank::least_inverse_alpha` (the guarded IHC's reach bound).
    pub const LEAST_INVERSE_ALPHA: usize = 8;
    /// `|a| + sum |b_i|` and `sum |b_i r_i|` of the lane's play-operator bank: the scale of
    /// the rounding in the plain delayed IHC's proof that a sample stays within its limits
    /// (`super::within`).
    pub const SLOPE_SUM: usize = 9;
    pub const REACH_SUM: usize = 10;
    const SCALARS: usize = 11;
    /// The rows every block holds before its operator tables: the scalars and the paper's
    /// three coefficients.
    pub const HEAD: usize = Self::SCALARS + PLAIN_DEGREE;

    pub const COUNTS: usize = 7;
    pub const OPERATORS: usize = 0;
    pub const RISING: usize = 1;
    pub const FALLING: usize = 2;
    pub const ALWAYS: usize = 3;
    pub const SINCE_SYNC: usize = 4;
    pub const DEGREE: usize = 5;
    pub const ODD_CUBIC: usize = 6;
}

/// The rows of one block of a DIHC bank: the inverse model (eq. (10)), its input range, the
/// output guard and the input polynomial; scalars and coefficients first, as
/// [`PlantRows`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct InverseRows {
    pub n: usize,
    pub degree: usize,
    pub values: usize,
}

impl InverseRows {
    pub const fn new(n: usize, degree: usize) -> Self {
        InverseRows {
            n,
            degree,
            values: unaliased(3 * n + Self::SCALARS + degree),
        }
    }
    const fn tables(&self) -> usize {
        Self::SCALARS + self.degree
    }
    pub const fn thresholds(&self) -> usize {
        self.tables()
    }
    pub const fn weights(&self) -> usize {
        self.tables() + self.n
    }
    pub const fn memory(&self) -> usize {
        self.tables() + 2 * self.n
    }
    /// The operators' thresholds, weights and memory.
    pub const fn operators(&self) -> OperatorTables {
        OperatorTables {
            thresholds: self.thresholds(),
            weights: self.weights(),
            memory: self.memory(),
            n: self.n,
        }
    }
    pub const fn scalar(&self, which: usize) -> usize {
        which
    }
    /// The rows of the output limits `(min, max)`.
    pub const fn limits(&self) -> (usize, usize) {
        (self.scalar(Self::LIMIT_MIN), self.scalar(Self::LIMIT_MAX))
    }
    pub const fn coefficient(&self, j: usize) -> usize {
        Self::SCALARS + j
    }
    pub const INPUT_MIN: usize = 0;
    pub const INPUT_MAX: usize = 1;
    pub const LIMIT_MIN: usize = 2;
    pub const LIMIT_MAX: usize = 3;
    pub const PREVIOUS: usize = 4;
    const SCALARS: usize = 5;
    /// The rows every block holds before its operator tables (see [`PlantRows::HEAD`]).
    pub const HEAD: usize = Self::SCALARS + PLAIN_DEGREE;

    pub const COUNTS: usize = 3;
    pub const OPERATORS: usize = 0;
    pub const DEGREE: usize = 1;
    pub const ODD_CUBIC: usize = 2;
}

/// The whole storage of a bank, with the number of rows per block of each kind.
#[derive(Debug, Clone)]
pub(crate) struct Blocks<T: Real, S: BankStorage<T, W>, const W: usize> {
    pub values: S::Values,
    pub counts: S::Counts,
    pub counters: S::Counters,
    pub value_rows: usize,
    pub count_rows: usize,
}

impl<T: Real, S: BankStorage<T, W>, const W: usize> Blocks<T, S, W> {
    /// Zeroed storage for `blocks` blocks, at most [`super::MAX_BANK_VALUES`] values (checked
    /// before allocating).
    pub fn new(blocks: usize, value_rows: usize, count_rows: usize) -> Result<Self, CoreError> {
        let values = blocks
            .checked_mul(value_rows)
            .and_then(|rows| rows.checked_mul(W))
            .unwrap_or(usize::MAX);
        if values > super::MAX_BANK_VALUES {
            return Err(CoreError::TooLarge {
                what: "values of bank storage (every channel, padded to a whole block of lanes, \
                       takes the rows of the bank's largest model; split channels of very \
                       different operator counts into banks by size)",
                found: values,
                max: super::MAX_BANK_VALUES,
            });
        }
        Ok(Blocks {
            values: filled([T::zero(); W], blocks * value_rows)?,
            counts: filled([0; W], blocks * count_rows)?,
            counters: filled([0; W], blocks * COUNTERS)?,
            value_rows,
            count_rows,
        })
    }

    /// Every block, in channel order.
    #[inline(always)]
    pub fn blocks_mut(&mut self) -> impl Iterator<Item = Block<'_, T, W>> {
        let (v, c) = (self.value_rows.max(1), self.count_rows.max(1));
        let mut values = self.values.as_mut();
        let mut counts = self.counts.as_mut();
        let mut counters = self.counters.as_mut();
        // Split off one block's rows at a time (as a zip of `chunks_exact_mut` would, stopping
        // at the first array that runs short), without the division by the chunk length that
        // such a zip makes when it is built: a compiler optimising for size may outline that
        // constructor, and the division's panic path with it (the thumbv7em image with three
        // banks did).
        core::iter::from_fn(move || {
            let (block_values, rest_values) =
                core::mem::take(&mut values).split_at_mut_checked(v)?;
            let (block_counts, rest_counts) =
                core::mem::take(&mut counts).split_at_mut_checked(c)?;
            let (block_counters, rest_counters) =
                core::mem::take(&mut counters).split_at_mut_checked(COUNTERS)?;
            (values, counts, counters) = (rest_values, rest_counts, rest_counters);
            Some(Block {
                values: block_values,
                counts: block_counts,
                counters: block_counters,
                hardware_gather: false,
            })
        })
    }

    /// The value in `row` of `channel`'s lane (0 when out of range).
    pub fn value(&self, channel: usize, row: usize) -> T {
        let at = (channel / W) * self.value_rows + row;
        self.values
            .as_ref()
            .get(at)
            .map_or(T::zero(), |r| r[channel % W])
    }

    /// The counter in `row` of `channel`'s lane.
    pub fn counter(&self, channel: usize, row: usize) -> u64 {
        let at = (channel / W) * COUNTERS + row;
        self.counters.as_ref().get(at).map_or(0, |r| r[channel % W])
    }

    /// Sets the value in `row` of `channel`'s lane.
    pub fn set_value(&mut self, channel: usize, row: usize, value: T) {
        let at = (channel / W) * self.value_rows + row;
        if let Some(r) = self.values.as_mut().get_mut(at) {
            r[channel % W] = value;
        }
    }

    /// Sets the counter in `row` of `channel`'s lane.
    pub fn set_counter(&mut self, channel: usize, row: usize, value: u64) {
        let at = (channel / W) * COUNTERS + row;
        if let Some(r) = self.counters.as_mut().get_mut(at) {
            r[channel % W] = value;
        }
    }

    /// Sets the count in `row` of `channel`'s lane.
    pub fn set_count(&mut self, channel: usize, row: usize, value: u32) {
        let at = (channel / W) * self.count_rows + row;
        if let Some(r) = self.counts.as_mut().get_mut(at) {
            r[channel % W] = value;
        }
    }
}

/// One block of a bank: its rows of values, counts and counters.
pub(crate) struct Block<'a, T, const W: usize> {
    pub values: &'a mut [[T; W]],
    pub counts: &'a mut [[u32; W]],
    pub counters: &'a mut [[u64; W]],
    /// Whether the code stepping the block is compiled with AVX2 (set by `super::run`, a
    /// constant on each of its paths): then [`gather`] reads each lane's row with the
    /// processor's gather instruction, or by selection from a single small table, instead of
    /// lane by lane.
    pub hardware_gather: bool,
}

impl<T: Real, const W: usize> Block<'_, T, W> {
    /// Whether the block holds `head` rows of values and the count rows up to `counts`: a
    /// bank's loop checks it once per block (`super::run`), so that the compiler drops the
    /// bounds checks of the step's reads of the rows at fixed offsets before them (the layouts
    /// always hold them).
    #[inline(always)]
    pub fn holds(&self, head: usize, counts: usize) -> bool {
        self.values.len() >= head && self.counts.len() >= counts && self.counters.len() >= COUNTERS
    }

    /// Row `row` of values (zeros when out of range, which the layout never asks for).
    #[inline(always)]
    pub fn get(&self, row: usize) -> Lanes<T, W> {
        Lanes(self.values.get(row).copied().unwrap_or([T::zero(); W]))
    }

    #[inline(always)]
    pub fn set(&mut self, row: usize, value: Lanes<T, W>) {
        if let Some(r) = self.values.get_mut(row) {
            *r = value.0;
        }
    }

    #[inline(always)]
    pub fn count(&self, row: usize) -> Lanes<u32, W> {
        Lanes(self.counts.get(row).copied().unwrap_or([0; W]))
    }

    #[inline(always)]
    pub fn set_count(&mut self, row: usize, value: Lanes<u32, W>) {
        if let Some(r) = self.counts.get_mut(row) {
            *r = value.0;
        }
    }

    #[inline(always)]
    pub fn counter(&self, row: usize) -> Lanes<u64, W> {
        Lanes(self.counters.get(row).copied().unwrap_or([0; W]))
    }

    #[inline(always)]
    pub fn set_counter(&mut self, row: usize, value: Lanes<u64, W>) {
        if let Some(r) = self.counters.get_mut(row) {
            *r = value.0;
        }
    }

    /// The `count` rows from `base`: a table of one row per operator (empty if the block ends
    /// before it, which the layout never asks for).
    #[inline(always)]
    pub fn table(&self, base: usize, count: usize) -> &[[T; W]] {
        base.checked_add(count)
            .and_then(|end| self.values.get(base..end))
            .unwrap_or(&[])
    }
}

/// Lane `l` of row `index[l]` of each of `tables` (tables of equal length, from
/// [`Block::table`]): each lane reads its own operator, the same row of every table, and
/// computes where once for all of them. An index beyond the tables (which only lanes whose
/// result is discarded ask for) reads their last row: the index is clamped to the tables'
/// common length.
///
/// With `hardware` (code compiled for AVX2, see [`Block::hardware_gather`]), one table of at
/// most [`SELECT_ROWS`] rows is read by [`select_rows`], and otherwise, with eight lanes of
/// `f32` or `f64`, each table with one gather instruction (`vgatherdps`, two `vgatherdpd`).
/// Everything else is read lane by lane (an extract, a load and an insert per lane and
/// table). All three read the same values.
#[inline(always)]
pub(crate) fn gather<T: Real, const W: usize, const K: usize>(
    tables: [&[[T; W]]; K],
    index: Lanes<u32, W>,
    hardware: bool,
) -> [Lanes<T, W>; K] {
    let n = tables.iter().map(|t| t.len()).min().unwrap_or(0);
    let Some(last) = n.checked_sub(1) else {
        return [Lanes::zero(); K];
    };
    // Each sliced to the common length `n` (`get`, not an index, so that the step keeps no
    // path to a panic, as on a Cortex-M build; a table is never shorter), leaving the reads
    // below only tables of length `n`, so that the compiler drops the check of each lane's
    // read (`k <= last < n`).
    let mut sliced: [&[[T; W]]; K] = [&[]; K];
    for (s, t) in sliced.iter_mut().zip(tables) {
        let Some(t) = t.get(..n) else {
            return [Lanes::zero(); K];
        };
        *s = t;
    }
    if hardware && K == 1 && n <= SELECT_ROWS {
        return select_rows(sliced, index, last);
    }
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if hardware && let Some(out) = x86::gather(sliced, index, last) {
        return out;
    }
    #[cfg(not(all(feature = "std", target_arch = "x86_64")))]
    let _ = hardware;
    lane_by_lane(sliced, index, last)
}

/// On the paths with gather instructions, a single table of at most this many rows is read
/// by [`select_rows`]. Measured with the bank probe on Zen 4 (AVX-512) at 10 operators, 4 096
/// channels (figures in the README, Many channels): the walk's two single-table reads
/// (`prefix`, `inverse_alpha`) by selection instead of `vgatherdps` took the exact IHC from
/// about 16 to 14 ns per channel-step in f32 and from about 26 to 24.5 in f64. The walk's
/// three tables at once stay gathered: selected too, f32 was no faster and f64 slower (exact
/// WIHC 24.5 to 32 ns). The paths without gather instructions (SSE2, other processors, the
/// microcontroller) keep reading lane by lane: there selection, a compare and a select per
/// row, would be unmeasured extra work.
const SELECT_ROWS: usize = 16;

/// [`gather`] by passing over every row of the tables and keeping, in each lane, the row its
/// index names (clamped to `last`): a compare and a masked load per row and table, no gather
/// instruction (whose latency the walk would wait on).
#[inline(always)]
fn select_rows<T: Real, const W: usize, const K: usize>(
    tables: [&[[T; W]]; K],
    index: Lanes<u32, W>,
    last: usize,
) -> [Lanes<T, W>; K] {
    let last = u32::try_from(last).unwrap_or(u32::MAX);
    let index = index.map(|k| k.min(last));
    let mut out = [Lanes::zero(); K];
    for (o, t) in out.iter_mut().zip(&tables) {
        for (k, row) in t.iter().enumerate() {
            let k = k as u32;
            *o = Lanes(*row).or_keep(index.test::<T>(|i| i == k), *o);
        }
    }
    out
}

/// [`gather`] lane by lane, from tables of at least `last + 1` rows.
// Indexed by the lane, the form the compiler vectorises (as in `super::lanes`).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn lane_by_lane<T: Real, const W: usize, const K: usize>(
    tables: [&[[T; W]]; K],
    index: Lanes<u32, W>,
    last: usize,
) -> [Lanes<T, W>; K] {
    let mut out = [[T::zero(); W]; K];
    for l in 0..W {
        let k = (index.0[l] as usize).min(last);
        for (o, t) in out.iter_mut().zip(&tables) {
            o[l] = t.get(k).map_or(T::zero(), |row| row[l]);
        }
    }
    out.map(Lanes)
}

/// The gather instructions of AVX2, for blocks of eight `f32` or `f64` lanes.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
mod x86 {
    use core::any::TypeId;
    use core::arch::x86_64::{
        __m256i, _mm256_add_epi32, _mm256_castsi256_si128, _mm256_extracti128_si256,
        _mm256_i32gather_pd, _mm256_i32gather_ps, _mm256_loadu_si256, _mm256_min_epu32,
        _mm256_set1_epi32, _mm256_setr_epi32, _mm256_slli_epi32, _mm256_storeu_pd,
        _mm256_storeu_ps,
    };

    use super::Lanes;
    use crate::Real;

    /// [`super::gather`] of eight `f32` or `f64` lanes with AVX2's gathers; `None` for other
    /// lane counts and types. Every table holds `last + 1` rows or more.
    ///
    /// Only code compiled with AVX2 may call it (the banks' AVX2 and AVX-512 paths), where the
    /// gathers are inlined.
    #[inline(always)]
    pub(super) fn gather<T: Real, const W: usize, const K: usize>(
        tables: [&[[T; W]]; K],
        index: Lanes<u32, W>,
        last: usize,
    ) -> Option<[Lanes<T, W>; K]> {
        if W != 8 || tables.iter().any(|t| t.len() <= last) {
            return None;
        }
        // Offsets in elements of the tables' rows of eight: within i32 for any table a bank
        // holds (a few thousand operators at most).
        let last = i32::try_from(last).ok().filter(|l| *l < i32::MAX / 16)?;
        let index: [u32; 8] = core::array::from_fn(|l| index.0.get(l).copied().unwrap_or(0));
        if TypeId::of::<T>() == TypeId::of::<f32>() {
            let tables = tables.map(|t| {
                // SAFETY: `T` is `f32` and `W` is 8: `[T; W]` is `[f32; 8]`, same layout.
                unsafe { core::slice::from_raw_parts(t.as_ptr().cast::<[f32; 8]>(), t.len()) }
            });
            // SAFETY: the callers run with AVX2 (see above); every offset is below
            // `8 (last + 1) <= 8 len` of each table.
            let out = unsafe { gather_f32(tables, index, last) };
            // SAFETY: `[[f32; 8]; K]` is `[Lanes<T, W>; K]` for `T = f32`, `W = 8`.
            return Some(unsafe { core::mem::transmute_copy(&out) });
        }
        if TypeId::of::<T>() == TypeId::of::<f64>() {
            let tables = tables.map(|t| {
                // SAFETY: `T` is `f64` and `W` is 8.
                unsafe { core::slice::from_raw_parts(t.as_ptr().cast::<[f64; 8]>(), t.len()) }
            });
            // SAFETY: as above.
            let out = unsafe { gather_f64(tables, index, last) };
            // SAFETY: `[[f64; 8]; K]` is `[Lanes<T, W>; K]` for `T = f64`, `W = 8`.
            return Some(unsafe { core::mem::transmute_copy(&out) });
        }
        None
    }

    /// The offset of lane `l`'s element of row `min(index[l], last)` in a table of rows of
    /// eight: `8 min(index[l], last) + l`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn offsets(index: [u32; 8], last: i32) -> __m256i {
        // SAFETY: `index` holds eight `u32`, 32 bytes (an unaligned load).
        let k = unsafe { _mm256_loadu_si256(index.as_ptr().cast()) };
        let k = _mm256_min_epu32(k, _mm256_set1_epi32(last));
        _mm256_add_epi32(
            _mm256_slli_epi32::<3>(k),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        )
    }

    /// # Safety
    /// The processor has AVX2; every table holds `last + 1` rows or more.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn gather_f32<const K: usize>(
        tables: [&[[f32; 8]]; K],
        index: [u32; 8],
        last: i32,
    ) -> [[f32; 8]; K] {
        let offsets = offsets(index, last);
        let mut out = [[0.0f32; 8]; K];
        for (o, t) in out.iter_mut().zip(tables) {
            // SAFETY: each offset is below `8 (last + 1)`, within the table.
            unsafe {
                let v = _mm256_i32gather_ps::<4>(t.as_ptr().cast(), offsets);
                _mm256_storeu_ps(o.as_mut_ptr(), v);
            }
        }
        out
    }

    /// # Safety
    /// As [`gather_f32`].
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn gather_f64<const K: usize>(
        tables: [&[[f64; 8]]; K],
        index: [u32; 8],
        last: i32,
    ) -> [[f64; 8]; K] {
        let offsets = offsets(index, last);
        let low = _mm256_castsi256_si128(offsets);
        let high = _mm256_extracti128_si256::<1>(offsets);
        let mut out = [[0.0f64; 8]; K];
        for (o, t) in out.iter_mut().zip(tables) {
            // SAFETY: each offset is below `8 (last + 1)`, within the table; `o` holds eight
            // `f64`, written four at a time.
            unsafe {
                let base: *const f64 = t.as_ptr().cast();
                let (a, b) = o.split_at_mut(4);
                _mm256_storeu_pd(a.as_mut_ptr(), _mm256_i32gather_pd::<8>(base, low));
                _mm256_storeu_pd(b.as_mut_ptr(), _mm256_i32gather_pd::<8>(base, high));
            }
        }
        out
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::vec::Vec;

    /// The plain reading: lane `l` of row `min(index[l], len - 1)` of each table.
    fn reference<const K: usize>(tables: [&[[f32; 8]]; K], index: [u32; 8]) -> [[f32; 8]; K] {
        tables.map(|t| core::array::from_fn(|l| t[(index[l] as usize).min(t.len() - 1)][l]))
    }

    fn table(rng: &mut ChaCha8Rng, rows: usize) -> Vec<[f32; 8]> {
        (0..rows)
            .map(|_| core::array::from_fn(|_| rng.random::<f32>() - 0.5))
            .collect()
    }

    /// Every way of reading (selection, the gather instructions, lane by lane) returns each
    /// lane's own row, the index clamped to the last row, on tables of 1 to 40 rows on either
    /// side of `SELECT_ROWS`; an empty table reads zeros.
    #[test]
    fn every_reading_returns_each_lanes_row() {
        let empty: [&[[f32; 8]]; 1] = [&[]];
        assert_eq!(gather(empty, Lanes([3; 8]), false)[0].0, [0.0; 8]);
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        for case in 0..400 {
            let rows = 1 + case % 40;
            let (a, b, c) = (
                table(&mut rng, rows),
                table(&mut rng, rows),
                table(&mut rng, rows),
            );
            let index: [u32; 8] = core::array::from_fn(|_| rng.random_range(0..rows as u32 + 5));
            let lanes = Lanes(index);
            // The gather instructions only where the processor has them (their callers'
            // promise).
            #[cfg(target_arch = "x86_64")]
            let readings = [false, std::is_x86_feature_detected!("avx2")];
            #[cfg(not(target_arch = "x86_64"))]
            let readings = [false];
            for hardware in readings {
                let [one] = gather([a.as_slice()], lanes, hardware);
                assert_eq!(one.0, reference([a.as_slice()], index)[0], "rows {rows}");
                let three = gather([a.as_slice(), b.as_slice(), c.as_slice()], lanes, hardware);
                let selected =
                    select_rows([a.as_slice(), b.as_slice(), c.as_slice()], lanes, rows - 1);
                let expected = reference([a.as_slice(), b.as_slice(), c.as_slice()], index);
                assert_eq!(three.map(|l| l.0), expected, "rows {rows}");
                assert_eq!(selected.map(|l| l.0), expected, "rows {rows}");
            }
        }
    }
}
