//! The committed C header `include/hystcomp.h` must be what cbindgen makes of `src/lib.rs` and
//! the modules it declares, with `cbindgen.toml` (faer's lesson: a committed header and a check
//! that fails when it is stale).
//!
//! Regenerate it with `HYSTCOMP_UPDATE_HEADER=1 cargo test -p hystcomp-c --test header`.

use std::path::Path;

const REGENERATE: &str = "HYSTCOMP_UPDATE_HEADER=1 cargo test -p hystcomp-c --test header";

fn generated_header() -> Vec<u8> {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("bindings/c/cbindgen.toml is readable and valid");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen can parse src/lib.rs and its modules");
    let mut text = Vec::new();
    bindings.write(&mut text);
    text
}

#[test]
fn committed_header_is_current() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/hystcomp.h");
    let generated = generated_header();
    if std::env::var_os("HYSTCOMP_UPDATE_HEADER").is_some_and(|v| v == "1") {
        std::fs::write(&path, &generated).expect("include/hystcomp.h is writable");
        eprintln!("rewrote {}", path.display());
        return;
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    if committed != generated {
        let first_difference = committed
            .iter()
            .zip(&generated)
            .position(|(a, b)| a != b)
            .unwrap_or(committed.len().min(generated.len()));
        let line = 1 + generated[..first_difference]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        panic!(
            "bindings/c/include/hystcomp.h is stale (first difference at line {line}): the C ABI \
             in bindings/c/src changed. Regenerate the header with\n    {REGENERATE}\n\
             and commit it."
        );
    }
}

/// The text of every Rust source file of the crate (`src/*.rs`).
fn sources() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("src/ is readable")
        .map(|entry| entry.expect("src/ entries are readable").path())
        .filter(|path| path.extension().is_some_and(|e| e == "rs"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).expect("sources are UTF-8");
            (path.display().to_string(), text)
        })
        .collect()
}

#[test]
fn header_declares_every_exported_function() {
    let header = String::from_utf8(generated_header()).expect("the header is UTF-8");
    let sources = sources();
    let exported: Vec<&str> = sources
        .iter()
        .flat_map(|(_, text)| text.split("extern \"C\" fn ").skip(1))
        .filter_map(|rest| rest.split('(').next())
        .collect();
    assert!(exported.len() >= 15, "found only {exported:?}");
    for name in exported {
        assert!(
            header.contains(&format!("{name}(")),
            "{name} is exported but not declared in the header"
        );
    }
    for code in [
        "HYSTCOMP_STATUS_OK = 0",
        "HYSTCOMP_STATUS_NULL_POINTER = 1",
        "HYSTCOMP_METHOD_DIHC = 4",
    ] {
        assert!(header.contains(code), "the header lacks {code}");
    }
}
