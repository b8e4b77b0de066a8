//! The report's sections beyond the paper (issue 11): the `full` pipeline (hysteresis, creep
//! and vibration identified by least squares and inverted in reverse order), the duration and
//! speed studies, each with its figures and tables, and issue 11's targets with the verdict of
//! each. The numbers are those of [`BeyondSummary`] (`study.json`'s `beyond`), so the page, the
//! JSON and the text summary agree.

use std::path::{Path, PathBuf};

use crate::beyond::BeyondSummary;
use crate::figures::{
    self, FigureError, FigureFiles, LABEL_ACTUAL_POSITION, LABEL_DESIRED_POSITION, LABEL_POSITION,
    LABEL_TRACKING_ERROR, Panel, SeriesStyle,
};
use crate::report::{FigureEntry, Table, TableRow, TextSection};
use crate::speed::SpeedPoint;
use crate::study::Study;

/// The style of an approach by its label (`exact / ihc`, `full / dihc`, `uncompensated`):
/// the compensator's colour; the `exact` pipeline dotted beside the `full` one's solid line.
pub(crate) fn style_of(label: &str) -> SeriesStyle {
    let (pipeline, approach) = label.split_once(" / ").unwrap_or(("", label));
    let style = SeriesStyle::of_approach(approach).unwrap_or(SeriesStyle::IHC);
    if pipeline == "exact" {
        style.with_line(figures::Line::Dotted)
    } else {
        style
    }
}

pub(crate) fn entry(files: &FigureFiles, caption: String) -> FigureEntry {
    let name = |path: &Path| {
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    FigureEntry {
        png_file: name(&files.png),
        svg_file: Some(name(&files.svg)),
        paper_figure: String::new(),
        caption,
    }
}

/// Writes the figures into `dir` and returns the sections (full pipeline, duration, speed,
/// issue 11's targets) and the files written.
pub(crate) fn beyond_sections(
    study: &Study,
    beyond: &BeyondSummary,
    dir: &Path,
) -> Result<(Vec<TextSection>, Vec<PathBuf>), FigureError> {
    let mut files = Vec::new();
    let mut keep = |f: FigureFiles| {
        files.extend([f.png.clone(), f.svg.clone()]);
        f
    };
    let full = full_section(study, beyond, dir, &mut keep)?;
    let duration = duration_section(beyond, dir, &mut keep)?;
    let speed = speed_section(beyond, dir, &mut keep)?;
    let targets = targets_section(beyond);
    Ok((vec![full, duration, speed, targets], files))
}

fn percent(v: f64) -> String {
    format!("{v:.3} %")
}

fn full_section(
    study: &Study,
    beyond: &BeyondSummary,
    dir: &Path,
    keep: &mut impl FnMut(FigureFiles) -> FigureFiles,
) -> Result<TextSection, FigureError> {
    let f = &beyond.full;
    let start = study.evaluation_start;
    let time = &study.time_s;
    let desired = &study.desired_um;
    let mut section = TextSection::new(
        "Beyond the paper: the full pipeline (hysteresis -> creep -> vibration)",
        vec![
            format!(
                "The plant is the chain y = D[C[H[v]]] (Croft, Shed & Devasia 2001, \
                 doi:10.1115/1.1341197): the MPIM H, then the creep link C acting on the \
                 hysteresis output (the stack's displacement creeps, not its voltage; {} \
                 first-order elements at fixed log-spaced time constants, Kuhnen's creep \
                 operators, Kuhnen & Krejci 2001, 2009), then the vibration link D (a discrete \
                 linear model of unit static gain with a delay of {} samples, {} poles and {} \
                 numerator coefficients, order chosen from data). The creep weights are fitted \
                 on the record's holds, where the hysteresis does not move (their smoothness \
                 and the longest time constant chosen by leaving each hold out), then the \
                 hysteresis on the creep-free displacement by least squares under the \
                 invertibility constraints; the vibration link from the small multisine around \
                 mid-range. \
                 Everything comes from the {:.0} s identification record's (voltage, \
                 displacement) samples, never from the stage file ({:.2} s of computing).",
                f.creep_time_constants_s.len(),
                f.vibration_delay_samples,
                f.vibration_order.0,
                f.vibration_order.1,
                f.record_s,
                f.identification_s,
            ),
            format!(
                "The compensators invert the chain in reverse order: the vibration link \
                 non-causally over the whole known trajectory (stable inversion with a preview: \
                 the zeros outside the unit circle anti-causally, Leang, Zou & Devasia 2009), \
                 then the creep link (a plain filter), then the exact IHC, WIHC or DIHC. The \
                 model's creep settles at {:.4} times a held step; its resonances: {}.",
                f.creep_static_gain,
                if f.modes.is_empty() {
                    "none (a first-order or pure-delay link was chosen)".to_string()
                } else {
                    f.modes
                        .iter()
                        .map(|(hz, zeta)| format!("{hz:.0} Hz, damping {zeta:.3}"))
                        .collect::<Vec<_>>()
                        .join("; ")
                }
            ),
        ],
    );
    section.id = "full-pipeline".into();
    let mut rows: Vec<TableRow> = Vec::new();
    if let Some(exact) = study.pipeline("exact") {
        for run in &exact.runs {
            rows.push(TableRow::new(
                run.label.clone(),
                vec![
                    percent(run.indices.e_mhe_percent),
                    percent(run.indices.e_m_percent),
                    percent(run.indices.e_rms_percent),
                ],
            ));
        }
    }
    for (label, i) in &f.runs {
        rows.push(TableRow::new(
            label.clone(),
            vec![
                percent(i.e_mhe_percent),
                percent(i.e_m_percent),
                percent(i.e_rms_percent),
            ],
        ));
    }
    section.tables.push(Table {
        id: "full-indices".into(),
        caption: "The paper's trajectory, last full period: the exact pipeline (hysteresis \
                  only) against the full one"
            .into(),
        columns: vec![
            "approach".into(),
            "e_mhe".into(),
            "e_m".into(),
            "e_rms".into(),
        ],
        rows,
        note: "% of the desired range; e_mhe over the study's bins.".into(),
    });
    let contributions = |list: &[hystcomp_identify::Contribution]| -> Vec<TableRow> {
        list.iter()
            .map(|c| {
                TableRow::new(
                    c.model.clone(),
                    vec![
                        percent(c.rms_percent),
                        c.segment_rms_percent.map_or("-".into(), percent),
                    ],
                )
            })
            .collect()
    };
    section.tables.push(Table {
        id: "full-contributions-plant".into(),
        caption: "What each link contributes: the plant chain's fit, link by link".into(),
        columns: vec![
            "links".into(),
            "RMS error, whole record".into(),
            "RMS error, vibration segment".into(),
        ],
        rows: contributions(&f.plant_contributions),
        note: "% of the fitted displacement range.".into(),
    });
    section.tables.push(Table {
        id: "full-contributions-inverse".into(),
        caption: "The inverse chain's fit (DIHC), link by link".into(),
        columns: vec![
            "links".into(),
            "RMS error, whole record".into(),
            "RMS error, vibration segment".into(),
        ],
        rows: contributions(&f.inverse_contributions),
        note: "% of the voltage range.".into(),
    });
    // The full IHC like figs. 8-10, and the three approaches' errors against the exact IHC's.
    if let Some(run) = study.full.runs.first() {
        let error: Vec<f64> = run
            .measured_um
            .iter()
            .zip(desired)
            .map(|(y, d)| y - d)
            .collect();
        let notes = [format!(
            "e_m = {:.2} %, e_rms = {:.3} %",
            run.indices.e_m_percent, run.indices.e_rms_percent
        )];
        let map = Panel::map("(a) actual against desired position", true)
            .with_axis_labels(LABEL_DESIRED_POSITION, LABEL_ACTUAL_POSITION)
            .with_styled_series(
                "measured y",
                &desired[start..],
                &run.measured_um[start..],
                SeriesStyle::IHC,
            );
        let response = Panel::time_series("(b) response", LABEL_POSITION)
            .with_styled_series("desired y_d", time, desired, SeriesStyle::DESIRED)
            .with_styled_series("measured y", time, &run.measured_um, SeriesStyle::IHC);
        let error_panel =
            Panel::time_series("(c) tracking error, last full period", LABEL_TRACKING_ERROR)
                .with_styled_series("y - y_d", &time[start..], &error[start..], SeriesStyle::IHC)
                .with_note(&notes[0]);
        let title = format!("full pipeline, IHC ({})", run.label);
        let files = keep(figures::write_approach_figure(
            dir,
            "figS_full_ihc",
            &title,
            &map,
            &response,
            &error_panel,
        )?);
        section.figures.push(entry(
            &files,
            "IHC in the full pipeline: (a) actual against desired position and (c) the tracking \
             error over the last full period, (b) the response from rest."
                .into(),
        ));
    }
    let mut runs: Vec<&crate::study::TrackingRun> = Vec::new();
    if let Some(exact) = study.pipeline("exact") {
        runs.extend(exact.runs.first());
    }
    runs.extend(
        study
            .full
            .runs
            .iter()
            .filter(|r| !r.label.ends_with("wihc")),
    );
    let errors: Vec<(String, Vec<f64>)> = runs
        .iter()
        .map(|run| {
            (
                format!("{} (e_rms {:.3} %)", run.label, run.indices.e_rms_percent),
                run.measured_um[start..]
                    .iter()
                    .zip(&desired[start..])
                    .map(|(y, d)| y - d)
                    .collect(),
            )
        })
        .collect();
    let mut panel = Panel::time_series(
        "Tracking errors, last full period: exact IHC against the full pipeline",
        LABEL_TRACKING_ERROR,
    );
    for (run, (label, error)) in runs.iter().zip(&errors) {
        panel = panel.with_styled_series(label, &time[start..], error, style_of(&run.label));
    }
    let files = keep(figures::write_panel_figure(
        dir,
        "figS_full_errors",
        &panel,
    )?);
    section.figures.push(entry(
        &files,
        "The tracking error of the exact pipeline's IHC (dotted; hysteresis only) and of the full \
         pipeline's IHC and DIHC over the last full period (WIHC tracks as IHC and is left out)."
            .into(),
    ));
    Ok(section)
}

fn duration_section(
    beyond: &BeyondSummary,
    dir: &Path,
    keep: &mut impl FnMut(FigureFiles) -> FigureFiles,
) -> Result<TextSection, FigureError> {
    let d = &beyond.duration;
    let mut section = TextSection::new(
        "Beyond the paper: how long (the duration study)",
        vec![format!(
            "The paper's trajectory tracked for {:.0} s instead of 20 s, the indices taken on \
             every {:.0} s period; and a {:.0} µm step from rest held for {:.0} s: the error \
             1 s after the step and the largest distance from that position over the rest of \
             the hold (the drift creep causes). Every approach runs from rest on a fresh stage. \
             WIHC is not repeated: the exact WIHC solves the same equation as the exact IHC \
             (eqs. (5) and (9)), so its drive is IHC's to rounding (the tracking runs above give \
             both the same indices).",
            d.duration_s, d.period_s, d.hold_step_um, d.hold_s
        )],
    );
    section.id = "duration".into();
    let rows = d
        .series
        .iter()
        .map(|s| {
            let at = |t: f64| s.at(t).map_or("-".into(), |i| percent(i.e_rms_percent));
            let hold = d.hold.iter().find(|h| h.label == s.label);
            TableRow::new(
                s.label.clone(),
                vec![
                    at(2.0 * d.period_s),
                    at(d.duration_s),
                    hold.map_or("-".into(), |h| format!("{:.3} µm", h.error_at_reference_um)),
                    hold.map_or("-".into(), |h| format!("{:.3} µm", h.drift_um)),
                ],
            )
        })
        .collect();
    section.tables.push(Table {
        id: "duration-table".into(),
        caption: "e_rms of the period ending at 20 s and at the end; the held step".into(),
        columns: vec![
            "approach".into(),
            format!("e_rms at {:.0} s", 2.0 * d.period_s),
            format!("e_rms at {:.0} s", d.duration_s),
            "error 1 s after the step".into(),
            format!("drift over {:.0} s", d.hold_s),
        ],
        rows,
        note: "e_rms in % of the desired range.".into(),
    });
    let values: Vec<Vec<f64>> = d
        .series
        .iter()
        .map(|s| s.indices.iter().map(|i| i.e_rms_percent).collect())
        .collect();
    let log_axis = values.iter().flatten().all(|&v| v > 0.0);
    let mut panel = Panel::time_series(
        "Duration: e_rms of each period against time",
        "e_rms of the period (% of the desired range)",
    )
    .with_axis_labels(
        "end of the period (s)",
        if log_axis {
            "e_rms of the period (%, log scale)"
        } else {
            "e_rms of the period (%)"
        },
    );
    if log_axis {
        panel = panel.with_log_y();
    }
    for (s, v) in d.series.iter().zip(&values) {
        panel = panel.with_styled_series(&s.label, &s.period_end_s, v, style_of(&s.label));
    }
    let files = keep(figures::write_panel_figure(dir, "figS_duration", &panel)?);
    section.figures.push(entry(
        &files,
        format!(
            "e_rms of each {:.0} s period of the paper's trajectory over {:.0} s (logarithmic \
             axis): creep makes the hysteresis-only compensation drift; the full pipeline holds.",
            d.period_s, d.duration_s
        ),
    ));
    // The hold: position minus the target, from 1 s after the step.
    let seconds: Vec<Vec<f64>> = d
        .hold
        .iter()
        .map(|h| (0..h.positions_um.len()).map(|k| 1.0 + k as f64).collect())
        .collect();
    let offsets: Vec<Vec<f64>> = d
        .hold
        .iter()
        .map(|h| h.positions_um.iter().map(|p| p - d.hold_step_um).collect())
        .collect();
    let mut panel = Panel::time_series(
        "Holding a step: position minus the target",
        "position - target (µm)",
    )
    .with_axis_labels("time after the step (s)", "position - target (µm)");
    for ((h, t), y) in d.hold.iter().zip(&seconds).zip(&offsets) {
        panel = panel.with_styled_series(&h.label, t, y, style_of(&h.label));
    }
    let files = keep(figures::write_panel_figure(dir, "figS_hold", &panel)?);
    section.figures.push(entry(
        &files,
        format!(
            "A {:.0} µm step from rest held {:.0} s: the position (0.1 s averages, one a second) \
             minus the target, from 1 s after the step.",
            d.hold_step_um, d.hold_s
        ),
    ));
    Ok(section)
}

/// A table of e_rms against rate for the approaches of `points`.
fn speed_table(id: &str, caption: String, unit: &str, points: &[SpeedPoint]) -> Table {
    let labels: Vec<String> = points
        .first()
        .map(|p| p.runs.iter().map(|r| r.label.clone()).collect())
        .unwrap_or_default();
    let mut columns = vec![unit.to_string(), "amplitude scale".into()];
    columns.extend(labels.iter().cloned());
    let rows = points
        .iter()
        .map(|p| {
            let mut cells = vec![format!("{:.3}", p.amplitude_scale)];
            for label in &labels {
                cells.push(p.run(label).map_or("-".into(), |r| {
                    let mut cell = percent(r.indices.e_rms_percent);
                    if r.limited_share > 0.005 {
                        cell.push_str(&format!(
                            " ({:.0} % at the amplifier's limits)",
                            100.0 * r.limited_share
                        ));
                    }
                    if r.slew_constrained {
                        cell.push_str(" (slew-constrained drive)");
                    }
                    cell
                }));
            }
            TableRow::new(format!("{} Hz", p.rate_hz), cells)
        })
        .collect();
    Table {
        id: id.into(),
        caption,
        columns,
        rows,
        note: "e_rms in % of the desired range (last period); a share at the amplifier's slew \
               or rail limit is given where it exceeds 0.5 % of the samples. Where the faithful \
               inverse of a chain with a vibration link asks more than the amplifier's slew \
               rate, the raster is driven by the slew-constrained drive (the chain's inverse \
               as a quadratic programme with every drive step within 0.9 of the slew rate)."
            .into(),
    }
}

fn speed_section(
    beyond: &BeyondSummary,
    dir: &Path,
    keep: &mut impl FnMut(FigureFiles) -> FigureFiles,
) -> Result<TextSection, FigureError> {
    let s = &beyond.speed;
    let mut section = TextSection::new(
        "Beyond the paper: how fast (the speed study)",
        vec![format!(
            "The same models, identified once from the study's excitation, track the paper's \
             trajectory time-compressed so that its fastest tone is 1-100 Hz (the amplitude \
             reduced where the amplifier cannot slew it, by the scale given), and a 20 µm \
             triangle raster around mid-range with corners rounded over 5 % of its period at \
             10-200 Hz, on the built-in amplifier and on one with ten times its slew rate \
             ({:.1} kV/s).",
            s.strong_slew_v_per_s / 1e3
        )],
    );
    section.id = "speed".into();
    let sets: [(&str, &str, &[SpeedPoint], &str); 3] = [
        (
            "speed-paper",
            "the paper's trajectory, time-compressed",
            &s.paper,
            "fastest tone",
        ),
        (
            "speed-raster",
            "the 20 µm rounded raster, built-in amplifier",
            &s.raster,
            "scan rate",
        ),
        (
            "speed-raster-strong",
            "the 20 µm rounded raster, amplifier with ten times the slew rate",
            &s.raster_strong_amplifier,
            "scan rate",
        ),
    ];
    for (id, what, points, unit) in sets {
        section.tables.push(speed_table(
            id,
            format!("e_rms against rate: {what}"),
            unit,
            points,
        ));
    }
    for (stem, title, points, x_label) in [
        (
            "figS_speed_paper",
            "Speed: the paper's trajectory, time-compressed",
            &s.paper,
            "fastest tone of the trajectory (Hz)",
        ),
        (
            "figS_speed_raster",
            "Speed: 20 µm rounded triangle raster (solid: built-in amplifier; faint: 10x slew)",
            &s.raster,
            "scan rate (Hz)",
        ),
    ] {
        let labels: Vec<String> = points
            .first()
            .map(|p| p.runs.iter().map(|r| r.label.clone()).collect())
            .unwrap_or_default();
        let rates: Vec<f64> = points.iter().map(|p| p.rate_hz).collect();
        let curve = |points: &[SpeedPoint], label: &str| -> Vec<f64> {
            points
                .iter()
                .map(|p| p.run(label).map_or(f64::NAN, |r| r.indices.e_rms_percent))
                .collect()
        };
        let values: Vec<Vec<f64>> = labels.iter().map(|l| curve(points, l)).collect();
        let strong_rates: Vec<f64> = s
            .raster_strong_amplifier
            .iter()
            .map(|p| p.rate_hz)
            .collect();
        let strong: Vec<Vec<f64>> = if stem == "figS_speed_raster" {
            labels
                .iter()
                .map(|l| curve(&s.raster_strong_amplifier, l))
                .collect()
        } else {
            Vec::new()
        };
        let positive = values.iter().chain(&strong).flatten().all(|&v| v > 0.0);
        let mut panel = Panel::time_series(title, "e_rms (% of the desired range)")
            .with_axis_labels(
                x_label,
                if positive {
                    "e_rms (%, log scale)"
                } else {
                    "e_rms (%)"
                },
            );
        if positive {
            panel = panel.with_log_y();
        }
        for (label, v) in labels.iter().zip(&values) {
            if v.iter().all(|x| x.is_finite()) {
                panel = panel.with_styled_series(label, &rates, v, style_of(label));
            }
        }
        for (label, v) in labels.iter().zip(&strong) {
            if v.iter().all(|x| x.is_finite()) {
                panel = panel.with_styled_series("", &strong_rates, v, style_of(label).faint());
            }
        }
        let files = keep(figures::write_panel_figure(dir, stem, &panel)?);
        section.figures.push(entry(
            &files,
            format!("{title}: e_rms against rate (logarithmic axis)."),
        ));
    }
    Ok(section)
}

/// The report writes µm where the text summary (and `study.json`) writes um.
fn micrometres(text: &str) -> String {
    let mut out = text.to_string();
    for (from, to) in [
        (" um ", " µm "),
        (" um)", " µm)"),
        (" um,", " µm,"),
        (" um.", " µm."),
    ] {
        out = out.replace(from, to);
    }
    match out.strip_suffix(" um") {
        Some(head) => format!("{head} µm"),
        None => out,
    }
}

fn targets_section(beyond: &BeyondSummary) -> TextSection {
    let met = beyond.checks.iter().filter(|c| c.passed).count();
    let mut section = TextSection::new(
        "Issue 11's targets (reported, not counted)",
        vec![format!(
            "{met} of {} met. These targets are measured, not tuned for: they do not change the \
             exit status of reproduce. The README's section on the full pipeline says by how \
             much and why each miss misses.",
            beyond.checks.len()
        )],
    );
    section.id = "issue-11-targets".into();
    section.tables.push(Table {
        id: "issue-11-checks".into(),
        caption: String::new(),
        columns: vec![
            "what".into(),
            "measured".into(),
            "bound".into(),
            "verdict".into(),
        ],
        rows: beyond
            .checks
            .iter()
            .map(|c| {
                TableRow::new(
                    micrometres(&c.what),
                    vec![
                        format!("{:.3}", c.value),
                        micrometres(&c.bound),
                        if c.passed { "met" } else { "missed" }.into(),
                    ],
                )
            })
            .collect(),
        note: String::new(),
    });
    section
}

#[cfg(test)]
mod tests {
    use super::micrometres;

    #[test]
    fn um_becomes_micrometres_only_as_a_unit() {
        assert_eq!(
            micrometres("drift over a 60 s hold after a 50 um step"),
            "drift over a 60 s hold after a 50 µm step"
        );
        assert_eq!(micrometres("<= 0.1 um"), "<= 0.1 µm");
        assert_eq!(micrometres("(0.2 um), 3 um."), "(0.2 µm), 3 µm.");
        assert_eq!(micrometres("uncompensated umbra"), "uncompensated umbra");
    }
}
