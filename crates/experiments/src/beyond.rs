//! The study beyond the paper, summarised (issue 11): the `full` pipeline (hysteresis, creep
//! and vibration), what each link contributes to the fit, the duration and speed studies, and
//! the acceptance figures measured against their bounds. Printed by `hystcomp
//! reproduce` and written in `study.json` (`beyond`).
//!
//! The checks here are **reported, not counted** in the study's acceptance (the exit status of
//! `reproduce`): they are targets the simulated stage is not tuned toward, and the report says
//! by how much and why one misses.

use std::fmt;

use hystcomp_identify::Contribution;
use serde::Serialize;

use crate::TrackingIndices;
use crate::duration::{DurationStudy, HoldRun};
use crate::speed::SpeedStudy;
use crate::study::{FULL_IHC_LABEL, Study};
use crate::study_report::{AcceptanceCheck, write_targets};

/// The `full` pipeline's summary.
#[derive(Debug, Clone, Serialize)]
pub struct FullSummary {
    /// IHC, WIHC and DIHC on the paper's trajectory (the study's two periods): label and
    /// indices.
    pub runs: Vec<(String, TrackingIndices)>,
    /// The plant chain's fit, link by link (RMS % of the fitted output range, over the fitted
    /// samples and over the vibration segment).
    pub plant_contributions: Vec<Contribution>,
    /// The inverse chain's fit, link by link (% of the voltage range).
    pub inverse_contributions: Vec<Contribution>,
    /// The creep link's weights (inverse parameterisation) and time constants, s.
    pub creep_time_constants_s: Vec<f64>,
    /// The creep link's weights.
    pub creep_weights: Vec<f64>,
    /// How far a held step creeps in the end, by the model.
    pub creep_static_gain: f64,
    /// The vibration link's resonances: (Hz, damping ratio).
    pub modes: Vec<(f64, f64)>,
    /// Its delay, samples, and orders (poles, numerator coefficients).
    pub vibration_delay_samples: usize,
    /// Its orders.
    pub vibration_order: (usize, usize),
    /// Length of the identification record the chain was fitted on, s.
    pub record_s: f64,
    /// Wall-clock time of the chain's two identifications, s.
    pub identification_s: f64,
}

/// Everything beyond the paper.
#[derive(Debug, Clone, Serialize)]
pub struct BeyondSummary {
    /// The `full` pipeline.
    pub full: FullSummary,
    /// The duration study (per-period indices of every approach, the held step).
    pub duration: DurationStudy,
    /// The speed study.
    pub speed: SpeedStudy,
    /// Issue 11's acceptance figures (reported, not counted).
    pub checks: Vec<AcceptanceCheck>,
}

fn check(what: String, value: f64, bound: f64, unit: &str) -> AcceptanceCheck {
    AcceptanceCheck {
        what,
        value,
        bound: format!("<= {bound} {unit}"),
        passed: value <= bound,
    }
}

/// The summary of the study's part beyond the paper, with issue 11's checks evaluated.
pub fn summarize_beyond(study: &Study) -> BeyondSummary {
    let full = &study.full;
    let plant = &full.plant.report;
    let creep = plant.creep.as_ref();
    let dynamics = plant.dynamics.as_ref();
    let mut checks = Vec::new();
    for run in &full.runs {
        checks.push(check(
            format!("{}: e_rms over 20 s", run.label),
            run.indices.e_rms_percent,
            0.25,
            "%",
        ));
    }
    for series in &study.duration.series {
        if series.label.starts_with("full")
            && let Some(i) = series.at(study.duration.duration_s)
        {
            checks.push(check(
                format!(
                    "{}: e_rms over {} s (last period)",
                    series.label, study.duration.duration_s
                ),
                i.e_rms_percent,
                0.30,
                "%",
            ));
        }
    }
    for hold in &study.duration.hold {
        if hold.label.starts_with("full") {
            checks.push(check(
                format!(
                    "{}: drift over a {} s hold after a {} um step",
                    hold.label, study.duration.hold_s, study.duration.hold_step_um
                ),
                hold.drift_um,
                0.1,
                "um",
            ));
        }
    }
    let speed = &study.speed;
    for (points, amplifier) in [
        (&speed.raster, "built-in amplifier"),
        (
            &speed.raster_strong_amplifier,
            "amplifier with 10x the slew rate",
        ),
    ] {
        if let Some(run) = points
            .iter()
            .find(|p| (p.rate_hz - 100.0).abs() < 1e-9)
            .and_then(|p| p.run(FULL_IHC_LABEL))
        {
            checks.push(check(
                format!("{FULL_IHC_LABEL}: 20 um raster at 100 Hz, {amplifier}: e_rms"),
                run.indices.e_rms_percent,
                0.5,
                "%",
            ));
        }
    }
    if let Some(run) = speed
        .paper
        .iter()
        .find(|p| (p.rate_hz - 10.0).abs() < 1e-9)
        .and_then(|p| p.run(FULL_IHC_LABEL))
    {
        checks.push(check(
            format!("{FULL_IHC_LABEL}: the paper's trajectory at 10x speed: e_rms"),
            run.indices.e_rms_percent,
            0.35,
            "%",
        ));
    }
    BeyondSummary {
        full: FullSummary {
            runs: full
                .runs
                .iter()
                .map(|r| (r.label.clone(), r.indices))
                .collect(),
            plant_contributions: plant.contributions.clone(),
            inverse_contributions: full.inverse.report.contributions.clone(),
            creep_time_constants_s: creep
                .map(|c| c.part.time_constants_s.clone())
                .unwrap_or_default(),
            creep_weights: creep.map(|c| c.part.weights.clone()).unwrap_or_default(),
            creep_static_gain: creep.map_or(1.0, |c| c.static_gain),
            modes: dynamics
                .map(|d| {
                    d.modes
                        .iter()
                        .map(|m| (m.frequency_hz, m.damping_ratio))
                        .collect()
                })
                .unwrap_or_default(),
            vibration_delay_samples: dynamics.map_or(0, |d| d.part.delay_samples),
            vibration_order: dynamics.map_or((0, 0), |d| d.order),
            record_s: full.record_s,
            identification_s: full.identification_s,
        },
        duration: study.duration.clone(),
        speed: study.speed.clone(),
        checks,
    }
}

fn hold_line(f: &mut fmt::Formatter<'_>, h: &HoldRun) -> fmt::Result {
    writeln!(
        f,
        "  {:<16} {:>8.3} um {:>10.3} um",
        h.label, h.error_at_reference_um, h.drift_um
    )
}

impl fmt::Display for BeyondSummary {
    /// The full pipeline, the duration and speed studies and issue 11's checks, as text.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "full pipeline (hysteresis + creep + vibration, least squares on {:.0} s of \
             excitation), e_mhe / e_m / e_rms %:",
            self.full.record_s
        )?;
        for (label, i) in &self.full.runs {
            writeln!(
                f,
                "  {:<16} {:>6.2} {:>6.2} {:>7.3}",
                label, i.e_mhe_percent, i.e_m_percent, i.e_rms_percent
            )?;
        }
        write!(f, "  plant fit, RMS % of the output range:")?;
        for c in &self.full.plant_contributions {
            write!(f, " {} {:.3}", c.model, c.rms_percent)?;
            if let Some(s) = c.segment_rms_percent {
                write!(f, " ({s:.3} on the vibration segment)")?;
            }
            write!(f, ";")?;
        }
        writeln!(f)?;
        let d = &self.duration;
        writeln!(
            f,
            "duration: e_rms % of the period ending at 20 s and at {} s:",
            d.duration_s
        )?;
        for s in &d.series {
            let at = |t: f64| s.at(t).map_or(f64::NAN, |i| i.e_rms_percent);
            writeln!(
                f,
                "  {:<16} {:>7.3} {:>7.3}",
                s.label,
                at(20.0),
                at(d.duration_s)
            )?;
        }
        writeln!(
            f,
            "held {} um step, {} s: error 1 s after the step, drift over the hold:",
            d.hold_step_um, d.hold_s
        )?;
        for h in &d.hold {
            hold_line(f, h)?;
        }
        writeln!(
            f,
            "speed: e_rms % (amplitude scale; share at the amplifier's limits):"
        )?;
        for (name, points) in [
            ("paper, fastest tone", &self.speed.paper),
            ("raster 20 um", &self.speed.raster),
            ("raster, 10x slew", &self.speed.raster_strong_amplifier),
        ] {
            for p in points.iter() {
                write!(
                    f,
                    "  {name} {:>5} Hz ({:.3}):",
                    p.rate_hz, p.amplitude_scale
                )?;
                for r in &p.runs {
                    write!(
                        f,
                        "  {} {:.3}{}",
                        r.label,
                        r.indices.e_rms_percent,
                        if r.limited_share > 0.0 {
                            format!(" ({:.0} % limited)", 100.0 * r.limited_share)
                        } else {
                            String::new()
                        }
                    )?;
                }
                writeln!(f)?;
            }
        }
        write_targets(f, 11, &self.checks, |v| format!("{v:.3}"))
    }
}
