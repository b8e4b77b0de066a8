//! Triangle and sawtooth rasters with rounded corners, the scan patterns of AFM and
//! nanopositioning.
//!
//! One period of the sharp raster rises linearly over `rise_fraction` of the period and falls
//! over the rest (0.5: a triangle; 0.9: a sawtooth with a 10 % flyback). Each corner is rounded
//! over `rounding` of the period, centred on the corner: there the sharp raster is replaced by
//! the parabola tangent to both of its lines, which is exactly the sharp raster averaged over a
//! moving window of that width (the tests use this as their reference). The velocity is then
//! continuous and the acceleration bounded (by `(slope up + slope down) / rounding period`),
//! which is what keeps a stage's resonance quiet at the turning points.
//!
//! Rounding lowers a corner by `rounding` times the sharp raster's amplitude whatever the rise
//! fraction, so the sharp raster is drawn with amplitude `1 / (1 - rounding)` and the rounded
//! one spans exactly -1 .. +1. The raster starts at the centre of its lowest corner (-1, at
//! rest) at nominal time 0.

use hystcomp_core::Shown;
use serde::{Deserialize, Serialize};

use super::{SignalError, check_range};

/// The highest raster frequency accepted, Hz (at speed 1).
pub const MAX_RASTER_HZ: f64 = 1.0e6;

/// A triangle or sawtooth raster with rounded corners (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Raster {
    /// Lines per second, Hz: one period is one rise and one fall (a "100 Hz raster").
    pub frequency_hz: f64,
    /// Fraction of the period spent rising, in (0, 1): 0.5 for a triangle.
    pub rise_fraction: f64,
    /// Fraction of the period over which each corner is rounded, `0 ..= min(rise_fraction,
    /// 1 - rise_fraction)` (0: sharp corners).
    pub rounding: f64,
}

impl Raster {
    /// A symmetric triangle raster at `frequency_hz`, corners rounded over `rounding` of the
    /// period.
    pub fn triangle(frequency_hz: f64, rounding: f64) -> Raster {
        Raster {
            frequency_hz,
            rise_fraction: 0.5,
            rounding,
        }
    }

    /// A sawtooth raster: rises over `rise_fraction` of the period, flies back over the rest.
    pub fn sawtooth(frequency_hz: f64, rise_fraction: f64, rounding: f64) -> Raster {
        Raster {
            frequency_hz,
            rise_fraction,
            rounding,
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SignalError> {
        if !(self.frequency_hz > 0.0 && self.frequency_hz <= MAX_RASTER_HZ) {
            return Err(SignalError::new(
                "frequency_hz",
                format!(
                    "must be in (0, {MAX_RASTER_HZ}] Hz, got {}",
                    Shown(self.frequency_hz)
                ),
            ));
        }
        if !(self.rise_fraction > 0.0 && self.rise_fraction < 1.0) {
            return Err(SignalError::new(
                "rise_fraction",
                format!("must be in (0, 1), got {}", Shown(self.rise_fraction)),
            ));
        }
        // A hair of tolerance, so that 1 - 0.9 (0.09999999999999998) admits a rounding of 0.1.
        let most = self.rise_fraction.min(1.0 - self.rise_fraction) + 1e-12;
        check_range("rounding", self.rounding, 0.0, most, " of the period")
    }

    /// The sharp raster's amplitude, `1 / (1 - rounding)`.
    fn sharp_amplitude(&self) -> f64 {
        1.0 / (1.0 - self.rounding)
    }

    /// Phase (fraction of a period after the sharp raster's lower corner) of the rounded
    /// raster's minimum, where the raster starts: the lower parabola's vertex lies
    /// `down / (up + down)` of the way through its window.
    fn start_phase(&self) -> f64 {
        // The window starts half a rounding before the corner; down / (up + down) = rho with
        // up = 2a / rho and down = 2a / (1 - rho).
        (self.rounding * (self.rise_fraction - 0.5)).rem_euclid(1.0)
    }

    /// The raster at nominal time `tau_s`, between -1 and +1.
    pub fn unit_value(&self, tau_s: f64) -> f64 {
        let u = (tau_s * self.frequency_hz + self.start_phase()).rem_euclid(1.0);
        let rho = self.rise_fraction;
        let a = self.sharp_amplitude();
        // Slopes per unit of phase (one period = 1).
        let up = 2.0 * a / rho;
        let down = 2.0 * a / (1.0 - rho);
        let w = self.rounding;
        let h = 0.5 * w;
        let bend = (up + down) / (2.0 * w);
        if w > 0.0 && (u - rho).abs() < h {
            // Top corner: tangent to the rising line at rho - h.
            let x = u - (rho - h);
            (a - up * h) + up * x - bend * x * x
        } else if w > 0.0 && (u < h || u > 1.0 - h) {
            // Bottom corner: tangent to the falling line at 1 - h (phase wraps at 0).
            let x = if u < h { u + h } else { u - (1.0 - h) };
            (-a + down * h) - down * x + bend * x * x
        } else if u <= rho {
            -a + up * u
        } else {
            a - down * (u - rho)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The sharp raster of amplitude `a`, literally.
    fn sharp(r: &Raster, a: f64, tau: f64) -> f64 {
        let u = (tau * r.frequency_hz).rem_euclid(1.0);
        if u <= r.rise_fraction {
            -a + 2.0 * a * u / r.rise_fraction
        } else {
            a - 2.0 * a * (u - r.rise_fraction) / (1.0 - r.rise_fraction)
        }
    }

    /// The sharp raster averaged over a window of `rounding` periods (midpoint rule), shifted to
    /// start at its minimum.
    fn box_filtered(r: &Raster, tau: f64) -> f64 {
        let tau = tau + r.start_phase() / r.frequency_hz;
        let a = 1.0 / (1.0 - r.rounding);
        if r.rounding == 0.0 {
            return sharp(r, a, tau);
        }
        let width = r.rounding / r.frequency_hz;
        let n = 4000;
        (0..n)
            .map(|i| {
                sharp(
                    r,
                    a,
                    tau - 0.5 * width + (i as f64 + 0.5) / n as f64 * width,
                )
            })
            .sum::<f64>()
            / n as f64
    }

    #[test]
    fn sharp_triangle_is_the_arcsine_of_a_sine() {
        let r = Raster::triangle(3.0, 0.0);
        for k in 0..1000 {
            let tau = k as f64 * 0.00137;
            let reference = 2.0 / std::f64::consts::PI
                * (2.0 * std::f64::consts::PI * 3.0 * tau - std::f64::consts::FRAC_PI_2)
                    .sin()
                    .asin();
            assert!((r.unit_value(tau) - reference).abs() < 1e-9, "{tau}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn rounded_raster_is_the_sharp_one_averaged_over_the_rounding_window(
            frequency in 0.5f64..200.0,
            rise in 0.05f64..0.95,
            share in 0.0f64..1.0,
            taus in proptest::collection::vec(0.0f64..3.0, 20),
        ) {
            let r = Raster::sawtooth(frequency, rise, share * rise.min(1.0 - rise));
            r.validate().unwrap();
            for tau in taus {
                let tau = tau / frequency;
                let got = r.unit_value(tau);
                let want = box_filtered(&r, tau);
                prop_assert!((got - want).abs() < 1e-5, "tau {tau}: {got} vs {want}");
                prop_assert!((-1.0 - 1e-12..=1.0 + 1e-12).contains(&got));
            }
        }

        #[test]
        fn rounded_raster_spans_minus_one_to_one_and_is_continuous(
            rise in 0.05f64..0.95,
            share in 0.0f64..1.0,
        ) {
            let r = Raster::sawtooth(1.0, rise, share * rise.min(1.0 - rise));
            // Starts at its minimum, at rest.
            prop_assert!((r.unit_value(0.0) + 1.0).abs() < 1e-12);
            prop_assert!((r.unit_value(1e-7) + 1.0).abs() < 1e-6);
            // Continuous: no step larger than the steepest slope allows.
            let steepest = 2.0 / (1.0 - r.rounding) / rise.min(1.0 - rise);
            let dt = 5e-5;
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for k in 0..20_000 {
                let t = k as f64 * dt;
                let y = r.unit_value(t);
                lo = lo.min(y);
                hi = hi.max(y);
                let step = (r.unit_value(t + dt) - y).abs();
                prop_assert!(step <= steepest * dt * (1.0 + 1e-6) + 1e-12, "{t}");
            }
            prop_assert!(lo >= -1.0 - 1e-12 && hi <= 1.0 + 1e-12 && hi > 1.0 - 1e-4, "{lo} {hi}");
        }
    }

    #[test]
    fn rounding_is_bounded_by_the_shorter_ramp() {
        assert!(Raster::sawtooth(10.0, 0.9, 0.1).validate().is_ok());
        let error = Raster::sawtooth(10.0, 0.9, 0.11).validate().unwrap_err();
        assert_eq!(error.parameter, "rounding");
        assert_eq!(
            Raster::sawtooth(10.0, 1.0, 0.0)
                .validate()
                .unwrap_err()
                .parameter,
            "rise_fraction"
        );
        assert_eq!(
            Raster::triangle(0.0, 0.0).validate().unwrap_err().parameter,
            "frequency_hz"
        );
    }
}
