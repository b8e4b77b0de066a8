//! The options of `identify` and `crossval` that add creep and vibration to the model (the
//! chain hysteresis -> creep -> vibration, `hystcomp_identify::chain`).

use hystcomp_identify::{ChainOptions, ChainReport, CreepOptions, DynamicsOptions};
use hystcomp_io::data;
use hystcomp_io::model_file::ModelFile;

use super::identify::{ColumnArgs, Loaded};
use crate::{CliError, bounds};

/// Which links the model has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Structure {
    /// The MPIM alone (format version 1's model).
    Hysteresis,
    /// The MPIM and a creep link.
    Creep,
    /// The MPIM and a vibration link (no creep link).
    Vibration,
    /// The MPIM, a creep link and a vibration link.
    Full,
}

/// How the creep link's weights are fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CreepFit {
    /// Jointly with the hysteresis, over the whole record.
    Joint,
    /// On the record's holds (the voltage constant for 1 s or more; at least two), the
    /// smoothness of the weights chosen by leaving each hold out, then the hysteresis on the
    /// creep-free displacement.
    Holds,
}

/// Creep and vibration options of `identify` and `crossval`.
#[derive(Debug, Clone, clap::Args)]
pub struct ChainArgs {
    /// Links of the model: hysteresis (the MPIM alone), creep (with a creep link: first-order
    /// elements at log-spaced time constants, fitted jointly with the hysteresis), vibration
    /// (with a vibration link: a unit-gain discrete model with a delay, order chosen from the
    /// data) or full (both links). --creep and --dynamics add one link each. Creep and
    /// vibration need the sample rate: a time column or --sample-rate.
    #[arg(
        long,
        value_enum,
        default_value = "hysteresis",
        value_name = "STRUCTURE"
    )]
    pub model_structure: Structure,
    /// Add the creep link (as --model-structure creep).
    #[arg(long)]
    pub creep: bool,
    /// Add the vibration link (as --model-structure vibration; with --creep, as full).
    #[arg(long)]
    pub dynamics: bool,
    /// The creep link's time constants, s, comma-separated and increasing (default: two per
    /// decade from 10 ms, or two sample periods, to a quarter of the record, at most 1000 s).
    #[arg(long, value_name = "T1,T2,...", value_delimiter = ',')]
    pub creep_time_constants: Option<Vec<f64>>,
    /// How the creep weights are fitted: joint (with the hysteresis, over the whole record) or
    /// holds (on the record's step-and-hold segments, where the hysteresis does not move, then
    /// the hysteresis on the creep-free displacement; the creep does not absorb the
    /// hysteresis model's mismatch, so a held step drifts less).
    #[arg(long, value_enum, default_value = "joint", value_name = "FIT")]
    pub creep_fit: CreepFit,
    /// Seconds from the start of the record where the vibration segment (high-frequency
    /// excitation) starts; default: the whole record.
    #[arg(long, value_name = "SECONDS")]
    pub dynamics_from: Option<f64>,
    /// Seconds from the start where the vibration segment ends; default: the record's end.
    #[arg(long, value_name = "SECONDS")]
    pub dynamics_to: Option<f64>,
    /// Fit the hysteresis and creep on every N-th sample (1 to 1000; the vibration link always
    /// uses every sample).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub decimation: usize,
}

impl ChainArgs {
    /// Whether the model has a creep link.
    pub fn has_creep(&self) -> bool {
        self.creep || matches!(self.model_structure, Structure::Creep | Structure::Full)
    }

    /// Whether the model has a vibration link.
    pub fn has_dynamics(&self) -> bool {
        self.dynamics || matches!(self.model_structure, Structure::Vibration | Structure::Full)
    }

    /// The chain's options for a record, `None` for the MPIM alone.
    pub fn options(
        &self,
        columns: &ColumnArgs,
        loaded: &Loaded,
    ) -> Result<Option<ChainOptions>, CliError> {
        bounds::count(
            "--decimation",
            self.decimation,
            1..=hystcomp_identify::chain::MAX_DECIMATION,
            "",
        )?;
        if !self.has_creep() && !self.has_dynamics() {
            if self.decimation != 1 {
                return Err(CliError::input(
                    "--decimation thins the samples the creep and hysteresis links are fitted \
                     on: it needs a chain (--creep, --dynamics or --model-structure)",
                ));
            }
            return Ok(None);
        }
        let rate = sample_rate(columns, loaded)?;
        let creep = match (self.has_creep(), &self.creep_time_constants) {
            (false, _) => None,
            (true, Some(t)) => Some(CreepOptions {
                time_constants_s: t.clone(),
                smoothness: 0.0,
                from_holds: false,
                hold_smoothness_candidates: Vec::new(),
            }),
            (true, None) => {
                // From 10 ms (or two decimated periods) to a quarter of the record (at most
                // 1000 s): longer elements would fit the sensor's drift, not creep.
                const LONGEST_S: f64 = 1000.0;
                let shortest = (2.0 * self.decimation as f64 / rate).max(0.01);
                if shortest > LONGEST_S {
                    return Err(CliError::input(format!(
                        "at {rate} Hz with --decimation {} the shortest creep time constant \
                         (two decimated sample periods) would be {shortest} s, beyond the \
                         longest the default bank takes ({LONGEST_S} s): check the sample \
                         rate (or the time column's unit), or give --creep-time-constants",
                        self.decimation
                    )));
                }
                let record_s = loaded.voltage.len() as f64 / rate;
                let longest = (record_s / 4.0).max(shortest).min(LONGEST_S);
                Some(CreepOptions::log_spaced(shortest, longest, 2))
            }
        };
        let creep = creep.map(|c| match self.creep_fit {
            CreepFit::Joint => c,
            CreepFit::Holds => {
                c.on_holds(&hystcomp_identify::creep_holds::DEFAULT_SMOOTHNESS_CANDIDATES)
            }
        });
        if let Some(c) = &creep {
            bounds::count(
                "--creep-time-constants",
                c.time_constants_s.len(),
                1..=hystcomp_identify::chain::MAX_CREEP_ELEMENTS,
                "time constants",
            )?;
        }
        let dynamics = if self.has_dynamics() {
            let n = loaded.voltage.len();
            let at = |seconds: Option<f64>, default: usize, option: &str| match seconds {
                None => Ok(default),
                Some(s) if s.is_finite() && s >= 0.0 => Ok(((s * rate).round() as usize).min(n)),
                Some(s) => Err(CliError::input(format!(
                    "{option} {s}: give a time in seconds from the start, >= 0"
                ))),
            };
            let from = at(self.dynamics_from, 0, "--dynamics-from")?;
            let to = at(self.dynamics_to, n, "--dynamics-to")?;
            if to <= from {
                return Err(CliError::input(format!(
                    "--dynamics-from .. --dynamics-to selects samples {from}..{to} of {n}: give \
                     a segment that ends after it starts"
                )));
            }
            Some(DynamicsOptions {
                segment: Some(from..to),
                ..DynamicsOptions::default()
            })
        } else {
            None
        };
        Ok(Some(ChainOptions {
            sample_rate_hz: rate,
            decimation: self.decimation,
            creep,
            dynamics,
            output_error_iterations: hystcomp_identify::chain::OUTPUT_ERROR_ITERATIONS,
        }))
    }
}

/// The record's sample rate: from the time column (its mean step), or --sample-rate.
fn sample_rate(columns: &ColumnArgs, loaded: &Loaded) -> Result<f64, CliError> {
    if let Some(step) = loaded.time.as_deref().and_then(data::mean_time_step)
        && step > 0.0
        && step.is_finite()
    {
        return Ok(1.0 / step);
    }
    match columns.sample_rate {
        Some(rate) if rate.is_finite() && rate > 0.0 => Ok(rate),
        Some(rate) => Err(CliError::input(format!(
            "--sample-rate {rate} is not usable: give a rate > 0 in Hz"
        ))),
        None => Err(CliError::input(
            "creep and vibration need the record's sample rate: give --time-column or \
             --sample-rate",
        )),
    }
}

/// With creep or vibration links, a signal must be sampled at the model's rate (the vibration
/// link is a discrete model at it, the creep link discretised for it): `rate_hz` is the
/// signal's (`what`, e.g. "the trajectory"), checked to 0.1 %.
pub fn check_model_rate(model: &ModelFile, rate_hz: f64, what: &str) -> Result<(), CliError> {
    let Some(rate) = model.sample_rate_hz.filter(|_| model.has_links()) else {
        return Ok(());
    };
    if (rate_hz / rate - 1.0).abs() > 1e-3 || !rate_hz.is_finite() {
        return Err(CliError::input(format!(
            "{what} is sampled at {} Hz but the model's creep and vibration links were \
             identified at {} Hz; resample {what} at the model's rate",
            crate::number(rate_hz),
            crate::number(rate)
        )));
    }
    Ok(())
}

/// [`check_model_rate`] for a record read with `columns`: its rate from its time column or
/// `--sample-rate`; with neither, the model's rate is taken and a warning says so.
pub fn check_record_rate(
    model: &ModelFile,
    columns: &ColumnArgs,
    loaded: &Loaded,
) -> Result<(), CliError> {
    let Some(rate) = model.sample_rate_hz.filter(|_| model.has_links()) else {
        return Ok(());
    };
    let timed = loaded.time.as_ref().is_some_and(|t| t.len() >= 2);
    if !timed && columns.sample_rate.is_none() {
        errln!(
            "hystcomp: warning: the record has no time column and no --sample-rate was given; \
             taking it as sampled at the model's {} Hz (its creep and vibration links hold at \
             that rate only)",
            crate::number(rate)
        );
        return Ok(());
    }
    check_model_rate(model, sample_rate(columns, loaded)?, "the record")
}

/// Prints what the chain's links contribute, for people.
pub fn print_chain(report: &ChainReport, unit: &str) -> Result<(), CliError> {
    let span = &report.span;
    if span.record > 0 && (span.hysteresis_end < span.record || span.decimation > 1) {
        let every = match span.decimation {
            1 => "every sample".to_owned(),
            k => format!("every {k} samples"),
        };
        outln!(
            "  chain: the record has {} samples; the hysteresis{} fitted on samples 1 .. {} \
             ({every}; the sample counts above are of those)",
            span.record,
            if report.creep.is_some() {
                " and creep"
            } else {
                ""
            },
            span.hysteresis_end,
        )?;
    }
    if let Some(c) = &report.creep {
        outln!(
            "  creep: {} elements ({} .. {} s), weights sum {:.4} (a held step creeps to {:.4} \
             of itself)",
            c.part.weights.len(),
            crate::number(c.part.time_constants_s[0]),
            crate::number(*c.part.time_constants_s.last().unwrap_or(&0.0)),
            c.part.weights.iter().sum::<f64>(),
            c.static_gain
        )?;
    }
    if let Some(d) = &report.dynamics {
        let modes: Vec<String> = d
            .modes
            .iter()
            .map(|m| format!("{:.1} Hz (damping {:.3})", m.frequency_hz, m.damping_ratio))
            .collect();
        outln!(
            "  vibration: {} poles, {} numerator coefficients, delay {} samples{}",
            d.order.0,
            d.order.1,
            d.part.delay_samples,
            if modes.is_empty() {
                String::new()
            } else {
                format!(", resonances {}", modes.join(", "))
            }
        )?;
    }
    for c in &report.contributions {
        outln!(
            "  {:<12} RMS {:.4} % of the output range{}",
            c.model,
            c.rms_percent,
            c.segment_rms_percent
                .map(|s| format!(" ({s:.4} % on the vibration segment)"))
                .unwrap_or_default()
        )?;
    }
    outln!(
        "  chain:       RMS {:.4} % ({} {unit}), max {:.4} % over the fitted samples",
        report.fit.rms_percent,
        crate::number(report.fit.rms),
        report.fit.max_percent
    )
}
