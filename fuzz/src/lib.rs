//! What the fuzz targets share: the properties they check are the test suites' own modules,
//! included here, so that the fuzzers and the proptests that run on stable in CI check the
//! same things.

/// The readers' promises (`crates/io/tests/common/properties.rs`).
#[path = "../../crates/io/tests/common/properties.rs"]
pub mod io_properties;

/// The stage's promises (`crates/stage/tests/common/properties.rs`).
#[path = "../../crates/stage/tests/common/properties.rs"]
pub mod stage_properties;

/// The compensators' invariants (`crates/core/tests/common/invariants.rs`).
#[path = "../../crates/core/tests/common/invariants.rs"]
pub mod invariants;

/// Panics with the violation, so that libFuzzer records the input as a crash.
pub fn ensure(result: Result<(), String>) {
    if let Err(violation) = result {
        panic!("property violated: {violation}");
    }
}
