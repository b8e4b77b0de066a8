//! The HTML report of the comparative study: one self-contained `index.html` (inline CSS, no
//! script, no external resource) with the figures beside it, something a person can attach to a
//! lab notebook.
//!
//! The study fills a [`ReportData`] (plain data, serialisable with serde) and calls
//! [`write_report`]. The report shows, in order:
//!
//! 1. the title, the date and time given by the caller (the report reads no clock), the software
//!    version (`hystcomp-experiments` version and the git description given by the caller), the
//!    command line, the run time and the seeds;
//! 2. Table 3 of Gu & Zhu (2014): rows e_mhe, e_m, e_rms; for the uncompensated run and for IHC,
//!    WIHC and DIHC, the paper's number (from [`Reference::paper`](crate::Reference::paper)) beside ours for each
//!    pipeline; numbers that miss an acceptance bound are marked in the table and listed in
//!    words, and the bin count of e_mhe is stated;
//! 3. the sections written by the study ([`TextSection`]: paragraphs, tables, figures, and
//!    optionally markup of their own), for instance why the pipelines differ, or a whole study;
//! 4. the figures, each labelled with the paper's equivalent figure;
//! 5. the identified parameters laid out like Tables 1 and 2 (Number, r_i, b_i, a_i), the paper's
//!    beside ours, with the physical scales of each model;
//! 6. further facts about the run and the stage configuration (TOML, verbatim).
//!
//! # How the page is made
//! Markup lives in templates (`crates/experiments/templates/`, rendered by minijinja and compiled
//! into the crate); the data they show is prepared here in Rust (`view.rs`: numbers formatted,
//! checks judged, rows laid out), and the engine escapes every value (the templates' names end in
//! `.html`). No HTML is assembled from strings. `index.html` is written atomically (temporary
//! file in the same directory, then rename).
//!
//! # Adding a study to the report
//! A study is data, a template block and figures. Push a [`TextSection`] onto
//! [`ReportData::sections`]:
//! - `heading`, `paragraphs` (plain text) and `tables` ([`Table`]: column headers and rows of
//!   text, numbers formatted by you with their units) cover most studies with no markup at all;
//! - `figures`: [`FigureEntry`]s whose files you wrote into the report's directory first (with
//!   [`crate::figures`]); they are shown inside the section, labelled like the others;
//! - for markup of its own, write `templates/studies/NAME.html`, add it to `TEMPLATES` in
//!   `view.rs`, and set `template: Some("NAME")` and `data` (any serde value the template
//!   reads as `section.data`);
//! - give the section an `id` so that tests (and links) find it; test it by rendering with
//!   [`render_html`] and asserting on the HTML, as `tests.rs` does.

use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::TrackingIndices;
use crate::reference::ReferenceIndices;

mod view;

/// Version of this crate, printed in the report.
const SOFTWARE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Everything the report shows. Plain data: the study fills it, and may save it as JSON beside
/// the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReportData {
    /// Title of the page, e.g. `"hystcomp reproduce: Gu & Zhu (2014), section 4"`.
    pub title: String,
    /// When the study ran, formatted by the caller (e.g. RFC 3339, `"2026-04-01T09:30:00Z"`).
    /// The report never reads a clock, so that the same data gives the same page.
    pub generated_at: String,
    /// `git describe --always --dirty` of the sources, when known.
    pub git_description: Option<String>,
    /// The command line that produced the report, when known.
    pub command_line: Option<String>,
    /// Wall-clock time the study took, s.
    pub run_time_s: Option<f64>,
    /// Every seed the study used, by purpose (stage noise, PSO, ...).
    pub seeds: Vec<Seed>,
    /// Further facts about the run, shown as a list: sample rate, duration, evaluation window
    /// ("last 10 s period, 10 s to 20 s"), ... Values are free text with their units.
    pub run_facts: Vec<Fact>,
    /// Indices of the uncompensated run (linear feedforward gain, fig. 7), % of the `y_d`
    /// range; `None` if it was not run.
    pub uncompensated: Option<TrackingIndices>,
    /// The pipelines, in the order of the table's columns (e.g. `paper`, then `exact`).
    /// Names must be distinct and not empty.
    pub pipelines: Vec<PipelineResult>,
    /// Sentences shown under Table 3, after what its columns mean (e.g. that the uncompensated
    /// number matches the paper's by calibration).
    #[serde(default)]
    pub table3_notes: Vec<String>,
    /// Bounds our numbers are checked against; each is marked in Table 3 and listed in words.
    pub acceptance: Vec<AcceptanceBound>,
    /// The figures, in the order shown. Their files must already be in the report's directory.
    pub figures: Vec<FigureEntry>,
    /// Free-text sections written by the study from its measurements, shown after Table 3.
    pub sections: Vec<TextSection>,
    /// The stage configuration as TOML, shown verbatim.
    pub stage_config_toml: String,
}

/// A named seed.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Seed {
    /// What the seed drives, e.g. `"stage sensor noise"`.
    pub name: String,
    /// The seed.
    pub value: u64,
}

/// A named fact, shown as `name: value`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fact {
    /// What, e.g. `"sample rate"`.
    pub name: String,
    /// Value with its unit, e.g. `"10 kHz"`.
    pub value: String,
}

impl Fact {
    /// A fact from anything printable.
    pub fn new(name: impl Into<String>, value: impl fmt::Display) -> Self {
        Fact {
            name: name.into(),
            value: value.to_string(),
        }
    }
}

/// The results of one pipeline (identification method plus compensators).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PipelineResult {
    /// Short name, used in the table headers and in acceptance bounds, e.g. `"paper"`.
    pub name: String,
    /// One line on what it does, e.g. `"PSO identification, delayed IHC and WIHC"`.
    pub description: String,
    /// Indices with IHC, % of the `y_d` range; `None` if it did not run (say why in `notes`).
    pub ihc: Option<TrackingIndices>,
    /// Indices with WIHC, % of the `y_d` range; `None` if it did not run.
    pub wihc: Option<TrackingIndices>,
    /// Indices with DIHC, % of the `y_d` range; `None` if it did not run.
    pub dihc: Option<TrackingIndices>,
    /// The MPIM of the hysteresis used by IHC and WIHC (the paper's Table 1), if identified.
    pub forward_model: Option<ModelParameters>,
    /// The MPIM of the inverse hysteresis used by DIHC (the paper's Table 2), if identified.
    pub inverse_model: Option<ModelParameters>,
    /// Short remarks shown with the pipeline's parameters.
    pub notes: Vec<String>,
}

impl PipelineResult {
    /// The indices of one compensator.
    pub fn indices(&self, compensator: Compensator) -> Option<&TrackingIndices> {
        match compensator {
            Compensator::Ihc => self.ihc.as_ref(),
            Compensator::Wihc => self.wihc.as_ref(),
            Compensator::Dihc => self.dihc.as_ref(),
        }
    }
}

/// An MPIM (eq. (4)) in normalised units (eq. (11)) with the physical scales of its input and
/// output: the model maps `input / input_scale` to `output / output_scale`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelParameters {
    /// Thresholds `r_i` of the play operators, normalised input units.
    pub thresholds: Vec<f64>,
    /// Weights `b_i`, one per threshold.
    pub weights: Vec<f64>,
    /// Cubic coefficient `a_1` of `g(x) = a_1 x^3 + a_2 x`.
    pub a1: f64,
    /// Linear coefficient `a_2`.
    pub a2: f64,
    /// Physical value of the normalised input 1 (e.g. `120.0` for volts).
    pub input_scale: f64,
    /// Unit of `input_scale`, e.g. `"V"` for the forward model, `"µm"` for the inverse.
    pub input_unit: String,
    /// Physical value of the normalised output 1.
    pub output_scale: f64,
    /// Unit of `output_scale`.
    pub output_unit: String,
    /// Facts about the fit, e.g. `"fit RMS error" = "0.21 µm"`, `"PSO iterations" = "400"`.
    pub fit: Vec<Fact>,
}

/// One of the paper's three compensators.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compensator {
    /// Inverse hysteresis compensation (eq. (7)).
    Ihc,
    /// Inverse multiplicative structure, "without inverse" (eq. (9)).
    Wihc,
    /// Direct inverse hysteresis compensation (eq. (10)).
    Dihc,
}

impl Compensator {
    /// The three, in the paper's order.
    pub const ALL: [Compensator; 3] = [Compensator::Ihc, Compensator::Wihc, Compensator::Dihc];

    /// `"IHC"`, `"WIHC"` or `"DIHC"`.
    pub fn name(self) -> &'static str {
        match self {
            Compensator::Ihc => "IHC",
            Compensator::Wihc => "WIHC",
            Compensator::Dihc => "DIHC",
        }
    }

    fn key(self) -> &'static str {
        match self {
            Compensator::Ihc => "ihc",
            Compensator::Wihc => "wihc",
            Compensator::Dihc => "dihc",
        }
    }
}

/// One of the three indices of Table 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum IndexName {
    /// Maximum hysteresis error, eq. (12).
    #[serde(rename = "e_mhe")]
    EMhe,
    /// Maximum tracking error, (D1).
    #[serde(rename = "e_m")]
    EM,
    /// RMS tracking error, (D2).
    #[serde(rename = "e_rms")]
    ERms,
}

impl IndexName {
    /// The three, in the paper's order.
    pub const ALL: [IndexName; 3] = [IndexName::EMhe, IndexName::EM, IndexName::ERms];

    /// `"e_mhe"`, `"e_m"` or `"e_rms"`.
    pub fn name(self) -> &'static str {
        match self {
            IndexName::EMhe => "e_mhe",
            IndexName::EM => "e_m",
            IndexName::ERms => "e_rms",
        }
    }

    /// This index of `t`, %.
    pub fn of(self, t: &TrackingIndices) -> f64 {
        match self {
            IndexName::EMhe => t.e_mhe_percent,
            IndexName::EM => t.e_m_percent,
            IndexName::ERms => t.e_rms_percent,
        }
    }

    fn of_paper(self, r: &ReferenceIndices) -> f64 {
        match self {
            IndexName::EMhe => r.e_mhe,
            IndexName::EM => r.e_m,
            IndexName::ERms => r.e_rms,
        }
    }
}

/// A bound one of our numbers should meet, e.g. "`exact` pipeline, every compensator:
/// e_mhe <= 3 %".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AcceptanceBound {
    /// The pipeline's name, or `None` for the uncompensated run.
    pub pipeline: Option<String>,
    /// The compensator, or `None` for all three (ignored for the uncompensated run).
    pub compensator: Option<Compensator>,
    /// Which index.
    pub index: IndexName,
    /// Lowest acceptable value, %, if any.
    pub min_percent: Option<f64>,
    /// Highest acceptable value, %, if any.
    pub max_percent: Option<f64>,
    /// Where the bound comes from, e.g. `"issue #1: the paper's e_mhe"`.
    pub source: String,
    /// `true` for a check shown (pass or fail) but not counted in the acceptance verdict,
    /// e.g. the `paper` pipeline against the bounds the `exact` one must meet.
    #[serde(default)]
    pub informational: bool,
}

/// A figure beside `index.html`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FigureEntry {
    /// File name of the PNG in the report's directory, e.g. `"fig07_uncompensated.png"`.
    pub png_file: String,
    /// File name of its SVG twin in the same directory, if any (linked from the caption).
    pub svg_file: Option<String>,
    /// The paper's equivalent figure, e.g. `"Fig. 7"` or `"Fig. 8 (a)-(c)"`; empty when the
    /// paper has none.
    pub paper_figure: String,
    /// What the figure shows, one or two sentences.
    pub caption: String,
}

/// A section of the report after Table 3: a heading, plain-text paragraphs, tables and
/// figures, shown in that order (every string escaped, none read as HTML). A study added to the
/// report is one such section (see the module's docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct TextSection {
    /// Heading, e.g. `"Why the pipelines differ"`.
    pub heading: String,
    /// Paragraphs of plain text.
    pub paragraphs: Vec<String>,
    /// HTML id of the section (letters, digits, `-`, `_`), for links and tests; none if empty.
    #[serde(default)]
    pub id: String,
    /// Tables shown after the paragraphs.
    #[serde(default)]
    pub tables: Vec<Table>,
    /// Figures shown at the end of the section (their files in the report's directory).
    #[serde(default)]
    pub figures: Vec<FigureEntry>,
    /// A template of `templates/studies/` (without `.html`) shown after the tables, with this
    /// section as `section`; `None` for none.
    #[serde(default)]
    pub template: Option<String>,
    /// What that template reads as `section.data`.
    #[serde(default)]
    pub data: serde_json::Value,
}

impl TextSection {
    /// A section of paragraphs only.
    pub fn new(heading: impl Into<String>, paragraphs: Vec<String>) -> Self {
        TextSection {
            heading: heading.into(),
            paragraphs,
            ..TextSection::default()
        }
    }
}

/// A table of text: a header row, then rows each led by a header cell. Numbers come formatted
/// with their units by the caller (µm, %, s).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Table {
    /// HTML id (letters, digits, `-`, `_`); none if empty.
    #[serde(default)]
    pub id: String,
    /// Shown above the table; none if empty.
    pub caption: String,
    /// Column headers, the first one over the rows' header cells.
    pub columns: Vec<String>,
    /// The rows.
    pub rows: Vec<TableRow>,
    /// Shown under the table (what the columns mean, units); none if empty.
    #[serde(default)]
    pub note: String,
}

/// One row of a [`Table`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TableRow {
    /// The row's header cell.
    pub header: String,
    /// The other cells, one per column after the first.
    pub cells: Vec<String>,
}

impl TableRow {
    /// A row from its header and cells.
    pub fn new(header: impl Into<String>, cells: Vec<String>) -> Self {
        TableRow {
            header: header.into(),
            cells,
        }
    }
}

/// Why the report could not be written.
#[derive(Debug)]
pub enum ReportError {
    /// Two pipelines share a name, or a name is empty.
    BadPipelineName(String),
    /// An acceptance bound names a pipeline that is not in the data.
    UnknownPipeline(String),
    /// An acceptance bound has neither a minimum nor a maximum, or a non-finite one.
    BadBound(String),
    /// A figure's file name is not a plain file name.
    BadFileName(String),
    /// A figure's file is not in the report's directory.
    MissingFigure(PathBuf),
    /// A figure's PNG file could not be read as a PNG.
    BadFigure {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A section's or table's id is not letters, digits, `-` and `_`, or a table row has
    /// another number of cells than the columns ask for.
    BadSection(String),
    /// A template failed to render (a broken template or a study's data it cannot read).
    Template(String),
    /// Creating the directory or writing `index.html` failed.
    Io {
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}

impl fmt::Display for ReportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReportError::BadPipelineName(name) => write!(
                f,
                "the pipeline name {name:?} is empty or used twice; give each pipeline its own name"
            ),
            ReportError::UnknownPipeline(name) => write!(
                f,
                "an acceptance bound names the pipeline {name:?}, which is not in the report data"
            ),
            ReportError::BadBound(what) => write!(
                f,
                "the acceptance bound {what} is not usable: give a finite minimum and/or maximum"
            ),
            ReportError::BadFileName(name) => write!(
                f,
                "the figure file name {name:?} is not a plain file name in the report's directory \
                 (letters, digits, '-', '_', '.'; no leading '.')"
            ),
            ReportError::MissingFigure(path) => write!(
                f,
                "the figure {} does not exist; write the figures into the report's directory \
                 before the report",
                path.display()
            ),
            ReportError::BadFigure { path, reason } => {
                write!(
                    f,
                    "the figure {} is not a readable PNG: {reason}",
                    path.display()
                )
            }
            ReportError::BadSection(what) => write!(f, "the report section {what}"),
            ReportError::Template(what) => write!(f, "the report's template failed: {what}"),
            ReportError::Io { path, source } => {
                write!(f, "could not write {}: {source}", path.display())
            }
        }
    }
}

impl std::error::Error for ReportError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ReportError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Writes `dir/index.html` atomically from `data` and returns its path. The figures named in
/// `data.figures` must already be in `dir`; `dir` is created if needed.
pub fn write_report(dir: &Path, data: &ReportData) -> Result<PathBuf, ReportError> {
    std::fs::create_dir_all(dir).map_err(|source| ReportError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let html = render_html(dir, data)?;
    let path = dir.join("index.html");
    crate::figures::write_file_atomically(&path, html.as_bytes()).map_err(|source| {
        ReportError::Io {
            path: path.clone(),
            source,
        }
    })?;
    Ok(path)
}

/// The HTML of the report, checking the figures named in `data` against the files in `dir`
/// (what [`write_report`] writes).
pub fn render_html(dir: &Path, data: &ReportData) -> Result<String, ReportError> {
    validate(data)?;
    let sizes = data
        .figures
        .iter()
        .chain(data.sections.iter().flat_map(|s| &s.figures))
        .map(|f| figure_size(dir, f))
        .collect::<Result<Vec<_>, _>>()?;
    let checks = check_bounds(data);
    view::render(data, &checks, &sizes)
}

// ---------------------------------------------------------------------------------------------
// Checks.

fn validate(data: &ReportData) -> Result<(), ReportError> {
    let mut names = BTreeSet::new();
    for p in &data.pipelines {
        if p.name.trim().is_empty() || !names.insert(p.name.as_str()) {
            return Err(ReportError::BadPipelineName(p.name.clone()));
        }
    }
    for section in &data.sections {
        validate_section(section)?;
    }
    for b in &data.acceptance {
        if let Some(name) = &b.pipeline
            && !names.contains(name.as_str())
        {
            return Err(ReportError::UnknownPipeline(name.clone()));
        }
        let finite = |v: Option<f64>| v.is_none_or(f64::is_finite);
        if (b.min_percent.is_none() && b.max_percent.is_none())
            || !finite(b.min_percent)
            || !finite(b.max_percent)
        {
            return Err(ReportError::BadBound(format!(
                "on {} of {}",
                b.index.name(),
                b.pipeline.as_deref().unwrap_or("the uncompensated run")
            )));
        }
    }
    Ok(())
}

/// An HTML id: empty, or letters, digits, `-` and `_`.
fn plain_id(id: &str) -> bool {
    id.chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_'))
}

fn validate_section(section: &TextSection) -> Result<(), ReportError> {
    let bad = |what: String| {
        Err(ReportError::BadSection(format!(
            "{:?} {what}",
            section.heading
        )))
    };
    if !plain_id(&section.id) {
        return bad(format!(
            "has the id {:?}: use letters, digits, '-' and '_'",
            section.id
        ));
    }
    if let Some(name) = &section.template
        && !view::has_study_template(name)
    {
        return bad(format!(
            "names the template {name:?}, which is not in templates/studies (see TEMPLATES in \
                 report/view.rs)"
        ));
    }
    for table in &section.tables {
        if !plain_id(&table.id) {
            return bad(format!("has a table with the id {:?}", table.id));
        }
        let wanted = table.columns.len().saturating_sub(1);
        if let Some(row) = table.rows.iter().find(|r| r.cells.len() != wanted) {
            return bad(format!(
                "has a table {:?} whose row {:?} has {} cells for {wanted} columns",
                table.caption,
                row.header,
                row.cells.len()
            ));
        }
    }
    Ok(())
}

fn plain_file_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
}

/// Checks the figure's files and returns the PNG's size in pixels.
fn figure_size(dir: &Path, figure: &FigureEntry) -> Result<(u32, u32), ReportError> {
    for name in std::iter::once(&figure.png_file).chain(&figure.svg_file) {
        if !plain_file_name(name) {
            return Err(ReportError::BadFileName(name.clone()));
        }
        if !dir.join(name).is_file() {
            return Err(ReportError::MissingFigure(dir.join(name)));
        }
    }
    let path = dir.join(&figure.png_file);
    let bad = |reason: String| ReportError::BadFigure {
        path: path.clone(),
        reason,
    };
    let file = std::fs::File::open(&path).map_err(|e| bad(e.to_string()))?;
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| bad(e.to_string()))?;
    let info = reader.info();
    Ok((info.width, info.height))
}

/// The outcome of one acceptance bound on one number.
struct Check<'a> {
    bound: &'a AcceptanceBound,
    /// `None` for the uncompensated run.
    pipeline: Option<&'a str>,
    /// `None` for the uncompensated run.
    compensator: Option<Compensator>,
    /// `None` when the run is missing.
    value: Option<f64>,
    met: bool,
}

impl Check<'_> {
    fn is_for(
        &self,
        pipeline: Option<&str>,
        compensator: Option<Compensator>,
        index: IndexName,
    ) -> bool {
        self.pipeline == pipeline && self.compensator == compensator && self.bound.index == index
    }
}

fn check_bounds(data: &ReportData) -> Vec<Check<'_>> {
    let mut checks = Vec::new();
    for bound in &data.acceptance {
        let judge = |value: Option<f64>| {
            value.is_some_and(|v| {
                v.is_finite()
                    && bound.min_percent.is_none_or(|lo| v >= lo)
                    && bound.max_percent.is_none_or(|hi| v <= hi)
            })
        };
        match &bound.pipeline {
            None => {
                let value = data.uncompensated.as_ref().map(|t| bound.index.of(t));
                checks.push(Check {
                    bound,
                    pipeline: None,
                    compensator: None,
                    value,
                    met: judge(value),
                });
            }
            Some(name) => {
                let Some(p) = data.pipelines.iter().find(|p| &p.name == name) else {
                    continue; // refused by `validate`
                };
                let compensators: Vec<Compensator> = match bound.compensator {
                    Some(c) => vec![c],
                    None => Compensator::ALL.to_vec(),
                };
                for c in compensators {
                    let value = p.indices(c).map(|t| bound.index.of(t));
                    checks.push(Check {
                        bound,
                        pipeline: Some(p.name.as_str()),
                        compensator: Some(c),
                        value,
                        met: judge(value),
                    });
                }
            }
        }
    }
    checks
}

#[cfg(test)]
mod tests;
