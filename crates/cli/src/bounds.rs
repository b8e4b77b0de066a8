//! Every size a user can set on the command line is bounded, and checked before anything is
//! allocated, with a message naming the option and the accepted range.
//!
//! Commands call [`count`] for each size option at the start of `run`; the library checks the
//! same bounds again (for the bindings), but its messages cannot name the command line's flags.

use std::ops::RangeInclusive;

use crate::CliError;

/// Refuses `value` of the size option `option` (e.g. `--samples`) outside `range`; `note` says
/// what the size costs or what the default is.
pub fn count(
    option: &str,
    value: usize,
    range: RangeInclusive<usize>,
    note: &str,
) -> Result<(), CliError> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(CliError::input(format!(
            "{option} {value}: give {} to {}{}{note}",
            range.start(),
            range.end(),
            if note.is_empty() { "" } else { " " },
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_message_names_the_option_and_the_range() {
        count("--samples", 100, 100..=1000, "").unwrap();
        let error = count("--samples", 1001, 100..=1000, "(default 200)").unwrap_err();
        assert_eq!(
            error.to_string(),
            "--samples 1001: give 100 to 1000 (default 200)"
        );
        assert_eq!(error.exit_code(), 1);
    }
}
