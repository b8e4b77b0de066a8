//! A number as messages show it: Rust's `Display` writes every digit of `1e308` (309 of them)
//! and of `1e-300`; a message that echoes a user's value uses [`Shown`] instead.

use core::fmt;

/// Displays an `f64` as `Display` does (`0.5`, `3`, `-12.25`, `NaN`, `inf`) unless the number
/// is at least `1e16` or below `1e-5` in magnitude, which are written in scientific notation
/// (`1e308`, `-2.5e-7`), as `Debug` does; every digit needed to read the value back is kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shown(pub f64);

impl fmt::Display for Shown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        let magnitude = v.abs();
        if v.is_finite() && v != 0.0 && !(1e-5..1e16).contains(&magnitude) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::Shown;
    use std::format;
    use std::string::ToString;

    #[test]
    fn ordinary_numbers_are_displayed_as_display_does() {
        for v in [
            0.0,
            -0.0,
            0.5,
            3.0,
            -12.25,
            1e-5,
            123456.789,
            9.999e15,
            f64::NAN,
            f64::INFINITY,
        ] {
            assert_eq!(Shown(v).to_string(), v.to_string(), "{v:?}");
        }
    }

    #[test]
    fn huge_and_tiny_numbers_are_short_and_read_back_exactly() {
        for v in [
            1e308,
            -1e308,
            1e16,
            2.5e-7,
            -9.9e-6,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
        ] {
            let text = Shown(v).to_string();
            assert!(text.len() <= 24, "{text}");
            assert_eq!(text.parse::<f64>().unwrap(), v, "{text}");
        }
        assert_eq!(format!("{}", Shown(1e308)), "1e308");
    }
}
