//! The unit of a record's time column (`--time-unit`): seconds by default; milliseconds and
//! microseconds as data loggers and oscilloscopes often write them.

/// The unit of a time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum TimeUnit {
    /// Seconds.
    #[default]
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
}

impl TimeUnit {
    /// Seconds per unit.
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
            TimeUnit::Us => 1e-6,
        }
    }

    /// The word `--time-unit` takes.
    pub fn name(self) -> &'static str {
        match self {
            TimeUnit::S => "s",
            TimeUnit::Ms => "ms",
            TimeUnit::Us => "us",
        }
    }

    /// Times in this unit, in seconds.
    pub fn to_seconds(self, times: &[f64]) -> Vec<f64> {
        times.iter().map(|t| t * self.seconds()).collect()
    }

    /// The unit a time column read as `self` is more likely in, when its step (read as
    /// `self`, in seconds) is 1000 or 10^6 times `expected_s` (to 1 %): e.g. milliseconds
    /// read as seconds give steps 1000 times too long.
    pub fn likely_instead(self, step_s: f64, expected_s: f64) -> Option<TimeUnit> {
        [TimeUnit::S, TimeUnit::Ms, TimeUnit::Us]
            .into_iter()
            .filter(|unit| *unit != self)
            .find(|unit| {
                let rescaled = step_s / self.seconds() * unit.seconds();
                (rescaled / expected_s - 1.0).abs() < 0.01
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn milliseconds_read_as_seconds_are_recognised() {
        // 10 kHz in ms: steps of 0.1 read as seconds.
        assert_eq!(TimeUnit::S.likely_instead(0.1, 1e-4), Some(TimeUnit::Ms));
        assert_eq!(TimeUnit::S.likely_instead(100.0, 1e-4), Some(TimeUnit::Us));
        assert_eq!(TimeUnit::Ms.likely_instead(1e-7, 1e-4), Some(TimeUnit::S));
        assert_eq!(TimeUnit::S.likely_instead(2e-4, 1e-4), None);
        assert_eq!(TimeUnit::Ms.to_seconds(&[0.0, 0.1]), [0.0, 1e-4]);
    }
}
