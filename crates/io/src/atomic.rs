//! Atomic file writes (to be filled in).
