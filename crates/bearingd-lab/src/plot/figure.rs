//! The scene description: plain data saying what a figure shows, not how to draw it.
//!
//! Callers (the CLI, tests) build a [`Figure`]; [`crate::plot::render_svg`] and
//! [`crate::plot::render_png`] turn the same value into pixels or markup.

use serde::{Deserialize, Serialize};

/// An sRGB colour with straight (not premultiplied) alpha.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Color {
    pub r: u8,
    pub g: u8,
    pub b: u8,
    pub a: u8,
}

impl Color {
    /// An opaque colour.
    pub const fn rgb(r: u8, g: u8, b: u8) -> Self {
        Color { r, g, b, a: 255 }
    }

    /// The same colour with another alpha (0 transparent, 255 opaque).
    pub const fn with_alpha(self, a: u8) -> Self {
        Color { a, ..self }
    }

    // The Okabe–Ito palette: distinguishable with the common forms of colour blindness.

    pub const BLACK: Color = Color::rgb(0, 0, 0);
    pub const WHITE: Color = Color::rgb(255, 255, 255);
    pub const GREY: Color = Color::rgb(128, 128, 128);
    pub const LIGHT_GREY: Color = Color::rgb(220, 220, 220);
    pub const ORANGE: Color = Color::rgb(230, 159, 0);
    pub const SKY_BLUE: Color = Color::rgb(86, 180, 233);
    pub const BLUISH_GREEN: Color = Color::rgb(0, 158, 115);
    pub const YELLOW: Color = Color::rgb(240, 228, 66);
    pub const BLUE: Color = Color::rgb(0, 114, 178);
    pub const VERMILLION: Color = Color::rgb(213, 94, 0);
    pub const REDDISH_PURPLE: Color = Color::rgb(204, 121, 167);

    /// Colours for successive series or fault families, in a readable order.
    pub const CYCLE: [Color; 7] = [
        Color::BLUE,
        Color::VERMILLION,
        Color::BLUISH_GREEN,
        Color::REDDISH_PURPLE,
        Color::ORANGE,
        Color::SKY_BLUE,
        Color::BLACK,
    ];
}

/// A whole picture: a title, a few lines of notes under it, and panels stacked vertically.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    pub title: String,
    /// Lines under the title, e.g. "band 2250–3750 Hz (GK index)".
    pub notes: Vec<String>,
    pub panels: Vec<Panel>,
}

impl Figure {
    /// A figure with a title and nothing else yet.
    pub fn new(title: impl Into<String>) -> Self {
        Figure {
            title: title.into(),
            notes: Vec::new(),
            panels: Vec::new(),
        }
    }

    /// Adds a line of notes under the title.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    /// Appends a panel below the existing ones.
    pub fn with_panel(mut self, panel: impl Into<Panel>) -> Self {
        self.panels.push(panel.into());
        self
    }
}

/// One plot area of a figure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Panel {
    Spectrum(SpectrumPanel),
    Heatmap(HeatmapPanel),
}

impl From<SpectrumPanel> for Panel {
    fn from(panel: SpectrumPanel) -> Self {
        Panel::Spectrum(panel)
    }
}

impl From<HeatmapPanel> for Panel {
    fn from(panel: HeatmapPanel) -> Self {
        Panel::Heatmap(panel)
    }
}

/// Line plots over a shared frequency axis, with vertical markers and shaded bands.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpectrumPanel {
    pub x_label: String,
    pub y_label: String,
    /// The frequency axis (Hz), shared by every series.
    pub x: Vec<f64>,
    /// E.g. "measured" and "twin"; each `y` pairs with `x` index by index.
    pub series: Vec<Series>,
    /// Vertical lines: fault frequencies and their harmonics.
    pub markers: Vec<Marker>,
    /// Shaded vertical bands, e.g. ±2 % tolerance around each marker.
    pub shaded: Vec<Shade>,
    /// Visible x interval; `None` spans the data.
    pub x_range: Option<(f64, f64)>,
    /// Logarithmic y axis; zeros and negatives sit on the axis floor.
    pub log_y: bool,
    /// Horizontal reference lines (e.g. zone boundaries), labelled at the right end.
    #[serde(default)]
    pub levels: Vec<Level>,
    /// What the marker colours, line styles and shading mean, listed after the series in the
    /// legend row above the plot.
    #[serde(default)]
    pub legend: Vec<LegendEntry>,
}

impl SpectrumPanel {
    /// An empty panel over `x` with the given axis labels.
    pub fn new(x_label: impl Into<String>, y_label: impl Into<String>, x: Vec<f64>) -> Self {
        SpectrumPanel {
            x_label: x_label.into(),
            y_label: y_label.into(),
            x,
            series: Vec::new(),
            markers: Vec::new(),
            shaded: Vec::new(),
            x_range: None,
            log_y: false,
            levels: Vec::new(),
            legend: Vec::new(),
        }
    }
}

/// One line of y values over the panel's x axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    pub label: String,
    pub y: Vec<f64>,
    pub color: Color,
}

/// A vertical line at `x` with a label written above the plot, e.g. "BPFO" or "2×BPFO".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    pub x: f64,
    pub label: String,
    pub color: Color,
    pub dashed: bool,
}

/// A legend entry: a sample drawn in `color` and what it stands for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LegendEntry {
    pub label: String,
    pub color: Color,
    pub sample: LegendSample,
}

/// How a legend entry's sample is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LegendSample {
    /// A short solid line, like a series or a solid marker.
    Line,
    /// A short dashed line, like a dashed marker.
    DashedLine,
    /// A filled box, like a shaded band.
    Band,
}

/// A horizontal line at `y` across a spectrum panel, labelled at its right end; the y axis
/// is extended to show it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Level {
    pub y: f64,
    pub label: String,
    pub color: Color,
    pub dashed: bool,
}

/// A shaded vertical band from `x0` to `x1`; give the colour some transparency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Shade {
    pub x0: f64,
    pub x1: f64,
    pub color: Color,
}

/// A band-selection map such as the kurtogram: one row per decomposition level, each row split
/// into equal-width cells covering `0..x_max`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeatmapPanel {
    pub title: String,
    pub x_label: String,
    pub x_max: f64,
    /// Top to bottom.
    pub rows: Vec<HeatmapRow>,
    /// The chosen band as `(row, cell)`, drawn outlined.
    pub highlight: Option<(usize, usize)>,
    /// What the colours mean, e.g. "GK index"; written by the colour bar.
    pub value_label: String,
    /// Title of the y axis (what a row is); empty for none.
    #[serde(default)]
    pub y_label: String,
}

/// One row of a heatmap: a label (e.g. the level "1.6") and cell values left to right.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeatmapRow {
    pub label: String,
    pub values: Vec<f64>,
}
