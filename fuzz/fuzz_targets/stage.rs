//! Stage files on any text, and the stage built from them driven by extreme commands (the
//! first eight bytes seed the sensor noise).
#![no_main]

use hystcomp_fuzz::{ensure, stage_properties::check_stage_text};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (seed, text) = match data.split_at_checked(8) {
        Some((seed, text)) => (u64::from_le_bytes(seed.try_into().unwrap_or([0; 8])), text),
        None => (0, data),
    };
    ensure(check_stage_text(&String::from_utf8_lossy(text), seed));
});
