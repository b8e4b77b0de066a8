//! `hystcomp bench --channels C,...`: the cost per channel-step of the compensator banks
//! (issue 16): `C` channels of ten operators, each its own model (Table 1 or 2 of the paper,
//! weights scaled by a factor of its own in [0.9, 1.1]) and its own phase of the paper's
//! trajectory, stepped tick after tick.
//!
//! Each figure is the median over repeated runs of a whole signal, divided by its ticks times
//! its channels, on the wall clock or (`--clock thread-cpu`) the timing thread's CPU time, for
//! the compilation of the kernels the banks take (`--vector-path best`) or each the processor
//! has (`--vector-path all`). The criterion benches (`cargo bench -p hystcomp-core --bench
//! bank`) measure the same with statistics.

use std::hint::black_box;

use hystcomp_core::{
    CompensatorBank, DihcBank, Heap, IhcBank, OutputLimits, Real, SolveMode, VectorPath, WihcBank,
    paper::bank_workload, with_vector_path,
};
use serde::Serialize;

use super::bench::time;
use super::clock::Clock;
use crate::{CliError, Context};

/// Most channels per bank (`--channels`), as many as a model set may hold.
pub const MAX_BENCH_CHANNELS: usize = hystcomp_io::bank::MAX_CHANNELS;

/// Operators of every channel.
const OPERATORS: usize = bank_workload::OPERATORS;

/// The compilations of the bank kernels `--vector-path` times
/// ([`hystcomp_core::VectorPath`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PathChoice {
    /// The widest the processor has: what the banks take by default.
    Best,
    /// Each the processor has, one after the other (baseline, AVX2, AVX-512).
    All,
    /// The target's baseline (SSE2 on x86-64).
    Baseline,
    /// AVX2.
    Avx2,
    /// AVX-512 (F, VL, BW, DQ).
    Avx512,
}

impl PathChoice {
    /// The paths to time; refuses one the processor lacks.
    fn paths(self) -> Result<Vec<VectorPath>, CliError> {
        let one = |path: VectorPath, name: &str| {
            if path.available() {
                Ok(vec![path])
            } else {
                Err(CliError::input(format!(
                    "--vector-path {name}: this processor cannot run it \
                     (--vector-path all times each it can)"
                )))
            }
        };
        match self {
            PathChoice::Best => Ok(vec![VectorPath::current()]),
            PathChoice::All => Ok([VectorPath::Baseline, VectorPath::Avx2, VectorPath::Avx512]
                .into_iter()
                .filter(|p| p.available())
                .collect()),
            PathChoice::Baseline => one(VectorPath::Baseline, "baseline"),
            PathChoice::Avx2 => one(VectorPath::Avx2, "avx2"),
            PathChoice::Avx512 => one(VectorPath::Avx512, "avx512"),
        }
    }
}

/// The name of a path in the report.
fn path_name(path: VectorPath) -> &'static str {
    match path {
        VectorPath::Best => "best",
        VectorPath::Baseline => "baseline",
        VectorPath::Avx2 => "avx2",
        VectorPath::Avx512 => "avx512",
    }
}

/// How `hystcomp bench --channels` times.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// About this many channel-steps per timed run (at least 50 ticks).
    pub samples: usize,
    /// Timed runs per figure (the median is reported).
    pub repeats: usize,
    /// What the figures are measured in (`--clock`).
    pub clock: Clock,
    /// The compilations of the kernels to time (`--vector-path`).
    pub path: PathChoice,
}

/// One measured figure.
#[derive(Debug, Clone, Serialize)]
struct Figure {
    /// `ihc`, `ihc-delayed`, `ihc-guarded`, `wihc`, `wihc-delayed`, `wihc-guarded` or `dihc`.
    what: &'static str,
    /// The compilation of the kernels: `baseline`, `avx2` or `avx512`.
    vector_path: &'static str,
    channels: usize,
    operators: usize,
    /// `f64` or `f32`.
    precision: &'static str,
    /// Ticks per timed run.
    ticks: usize,
    /// Median cost per channel-step, ns.
    median_ns_per_channel_step: f64,
    /// Fastest run, ns per channel-step.
    min_ns_per_channel_step: f64,
}

#[derive(Debug, Serialize)]
struct Report {
    repeats: usize,
    clock: Clock,
    figures: Vec<Figure>,
}

/// Times every bank kind for `channels` channels in `T`, on each of `paths`.
fn bank<T: Real>(
    figures: &mut Vec<Figure>,
    channels: usize,
    options: Options,
    paths: &[VectorPath],
    precision: &'static str,
) -> Result<(), CliError> {
    // At least 50 ticks, and about `samples` channel-steps per run.
    let ticks = (options.samples / channels).max(50);
    // The channels and signal of the core's bank benches.
    let (plants, inverses) = bank_workload::channel_models::<T>(channels)?;
    let desired = bank_workload::signal(&plants, ticks)?;
    let mut control = vec![T::zero(); desired.len()];
    let limits = [OutputLimits::new(T::zero(), T::one())?];
    let bank_error = |e: hystcomp_core::BankError| CliError::input(e.to_string());
    // The plain delayed loops are timed even where their loop gain is 1 or more (Table 1's
    // WIHC: 1.66), as the single-channel figures are: the signal rises from rest.
    let unchecked = SolveMode::DelayedAllowUnstable;
    let guarded = SolveMode::DelayedGuarded;
    let banks: [(&'static str, Box<dyn CompensatorBank<T>>); 7] = [
        (
            "ihc",
            Box::new(
                IhcBank::<T, Heap>::new(&plants, &limits, SolveMode::Exact).map_err(bank_error)?,
            ),
        ),
        (
            "ihc-delayed",
            Box::new(IhcBank::<T, Heap>::new(&plants, &limits, unchecked).map_err(bank_error)?),
        ),
        (
            "ihc-guarded",
            Box::new(IhcBank::<T, Heap>::new(&plants, &limits, guarded).map_err(bank_error)?),
        ),
        (
            "wihc",
            Box::new(
                WihcBank::<T, Heap>::new(&plants, &limits, SolveMode::Exact).map_err(bank_error)?,
            ),
        ),
        (
            "wihc-delayed",
            Box::new(WihcBank::<T, Heap>::new(&plants, &limits, unchecked).map_err(bank_error)?),
        ),
        (
            "wihc-guarded",
            Box::new(WihcBank::<T, Heap>::new(&plants, &limits, guarded).map_err(bank_error)?),
        ),
        (
            "dihc",
            Box::new(
                DihcBank::<T, Heap>::new(&inverses, &[(T::zero(), T::one())], &limits)
                    .map_err(bank_error)?,
            ),
        ),
    ];
    for (what, mut b) in banks {
        for &path in paths {
            let (median, min) = with_vector_path(path, || {
                time(options.clock, ticks * channels, options.repeats, || {
                    b.reset();
                    b.process(black_box(&desired), &mut control)
                        .expect("a whole number of ticks");
                })
            });
            figures.push(Figure {
                what,
                vector_path: path_name(path),
                channels,
                operators: OPERATORS,
                precision,
                ticks,
                median_ns_per_channel_step: median,
                min_ns_per_channel_step: min,
            });
        }
    }
    Ok(())
}

/// Runs `hystcomp bench --channels ...`: every bank kind for every channel count, f64 and f32.
pub fn run(channels: &[usize], options: Options, ctx: Context) -> Result<(), CliError> {
    for &c in channels {
        crate::bounds::count(
            "--channels",
            c,
            1..=MAX_BENCH_CHANNELS,
            "channels per bank (e.g. --channels 1,8,64,1024,4096)",
        )?;
    }
    let paths = options.path.paths()?;
    let mut figures = Vec::new();
    for &c in channels {
        bank::<f64>(&mut figures, c, options, &paths, "f64")?;
        bank::<f32>(&mut figures, c, options, &paths, "f32")?;
    }
    let repeats = options.repeats;
    let report = Report {
        repeats,
        clock: options.clock,
        figures,
    };
    if ctx.json {
        crate::print_json(&report)?;
        return Ok(());
    }
    outln!(
        "bank cost per channel-step, ns of {} time ({OPERATORS} operators, each channel its own \
         model; median of {repeats} runs, fastest in brackets)",
        options.clock.name()
    )?;
    outln!(
        "{:<14} {:>9} {:>9} {:>22} {:>22}",
        "",
        "path",
        "channels",
        "f64",
        "f32"
    )?;
    let mut rows: Vec<(&str, &str, usize)> = Vec::new();
    for f in &report.figures {
        let key = (f.what, f.vector_path, f.channels);
        if !rows.contains(&key) {
            rows.push(key);
        }
    }
    for (what, path, c) in rows {
        let cell = |precision: &str| {
            report
                .figures
                .iter()
                .find(|f| {
                    f.what == what
                        && f.vector_path == path
                        && f.channels == c
                        && f.precision == precision
                })
                .map(|f| {
                    format!(
                        "{:.2} ({:.2})",
                        f.median_ns_per_channel_step, f.min_ns_per_channel_step
                    )
                })
                .unwrap_or_else(|| "-".into())
        };
        outln!(
            "{:<14} {:>9} {:>9} {:>22} {:>22}",
            what,
            path,
            c,
            cell("f64"),
            cell("f32")
        )?;
    }
    Ok(())
}
