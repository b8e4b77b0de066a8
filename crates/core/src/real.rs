//! The scalar types the core is generic over.

use core::fmt::{Debug, Display};

use num_traits::Float;

/// A floating-point sample type: `f32` (microcontrollers) or `f64` (host).
///
/// Works without `std` through `num-traits` with `libm`.
pub trait Real: Float + Debug + Display + Default + Send + Sync + 'static {
    /// Converts an `f64` constant (rounding to nearest for `f32`).
    fn from_f64(value: f64) -> Self;
    /// Converts to `f64` (exact).
    fn to_f64(self) -> f64;
}

impl Real for f64 {
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
    #[inline]
    fn from_f64(value: f64) -> Self {
        value as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
}
