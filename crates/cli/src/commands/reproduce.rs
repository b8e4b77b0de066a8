//! `hystcomp reproduce`: section 4 of the paper on the simulated stage (or a stage file), with
//! Table 3, the figures and the HTML report.

use std::path::PathBuf;

use hystcomp_experiments::study::{MAX_STUDY_PERIODS, STUDY_PSO_ITERATIONS, StudyObserver};
use hystcomp_experiments::{RunMeta, StudyOptions, run_study, summarize, write_outputs};
use hystcomp_stage::StageConfig;
use serde::Serialize;

use crate::files::{Files, NamesFiles};
use crate::progress::Bar;
use crate::{CliError, Context};

/// Arguments of `hystcomp reproduce`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Stage file (TOML); the built-in default stage without it.
    #[arg(long, value_name = "FILE")]
    stage: Option<PathBuf>,
    /// Directory for the report, the figures and the identified models.
    #[arg(
        short = 'o',
        long = "output",
        alias = "out",
        default_value = "report",
        value_name = "DIR"
    )]
    out: PathBuf,
    /// Seed of the stage noise (identification run; the tracking runs use seed + 1) and of the
    /// particle swarm [default: the stage file's `seed`, 1 for the built-in stage].
    #[arg(long)]
    seed: Option<u64>,
    /// Particle swarm iterations of the `paper` pipeline (1 to 100000).
    #[arg(long, default_value_t = STUDY_PSO_ITERATIONS)]
    pso_iterations: usize,
    /// Particles of the `paper` pipeline's swarm (2 to 1000).
    #[arg(long, default_value_t = hystcomp_identify::DEFAULT_PARTICLES)]
    pso_particles: usize,
    /// Exit with status 0 even when an acceptance check fails (by default such a run writes
    /// everything, then exits with status 5).
    #[arg(long)]
    no_check: bool,
    /// Periods of the paper's trajectory to track (10 s each; indices on the last; 2 to 20).
    #[arg(long, default_value_t = 2)]
    periods: usize,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .stage("--stage", self.stage.as_ref())
            .output_directory("--output", &self.out)
    }
}

/// An observer drawing one progress bar per step of the study.
struct Bars {
    bar: Option<Bar>,
}

impl StudyObserver for Bars {
    fn begin(&mut self, step: &str, total: u64) {
        self.bar = Some(Bar::new(step, total));
    }
    fn advance(&mut self, done: u64) {
        if let Some(bar) = &self.bar {
            bar.set_position(done);
        }
    }
    fn end(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish();
        }
    }
}

#[derive(Serialize)]
struct Output<'a> {
    #[serde(flatten)]
    summary: &'a hystcomp_experiments::StudySummary,
    out_dir: String,
    report: String,
}

/// `git describe` of the sources this binary was built from, when the build could tell.
fn git_description() -> Option<String> {
    option_env!("HYSTCOMP_GIT_DESCRIBE").map(str::to_owned)
}

/// Now, as RFC 3339 UTC, from the system clock (the study itself reads no clock).
fn now_rfc3339() -> String {
    humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string()
}

/// Most particle swarm iterations `--pso-iterations` accepts (the library's bound).
const MAX_PSO_ITERATIONS: usize = hystcomp_identify::MAX_ITERATIONS;
/// Most particles `--pso-particles` accepts (the library's bound).
const MAX_PSO_PARTICLES: usize = hystcomp_identify::MAX_PARTICLES;

/// Refuses options the study cannot use, with the flag named and the accepted range.
fn check_args(args: &Args) -> Result<(), CliError> {
    if !(2..=MAX_STUDY_PERIODS).contains(&args.periods) {
        return Err(CliError::input(format!(
            "--periods {}: give 2 to {MAX_STUDY_PERIODS} periods (the indices use the last full \
             one, so the default 2 is enough; each period adds 10 s of simulation to every \
             tracking run)",
            args.periods
        )));
    }
    if !(1..=MAX_PSO_ITERATIONS).contains(&args.pso_iterations) {
        return Err(CliError::input(format!(
            "--pso-iterations {}: give 1 to {MAX_PSO_ITERATIONS} iterations (the study's \
             default is {STUDY_PSO_ITERATIONS})",
            args.pso_iterations
        )));
    }
    if !(2..=MAX_PSO_PARTICLES).contains(&args.pso_particles) {
        return Err(CliError::input(format!(
            "--pso-particles {}: give 2 to {MAX_PSO_PARTICLES} particles (the study's default \
             is {})",
            args.pso_particles,
            hystcomp_identify::DEFAULT_PARTICLES
        )));
    }
    Ok(())
}

/// Runs `hystcomp reproduce`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    check_args(args)?;
    let stage = match &args.stage {
        Some(path) => StageConfig::from_toml_file(path).map_err(|e| match e {
            // An unreadable stage file already names itself.
            hystcomp_stage::StageError::Io { .. } => CliError::input(e.to_string()),
            _ => CliError::input(e.to_string()).context(path.display()),
        })?,
        None => StageConfig::default(),
    };
    let seed = args.seed.unwrap_or(stage.seed);
    let mut options = StudyOptions {
        stage,
        seed,
        pso_seed: seed,
        periods: args.periods,
        ..StudyOptions::default()
    };
    options.pso.iterations = args.pso_iterations;
    options.pso.particles = args.pso_particles;
    // The stage's rate decides how long the study's runs are: refused before anything is
    // simulated, naming the stage file.
    hystcomp_experiments::study::check_run_lengths(&options).map_err(|e| {
        let error = CliError::input(e.to_string());
        match &args.stage {
            Some(path) => error.context(path.display()),
            None => error,
        }
    })?;
    // The output folder before the study's seconds of work: a path that names a file, or a
    // folder that cannot be made, is said at once.
    std::fs::create_dir_all(&args.out).map_err(|e| {
        CliError::output(format!(
            "cannot make the output folder {}: {e}",
            args.out.display()
        ))
    })?;
    let mut bars = Bars { bar: None };
    let study = run_study(&options, &mut bars)?;
    let meta = RunMeta {
        generated_at: now_rfc3339(),
        git_description: git_description(),
        command_line: Some(std::env::args().collect::<Vec<_>>().join(" ")),
    };
    let files = write_outputs(&study, &args.out, &meta, &mut bars)
        .map_err(|e| CliError::output(e.to_string()))?;
    let summary = summarize(&study);
    if ctx.json {
        let output = Output {
            summary: &summary,
            out_dir: args.out.display().to_string(),
            report: files.report.display().to_string(),
        };
        crate::print_json(&output)?;
    } else {
        out!("{summary}")?;
        outln!(
            "report: {} (figures, models/ and study.json beside it); study computed in {:.1} s",
            files.report.display(),
            study.elapsed_s
        )?;
    }
    let missed: Vec<String> = summary
        .acceptance
        .iter()
        .filter(|c| !c.passed)
        .map(|c| {
            format!(
                "{} = {} % (bound {})",
                c.what,
                crate::number(c.value),
                c.bound
            )
        })
        .collect();
    if !missed.is_empty() && !args.no_check {
        return Err(CliError::with_code(
            format!(
                "{} of {} acceptance checks failed ({}); the report is written; --no-check \
                 exits 0",
                missed.len(),
                summary.acceptance.len(),
                missed.join("; ")
            ),
            crate::error::EXIT_CHECK_FAILED,
        ));
    }
    Ok(())
}
