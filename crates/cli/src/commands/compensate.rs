//! `hystcomp compensate`: a desired trajectory through a compensator, CSV in, CSV out; with a
//! model set, a multi-column trajectory through a bank (module `bank`).

mod bank;

use std::path::PathBuf;

use hystcomp_core::CoreError;
use hystcomp_io::compensator::{CompensatorError, Method, ScaledCompensator, UnstableDelay};
use hystcomp_io::data::{self, Column, Delimiter, Header, ReadOptions};
use hystcomp_io::model_file::ModelFile;
use serde::Serialize;

use crate::error::EXIT_SATURATED;
use crate::files::{Files, NamesFiles};
use crate::{CliError, Context};

/// Arguments of `hystcomp compensate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (JSON): a plant model for ihc / wihc, an inverse model for dihc. A model set
    /// (a model-set file or a directory of model files) compensates one column per channel.
    #[arg(long, value_name = "FILE")]
    model: PathBuf,
    /// Compensator: ihc, wihc (exact solves), ihc-delayed, wihc-delayed (one-sample-delayed
    /// loops, refused on a model where they can oscillate), ihc-guarded, wihc-guarded (delayed
    /// loops with a guard: they never oscillate) or dihc (inverse model).
    #[arg(long, value_name = "METHOD", value_parser = parse_method)]
    method: Method,
    /// Desired trajectory: a CSV (or tab / whitespace separated, or .mat) file with a time
    /// column (s) and a desired position column (in the model's displacement unit).
    #[arg(long = "desired", alias = "trajectory", value_name = "FILE")]
    trajectory: PathBuf,
    /// Where to write the drive signal (CSV: time, drive voltage, desired position; the drive
    /// is the second column, which `hystcomp simulate` reads by default).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Time column of the trajectory, by name or 1-based index.
    #[arg(long, default_value = "1", value_name = "COLUMN")]
    time_column: Column,
    /// Desired position column of the trajectory, by name or 1-based index.
    #[arg(long, default_value = "2", value_name = "COLUMN")]
    desired_column: Column,
    /// With a model set: the desired position columns, one per channel in the set's order
    /// (comma-separated names or 1-based indices). Default: the columns named after the
    /// channels if the file has them all, else the consecutive columns from --desired-column.
    #[arg(long, value_name = "COLUMN,...", value_delimiter = ',')]
    desired_columns: Option<Vec<Column>>,
    /// Field delimiter of the trajectory file: auto, comma, tab, semicolon or whitespace.
    #[arg(long, default_value = "auto")]
    delimiter: Delimiter,
    /// Whether the trajectory file starts with column names: auto, present or absent.
    #[arg(long, default_value = "auto")]
    header: Header,
    /// Drive limits MIN:MAX in the model's voltage unit (default: the voltage range the model
    /// was identified on). The compensator never leaves them. With a model set, one pair for
    /// every channel or one per channel, comma-separated in the set's channel order (e.g.
    /// 0:10,0:10,-5:5), each in its channel's voltage unit.
    #[arg(
        long,
        value_name = "MIN:MAX[,...]",
        value_parser = parse_limits,
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    limits: Option<Vec<(f64, f64)>>,
    /// Stage file whose amplifier the drive is checked against before anything is driven (slew
    /// rate into the stack's capacitance, rails, bandwidth); default: the built-in stage's.
    #[arg(long, value_name = "FILE")]
    stage: Option<PathBuf>,
    /// With a vibration link: the preview of the streaming inverse, samples (the drive of
    /// sample k uses the desired positions up to k + preview). Default: as long as the
    /// vibration inverse needs for a negligible cut (the file is a whole known trajectory).
    #[arg(long, value_name = "SAMPLES")]
    preview: Option<usize>,
    /// With a vibration link: invert the trajectory low-passed with zero phase at this
    /// frequency, Hz (band-limited inversion: a second-order Butterworth run forward and
    /// backward, -6 dB here). Meant as the top of the band the link was identified on, above
    /// which its inverse extrapolates and can ask more slew than the amplifier has. The drive
    /// file's desired column stays the trajectory as given. Default: inverted whole.
    #[arg(long, value_name = "HZ")]
    inverse_band_hz: Option<f64>,
    /// With a chain model with a vibration link and --method ihc or wihc: keep every step of
    /// the drive within this share (0 to 1) of the amplifier's slew rate (--stage, or the
    /// built-in stage's), the drive chosen so that the model tracks the trajectory as closely
    /// as it can in the least-squares sense (a quadratic programme through the vibration link;
    /// see the README). Where the whole inverse is already within it, the drive is unchanged.
    #[arg(long, value_name = "SHARE")]
    within_slew: Option<f64>,
    /// Exit with status 0 even when the drive was clamped to its limits: because the trajectory
    /// left the reachable range, or because a delayed loop lagged or rang (the samples are
    /// counted either way, and the drive file is written).
    #[arg(long)]
    allow_saturation: bool,
    /// Run ihc-delayed or wihc-delayed even when its loop gain on this model is 1 or more, so
    /// that it can ring between the drive limits after a jump in the desired position (it is
    /// refused otherwise; ihc-guarded and wihc-guarded never oscillate).
    #[arg(long)]
    allow_unstable_delay: bool,
}

impl NamesFiles for Args {
    fn files(&self) -> Files<'_> {
        Files::new()
            .input("--model", &self.model)
            .input("--desired", &self.trajectory)
            .stage("--stage", self.stage.as_ref())
            .output("--output", &self.output)
    }
}

fn parse_method(s: &str) -> Result<Method, String> {
    s.parse()
        .map_err(|e: hystcomp_io::compensator::CompensatorError| e.to_string())
}

/// Parses `MIN:MAX`.
pub fn parse_limits(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = s
        .split_once(':')
        .ok_or_else(|| format!("expected MIN:MAX, e.g. 0:10, got {s:?}"))?;
    let parse = |t: &str| {
        t.trim()
            .parse::<f64>()
            .map_err(|_| format!("{t:?} is not a number (expected MIN:MAX, e.g. 0:10)"))
    };
    Ok((parse(lo)?, parse(hi)?))
}

/// What `compensate` reports.
#[derive(Debug, Serialize)]
struct Report {
    model: String,
    method: Method,
    trajectory: String,
    output: String,
    samples: usize,
    limits: (f64, f64),
    control_unit: String,
    desired_unit: String,
    /// Samples whose drive was clamped to a limit, for either reason below
    /// (`unreachable + loop_saturated`).
    saturated: u64,
    /// Samples whose desired position lay outside what the model can reach within the limits
    /// from its state (DIHC: outside the inverse model's input range, or needing a drive
    /// beyond the limits): the drive was clamped.
    unreachable: u64,
    /// Samples whose drive a delayed loop (ihc-delayed, wihc-delayed) pushed into a limit
    /// although the desired position was reachable: the loop lagged or rang.
    loop_saturated: u64,
    /// Time (s) of the first clamped sample, either reason.
    first_saturated_time_s: Option<f64>,
    /// Time (s) of the first unreachable desired position.
    first_unreachable_time_s: Option<f64>,
    /// Time (s) of the first loop saturation.
    first_loop_saturated_time_s: Option<f64>,
    /// IHC and WIHC methods: the worst-case gain of the family's one-sample-delayed loop over
    /// the limits (at or above 1 the plain delayed loop can ring after a jump, and is refused
    /// without --allow-unstable-delay).
    delayed_loop_gain: Option<f64>,
    /// IHC and WIHC methods: the under-relaxation of the family's guarded delayed loop, in
    /// (0, 1] (1: no under-relaxation).
    guard_relaxation: Option<f64>,
    /// Whether --allow-unstable-delay was given.
    allow_unstable_delay: bool,
    /// DIHC: the desired positions the inverse model accepts (it clamps into this range).
    desired_range: Option<(f64, f64)>,
    /// Smallest and largest drive emitted.
    control_range: (f64, f64),
    /// With a vibration link: the preview of its inverse, samples (0 without).
    preview: usize,
    /// With `--inverse-band-hz`: the band the vibration inverse was limited to, Hz.
    inverse_band_hz: Option<f64>,
    /// With `--within-slew`: whether the drive had to be slew-constrained (false: the whole
    /// inverse was already within the share of the slew rate).
    slew_constrained: Option<bool>,
    /// What the drive asks of the stage's amplifier (`--stage`, or the built-in stage's).
    feasibility: hystcomp_stage::Feasibility,
}

/// Runs `hystcomp compensate`.
pub fn run(args: &Args, ctx: Context) -> Result<(), CliError> {
    if hystcomp_io::bank::is_model_set(&args.model) {
        return bank::run(args, ctx);
    }
    if args.desired_columns.is_some() {
        return Err(CliError::input(
            "--desired-columns needs a model set (one model per column) as --model; give \
             --desired-column for one model",
        ));
    }
    let model = ModelFile::load(&args.model)?;
    if let Some(p) = args.preview {
        crate::bounds::count(
            "--preview",
            p,
            0..=hystcomp_core::MAX_PREVIEW_SAMPLES,
            "samples",
        )?;
    }
    let limits = match args.limits.as_deref() {
        None => None,
        Some([one]) => Some(*one),
        Some(many) => {
            return Err(CliError::input(format!(
                "--limits gives {} pairs for one model; give one MIN:MAX (a model set takes one \
                 pair per channel)",
                many.len()
            )));
        }
    };
    let mut compensator = ScaledCompensator::with_options(
        &model,
        args.method,
        limits,
        args.preview,
        args.unstable_delay(),
    )
    .map_err(|e| build_error(e, args.method).context(args.model.display()))?;
    if let Some(band) = args.inverse_band_hz {
        if model.vibration.is_none() {
            return Err(CliError::input(format!(
                "--inverse-band-hz {band}: the model has no vibration link, so there is no \
                 vibration inverse to band-limit ({})",
                args.model.display()
            )));
        }
        compensator = compensator
            .with_inverse_band(Some(band))
            .map_err(|e| CliError::input(format!("--inverse-band-hz: {e}")))?;
    }
    if let Some(share) = args.within_slew {
        check_within_slew(share, args, &model)?;
    }
    let stage = args.stage()?;
    let columns = data::read_columns(
        &args.trajectory,
        &[args.time_column.clone(), args.desired_column.clone()],
        &args.read_options(),
    )?;
    let (time, desired) = (&columns.values[0], &columns.values[1]);
    data::check_time_increasing(time)
        .map_err(|e| CliError::from(e).context(args.trajectory.display()))?;
    if let Some(step) = data::mean_time_step(time) {
        super::chain_args::check_model_rate(&model, 1.0 / step, "the trajectory")
            .map_err(|e| e.context(args.trajectory.display()))?;
    }

    if args.method.is_plain_delayed()
        && let Some(gain) = compensator.delayed_loop_gain().filter(|g| *g >= 1.0)
    {
        errln!(
            "hystcomp: warning: --allow-unstable-delay: the {} loop gain on this model is \
             {gain:.3} (>= 1 over the drive limits), so after a jump in the desired position its \
             drive can ring between the limits; --method {} solves the law exactly and --method \
             {} never oscillates",
            args.method,
            args.method.exact(),
            args.method.guarded().unwrap_or(args.method.exact()),
        );
    }

    let mut control = vec![0.0; desired.len()];
    let mut first_unreachable = None;
    let mut first_loop = None;
    let mut before = compensator.diagnostics();
    // With a preview the drive of sample k comes p samples later: the trajectory is fed whole,
    // then held at its last value for p samples, and the first p drives (before it starts,
    // the trajectory taken at rest at its first value) are dropped.
    let p = compensator.preview();
    let n = desired.len();
    if n == 0 {
        return Err(
            CliError::input("the trajectory has no samples").context(args.trajectory.display())
        );
    }
    // With --inverse-band-hz the chain inverts the trajectory low-passed (a non-finite sample
    // leaves it as it is, for the check below to name its row).
    let inverted = compensator.band_limited(desired);
    for k in 0..n + p {
        let d = inverted[k.min(n - 1)];
        let drive = compensator.step(d);
        // While the preview fills (k < p) no drive sample is written yet, but a clamp then
        // shapes the first samples' drive: it is dated at the trajectory's start.
        let at = k.checked_sub(p);
        let after = compensator.diagnostics();
        if let Some(at) = at {
            control[at] = drive;
            if after.non_finite > before.non_finite {
                // The drive held its previous value: never written as if it were a result.
                return Err(CliError::input(format!(
                    "{}, row {}: the desired position {d} {} is not finite once normalised by \
                     the model ({}); the drive would hold its previous value there. Check the \
                     trajectory's unit against the model's",
                    args.trajectory.display(),
                    columns.file_row(k.min(n - 1) + 1),
                    compensator.desired_unit(),
                    args.model.display()
                )));
            }
        }
        let when = time.get(at.unwrap_or(0)).copied();
        if after.saturated > before.saturated && first_unreachable.is_none() {
            first_unreachable = when;
        }
        if after.loop_saturated > before.loop_saturated && first_loop.is_none() {
            first_loop = when;
        }
        before = after;
    }

    let mut slew_constrained = None;
    if let Some(share) = args.within_slew {
        let max_step_v = share * stage.amplifier.slew_rate_v_per_s() / stage.amplifier.gain
            * drive_period_s(time, &stage);
        let drive = hystcomp_experiments::slew_drive::slew_constrained_drive(
            &model,
            args.method,
            compensator.limits(),
            desired,
            max_step_v,
        )
        .map_err(|e| CliError::input(format!("--within-slew {share}: {e}")))?;
        control = drive.drive;
        slew_constrained = Some(drive.constrained);
    }

    let time_name = columns.names[0].clone();
    let desired_name = format!("desired_{}", compensator.desired_unit());
    let control_name = format!("drive_{}", compensator.control_unit().to_lowercase());
    data::write_csv(
        &args.output,
        &[&time_name, &control_name, &desired_name],
        &[time, &control, desired],
    )
    .map_err(|e| CliError::output(e.to_string()))?;

    let diagnostics = compensator.diagnostics();
    let report = Report {
        model: args.model.display().to_string(),
        method: args.method,
        trajectory: args.trajectory.display().to_string(),
        output: args.output.display().to_string(),
        samples: desired.len(),
        limits: compensator.limits(),
        control_unit: compensator.control_unit().to_string(),
        desired_unit: compensator.desired_unit().to_string(),
        saturated: diagnostics.saturated + diagnostics.loop_saturated,
        unreachable: diagnostics.saturated,
        loop_saturated: diagnostics.loop_saturated,
        first_saturated_time_s: earliest(first_unreachable, first_loop),
        first_unreachable_time_s: first_unreachable,
        first_loop_saturated_time_s: first_loop,
        delayed_loop_gain: compensator.delayed_loop_gain(),
        guard_relaxation: compensator.guard_relaxation(),
        allow_unstable_delay: args.allow_unstable_delay,
        desired_range: compensator.desired_range(),
        control_range: range(&control),
        preview: p,
        inverse_band_hz: compensator.inverse_band_hz(),
        slew_constrained,
        feasibility: hystcomp_stage::feasibility_held(
            &stage,
            &control,
            drive_period_s(time, &stage),
        )
        .map_err(|e| CliError::input(e.to_string()))?,
    };
    if ctx.json {
        crate::print_json(&report)?;
    } else {
        outln!(
            "{}: {} samples through {} -> {} (drive {:.4} .. {:.4} {}, limits {:.4} .. {:.4} {})",
            report.trajectory,
            report.samples,
            report.method,
            report.output,
            report.control_range.0,
            report.control_range.1,
            report.control_unit,
            report.limits.0,
            report.limits.1,
            report.control_unit,
        )?;
    }
    if !report.feasibility.is_feasible() {
        // Said before anything is driven: the stage would not follow this drive.
        errln!(
            "hystcomp: warning: the stage's amplifier cannot deliver this drive as asked ({}): \
             {}; slow the trajectory down or reduce its amplitude",
            args.stage_name(),
            report.feasibility.summary()
        );
    }
    let mut problems = Vec::new();
    if report.unreachable > 0 {
        problems.push(unreachable_message(&report, desired));
    }
    if report.loop_saturated > 0 {
        problems.push(loop_message(&report));
    }
    if problems.is_empty() {
        return Ok(());
    }
    clamped(problems.join(". Also, "), "", args.allow_saturation)
}

impl Args {
    /// Whether a delayed loop that can oscillate on the model is run
    /// (`--allow-unstable-delay`) or refused.
    fn unstable_delay(&self) -> UnstableDelay {
        if self.allow_unstable_delay {
            UnstableDelay::Allow
        } else {
            UnstableDelay::Refuse
        }
    }

    /// The stage whose amplifier the drive is checked against: `--stage`, or the built-in one.
    fn stage(&self) -> Result<hystcomp_stage::StageConfig, CliError> {
        match &self.stage {
            Some(path) => hystcomp_stage::StageConfig::from_toml_file(path)
                .map_err(|e| CliError::input(e.to_string()).context(path.display())),
            None => Ok(hystcomp_stage::StageConfig::default()),
        }
    }

    /// That stage, as the feasibility warning names it.
    fn stage_name(&self) -> String {
        self.stage
            .as_ref()
            .map_or("the built-in stage".to_owned(), |p| p.display().to_string())
    }

    /// How the trajectory file is read (every row).
    fn read_options(&self) -> ReadOptions {
        ReadOptions {
            delimiter: self.delimiter,
            header: self.header,
            rows: None,
        }
    }
}

/// `--within-slew SHARE` needs a share in (0, 1], an exact IHC or WIHC, a model with a
/// vibration link, and the whole trajectory inverted offline as given.
fn check_within_slew(share: f64, args: &Args, model: &ModelFile) -> Result<(), CliError> {
    let refuse = |why: &str| Err(CliError::input(format!("--within-slew {share}: {why}")));
    if !(share > 0.0 && share <= 1.0) {
        return refuse("give a share of the amplifier's slew rate between 0 (excluded) and 1");
    }
    if !matches!(args.method, Method::Ihc | Method::Wihc) {
        return refuse(
            "the slew-constrained drive inverts the hysteresis with --method ihc or wihc",
        );
    }
    if model.vibration.is_none() {
        return refuse(&format!(
            "the model has no vibration link ({}); the slew-constrained drive works through it",
            args.model.display()
        ));
    }
    if args.preview.is_some() || args.inverse_band_hz.is_some() {
        return refuse(
            "the slew-constrained drive inverts the whole trajectory offline: drop --preview \
             and --inverse-band-hz",
        );
    }
    Ok(())
}

/// The earlier of two optional times.
fn earliest(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Smallest and largest of `values` (`(inf, -inf)` when empty).
fn range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// The end of a run whose drive was clamped: a warning with `--allow-saturation`, else the
/// error `message` followed by `advice` (empty, or ending in "; ") and the flag that accepts
/// it, with the exit status for saturation.
fn clamped(mut message: String, advice: &str, allow_saturation: bool) -> Result<(), CliError> {
    if allow_saturation {
        errln!("hystcomp: warning: {message}");
        Ok(())
    } else {
        message.push_str("; ");
        message.push_str(advice);
        message.push_str(
            "--allow-saturation accepts the clamped output with exit status 0 (the drive file \
             is written either way)",
        );
        Err(CliError::with_code(message, EXIT_SATURATED))
    }
}

/// How long each drive sample is held, s: the trajectory's mean time step (its time column,
/// in seconds), or the stage's own period for a trajectory of fewer than two samples. The
/// feasibility check holds each drive sample for this long, as a DAC updated at the
/// trajectory's rate does.
fn drive_period_s(time: &[f64], stage: &hystcomp_stage::StageConfig) -> f64 {
    data::mean_time_step(time)
        .filter(|step| *step > 0.0)
        .unwrap_or(1.0 / stage.sample_rate_hz)
}

/// The message for desired positions out of the model's reach, per method.
fn unreachable_message(report: &Report, desired: &[f64]) -> String {
    let (v0, v1, volt) = (report.limits.0, report.limits.1, &report.control_unit);
    let unit = &report.desired_unit;
    let first = report.first_unreachable_time_s.unwrap_or(f64::NAN);
    match report.desired_range {
        Some((lo, hi)) => {
            // DIHC: the desired position is clamped into the inverse model's input range, and
            // then the drive into the limits.
            let outside = desired
                .iter()
                .filter(|d| d.is_finite() && (**d < lo || **d > hi))
                .count() as u64;
            let beyond = report.unreachable.saturating_sub(outside);
            let mut parts = Vec::new();
            if outside > 0 {
                parts.push(format!(
                    "{outside} of {} desired positions lie outside the range {lo:.4} .. {hi:.4} \
                     {unit} the inverse model was identified on, and DIHC clamped them into it",
                    report.samples
                ));
            }
            if beyond > 0 {
                parts.push(format!(
                    "{beyond} of {} desired positions need a drive beyond the limits {v0:.4} .. \
                     {v1:.4} {volt}, and the drive was clamped to the limits there",
                    report.samples
                ));
            }
            format!(
                "{} (first at t = {first} s). Scale the trajectory into that range, identify the \
                 inverse model on a wider range, or widen --limits",
                parts.join("; ")
            )
        }
        None => format!(
            "{} of {} desired positions lie outside what the model can reach within the drive \
             limits {v0:.4} .. {v1:.4} {volt} (first at t = {first} s); the drive was clamped to \
             the nearest limit there. Scale the trajectory into the stage's range or widen \
             --limits",
            report.unreachable, report.samples
        ),
    }
}

/// A compensator that could not be built, for the user: a delayed loop that can oscillate
/// names the flag that overrides the refusal and the methods that do not oscillate.
fn build_error(error: CompensatorError, method: Method) -> CliError {
    let mut message = error.to_string();
    if matches!(
        error,
        CompensatorError::Core(CoreError::DelayedLoopUnstable { .. })
    ) {
        message = format!(
            "{message}: --method {} (exact) or --method {} (guarded delayed loop) never \
             oscillate; --allow-unstable-delay runs it anyway",
            method.exact(),
            method.guarded().unwrap_or(method.exact()),
        );
    }
    CliError::input(message)
}

/// The message for a delayed loop that hit the limits although the positions were reachable.
fn loop_message(report: &Report) -> String {
    let exact = report.method.exact().name();
    let gain = match report.delayed_loop_gain {
        Some(g) if g >= 1.0 => format!(" (its loop gain on this model is {g:.3} >= 1)"),
        Some(g) => format!(" (its loop gain on this model is {g:.3})"),
        None => String::new(),
    };
    format!(
        "on {} of {} samples the {} loop drove the output to the drive limits {:.4} .. {:.4} {} \
         although the desired positions were within reach (first at t = {} s): the \
         one-sample-delayed loop lagged or rang after a jump in the desired position{gain}. \
         Use --method {exact}, which solves the law exactly each sample, or start the trajectory \
         where the stage rests",
        report.loop_saturated,
        report.samples,
        report.method,
        report.limits.0,
        report.limits.1,
        report.control_unit,
        report.first_loop_saturated_time_s.unwrap_or(f64::NAN),
    )
}
