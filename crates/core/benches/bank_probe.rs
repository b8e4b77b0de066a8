//! A small probe of one compensator bank's cost per channel-step (issue 16), for instruction
//! counts under `valgrind --tool=callgrind` and for timing one kernel on one vector path
//! without building the command-line tool. A bench target without a harness, so that
//! `cargo test` does not build it (it compiles every bank kernel on every vector path):
//!
//! ```text
//! cargo bench -p hystcomp-core --bench bank_probe -- KIND PRECISION PATH CHANNELS TICKS REPEATS
//! ```
//!
//! or, for callgrind, the binary `cargo bench --no-run` names
//! (`target/release/deps/bank_probe-*`) with the same arguments.
//!
//! `KIND` is `ihc`, `ihc-delayed`, `ihc-guarded`, `wihc`, `wihc-delayed`, `wihc-guarded` or
//! `dihc`; `PRECISION` `f32` or `f64`; `PATH` `best`, `baseline`, `avx2` or `avx512` (valgrind
//! runs no AVX-512: take `avx2` there). The channels are those of `hystcomp bench --channels`
//! (ten operators, Table 1 or 2 of the paper, each channel's weights scaled by its own factor in
//! [0.9, 1.1], each its own phase of a three-tone trajectory). Prints the median over `REPEATS`
//! runs of the thread's CPU time per channel-step (Linux `CLOCK_THREAD_CPUTIME_ID`, else the
//! wall clock), and a checksum of the controls (the same on every path: the same bits).

use std::hint::black_box;

use hystcomp_core::paper::bank_workload::{channel_models, signal};

use hystcomp_core::{
    CompensatorBank, DihcBank, Heap, IhcBank, OutputLimits, Real, SolveMode, VectorPath, WihcBank,
    with_vector_path,
};

/// `struct timespec` of 64-bit Linux.
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
#[repr(C)]
struct Timespec {
    seconds: i64,
    nanoseconds: i64,
}

#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
unsafe extern "C" {
    fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
}

/// The thread's CPU time in ns (Linux `CLOCK_THREAD_CPUTIME_ID`), else the wall clock.
fn now_ns(start: std::time::Instant) -> f64 {
    #[cfg(all(target_os = "linux", target_pointer_width = "64"))]
    {
        const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
        let mut time = Timespec {
            seconds: 0,
            nanoseconds: 0,
        };
        // SAFETY: `time` is a valid `struct timespec` for the call to fill.
        if unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut time) } == 0 {
            return time.seconds as f64 * 1e9 + time.nanoseconds as f64;
        }
    }
    start.elapsed().as_nanos() as f64
}

fn probe<T: Real>(kind: &str, path: VectorPath, channels: usize, ticks: usize, repeats: usize) {
    let (plants, inverses) = channel_models::<T>(channels).expect("the paper's tables");
    let desired = signal(&plants, ticks).expect("a bounded workload");
    let mut control = vec![T::zero(); desired.len()];
    let limits = [OutputLimits::new(T::zero(), T::one()).expect("0 < 1")];
    let mode = |m: &str| match m {
        "delayed" => SolveMode::DelayedAllowUnstable,
        "guarded" => SolveMode::DelayedGuarded,
        _ => SolveMode::Exact,
    };
    let mut bank: Box<dyn CompensatorBank<T>> = match kind.split_once('-') {
        Some(("ihc", m)) => Box::new(IhcBank::<T, Heap>::new(&plants, &limits, mode(m)).unwrap()),
        Some(("wihc", m)) => Box::new(WihcBank::<T, Heap>::new(&plants, &limits, mode(m)).unwrap()),
        None if kind == "ihc" => {
            Box::new(IhcBank::<T, Heap>::new(&plants, &limits, SolveMode::Exact).unwrap())
        }
        None if kind == "wihc" => {
            Box::new(WihcBank::<T, Heap>::new(&plants, &limits, SolveMode::Exact).unwrap())
        }
        None if kind == "dihc" => Box::new(
            DihcBank::<T, Heap>::new(&inverses, &[(T::zero(), T::one())], &limits).unwrap(),
        ),
        _ => panic!("unknown kind {kind}"),
    };
    let start = std::time::Instant::now();
    let mut times = Vec::with_capacity(repeats);
    with_vector_path(path, || {
        for _ in 0..repeats {
            let t0 = now_ns(start);
            bank.reset();
            bank.process(black_box(&desired), &mut control).unwrap();
            times.push((now_ns(start) - t0) / (ticks * channels) as f64);
        }
    });
    times.sort_by(f64::total_cmp);
    let checksum = control
        .iter()
        .fold(0u64, |h, c| h.rotate_left(5) ^ Real::to_f64(*c).to_bits());
    println!(
        "{kind} {path:?} {channels} ch: median {:.2} ns, min {:.2} ns per channel-step; checksum {checksum:016x}",
        times[times.len() / 2],
        times[0]
    );
}

fn main() {
    // `cargo bench` appends `--bench`; the probe's arguments are positional.
    let args: Vec<String> = std::env::args().filter(|a| a != "--bench").collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.into());
    let kind = arg(1, "ihc");
    let precision = arg(2, "f32");
    let path = match arg(3, "best").as_str() {
        "baseline" => VectorPath::Baseline,
        "avx2" => VectorPath::Avx2,
        "avx512" => VectorPath::Avx512,
        _ => VectorPath::Best,
    };
    let channels: usize = arg(4, "4096").parse().expect("channels");
    let ticks: usize = arg(5, "200").parse().expect("ticks");
    let repeats: usize = arg(6, "5").parse().expect("repeats");
    if precision == "f64" {
        probe::<f64>(&kind, path, channels, ticks, repeats.max(1));
    } else {
        probe::<f32>(&kind, path, channels, ticks, repeats.max(1));
    }
}
