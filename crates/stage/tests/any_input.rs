//! The stage's promises (`common/properties.rs`) on mutations of the shipped stage file and on
//! stage files with extreme values: the stable counterpart of the fuzz target `stage`.

mod common {
    pub mod properties;
}

use common::properties::check_stage_text;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn default_stage() -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("stages/default.toml"),
    )
    .expect("the shipped stage file")
}

proptest! {
    #![proptest_config(Config {
        cases: 64,
        rng_seed: RngSeed::Fixed(0x7374_6167_6566_696c),
        failure_persistence: None,
        ..Config::default()
    })]

    /// Bytes of the shipped stage file overwritten, cut or inserted.
    #[test]
    fn mutated_stage_files_keep_the_promises(
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 1..10),
        seed in any::<u64>(),
    ) {
        let mut bytes = default_stage().into_bytes();
        for (at, byte, kind) in edits {
            let at = at.index(bytes.len().max(1));
            match kind {
                0 if at < bytes.len() => bytes[at] = byte,
                1 => bytes.truncate(at),
                _ => bytes.insert(at.min(bytes.len()), byte),
            }
        }
        prop_assert_eq!(check_stage_text(&String::from_utf8_lossy(&bytes), seed), Ok(()));
    }
}

/// Every numeric field of the shipped stage file set to the extremes a fuzzer tries first.
#[test]
fn extreme_values_in_every_field_keep_the_promises() {
    let text = default_stage();
    for (k, line) in text.lines().enumerate() {
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        if value.trim().parse::<f64>().is_err() {
            continue;
        }
        for extreme in [
            "1e300",
            "-1e300",
            "5e-324",
            "0.0",
            "1e7",
            "nan",
            "inf",
            "4294967295",
        ] {
            let mut lines: Vec<&str> = text.lines().collect();
            let replaced = format!("{key}= {extreme}");
            lines[k] = &replaced;
            let edited = lines.join("\n");
            check_stage_text(&edited, 1).unwrap_or_else(|e| panic!("{key}= {extreme}: {e}"));
        }
    }
}
