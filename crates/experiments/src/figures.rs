//! Figures of the study (to be filled in).
