//! File formats of hystcomp, shared by the command line and the bindings:
//!
//! - [`model_file`]: the JSON model file (`format_version`, physical scales and units, the
//!   normalised MPIM parameters and the direction the model maps);
//! - [`data`]: measured or desired records from CSV and MATLAB Level-5 `.mat` files, with
//!   errors a person can act on;
//! - [`atomic`]: files written atomically (temporary file, then rename);
//! - [`bounded`]: files read with a bound on their size, checked while reading;
//! - [`compensator`]: a compensator built from a model file, in physical units;
//! - `bank` (feature `bank`, on by default): model sets (many channels' models) and the
//!   compensator bank built from one.

pub mod atomic;
pub mod band_limit;
// Not in this crate's own unit-test build: no unit test uses the bank, and its kernels (every
// one compiled for every vector path) would be compiled a second time for it. The integration
// tests (tests/bank.rs, tests/threads.rs) test it, built once with the library.
#[cfg(all(feature = "bank", not(test)))]
pub mod bank;
pub mod bounded;
pub mod compensator;
pub mod data;
pub mod model_file;
#[cfg(feature = "parallel")]
pub mod threads;
