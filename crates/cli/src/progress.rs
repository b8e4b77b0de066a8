//! Progress bars for long steps (to be filled in).
