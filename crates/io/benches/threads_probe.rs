//! Whether threads pay for a compensator bank (issue 16, feature `parallel`): the plain core
//! bank against [`ThreadedBank`] of the same channels, in wall time per channel-step, runs
//! interleaved so that the machine's load weighs on both alike. A bench target without a
//! harness (`cargo test` does not build it):
//!
//! ```text
//! cargo bench -p hystcomp-io --features parallel --bench threads_probe -- \
//!     KIND PRECISION CHANNELS TICKS REPEATS PARTS
//! ```
//!
//! `KIND` is `ihc` (exact), `ihc-delayed` or `dihc`; `PRECISION` `f32` or `f64`. The channels
//! and the signal are those of `hystcomp bench --channels` (the core's bank benches). Prints,
//! for each of the plain bank stepped tick by tick, the threaded bank stepped tick by tick (one
//! fork and join per tick, what a controller does) and the threaded bank processing the whole
//! signal (one fork and join for all ticks, an offline run), the median and the minimum over
//! `REPEATS` runs, and whether every run gave the plain bank's bits.

use std::hint::black_box;
use std::ops::Range;
use std::time::Instant;

use hystcomp_core::paper::bank_workload::{channel_models, signal};

use hystcomp_core::{CompensatorBank, DihcBank, Heap, IhcBank, OutputLimits, Real, SolveMode};
use hystcomp_io::threads::ThreadedBank;

/// ns per channel-step of one run, and the controls' bits. The controls are set to NaN first
/// (outside the timing), so that a run that leaves one unwritten cannot pass the comparison
/// with what the run before it wrote.
fn time_run<T: Real>(
    run: &mut dyn FnMut(&[T], &mut [T]),
    desired: &[T],
    control: &mut [T],
) -> (f64, Vec<u64>) {
    control.fill(T::nan());
    let t0 = Instant::now();
    run(black_box(desired), control);
    let ns = t0.elapsed().as_nanos() as f64 / desired.len() as f64;
    (
        ns,
        control.iter().map(|c| Real::to_f64(*c).to_bits()).collect(),
    )
}

/// Times the bank `build(0..channels)` against `ThreadedBank` of `parts` parts of it, and
/// prints the figures; an error when a threaded run's bits differ from the plain bank's.
fn compare<T: Real, B: CompensatorBank<T> + Send>(
    label: &str,
    build: impl Fn(Range<usize>) -> B,
    desired: &[T],
    channels: usize,
    repeats: usize,
    parts: usize,
) -> Result<(), String> {
    let mut control = vec![T::zero(); desired.len()];
    let mut plain = build(0..channels);
    let mut threaded =
        ThreadedBank::new(channels, parts, |r| Ok(build(r))).map_err(|e| e.to_string())?;
    fn by_tick<T: Real>(b: &mut impl CompensatorBank<T>, d: &[T], c: &mut [T], channels: usize) {
        b.reset();
        for (d, c) in d.chunks_exact(channels).zip(c.chunks_exact_mut(channels)) {
            b.step(d, c).expect("one tick");
        }
    }
    let mut times: [Vec<f64>; 3] = Default::default();
    let mut same = true;
    for _ in 0..repeats {
        let (ns, expected) = time_run(
            &mut |d, c| by_tick(&mut plain, d, c, channels),
            desired,
            &mut control,
        );
        times[0].push(ns);
        let (ns, bits) = time_run(
            &mut |d, c| by_tick(&mut threaded, d, c, channels),
            desired,
            &mut control,
        );
        times[1].push(ns);
        same &= bits == expected;
        let (ns, bits) = time_run(
            &mut |d, c| {
                threaded.reset();
                threaded.process(d, c).expect("the signal");
            },
            desired,
            &mut control,
        );
        times[2].push(ns);
        same &= bits == expected;
    }
    println!(
        "{label}, {} parts on {} threads, wall ns per channel-step:",
        threaded.parts(),
        rayon::current_num_threads()
    );
    for (name, t) in [
        "plain, by tick",
        "threaded, by tick",
        "threaded, whole signal",
    ]
    .iter()
    .zip(times.iter_mut())
    {
        t.sort_by(f64::total_cmp);
        println!(
            "  {name:<23} median {:>7.2}  min {:>7.2}",
            t[t.len() / 2],
            t[0]
        );
    }
    println!("  same bits as the plain bank: {same}");
    if same {
        Ok(())
    } else {
        Err("the threaded bank's controls differ from the plain bank's".into())
    }
}

fn probe<T: Real>(
    kind: &str,
    channels: usize,
    ticks: usize,
    repeats: usize,
    parts: usize,
) -> Result<(), String> {
    let (plants, inverses) = channel_models::<T>(channels).expect("the paper's tables");
    let desired = signal(&plants, ticks).expect("a bounded workload");
    let limits = [OutputLimits::new(T::zero(), T::one()).expect("0 < 1")];
    let label = format!(
        "{kind} {} {channels} ch, {ticks} ticks",
        core::any::type_name::<T>()
    );
    let ihc = |mode: SolveMode| {
        move |r: Range<usize>| IhcBank::<T, Heap>::new(&plants[r], &limits, mode).expect("models")
    };
    match kind {
        "ihc" => compare(
            &label,
            ihc(SolveMode::Exact),
            &desired,
            channels,
            repeats,
            parts,
        ),
        "ihc-delayed" => compare(
            &label,
            ihc(SolveMode::DelayedAllowUnstable),
            &desired,
            channels,
            repeats,
            parts,
        ),
        "dihc" => compare(
            &label,
            |r: Range<usize>| {
                DihcBank::<T, Heap>::new(&inverses[r], &[(T::zero(), T::one())], &limits)
                    .expect("models")
            },
            &desired,
            channels,
            repeats,
            parts,
        ),
        other => Err(format!("kind {other}: ihc, ihc-delayed or dihc")),
    }
}

fn main() -> Result<(), String> {
    // `cargo bench` appends `--bench`; the probe's arguments are positional.
    let args: Vec<String> = std::env::args().filter(|a| a != "--bench").collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.into());
    let number = |i: usize, default: &str, what: &str| {
        arg(i, default)
            .parse::<usize>()
            .map_err(|e| format!("{what}: {e}"))
    };
    let kind = arg(1, "ihc");
    let precision = arg(2, "f32");
    // Bounded before allocating: at most 65 536 channels, 10^6 ticks, 10^7 channel-steps.
    let channels = number(3, "4096", "channels")?.clamp(1, 65_536);
    let ticks = number(4, "200", "ticks")?.clamp(1, 1_000_000);
    if channels.saturating_mul(ticks) > 10_000_000 {
        return Err(format!("{channels} x {ticks} channel-steps: at most 10^7"));
    }
    let repeats = number(5, "9", "repeats")?.clamp(1, 1000);
    let parts = number(6, "2", "parts")?.clamp(1, 64);
    match precision.as_str() {
        "f64" => probe::<f64>(&kind, channels, ticks, repeats, parts),
        "f32" => probe::<f32>(&kind, channels, ticks, repeats, parts),
        other => Err(format!("precision {other}: f32 or f64")),
    }
}
