//! Model files on any text: refused with a message, or loaded, reloaded bit for bit, and every
//! compensator built from them safe on any desired position.
#![no_main]

use hystcomp_fuzz::{ensure, io_properties::check_model_text};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    ensure(check_model_text(&String::from_utf8_lossy(data)));
});
