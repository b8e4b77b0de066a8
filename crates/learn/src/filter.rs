//! The learning operator `Q L` of one trial length: `L = gamma z^m` (gain and phase lead),
//! `Q` the zero-phase low-pass `Q(f) = 1 / (1 + (f / f_c)^(2n))` (the magnitude of an `n`-th
//! order Butterworth filter run forwards and backwards), applied in the frequency domain.
//!
//! Plan once, run many times: [`LearningFilter::new`] plans the transforms for one record
//! length and tabulates `gamma Q(f) e^(j 2 pi f m / f_s)`; [`LearningFilter::apply`] then
//! transforms, weighs and transforms back with its own scratch space, allocating nothing.
//! A periodic record is filtered circularly (its DFT is exact for a periodic signal); a finite
//! one is padded with zeros on both sides by the filter's support, so the convolution is
//! linear and nothing wraps around.

use std::f64::consts::PI;
use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

/// The zero-phase learning filter of one record length (see the [module documentation](self)).
pub struct LearningFilter {
    len: usize,
    pad: usize,
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    /// `gamma Q(f_h) e^(j 2 pi h m / M) / M` per bin `h` of the padded length `M`.
    weights: Vec<Complex<f64>>,
    buffer: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
    noise_gain: f64,
}

impl std::fmt::Debug for LearningFilter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LearningFilter")
            .field("len", &self.len)
            .field("pad", &self.pad)
            .field("noise_gain", &self.noise_gain)
            .finish()
    }
}

impl Clone for LearningFilter {
    fn clone(&self) -> Self {
        LearningFilter {
            len: self.len,
            pad: self.pad,
            forward: Arc::clone(&self.forward),
            inverse: Arc::clone(&self.inverse),
            weights: self.weights.clone(),
            buffer: self.buffer.clone(),
            scratch: self.scratch.clone(),
            noise_gain: self.noise_gain,
        }
    }
}

/// `Q(f) = 1 / (1 + (f / f_c)^(2n))`.
pub fn q_response(frequency_hz: f64, cutoff_hz: f64, order: usize) -> f64 {
    1.0 / (1.0 + (frequency_hz.abs() / cutoff_hz).powi(2 * order as i32))
}

impl LearningFilter {
    /// The filter for records of `len` samples at `sample_rate_hz`, periodic or finite, with
    /// gain `gamma`, lead `lead` samples and `Q`'s cut-off and order. The caller has checked
    /// the values ([`crate::LearningOptions::validate`]) and `len >= 2`.
    pub fn new(
        len: usize,
        periodic: bool,
        sample_rate_hz: f64,
        gamma: f64,
        cutoff_hz: f64,
        order: usize,
        lead: usize,
    ) -> LearningFilter {
        // Q's impulse response decays within a few periods of its cut-off: 8 / f_c is far into
        // its tail for every order (tested against longer padding).
        let pad = if periodic {
            0
        } else {
            // (At most `len` before the lead is added: a cut-off near zero cannot overflow.)
            let tail = (8.0 * sample_rate_hz / cutoff_hz).ceil().min(len as f64) as usize;
            tail.saturating_add(lead).min(len)
        };
        let m = len + 2 * pad;
        let mut planner = FftPlanner::new();
        let forward = planner.plan_fft_forward(m);
        let inverse = planner.plan_fft_inverse(m);
        let scratch_len = forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len());
        let mut noise_gain = 0.0;
        let weights = (0..m)
            .map(|h| {
                let bin = h.min(m - h) as f64;
                let q = q_response(bin * sample_rate_hz / m as f64, cutoff_hz, order);
                noise_gain += (gamma * q).powi(2);
                let phase = 2.0 * PI * (h as f64) * lead as f64 / m as f64;
                Complex::from_polar(gamma * q / m as f64, phase)
            })
            .collect();
        LearningFilter {
            len,
            pad,
            forward,
            inverse,
            weights,
            buffer: vec![Complex::new(0.0, 0.0); m],
            scratch: vec![Complex::new(0.0, 0.0); scratch_len],
            noise_gain: noise_gain / m as f64,
        }
    }

    /// The record length it was planned for.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it was planned for empty records (never: at least two samples).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Zeros padded on each side of a finite record (0 for a periodic one).
    pub fn padding(&self) -> usize {
        self.pad
    }

    /// `mean over f of (gamma Q(f))^2`: the share of a white noise's variance that one update
    /// passes into the correction.
    pub fn noise_gain(&self) -> f64 {
        self.noise_gain
    }

    /// `out = Q L [error]`. Both slices have the planned length (the caller checks).
    pub fn apply(&mut self, error: &[f64], out: &mut [f64]) {
        debug_assert_eq!(error.len(), self.len);
        debug_assert_eq!(out.len(), self.len);
        let pad = self.pad;
        self.buffer.fill(Complex::new(0.0, 0.0));
        for (b, e) in self.buffer[pad..pad + self.len].iter_mut().zip(error) {
            b.re = *e;
        }
        self.forward
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
        for (b, w) in self.buffer.iter_mut().zip(&self.weights) {
            *b *= *w;
        }
        self.inverse
            .process_with_scratch(&mut self.buffer, &mut self.scratch);
        for (o, b) in out.iter_mut().zip(&self.buffer[pad..pad + self.len]) {
            *o = b.re;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::LearningFilter;

    /// A cut-off so low that `8 fs / f_c` passes every integer pads the whole record (the
    /// most it may), whatever the lead: no overflow (a panic in a debug build, a wrapped and
    /// wrong padding in a release build).
    #[test]
    fn a_cutoff_near_zero_pads_the_whole_record() {
        for lead in [0, 1, 7] {
            let filter = LearningFilter::new(64, false, 1000.0, 0.5, 1e-17, 2, lead);
            assert_eq!(filter.padding(), 64, "lead {lead}");
        }
        // An ordinary cut-off pads its tail and the lead, within the record.
        let filter = LearningFilter::new(10_000, false, 1000.0, 0.5, 100.0, 2, 3);
        assert_eq!(filter.padding(), 80 + 3);
    }
}
