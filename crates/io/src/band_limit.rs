//! A zero-phase low-pass for a known trajectory: a second-order Butterworth section (bilinear
//! transform, cut-off pre-warped) run forward and then backward over the whole signal, as
//! MATLAB's and SciPy's `filtfilt` do (F. Gustafsson, "Determining the initial states in
//! forward-backward filtering", IEEE Trans. Signal Process. 44 (1996) 988-992,
//! doi:10.1109/78.492552): magnitude `|H|^2` (-6 dB at the cut-off, fourth-order roll-off),
//! no phase and no delay. Each pass starts at rest at its first sample, so a trajectory that
//! starts and ends at rest is not disturbed at its ends.
//!
//! [`crate::compensator::ScaledCompensator::with_inverse_band`] band-limits the known
//! trajectory a chain's vibration inverse inverts offline to the band its vibration link was
//! identified on: above it the link's inverse is an extrapolation, and on the study's 20 um
//! raster at 100 Hz the faithful inverse asks three times the amplifier's slew rate for content
//! the stage barely passes. This is the band-limited inversion of inversion-based feedforward
//! (Q. Zou, S. Devasia, "Preview-based optimal inversion for output tracking: application to
//! scanning tunneling microscopy", IEEE Trans. Control Syst. Technol. 12 (2004) 375-386,
//! doi:10.1109/TCST.2004.824339; K. K. Leang, S. Devasia, "Feedback-linearized inverse
//! feedforward for creep, hysteresis, and vibration compensation in AFM piezoactuators", IEEE
//! Trans. Control Syst. Technol. 15 (2007) 927-935, doi:10.1109/TCST.2007.902956), here with
//! the simplest filter: the inverse is applied to the trajectory's content within the band.

/// `x` low-passed at `cutoff_hz` with zero phase, at `sample_rate_hz`. `cutoff_hz` must lie
/// strictly between 0 and the Nyquist frequency (else the signal is returned as it is).
pub fn zero_phase_low_pass(x: &[f64], cutoff_hz: f64, sample_rate_hz: f64) -> Vec<f64> {
    if x.is_empty() || !(cutoff_hz > 0.0 && cutoff_hz < 0.5 * sample_rate_hz) {
        return x.to_vec();
    }
    let k = (std::f64::consts::PI * cutoff_hz / sample_rate_hz).tan();
    let q = std::f64::consts::FRAC_1_SQRT_2;
    let norm = 1.0 / (1.0 + k / q + k * k);
    let b0 = k * k * norm;
    let (b1, b2) = (2.0 * b0, b0);
    let a1 = 2.0 * (k * k - 1.0) * norm;
    let a2 = (1.0 - k / q + k * k) * norm;
    let pass = |v: &mut Vec<f64>| {
        let (mut x1, mut x2, mut y1, mut y2) = (v[0], v[0], v[0], v[0]);
        for value in v.iter_mut() {
            let x0 = *value;
            let y0 = b0 * x0 + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
            x2 = x1;
            x1 = x0;
            y2 = y1;
            y1 = y0;
            *value = y0;
        }
    };
    let mut out = x.to_vec();
    pass(&mut out);
    out.reverse();
    pass(&mut out);
    out.reverse();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Amplitude and phase (rad) of `y` against `sin(2 pi f t)` over whole periods.
    fn tone(y: &[f64], f: f64, fs: f64, from: usize, to: usize) -> (f64, f64) {
        let (mut s, mut c) = (0.0, 0.0);
        for (k, v) in y.iter().enumerate().take(to).skip(from) {
            let p = 2.0 * std::f64::consts::PI * f * k as f64 / fs;
            s += v * p.sin();
            c += v * p.cos();
        }
        let n = (to - from) as f64;
        let (a, b) = (2.0 * s / n, 2.0 * c / n);
        ((a * a + b * b).sqrt(), b.atan2(a))
    }

    #[test]
    fn tones_pass_with_the_butterworth_magnitude_squared_and_no_phase() {
        let fs = 10_000.0;
        let fc = 1_500.0;
        for f in [50.0, 200.0, 700.0, 1_500.0, 2_500.0, 4_000.0] {
            // 2 s of the tone about an offset; measured on the middle second.
            let x: Vec<f64> = (0..20_000)
                .map(|k| 30.0 + (2.0 * std::f64::consts::PI * f * k as f64 / fs).sin())
                .collect();
            let y = zero_phase_low_pass(&x, fc, fs);
            let centred: Vec<f64> = y.iter().map(|v| v - 30.0).collect();
            let (amplitude, phase) = tone(&centred, f, fs, 5_000, 15_000);
            // The analogue Butterworth's |H|^2 at the pre-warped frequency.
            let warp = |f: f64| (std::f64::consts::PI * f / fs).tan();
            let ratio = warp(f) / warp(fc);
            let expected = 1.0 / (1.0 + ratio.powi(4));
            assert!(
                (amplitude - expected).abs() < 1e-3,
                "{f} Hz: {amplitude} vs {expected}"
            );
            if expected > 0.01 {
                assert!(phase.abs() < 1e-3, "{f} Hz: phase {phase}");
            }
        }
    }

    #[test]
    fn rests_stay_where_they_are_and_bad_cutoffs_change_nothing() {
        let fs = 10_000.0;
        let mut x = vec![12.0; 3_000];
        x.extend(vec![40.0; 3_000]);
        let y = zero_phase_low_pass(&x, 1_000.0, fs);
        assert!((y[0] - 12.0).abs() < 1e-9 && (y[5_999] - 40.0).abs() < 1e-9);
        // Symmetric about the step: no delay.
        for k in 0..100 {
            let a = y[2_999 - k] - 12.0;
            let b = 40.0 - y[3_000 + k];
            assert!((a - b).abs() < 1e-6, "{k}: {a} {b}");
        }
        for bad in [0.0, -1.0, 5_000.0, f64::NAN] {
            assert_eq!(zero_phase_low_pass(&x, bad, fs), x);
        }
        assert!(zero_phase_low_pass(&[], 100.0, fs).is_empty());
    }
}
