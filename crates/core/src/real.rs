//! The scalar types the core is generic over.

use core::fmt::{Debug, Display};
use core::ops::{BitAnd, BitOr, Not};

use num_traits::Float;

/// A floating-point sample type: `f32` (microcontrollers) or `f64` (host).
///
/// Works without `std` through `num-traits` with `libm`.
pub trait Real: Float + Debug + Display + Default + Send + Sync + 'static {
    /// Converts an `f64` constant (rounding to nearest for `f32`).
    fn from_f64(value: f64) -> Self;
    /// Converts to `f64` (exact).
    fn to_f64(self) -> f64;

    /// An unsigned integer as wide as the type (`u32` for `f32`, `u64` for `f64`): a lane of a
    /// mask in the banks' vector code is all ones or all zeros of this width, the form the
    /// processor's vector compares produce and its blends consume.
    #[doc(hidden)]
    type Bits: Copy
        + Default
        + PartialEq
        + Debug
        + BitAnd<Output = Self::Bits>
        + BitOr<Output = Self::Bits>
        + Not<Output = Self::Bits>
        + Send
        + Sync
        + 'static;

    /// The raw bits (`f32::to_bits`, `f64::to_bits`).
    #[doc(hidden)]
    fn lane_bits(self) -> Self::Bits;

    /// The value of raw bits (`f32::from_bits`, `f64::from_bits`).
    #[doc(hidden)]
    fn from_lane_bits(bits: Self::Bits) -> Self;

    /// The lowest bit of `bits`, as 0 or 1.
    #[doc(hidden)]
    fn low_bit(bits: Self::Bits) -> u32;
}

impl Real for f64 {
    type Bits = u64;
    #[inline(always)]
    fn lane_bits(self) -> u64 {
        f64::to_bits(self)
    }
    #[inline(always)]
    fn from_lane_bits(bits: u64) -> Self {
        f64::from_bits(bits)
    }
    #[inline(always)]
    fn low_bit(bits: u64) -> u32 {
        (bits & 1) as u32
    }
    #[inline]
    fn from_f64(value: f64) -> Self {
        value
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

impl Real for f32 {
    type Bits = u32;
    #[inline(always)]
    fn lane_bits(self) -> u32 {
        f32::to_bits(self)
    }
    #[inline(always)]
    fn from_lane_bits(bits: u32) -> Self {
        f32::from_bits(bits)
    }
    #[inline(always)]
    fn low_bit(bits: u32) -> u32 {
        bits & 1
    }
    #[inline]
    fn from_f64(value: f64) -> Self {
        value as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
}

/// Whether `x` is within the square root of the largest finite value (about `1.8e19` in
/// `f32`, `1.3e154` in f64): a position the dynamic links (creep, vibration) can follow
/// without their states overflowing, whose gains are far below that root. NaN: no.
#[inline]
pub(crate) fn followable<T: Real>(x: T) -> bool {
    x.abs() <= T::max_value().sqrt()
}
