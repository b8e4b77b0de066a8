//! Storage for per-operator arrays: heap vectors or fixed arrays.

use crate::CoreError;

/// Storage of one value per play operator.
///
/// Implemented for `[T; N]` (no allocator needed: the length is fixed at `N`) and, with the
/// `alloc` feature, for `Vec<T>` (any length).
pub trait Buffer<T: Copy>: AsRef<[T]> + AsMut<[T]> + Clone {
    /// The largest length this storage can hold (`Some(N)` for `[T; N]`, which holds exactly
    /// `N`, and for [`Bounded<T, N>`], which holds up to `N`), or `None` for any length.
    const CAPACITY: Option<usize>;

    /// A buffer of `len` copies of `value`, or `None` when this storage cannot hold exactly
    /// `len` values (an array of another length).
    fn filled(value: T, len: usize) -> Option<Self>;
}

impl<T: Copy, const N: usize> Buffer<T> for [T; N] {
    const CAPACITY: Option<usize> = Some(N);

    #[inline]
    fn filled(value: T, len: usize) -> Option<Self> {
        (len == N).then_some([value; N])
    }
}

/// Up to `N` values in a fixed array, without an allocator: storage for the chain's links,
/// whose arrays (creep elements, filter coefficients, the preview) have different lengths.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounded<T, const N: usize> {
    data: [T; N],
    len: usize,
}

impl<T, const N: usize> AsRef<[T]> for Bounded<T, N> {
    #[inline]
    fn as_ref(&self) -> &[T] {
        // `len <= N` always (`filled` checks it); the `min` says so to the compiler, so that
        // the slice has no panic path (the banks' per-sample code reads through it).
        &self.data[..self.len.min(N)]
    }
}

impl<T, const N: usize> AsMut<[T]> for Bounded<T, N> {
    #[inline]
    fn as_mut(&mut self) -> &mut [T] {
        &mut self.data[..self.len.min(N)]
    }
}

impl<T: Copy, const N: usize> Buffer<T> for Bounded<T, N> {
    const CAPACITY: Option<usize> = Some(N);

    #[inline]
    fn filled(value: T, len: usize) -> Option<Self> {
        (len <= N).then_some(Bounded {
            data: [value; N],
            len,
        })
    }
}

#[cfg(feature = "alloc")]
impl<T: Copy> Buffer<T> for alloc::vec::Vec<T> {
    const CAPACITY: Option<usize> = None;

    #[inline]
    fn filled(value: T, len: usize) -> Option<Self> {
        Some(alloc::vec![value; len])
    }
}

/// A buffer of `len` copies of `value`, or the capacity error naming both lengths.
pub(crate) fn filled<T: Copy, B: Buffer<T>>(value: T, len: usize) -> Result<B, CoreError> {
    B::filled(value, len).ok_or(CoreError::Capacity {
        needed: len,
        capacity: B::CAPACITY.unwrap_or(len),
    })
}

/// A buffer holding a copy of `values`.
pub(crate) fn copied<T: Copy + Default, B: Buffer<T>>(values: &[T]) -> Result<B, CoreError> {
    let mut buffer: B = filled(T::default(), values.len())?;
    buffer.as_mut().copy_from_slice(values);
    Ok(buffer)
}
