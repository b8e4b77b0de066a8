//! The models published in the reference paper (Gu & Zhu 2014, Tables 1 and 2), in its
//! normalised units, for examples, tests and benchmarks.

use crate::{Buffer, CoreError, Mpim, Real};

#[cfg(feature = "std")]
pub mod bank_workload;

/// The parameters of one published MPIM (eq. (4)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PublishedMpim {
    /// Thresholds `r_i`.
    pub thresholds: [f64; 10],
    /// Weights `b_i`.
    pub weights: [f64; 10],
    /// Cubic coefficient `a1`.
    pub a1: f64,
    /// Linear coefficient `a2`.
    pub a2: f64,
}

/// Table 1: the MPIM identified for IHC and WIHC (input: normalised voltage, output:
/// normalised displacement).
pub const TABLE1: PublishedMpim = PublishedMpim {
    thresholds: [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9],
    weights: [
        0.2313, 0.3059, 0.0155, 0.0752, 0.0683, 0.0252, 0.0035, 0.0094, 0.0264, 0.0032,
    ],
    a1: -0.1569,
    a2: 0.4603,
};

/// Table 2: the MPIM identified for DIHC (input: normalised desired displacement, output:
/// normalised voltage; eq. (10) with `a2`, ERRATA item 1).
pub const TABLE2: PublishedMpim = PublishedMpim {
    thresholds: [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9],
    weights: [
        -0.00002, -0.26603, -0.10684, -0.01221, -0.08412, -0.00238, -0.00328, -0.01115, -0.03417,
        -0.47999,
    ],
    a1: 0.1608,
    a2: 1.2588,
};

impl PublishedMpim {
    /// The model in storage `B` and sample type `T`.
    pub fn model<T: Real, B: Buffer<T>>(&self) -> Result<Mpim<T, B>, CoreError> {
        self.spread(10)
    }

    /// The same hysteresis spread over `n` operators (a multiple of 10): each published operator
    /// `(r_i, b_i)` becomes `n / 10` operators of weight `b_i 10 / n` at thresholds
    /// `r_i, r_i + 0.1 (10 / n), ...`. Used to benchmark larger models of realistic shape.
    pub fn spread<T: Real, B: Buffer<T>>(&self, n: usize) -> Result<Mpim<T, B>, CoreError> {
        let per = (n / 10).max(1);
        let count = per * 10;
        let mut thresholds: B = crate::buffer::filled(T::zero(), count)?;
        let mut weights: B = crate::buffer::filled(T::zero(), count)?;
        for (i, (&r, &b)) in self.thresholds.iter().zip(&self.weights).enumerate() {
            for j in 0..per {
                thresholds.as_mut()[i * per + j] = T::from_f64(r + 0.1 * j as f64 / per as f64);
                weights.as_mut()[i * per + j] = T::from_f64(b / per as f64);
            }
        }
        Mpim::new(
            thresholds.as_ref(),
            weights.as_ref(),
            T::from_f64(self.a1),
            T::from_f64(self.a2),
        )
    }
}
