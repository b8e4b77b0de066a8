//! `hystcomp identify`: measured (voltage, displacement) samples in, a model file out.

use hystcomp_core::Shown;
use std::path::{Path, PathBuf};

use hystcomp_identify::{
    IdentifyError, IdentifyOptions, Method, OutputOffset, PsoBounds, PsoOptions, Thresholds,
    Topology, Warmup, identify_observed,
};
use hystcomp_io::data::{self, Column, Delimiter, Header, ReadOptions, RowRange};
use hystcomp_io::model_file::Direction;
use serde::Serialize;

use crate::bounds;
use crate::files::{Files, NamesFiles};
use crate::progress::Bar;
use crate::{CliError, Context};

/// Which columns of a data file to read, and how.
#[derive(Debug, Clone, clap::Args)]
pub struct ColumnArgs {
    /// Column of the drive voltage (the stage's input), by 1-based index or header name (a
    /// variable name, or name:k for column k of a matrix, in a .mat file).
    #[arg(long, alias = "input-column", value_name = "COLUMN")]
    pub voltage_column: Column,
    /// Column of the measured displacement (the stage's output), by 1-based index or name.
    #[arg(long, alias = "output-column", value_name = "COLUMN")]
    pub displacement_column: Column,
    /// Optional time column (s): checked to increase, and used by --warmup-seconds.
    #[arg(long, value_name = "COLUMN")]
    pub time_column: Option<Column>,
    /// Unit of the time column: s, ms or us.
    #[arg(long, value_enum, default_value = "s", value_name = "UNIT")]
    pub time_unit: crate::time_unit::TimeUnit,
    /// Field delimiter of text files: auto, comma, tab, semicolon or whitespace.
    #[arg(long, default_value = "auto")]
    pub delimiter: Delimiter,
    /// Whether text files start with column names: auto, present or absent.
    #[arg(long, default_value = "auto")]
    pub header: Header,
    /// Rows to read, 1-based and inclusive: FIRST..LAST, FIRST.., ..LAST (or FIRST:LAST).
    #[arg(long, value_name = "FIRST..LAST", value_parser = parse_rows)]
    pub rows: Option<RowRange>,
    /// Multiply the voltage column by this to get volts (or --voltage-unit), e.g. 15 for
    /// a 15x amplifier when the column holds the DAC command.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "FACTOR",
        allow_hyphen_values = true
    )]
    pub voltage_factor: f64,
    /// Multiply the displacement column by this to get --displacement-unit, e.g. 10 for a
    /// sensor of 10 um/V.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "FACTOR",
        allow_hyphen_values = true
    )]
    pub displacement_factor: f64,
    /// Unit of the (scaled) voltage, written to the model file.
    #[arg(long, default_value = "V", value_name = "UNIT")]
    pub voltage_unit: String,
    /// Unit of the (scaled) displacement, written to the model file.
    #[arg(long, default_value = "um", value_name = "UNIT")]
    pub displacement_unit: String,
    /// Sample rate (Hz) for --warmup-seconds when there is no time column.
    #[arg(long, value_name = "HZ")]
    pub sample_rate: Option<f64>,
}

/// How the model is identified (shared by `identify` and `crossval`).
#[derive(Debug, Clone, clap::Args)]
pub struct FitArgs {
    /// Solver: ls (constrained least squares, the exact optimum for the thresholds) or pso
    /// (particle swarm, as the paper).
    #[arg(long, default_value = "ls", value_parser = ["ls", "pso"])]
    pub method: String,
    /// Number of play operators n (1 to 1000); thresholds (i - 1)/n of the input range
    /// (eq. (11)). `auto` chooses among 5, 10, 15, 20, 30, 40 and 50 the one whose model
    /// predicts the last 25 % of the record (or --holdout) best, and says which and why.
    #[arg(
        short = 'n',
        long = "operators",
        default_value = "10",
        value_name = "N|auto",
        value_parser = parse_operators
    )]
    pub operators: Operators,
    /// Thresholds given explicitly, comma-separated fractions of the input range in [0, 1),
    /// strictly increasing (instead of -n), e.g. 0,0.1,0.25,0.5.
    #[arg(
        long,
        value_name = "R1,R2,...",
        value_delimiter = ',',
        conflicts_with = "operators"
    )]
    pub thresholds: Option<Vec<f64>>,
    /// Degree of the odd input polynomial g(x) = a2 x + a1 x^3 + c5 x^5 + ... (eq. (3)): 3
    /// (the paper's cubic), 5, 7 or 9. The fit keeps every branch slope g'(x) + b_1 + ... +
    /// b_k >= --margin over the fitted input range, so the model stays invertible. Least
    /// squares only (the particle swarm fits the cubic); not with --creep-elements or
    /// --vibration (the chain fits the cubic).
    #[arg(long, default_value_t = 3, value_name = "D")]
    pub input_degree: usize,
    /// Degree of the output map psi(y) = y - e2 y^2 - ... - eK y^K fitted jointly with the
    /// MPIM, psi(y(t)) = H[v(t)] + c (Kuhnen's modified Prandtl-Ishlinskii structure: asymmetric
    /// loops, inverted analytically): 1 (none, the paper's model) to 5. The fit keeps psi
    /// rising; IHC and WIHC solve for psi(y_d), DIHC maps its output back. The model file
    /// gains an output_map field. Least squares only; with creep, --creep-fit holds.
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub output_map_degree: usize,
    /// Where the play operators' memory at the start comes from, and so which samples are
    /// fitted. auto: up to the first sample where the voltage reaches the record's minimum or
    /// maximum, where the memory becomes known whatever came before (wiping-out). estimate:
    /// every sample fitted, the memory at the first sample estimated with the parameters (as
    /// left by the input coming from one end of the range to a turning point, searched by
    /// least squares); best when the record starts mid-range with a clean response, not with
    /// a transient. A number: that many samples left out (the operators still run over them,
    /// from zero memory). The report says which samples were used and why.
    #[arg(long, default_value = "auto", value_name = "auto|estimate|N", value_parser = parse_warmup)]
    pub warmup: Warmup,
    /// Warm-up in seconds instead (needs --time-column or --sample-rate).
    #[arg(long, value_name = "SECONDS", conflicts_with = "warmup")]
    pub warmup_seconds: Option<f64>,
    /// Output offset of the model (the displacement for a plant model, the voltage for an
    /// inverse one): fit (a fitted constant, for sensors with an arbitrary zero), none (the
    /// output's minimum is its zero) or a value in the output's unit.
    #[arg(long, default_value = "fit", value_name = "fit|none|VALUE", value_parser = parse_offset, allow_hyphen_values = true)]
    pub offset: OutputOffset,
    /// Smallest branch slope the model keeps (normalised: output range per input range).
    #[arg(long, default_value_t = hystcomp_identify::DEFAULT_MARGIN, value_name = "SLOPE")]
    pub margin: f64,
    /// Largest condition number of the column-scaled regressors accepted.
    #[arg(long, default_value_t = hystcomp_identify::DEFAULT_MAX_CONDITION, value_name = "K")]
    pub max_condition: f64,
    /// pso: seed of the random numbers (the result is reproducible).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// pso: number of particles (2 to 1000).
    #[arg(
        long = "pso-particles",
        alias = "particles",
        default_value_t = hystcomp_identify::DEFAULT_PARTICLES,
        value_name = "N"
    )]
    pub particles: usize,
    /// pso: number of iterations (1 to 100000).
    #[arg(
        long = "pso-iterations",
        alias = "iterations",
        default_value_t = hystcomp_identify::DEFAULT_ITERATIONS,
        value_name = "N"
    )]
    pub iterations: usize,
    /// pso: whom each particle follows: ring (the best of itself and its two neighbours,
    /// Bratton & Kennedy's standard swarm) or global (the swarm's best, the 1995 swarm).
    #[arg(long, default_value = "ring", value_name = "ring|global", value_parser = parse_topology)]
    pub pso_topology: Topology,
    /// pso: inertia weight at the first and last iteration, START,END (linear in between;
    /// default 0.7298 throughout, Clerc & Kennedy's constriction; Shi & Eberhart use 0.9,0.4).
    #[arg(long, value_name = "START,END", value_delimiter = ',')]
    pub inertia: Option<Vec<f64>>,
    /// pso: cognitive acceleration c1.
    #[arg(long, default_value_t = hystcomp_identify::CONSTRICTION_ACCELERATION)]
    pub c1: f64,
    /// pso: social acceleration c2.
    #[arg(long, default_value_t = hystcomp_identify::CONSTRICTION_ACCELERATION)]
    pub c2: f64,
    /// pso: velocity clamp, a fraction of each parameter's search width.
    #[arg(long, default_value_t = 0.2, value_name = "FRACTION")]
    pub velocity_clamp: f64,
    /// pso: search bound B: a1, a2 and every b_i in [-B, B] (normalised units: output range
    /// per input range; Tables 1 and 2 of the paper lie within 1.3).
    #[arg(
        long,
        default_value_t = 3.0,
        allow_hyphen_values = true,
        value_name = "B"
    )]
    pub bound: f64,
    /// pso: search bound C of the fitted output offset c (with --offset fit): c in [-C, C],
    /// in output ranges (the offset is relative to the output's minimum, so 1 covers it).
    #[arg(
        long,
        default_value_t = 1.0,
        allow_hyphen_values = true,
        value_name = "C"
    )]
    pub offset_bound: f64,
    /// Write the model even when its RMS fit error exceeds 10 % of the output range, or the
    /// displacement does not rise with the voltage (correlation below 0.5): both are refused
    /// by default, since the columns, factors or offset are probably wrong. The same column
    /// given twice stays refused.
    #[arg(long)]
    pub accept_poor_fit: bool,
    /// Fit a plant model meant for one-sample-delayed compensation (ihc-delayed,
    /// wihc-delayed): both delayed loops' gains, over every number of moving operators and
    /// every drive in the fitted range, are held to at most --delayed-loop-bound, so that
    /// neither loop can oscillate; the report says what it costs in fit RMS. Inverse models
    /// (DIHC) have no delayed loop and ignore it.
    #[arg(long)]
    pub for_delayed: bool,
    /// With --for-delayed: the bound on both delayed loops' gains, in (0, 1).
    #[arg(long, default_value_t = hystcomp_identify::DEFAULT_DELAYED_LOOP_BOUND, value_name = "G")]
    pub delayed_loop_bound: f64,
    /// pso: weight of the constraint violation added to the RMS error.
    #[arg(long, default_value_t = 10.0)]
    pub penalty: f64,
    /// pso: polish the best particle by least squares on the constraints it leaves active.
    #[arg(long)]
    pub polish: bool,
}

/// `-n`: a number of play operators, or `auto` (chosen by held-out error).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Operators {
    /// This many.
    Count(usize),
    /// Chosen by [`hystcomp_identify::select_operators`].
    Auto,
}

fn parse_operators(text: &str) -> Result<Operators, String> {
    let text = text.trim();
    if text.eq_ignore_ascii_case("auto") {
        return Ok(Operators::Auto);
    }
    text.parse()
        .map(Operators::Count)
        .map_err(|_| format!("expected a number of play operators or auto, got {text:?}"))
}

/// The constraints of the fit, for `--help` of `identify` and `crossval`.
pub const CONSTRAINTS_HELP: &str = "\
Constraints of the fit (both solvers): the model is strictly increasing along every branch \
(every branch slope >= --margin over the fitted input range), so that it is invertible. A plant \
model must meet two more, beyond the paper: the play-operator part a2 + b_1 + ... + b_k >= \
margin for every k, so that the analytic inverse of eq. (7) exists (IHC), and |3 a1 x^2 + b_1| \
< a2 with margin over the range, so that the one-sample-delayed WIHC of eq. (9) contracts around \
reversals; after a jump it may still ring when its full loop gain (every number of moving \
operators) exceeds 1, which `hystcomp compensate` refuses. With --for-delayed a plant model also keeps both delayed loops' gains (every number of moving \
operators, every drive) at most --delayed-loop-bound, so that ihc-delayed and wihc-delayed \
cannot oscillate. Fits are refused when the displacement does not rise with the voltage \
(correlation below 0.5), or when the RMS error exceeds 10 % of the output range (both unless \
--accept-poor-fit).";

/// Arguments of `hystcomp identify`.
#[derive(Debug, clap::Args)]
#[command(after_help = CONSTRAINTS_HELP)]
pub struct Args {
    /// Measured record: delimited text (CSV, tab or whitespace separated, with or without a
    /// header) or a MATLAB Level-5 .mat file.
    #[arg(long, value_name = "FILE")]
    pub data: PathBuf,
    #[command(flatten)]
    pub columns: ColumnArgs,
    /// plant: voltage in, displacement out (for IHC and WIHC). inverse: displacement in,
    /// voltage out (for DIHC). The columns are named the same way in both cases.
    #[arg(long, default_value = "plant", value_parser = parse_direction)]
    pub direction: Direction,
    #[command(flatten)]
    pub fit: FitArgs,
    #[command(flatten)]
    pub chain: super::chain_args::ChainArgs,
    /// Fraction of the samples after the warm-up, at the end, held out of the fit and
    /// reported separately, in [0, 1).
    #[arg(
        long,
        default_value_t = 0.2,
        value_name = "FRACTION",
        allow_hyphen_values = true
    )]
    pub holdout: f64,
    /// Where to write the model file (JSON, written atomically).
    #[arg(short, long, value_name = "MODEL.json")]
    pub output: PathBuf,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .input("--data", &self.data)
            .output("--output", &self.output)
    }
}

fn parse_rows(text: &str) -> Result<RowRange, String> {
    let text = if !text.contains("..") {
        text.replacen(':', "..", 1)
    } else {
        text.to_owned()
    };
    text.parse().map_err(|e: data::DataError| e.to_string())
}

fn parse_warmup(text: &str) -> Result<Warmup, String> {
    if text.trim().eq_ignore_ascii_case("auto") {
        return Ok(Warmup::Auto);
    }
    if text.trim().eq_ignore_ascii_case("estimate") {
        return Ok(Warmup::Estimate);
    }
    text.trim()
        .parse::<usize>()
        .map(Warmup::Samples)
        .map_err(|_| format!("expected auto, estimate or a number of samples, got {text:?}"))
}

fn parse_offset(text: &str) -> Result<OutputOffset, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "fit" => Ok(OutputOffset::Fit),
        "none" => Ok(OutputOffset::None),
        other => other
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .map(OutputOffset::Value)
            .ok_or_else(|| format!("expected fit, none or a number, got {text:?}")),
    }
}

fn parse_topology(text: &str) -> Result<Topology, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "ring" => Ok(Topology::Ring),
        "global" => Ok(Topology::Global),
        _ => Err(format!("expected ring or global, got {text:?}")),
    }
}

fn parse_direction(text: &str) -> Result<Direction, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "plant" => Ok(Direction::Plant),
        "inverse" => Ok(Direction::Inverse),
        _ => Err(format!("expected plant or inverse, got {text:?}")),
    }
}

/// One record read from a file.
#[derive(Debug)]
pub struct Loaded {
    /// Voltage samples (scaled by the factor).
    pub voltage: Vec<f64>,
    /// Displacement samples (scaled by the factor).
    pub displacement: Vec<f64>,
    /// Time samples, if a time column was given.
    pub time: Option<Vec<f64>>,
    /// The columns' names as the file gives them.
    pub names: Vec<String>,
}

impl ColumnArgs {
    /// Reads the record `path` with these options' own columns and rows (see [`load`]).
    pub fn load(&self, path: &Path) -> Result<Loaded, CliError> {
        load(
            path,
            self,
            &self.voltage_column,
            &self.displacement_column,
            self.time_column.as_ref(),
            self.rows,
        )
    }
}

/// Reads the voltage, displacement and (optional) time columns of `path`, with the file's
/// name in every message; checks that time increases.
pub fn load(
    path: &Path,
    columns: &ColumnArgs,
    voltage_column: &Column,
    displacement_column: &Column,
    time_column: Option<&Column>,
    rows: Option<RowRange>,
) -> Result<Loaded, CliError> {
    for (what, factor) in [
        ("--voltage-factor", columns.voltage_factor),
        ("--displacement-factor", columns.displacement_factor),
    ] {
        if !(factor.is_finite() && factor != 0.0) {
            return Err(CliError::input(format!(
                "{what} {factor} is not usable: give a finite, non-zero factor"
            )));
        }
    }
    let mut selection = vec![voltage_column.clone(), displacement_column.clone()];
    if let Some(t) = time_column {
        selection.push(t.clone());
    }
    let options = ReadOptions {
        delimiter: columns.delimiter,
        header: columns.header,
        rows,
    };
    let read = data::read_columns(path, &selection, &options)?;
    let names = read.names.clone();
    for (what, column, factor) in [
        ("--voltage-factor", &read.values[0], columns.voltage_factor),
        (
            "--displacement-factor",
            &read.values[1],
            columns.displacement_factor,
        ),
    ] {
        let bound = data::MAX_MAGNITUDE;
        if let Some(v) = column
            .iter()
            .find(|v| (*v * factor).is_nan() || (*v * factor).abs() > bound)
        {
            return Err(CliError::input(format!(
                "{what} {factor:e} is too large: {v} times it is {:e}, beyond {bound:e} in \
                 magnitude (the largest a record may hold, so that fits and indices stay \
                 finite); give a factor that keeps the scaled values within it",
                v * factor
            )));
        }
    }
    let mut values = read.values.into_iter();
    let voltage: Vec<f64> = values
        .next()
        .unwrap_or_default()
        .into_iter()
        .map(|v| v * columns.voltage_factor)
        .collect();
    let displacement: Vec<f64> = values
        .next()
        .unwrap_or_default()
        .into_iter()
        .map(|v| v * columns.displacement_factor)
        .collect();
    for (what, name, values) in [
        ("voltage", &names[0], &voltage),
        ("displacement", &names[1], &displacement),
    ] {
        let label = if name == what {
            what.to_owned()
        } else {
            format!("{what} ({name})")
        };
        data::check_not_constant(&label, values)
            .map_err(|e| CliError::from(e).context(path.display()))?;
    }
    let time = values.next().map(|t| columns.time_unit.to_seconds(&t));
    if let Some(time) = &time {
        data::check_time_increasing(time).map_err(|e| {
            let column = if names[2].starts_with("column ") {
                names[2].clone()
            } else {
                format!("column \"{}\"", names[2])
            };
            CliError::from(e).context(format!("{}, time {column}", path.display()))
        })?;
    }
    Ok(Loaded {
        voltage,
        displacement,
        time,
        names,
    })
}

impl FitArgs {
    /// Refuses sizes beyond their bounds (operators, particles, iterations), naming the
    /// option, before any record is read.
    pub fn check_sizes(&self) -> Result<(), CliError> {
        use hystcomp_identify::{MAX_ITERATIONS, MAX_OPERATORS, MAX_PARTICLES};
        if let Operators::Count(n) = self.operators {
            bounds::count(
                "-n/--operators",
                n,
                1..=MAX_OPERATORS,
                "play operators (the paper uses 10; the fit's cost grows with their square)",
            )?;
        }
        if let Some(thresholds) = &self.thresholds {
            bounds::count(
                "--thresholds",
                thresholds.len(),
                1..=MAX_OPERATORS,
                "thresholds",
            )?;
        }
        if !(self.input_degree % 2 == 1
            && (3..=hystcomp_identify::MAX_FIT_INPUT_DEGREE).contains(&self.input_degree))
        {
            return Err(CliError::input(format!(
                "--input-degree {} is not usable: the input polynomial a2 x + a1 x^3 + c5 x^5 + \
                 ... is odd, of degree 3 (the paper's cubic), 5, 7 or 9",
                self.input_degree
            )));
        }
        if !(1..=hystcomp_core::MAX_OUTPUT_MAP_DEGREE).contains(&self.output_map_degree) {
            return Err(CliError::input(format!(
                "--output-map-degree {} is not usable: give 1 (no output map) to {}",
                self.output_map_degree,
                hystcomp_core::MAX_OUTPUT_MAP_DEGREE
            )));
        }
        if self.output_map_degree != 1 && self.method == "pso" {
            return Err(CliError::input(format!(
                "--output-map-degree {} needs --method ls: the output map is fitted by least \
                 squares only",
                self.output_map_degree
            )));
        }
        if self.input_degree != 3 && self.method == "pso" {
            return Err(CliError::input(format!(
                "--input-degree {} needs --method ls: the particle swarm fits the paper's cubic \
                 only",
                self.input_degree
            )));
        }
        bounds::count(
            "--pso-particles",
            self.particles,
            2..=MAX_PARTICLES,
            &format!(
                "particles (the default is {})",
                hystcomp_identify::DEFAULT_PARTICLES
            ),
        )?;
        bounds::count(
            "--pso-iterations",
            self.iterations,
            1..=MAX_ITERATIONS,
            &format!(
                "iterations (the default is {})",
                hystcomp_identify::DEFAULT_ITERATIONS
            ),
        )
    }

    /// The identification options these arguments describe.
    pub fn options(
        &self,
        columns: &ColumnArgs,
        direction: Direction,
        holdout: f64,
        loaded: &Loaded,
    ) -> Result<IdentifyOptions, CliError> {
        let method = match self.method.as_str() {
            "pso" => {
                let mut pso = PsoOptions::default()
                    .with_particles(self.particles)?
                    .with_iterations(self.iterations)?
                    .with_acceleration(self.c1, self.c2)?
                    .with_velocity_clamp(self.velocity_clamp)?
                    .with_penalty(self.penalty)?
                    .with_seed(self.seed)
                    .with_topology(self.pso_topology)
                    .with_polish(self.polish);
                match self.inertia.as_deref() {
                    None => {}
                    Some(&[start, end]) => pso = pso.with_inertia(start, end)?,
                    Some(other) => {
                        return Err(CliError::input(format!(
                            "--inertia takes two weights START,END (e.g. 0.9,0.4), got {} value(s)",
                            other.len()
                        )));
                    }
                }
                for (option, value) in [
                    ("--bound", self.bound),
                    ("--offset-bound", self.offset_bound),
                ] {
                    if !(value.is_finite() && value > 0.0) {
                        return Err(CliError::input(format!(
                            "{option} {} is not usable: give a positive search bound in \
                             normalised units (the defaults are 3 for --bound, 1 for \
                             --offset-bound)",
                            Shown(value)
                        )));
                    }
                }
                let (b, c) = (self.bound, self.offset_bound);
                pso = pso.with_bounds(PsoBounds {
                    cubic: [-b, b],
                    linear: [-b, b],
                    weights: [-b, b],
                    offset: [-c, c],
                })?;
                Method::ParticleSwarm(pso)
            }
            _ => Method::LeastSquares,
        };
        let thresholds = match &self.thresholds {
            Some(values) => Thresholds::Given(values.clone()),
            None => match self.operators {
                Operators::Count(n) => Thresholds::Uniform(n),
                // Chosen below, once the other options are known.
                Operators::Auto => Thresholds::Uniform(hystcomp_identify::DEFAULT_OPERATORS),
            },
        };
        let warmup = match self.warmup_seconds {
            Some(seconds) => Warmup::Samples(warmup_samples(seconds, columns, loaded)?),
            None => self.warmup,
        };
        let options = IdentifyOptions {
            direction,
            method,
            thresholds,
            warmup,
            holdout,
            offset: self.offset,
            margin: self.margin,
            max_condition: self.max_condition,
            max_fit_rms_percent: if self.accept_poor_fit {
                None
            } else {
                Some(hystcomp_identify::DEFAULT_MAX_FIT_RMS_PERCENT)
            },
            delayed_loop_bound: self.for_delayed.then_some(self.delayed_loop_bound),
            input_degree: self.input_degree,
            output_map_degree: self.output_map_degree,
            voltage_unit: columns.voltage_unit.clone(),
            displacement_unit: columns.displacement_unit.clone(),
        };
        options.validate()?;
        if self.operators == Operators::Auto && self.thresholds.is_none() {
            let selection = hystcomp_identify::select_operators(
                &loaded.voltage,
                &loaded.displacement,
                &options,
                &hystcomp_identify::AUTO_OPERATOR_CANDIDATES,
            )?;
            let tried: Vec<String> = selection
                .candidates
                .iter()
                .map(|c| {
                    format!(
                        "{} -> {} %",
                        c.operators,
                        crate::number(c.holdout_rms_percent)
                    )
                })
                .collect();
            errln!(
                "hystcomp: -n auto: held-out RMS error (last {} % of the record, fitted on the \
                 rest) for n = {}; chose n = {}",
                crate::number(100.0 * selection.holdout),
                tried.join(", "),
                selection.operators
            );
            return Ok(IdentifyOptions {
                thresholds: Thresholds::Uniform(selection.operators),
                ..options
            });
        }
        Ok(options)
    }

    /// Whether a progress bar is worth drawing (only the swarm iterates).
    pub fn iterates(&self) -> bool {
        self.method == "pso"
    }
}

/// The number of samples within `seconds` of the first, from the time column or the rate.
fn warmup_samples(seconds: f64, columns: &ColumnArgs, loaded: &Loaded) -> Result<usize, CliError> {
    if !(seconds.is_finite() && seconds >= 0.0) {
        return Err(CliError::input(format!(
            "--warmup-seconds {seconds} is not usable: give a duration >= 0"
        )));
    }
    if let Some(time) = &loaded.time {
        let t0 = time.first().copied().unwrap_or(0.0);
        return Ok(time
            .iter()
            .position(|&t| t - t0 >= seconds)
            .unwrap_or(time.len()));
    }
    match columns.sample_rate {
        Some(rate) if rate.is_finite() && rate > 0.0 => Ok((seconds * rate).ceil() as usize),
        Some(rate) => Err(CliError::input(format!(
            "--sample-rate {rate} is not usable: give a rate > 0 in Hz"
        ))),
        None => Err(CliError::input(
            "--warmup-seconds needs a time column (--time-column) or --sample-rate; or give \
             the warm-up in samples with --warmup",
        )),
    }
}

#[derive(Serialize)]
struct Output<'a> {
    data: String,
    output: String,
    columns: &'a [String],
    report: &'a hystcomp_identify::FitReport,
    model: &'a hystcomp_io::model_file::ModelFile,
}

/// Prints a fit report for people.
pub fn print_fit(report: &hystcomp_identify::FitReport) -> Result<(), CliError> {
    let unit = &report.output.unit;
    let s = &report.samples;
    outln!(
        "  samples: {} in the record, {} warm-up, {} fitted, {} held out",
        s.total,
        s.warmup,
        s.fit,
        s.holdout
    )?;
    outln!(
        "  {} {} .. {} {} -> {} {} .. {} {} (fitted ranges; {} play operator{}, condition \
         number {:.3e})",
        report.input.quantity,
        crate::number(report.input.min),
        crate::number(report.input.max),
        report.input.unit,
        report.output.quantity,
        crate::number(report.output.min),
        crate::number(report.output.max),
        unit,
        report.thresholds.len(),
        if report.thresholds.len() == 1 {
            ""
        } else {
            "s"
        },
        report.condition_number
    )?;
    outln!(
        "  fit:      RMS {:.4} % ({:.4} {unit}), max {:.4} % ({:.4} {unit}) of the output range",
        report.fit.rms_percent,
        report.fit.rms,
        report.fit.max_percent,
        report.fit.max
    )?;
    if let Some(h) = &report.holdout {
        outln!(
            "  held out: RMS {:.4} % ({:.4} {unit}), max {:.4} % ({:.4} {unit}) of the held-out \
             span's own range ({:.4} {unit}, as crossval normalises a test span)",
            h.rms_percent,
            h.rms,
            h.max_percent,
            h.max,
            h.range
        )?;
    }
    outln!(
        "  solver: {} ({}), {} of {} constraints active{}, smallest branch slope {:.4} \
         (margin {}), {:.1} ms",
        report.solver,
        report.detail,
        report.active_constraints,
        report.constraints,
        match report.violated_constraints {
            0 => String::new(),
            v => format!(" and {v} violated"),
        },
        report.min_branch_slope,
        report.margin,
        report.elapsed_s * 1e3
    )?;
    if let Some(g) = &report.delayed_loop_gains {
        let verdict = |gain: f64| {
            if gain < 1.0 {
                "settles"
            } else {
                "can ring: refused by compensate without --allow-unstable-delay"
            }
        };
        outln!(
            "  delayed loops over the fitted voltage range: ihc-delayed gain {:.4} ({}), \
             wihc-delayed gain {:.4} ({})",
            g.ihc,
            verdict(g.ihc),
            g.wihc,
            verdict(g.wihc)
        )?;
        if let Some(c) = &report.delayed_constraint {
            outln!(
                "  fitted for delayed compensation (--for-delayed): both gains held to at most \
                 {:.4}; it costs {:+.4} % of the output range in fit RMS ({:.4} % without the \
                 bound, whose gains were ihc-delayed {:.4}, wihc-delayed {:.4})",
                c.bound,
                report.fit.rms_percent - c.unconstrained_fit_rms_percent,
                c.unconstrained_fit_rms_percent,
                c.unconstrained_gains.ihc,
                c.unconstrained_gains.wihc
            )?;
        } else if g.ihc >= 1.0 || g.wihc >= 1.0 {
            outln!("  (identify with --for-delayed to bound both delayed loops' gains below 1)")?;
        }
    }
    Ok(())
}

/// Says on stderr which samples were fitted and why (the report's warm-up; `--json` has it
/// in `report.warmup`).
pub fn note_samples(report: &hystcomp_identify::FitReport) {
    if let Some(w) = &report.warmup {
        let s = &report.samples;
        errln!(
            "hystcomp: fitted samples {}..{} of {} ({} held out at the end): {}",
            s.warmup + 1,
            s.warmup + s.fit,
            s.total,
            s.holdout,
            w.reason
        );
    }
}

/// A library error of a fit on `loaded` (read from `path`) for the user: the file's name, and
/// for [`IdentifyError::SameSignal`] the two columns given.
pub fn fit_error(error: IdentifyError, path: &Path, loaded: &Loaded) -> CliError {
    let column = |name: &String| {
        if name.starts_with("column ") {
            name.clone()
        } else {
            format!("column \"{name}\"")
        }
    };
    let context = match (&error, loaded.names.as_slice()) {
        (IdentifyError::SameSignal, [voltage, displacement, ..]) => format!(
            "{} (voltage {}, displacement {})",
            path.display(),
            column(voltage),
            column(displacement)
        ),
        _ => path.display().to_string(),
    };
    CliError::from(error).context(context)
}

#[derive(Serialize)]
struct ChainOutput<'a> {
    data: String,
    output: String,
    columns: &'a [String],
    report: &'a hystcomp_identify::ChainReport,
    model: &'a hystcomp_io::model_file::ModelFile,
}

/// Writes the identified `model` to `--output`, its identification record naming the data
/// file and the columns read; returns the model as written.
fn save(
    args: &Args,
    loaded: &Loaded,
    model: &hystcomp_io::model_file::ModelFile,
) -> Result<hystcomp_io::model_file::ModelFile, CliError> {
    let mut model = model.clone();
    if let Some(serde_json::Value::Object(map)) = &mut model.identification {
        map.insert(
            "data".to_owned(),
            serde_json::Value::String(args.data.display().to_string()),
        );
        map.insert(
            "columns".to_owned(),
            serde_json::Value::from(loaded.names.clone()),
        );
    }
    model
        .save(&args.output)
        .map_err(|e| CliError::output(e.to_string()))?;
    Ok(model)
}

/// `identify` with creep and vibration: the chain of `hystcomp_identify::chain`.
fn run_chain(
    args: &Args,
    ctx: Context,
    loaded: &Loaded,
    options: &IdentifyOptions,
    chain: &hystcomp_identify::ChainOptions,
) -> Result<(), CliError> {
    let fit =
        hystcomp_identify::identify_chain(&loaded.voltage, &loaded.displacement, options, chain)
            .map_err(|e| fit_error(e, &args.data, loaded))?;
    let model = save(args, loaded, &fit.model)?;
    if ctx.json {
        crate::print_json(&ChainOutput {
            data: args.data.display().to_string(),
            output: args.output.display().to_string(),
            columns: &loaded.names,
            report: &fit.report,
            model: &model,
        })?;
    } else {
        outln!(
            "{} chain identified from {} at {} Hz -> {}",
            args.direction,
            args.data.display(),
            crate::number(chain.sample_rate_hz),
            args.output.display()
        )?;
        print_fit(&fit.report.hysteresis)?;
        super::chain_args::print_chain(&fit.report, &fit.report.hysteresis.output.unit)?;
    }
    Ok(())
}

/// Runs `hystcomp identify`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    args.fit.check_sizes()?;
    let c = &args.columns;
    let loaded = c.load(&args.data)?;
    let options = args.fit.options(c, args.direction, args.holdout, &loaded)?;
    if let Some(chain) = args.chain.options(c, &loaded)? {
        if options.input_degree != 3 {
            return Err(CliError::input(format!(
                "--input-degree {} is not available with the creep or vibration chain, which \
                 fits the paper's cubic; leave it out, or identify the hysteresis alone",
                options.input_degree
            )));
        }
        if options.warmup == Warmup::Estimate {
            return Err(CliError::input(
                "--warmup estimate is not available with the creep or vibration chain, whose \
                 joint fit runs the operators from zero memory; use --warmup auto (the \
                 default) or a number of samples",
            ));
        }
        return run_chain(args, ctx, &loaded, &options, &chain);
    }
    let mut bar = if args.fit.iterates() {
        Bar::new("identifying", args.fit.iterations as u64)
    } else {
        Bar::hidden()
    };
    let fit = identify_observed(&loaded.voltage, &loaded.displacement, &options, &mut bar)
        .map_err(|e| fit_error(e, &args.data, &loaded))?;
    bar.finish();
    note_samples(&fit.report);
    let model = save(args, &loaded, &fit.model)?;
    if ctx.json {
        let output = Output {
            data: args.data.display().to_string(),
            output: args.output.display().to_string(),
            columns: &loaded.names,
            report: &fit.report,
            model: &model,
        };
        crate::print_json(&output)?;
    } else {
        outln!(
            "{} model identified from {} -> {}",
            args.direction,
            args.data.display(),
            args.output.display()
        )?;
        print_fit(&fit.report)?;
    }
    Ok(())
}
