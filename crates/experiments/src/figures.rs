//! Figures of the study, equivalent to figures 7-12 of Gu & Zhu (2014), written as PNG and SVG.
//!
//! The functions take plain slices, so they know nothing of the study that feeds them:
//!
//! * a **map** ([`Panel::map`]): several `(x, y)` series, for instance the actual position `y`
//!   against the desired position `y_d` (figs. 7, 8a-10a and 12), optionally with the `y = x`
//!   line an ideal compensator would follow;
//! * a **time series** ([`Panel::time_series`]): several series against time, for tracking
//!   responses (figs. 8b-10b) and tracking errors (figs. 8c-10c and 11);
//! * a **composite per approach** ([`write_approach_figure`]): map, response and error as the
//!   three panels (a), (b), (c) of one image, like the paper's figures 8-10.
//!
//! Each figure is written as `<stem>.png` and `<stem>.svg` in the directory given, atomically
//! (drawn in memory, written to a temporary file in the same directory, then renamed), so a
//! reader never sees half a file. Records are long (200 000 samples at 10 kHz): every series is
//! thinned for drawing by [`decimate_min_max`], which keeps the smallest and the largest `y` of
//! each run of consecutive samples, so that the envelope of the data (and hence the width of a
//! hysteresis loop, index (12)) looks the same as undecimated while SVG files stay small.
//!
//! Text is drawn with DejaVu Sans, compiled into the binary from `assets/` and registered with
//! plotters' `ab_glyph` renderer, so no system font library is needed to build or run.
//!
//! Bad data (no series, an empty series, unequal `x` and `y` lengths, NaN or infinite samples)
//! gives a [`FigureError`], never a panic.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};

/// The family name the committed font is registered under (the name plotters uses by default,
/// so that SVG viewers fall back to their own sans-serif font).
const FONT_FAMILY: &str = "sans-serif";
/// DejaVu Sans (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`).
const FONT_BYTES: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Axis label for the desired position, the horizontal axis of the maps (figs. 7-10a, 12).
pub const LABEL_DESIRED_POSITION: &str = "desired position y_d (µm)";
/// Axis label for the actual (measured) position, the vertical axis of the maps.
pub const LABEL_ACTUAL_POSITION: &str = "actual position y (µm)";
/// Axis label for time, the horizontal axis of the time series.
pub const LABEL_TIME: &str = "time (s)";
/// Axis label for a position against time (figs. 8b-10b).
pub const LABEL_POSITION: &str = "position (µm)";
/// Axis label for the tracking error `y - y_d` (figs. 8c-10c, 11).
pub const LABEL_TRACKING_ERROR: &str = "tracking error y − y_d (µm)";

/// How many points each series keeps at most after [`decimate_min_max`] when drawn.
pub const DEFAULT_MAX_POINTS: usize = 4000;

/// Size of a single-panel figure in pixels (PNG) and user units (SVG).
pub const PANEL_FIGURE_SIZE: (u32, u32) = (1200, 800);
/// Size of a composite figure made by [`write_approach_figure`].
pub const APPROACH_FIGURE_SIZE: (u32, u32) = (1600, 900);

/// Why a figure could not be drawn or written.
#[derive(Debug)]
pub enum FigureError {
    /// The panel has no series to draw.
    NoSeries {
        /// Title of the panel.
        panel: String,
    },
    /// A series has no samples.
    EmptySeries {
        /// Label of the series.
        series: String,
    },
    /// A series has `x` and `y` of different lengths.
    LengthMismatch {
        /// Label of the series.
        series: String,
        /// Number of `x` samples.
        x_len: usize,
        /// Number of `y` samples.
        y_len: usize,
    },
    /// A sample is NaN or infinite.
    NonFinite {
        /// Label of the series.
        series: String,
        /// `"x"` or `"y"`.
        axis: &'static str,
        /// 0-based index of the first bad sample.
        index: usize,
    },
    /// The data spans a range too wide to draw (its width overflows `f64`).
    RangeTooWide {
        /// Title of the panel.
        panel: String,
    },
    /// A series of a panel with a logarithmic vertical axis has a `y` <= 0.
    NotPositive {
        /// Label of the series.
        series: String,
        /// 0-based index of the first bad sample.
        index: usize,
    },
    /// Fewer than two points asked of [`decimate_min_max`].
    TooFewPoints(usize),
    /// The file stem is empty or not a plain file name.
    BadStem(String),
    /// The committed font could not be registered (a broken build, not bad data).
    Font(String),
    /// plotters failed while drawing.
    Drawing(String),
    /// The PNG encoder failed.
    Encoding(String),
    /// Creating the directory or writing a file failed.
    Io {
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}

impl fmt::Display for FigureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FigureError::NoSeries { panel } => {
                write!(
                    f,
                    "the panel {panel:?} has no series to draw; give at least one"
                )
            }
            FigureError::EmptySeries { series } => {
                write!(f, "the series {series:?} has no samples; give at least one")
            }
            FigureError::LengthMismatch {
                series,
                x_len,
                y_len,
            } => write!(
                f,
                "the series {series:?} has {x_len} x samples but {y_len} y samples; \
                 give one x per y"
            ),
            FigureError::NonFinite {
                series,
                axis,
                index,
            } => write!(
                f,
                "the series {series:?} has a NaN or infinite {axis} value at sample {index} \
                 (0-based); figures need finite data"
            ),
            FigureError::RangeTooWide { panel } => write!(
                f,
                "the data of the panel {panel:?} spans a range too wide to draw \
                 (its width overflows f64)"
            ),
            FigureError::NotPositive { series, index } => write!(
                f,
                "series {series:?} has a value <= 0 at sample {index} (0-based), which a \
                 logarithmic axis cannot show"
            ),
            FigureError::TooFewPoints(n) => {
                write!(f, "decimation to {n} point(s) asked; ask for at least 2")
            }
            FigureError::BadStem(stem) => write!(
                f,
                "the figure name {stem:?} is not a plain file name: use letters, digits, \
                 '-', '_' and '.' only, without a leading '.'"
            ),
            FigureError::Font(msg) => write!(f, "the committed font could not be loaded: {msg}"),
            FigureError::Drawing(msg) => write!(f, "drawing the figure failed: {msg}"),
            FigureError::Encoding(msg) => write!(f, "encoding the PNG failed: {msg}"),
            FigureError::Io { path, source } => {
                write!(f, "could not write {}: {source}", path.display())
            }
        }
    }
}

impl std::error::Error for FigureError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            FigureError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// One labelled curve: `y[i]` against `x[i]`.
#[derive(Debug, Clone, Copy)]
pub struct Series<'a> {
    /// Legend text, e.g. `"desired y_d"`; an empty label leaves the series out of the legend.
    pub label: &'a str,
    /// Horizontal coordinates (µm for maps, s for time series).
    pub x: &'a [f64],
    /// Vertical coordinates, one per `x`.
    pub y: &'a [f64],
    /// Colour and line; `None` takes the next of the palette and the line patterns in turn.
    pub style: Option<SeriesStyle>,
}

impl<'a> Series<'a> {
    /// A series from its legend text and coordinates.
    pub fn new(label: &'a str, x: &'a [f64], y: &'a [f64]) -> Self {
        Series {
            label,
            x,
            y,
            style: None,
        }
    }
}

/// A colour of the figures: the Okabe-Ito colour-blind-safe palette, plus black.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Colour {
    /// #0072B2.
    Blue,
    /// #D55E00.
    Vermilion,
    /// #009E73.
    Green,
    /// #CC79A7.
    Purple,
    /// #E69F00.
    Orange,
    /// #56B4E9.
    SkyBlue,
    /// #000000.
    Black,
}

impl Colour {
    fn rgb(self) -> RGBColor {
        match self {
            Colour::Blue => PALETTE[0],
            Colour::Vermilion => PALETTE[1],
            Colour::Green => PALETTE[2],
            Colour::Purple => PALETTE[3],
            Colour::Orange => PALETTE[4],
            Colour::SkyBlue => PALETTE[5],
            Colour::Black => BLACK,
        }
    }

    /// `#RRGGBB`, as the SVG files write it.
    pub fn hex(self) -> String {
        let RGBColor(r, g, b) = self.rgb();
        format!("#{r:02X}{g:02X}{b:02X}")
    }
}

/// A line pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Line {
    /// Solid.
    Solid,
    /// Long dashes.
    Dashed,
    /// Short dots.
    Dotted,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SeriesStyle {
    /// Its colour.
    pub colour: Colour,
    /// Its line.
    pub line: Line,
    /// Drawn thin and pale, behind what matters (e.g. raw loops behind their envelope).
    pub faint: bool,
}

impl SeriesStyle {
    /// The desired trajectory `y_d`: black, dashed.
    pub const DESIRED: SeriesStyle = SeriesStyle::solid(Colour::Black).with_line(Line::Dashed);
    /// The uncompensated run (linear feedforward gain).
    pub const UNCOMPENSATED: SeriesStyle = SeriesStyle::solid(Colour::Orange);
    /// IHC, in every figure and pipeline.
    pub const IHC: SeriesStyle = SeriesStyle::solid(Colour::Blue);
    /// WIHC, in every figure and pipeline.
    pub const WIHC: SeriesStyle = SeriesStyle::solid(Colour::Vermilion).with_line(Line::Dashed);
    /// DIHC, in every figure and pipeline.
    pub const DIHC: SeriesStyle = SeriesStyle::solid(Colour::Green);

    /// A solid line of `colour`.
    pub const fn solid(colour: Colour) -> Self {
        SeriesStyle {
            colour,
            line: Line::Solid,
            faint: false,
        }
    }

    /// The same with another line pattern.
    pub const fn with_line(mut self, line: Line) -> Self {
        self.line = line;
        self
    }

    /// The same drawn faint (thin, pale, solid).
    pub const fn faint(mut self) -> Self {
        self.faint = true;
        self.line = Line::Solid;
        self
    }

    /// The style of an approach in every figure: `"ihc"`, `"wihc"`, `"dihc"` (also with a
    /// `-delayed` suffix, the same approach), `"uncompensated"`, `"desired"`. A new approach
    /// (a pipeline's chain, a learned correction) adds its name here, so that it keeps one
    /// colour across figures.
    pub fn of_approach(name: &str) -> Option<SeriesStyle> {
        match name.trim_end_matches("-delayed") {
            "ihc" => Some(SeriesStyle::IHC),
            "wihc" => Some(SeriesStyle::WIHC),
            "dihc" => Some(SeriesStyle::DIHC),
            "uncompensated" => Some(SeriesStyle::UNCOMPENSATED),
            "desired" => Some(SeriesStyle::DESIRED),
            _ => None,
        }
    }
}

/// What a panel shows, which sets its ranges and where its legend and notes go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PanelKind {
    /// `y` against `x` for maps: legend at the upper left and notes at the lower right, the
    /// corners a monotone map leaves empty.
    Map {
        /// Draw the line `y = x` (what an ideal compensator gives), and give both axes the same
        /// range so that it is the diagonal.
        diagonal: bool,
    },
    /// Series against time: the time axis spans the data exactly, and a band is left free at
    /// the top for the legend (right) and notes (left), so that they never hide data.
    TimeSeries,
}

/// One plot: title, axis labels with units, series and short notes.
#[derive(Debug, Clone)]
pub struct Panel<'a> {
    /// Title drawn above the plot, e.g. `"IHC: desired versus actual position"`.
    pub title: &'a str,
    /// Horizontal axis label with its unit, e.g. [`LABEL_DESIRED_POSITION`].
    pub x_label: &'a str,
    /// Vertical axis label with its unit, e.g. [`LABEL_ACTUAL_POSITION`].
    pub y_label: &'a str,
    /// The curves, drawn in order; colours and line styles cycle through a colour-blind-safe
    /// palette (blue solid, vermilion dashed, green solid, purple dotted, ...), so that the
    /// paper's "blue solid: desired, red dashed: actual" comes out of giving desired first.
    pub series: Vec<Series<'a>>,
    /// Map or time series.
    pub kind: PanelKind,
    /// Short lines shown in a box inside the plot, e.g. `"e_mhe = 2.9 % (100 bins)"`.
    pub notes: Vec<&'a str>,
    /// At most this many points are drawn per series (see [`decimate_min_max`]).
    pub max_points: usize,
    /// A logarithmic vertical axis (every `y` must then be > 0).
    pub log_y: bool,
    /// A fixed vertical range `(lo, hi)` instead of the data's, e.g. the same for panels that
    /// are to be compared by eye; data outside it is clipped.
    pub y_range: Option<(f64, f64)>,
    /// Leave a band at the top for the legend and notes, so that they never cover data (always
    /// so for time series; for maps whose corners are not empty).
    pub legend_band: bool,
}

impl<'a> Panel<'a> {
    /// A map of actual against desired position, with the axis labels
    /// [`LABEL_DESIRED_POSITION`] and [`LABEL_ACTUAL_POSITION`] and the `y = x` line when
    /// `diagonal`.
    pub fn map(title: &'a str, diagonal: bool) -> Self {
        Panel {
            title,
            x_label: LABEL_DESIRED_POSITION,
            y_label: LABEL_ACTUAL_POSITION,
            series: Vec::new(),
            kind: PanelKind::Map { diagonal },
            notes: Vec::new(),
            max_points: DEFAULT_MAX_POINTS,
            log_y: false,
            y_range: None,
            legend_band: false,
        }
    }

    /// Series against time ([`LABEL_TIME`]) with the given vertical label, e.g.
    /// [`LABEL_POSITION`] or [`LABEL_TRACKING_ERROR`].
    pub fn time_series(title: &'a str, y_label: &'a str) -> Self {
        Panel {
            title,
            x_label: LABEL_TIME,
            y_label,
            series: Vec::new(),
            kind: PanelKind::TimeSeries,
            notes: Vec::new(),
            max_points: DEFAULT_MAX_POINTS,
            log_y: false,
            y_range: None,
            legend_band: false,
        }
    }

    /// Adds a series (builder style).
    pub fn with_series(mut self, label: &'a str, x: &'a [f64], y: &'a [f64]) -> Self {
        self.series.push(Series::new(label, x, y));
        self
    }

    /// Adds a series drawn in `style` (builder style).
    pub fn with_styled_series(
        mut self,
        label: &'a str,
        x: &'a [f64],
        y: &'a [f64],
        style: SeriesStyle,
    ) -> Self {
        let mut series = Series::new(label, x, y);
        series.style = Some(style);
        self.series.push(series);
        self
    }

    /// Fixes the vertical range (builder style), e.g. to share it between panels.
    pub fn with_y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = Some((lo, hi));
        self
    }

    /// Leaves a band at the top for the legend and notes (builder style).
    pub fn with_legend_band(mut self) -> Self {
        self.legend_band = true;
        self
    }

    /// Adds a note line (builder style).
    pub fn with_note(mut self, note: &'a str) -> Self {
        self.notes.push(note);
        self
    }

    /// Makes the vertical axis logarithmic (builder style); every `y` must be > 0.
    pub fn with_log_y(mut self) -> Self {
        self.log_y = true;
        self
    }

    /// Replaces the axis labels (builder style).
    pub fn with_axis_labels(mut self, x_label: &'a str, y_label: &'a str) -> Self {
        self.x_label = x_label;
        self.y_label = y_label;
        self
    }
}

/// The two files written for one figure.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FigureFiles {
    /// `<dir>/<stem>.png`.
    pub png: PathBuf,
    /// `<dir>/<stem>.svg`.
    pub svg: PathBuf,
}

/// Draws one panel as `<dir>/<stem>.png` and `<dir>/<stem>.svg` ([`PANEL_FIGURE_SIZE`]),
/// creating `dir` if needed.
///
/// Use a [`PanelKind::Map`] panel for figs. 7, 8a-10a and 12, and a
/// [`PanelKind::TimeSeries`] panel for figs. 8b-10b, 8c-10c and 11.
pub fn write_panel_figure(
    dir: &Path,
    stem: &str,
    panel: &Panel<'_>,
) -> Result<FigureFiles, FigureError> {
    let prepared = prepare(panel, plot_height_px(PANEL_FIGURE_SIZE.1))?;
    let layout = Layout::Single(&prepared);
    render(dir, stem, PANEL_FIGURE_SIZE, &layout)
}

/// Draws the three results of one approach as one image, like the paper's figs. 8-10:
/// `(a)` the map of actual against desired position on the left, `(b)` the tracking response
/// at the upper right and `(c)` the tracking error at the lower right, under `title`
/// ([`APPROACH_FIGURE_SIZE`]).
pub fn write_approach_figure(
    dir: &Path,
    stem: &str,
    title: &str,
    map: &Panel<'_>,
    response: &Panel<'_>,
    error: &Panel<'_>,
) -> Result<FigureFiles, FigureError> {
    let full = plot_height_px(APPROACH_FIGURE_SIZE.1 - COMPOSITE_TITLE_PX);
    let half = plot_height_px((APPROACH_FIGURE_SIZE.1 - COMPOSITE_TITLE_PX) / 2);
    let prepared = [
        prepare(map, full)?,
        prepare(response, half)?,
        prepare(error, half)?,
    ];
    let layout = Layout::Approach {
        title,
        panels: &prepared,
    };
    render(dir, stem, APPROACH_FIGURE_SIZE, &layout)
}

/// Thins `(x, y)` to at most `max_points` points for drawing, keeping the envelope.
///
/// The samples are cut into `max_points / 2` runs of consecutive samples of (nearly) equal
/// length, run `b` being indices `b * n / bins .. (b + 1) * n / bins`; from each run the sample
/// with the smallest `y` and the one with the largest `y` are kept (the first of equals), in
/// their original order. Records of at most `max_points` samples come back whole.
/// See [`decimate_min_max_indices`] for the indices kept.
pub fn decimate_min_max(
    x: &[f64],
    y: &[f64],
    max_points: usize,
) -> Result<Vec<(f64, f64)>, FigureError> {
    let series = Series::new("decimated", x, y);
    validate_series(&series)?;
    let indices = decimate_min_max_indices(y, max_points)?;
    Ok(indices.into_iter().map(|i| (x[i], y[i])).collect())
}

/// The indices [`decimate_min_max`] keeps, strictly increasing.
///
/// Errors when `max_points < 2` or a value is NaN (infinities are ordered and allowed here).
pub fn decimate_min_max_indices(y: &[f64], max_points: usize) -> Result<Vec<usize>, FigureError> {
    if max_points < 2 {
        return Err(FigureError::TooFewPoints(max_points));
    }
    if let Some(index) = y.iter().position(|v| v.is_nan()) {
        return Err(FigureError::NonFinite {
            series: "decimated".to_string(),
            axis: "y",
            index,
        });
    }
    let n = y.len();
    if n <= max_points {
        return Ok((0..n).collect());
    }
    let bins = max_points / 2;
    let mut kept = Vec::with_capacity(2 * bins);
    for b in 0..bins {
        let start = bin_boundary(b, n, bins);
        let end = bin_boundary(b + 1, n, bins);
        let (mut lo, mut hi) = (start, start);
        for i in start + 1..end {
            if y[i] < y[lo] {
                lo = i;
            }
            if y[i] > y[hi] {
                hi = i;
            }
        }
        let (first, second) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        kept.push(first);
        if second != first {
            kept.push(second);
        }
    }
    Ok(kept)
}

/// First index of run `b` when `n` samples are cut into `bins` runs.
fn bin_boundary(b: usize, n: usize, bins: usize) -> usize {
    // u128 so that `b * n` cannot overflow for any slice length.
    (b as u128 * n as u128 / bins as u128) as usize
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so
/// that readers see either the old file or the whole new one. The file is made readable by
/// everyone (0644 on Unix) like a file written plainly.
pub(crate) fn write_file_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".hystcomp-tmp-")
        .tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    tmp.as_file().sync_all()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Preparation: validation, decimation and ranges, shared by the PNG and the SVG drawing.

/// A panel checked, thinned and with its ranges fixed.
struct PreparedPanel<'a> {
    panel: &'a Panel<'a>,
    points: Vec<Vec<(f64, f64)>>,
    x_range: (f64, f64),
    y_range: (f64, f64),
}

fn validate_series(s: &Series<'_>) -> Result<(), FigureError> {
    if s.x.len() != s.y.len() {
        return Err(FigureError::LengthMismatch {
            series: s.label.to_string(),
            x_len: s.x.len(),
            y_len: s.y.len(),
        });
    }
    if s.x.is_empty() {
        return Err(FigureError::EmptySeries {
            series: s.label.to_string(),
        });
    }
    for (axis, values) in [("x", s.x), ("y", s.y)] {
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(FigureError::NonFinite {
                series: s.label.to_string(),
                axis,
                index,
            });
        }
    }
    Ok(())
}

/// Height in pixels of the plotting area of a panel `panel_height_px` high (see `draw_panel`).
fn plot_height_px(panel_height_px: u32) -> f64 {
    let caption = TITLE_FONT_PX as f64 * 1.5;
    (panel_height_px as f64 - 2.0 * PANEL_MARGIN_PX as f64 - X_LABEL_AREA_PX as f64 - caption)
        .max(100.0)
}

fn prepare<'a>(panel: &'a Panel<'a>, plot_px: f64) -> Result<PreparedPanel<'a>, FigureError> {
    if panel.series.is_empty() {
        return Err(FigureError::NoSeries {
            panel: panel.title.to_string(),
        });
    }
    let mut points = Vec::with_capacity(panel.series.len());
    for s in &panel.series {
        validate_series(s)?;
        if panel.log_y
            && let Some(index) = s.y.iter().position(|&y| y <= 0.0)
        {
            return Err(FigureError::NotPositive {
                series: s.label.to_string(),
                index,
            });
        }
        let kept = decimate_min_max_indices(s.y, panel.max_points)?;
        points.push(
            kept.into_iter()
                .map(|i| (s.x[i], s.y[i]))
                .collect::<Vec<_>>(),
        );
    }
    let span = |values: &mut dyn Iterator<Item = f64>| {
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
    };
    // Ranges from the full data, not the decimated points (the x extremes may fall between).
    let x_span = span(&mut panel.series.iter().flat_map(|s| s.x.iter().copied()));
    // A logarithmic axis is laid out in log10(y) and converted back at the end.
    let to_axis = |y: f64| if panel.log_y { y.log10() } else { y };
    let y_span = span(
        &mut panel
            .series
            .iter()
            .flat_map(|s| s.y.iter().copied().map(to_axis)),
    );
    let too_wide = || FigureError::RangeTooWide {
        panel: panel.title.to_string(),
    };
    let fixed = match panel.y_range {
        Some((lo, hi)) if lo.is_finite() && hi.is_finite() && lo < hi => {
            Some((to_axis(lo), to_axis(hi)))
        }
        Some(_) => return Err(too_wide()),
        None => None,
    };
    let (x_range, y_range) = match panel.kind {
        PanelKind::Map { diagonal } => {
            let (x_span, y_span) = if diagonal {
                let both = (x_span.0.min(y_span.0), x_span.1.max(y_span.1));
                (both, both)
            } else {
                (x_span, y_span)
            };
            let y = match fixed {
                Some(y) => y,
                None => padded(y_span, 0.03, 0.03).ok_or_else(too_wide)?,
            };
            (padded(x_span, 0.03, 0.03).ok_or_else(too_wide)?, y)
        }
        PanelKind::TimeSeries => {
            let x = padded(x_span, 0.0, 0.0).ok_or_else(too_wide)?;
            let y = match fixed {
                Some(y) => y,
                None => padded(y_span, 0.05, 0.05).ok_or_else(too_wide)?,
            };
            (x, y)
        }
    };
    let y_range = if panel.kind == PanelKind::TimeSeries || panel.legend_band {
        // Headroom for the legend: rows of ~1.3 font heights plus margins, as a fraction
        // of the plot height (checked by eye on the rendered figures).
        let labelled = panel.series.iter().filter(|s| !s.label.is_empty()).count();
        let rows = labelled.max(panel.notes.len()) as f64;
        let legend_px = rows * LEGEND_FONT_PX as f64 * 1.3 + 32.0;
        let top = (legend_px / plot_px).min(0.6);
        let width = y_range.1 - y_range.0;
        let y = (y_range.0, y_range.1 + width * top / (1.0 - top));
        if !(y.1 - y.0).is_finite() {
            return Err(too_wide());
        }
        y
    } else {
        y_range
    };
    let y_range = if panel.log_y {
        (10f64.powf(y_range.0), 10f64.powf(y_range.1))
    } else {
        y_range
    };
    Ok(PreparedPanel {
        panel,
        points,
        x_range,
        y_range,
    })
}

/// `(lo, hi)` widened by fractions of its width below and above; a zero width becomes a unit
/// (or 10 %) width around the value. `None` when the width overflows.
fn padded((lo, hi): (f64, f64), below: f64, above: f64) -> Option<(f64, f64)> {
    let width = hi - lo;
    if !width.is_finite() {
        return None;
    }
    if width <= f64::EPSILON * lo.abs().max(hi.abs()).max(f64::MIN_POSITIVE) {
        let half = (0.1 * lo.abs()).max(1.0);
        return Some((lo - half, hi + half));
    }
    let r = (lo - below * width, hi + above * width);
    (r.1 - r.0).is_finite().then_some(r)
}

// ---------------------------------------------------------------------------------------------
// Drawing.

const TITLE_FONT_PX: u32 = 24;
const AXIS_FONT_PX: u32 = 20;
const TICK_FONT_PX: u32 = 17;
const LEGEND_FONT_PX: u32 = 17;
/// Margin around each panel.
const PANEL_MARGIN_PX: u32 = 14;
/// Height of the area under a panel for the tick labels and the horizontal axis label.
const X_LABEL_AREA_PX: u32 = 62;
/// Height taken by the title of a composite figure.
const COMPOSITE_TITLE_PX: u32 = 50;
/// Above this many drawn points a series is drawn 1 px wide instead of 2.
const DENSE_POINTS: usize = 1000;

/// Okabe-Ito colour-blind-safe palette, in the order series use it.
const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermilion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
];

/// The colours of series without a style, in turn.
const DEFAULT_COLOURS: [Colour; 6] = [
    Colour::Blue,
    Colour::Vermilion,
    Colour::Green,
    Colour::Purple,
    Colour::Orange,
    Colour::SkyBlue,
];

/// Line patterns, cycled with a period coprime to the palette's so that pairs stay distinct.
const DASHES: [Line; 4] = [Line::Solid, Line::Dashed, Line::Solid, Line::Dotted];

enum Layout<'a> {
    Single(&'a PreparedPanel<'a>),
    Approach {
        title: &'a str,
        panels: &'a [PreparedPanel<'a>; 3],
    },
}

fn check_stem(stem: &str) -> Result<(), FigureError> {
    let ok = !stem.is_empty()
        && !stem.starts_with('.')
        && stem
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if ok {
        Ok(())
    } else {
        Err(FigureError::BadStem(stem.to_string()))
    }
}

fn ensure_font() -> Result<(), FigureError> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            register_font(FONT_FAMILY, FontStyle::Normal, FONT_BYTES)
                .map_err(|_| "assets/DejaVuSans.ttf is not a valid TrueType font".to_string())
        })
        .clone()
        .map_err(FigureError::Font)
}

fn drawing_error<E: std::error::Error + Send + Sync>(
    e: plotters::drawing::DrawingAreaErrorKind<E>,
) -> FigureError {
    FigureError::Drawing(e.to_string())
}

fn render(
    dir: &Path,
    stem: &str,
    size: (u32, u32),
    layout: &Layout<'_>,
) -> Result<FigureFiles, FigureError> {
    check_stem(stem)?;
    ensure_font()?;
    std::fs::create_dir_all(dir).map_err(|source| FigureError::Io {
        path: dir.to_path_buf(),
        source,
    })?;

    let (w, h) = size;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_layout(&root, layout)?;
        root.present().map_err(drawing_error)?;
    }
    let png = encode_png(&rgb, size)?;

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_layout(&root, layout)?;
        root.present().map_err(drawing_error)?;
    }

    let files = FigureFiles {
        png: dir.join(format!("{stem}.png")),
        svg: dir.join(format!("{stem}.svg")),
    };
    for (path, bytes) in [(&files.png, png.as_slice()), (&files.svg, svg.as_bytes())] {
        write_file_atomically(path, bytes).map_err(|source| FigureError::Io {
            path: path.clone(),
            source,
        })?;
    }
    Ok(files)
}

fn encode_png(rgb: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, FigureError> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    // Figures are mostly flat colour: adaptive filtering makes them about five times smaller
    // (the best compression level gains nothing more and is several times slower).
    encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
    encoder.set_compression(png::Compression::Default);
    let mut writer = encoder
        .write_header()
        .map_err(|e| FigureError::Encoding(e.to_string()))?;
    writer
        .write_image_data(rgb)
        .map_err(|e| FigureError::Encoding(e.to_string()))?;
    writer
        .finish()
        .map_err(|e| FigureError::Encoding(e.to_string()))?;
    Ok(out)
}

fn draw_layout<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    layout: &Layout<'_>,
) -> Result<(), FigureError> {
    root.fill(&WHITE).map_err(drawing_error)?;
    match layout {
        Layout::Single(panel) => draw_panel(root, panel),
        Layout::Approach { title, panels } => {
            let (head, body) = root.split_vertically(COMPOSITE_TITLE_PX);
            let style = TextStyle::from((FONT_FAMILY, TITLE_FONT_PX + 4).into_font())
                .pos(Pos::new(HPos::Center, VPos::Center));
            let (w, h) = head.dim_in_pixel();
            head.draw(&Text::new(
                title.to_string(),
                (w as i32 / 2, h as i32 / 2 + 4),
                style,
            ))
            .map_err(drawing_error)?;
            let (w, _) = body.dim_in_pixel();
            let (left, right) = body.split_horizontally(w * 9 / 20);
            let (upper, lower) = {
                let (_, h) = right.dim_in_pixel();
                right.split_vertically(h / 2)
            };
            draw_panel(&left, &panels[0])?;
            draw_panel(&upper, &panels[1])?;
            draw_panel(&lower, &panels[2])
        }
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    prepared: &PreparedPanel<'_>,
) -> Result<(), FigureError> {
    let panel = prepared.panel;
    let (x0, x1) = prepared.x_range;
    let (y0, y1) = prepared.y_range;
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(PANEL_MARGIN_PX)
        .margin_right(2 * PANEL_MARGIN_PX)
        .caption(panel.title, (FONT_FAMILY, TITLE_FONT_PX))
        .x_label_area_size(X_LABEL_AREA_PX)
        .y_label_area_size(92);
    if panel.log_y {
        let chart = builder
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(drawing_error)?;
        draw_chart(chart, prepared)
    } else {
        let chart = builder
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(drawing_error)?;
        draw_chart(chart, prepared)
    }
}

/// Draws the mesh, the series, the legend and the notes of a panel on its chart.
fn draw_chart<'a, DB, Y>(
    mut chart: ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    prepared: &PreparedPanel<'_>,
) -> Result<(), FigureError>
where
    DB: DrawingBackend + 'a,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let panel = prepared.panel;
    let (x0, x1) = prepared.x_range;
    chart
        .configure_mesh()
        .x_desc(panel.x_label)
        .y_desc(panel.y_label)
        .axis_desc_style((FONT_FAMILY, AXIS_FONT_PX))
        .label_style((FONT_FAMILY, TICK_FONT_PX))
        .x_labels(9)
        .y_labels(8)
        .x_label_formatter(&tick_label)
        .y_label_formatter(&tick_label)
        .bold_line_style(RGBColor(222, 222, 222))
        .light_line_style(RGBColor(242, 242, 242))
        .max_light_lines(4)
        .axis_style(RGBColor(90, 90, 90))
        .draw()
        .map_err(drawing_error)?;

    if let PanelKind::Map { diagonal: true } = panel.kind {
        let grey = RGBColor(120, 120, 120);
        let line = [(x0, x0), (x1, x1)];
        chart
            .draw_series(DashedLineSeries::new(line, 6, 6, grey.stroke_width(1)))
            .map_err(drawing_error)?
            .label("ideal: y = y_d")
            .legend(move |(x, y)| {
                DashedPathElement::new([(x, y), (x + 32, y)], 6, 4, grey.stroke_width(1))
            });
    }

    for (k, (series, points)) in panel.series.iter().zip(&prepared.points).enumerate() {
        let style = series.style.unwrap_or(SeriesStyle {
            colour: DEFAULT_COLOURS[k % DEFAULT_COLOURS.len()],
            line: DASHES[k % DASHES.len()],
            faint: false,
        });
        let colour = style.colour.rgb();
        // Dense records (more points than the plot has pixels across) are drawn thin so that
        // overlaid noisy series stay apart; the legend keeps a thick line to show the colour.
        let width = if points.len() > DENSE_POINTS || style.faint {
            1
        } else {
            2
        };
        let pen = if style.faint {
            colour.mix(0.3).stroke_width(width)
        } else {
            colour.stroke_width(width)
        };
        let key = colour.stroke_width(2);
        let anno = match style.line {
            Line::Solid => chart
                .draw_series(LineSeries::new(points.iter().copied(), pen))
                .map_err(drawing_error)?,
            Line::Dashed => chart
                .draw_series(DashedLineSeries::new(points.iter().copied(), 12, 7, pen))
                .map_err(drawing_error)?,
            Line::Dotted => chart
                .draw_series(DashedLineSeries::new(points.iter().copied(), 3, 5, pen))
                .map_err(drawing_error)?,
        };
        if series.label.is_empty() {
            continue;
        }
        anno.label(series.label);
        match style.line {
            Line::Solid => {
                anno.legend(move |(x, y)| PathElement::new([(x, y), (x + 32, y)], key));
            }
            Line::Dashed => {
                anno.legend(move |(x, y)| {
                    DashedPathElement::new([(x, y), (x + 32, y)], 10, 6, key)
                });
            }
            Line::Dotted => {
                anno.legend(move |(x, y)| DashedPathElement::new([(x, y), (x + 32, y)], 3, 5, key));
            }
        }
    }

    let (legend_at, notes_at) = match panel.kind {
        PanelKind::Map { .. } if !panel.legend_band => {
            (SeriesLabelPosition::UpperLeft, Corner::LowerRight)
        }
        _ => (SeriesLabelPosition::UpperRight, Corner::UpperLeft),
    };
    chart
        .configure_series_labels()
        .position(legend_at)
        .margin(10)
        .legend_area_size(40)
        .label_font((FONT_FAMILY, LEGEND_FONT_PX))
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(150, 150, 150))
        .draw()
        .map_err(drawing_error)?;

    if !panel.notes.is_empty() {
        draw_notes(
            &chart.plotting_area().strip_coord_spec(),
            &panel.notes,
            notes_at,
        )?;
    }
    Ok(())
}

/// A tick value without needless digits: `10`, `2.5`, `0.2` (not `10.0`, `0.20000000000000004`)
/// and never `-0`.
fn tick_label(v: &f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    match s {
        "-0" | "" => "0".to_string(),
        s => s.to_string(),
    }
}

#[derive(Clone, Copy)]
enum Corner {
    UpperLeft,
    LowerRight,
}

/// Draws `notes` as left-aligned lines in a framed box at a corner of the plotting area.
fn draw_notes<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    notes: &[&str],
    corner: Corner,
) -> Result<(), FigureError> {
    let style = TextStyle::from((FONT_FAMILY, LEGEND_FONT_PX).into_font())
        .pos(Pos::new(HPos::Left, VPos::Top));
    let mut width = 0i32;
    for note in notes {
        let (w, _) = area
            .estimate_text_size(note, &style)
            .map_err(drawing_error)?;
        width = width.max(w as i32);
    }
    let line = (LEGEND_FONT_PX as f64 * 1.3).round() as i32;
    let pad = 10;
    let (box_w, box_h) = (width + 2 * pad, line * notes.len() as i32 + 2 * pad - 4);
    let (area_w, area_h) = area.dim_in_pixel();
    let (left, top) = match corner {
        Corner::UpperLeft => (8, 8),
        Corner::LowerRight => (area_w as i32 - box_w - 8, area_h as i32 - box_h - 8),
    };
    area.draw(&Rectangle::new(
        [(left, top), (left + box_w, top + box_h)],
        WHITE.mix(0.9).filled(),
    ))
    .map_err(drawing_error)?;
    area.draw(&Rectangle::new(
        [(left, top), (left + box_w, top + box_h)],
        RGBColor(150, 150, 150),
    ))
    .map_err(drawing_error)?;
    for (i, note) in notes.iter().enumerate() {
        area.draw(&Text::new(
            note.to_string(),
            (left + pad, top + pad + i as i32 * line),
            style.clone(),
        ))
        .map_err(drawing_error)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padded_widens_a_constant_range_instead_of_dividing_by_zero() {
        let (lo, hi) = padded((5.0, 5.0), 0.1, 0.1).unwrap();
        assert!(lo < 5.0 && hi > 5.0);
        assert_eq!(padded((0.0, f64::MAX), 0.0, 0.0), Some((0.0, f64::MAX)));
        assert_eq!(padded((-f64::MAX, f64::MAX), 0.0, 0.0), None);
    }

    #[test]
    fn tick_labels_have_no_needless_digits() {
        assert_eq!(tick_label(&10.0), "10");
        assert_eq!(tick_label(&2.5), "2.5");
        assert_eq!(tick_label(&(0.1 + 0.2)), "0.3");
        assert_eq!(tick_label(&-0.0), "0");
        assert_eq!(tick_label(&-1e-17), "0");
        assert_eq!(tick_label(&-0.4), "-0.4");
        assert_eq!(tick_label(&1.0e6), "1000000");
    }

    #[test]
    fn stems_must_be_plain_file_names() {
        for bad in ["", "../x", "a/b", ".hidden", "a b", "a\\b"] {
            assert!(check_stem(bad).is_err(), "{bad:?} accepted");
        }
        for good in ["fig07_uncompensated", "fig-8.ihc"] {
            assert!(check_stem(good).is_ok(), "{good:?} refused");
        }
    }

    #[test]
    fn bin_boundaries_cover_every_index_once() {
        for (n, bins) in [(10usize, 3usize), (200_000, 2000), (7, 7), (1001, 500)] {
            assert_eq!(bin_boundary(0, n, bins), 0);
            assert_eq!(bin_boundary(bins, n, bins), n);
            for b in 0..bins {
                assert!(bin_boundary(b, n, bins) < bin_boundary(b + 1, n, bins));
            }
        }
    }
}
