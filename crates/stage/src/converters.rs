//! DAC and ADC quantisation.

use crate::config::ConverterConfig;

/// A uniform quantiser with `2^bits` codes over `[min_v, max_v)`: code `k` stands for
/// `min_v + k * lsb`, `lsb = (max_v - min_v) / 2^bits`. With +-10 V and 16 bits, 0 V is a code.
#[derive(Debug, Clone)]
pub(crate) struct Quantiser {
    min_v: f64,
    max_v: f64,
    lsb_v: f64,
    max_code: f64,
}

impl Quantiser {
    pub(crate) fn new(config: &ConverterConfig) -> Self {
        let codes = 2f64.powi(config.bits as i32);
        Quantiser {
            min_v: config.min_v,
            max_v: config.max_v,
            lsb_v: (config.max_v - config.min_v) / codes,
            max_code: codes - 1.0,
        }
    }

    /// One least significant bit, V.
    #[cfg(test)]
    pub(crate) fn lsb_v(&self) -> f64 {
        self.lsb_v
    }

    /// The voltage of the nearest code to a finite `x`, and whether `x` lay outside the span
    /// (and was clamped).
    pub(crate) fn quantise(&self, x: f64) -> (f64, bool) {
        let clamped = x < self.min_v || x > self.max_v;
        let code = ((x - self.min_v) / self.lsb_v)
            .round()
            .clamp(0.0, self.max_code);
        (self.min_v + code * self.lsb_v, clamped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn quantisation_error_is_within_half_a_code_inside_the_span() {
        let q = Quantiser::new(&ConverterConfig::default());
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..10_000 {
            let x: f64 = -10.0 + 19.99 * rng.random::<f64>();
            let (y, clamped) = q.quantise(x);
            assert!(!clamped);
            assert!((y - x).abs() <= 0.5 * q.lsb_v() + 1e-12, "{x} -> {y}");
            // y is a code: an integer number of LSBs above min_v.
            let k = (y + 10.0) / q.lsb_v();
            assert!((k - k.round()).abs() < 1e-6);
        }
        assert_eq!(q.quantise(0.0), (0.0, false));
        assert!(q.quantise(12.0).1);
        assert!(q.quantise(12.0).0 < 10.0);
        assert_eq!(q.quantise(-12.0), (-10.0, true));
    }
}
