//! The report's section on the learning study (issue 12): e_rms against trial number for the
//! paper's trajectory and the 100 Hz raster, from the `exact` and the `full` pipeline's IHC, a
//! table of every trial, the laws in force, and issue 12's acceptance figures. The numbers are
//! those of [`LearningStudy`] (`study.json`'s `learning`), so the page, the JSON and the text
//! summary agree.

use std::path::{Path, PathBuf};

use crate::beyond_report::{entry, style_of};
use crate::figures::{self, FigureError, Panel, SeriesStyle};
use crate::learning_study::{LearningStudy, PAPER, PAPER_MHE_BINS, RASTER};
use crate::report::{Table, TableRow, TextSection};

fn percent(v: f64) -> String {
    format!("{v:.4} %")
}

/// Writes the figures into `dir` and returns the section and the files written.
pub(crate) fn learning_section(
    study: &LearningStudy,
    dir: &Path,
) -> Result<(TextSection, Vec<PathBuf>), FigureError> {
    let mut files = Vec::new();
    let laws: Vec<String> = study
        .series
        .iter()
        .map(|s| {
            format!(
                "{}: gain {}, Q cut-off {:.0} Hz (order {}), lead {} samples, stationary noise \
                 ratio {}",
                s.label(),
                s.law.gain,
                s.law.bandwidth_hz,
                s.law.filter_order,
                s.law.lead_samples,
                s.law
                    .stationary_noise_ratio
                    .map_or("unbounded".into(), |r| format!("{r:.4}")),
            )
        })
        .collect();
    let mut section = TextSection::new(
        "Learning from repetition (issue 12)",
        vec![
            "When a motion repeats, hystcomp-learn learns the reference the compensator \
             follows from each measured trial, r_k+1 = sat(r_k + Q[gamma z^m e_k]) (learning \
             through the inverse hysteresis model, Leang & Devasia 2006, \
             doi:10.1016/j.mechatronics.2005.11.006; Q a zero-phase low-pass, Longman 2000, \
             doi:10.1080/002071700405905). Trial 0 is the compensator's own drive (where the \
             amplifier cannot slew it, the speed study's slew-constrained drive); every trial \
             starts from a fresh stage at rest with its own sensor-noise seed, so the noise \
             does not repeat and is not learned. The law runs with its defaults, the same for \
             every motion: nothing here is tuned."
                .into(),
            format!(
                "The paper's trajectory: one 10 s period per trial, played {} times from rest and \
                 measured on the last; e_mhe over {PAPER_MHE_BINS} bins (with 100 a perfect \
                 tracker reads 1 %). The raster: {} µm triangle at {} Hz about the trajectory's \
                 mid-range, corners rounded over {:.0} % of its period, one period per trial \
                 played {} times from rest and measured on the last.",
                study.periods_per_trial.0,
                study.raster_um,
                study.raster_rate_hz,
                100.0 * study.raster_rounding,
                study.periods_per_trial.1,
            ),
            format!("The laws in force: {}.", laws.join("; ")),
        ],
    );
    section.id = "learning".into();
    let longest = study
        .series
        .iter()
        .map(|s| s.trials.len())
        .max()
        .unwrap_or(0);
    let mut columns = vec!["trial".to_string()];
    columns.extend(study.series.iter().map(|s| s.label()));
    let rows = (0..longest)
        .map(|k| {
            TableRow::new(
                k.to_string(),
                study
                    .series
                    .iter()
                    .map(|s| {
                        s.trials.get(k).map_or("-".into(), |p| {
                            if p.limited_share > 0.005 {
                                format!(
                                    "{} ({:.0} % limited)",
                                    percent(p.indices.e_rms_percent),
                                    100.0 * p.limited_share
                                )
                            } else {
                                percent(p.indices.e_rms_percent)
                            }
                        })
                    })
                    .collect(),
            )
        })
        .collect();
    section.tables.push(Table {
        id: "learning-trials".into(),
        caption: "e_rms against trial number".into(),
        columns,
        rows,
        note: "e_rms in % of the desired range over the measured period; where the amplifier \
               was at its slew or rail limit in more than 0.5 % of that period's samples, the \
               share is given."
            .into(),
    });
    let mut floor_rows = Vec::new();
    for s in &study.series {
        if let Some(last) = s.trials.last() {
            floor_rows.push(TableRow::new(
                s.label(),
                vec![
                    percent(last.indices.e_rms_percent),
                    percent(last.indices.e_m_percent),
                    percent(last.indices.e_mhe_percent),
                    percent(last.noise_floor_percent),
                    if s.stopped { "stopped" } else { "learning" }.into(),
                ],
            ));
        }
    }
    section.tables.push(Table {
        id: "learning-last".into(),
        caption: "The last trial against the sensor's noise floor".into(),
        columns: vec![
            "series".into(),
            "e_rms".into(),
            "e_m".into(),
            "e_mhe".into(),
            "noise floor (RMS)".into(),
            "status".into(),
        ],
        rows: floor_rows,
        note: "The noise floor is the RMS of the sensor noise alone over the measured period \
               (measured minus true position), in % of the desired range."
            .into(),
    });
    section.tables.push(Table {
        id: "learning-checks".into(),
        caption: "Issue 12's acceptance figures (reported, not counted)".into(),
        columns: vec![
            "what".into(),
            "measured".into(),
            "bound".into(),
            "verdict".into(),
        ],
        rows: study
            .checks
            .iter()
            .map(|c| {
                TableRow::new(
                    c.what.clone(),
                    vec![
                        percent(c.value),
                        c.bound.clone(),
                        if c.passed { "met" } else { "missed" }.into(),
                    ],
                )
            })
            .collect(),
        note: "The README's section on learning says by how much and why a miss misses.".into(),
    });
    for (trajectory, stem, title) in [
        (
            PAPER,
            "figS_learning_paper",
            "Learning: the paper's trajectory (dotted: from exact / ihc; solid: from full / ihc)",
        ),
        (
            RASTER,
            "figS_learning_raster",
            "Learning: 20 µm raster at 100 Hz (dotted: from exact / ihc; solid: from full / ihc)",
        ),
    ] {
        let series: Vec<_> = study
            .series
            .iter()
            .filter(|s| s.trajectory == trajectory)
            .collect();
        let curves: Vec<(String, Vec<f64>, Vec<f64>)> = series
            .iter()
            .map(|s| {
                (
                    s.start.clone(),
                    s.trials.iter().map(|p| p.trial as f64).collect(),
                    s.trials.iter().map(|p| p.indices.e_rms_percent).collect(),
                )
            })
            .collect();
        let floor: Option<(Vec<f64>, Vec<f64>)> = series.first().map(|s| {
            (
                s.trials.iter().map(|p| p.trial as f64).collect(),
                s.trials.iter().map(|p| p.noise_floor_percent).collect(),
            )
        });
        let positive = curves
            .iter()
            .flat_map(|c| &c.2)
            .chain(floor.iter().flat_map(|f| &f.1))
            .all(|&v| v > 0.0 && v.is_finite());
        let mut panel = Panel::time_series(title, "e_rms (% of the desired range)")
            .with_axis_labels(
                "trial",
                if positive {
                    "e_rms (%, log scale)"
                } else {
                    "e_rms (%)"
                },
            );
        if positive {
            panel = panel.with_log_y();
        }
        for (label, x, y) in &curves {
            if y.iter().all(|v| v.is_finite()) && y.len() >= 2 {
                panel = panel.with_styled_series(label, x, y, style_of(label));
            }
        }
        if let Some((x, y)) = &floor
            && y.iter().all(|v| v.is_finite())
            && y.len() >= 2
        {
            panel = panel.with_styled_series("sensor noise floor", x, y, SeriesStyle::DESIRED);
        }
        let written = figures::write_panel_figure(dir, stem, &panel)?;
        files.extend([written.png.clone(), written.svg.clone()]);
        section.figures.push(entry(
            &written,
            format!("{title}: e_rms against trial number (logarithmic axis), with the sensor noise floor."),
        ));
    }
    Ok((section, files))
}
