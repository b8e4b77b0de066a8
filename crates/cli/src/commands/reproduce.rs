//! `hystcomp reproduce`: section 4 of the paper on the simulated stage (or a stage file), with
//! Table 3, the figures and the HTML report.

use std::path::PathBuf;

use hystcomp_experiments::study::StudyObserver;
use hystcomp_experiments::{RunMeta, StudyOptions, run_study, summarize, write_outputs};
use hystcomp_stage::StageConfig;
use serde::Serialize;

use crate::progress::Bar;
use crate::{CliError, Context};

/// Arguments of `hystcomp reproduce`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Stage file (TOML); the built-in default stage without it.
    #[arg(long, value_name = "FILE")]
    stage: Option<PathBuf>,
    /// Directory for the report, the figures and the identified models.
    #[arg(long, default_value = "report", value_name = "DIR")]
    out: PathBuf,
    /// Seed of the stage noise (identification run; the tracking runs use seed + 1) and of the
    /// particle swarm.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Particle swarm iterations of the `paper` pipeline.
    #[arg(long, default_value_t = hystcomp_experiments::study::STUDY_PSO_ITERATIONS)]
    pso_iterations: usize,
    /// Particles of the `paper` pipeline's swarm.
    #[arg(long, default_value_t = 40)]
    pso_particles: usize,
    /// Periods of the paper's trajectory to track (10 s each; indices on the last).
    #[arg(long, default_value_t = 2)]
    periods: usize,
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

/// Runs `hystcomp reproduce`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    let stage = match &args.stage {
        Some(path) => StageConfig::from_toml_file(path)?,
        None => StageConfig::default(),
    };
    let mut options = StudyOptions {
        stage,
        seed: args.seed,
        pso_seed: args.seed,
        periods: args.periods,
        ..StudyOptions::default()
    };
    options.pso.iterations = args.pso_iterations;
    options.pso.particles = args.pso_particles;
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
        print!("{summary}");
        println!(
            "report: {} (figures, models/ and study.json beside it); {:.1} s",
            files.report.display(),
            study.elapsed_s
        );
    }
    Ok(())
}
