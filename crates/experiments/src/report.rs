//! The HTML report (to be filled in).
