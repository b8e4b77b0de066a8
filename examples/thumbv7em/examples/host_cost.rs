//! Runs one compensator of the firmware for a number of samples on the host, for an
//! instruction count under valgrind and a time per sample (`docs/microcontroller.md`):
//!
//!     cargo build --profile cost --example host_cost --target x86_64-unknown-linux-gnu
//!     valgrind --tool=callgrind host_cost ihc 100000
//!
//! `host_cost ram` prints the RAM per compensator on the host. `none` runs the loop and the trajectory without a compensator: the baseline to subtract.
//! The difference between two sample counts, divided by their difference, is the cost of one
//! sample without the set-up.
use std::hint::black_box;
use std::time::Instant;

use hystcomp_thumbv7em_example::{
    Compensators, desired, hystcomp_dihc_step, hystcomp_ihc_step, hystcomp_wihc_step,
};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("ram") {
        // [IHC, WIHC, DIHC, MPIM] x [10, 100] operators, on this host.
        println!("{:?}", hystcomp_thumbv7em_example::RAM_BYTES);
        return;
    }
    let (which, samples) = match (args.get(1), args.get(2).and_then(|s| s.parse::<u32>().ok())) {
        (Some(w), Some(n)) if ["ihc", "wihc", "dihc", "none"].contains(&w.as_str()) => {
            (w.clone(), n)
        }
        _ => {
            eprintln!("usage: host_cost ihc|wihc|dihc|none SAMPLES");
            std::process::exit(2);
        }
    };
    let mut c = Compensators::from_paper().expect("the paper's tables give compensators");
    let mut sum = 0.0f32;
    let started = Instant::now();
    for k in 0..samples {
        let y_d = black_box(desired(k, 2000));
        sum += match which.as_str() {
            "ihc" => hystcomp_ihc_step(&mut c.ihc, y_d),
            "wihc" => hystcomp_wihc_step(&mut c.wihc, y_d),
            "dihc" => hystcomp_dihc_step(&mut c.dihc, y_d),
            _ => y_d,
        };
    }
    let ns = started.elapsed().as_secs_f64() * 1e9 / f64::from(samples.max(1));
    println!(
        "{which}: {samples} samples, {ns:.1} ns per sample (loop included), mean output {}",
        sum / samples.max(1) as f32
    );
}
