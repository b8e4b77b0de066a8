//! `hystcomp bench`: the per-sample cost of the forward MPIM and of every compensator, so a
//! user can check the budget of their control loop on their own machine.
//!
//! Each figure is the median over repeated runs of a whole trajectory, divided by its length.
//! The criterion benches (`cargo bench -p hystcomp-core`) measure the same with statistics.

use std::hint::black_box;
use std::path::PathBuf;

use hystcomp_core::{
    ChainCompensator, Compensator, CreepInverse, Dihc, Ihc, Mpim, OutputLimits, Real, SolveMode,
    VibrationInverse, Wihc, paper,
};
use hystcomp_experiments::Reference;
use hystcomp_io::compensator::{Method, ScaledCompensator};
use hystcomp_io::model_file::{Direction, ModelFile};
use serde::Serialize;

use super::clock::Clock;
use crate::files::{Files, NamesFiles};
use crate::{CliError, Context};

/// Arguments of `hystcomp bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Samples per timed run (100 to 1000000).
    #[arg(long, default_value_t = 20_000)]
    samples: usize,
    /// Timed runs per figure, 1 to 1000 (the median is reported).
    #[arg(long, default_value_t = 15)]
    repeats: usize,
    /// Also time this model file (its own operator count): a plant model times the forward
    /// model, IHC and WIHC; an inverse model times DIHC; with creep or vibration links, also
    /// the whole chain around IHC or DIHC. Not with --channels.
    #[arg(long, value_name = "FILE")]
    model: Option<PathBuf>,
    /// Time the compensator banks instead, for these channel counts (comma-separated, each 1
    /// to 65536, e.g. 1,8,64,1024,4096): cost per channel-step of every method, f64 and f32.
    #[arg(long, value_name = "C,...", value_delimiter = ',')]
    channels: Option<Vec<usize>>,
    /// What the figures are measured in: `wall` time, or `thread-cpu`, the CPU time of the
    /// timing thread alone (Linux), steadier on a machine shared with other work.
    #[arg(long, value_enum, default_value_t = Clock::Wall)]
    clock: Clock,
    /// With `--channels`: the compilation of the bank kernels to time (`best`, the widest the
    /// processor has, as the banks take by default; `all`, each the processor has, one after
    /// the other).
    #[arg(long, value_enum, default_value_t = super::bench_bank::PathChoice::Best)]
    vector_path: super::bench_bank::PathChoice,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new().maybe_input("--model", self.model.as_ref())
    }
}

/// Most samples per timed run (`--samples`): each figure holds a few signals of this length.
const MAX_SAMPLES: usize = 1_000_000;

/// Most timed runs per figure (`--repeats`).
const MAX_REPEATS: usize = 1_000;

/// Most work of one bench: samples (channel-steps for the banks) times repeats, summed over
/// the channel counts, per figure: about a minute or two of timing on a desktop processor.
const MAX_WORK: usize = 100_000_000;

/// Most channel counts in one `--channels` list.
const MAX_CHANNEL_COUNTS: usize = 32;

/// Refuses a `--channels` list longer than [`MAX_CHANNEL_COUNTS`], or whose channel-steps
/// (at least 50 ticks of each count, as `bench_bank` runs them) times `repeats` exceed
/// [`MAX_WORK`]. Each count's own range is `bench_bank`'s to check.
fn bounds_work(channels: &[usize], samples: usize, repeats: usize) -> Result<(), CliError> {
    crate::bounds::count(
        "--channels (the number of channel counts)",
        channels.len(),
        1..=MAX_CHANNEL_COUNTS,
        "",
    )?;
    let steps = channels
        .iter()
        .map(|&c| samples.max(c.saturating_mul(50)))
        .fold(0usize, usize::saturating_add)
        .saturating_mul(repeats);
    if steps > MAX_WORK {
        return Err(CliError::input(format!(
            "--channels with --samples {samples} and --repeats {repeats} is {steps} channel-steps \
             per figure (at least 50 ticks of each count), more than the {MAX_WORK} one bench \
             takes; give fewer channel counts, samples or repeats"
        )));
    }
    Ok(())
}

/// The preview of the reference chain's vibration inverse, samples (as a streaming user would
/// choose: a few samples of latency; see `hystcomp_core::reference`).
const CHAIN_PREVIEW: usize = 8;

/// One measured figure.
#[derive(Debug, Clone, Serialize)]
struct Figure {
    /// `mpim-forward` (a whole signal: consecutive samples overlap in the processor),
    /// `mpim-chained` (each input waits for the previous output, as in a control loop),
    /// `ihc`, `ihc-delayed`, `ihc-guarded`, `wihc`, `wihc-delayed`, `wihc-guarded` or `dihc`;
    /// for the built-in models also the chain's links (`creep-inverse`, `vibration-inverse`,
    /// each alone, per sample) and `chain-ihc` (vibration inverse with a preview of 8 samples,
    /// creep inverse and exact IHC: the links of `hystcomp_core::reference`); for a model file
    /// with creep or vibration parts, `chain-ihc` (a plant model) or `chain-dihc` (an inverse
    /// model) with its own links (the preview an offline inversion needs).
    what: &'static str,
    /// Where the model came from: `table1` / `table2` spread over `operators`, or the file.
    model: String,
    operators: usize,
    /// `f64` or `f32`.
    precision: &'static str,
    /// Median cost per sample, ns.
    median_ns_per_sample: f64,
    /// Fastest run, ns per sample.
    min_ns_per_sample: f64,
}

#[derive(Debug, Serialize)]
struct Report {
    samples: usize,
    repeats: usize,
    clock: Clock,
    figures: Vec<Figure>,
}

/// Median and minimum of `repeats` timed runs of `run` on `clock`, in ns per sample.
pub(super) fn time(
    clock: Clock,
    samples: usize,
    repeats: usize,
    mut run: impl FnMut(),
) -> (f64, f64) {
    run(); // warm up caches and branch predictors
    let mut per_sample: Vec<f64> = (0..repeats)
        .map(|_| {
            let start = clock.start();
            run();
            start.seconds() * 1e9 / samples as f64
        })
        .collect();
    per_sample.sort_by(f64::total_cmp);
    (per_sample[per_sample.len() / 2], per_sample[0])
}

/// One period of the paper's trajectory (section 4.3) as normalised voltages, through `plant`:
/// every desired sample is reachable. The trajectory is mapped onto 0.1 .. 0.9 and multiplied by
/// a half-cosine ramp from 0 to 1 over its first tenth, so the voltage starts at rest (0), rises
/// smoothly as a stage starts, and stays within 0.1 .. 0.9 after the first tenth (0 .. 0.9
/// overall). No compensator starts with a jump, after which a delayed WIHC with a loop gain
/// above 1 rings for a while. Returns the voltages and the desired positions.
fn trajectory<T: Real>(plant: &Mpim<T, Vec<T>>, samples: usize) -> (Vec<T>, Vec<T>) {
    let reference = Reference::paper();
    let [lo, hi] = reference.trajectory.range_um;
    let rate_hz = samples as f64 / reference.trajectory.period_s;
    let (_, positions) = reference.trajectory().sample(rate_hz, samples);
    let rise_samples = (samples / 10).max(1) as f64;
    let mut p = plant.clone();
    let volts: Vec<T> = positions
        .iter()
        .enumerate()
        .map(|(k, y)| {
            let rise =
                0.5 - 0.5 * (std::f64::consts::PI * (k as f64 / rise_samples).min(1.0)).cos();
            T::from_f64(rise * (0.1 + 0.8 * (y - lo) / (hi - lo)))
        })
        .collect();
    let desired = volts.iter().map(|&v| p.step(v)).collect();
    (volts, desired)
}

struct Bench {
    samples: usize,
    repeats: usize,
    clock: Clock,
    figures: Vec<Figure>,
}

impl Bench {
    fn record(
        &mut self,
        what: &'static str,
        model: &str,
        operators: usize,
        precision: &'static str,
        run: impl FnMut(),
    ) {
        let (median, min) = time(self.clock, self.samples, self.repeats, run);
        self.figures.push(Figure {
            what,
            model: model.to_string(),
            operators,
            precision,
            median_ns_per_sample: median,
            min_ns_per_sample: min,
        });
    }

    fn plant<T: Real>(
        &mut self,
        name: &str,
        plant: &Mpim<T, Vec<T>>,
        precision: &'static str,
        reference_chain: bool,
    ) -> Result<(), CliError> {
        let n = plant.len();
        let (volts, desired) = trajectory(plant, self.samples);
        let mut out = vec![T::zero(); self.samples];
        let mut forward = plant.clone();
        self.record("mpim-forward", name, n, precision, || {
            forward.reset();
            forward
                .process(black_box(&volts), &mut out)
                .expect("equal lengths");
        });
        // Each input waiting for the previous output, as in a control loop (and as each
        // compensator's solve waits for its previous sample): the step's latency.
        let mut chained = plant.clone();
        let tiny = T::from_f64(1e-30);
        self.record("mpim-chained", name, n, precision, || {
            chained.reset();
            let mut y = T::zero();
            for (x, o) in volts.iter().zip(out.iter_mut()) {
                y = chained.step(*x + tiny * y);
                *o = y;
            }
            black_box(&out);
        });
        let limits = OutputLimits::new(T::zero(), T::one())?;
        // The plain delayed loops are timed even where their loop gain is 1 or more (Table 1's
        // WIHC: 1.66): the trajectory rises from rest, so they track without ringing.
        let unchecked = SolveMode::DelayedAllowUnstable;
        let guarded = SolveMode::DelayedGuarded;
        let compensators: [(&'static str, Box<dyn Compensator<T>>); 6] = [
            (
                "ihc",
                Box::new(Ihc::<T, Vec<T>>::new(plant, limits, SolveMode::Exact)?),
            ),
            (
                "ihc-delayed",
                Box::new(Ihc::<T, Vec<T>>::new(plant, limits, unchecked)?),
            ),
            (
                "ihc-guarded",
                Box::new(Ihc::<T, Vec<T>>::new(plant, limits, guarded)?),
            ),
            (
                "wihc",
                Box::new(Wihc::<T, Vec<T>>::new(plant, limits, SolveMode::Exact)?),
            ),
            (
                "wihc-delayed",
                Box::new(Wihc::<T, Vec<T>>::new(plant, limits, unchecked)?),
            ),
            (
                "wihc-guarded",
                Box::new(Wihc::<T, Vec<T>>::new(plant, limits, guarded)?),
            ),
        ];
        for (what, mut c) in compensators {
            self.record(what, name, n, precision, || {
                c.reset();
                c.process(black_box(&desired), &mut out)
                    .expect("equal lengths");
            });
        }
        if !reference_chain {
            return Ok(());
        }
        // The chain (hystcomp_core::reference): each link, then the whole chain around the
        // exact IHC, streaming with a preview of 8 samples.
        let links = hystcomp_core::reference::chain_links::<T>();
        let mut creep: CreepInverse<T, Vec<T>> = CreepInverse::new(
            &links.time_constants_s,
            &links.weights,
            T::zero(),
            links.period_s,
        )?;
        self.record("creep-inverse", name, n, precision, || {
            creep.reset();
            for (y, o) in desired.iter().zip(out.iter_mut()) {
                *o = creep.step(black_box(*y));
            }
        });
        let vibration = || {
            VibrationInverse::<T, Vec<T>>::new(
                &links.numerator,
                &links.denominator,
                links.delay,
                CHAIN_PREVIEW,
            )
        };
        let mut inverse = vibration()?;
        self.record("vibration-inverse", name, n, precision, || {
            inverse.reset();
            for (y, o) in desired.iter().zip(out.iter_mut()) {
                *o = inverse.step(black_box(*y));
            }
        });
        let mut chain: ChainCompensator<T, Vec<T>, _> = ChainCompensator::new(
            Some(vibration()?),
            Some(creep.clone()),
            Ihc::<T, Vec<T>>::new(plant, limits, SolveMode::Exact)?,
        );
        self.record("chain-ihc", name, n, precision, || {
            chain.reset();
            chain
                .process(black_box(&desired), &mut out)
                .expect("equal lengths");
        });
        Ok(())
    }

    /// The chain of a model file with creep or vibration parts around the exact IHC (a plant
    /// model) or DIHC (an inverse model), in the file's physical units: for IHC the bench's
    /// trajectory mapped onto the plant's output scale, for DIHC the inverse bench's desired
    /// positions onto the inverse model's input scale.
    fn file_chain(
        &mut self,
        name: &str,
        file: &ModelFile,
        model: &Mpim<f64, Vec<f64>>,
    ) -> Result<(), CliError> {
        let (method, figure, desired): (_, _, Vec<f64>) = match file.direction {
            Direction::Plant => {
                let (_, desired) = trajectory(model, self.samples);
                let desired = desired
                    .iter()
                    .map(|&y| file.output_to_physical(y))
                    .collect();
                (Method::Ihc, "chain-ihc", desired)
            }
            Direction::Inverse => (
                Method::Dihc,
                "chain-dihc",
                (0..self.samples)
                    .map(|k| file.input.to_physical(0.5 + 0.45 * (k as f64 * 6e-4).sin()))
                    .collect(),
            ),
        };
        let mut out = vec![0.0; self.samples];
        let mut chain = ScaledCompensator::new(file, method, None)?;
        self.record(figure, name, model.len(), "f64", || {
            chain.reset();
            for (y, o) in desired.iter().zip(out.iter_mut()) {
                *o = chain.step(black_box(*y));
            }
        });
        Ok(())
    }

    fn inverse<T: Real>(
        &mut self,
        name: &str,
        inverse: &Mpim<T, Vec<T>>,
        precision: &'static str,
    ) -> Result<(), CliError> {
        let n = inverse.len();
        let desired: Vec<T> = (0..self.samples)
            .map(|k| T::from_f64(0.5 + 0.45 * (k as f64 * 6e-4).sin()))
            .collect();
        let mut out = vec![T::zero(); self.samples];
        let limits = OutputLimits::new(T::from_f64(-1.0), T::from_f64(2.0))?;
        let mut c = Dihc::<T, Vec<T>>::new(inverse, T::zero(), T::one(), limits)?;
        self.record("dihc", name, n, precision, || {
            c.reset();
            c.process(black_box(&desired), &mut out)
                .expect("equal lengths");
        });
        Ok(())
    }
}

/// Runs `hystcomp bench`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    crate::bounds::count(
        "--samples",
        args.samples,
        100..=MAX_SAMPLES,
        "samples per timed run (the default is 20000)",
    )?;
    crate::bounds::count(
        "--repeats",
        args.repeats,
        1..=MAX_REPEATS,
        "timed runs (the default is 15)",
    )?;
    args.clock.check()?;
    if let Some(channels) = &args.channels {
        if let Some(model) = &args.model {
            return Err(CliError::input(format!(
                "--model {} with --channels: the banks are timed on the built-in channel \
                 models, not a model file; time the file without --channels",
                model.display()
            )));
        }
        bounds_work(channels, args.samples, args.repeats)?;
        let options = super::bench_bank::Options {
            samples: args.samples,
            repeats: args.repeats,
            clock: args.clock,
            path: args.vector_path,
        };
        return super::bench_bank::run(channels, options, ctx);
    }
    if args.vector_path != super::bench_bank::PathChoice::Best {
        return Err(CliError::input(
            "--vector-path times the compensator banks: give --channels too",
        ));
    }
    let user_model = args.model.as_deref().map(ModelFile::load).transpose()?;
    // Each figure's work grows with the operators beyond the built-in 100.
    let operators = user_model.as_ref().map_or(0, |m| m.thresholds.len());
    let per_sample = operators.div_ceil(100).max(1);
    let work = args
        .samples
        .saturating_mul(args.repeats)
        .saturating_mul(per_sample);
    if work > MAX_WORK {
        return Err(CliError::input(format!(
            "--samples {} x --repeats {}{} is {work} sample-runs per figure, more than the \
             {MAX_WORK} one bench takes (hours of timing); give fewer samples or repeats",
            args.samples,
            args.repeats,
            if per_sample > 1 {
                format!(" x {per_sample} (the model's {operators} operators, per 100)")
            } else {
                String::new()
            },
        )));
    }
    let mut bench = Bench {
        samples: args.samples,
        repeats: args.repeats,
        clock: args.clock,
        figures: Vec::new(),
    };
    for n in [10, 100] {
        let name = if n == 10 {
            "table1".to_string()
        } else {
            format!("table1 spread over {n}")
        };
        bench.plant::<f64>(&name, &paper::TABLE1.spread(n)?, "f64", true)?;
        bench.plant::<f32>(&name, &paper::TABLE1.spread(n)?, "f32", true)?;
        let name = name.replace("table1", "table2");
        bench.inverse::<f64>(&name, &paper::TABLE2.spread(n)?, "f64")?;
        bench.inverse::<f32>(&name, &paper::TABLE2.spread(n)?, "f32")?;
    }
    if let (Some(file), Some(path)) = (&user_model, &args.model) {
        let name = path.display().to_string();
        let model = file.model()?;
        match file.direction {
            Direction::Plant => {
                bench
                    .plant::<f64>(&name, &model, "f64", false)
                    .map_err(|e| {
                        e.context(format!("{name} (the model must be invertible on [0, 1])"))
                    })?;
                if file.has_links() {
                    bench.file_chain(&name, file, &model)?;
                }
            }
            Direction::Inverse => {
                bench.inverse::<f64>(&name, &model, "f64")?;
                if file.has_links() {
                    bench.file_chain(&name, file, &model)?;
                }
            }
        }
    }
    let report = Report {
        samples: args.samples,
        repeats: args.repeats,
        clock: args.clock,
        figures: bench.figures,
    };
    if ctx.json {
        crate::print_json(&report)?;
        return Ok(());
    }
    outln!(
        "per-sample cost, ns of {} time (median of {} runs of {} samples; fastest in brackets)",
        report.clock.name(),
        report.repeats,
        report.samples
    )?;
    outln!("{:<18} {:>10} {:>22} {:>22}", "", "operators", "f64", "f32")?;
    let mut rows: Vec<(&str, String, usize)> = Vec::new();
    for f in &report.figures {
        let key = (f.what, f.model.clone(), f.operators);
        if !rows.contains(&key) {
            rows.push(key);
        }
    }
    for (what, model, n) in rows {
        let cell = |precision: &str| {
            report
                .figures
                .iter()
                .find(|f| {
                    f.what == what
                        && f.model == model
                        && f.operators == n
                        && f.precision == precision
                })
                .map(|f| format!("{:.1} ({:.1})", f.median_ns_per_sample, f.min_ns_per_sample))
                .unwrap_or_else(|| "-".into())
        };
        outln!(
            "{:<18} {:>10} {:>22} {:>22}   {}",
            what,
            n,
            cell("f64"),
            cell("f32"),
            model
        )?;
    }
    Ok(())
}
