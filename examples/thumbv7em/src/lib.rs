//! The compensators of `hystcomp-core` as a microcontroller runs them: `f32` samples, storage in
//! fixed arrays (`[f32; N]`), no allocator, no `std`.
//!
//! [`Compensators`] holds an IHC and a WIHC built from the paper's Table 1 and a DIHC from its
//! Table 2; the `*_step` functions are the per-sample calls a control loop makes (kept as
//! separate functions so that their code can be measured). [`RAM_BYTES`] is the RAM each
//! compensator takes, for `n = 10` and `n = 100` operators.
//!
//! [`SixAxes`] is a bank of six IHC channels (a six-axis stage, issue 16) with its storage
//! fixed at compile time ([`hystcomp_core::Fixed`]), [`SixAxesWihc`] and [`SixAxesDihc`] the
//! WIHC and DIHC banks of the same stage; [`BANK_RAM_BYTES`] is their RAM.
//!
//! [`Chain`] is the full pipeline's streaming compensator (issue 11): a vibration inverse with
//! a preview, a creep inverse and the IHC, every link's arrays in [`Bounded`] storage.
#![no_std]

use core::mem::size_of;

use hystcomp_core::{
    BankError, Bounded, ChainCompensator, Compensator, CompensatorBank, CoreError, CreepInverse,
    Dihc, DihcBank, Fixed, Ihc, IhcBank, Mpim, OutputLimits, PLAIN_DEGREE, SolveMode,
    VibrationInverse, Wihc, WihcBank, dihc_bank_rows, paper, plant_bank_rows,
};

/// Ten play operators, as in the paper.
pub const N: usize = 10;

/// The RAM of one compensator (its whole state: model, inverse, memory, limits, counters),
/// bytes: `[IHC, WIHC, DIHC, forward MPIM]` with 10 operators, then the same with 100.
pub const RAM_BYTES: [usize; 8] = [
    size_of::<Ihc<f32, [f32; 10]>>(),
    size_of::<Wihc<f32, [f32; 10]>>(),
    size_of::<Dihc<f32, [f32; 10]>>(),
    size_of::<Mpim<f32, [f32; 10]>>(),
    size_of::<Ihc<f32, [f32; 100]>>(),
    size_of::<Wihc<f32, [f32; 100]>>(),
    size_of::<Dihc<f32, [f32; 100]>>(),
    size_of::<Mpim<f32, [f32; 100]>>(),
];

/// The three compensators of the paper, in `f32` with ten operators each.
pub struct Compensators {
    /// IHC, eqs. (5)-(8), exact per-sample solve, from Table 1.
    pub ihc: Ihc<f32, [f32; N]>,
    /// WIHC, eq. (9), exact per-sample solve, from Table 1.
    pub wihc: Wihc<f32, [f32; N]>,
    /// DIHC, eq. (10), from Table 2.
    pub dihc: Dihc<f32, [f32; N]>,
}

impl Compensators {
    /// Builds the three from the paper's tables, with outputs limited to `[0, 1]` (normalised).
    pub fn from_paper() -> Result<Self, CoreError> {
        let plant: Mpim<f32, [f32; N]> = paper::TABLE1.model()?;
        let inverse: Mpim<f32, [f32; N]> = paper::TABLE2.model()?;
        let limits = OutputLimits::new(0.0, 1.0)?;
        Ok(Compensators {
            ihc: Ihc::new(&plant, limits, SolveMode::Exact)?,
            wihc: Wihc::new(&plant, limits, SolveMode::Exact)?,
            dihc: Dihc::new(&inverse, 0.0, 1.0, limits)?,
        })
    }
}

/// The axes of the stage the bank drives.
pub const AXES: usize = 6;

/// Channels per block of the banks: one (a Cortex-M4F has no vector unit for `f32`, so wider
/// blocks would only pad).
pub const BANK_LANES: usize = 1;

const IHC_ROWS: [usize; 3] = plant_bank_rows(AXES, N, PLAIN_DEGREE, BANK_LANES);
const DIHC_ROWS: [usize; 3] = dihc_bank_rows(AXES, N, PLAIN_DEGREE, BANK_LANES);

/// Six IHC channels of ten operators in `f32`, storage fixed at compile time.
pub type SixAxes =
    IhcBank<f32, Fixed<{ IHC_ROWS[0] }, { IHC_ROWS[1] }, { IHC_ROWS[2] }>, BANK_LANES>;

/// Six WIHC channels of ten operators in `f32` (the IHC bank's rows).
pub type SixAxesWihc =
    WihcBank<f32, Fixed<{ IHC_ROWS[0] }, { IHC_ROWS[1] }, { IHC_ROWS[2] }>, BANK_LANES>;

/// Six DIHC channels of ten operators in `f32`.
pub type SixAxesDihc =
    DihcBank<f32, Fixed<{ DIHC_ROWS[0] }, { DIHC_ROWS[1] }, { DIHC_ROWS[2] }>, BANK_LANES>;

/// The RAM of the six-channel banks, bytes: `[IHC bank, WIHC bank, DIHC bank]`.
pub const BANK_RAM_BYTES: [usize; 3] = [
    size_of::<SixAxes>(),
    size_of::<SixAxesWihc>(),
    size_of::<SixAxesDihc>(),
];

/// `model` for each of the six axes (each its own copy).
fn six_copies(model: &Mpim<f32, [f32; N]>) -> [Mpim<f32, [f32; N]>; AXES] {
    core::array::from_fn(|_| model.clone())
}

/// The six-axis IHC bank from Table 1 (each axis its own copy of the model), outputs in
/// `[0, 1]`.
pub fn six_axes() -> Result<SixAxes, BankError> {
    SixAxes::new(
        &six_copies(&paper::TABLE1.model()?),
        &[OutputLimits::new(0.0, 1.0)?],
        SolveMode::Exact,
    )
}

/// The six-axis WIHC bank from Table 1, outputs in `[0, 1]`.
pub fn six_axes_wihc() -> Result<SixAxesWihc, BankError> {
    SixAxesWihc::new(
        &six_copies(&paper::TABLE1.model()?),
        &[OutputLimits::new(0.0, 1.0)?],
        SolveMode::Exact,
    )
}

/// The six-axis DIHC bank from Table 2 (the inverse model on inputs `[0, 1]`), outputs in
/// `[0, 1]`.
pub fn six_axes_dihc() -> Result<SixAxesDihc, BankError> {
    let inverses = six_copies(&paper::TABLE2.model()?);
    SixAxesDihc::new(&inverses, &[(0.0, 1.0)], &[OutputLimits::new(0.0, 1.0)?])
}

/// One tick of the six-axis IHC bank: `out[c]` for `desired[c]`.
#[inline(never)]
#[unsafe(no_mangle)]
pub fn hystcomp_ihc_bank_step(
    bank: &mut SixAxes,
    desired: &[f32; AXES],
    out: &mut [f32; AXES],
) -> bool {
    bank.step(desired, out).is_ok()
}

/// One tick of the six-axis WIHC bank.
#[inline(never)]
#[unsafe(no_mangle)]
pub fn hystcomp_wihc_bank_step(
    bank: &mut SixAxesWihc,
    desired: &[f32; AXES],
    out: &mut [f32; AXES],
) -> bool {
    bank.step(desired, out).is_ok()
}

/// One tick of the six-axis DIHC bank.
#[inline(never)]
#[unsafe(no_mangle)]
pub fn hystcomp_dihc_bank_step(
    bank: &mut SixAxesDihc,
    desired: &[f32; AXES],
    out: &mut [f32; AXES],
) -> bool {
    bank.step(desired, out).is_ok()
}

/// One IHC sample.
#[inline(never)]
#[unsafe(no_mangle)]
pub fn hystcomp_ihc_step(c: &mut Ihc<f32, [f32; N]>, desired: f32) -> f32 {
    c.step(desired)
}

/// One WIHC sample.
#[inline(never)]
#[unsafe(no_mangle)]
pub fn hystcomp_wihc_step(c: &mut Wihc<f32, [f32; N]>, desired: f32) -> f32 {
    c.step(desired)
}

/// One DIHC sample.
#[inline(never)]
#[unsafe(no_mangle)]
pub fn hystcomp_dihc_step(c: &mut Dihc<f32, [f32; N]>, desired: f32) -> f32 {
    c.step(desired)
}

/// The most values of one array of the chain's links (creep elements, filter coefficients, the
/// preview ring of [`CHAIN_PREVIEW`] + 1 samples).
pub const CHAIN_CAPACITY: usize = 48;

/// The chain's preview, samples (its output lags its input by this many).
pub const CHAIN_PREVIEW: usize = 40;

/// The full pipeline's compensator on a microcontroller: vibration inverse, creep inverse and
/// the exact IHC of Table 1, no allocator.
pub type Chain = ChainCompensator<f32, Bounded<f32, CHAIN_CAPACITY>, Ihc<f32, [f32; N]>>;

/// A chain at 10 kHz with illustrative links (not identified from a stage): creep elements at
/// 0.1, 1 and 10 s of weight 0.01 each, and a unit-gain resonance at 800 Hz (poles at radius
/// 0.98) with a zero inside the unit circle and one sample of delay.
pub fn chain() -> Result<Chain, CoreError> {
    let plant: Mpim<f32, [f32; N]> = paper::TABLE1.model()?;
    let ihc = Ihc::new(&plant, OutputLimits::new(0.0, 1.0)?, SolveMode::Exact)?;
    let period_s = 1e-4;
    let creep = CreepInverse::new(&[0.1, 1.0, 10.0], &[0.01, 0.01, 0.01], 0.0, period_s)?;
    // 1 - 2 r cos(theta) z^-1 + r^2 z^-2, r = 0.98, theta = 2 pi 800 / 10 000.
    let denominator = [1.0, -1.717_542_7, 0.960_4];
    let gain: f32 = denominator.iter().sum();
    let numerator = [0.7 * gain, 0.3 * gain];
    let vibration = VibrationInverse::new(&numerator, &denominator, 1, CHAIN_PREVIEW)?;
    Ok(ChainCompensator::new(Some(vibration), Some(creep), ihc))
}

/// One sample of the chain: the drive for the desired position [`CHAIN_PREVIEW`] samples
/// ago.
#[inline(never)]
#[unsafe(no_mangle)]
pub fn hystcomp_chain_step(c: &mut Chain, desired: f32) -> f32 {
    c.step(desired)
}

/// A desired trajectory without `sin` (no libm needed here): a triangle wave over
/// `[0.1, 0.8]` with a period of `period` samples, plus a small second triangle.
pub fn desired(k: u32, period: u32) -> f32 {
    let triangle = |k: u32, p: u32| {
        let phase = (k % p) as f32 / p as f32;
        if phase < 0.5 {
            2.0 * phase
        } else {
            2.0 - 2.0 * phase
        }
    };
    0.1 + 0.6 * triangle(k, period) + 0.1 * triangle(k, period / 7 + 1)
}
