//! What the report's templates show, prepared from [`ReportData`]: numbers formatted, checks
//! judged, rows laid out. The templates (`crates/experiments/templates/`) hold the markup; the
//! engine (minijinja) escapes every value, since their names end in `.html`.

use std::collections::BTreeSet;
use std::sync::OnceLock;

use minijinja::Environment;
use serde::Serialize;

use super::{
    AcceptanceBound, Check, Compensator, Fact, FigureEntry, IndexName, ModelParameters, ReportData,
    ReportError, SOFTWARE_VERSION, Seed, Table,
};
use crate::reference::{Reference, ReferenceMpim};

/// The templates, by name, compiled into the crate. A study with markup of its own adds
/// `("studies/NAME.html", include_str!(...))` here.
const TEMPLATES: &[(&str, &str)] = &[
    ("report.html", include_str!("../../templates/report.html")),
    ("report.css", include_str!("../../templates/report.css")),
    ("macros.html", include_str!("../../templates/macros.html")),
    ("header.html", include_str!("../../templates/header.html")),
    ("table3.html", include_str!("../../templates/table3.html")),
    ("section.html", include_str!("../../templates/section.html")),
    ("figures.html", include_str!("../../templates/figures.html")),
    (
        "parameters.html",
        include_str!("../../templates/parameters.html"),
    ),
    ("run.html", include_str!("../../templates/run.html")),
];

/// Whether `templates/studies/{name}.html` is registered.
pub(super) fn has_study_template(name: &str) -> bool {
    let wanted = format!("studies/{name}.html");
    TEMPLATES.iter().any(|(n, _)| *n == wanted)
}

/// The environment with every template added (once per process).
fn environment() -> Result<&'static Environment<'static>, ReportError> {
    static ENV: OnceLock<Result<Environment<'static>, String>> = OnceLock::new();
    ENV.get_or_init(|| {
        let mut env = Environment::new();
        for (name, source) in TEMPLATES {
            env.add_template(name, source)
                .map_err(|e| format!("{name}: {e:#}"))?;
        }
        Ok(env)
    })
    .as_ref()
    .map_err(|e| ReportError::Template(e.clone()))
}

/// The page, from validated data, its checks and the figures' sizes (the report's figures,
/// then each section's, in order).
pub(super) fn render(
    data: &ReportData,
    checks: &[Check<'_>],
    sizes: &[(u32, u32)],
) -> Result<String, ReportError> {
    let mut sizes = sizes.iter().copied();
    // Figures are labelled with the paper's number ("Fig. 8 (a)-(c)"); those the paper has
    // no equivalent of are numbered S1, S2, ... (supplementary).
    let mut supplementary = 0;
    let mut label = |f: &FigureEntry| {
        if f.paper_figure.is_empty() {
            supplementary += 1;
            format!("Fig. S{supplementary}")
        } else {
            f.paper_figure.clone()
        }
    };
    let figures: Vec<FigureView<'_>> = data
        .figures
        .iter()
        .map(|f| FigureView::new(f, label(f), &mut sizes))
        .collect();
    let sections: Vec<SectionView<'_>> = data
        .sections
        .iter()
        .map(|s| SectionView {
            id: &s.id,
            heading: &s.heading,
            paragraphs: &s.paragraphs,
            tables: &s.tables,
            figures: s
                .figures
                .iter()
                .map(|f| FigureView::new(f, label(f), &mut sizes))
                .collect(),
            template: s.template.as_deref(),
            data: &s.data,
        })
        .collect();
    let reference = Reference::paper();
    let page = Page {
        title: &data.title,
        version: SOFTWARE_VERSION,
        generated_at: &data.generated_at,
        git_description: data.git_description.as_deref(),
        command_line: data.command_line.as_deref(),
        run_time: data.run_time_s.map(|t| format!("{t:.1}")),
        seeds: &data.seeds,
        table3: table3(data, &reference, checks),
        acceptance: acceptance(checks),
        sections,
        figures,
        parameters: parameters(data, &reference),
        run_facts: &data.run_facts,
        stage_config_toml: &data.stage_config_toml,
    };
    environment()?
        .get_template("report.html")
        .and_then(|t| t.render(&page))
        .map_err(|e| ReportError::Template(format!("{e:#}")))
}

#[derive(Serialize)]
struct Page<'a> {
    title: &'a str,
    version: &'a str,
    generated_at: &'a str,
    git_description: Option<&'a str>,
    command_line: Option<&'a str>,
    run_time: Option<String>,
    seeds: &'a [Seed],
    table3: Table3View<'a>,
    acceptance: AcceptanceView<'a>,
    sections: Vec<SectionView<'a>>,
    figures: Vec<FigureView<'a>>,
    parameters: ParametersView<'a>,
    run_facts: &'a [Fact],
    stage_config_toml: &'a str,
}

#[derive(Serialize)]
struct SectionView<'a> {
    id: &'a str,
    heading: &'a str,
    paragraphs: &'a [String],
    tables: &'a [Table],
    figures: Vec<FigureView<'a>>,
    template: Option<&'a str>,
    data: &'a serde_json::Value,
}

#[derive(Serialize)]
struct FigureView<'a> {
    /// HTML id, from the PNG's file name.
    id: String,
    label: String,
    png_file: &'a str,
    svg_file: Option<&'a str>,
    width: u32,
    height: u32,
    paper_figure: &'a str,
    caption: &'a str,
}

impl<'a> FigureView<'a> {
    fn new(
        f: &'a FigureEntry,
        label: String,
        sizes: &mut impl Iterator<Item = (u32, u32)>,
    ) -> Self {
        let (width, height) = sizes.next().unwrap_or_default();
        FigureView {
            id: format!(
                "figure-{}",
                f.png_file.trim_end_matches(".png").replace('.', "-")
            ),
            label,
            png_file: &f.png_file,
            svg_file: f.svg_file.as_deref(),
            width,
            height,
            paper_figure: &f.paper_figure,
            caption: &f.caption,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Table 3 and the acceptance checks.

#[derive(Serialize)]
struct Table3View<'a> {
    compensators: [&'static str; 3],
    pipelines: Vec<&'a str>,
    rows: Vec<Table3Row>,
    pipeline_notes: Vec<PipelineNote<'a>>,
    bins: Vec<usize>,
    notes: &'a [String],
}

#[derive(Serialize)]
struct PipelineNote<'a> {
    name: &'a str,
    description: &'a str,
}

#[derive(Serialize)]
struct Table3Row {
    index: &'static str,
    cells: Vec<Cell>,
}

/// A cell of Table 3: the paper's number, or ours with its checks.
#[derive(Serialize, Default)]
struct Cell {
    paper: bool,
    text: String,
    class: &'static str,
    pipeline: String,
    compensator: &'static str,
    title: String,
    checked: bool,
    missed: bool,
}

impl Cell {
    fn paper(text: String) -> Self {
        Cell {
            paper: true,
            text,
            ..Cell::default()
        }
    }

    fn ours(
        checks: &[Check<'_>],
        pipeline: Option<&str>,
        comp: Option<Compensator>,
        index: IndexName,
        value: Option<f64>,
    ) -> Self {
        let relevant: Vec<&Check<'_>> = checks
            .iter()
            .filter(|ch| ch.is_for(pipeline, comp, index))
            .collect();
        let missed = relevant.iter().any(|ch| !ch.met);
        let class = match (relevant.is_empty(), missed) {
            (true, _) => "ours",
            (false, true) => "ours miss",
            (false, false) => "ours pass",
        };
        let title: Vec<String> = relevant
            .iter()
            .map(|ch| {
                format!(
                    "{} bound {}",
                    if ch.met { "meets" } else { "misses" },
                    bound_text(ch.bound)
                )
            })
            .collect();
        Cell {
            paper: false,
            text: value.map_or_else(|| "not run".to_string(), pct),
            class,
            pipeline: pipeline.unwrap_or("uncompensated").to_string(),
            compensator: comp.map_or("none", Compensator::key),
            title: title.join("; "),
            checked: !relevant.is_empty(),
            missed,
        }
    }
}

fn table3<'a>(data: &'a ReportData, reference: &Reference, checks: &[Check<'_>]) -> Table3View<'a> {
    let paper = &reference.table3_results_percent;
    let rows = IndexName::ALL
        .into_iter()
        .map(|index| {
            let mut cells = vec![Cell::paper(match index {
                IndexName::EMhe => num(paper.uncompensated_e_mhe),
                _ => "—".to_string(),
            })];
            cells.push(Cell::ours(
                checks,
                None,
                None,
                index,
                data.uncompensated.as_ref().map(|t| index.of(t)),
            ));
            for c in Compensator::ALL {
                let r = match c {
                    Compensator::Ihc => &paper.ihc,
                    Compensator::Wihc => &paper.wihc,
                    Compensator::Dihc => &paper.dihc,
                };
                cells.push(Cell::paper(num(index.of_paper(r))));
                for pipe in &data.pipelines {
                    let value = pipe.indices(c).map(|t| index.of(t));
                    cells.push(Cell::ours(checks, Some(&pipe.name), Some(c), index, value));
                }
            }
            Table3Row {
                index: index.name(),
                cells,
            }
        })
        .collect();
    let bins: BTreeSet<usize> = data
        .uncompensated
        .iter()
        .chain(
            data.pipelines
                .iter()
                .flat_map(|p| [&p.ihc, &p.wihc, &p.dihc].into_iter().flatten()),
        )
        .map(|t| t.mhe_bins)
        .collect();
    Table3View {
        compensators: Compensator::ALL.map(Compensator::name),
        pipelines: data.pipelines.iter().map(|p| p.name.as_str()).collect(),
        rows,
        pipeline_notes: data
            .pipelines
            .iter()
            .map(|p| PipelineNote {
                name: &p.name,
                description: &p.description,
            })
            .collect(),
        bins: bins.into_iter().collect(),
        notes: &data.table3_notes,
    }
}

#[derive(Serialize)]
struct AcceptanceView<'a> {
    items: Vec<CheckView<'a>>,
    counted: usize,
    missed: usize,
    informational: usize,
    informational_missed: usize,
}

#[derive(Serialize)]
struct CheckView<'a> {
    met: bool,
    pipeline: Option<&'a str>,
    compensator: Option<&'static str>,
    index: &'static str,
    value: Option<String>,
    bound: String,
    source: &'a str,
    informational: bool,
}

fn acceptance<'a>(checks: &[Check<'a>]) -> AcceptanceView<'a> {
    let counted = checks.iter().filter(|c| !c.bound.informational);
    let informational = checks.iter().filter(|c| c.bound.informational);
    AcceptanceView {
        counted: counted.clone().count(),
        missed: counted.filter(|c| !c.met).count(),
        informational: informational.clone().count(),
        informational_missed: informational.filter(|c| !c.met).count(),
        items: checks
            .iter()
            .map(|c| CheckView {
                met: c.met,
                pipeline: c.pipeline.filter(|_| c.compensator.is_some()),
                compensator: c.compensator.map(Compensator::name),
                index: c.bound.index.name(),
                value: c.value.map(pct),
                bound: bound_text(c.bound),
                source: &c.bound.source,
                informational: c.bound.informational,
            })
            .collect(),
    }
}

// ---------------------------------------------------------------------------------------------
// Tables 1 and 2.

#[derive(Serialize)]
struct ParametersView<'a> {
    tables: [ParameterTable<'a>; 2],
    notes: Vec<NoteView<'a>>,
}

#[derive(Serialize)]
struct ParameterTable<'a> {
    id: &'static str,
    pipelines: Vec<ScalesView<'a>>,
    /// Per row, the paper's column then each pipeline's.
    rows: Vec<Vec<ParameterCell>>,
    fits: Vec<FitView<'a>>,
}

#[derive(Serialize)]
struct ScalesView<'a> {
    name: &'a str,
    input_scale: String,
    input_unit: &'a str,
    output_scale: String,
    output_unit: &'a str,
}

#[derive(Serialize)]
struct ParameterCell {
    class: &'static str,
    r: String,
    b: String,
    a: String,
}

#[derive(Serialize)]
struct FitView<'a> {
    name: &'a str,
    fit: &'a [Fact],
}

#[derive(Serialize)]
struct NoteView<'a> {
    pipeline: &'a str,
    note: &'a str,
}

fn parameters<'a>(data: &'a ReportData, reference: &Reference) -> ParametersView<'a> {
    let models = |inverse: bool| -> Vec<(&'a str, &'a ModelParameters)> {
        data.pipelines
            .iter()
            .filter_map(|p| {
                let m = if inverse {
                    p.inverse_model.as_ref()
                } else {
                    p.forward_model.as_ref()
                };
                m.map(|m| (p.name.as_str(), m))
            })
            .collect()
    };
    ParametersView {
        tables: [
            parameter_table("table1", &reference.table1_forward_mpim, &models(false)),
            parameter_table("table2", &reference.table2_inverse_mpim, &models(true)),
        ],
        notes: data
            .pipelines
            .iter()
            .flat_map(|p| {
                p.notes.iter().map(|n| NoteView {
                    pipeline: &p.name,
                    note: n,
                })
            })
            .collect(),
    }
}

fn parameter_table<'a>(
    id: &'static str,
    paper: &ReferenceMpim,
    ours: &[(&'a str, &'a ModelParameters)],
) -> ParameterTable<'a> {
    let rows = ours
        .iter()
        .map(|(_, m)| m.thresholds.len().max(m.weights.len()))
        .chain([paper.thresholds.len().max(paper.weights.len()), 2])
        .max()
        .unwrap_or(2);
    let cell = |thresholds: &[f64], weights: &[f64], a1: f64, a2: f64, i: usize, printed: bool| {
        let f = |v: f64| if printed { num(v) } else { param(v) };
        ParameterCell {
            class: if printed { "paper" } else { "ours" },
            r: thresholds.get(i).map_or(String::new(), |&v| f(v)),
            b: weights.get(i).map_or(String::new(), |&v| f(v)),
            a: match i {
                0 => f(a1),
                1 => f(a2),
                _ => String::new(),
            },
        }
    };
    ParameterTable {
        id,
        pipelines: ours
            .iter()
            .map(|(name, m)| ScalesView {
                name,
                input_scale: param(m.input_scale),
                input_unit: &m.input_unit,
                output_scale: param(m.output_scale),
                output_unit: &m.output_unit,
            })
            .collect(),
        rows: (0..rows)
            .map(|i| {
                std::iter::once(cell(
                    &paper.thresholds,
                    &paper.weights,
                    paper.a1,
                    paper.a2,
                    i,
                    true,
                ))
                .chain(
                    ours.iter()
                        .map(|(_, m)| cell(&m.thresholds, &m.weights, m.a1, m.a2, i, false)),
                )
                .collect()
            })
            .collect(),
        fits: ours
            .iter()
            .filter(|(_, m)| !m.fit.is_empty())
            .map(|(name, m)| FitView { name, fit: &m.fit })
            .collect(),
    }
}

// ---------------------------------------------------------------------------------------------
// Numbers as text.

/// A bound in words, e.g. `e_mhe ≤ 3 %`.
pub(super) fn bound_text(b: &AcceptanceBound) -> String {
    match (b.min_percent, b.max_percent) {
        (Some(lo), Some(hi)) => format!("{} % ≤ {} ≤ {} %", num(lo), b.index.name(), num(hi)),
        (Some(lo), None) => format!("{} ≥ {} %", b.index.name(), num(lo)),
        (None, Some(hi)) => format!("{} ≤ {} %", b.index.name(), num(hi)),
        (None, None) => b.index.name().to_string(),
    }
}

/// A number as the paper prints it: shortest form (`3`, `2.5`, `0.75`).
pub(super) fn num(v: f64) -> String {
    format!("{v}")
}

/// One of our indices, %, two decimals.
pub(super) fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "not finite".to_string()
    }
}

/// A model parameter: five decimals, trailing zeros trimmed (`0.2313`, `-0.00002`, `0.1`).
pub(super) fn param(v: f64) -> String {
    if !v.is_finite() {
        return "not finite".to_string();
    }
    let s = format!("{v:.5}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    match s {
        "-0" | "" => "0".to_string(),
        s => s.to_string(),
    }
}
