//! The core's compensators on a microcontroller: `examples/thumbv7em`, a `no_std`, `no_main`
//! program that builds IHC, WIHC and DIHC in `f32` with fixed arrays and no allocator,
//! six-axis IHC, WIHC and DIHC banks with their storage fixed at compile time (issue 16) and
//! the full pipeline's chain (vibration and creep inverses before the IHC, issue 11), is built
//! for a Cortex-M4F (`thumbv7em-none-eabihf`) and its image inspected: no allocator linked, the step functions
//! (the banks' and the chain's too) present and unable to reach a panic, the code small, and
//! the RAM per compensator and per bank equal to the tables in `docs/microcontroller.md` (on
//! the target and on this host).
//!
//! Without the target (and no way to add it with rustup) the test says so and builds the core
//! without default features on the host instead.

use std::mem::size_of;
use std::path::PathBuf;
use std::process::Command;

use hystcomp_core::{
    Dihc, DihcBank, Fixed, Ihc, IhcBank, Mpim, PLAIN_DEGREE, Wihc, WihcBank, dihc_bank_rows,
    plant_bank_rows,
};
use hystcomp_testkit::{cargo, run, workspace_root};
use object::{Object, ObjectSection, ObjectSymbol};

const TARGET: &str = "thumbv7em-none-eabihf";
const LABELS: [&str; 4] = ["IHC", "WIHC", "DIHC", "MPIM"];

/// `[IHC, WIHC, DIHC, MPIM]` for 10 then 100 operators, as `examples/thumbv7em` lists them.
fn host_ram_bytes() -> [usize; 8] {
    [
        size_of::<Ihc<f32, [f32; 10]>>(),
        size_of::<Wihc<f32, [f32; 10]>>(),
        size_of::<Dihc<f32, [f32; 10]>>(),
        size_of::<Mpim<f32, [f32; 10]>>(),
        size_of::<Ihc<f32, [f32; 100]>>(),
        size_of::<Wihc<f32, [f32; 100]>>(),
        size_of::<Dihc<f32, [f32; 100]>>(),
        size_of::<Mpim<f32, [f32; 100]>>(),
    ]
}

/// The six-axis banks of `examples/thumbv7em` (six channels of ten operators, one lane per
/// block, storage fixed at compile time).
const IHC_ROWS: [usize; 3] = plant_bank_rows(6, 10, PLAIN_DEGREE, 1);
const DIHC_ROWS: [usize; 3] = dihc_bank_rows(6, 10, PLAIN_DEGREE, 1);
type SixAxes = IhcBank<f32, Fixed<{ IHC_ROWS[0] }, { IHC_ROWS[1] }, { IHC_ROWS[2] }>, 1>;
type SixAxesWihc = WihcBank<f32, Fixed<{ IHC_ROWS[0] }, { IHC_ROWS[1] }, { IHC_ROWS[2] }>, 1>;
type SixAxesDihc = DihcBank<f32, Fixed<{ DIHC_ROWS[0] }, { DIHC_ROWS[1] }, { DIHC_ROWS[2] }>, 1>;
const BANK_LABELS: [&str; 3] = ["IHC bank", "WIHC bank", "DIHC bank"];

/// The bank rows of `docs/microcontroller.md`: `(target bytes, host bytes)` of the six-channel
/// IHC, WIHC and DIHC banks.
fn documented_bank_ram_bytes() -> Vec<(usize, usize)> {
    let doc = microcontroller_doc();
    BANK_LABELS
        .iter()
        .map(|label| documented_row(&doc, &format!("| {label} | 6 x 10 |")))
        .collect()
}

/// `docs/microcontroller.md`'s text.
fn microcontroller_doc() -> String {
    std::fs::read_to_string(workspace_root().join("docs/microcontroller.md"))
        .expect("docs/microcontroller.md exists")
}

/// The `(target bytes, host bytes)` of the row of `doc` that begins with `prefix`.
fn documented_row(doc: &str, prefix: &str) -> (usize, usize) {
    let line = doc
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("docs/microcontroller.md has no row {prefix}"));
    let cells: Vec<usize> = line
        .split('|')
        .skip(3)
        .filter_map(|c| c.trim().parse().ok())
        .collect();
    assert!(cells.len() >= 2, "row {line:?} needs target and host bytes");
    (cells[0], cells[1])
}

#[test]
fn ram_of_the_six_axis_banks_on_the_host_is_the_documented_one() {
    let documented = documented_bank_ram_bytes();
    for (i, bytes) in [
        size_of::<SixAxes>(),
        size_of::<SixAxesWihc>(),
        size_of::<SixAxesDihc>(),
    ]
    .into_iter()
    .enumerate()
    {
        assert_eq!(
            documented[i].1, bytes,
            "docs/microcontroller.md: the six-axis {} takes {bytes} bytes on this host",
            BANK_LABELS[i]
        );
    }
}

/// The RAM table of `docs/microcontroller.md`: `(label, n) -> (target bytes, host bytes)`, in
/// the order of [`host_ram_bytes`].
fn documented_ram_bytes() -> Vec<(usize, usize)> {
    let doc = microcontroller_doc();
    let mut rows = Vec::new();
    for n in [10, 100] {
        for label in LABELS {
            rows.push(documented_row(&doc, &format!("| {label} | {n} |")));
        }
    }
    rows
}

#[test]
fn ram_per_compensator_on_the_host_is_the_documented_one() {
    let documented = documented_ram_bytes();
    for (i, bytes) in host_ram_bytes().into_iter().enumerate() {
        assert_eq!(
            documented[i].1,
            bytes,
            "docs/microcontroller.md: {} with {} operators takes {bytes} bytes on this host",
            LABELS[i % 4],
            if i < 4 { 10 } else { 100 }
        );
    }
}

fn target_installed() -> bool {
    Command::new("rustup")
        .args(["target", "list", "--installed"])
        .output()
        .is_ok_and(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .any(|l| l.trim() == TARGET)
        })
}

/// Builds the firmware image; `None` when the target is not available.
fn firmware() -> Option<PathBuf> {
    if !target_installed() {
        let added = Command::new("rustup")
            .args(["target", "add", TARGET])
            .status()
            .is_ok_and(|s| s.success());
        if !added || !target_installed() {
            return None;
        }
    }
    let root = workspace_root();
    let target_dir = root.join("target/thumbv7em-build");
    run(
        cargo()
            .current_dir(root.join("examples/thumbv7em"))
            .env("CARGO_TARGET_DIR", &target_dir)
            .args(["build", "--quiet", "--release", "--target", TARGET]),
        "examples/thumbv7em must build for a Cortex-M4F without an allocator",
    );
    Some(target_dir.join(format!("{TARGET}/release/hystcomp-thumbv7em-example")))
}

#[test]
fn compensators_build_for_a_cortex_m4f_without_an_allocator() {
    let Some(image) = firmware() else {
        hystcomp_testkit::require_tool(
            TARGET,
            false,
            "rustup target add thumbv7em-none-eabihf; without it this test builds hystcomp-core \
             without default features (no std, no alloc) on the host instead",
        );
        let root = workspace_root();
        run(
            cargo()
                .current_dir(&root)
                .env("CARGO_TARGET_DIR", root.join("target/thumbv7em-build"))
                .args([
                    "build",
                    "--quiet",
                    "-p",
                    "hystcomp-core",
                    "--no-default-features",
                ]),
            "hystcomp-core must build without std and alloc",
        );
        return;
    };
    let data = std::fs::read(&image).expect("the image was built");
    let elf = object::File::parse(&*data).expect("the image is an ELF file");
    assert_eq!(elf.architecture(), object::Architecture::Arm);
    assert!(!elf.is_64());

    let names: Vec<String> = elf
        .symbols()
        .filter_map(|s| s.name().ok().map(str::to_owned))
        .collect();
    for allocator in [
        "__rust_alloc",
        "__rust_alloc_zeroed",
        "__rg_alloc",
        "malloc",
    ] {
        assert!(
            !names.iter().any(|n| n == allocator),
            "the image links an allocator ({allocator})"
        );
    }
    for step in [
        "hystcomp_ihc_step",
        "hystcomp_wihc_step",
        "hystcomp_dihc_step",
        "hystcomp_ihc_bank_step",
        "hystcomp_wihc_bank_step",
        "hystcomp_dihc_bank_step",
        "hystcomp_chain_step",
        "_start",
    ] {
        let symbol = elf
            .symbols()
            .find(|s| s.name() == Ok(step))
            .unwrap_or_else(|| panic!("{step} is missing from the image"));
        assert!(symbol.size() > 0, "{step} has no code");
        eprintln!("{step}: {} bytes", symbol.size());
    }

    // The per-sample path cannot panic: no function a step function can reach by a call or a
    // branch is one of core's panic entry points (bounds checks, slice indexing, panic!). The
    // bank's step included: its rows are read through lengths checked once per block.
    for step in [
        "hystcomp_ihc_step",
        "hystcomp_wihc_step",
        "hystcomp_dihc_step",
        "hystcomp_ihc_bank_step",
        "hystcomp_wihc_bank_step",
        "hystcomp_dihc_bank_step",
        "hystcomp_chain_step",
    ] {
        let reached = reachable_functions(&elf, step);
        assert!(reached.len() > 1, "{step} reaches nothing: {reached:?}");
        let panics: Vec<&String> = reached.iter().filter(|n| n.contains("panic")).collect();
        assert!(
            panics.is_empty(),
            "{step} can reach a panic: {panics:?} (of {reached:?})"
        );
    }

    let text = elf
        .section_by_name(".text")
        .expect("a .text section")
        .size();
    let rodata = elf.section_by_name(".rodata").map_or(0, |s| s.size());
    let bss = elf.section_by_name(".bss").map_or(0, |s| s.size());
    eprintln!("{TARGET} image: .text {text} B, .rodata {rodata} B, .bss {bss} B");
    // The three compensators take about 23 KiB; the six-axis IHC bank's step, with the guarded
    // loops' reachability walk (2649e29), brings the image to about 52 KiB (53 556 B measured);
    // the chain to 79 200 B: its step is 740 B, the rest the vibration inverse's construction
    // (the numerator's roots, the anti-causal series), run once at start-up; the WIHC and DIHC
    // banks to 111 980 B (the WIHC bank's loop over its blocks 25 500 B, the DIHC bank's step
    // 4 780 B); the IHC bank's modes each with its own loop over the blocks (65dee6f) to
    // 115 684 B; the guarded IHC's direct evaluation beside its walks to 120 588 B; the
    // delayed IHC bank's one-pass step (`bank::within`) to 123 340 B. A
    // Cortex-M4F part has 256 KiB to 2 MiB of flash.
    assert!(
        text < 128 * 1024,
        "the compensators, the banks and the chain take {text} bytes of code; keep them under \
         128 KiB"
    );

    // The target's own `size_of` values, compiled into the image.
    let table = elf
        .symbols()
        .find(|s| s.name() == Ok("HYSTCOMP_RAM_BYTES"))
        .expect("the RAM table is in the image");
    let section = elf
        .section_by_index(table.section_index().expect("in a section"))
        .expect("its section");
    let bytes = section
        .data_range(table.address(), 32)
        .expect("readable")
        .expect("32 bytes");
    let target: Vec<usize> = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap()) as usize)
        .collect();
    let documented_banks = documented_bank_ram_bytes();
    let table = elf
        .symbols()
        .find(|s| s.name() == Ok("HYSTCOMP_BANK_RAM_BYTES"))
        .expect("the banks' RAM table is in the image");
    let section = elf
        .section_by_index(table.section_index().expect("in a section"))
        .expect("its section");
    let bank_bytes = section
        .data_range(table.address(), 12)
        .expect("readable")
        .expect("12 bytes");
    for (i, b) in bank_bytes.chunks_exact(4).enumerate() {
        let bytes = u32::from_le_bytes(b.try_into().unwrap()) as usize;
        assert_eq!(
            documented_banks[i].0, bytes,
            "docs/microcontroller.md: the six-axis {} takes {bytes} bytes on {TARGET}",
            BANK_LABELS[i]
        );
    }
    let documented = documented_ram_bytes();
    for (i, bytes) in target.iter().enumerate() {
        assert_eq!(
            documented[i].0,
            *bytes,
            "docs/microcontroller.md: {} with {} operators takes {bytes} bytes on {TARGET}",
            LABELS[i % 4],
            if i < 4 { 10 } else { 100 }
        );
    }
}

/// The functions (by symbol name) reachable from `start` through Thumb-2 `BL`, `B.W` and
/// 16-bit `B` instructions whose targets lie in another function (calls and tail calls),
/// `start` included. Literal pools (between the `$d` and `$t` mapping symbols) are skipped.
fn reachable_functions(elf: &object::File<'_>, start: &str) -> Vec<String> {
    let text = elf.section_by_name(".text").expect("a .text section");
    let base = text.address();
    let code = text.data().expect("the .text bytes");
    let mut functions: Vec<(u64, u64, String)> = Vec::new();
    let mut data_marks: Vec<(u64, bool)> = Vec::new(); // (address, is data)
    for symbol in elf.symbols() {
        let Ok(name) = symbol.name() else { continue };
        let address = symbol.address() & !1;
        match name {
            "$d" => data_marks.push((address, true)),
            "$t" => data_marks.push((address, false)),
            _ if symbol.kind() == object::SymbolKind::Text && symbol.size() > 0 => {
                functions.push((address, symbol.size(), name.to_owned()))
            }
            _ => {}
        }
    }
    data_marks.sort_unstable();
    let in_data = |address: u64| {
        data_marks
            .iter()
            .rev()
            .find(|(at, _)| *at <= address)
            .is_some_and(|(_, data)| *data)
    };
    let function_at = |address: u64| {
        functions
            .iter()
            .find(|(at, size, _)| (*at..*at + *size).contains(&address))
    };
    let halfword = |address: u64| -> Option<u16> {
        let k = usize::try_from(address.checked_sub(base)?).ok()?;
        Some(u16::from_le_bytes([*code.get(k)?, *code.get(k + 1)?]))
    };
    let (first, size, _) = functions
        .iter()
        .find(|(_, _, n)| n == start)
        .unwrap_or_else(|| panic!("{start} is missing from the image"))
        .clone();
    let mut seen = vec![start.to_owned()];
    let mut queue = vec![(first, size)];
    while let Some((at, size)) = queue.pop() {
        let mut pc = at;
        while pc < at + size {
            let Some(h1) = halfword(pc) else { break };
            if in_data(pc) {
                pc += 2;
                continue;
            }
            let wide = (h1 >> 11) >= 0b11101;
            let target = if wide {
                let h2 = halfword(pc + 2).unwrap_or(0);
                // BL (T1) and B.W (T4): 1111 0 S imm10 : 11 J1 1 J2 imm11 / 10 J1 1 J2 imm11.
                if h1 >> 11 == 0b11110 && (h2 & 0xD000 == 0xD000 || h2 & 0xD000 == 0x9000) {
                    let s = u32::from(h1 >> 10) & 1;
                    let i1 = 1 ^ ((u32::from(h2) >> 13) & 1) ^ s;
                    let i2 = 1 ^ ((u32::from(h2) >> 11) & 1) ^ s;
                    let raw = (s << 24)
                        | (i1 << 23)
                        | (i2 << 22)
                        | ((u32::from(h1) & 0x3FF) << 12)
                        | ((u32::from(h2) & 0x7FF) << 1);
                    let offset = ((raw << 7) as i32) >> 7; // sign-extend 25 bits
                    Some((pc as i64 + 4 + i64::from(offset)) as u64)
                } else {
                    None
                }
            } else if h1 >> 11 == 0b11100 {
                // B (T2): 11100 imm11.
                let offset = ((u32::from(h1 & 0x7FF) << 21) as i32) >> 20;
                Some((pc as i64 + 4 + i64::from(offset)) as u64)
            } else {
                None
            };
            if let Some((to, to_size, name)) = target.and_then(function_at)
                && !(at..at + size).contains(&target.unwrap_or(0))
                && !seen.contains(name)
            {
                seen.push(name.clone());
                queue.push((*to, *to_size));
            }
            pc += if wide { 4 } else { 2 };
        }
    }
    seen
}
