//! Running every block of a bank for one control tick, with the widest vector instructions the
//! processor has.
//!
//! The kernels are written once, generic over the lane count; on x86-64 with `std` the same
//! code is also compiled for AVX2 and chosen at run time when the processor has it (no fused
//! multiply-add is enabled or used, so both compilations round every operation the same way
//! and give the same bits as the single-channel compensators).

use super::lanes::Lanes;
use super::storage::Block;
use crate::Real;

/// One block's sample: the kernel of a bank.
pub(crate) trait BlockKernel<T: Real, const W: usize> {
    /// Steps the block with one desired position per lane (NaN for a padding lane) and returns
    /// one output per lane.
    fn step(&self, block: &mut Block<'_, T, W>, desired: Lanes<T, W>) -> Lanes<T, W>;
}

/// Steps every block: `desired` and `control` hold one value per channel, in channel order
/// (the blocks' padding lanes beyond the last channel are fed NaN and their outputs dropped).
#[inline(always)]
fn run_blocks<'a, T: Real, K: BlockKernel<T, W>, const W: usize>(
    kernel: &K,
    blocks: impl Iterator<Item = Block<'a, T, W>>,
    desired: &[T],
    control: &mut [T],
) {
    for ((mut block, d), c) in blocks.zip(desired.chunks(W)).zip(control.chunks_mut(W)) {
        let lanes = Lanes(core::array::from_fn(|l| {
            d.get(l).copied().unwrap_or(T::nan())
        }));
        let out = kernel.step(&mut block, lanes);
        for (o, v) in c.iter_mut().zip(out.0) {
            *o = v;
        }
    }
}

/// [`run_blocks`] compiled with AVX2.
///
/// # Safety
/// The processor must support AVX2.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "avx2")]
unsafe fn run_blocks_avx2<'a, T: Real, K: BlockKernel<T, W>, const W: usize>(
    kernel: &K,
    blocks: impl Iterator<Item = Block<'a, T, W>>,
    desired: &[T],
    control: &mut [T],
) {
    run_blocks(kernel, blocks, desired, control)
}

/// Steps every block with the best compilation of the kernel for this processor.
#[inline]
pub(crate) fn run<'a, T: Real, K: BlockKernel<T, W>, const W: usize>(
    kernel: &K,
    blocks: impl Iterator<Item = Block<'a, T, W>>,
    desired: &[T],
    control: &mut [T],
) {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor supports AVX2 (checked just above).
        unsafe { run_blocks_avx2(kernel, blocks, desired, control) };
        return;
    }
    run_blocks(kernel, blocks, desired, control)
}
