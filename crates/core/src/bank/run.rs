//! Running every block of a bank for one control tick, with the widest vector instructions the
//! processor has.
//!
//! The kernels are written once, generic over the lane count; on x86-64 with `std` the same
//! code is also compiled for AVX2 and for AVX-512, and the widest the processor has is chosen at
//! run time ([`VectorPath`]). No fused multiply-add is used in any of them (Rust never fuses a
//! multiplication and an addition by itself, whatever the target features), so every
//! compilation rounds every operation the same way and gives the same bits as the
//! single-channel compensators.

use super::lanes::Lanes;
use super::storage::Block;
use crate::Real;

/// One block's sample: the kernel of a bank.
pub(crate) trait BlockKernel<T: Real, const W: usize> {
    /// The value rows every block of the kernel's layout holds before its operator tables.
    const HEAD: usize;
    /// The count rows every block of the kernel's layout holds.
    const COUNTS: usize;

    /// Steps the block with one desired position per lane (NaN for a padding lane) and returns
    /// one output per lane.
    fn step(&self, block: &mut Block<'_, T, W>, desired: Lanes<T, W>) -> Lanes<T, W>;
}

/// What a bank asks of its kernel besides one block's sample (`super::channels::Channels`).
pub(crate) trait BankKernel<T: Real, const W: usize> {
    /// Every lane of the block back to its initial state.
    fn reset_block(&self, block: &mut Block<'_, T, W>);

    /// The value rows of the output limits `(min, max)`.
    fn limit_rows(&self) -> (usize, usize);

    /// Steps every block for one control tick: [`run`] with a [`BlockKernel`] (for a bank whose
    /// mode is set when it is built, the compilation specialised to that mode).
    fn run_tick<'a>(
        &self,
        blocks: impl Iterator<Item = Block<'a, T, W>>,
        desired: &[T],
        control: &mut [T],
    ) where
        T: 'a;
}

/// The compilations of the banks' kernels (x86-64 with `std`): the one a bank uses is the widest
/// the processor has, unless a thread asks for another with [`with_vector_path`].
///
/// Every path gives the same bits (the tests compare each with the single-channel
/// compensators); they differ only in speed.
#[cfg(feature = "std")]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VectorPath {
    /// The widest the processor has (the default).
    Best,
    /// The target's baseline (SSE2 on x86-64): what every other target runs.
    Baseline,
    /// AVX2: eight `f32` lanes in a register, four `f64`.
    Avx2,
    /// AVX-512 (F, VL, BW, DQ): 32 vector registers, mask registers for the lanes' conditions,
    /// eight `f64` lanes in one register.
    Avx512,
}

#[cfg(feature = "std")]
std::thread_local! {
    static PATH: core::cell::Cell<VectorPath> = const { core::cell::Cell::new(VectorPath::Best) };
}

#[cfg(feature = "std")]
impl VectorPath {
    /// Whether this processor can run the path.
    pub fn available(self) -> bool {
        match self {
            VectorPath::Best | VectorPath::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            VectorPath::Avx2 => std::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            VectorPath::Avx512 => {
                std::is_x86_feature_detected!("avx512f")
                    && std::is_x86_feature_detected!("avx512vl")
                    && std::is_x86_feature_detected!("avx512bw")
                    && std::is_x86_feature_detected!("avx512dq")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The path the banks of this thread take: the one asked for if the processor has it,
    /// else the widest it has.
    pub fn current() -> VectorPath {
        let asked = PATH.with(|p| p.get());
        if asked != VectorPath::Best && asked.available() {
            return asked;
        }
        [VectorPath::Avx512, VectorPath::Avx2]
            .into_iter()
            .find(|p| p.available())
            .unwrap_or(VectorPath::Baseline)
    }
}

/// Runs `f` with this thread's banks on `path` (if the processor has it; the widest it has
/// otherwise), then returns to the path before: to compare the compilations, or to measure
/// one.
#[cfg(feature = "std")]
pub fn with_vector_path<R>(path: VectorPath, f: impl FnOnce() -> R) -> R {
    struct Restore(VectorPath);
    impl Drop for Restore {
        fn drop(&mut self) {
            PATH.with(|p| p.set(self.0));
        }
    }
    let _restore = Restore(PATH.with(|p| p.replace(path)));
    f()
}

/// Steps every block: `desired` and `control` hold one value per channel, in channel order
/// (the blocks' padding lanes beyond the last channel are fed NaN and their outputs dropped).
/// `hardware_gather`: whether the caller is compiled with AVX2 (a constant at each call), so
/// that the tables' reads may use its gather instructions ([`Block::hardware_gather`]).
#[inline(always)]
fn run_blocks<'a, T: Real, K: BlockKernel<T, W>, const W: usize>(
    kernel: &K,
    blocks: impl Iterator<Item = Block<'a, T, W>>,
    desired: &[T],
    control: &mut [T],
    hardware_gather: bool,
) {
    for ((mut block, d), c) in blocks.zip(desired.chunks(W)).zip(control.chunks_mut(W)) {
        block.hardware_gather = hardware_gather;
        let lanes = Lanes(super::lanes::lanewise(|l| {
            d.get(l).copied().unwrap_or(T::nan())
        }));
        // Checked once per block, before the inlined step, so that the compiler drops the
        // bounds checks of the step's reads of the rows at fixed offsets. Never false: every
        // block of the storage holds its layout's rows.
        let out = if block.holds(K::HEAD, K::COUNTS) {
            kernel.step(&mut block, lanes)
        } else {
            Lanes::zero()
        };
        for (o, v) in c.iter_mut().zip(out.0) {
            *o = v;
        }
    }
}

/// The AVX2 compilation, in a module of its own: the compiler gives each module's
/// instantiations their own code-generation unit, so that the three compilations of a kernel
/// (each the whole kernel inlined) are optimised in parallel rather than one after another.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
mod avx2 {
    use super::{Block, BlockKernel, Real, run_blocks};

    /// [`run_blocks`] compiled with AVX2.
    ///
    /// # Safety
    /// The processor must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn run_blocks_avx2<'a, T: Real, K: BlockKernel<T, W>, const W: usize>(
        kernel: &K,
        blocks: impl Iterator<Item = Block<'a, T, W>>,
        desired: &[T],
        control: &mut [T],
    ) {
        run_blocks(kernel, blocks, desired, control, true)
    }
}

/// The AVX-512 compilation, in a module of its own (see [`avx2`]).
#[cfg(all(feature = "std", target_arch = "x86_64"))]
mod avx512 {
    use super::{Block, BlockKernel, Real, run_blocks};

    /// [`run_blocks`] compiled with AVX-512 (foundation, with 256-bit forms, byte/word and
    /// double/quad-word instructions).
    ///
    /// # Safety
    /// The processor must support AVX-512 F, VL, BW and DQ.
    #[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq")]
    pub(super) unsafe fn run_blocks_avx512<'a, T: Real, K: BlockKernel<T, W>, const W: usize>(
        kernel: &K,
        blocks: impl Iterator<Item = Block<'a, T, W>>,
        desired: &[T],
        control: &mut [T],
    ) {
        run_blocks(kernel, blocks, desired, control, true)
    }
}

/// Steps every block with the compilation of the kernel [`VectorPath::current`] names.
///
/// Not `#[inline]`: one copy per bank type in the crate that uses it, not one in each of its
/// codegen units (every copy holds the whole kernel three times over, one per vector path).
pub(crate) fn run<'a, T: Real, K: BlockKernel<T, W>, const W: usize>(
    kernel: &K,
    blocks: impl Iterator<Item = Block<'a, T, W>>,
    desired: &[T],
    control: &mut [T],
) {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    match VectorPath::current() {
        VectorPath::Avx512 => {
            // SAFETY: `current` names a path only if the processor supports it.
            unsafe { avx512::run_blocks_avx512(kernel, blocks, desired, control) };
            return;
        }
        VectorPath::Avx2 => {
            // SAFETY: as above.
            unsafe { avx2::run_blocks_avx2(kernel, blocks, desired, control) };
            return;
        }
        VectorPath::Best | VectorPath::Baseline => {}
    }
    run_blocks(kernel, blocks, desired, control, false)
}
