//! Reading records (to be filled in).
