//! The model file format (to be filled in).
