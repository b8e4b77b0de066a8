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
//!    WIHC and DIHC, the paper's number (from [`Reference::paper`]) beside ours for each
//!    pipeline; numbers that miss an acceptance bound are marked in the table and listed in
//!    words, and the bin count of e_mhe is stated;
//! 3. the free-text sections written by the study (for instance why the pipelines differ);
//! 4. the figures, each captioned with the paper's equivalent figure;
//! 5. the identified parameters laid out like Tables 1 and 2 (Number, r_i, b_i, a_i), the paper's
//!    beside ours, with the physical scales of each model;
//! 6. further facts about the run and the stage configuration (TOML, verbatim).
//!
//! Every string from the caller is HTML-escaped. `index.html` is written atomically (temporary
//! file in the same directory, then rename).

use std::collections::BTreeSet;
use std::fmt::{self, Write as _};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::TrackingIndices;
use crate::reference::{Reference, ReferenceIndices, ReferenceMpim};

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

    /// HTML for the index name with a subscript, e.g. `e<sub>mhe</sub>`.
    fn html(self) -> &'static str {
        match self {
            IndexName::EMhe => "e<sub>mhe</sub>",
            IndexName::EM => "e<sub>m</sub>",
            IndexName::ERms => "e<sub>rms</sub>",
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

/// A free-text section: a heading and plain-text paragraphs (escaped, not HTML).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TextSection {
    /// Heading, e.g. `"Why the pipelines differ"`.
    pub heading: String,
    /// Paragraphs of plain text.
    pub paragraphs: Vec<String>,
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
    let figures = data
        .figures
        .iter()
        .map(|f| figure_size(dir, f))
        .collect::<Result<Vec<_>, _>>()?;
    let reference = Reference::paper();
    let checks = check_bounds(data);

    let mut h = String::with_capacity(64 * 1024);
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    let _ = writeln!(h, "<title>{}</title>", esc(&data.title));
    let _ = writeln!(
        h,
        "<meta name=\"generator\" content=\"hystcomp-experiments {SOFTWARE_VERSION}\">"
    );
    let _ = writeln!(h, "<style>{CSS}</style>\n</head>\n<body>\n<main>");
    header(&mut h, data);
    table3(&mut h, data, &reference, &checks);
    for section in &data.sections {
        let _ = writeln!(
            h,
            "<section class=\"text\">\n<h2>{}</h2>",
            esc(&section.heading)
        );
        for p in &section.paragraphs {
            let _ = writeln!(h, "<p>{}</p>", esc(p));
        }
        h.push_str("</section>\n");
    }
    figures_section(&mut h, data, &figures);
    parameters(&mut h, data, &reference);
    run_section(&mut h, data);
    let _ = writeln!(
        h,
        "<footer>Generated by hystcomp-experiments {} at {}.</footer>\n</main>\n</body>\n</html>",
        esc(SOFTWARE_VERSION),
        esc(&data.generated_at)
    );
    Ok(h)
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
    for b in &data.acceptance {
        if let Some(name) = &b.pipeline {
            if !names.contains(name.as_str()) {
                return Err(ReportError::UnknownPipeline(name.clone()));
            }
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

fn bound_text(b: &AcceptanceBound) -> String {
    match (b.min_percent, b.max_percent) {
        (Some(lo), Some(hi)) => format!("{} % ≤ {} ≤ {} %", num(lo), b.index.name(), num(hi)),
        (Some(lo), None) => format!("{} ≥ {} %", b.index.name(), num(lo)),
        (None, Some(hi)) => format!("{} ≤ {} %", b.index.name(), num(hi)),
        (None, None) => b.index.name().to_string(),
    }
}

// ---------------------------------------------------------------------------------------------
// Formatting.

/// Escapes text for HTML element content and quoted attribute values.
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A number as the paper prints it: shortest form (`3`, `2.5`, `0.75`).
fn num(v: f64) -> String {
    format!("{v}")
}

/// One of our indices, %, two decimals.
fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "not finite".to_string()
    }
}

/// A model parameter: five decimals, trailing zeros trimmed (`0.2313`, `-0.00002`, `0.1`).
fn param(v: f64) -> String {
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

fn header(h: &mut String, data: &ReportData) {
    let _ = writeln!(h, "<header>\n<h1>{}</h1>", esc(&data.title));
    h.push_str(
        "<p class=\"subtitle\">Section 4 of G.-Y. Gu and L.-M. Zhu, “Comparative experiments \
         regarding approaches to feedforward hysteresis compensation for piezoceramic \
         actuators”, <i>Smart Mater. Struct.</i> 23 (2014) 095029, rerun on a simulated stage. \
         The paper's numbers were measured on a real stage.</p>\n<dl class=\"meta\">\n",
    );
    let mut item = |name: &str, value: String| {
        let _ = writeln!(h, "<dt>{}</dt><dd>{value}</dd>", esc(name));
    };
    item("generated", esc(&data.generated_at));
    let version = match &data.git_description {
        Some(g) => format!(
            "hystcomp-experiments {} (git <code>{}</code>)",
            esc(SOFTWARE_VERSION),
            esc(g)
        ),
        None => format!(
            "hystcomp-experiments {} (git description unknown)",
            esc(SOFTWARE_VERSION)
        ),
    };
    item("software", version);
    if let Some(cmd) = &data.command_line {
        item("command", format!("<code>{}</code>", esc(cmd)));
    }
    if let Some(t) = data.run_time_s {
        item(
            "run time",
            format!("{t:.1} s (the study's computations; figures and this report not included)"),
        );
    }
    if !data.seeds.is_empty() {
        let seeds: Vec<String> = data
            .seeds
            .iter()
            .map(|s| format!("{} <code>{}</code>", esc(&s.name), s.value))
            .collect();
        item("seeds", seeds.join(", "));
    }
    h.push_str("</dl>\n</header>\n");
}

fn table3(h: &mut String, data: &ReportData, reference: &Reference, checks: &[Check<'_>]) {
    let paper = &reference.table3_results_percent;
    let p = data.pipelines.len();
    h.push_str("<section id=\"table3\">\n<h2>Table 3: tracking indices</h2>\n");
    h.push_str(
        "<table class=\"results\" id=\"table3-table\">\n<thead>\n<tr><th rowspan=\"2\">Index</th>",
    );
    let _ = write!(h, "<th colspan=\"2\" class=\"group\">Uncompensated</th>");
    for c in Compensator::ALL {
        let _ = write!(
            h,
            "<th colspan=\"{}\" class=\"group\">{}</th>",
            p + 1,
            c.name()
        );
    }
    h.push_str("</tr>\n<tr><th class=\"paper\">published</th><th>ours</th>");
    for _ in Compensator::ALL {
        h.push_str("<th class=\"paper\">published</th>");
        for pipe in &data.pipelines {
            let _ = write!(h, "<th><code>{}</code></th>", esc(&pipe.name));
        }
    }
    h.push_str("</tr>\n</thead>\n<tbody>\n");

    let cell = |h: &mut String,
                pipeline: Option<&str>,
                comp: Option<Compensator>,
                index: IndexName,
                value: Option<f64>| {
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
        let _ = write!(
            h,
            "<td class=\"{class}\" data-pipeline=\"{}\" data-compensator=\"{}\" data-index=\"{}\"",
            esc(pipeline.unwrap_or("uncompensated")),
            comp.map_or("none", Compensator::key),
            index.name()
        );
        if !title.is_empty() {
            let _ = write!(h, " title=\"{}\"", esc(&title.join("; ")));
        }
        h.push('>');
        match value {
            Some(v) => h.push_str(&pct(v)),
            None => h.push_str("not run"),
        }
        if !relevant.is_empty() {
            h.push_str(if missed {
                "<span class=\"mark\"> ✗</span>"
            } else {
                "<span class=\"mark\"> ✓</span>"
            });
        }
        h.push_str("</td>");
    };

    for index in IndexName::ALL {
        let _ = write!(h, "<tr><th scope=\"row\">{}</th>", index.html());
        let paper_uncomp = match index {
            IndexName::EMhe => num(paper.uncompensated_e_mhe),
            _ => "—".to_string(),
        };
        let _ = write!(h, "<td class=\"paper\">{paper_uncomp}</td>");
        cell(
            h,
            None,
            None,
            index,
            data.uncompensated.as_ref().map(|t| index.of(t)),
        );
        for c in Compensator::ALL {
            let r = match c {
                Compensator::Ihc => &paper.ihc,
                Compensator::Wihc => &paper.wihc,
                Compensator::Dihc => &paper.dihc,
            };
            let _ = write!(h, "<td class=\"paper\">{}</td>", num(index.of_paper(r)));
            for pipe in &data.pipelines {
                let value = pipe.indices(c).map(|t| index.of(t));
                cell(h, Some(pipe.name.as_str()), Some(c), index, value);
            }
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n</table>\n");

    // What the columns are, and the bin count of e_mhe.
    let mut bins = BTreeSet::new();
    for t in data.uncompensated.iter().chain(
        data.pipelines
            .iter()
            .flat_map(|p| [&p.ihc, &p.wihc, &p.dihc].into_iter().flatten()),
    ) {
        bins.insert(t.mhe_bins);
    }
    let bins_text = match bins.len() {
        0 => "no e<sub>mhe</sub> was computed".to_string(),
        1 => format!(
            "e<sub>mhe</sub> (eq. (12)) is the largest vertical width of the y versus y<sub>d</sub> \
             map over {} equal bins of y<sub>d</sub> (ERRATA item 6)",
            bins.iter().next().copied().unwrap_or_default()
        ),
        _ => format!(
            "e<sub>mhe</sub> (eq. (12)) is the largest vertical width of the y versus y<sub>d</sub> \
             map over equal bins of y<sub>d</sub> (ERRATA item 6); the bin counts differ between \
             runs: {}",
            bins.iter()
                .map(|b| b.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    h.push_str("<p class=\"table-note\">All numbers in % of the desired range max y<sub>d</sub> − min y<sub>d</sub>. ");
    h.push_str("<b>published</b>: Table 3 of the paper (real stage); ");
    for (i, pipe) in data.pipelines.iter().enumerate() {
        let _ = write!(
            h,
            "{}<b><code>{}</code></b>: {}",
            if i == 0 { "" } else { "; " },
            esc(&pipe.name),
            esc(&pipe.description)
        );
    }
    if !data.pipelines.is_empty() {
        h.push_str(". ");
    }
    let _ = write!(
        h,
        "{bins_text}. The paper gives only e<sub>mhe</sub> for the uncompensated run."
    );
    if !checks.is_empty() {
        h.push_str(
            " ✓ marks a number that meets its acceptance bound, ✗ (on red) one that misses it.",
        );
    }
    h.push_str("</p>\n");

    // The bounds in words.
    h.push_str("<div class=\"acceptance\">\n<h3>Acceptance</h3>\n");
    if checks.is_empty() {
        h.push_str("<p>No acceptance bounds were given.</p>\n");
    } else {
        let counted: Vec<&Check<'_>> = checks.iter().filter(|c| !c.bound.informational).collect();
        let missed = counted.iter().filter(|c| !c.met).count();
        if missed == 0 {
            let _ = writeln!(
                h,
                "<p class=\"verdict pass\">All {} checks against acceptance bounds are met.</p>",
                counted.len()
            );
        } else {
            let _ = writeln!(
                h,
                "<p class=\"verdict miss\">{missed} of {} checks against acceptance bounds miss.</p>",
                counted.len()
            );
        }
        let informational = checks.len() - counted.len();
        if informational > 0 {
            let missed = checks
                .iter()
                .filter(|c| c.bound.informational && !c.met)
                .count();
            let _ = writeln!(
                h,
                "<p class=\"verdict informational\">{informational} further checks are \
                 informational (marked <i>informational</i>; not counted in the verdict above): \
                 {missed} of them miss.</p>"
            );
        }
        h.push_str("<ul>\n");
        for c in checks {
            let run = match (c.pipeline, c.compensator) {
                (Some(p), Some(comp)) => {
                    format!("<code>{}</code> pipeline, {}", esc(p), comp.name())
                }
                _ => "uncompensated run".to_string(),
            };
            let value = match c.value {
                Some(v) => format!("{} = {} %", c.bound.index.name(), pct(v)),
                None => format!("{} not available (not run)", c.bound.index.name()),
            };
            let _ = writeln!(
                h,
                "<li class=\"{}\">{} {run}: {value} {} the bound {} <span class=\"source\">({}{})</span></li>",
                if c.met { "pass" } else { "miss" },
                if c.met { "✓" } else { "✗" },
                if c.met { "meets" } else { "misses" },
                esc(&bound_text(c.bound)),
                esc(&c.bound.source),
                if c.bound.informational {
                    "; <i>informational</i>, not counted"
                } else {
                    ""
                }
            );
        }
        h.push_str("</ul>\n");
    }
    h.push_str("</div>\n</section>\n");
}

fn figures_section(h: &mut String, data: &ReportData, sizes: &[(u32, u32)]) {
    if data.figures.is_empty() {
        return;
    }
    h.push_str("<section id=\"figures\">\n<h2>Figures</h2>\n");
    for (k, (f, (w, ht))) in data.figures.iter().zip(sizes).enumerate() {
        let _ = writeln!(
            h,
            "<figure>\n<img src=\"{}\" width=\"{w}\" height=\"{ht}\" alt=\"{}\">",
            esc(&f.png_file),
            esc(&f.caption)
        );
        let equivalent = if f.paper_figure.is_empty() {
            "no equivalent in the paper".to_string()
        } else {
            format!("the paper's {}", esc(&f.paper_figure))
        };
        let _ = write!(
            h,
            "<figcaption><b>Figure {}</b> ({equivalent}): {}",
            k + 1,
            esc(&f.caption)
        );
        if let Some(svg) = &f.svg_file {
            let _ = write!(h, " <a href=\"{}\">SVG</a>", esc(svg));
        }
        h.push_str("</figcaption>\n</figure>\n");
    }
    h.push_str("</section>\n");
}

fn parameters(h: &mut String, data: &ReportData, reference: &Reference) {
    h.push_str("<section id=\"parameters\">\n<h2>Identified parameters</h2>\n");
    h.push_str(
        "<p>MPIM of eq. (4) in normalised units (eq. (11): the model input is divided by its \
         largest value, so r<sub>i</sub> are fractions of the input range): play-operator \
         thresholds r<sub>i</sub>, weights b<sub>i</sub>, and a<sub>1</sub>, a<sub>2</sub> of \
         g(x) = a<sub>1</sub>x<sup>3</sup> + a<sub>2</sub>x in the first two rows of the \
         a<sub>i</sub> column. The scales give the physical value of a normalised 1.</p>\n",
    );
    let forward: Vec<(&str, &ModelParameters)> = data
        .pipelines
        .iter()
        .filter_map(|p| p.forward_model.as_ref().map(|m| (p.name.as_str(), m)))
        .collect();
    let inverse: Vec<(&str, &ModelParameters)> = data
        .pipelines
        .iter()
        .filter_map(|p| p.inverse_model.as_ref().map(|m| (p.name.as_str(), m)))
        .collect();
    parameter_table(
        h,
        "table1",
        "Table 1: MPIM for IHC and WIHC (input: voltage v, output: position y)",
        &reference.table1_forward_mpim,
        &forward,
    );
    parameter_table(
        h,
        "table2",
        "Table 2: MPIM for DIHC (input: desired position y<sub>d</sub>, output: voltage v)",
        &reference.table2_inverse_mpim,
        &inverse,
    );
    let noted: Vec<&PipelineResult> = data
        .pipelines
        .iter()
        .filter(|p| !p.notes.is_empty())
        .collect();
    if !noted.is_empty() {
        h.push_str("<h3>Notes on the pipelines</h3>\n<ul>\n");
        for p in noted {
            for n in &p.notes {
                let _ = writeln!(h, "<li><code>{}</code>: {}</li>", esc(&p.name), esc(n));
            }
        }
        h.push_str("</ul>\n");
    }
    h.push_str("</section>\n");
}

/// `heading` is trusted HTML (a constant of this module).
fn parameter_table(
    h: &mut String,
    id: &str,
    heading: &str,
    paper: &ReferenceMpim,
    ours: &[(&str, &ModelParameters)],
) {
    let _ = writeln!(h, "<h3>{heading}</h3>");
    let _ = writeln!(
        h,
        "<table class=\"params\" id=\"{id}\">\n<thead>\n<tr><th rowspan=\"2\">Number</th><th colspan=\"3\" class=\"group paper\">published</th>"
    );
    for (name, _) in ours {
        let _ = write!(
            h,
            "<th colspan=\"3\" class=\"group\"><code>{}</code></th>",
            esc(name)
        );
    }
    h.push_str("</tr>\n<tr>");
    for _ in 0..=ours.len() {
        h.push_str("<th>r<sub>i</sub></th><th>b<sub>i</sub></th><th>a<sub>i</sub></th>");
    }
    h.push_str("</tr>\n</thead>\n<tbody>\n");
    let rows = ours
        .iter()
        .map(|(_, m)| m.thresholds.len().max(m.weights.len()))
        .chain([paper.thresholds.len().max(paper.weights.len()), 2])
        .max()
        .unwrap_or(2);
    let column = |h: &mut String,
                  thresholds: &[f64],
                  weights: &[f64],
                  a1: f64,
                  a2: f64,
                  i: usize,
                  class: &str,
                  printed: bool| {
        let f = |v: f64| if printed { num(v) } else { param(v) };
        let r = thresholds.get(i).map_or(String::new(), |&v| f(v));
        let b = weights.get(i).map_or(String::new(), |&v| f(v));
        let a = match i {
            0 => f(a1),
            1 => f(a2),
            _ => String::new(),
        };
        let _ = write!(
            h,
            "<td class=\"{class}\">{r}</td><td class=\"{class}\">{b}</td><td class=\"{class}\">{a}</td>"
        );
    };
    for i in 0..rows {
        let _ = write!(h, "<tr><th scope=\"row\">{}</th>", i + 1);
        column(
            h,
            &paper.thresholds,
            &paper.weights,
            paper.a1,
            paper.a2,
            i,
            "paper",
            true,
        );
        for (_, m) in ours {
            column(h, &m.thresholds, &m.weights, m.a1, m.a2, i, "ours", false);
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n<tfoot>\n<tr><th scope=\"row\">scales</th><td colspan=\"3\" class=\"paper\">not printed</td>");
    for (_, m) in ours {
        let _ = write!(
            h,
            "<td colspan=\"3\">input 1 = {} {}<br>output 1 = {} {}</td>",
            esc(&param(m.input_scale)),
            esc(&m.input_unit),
            esc(&param(m.output_scale)),
            esc(&m.output_unit)
        );
    }
    h.push_str("</tr>\n</tfoot>\n</table>\n");
    let fitted: Vec<&(&str, &ModelParameters)> =
        ours.iter().filter(|(_, m)| !m.fit.is_empty()).collect();
    if !fitted.is_empty() {
        h.push_str("<ul class=\"fit\">\n");
        for (name, m) in fitted {
            let facts: Vec<String> = m
                .fit
                .iter()
                .map(|f| format!("{}: {}", esc(&f.name), esc(&f.value)))
                .collect();
            let _ = writeln!(
                h,
                "<li><code>{}</code>: {}</li>",
                esc(name),
                facts.join("; ")
            );
        }
        h.push_str("</ul>\n");
    }
    if ours.is_empty() {
        h.push_str("<p>No pipeline reported this model.</p>\n");
    }
}

fn run_section(h: &mut String, data: &ReportData) {
    h.push_str("<section id=\"run\">\n<h2>Run and stage configuration</h2>\n");
    if !data.run_facts.is_empty() || !data.seeds.is_empty() {
        h.push_str("<table class=\"facts\">\n<tbody>\n");
        for f in &data.run_facts {
            let _ = writeln!(
                h,
                "<tr><th scope=\"row\">{}</th><td>{}</td></tr>",
                esc(&f.name),
                esc(&f.value)
            );
        }
        for s in &data.seeds {
            let _ = writeln!(
                h,
                "<tr><th scope=\"row\">seed: {}</th><td><code>{}</code></td></tr>",
                esc(&s.name),
                s.value
            );
        }
        h.push_str("</tbody>\n</table>\n");
    }
    h.push_str("<h3>Stage configuration (TOML)</h3>\n");
    let _ = writeln!(
        h,
        "<pre class=\"config\">{}</pre>",
        esc(&data.stage_config_toml)
    );
    h.push_str("</section>\n");
}

/// The page's style sheet: system fonts, readable tables, printable (no colour needed to read
/// the marks: ✓ and ✗ are text).
const CSS: &str = r#"
:root { color-scheme: light; }
body { margin: 0; background: #ffffff; color: #1a1a1a;
  font: 15px/1.5 "DejaVu Sans", "Liberation Sans", Arial, Helvetica, sans-serif; }
main { max-width: 1180px; margin: 0 auto; padding: 24px 28px 40px; }
h1 { font-size: 26px; margin: 0 0 6px; }
h2 { font-size: 20px; margin: 32px 0 10px; padding-bottom: 4px; border-bottom: 2px solid #2b5d8a; }
h3 { font-size: 16px; margin: 20px 0 8px; }
.subtitle { margin: 0 0 12px; color: #333333; }
dl.meta { display: grid; grid-template-columns: max-content 1fr; gap: 2px 16px; margin: 0;
  padding: 10px 14px; background: #f4f6f8; border: 1px solid #d0d7de; }
dl.meta dt { font-weight: bold; }
dl.meta dd { margin: 0; }
code, pre { font-family: "DejaVu Sans Mono", "Liberation Mono", Consolas, monospace; font-size: 13px; }
table { border-collapse: collapse; margin: 8px 0; }
th, td { border: 1px solid #9aa5b1; padding: 5px 9px; }
thead th { background: #dce6f2; }
th.group { text-align: center; }
td { text-align: right; font-variant-numeric: tabular-nums; }
td.paper, th.paper { background: #f1f1f1; color: #444444; }
td.miss { background: #f6d5d5; color: #8a1010; font-weight: bold; }
td.pass { background: #ddf1df; }
.mark { font-weight: bold; }
table.results { font-size: 15px; }
table.results tbody th { text-align: left; }
.table-note { font-size: 13px; color: #333333; max-width: 1100px; }
.acceptance ul { padding-left: 20px; margin: 4px 0; }
.acceptance li.miss { color: #8a1010; }
.acceptance li.pass { color: #1d5e27; }
.verdict { font-weight: bold; }
.verdict.miss { color: #8a1010; }
.verdict.pass { color: #1d5e27; }
.source { color: #555555; }
section.text p { max-width: 900px; }
figure { margin: 18px 0 26px; }
figure img { display: block; max-width: 100%; height: auto; border: 1px solid #d0d7de; }
figcaption { font-size: 14px; margin-top: 6px; max-width: 1000px; }
table.params td { min-width: 60px; }
table.params tfoot td { text-align: left; font-size: 13px; }
table.facts th { text-align: left; background: #f4f6f8; }
table.facts td { text-align: left; }
pre.config { background: #f7f7f7; border: 1px solid #d0d7de; padding: 10px 12px;
  overflow-x: auto; white-space: pre-wrap; }
footer { margin-top: 36px; font-size: 12px; color: #666666; }
@media print {
  main { max-width: none; padding: 0; }
  h2 { break-after: avoid; }
  figure, table, .acceptance { break-inside: avoid; }
  a { color: inherit; text-decoration: none; }
}
"#;

#[cfg(test)]
mod tests {
    use super::*;

    fn indices(e_mhe: f64, e_m: f64, e_rms: f64) -> TrackingIndices {
        TrackingIndices {
            e_mhe_percent: e_mhe,
            e_m_percent: e_m,
            e_rms_percent: e_rms,
            mhe_bins: 100,
        }
    }

    fn model(unit_in: &str, unit_out: &str) -> ModelParameters {
        ModelParameters {
            thresholds: (0..10).map(|i| i as f64 / 10.0).collect(),
            weights: vec![
                0.25, 0.3, 0.01, 0.07, 0.06, 0.02, 0.004, 0.009, 0.026, -0.00002,
            ],
            a1: -0.15,
            a2: 0.47,
            input_scale: 120.0,
            input_unit: unit_in.to_string(),
            output_scale: 69.3,
            output_unit: unit_out.to_string(),
            fit: vec![Fact::new("fit RMS error", "0.21 µm")],
        }
    }

    fn data() -> ReportData {
        ReportData {
            title: "Study <one>".to_string(),
            generated_at: "2026-04-01T09:30:00Z".to_string(),
            git_description: Some("v0.1.0-3-gabcdef".to_string()),
            command_line: Some("hystcomp reproduce --out report".to_string()),
            run_time_s: Some(42.5),
            seeds: vec![Seed {
                name: "stage noise".to_string(),
                value: 7,
            }],
            run_facts: vec![Fact::new("sample rate", "10 kHz")],
            uncompensated: Some(indices(12.34, 11.0, 4.0)),
            pipelines: vec![
                PipelineResult {
                    name: "paper".to_string(),
                    description: "PSO identification, delayed IHC & WIHC".to_string(),
                    ihc: Some(indices(3.21, 2.71, 0.81)),
                    wihc: Some(indices(3.05, 2.95, 0.79)),
                    dihc: None,
                    forward_model: Some(model("V", "µm")),
                    inverse_model: None,
                    notes: vec!["DIHC model refused: not invertible".to_string()],
                },
                PipelineResult {
                    name: "exact".to_string(),
                    description: "least squares, exact inverses".to_string(),
                    ihc: Some(indices(1.11, 1.22, 0.33)),
                    wihc: Some(indices(1.12, 1.23, 0.34)),
                    dihc: Some(indices(1.13, 1.24, 0.35)),
                    forward_model: Some(model("V", "µm")),
                    inverse_model: Some(model("µm", "V")),
                    notes: vec![],
                },
            ],
            acceptance: vec![
                AcceptanceBound {
                    pipeline: Some("exact".to_string()),
                    compensator: None,
                    index: IndexName::EMhe,
                    min_percent: None,
                    max_percent: Some(3.0),
                    source: "the paper's e_mhe".to_string(),
                    informational: false,
                },
                AcceptanceBound {
                    pipeline: Some("paper".to_string()),
                    compensator: Some(Compensator::Ihc),
                    index: IndexName::EMhe,
                    min_percent: None,
                    max_percent: Some(3.0),
                    source: "the paper's e_mhe".to_string(),
                    informational: false,
                },
                AcceptanceBound {
                    pipeline: Some("paper".to_string()),
                    compensator: Some(Compensator::Dihc),
                    index: IndexName::ERms,
                    min_percent: None,
                    max_percent: Some(0.75),
                    source: "the paper's e_rms".to_string(),
                    informational: false,
                },
                AcceptanceBound {
                    pipeline: None,
                    compensator: None,
                    index: IndexName::EMhe,
                    min_percent: Some(10.0),
                    max_percent: Some(16.0),
                    source: "near the paper's 13 %".to_string(),
                    informational: false,
                },
            ],
            figures: vec![],
            sections: vec![TextSection {
                heading: "Why <b>pipelines</b> differ".to_string(),
                paragraphs: vec!["<script>alert('x')</script> & more".to_string()],
            }],
            stage_config_toml: "[amplifier]\ngain = 15.0 # <V/V>\n".to_string(),
        }
    }

    fn html() -> String {
        let dir = tempfile::tempdir().unwrap();
        render_html(dir.path(), &data()).unwrap()
    }

    /// The text of the Table 3 element.
    fn table3_of(html: &str) -> &str {
        let start = html
            .find("<table class=\"results\"")
            .expect("Table 3 is there");
        let end = start + html[start..].find("</table>").unwrap();
        &html[start..end]
    }

    #[test]
    fn table3_holds_the_papers_numbers_beside_ours() {
        let html = html();
        let t = table3_of(&html);
        for printed in [
            ">13<", ">3<", ">2.5<", ">2.66<", ">2.87<", ">2.06<", ">0.75<", ">0.76<", ">0.78<",
        ] {
            assert!(t.contains(printed), "paper number {printed} missing");
        }
        for ours in [
            "data-pipeline=\"paper\" data-compensator=\"wihc\" data-index=\"e_m\">2.95<",
            "data-pipeline=\"exact\" data-compensator=\"dihc\" data-index=\"e_rms\"",
            "data-pipeline=\"uncompensated\" data-compensator=\"none\" data-index=\"e_mhe\"",
        ] {
            assert!(t.contains(ours), "{ours} missing");
        }
        assert!(t.contains(">12.34<"));
        assert!(t.contains(">1.13<"));
        // The paper pipeline's DIHC did not run.
        assert!(t.contains("data-compensator=\"dihc\" data-index=\"e_mhe\">not run<"));
        // Column headers name both pipelines under every compensator.
        assert_eq!(t.matches("<code>paper</code>").count(), 3);
        assert_eq!(t.matches("<code>exact</code>").count(), 3);
        assert!(html.contains("over 100 equal bins"));
    }

    #[test]
    fn misses_are_marked_in_the_table_and_in_words() {
        let html = html();
        let t = table3_of(&html);
        // paper IHC e_mhe 3.21 > 3: a miss; exact e_mhe all <= 3: passes.
        assert!(t.contains(
            "class=\"ours miss\" data-pipeline=\"paper\" data-compensator=\"ihc\" data-index=\"e_mhe\""
        ));
        assert!(t.contains(
            "class=\"ours pass\" data-pipeline=\"exact\" data-compensator=\"wihc\" data-index=\"e_mhe\""
        ));
        // Unbounded numbers are neither.
        assert!(t.contains(
            "class=\"ours\" data-pipeline=\"paper\" data-compensator=\"wihc\" data-index=\"e_mhe\""
        ));
        // DIHC of the paper pipeline did not run: its bound is missed.
        assert!(t.contains(
            "class=\"ours miss\" data-pipeline=\"paper\" data-compensator=\"dihc\" data-index=\"e_rms\""
        ));
        assert!(html.contains("2 of 6 checks against acceptance bounds miss"));
        assert!(html.contains(
            "✗ <code>paper</code> pipeline, IHC: e_mhe = 3.21 % misses the bound e_mhe ≤ 3 %"
        ));
        assert!(
            html.contains(
                "✓ uncompensated run: e_mhe = 12.34 % meets the bound 10 % ≤ e_mhe ≤ 16 %"
            )
        );
    }

    #[test]
    fn every_caller_string_is_escaped() {
        let html = html();
        assert!(!html.contains("<script>"));
        assert!(html.contains("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; more"));
        assert!(html.contains("<title>Study &lt;one&gt;</title>"));
        assert!(html.contains("Why &lt;b&gt;pipelines&lt;/b&gt; differ"));
        assert!(html.contains("gain = 15.0 # &lt;V/V&gt;"));
        assert!(html.contains("delayed IHC &amp; WIHC"));
        assert_eq!(esc("a\"b'c"), "a&quot;b&#39;c");
    }

    #[test]
    fn parameters_are_laid_out_like_tables_1_and_2() {
        let html = html();
        let start = html.find("id=\"table1\"").unwrap();
        let t1 = &html[start..start + html[start..].find("</table>").unwrap()];
        // Row 1: paper r=0, b=0.2313, a1=-0.1569; ours r=0, b=0.25, a1=-0.15.
        assert!(t1.contains(
            "<tr><th scope=\"row\">1</th><td class=\"paper\">0</td><td class=\"paper\">0.2313</td><td class=\"paper\">-0.1569</td><td class=\"ours\">0</td><td class=\"ours\">0.25</td><td class=\"ours\">-0.15</td>"
        ));
        // Row 3 has no a_i.
        assert!(t1.contains("<tr><th scope=\"row\">3</th><td class=\"paper\">0.2</td><td class=\"paper\">0.0155</td><td class=\"paper\"></td>"));
        assert!(t1.contains("input 1 = 120 V<br>output 1 = 69.3 µm"));
        let start = html.find("id=\"table2\"").unwrap();
        let t2 = &html[start..start + html[start..].find("</table>").unwrap()];
        // Only the exact pipeline has a DIHC model.
        assert!(t2.contains("<code>exact</code>") && !t2.contains("<code>paper</code>"));
        assert!(t2.contains(">-0.47999<") && t2.contains(">-0.00002<"));
        assert!(html.contains("DIHC model refused: not invertible"));
    }

    #[test]
    fn parameters_are_printed_with_trimmed_decimals() {
        assert_eq!(param(0.1), "0.1");
        assert_eq!(param(-0.00002), "-0.00002");
        assert_eq!(param(0.000001), "0");
        assert_eq!(param(-0.000001), "0");
        assert_eq!(param(1.25886), "1.25886");
        assert_eq!(param(f64::NAN), "not finite");
        assert_eq!(pct(2.666), "2.67");
    }

    #[test]
    fn bad_data_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut d = data();
        d.pipelines[1].name = "paper".to_string();
        assert!(matches!(
            render_html(dir.path(), &d),
            Err(ReportError::BadPipelineName(_))
        ));
        let mut d = data();
        d.acceptance[0].pipeline = Some("nope".to_string());
        assert!(matches!(
            render_html(dir.path(), &d),
            Err(ReportError::UnknownPipeline(_))
        ));
        let mut d = data();
        d.acceptance[0].max_percent = None;
        assert!(matches!(
            render_html(dir.path(), &d),
            Err(ReportError::BadBound(_))
        ));
        let mut d = data();
        d.acceptance[0].max_percent = Some(f64::NAN);
        assert!(matches!(
            render_html(dir.path(), &d),
            Err(ReportError::BadBound(_))
        ));
        let figure = |png: &str| FigureEntry {
            png_file: png.to_string(),
            svg_file: None,
            paper_figure: "Fig. 7".to_string(),
            caption: "c".to_string(),
        };
        let mut d = data();
        d.figures = vec![figure("../x.png")];
        assert!(matches!(
            render_html(dir.path(), &d),
            Err(ReportError::BadFileName(_))
        ));
        d.figures = vec![figure("absent.png")];
        let err = render_html(dir.path(), &d).unwrap_err();
        assert!(matches!(err, ReportError::MissingFigure(_)), "{err}");
        std::fs::write(dir.path().join("fake.png"), "not a png").unwrap();
        d.figures = vec![figure("fake.png")];
        assert!(matches!(
            render_html(dir.path(), &d),
            Err(ReportError::BadFigure { .. })
        ));
        // Nothing was written.
        assert!(!dir.path().join("index.html").exists());
    }

    #[test]
    fn report_data_round_trips_through_json() {
        let d = data();
        let json = serde_json::to_string(&d).unwrap();
        assert!(json.contains("\"index\":\"e_mhe\"") && json.contains("\"compensator\":\"ihc\""));
        let back: ReportData = serde_json::from_str(&json).unwrap();
        assert_eq!(back, d);
    }

    #[test]
    fn the_report_is_written_atomically_and_replaces_an_old_one() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("index.html"), "old").unwrap();
        let path = write_report(dir.path(), &data()).unwrap();
        assert_eq!(path, dir.path().join("index.html"));
        let written = std::fs::read_to_string(&path).unwrap();
        assert!(written.starts_with("<!DOCTYPE html>") && written.trim_end().ends_with("</html>"));
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            names,
            vec!["index.html".to_string()],
            "temporary files left behind"
        );
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&path).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o644);
        }
        // A directory that cannot be created gives an error, not a panic.
        let blocked = dir.path().join("index.html").join("sub");
        assert!(matches!(
            write_report(&blocked, &data()),
            Err(ReportError::Io { .. })
        ));
    }

    #[test]
    fn the_page_needs_nothing_from_outside() {
        let html = html();
        for outside in ["<script", "<link", "http://", "https://", "@import", "url("] {
            assert!(!html.contains(outside), "{outside} found");
        }
    }
}
