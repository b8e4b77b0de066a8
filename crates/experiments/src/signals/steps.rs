//! Steps and holds: the signal moves from level to level and holds each one, the test of creep
//! (a step held for a minute) and of settling.
//!
//! The signal starts at `levels[0]` and holds it for `hold_s`; then, for each further level, it
//! moves there over `transition_s` along a raised cosine (`0.5 (1 - cos(pi s))`, velocity zero
//! at both ends; an ideal jump when `transition_s` is 0) and holds it for `hold_s`. The last
//! level is held to the end of the signal, however long; a signal shorter than the sequence
//! stops part-way. Times are nominal (divided by the signal's speed factor in real time).

use hystcomp_core::Shown;
use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::{SignalError, check_range};

/// The most levels a sequence may have.
pub const MAX_LEVELS: usize = 100_000;

/// A sequence of held levels (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Steps {
    /// The levels in turn, each in -1 ..= +1 (scaled by the signal's amplitude about its
    /// offset); at least one.
    pub levels: Vec<f64>,
    /// How long each level is held, s (nominal); positive.
    pub hold_s: f64,
    /// How long each move between levels takes, s (nominal); 0 for ideal jumps.
    pub transition_s: f64,
}

impl Steps {
    /// One step: `from` held for `hold_s`, then a move to `to` over `transition_s`, held to the
    /// end.
    pub fn step(from: f64, to: f64, hold_s: f64, transition_s: f64) -> Steps {
        Steps {
            levels: vec![from, to],
            hold_s,
            transition_s,
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), SignalError> {
        if self.levels.is_empty() || self.levels.len() > MAX_LEVELS {
            return Err(SignalError::new(
                "levels",
                format!(
                    "between 1 and {MAX_LEVELS} levels are allowed, got {}",
                    self.levels.len()
                ),
            ));
        }
        for &level in &self.levels {
            check_range("levels", level, -1.0, 1.0, "")?;
        }
        if !(self.hold_s > 0.0 && self.hold_s.is_finite()) {
            return Err(SignalError::new(
                "hold_s",
                format!("must be positive and finite, got {} s", Shown(self.hold_s)),
            ));
        }
        check_range("transition_s", self.transition_s, 0.0, 1e9, " s")
    }

    /// The sequence at nominal time `tau_s`, between -1 and +1.
    pub fn unit_value(&self, tau_s: f64) -> f64 {
        let first = self.levels[0];
        if tau_s < self.hold_s {
            return first;
        }
        let segment = self.transition_s + self.hold_s;
        let since = tau_s - self.hold_s;
        let index = (since / segment).floor();
        let moves = self.levels.len() - 1;
        if index >= moves as f64 {
            return self.levels[moves];
        }
        let index = index as usize;
        let (from, to) = (self.levels[index], self.levels[index + 1]);
        // Not below 0: at a move's start the rounding of `since / segment` can leave `into`
        // an ulp negative, which an ideal jump (transition 0) would divide as 0 / 0.
        let into = (since - index as f64 * segment).max(0.0);
        if into >= self.transition_s {
            to
        } else {
            from + (to - from) * 0.5 * (1.0 - (PI * into / self.transition_s).cos())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The sequence built literally: a list of (start time, from, to) moves, searched in order.
    fn reference(s: &Steps, tau: f64) -> f64 {
        let mut value = s.levels[0];
        let mut start = s.hold_s;
        for w in s.levels.windows(2) {
            if tau < start {
                break;
            }
            let into = tau - start;
            value = if into >= s.transition_s {
                w[1]
            } else {
                let x = into / s.transition_s;
                w[0] + (w[1] - w[0]) * (1.0 - (PI * x).cos()) / 2.0
            };
            start += s.transition_s + s.hold_s;
        }
        value
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn steps_follow_the_literal_sequence(
            levels in proptest::collection::vec(-1.0f64..=1.0, 1..8),
            hold in 0.01f64..2.0,
            transition in prop_oneof![Just(0.0), 0.001f64..1.0],
            taus in proptest::collection::vec(0.0f64..30.0, 50),
        ) {
            let s = Steps { levels, hold_s: hold, transition_s: transition };
            s.validate().unwrap();
            for tau in taus {
                let got = s.unit_value(tau);
                let want = reference(&s, tau);
                prop_assert!((got - want).abs() < 1e-9, "{tau}: {got} vs {want}");
            }
        }
    }

    /// Sampled on a grid as the signal command samples it (1 kHz, holds of whole tenths,
    /// ideal jumps or short moves), every value is finite and between the levels: at a move's
    /// start the rounding once left an ulp before it, and an ideal jump gave NaN (`signal steps
    /// --levels 1,-1,1,... --hold 0.1` was refused at t = 1.8 s).
    #[test]
    fn sampled_sequences_are_finite_at_every_move() {
        for transition in [0.0, 1e-4, 0.003] {
            for hold in [0.1, 0.0001, 0.3] {
                let levels: Vec<f64> = (0..19)
                    .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
                    .collect();
                let s = Steps {
                    levels,
                    hold_s: hold,
                    transition_s: transition,
                };
                for k in 0..5000 {
                    let value = s.unit_value(k as f64 / 1000.0);
                    assert!(
                        (-1.0..=1.0).contains(&value),
                        "hold {hold}, transition {transition}: {value} at sample {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_step_holds_then_moves_smoothly_then_holds_forever() {
        let s = Steps::step(-1.0, 1.0, 1.0, 0.1);
        assert_eq!(s.unit_value(0.0), -1.0);
        assert_eq!(s.unit_value(0.999), -1.0);
        assert!((s.unit_value(1.05)).abs() < 1e-12, "half way at mid-move");
        assert_eq!(s.unit_value(1.1), 1.0);
        assert_eq!(s.unit_value(1e6), 1.0);
    }

    #[test]
    fn bad_sequences_are_refused() {
        let bad = [
            (Steps::step(0.0, 1.5, 1.0, 0.0), "levels"),
            (Steps::step(0.0, 1.0, 0.0, 0.0), "hold_s"),
            (Steps::step(0.0, 1.0, 1.0, -1.0), "transition_s"),
            (
                Steps {
                    levels: vec![],
                    hold_s: 1.0,
                    transition_s: 0.0,
                },
                "levels",
            ),
        ];
        for (s, parameter) in bad {
            assert_eq!(s.validate().unwrap_err().parameter, parameter);
        }
    }
}
