//! Turns a [`Figure`] into a [`Scene`]: a flat list of drawing primitives in pixel
//! coordinates. Every placement decision (margins, ticks, legends, label staggering, colour
//! mapping, decimation) is made here once; the SVG and PNG renderers only translate primitives.

use super::figure::{Color, Figure, HeatmapPanel, Panel, SpectrumPanel};
use super::layout::{decimate_min_max, finite_range, format_number, Axis, PixelScale, Tick};
use super::PlotError;

/// Width of one glyph cell at text scale 1, in pixels (the 8×8 bitmap font; the SVG uses a
/// monospace font sized to the same advance).
pub(crate) const GLYPH_SIZE: f64 = 8.0;

/// Figure width in pixels.
const FIGURE_WIDTH: f64 = 1200.0;
/// Height of one panel in pixels.
const PANEL_HEIGHT: f64 = 380.0;
/// More panels than this would make an unreasonably tall image.
pub(crate) const MAX_PANELS: usize = 16;
/// Notes beyond this many lines are summarised as "… n more".
const MAX_NOTE_LINES: usize = 12;

const OUTER_PAD: f64 = 16.0;
const PLOT_LEFT: f64 = 96.0;
const PLOT_RIGHT_PAD: f64 = 32.0;
const LINE_HEIGHT: f64 = 14.0;
const TITLE_SCALE: u32 = 2;
const TEXT_SCALE: u32 = 1;
/// Marker labels are staggered over at most this many rows above the plot.
const MAX_MARKER_ROWS: usize = 4;
/// Heatmap cells narrower than this many pixels are merged (showing the column maximum).
const MIN_CELL_WIDTH: f64 = 1.0;
/// Space right of a heatmap for the colour bar, its ticks and its label.
const COLOR_BAR_AREA: f64 = 120.0;
const COLOR_BAR_WIDTH: f64 = 18.0;
const COLOR_BAR_STEPS: usize = 96;

const TEXT_COLOR: Color = Color::rgb(30, 30, 30);
const MUTED_TEXT: Color = Color::rgb(80, 80, 80);
const FRAME_COLOR: Color = Color::rgb(60, 60, 60);
const GRID_COLOR: Color = Color::rgb(228, 228, 228);
const MISSING_CELL: Color = Color::rgb(200, 200, 200);

/// A line style.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Stroke {
    pub color: Color,
    pub width: f64,
    /// Dash and gap lengths; `None` for a solid line.
    pub dash: Option<(f64, f64)>,
}

impl Stroke {
    fn solid(color: Color, width: f64) -> Self {
        Stroke {
            color,
            width,
            dash: None,
        }
    }
}

/// Horizontal alignment of text relative to its anchor point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    /// Share of the text width lying before the anchor point.
    pub fn offset_fraction(self) -> f64 {
        match self {
            Anchor::Start => 0.0,
            Anchor::Middle => 0.5,
            Anchor::End => 1.0,
        }
    }
}

/// A line of text set in the 8×8 font at an integer scale.
///
/// Horizontal text: `x` is the anchor point along the line, `y` the top of the glyph box.
/// Vertical text (reading bottom to top): `x` is the left of the rotated glyph box and `y`
/// the anchor point along the line.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Text {
    pub x: f64,
    pub y: f64,
    pub content: String,
    pub scale: u32,
    pub anchor: Anchor,
    pub color: Color,
    pub vertical: bool,
}

/// One drawing primitive, in pixel coordinates with y pointing down.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Item {
    Rect {
        x: f64,
        y: f64,
        width: f64,
        height: f64,
        fill: Option<Color>,
        stroke: Option<Stroke>,
        /// Edges lie on whole pixels and must not be anti-aliased (heatmap cells).
        crisp: bool,
    },
    Polyline {
        points: Vec<(f64, f64)>,
        stroke: Stroke,
    },
    Dot {
        x: f64,
        y: f64,
        radius: f64,
        color: Color,
    },
    Text(Text),
}

/// A figure laid out: canvas size, background and primitives in painting order.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Scene {
    pub width: u32,
    pub height: u32,
    pub background: Color,
    pub items: Vec<Item>,
}

/// Width in pixels of `text` at `scale`.
pub(crate) fn text_width(text: &str, scale: u32) -> f64 {
    text.chars().count() as f64 * GLYPH_SIZE * f64::from(scale)
}

/// `text` shortened with "..." so that it fits `max_width` pixels at `scale`.
fn fit_text(text: &str, scale: u32, max_width: f64) -> String {
    let capacity = (max_width / (GLYPH_SIZE * f64::from(scale)))
        .floor()
        .max(0.0) as usize;
    if text.chars().count() <= capacity {
        return text.to_string();
    }
    if capacity <= 3 {
        return text.chars().take(capacity).collect();
    }
    let mut short: String = text.chars().take(capacity - 3).collect();
    short.push_str("...");
    short
}

/// The unit in an axis label written as "name (unit)", e.g. "Hz" in "frequency (Hz)".
fn unit_in(label: &str) -> Option<&str> {
    let inner = label.trim_end().strip_suffix(')')?;
    let unit = &inner[inner.rfind('(')? + 1..];
    (!unit.trim().is_empty()).then(|| unit.trim())
}

/// Half-pixel aligned coordinate so that a 1 px line covers exactly one pixel row or column.
fn crisp(v: f64) -> f64 {
    v.floor() + 0.5
}

/// Lays out a whole figure.
pub(crate) fn build(figure: &Figure) -> Result<Scene, PlotError> {
    if figure.panels.is_empty() {
        return Err(PlotError::NoPanels);
    }
    if figure.panels.len() > MAX_PANELS {
        return Err(PlotError::TooManyPanels {
            count: figure.panels.len(),
            max: MAX_PANELS,
        });
    }
    let mut items = Vec::new();
    let header_bottom = header(figure, &mut items);
    let mut top = header_bottom;
    for panel in &figure.panels {
        match panel {
            Panel::Spectrum(spectrum) => spectrum_panel(spectrum, top, &mut items),
            Panel::Heatmap(heatmap) => heatmap_panel(heatmap, top, &mut items),
        }
        top += PANEL_HEIGHT;
    }
    Ok(Scene {
        width: FIGURE_WIDTH as u32,
        height: (top + OUTER_PAD).ceil() as u32,
        background: Color::WHITE,
        items,
    })
}

fn text(x: f64, y: f64, content: String, scale: u32, anchor: Anchor, color: Color) -> Item {
    Item::Text(Text {
        x,
        y,
        content,
        scale,
        anchor,
        color,
        vertical: false,
    })
}

/// Title and notes; returns the y where panels start.
fn header(figure: &Figure, items: &mut Vec<Item>) -> f64 {
    let max_width = FIGURE_WIDTH - 2.0 * OUTER_PAD;
    let mut y = OUTER_PAD;
    items.push(text(
        OUTER_PAD,
        y,
        fit_text(&figure.title, TITLE_SCALE, max_width),
        TITLE_SCALE,
        Anchor::Start,
        TEXT_COLOR,
    ));
    y += GLYPH_SIZE * f64::from(TITLE_SCALE) + 10.0;
    let shown = if figure.notes.len() > MAX_NOTE_LINES {
        MAX_NOTE_LINES - 1
    } else {
        figure.notes.len()
    };
    for note in &figure.notes[..shown] {
        items.push(text(
            OUTER_PAD,
            y,
            fit_text(note, TEXT_SCALE, max_width),
            TEXT_SCALE,
            Anchor::Start,
            MUTED_TEXT,
        ));
        y += LINE_HEIGHT;
    }
    if shown < figure.notes.len() {
        let more = format!("... {} more", figure.notes.len() - shown);
        items.push(text(
            OUTER_PAD,
            y,
            more,
            TEXT_SCALE,
            Anchor::Start,
            MUTED_TEXT,
        ));
        y += LINE_HEIGHT;
    }
    y + 4.0
}

/// The plot rectangle of a panel, in pixels.
#[derive(Debug, Clone, Copy)]
struct PlotArea {
    left: f64,
    top: f64,
    right: f64,
    bottom: f64,
}

impl PlotArea {
    fn width(&self) -> f64 {
        self.right - self.left
    }
    fn height(&self) -> f64 {
        self.bottom - self.top
    }
}

/// A marker label placed in one of the staggered rows above the plot.
struct PlacedLabel {
    x: f64,
    text: String,
    row: usize,
    color: Color,
    marker_x: f64,
}

/// Places marker labels centred on their markers (kept inside the figure), each in the lowest
/// row where it overlaps no label placed before it. Labels are taken in the caller's order, so
/// list fundamentals before harmonics: when all rows are taken at a spot, later labels there
/// are left out (their marker lines are still drawn). Returns the labels and the rows used.
fn stagger_labels(labels: Vec<(f64, String, Color)>) -> (Vec<PlacedLabel>, usize) {
    const GAP: f64 = 6.0;
    /// Beyond this many labels the top of the plot is full anyway.
    const MAX_LABELS_TRIED: usize = 256;
    let mut rows: [Vec<(f64, f64)>; MAX_MARKER_ROWS] = Default::default();
    let mut placed = Vec::new();
    for (marker_x, label, color) in labels.into_iter().take(MAX_LABELS_TRIED) {
        let text = fit_text(&label, TEXT_SCALE, 160.0);
        let width = text_width(&text, TEXT_SCALE);
        let left = (marker_x - width / 2.0).clamp(4.0, FIGURE_WIDTH - 4.0 - width);
        let right = left + width;
        let free = |row: &Vec<(f64, f64)>| {
            row.iter()
                .all(|&(l, r)| right + GAP <= l || left >= r + GAP)
        };
        if let Some(row) = rows.iter().position(free) {
            rows[row].push((left, right));
            placed.push(PlacedLabel {
                x: left,
                text,
                row,
                color,
                marker_x,
            });
        }
    }
    let rows_used = rows.iter().filter(|r| !r.is_empty()).count();
    (placed, rows_used)
}

fn spectrum_panel(panel: &SpectrumPanel, top: f64, items: &mut Vec<Item>) {
    let plot_left = PLOT_LEFT;
    let plot_right = FIGURE_WIDTH - PLOT_RIGHT_PAD;

    // x axis: the requested range, or the data's.
    let x_axis = Axis::linear(
        panel
            .x_range
            .or_else(|| finite_range(panel.x.iter().copied()))
            .unwrap_or((0.0, 1.0)),
    );
    let x_scale = PixelScale {
        axis: x_axis,
        start: plot_left,
        end: plot_right,
    };
    let columns = (plot_right - plot_left).round() as usize;

    // Thin each series to what the pixel columns can show.
    let thinned: Vec<Vec<(f64, f64)>> = panel
        .series
        .iter()
        .map(|s| decimate_min_max(&panel.x, &s.y, (x_axis.min, x_axis.max), columns))
        .collect();

    // y axis from what is visible.
    let visible_y = thinned.iter().flatten().map(|&(_, y)| y);
    let y_axis = if panel.log_y {
        Axis::log_for_data(finite_range(visible_y.filter(|&y| y > 0.0)))
    } else {
        Axis::linear_for_data(finite_range(visible_y))
    };

    // Markers inside the x range, and their staggered labels.
    let markers: Vec<_> = panel
        .markers
        .iter()
        .filter(|m| m.x.is_finite() && x_axis.contains(m.x))
        .collect();
    let (labels, label_rows) = stagger_labels(
        markers
            .iter()
            .filter(|m| !m.label.is_empty())
            .filter_map(|m| Some((x_scale.to_pixel(m.x)?, m.label.clone(), m.color)))
            .collect(),
    );

    // Vertical budget: legend row, marker label rows, plot, tick labels, x label.
    let legend_y = top + 4.0;
    let labels_top = legend_y + LINE_HEIGHT + 6.0;
    let area = PlotArea {
        left: plot_left,
        right: plot_right,
        top: (labels_top + label_rows as f64 * LINE_HEIGHT + 6.0).round(),
        bottom: (top + PANEL_HEIGHT - 52.0).round(),
    };
    let y_scale = PixelScale {
        axis: y_axis,
        start: area.bottom,
        end: area.top,
    };

    // Grid and ticks.
    let x_ticks = x_axis.ticks(((area.width() / 90.0) as usize).max(2));
    let y_ticks = y_axis.ticks(((area.height() / 45.0) as usize).max(2));
    grid(items, &area, &x_scale, &x_ticks, &y_scale, &y_ticks);

    // Shaded bands, clipped to the plot.
    for shade in &panel.shaded {
        let (Some(a), Some(b)) = (x_scale.to_pixel(shade.x0), x_scale.to_pixel(shade.x1)) else {
            continue;
        };
        let left = a.min(b).max(area.left);
        let right = a.max(b).min(area.right);
        if right > left {
            items.push(Item::Rect {
                x: left,
                y: area.top,
                width: (right - left).max(1.0),
                height: area.height(),
                fill: Some(shade.color),
                stroke: None,
                crisp: false,
            });
        }
    }

    // Marker lines, then their labels with a thin leader down to the plot.
    for marker in &markers {
        let Some(px) = x_scale.to_pixel(marker.x) else {
            continue;
        };
        let px = crisp(px);
        items.push(Item::Polyline {
            points: vec![(px, area.top), (px, area.bottom)],
            stroke: Stroke {
                color: marker.color,
                width: 1.0,
                dash: marker.dashed.then_some((5.0, 4.0)),
            },
        });
    }
    for label in &labels {
        let y = labels_top + (label_rows - 1 - label.row) as f64 * LINE_HEIGHT;
        let leader_x = crisp(label.marker_x);
        items.push(Item::Polyline {
            points: vec![(leader_x, y + GLYPH_SIZE + 2.0), (leader_x, area.top)],
            stroke: Stroke {
                color: label.color.with_alpha(label.color.a / 2),
                width: 1.0,
                dash: Some((1.0, 2.0)),
            },
        });
        items.push(text(
            label.x,
            y,
            label.text.clone(),
            TEXT_SCALE,
            Anchor::Start,
            label.color,
        ));
    }

    // The series themselves.
    for (series, points) in panel.series.iter().zip(&thinned) {
        let pixels: Vec<(f64, f64)> = points
            .iter()
            .filter_map(|&(x, y)| Some((x_scale.to_pixel(x)?, y_scale.to_pixel_clamped(y)?)))
            .collect();
        match pixels.as_slice() {
            [] => {}
            [(x, y)] => items.push(Item::Dot {
                x: *x,
                y: *y,
                radius: 2.5,
                color: series.color,
            }),
            _ => items.push(Item::Polyline {
                points: pixels,
                stroke: Stroke::solid(series.color, 1.25),
            }),
        }
    }

    frame(items, &area);
    tick_labels_x(items, &area, &x_scale, &x_ticks);
    tick_labels_y(items, &area, &y_scale, &y_ticks);
    axis_titles(items, &area, &panel.x_label, &panel.y_label);
    legend(items, &area, legend_y, panel);
}

fn grid(
    items: &mut Vec<Item>,
    area: &PlotArea,
    x_scale: &PixelScale,
    x_ticks: &[Tick],
    y_scale: &PixelScale,
    y_ticks: &[Tick],
) {
    let stroke = Stroke::solid(GRID_COLOR, 1.0);
    for tick in x_ticks {
        if let Some(px) = x_scale.to_pixel(tick.value) {
            let px = crisp(px);
            items.push(Item::Polyline {
                points: vec![(px, area.top), (px, area.bottom)],
                stroke,
            });
        }
    }
    for tick in y_ticks {
        if let Some(py) = y_scale.to_pixel(tick.value) {
            let py = crisp(py);
            items.push(Item::Polyline {
                points: vec![(area.left, py), (area.right, py)],
                stroke,
            });
        }
    }
}

fn frame(items: &mut Vec<Item>, area: &PlotArea) {
    items.push(Item::Rect {
        x: area.left + 0.5,
        y: area.top + 0.5,
        width: area.width() - 1.0,
        height: area.height() - 1.0,
        fill: None,
        stroke: Some(Stroke::solid(FRAME_COLOR, 1.0)),
        crisp: false,
    });
}

const TICK_LENGTH: f64 = 5.0;

fn tick_labels_x(items: &mut Vec<Item>, area: &PlotArea, scale: &PixelScale, ticks: &[Tick]) {
    let mut last_right = f64::NEG_INFINITY;
    for tick in ticks {
        let Some(px) = scale.to_pixel(tick.value) else {
            continue;
        };
        let px = crisp(px);
        items.push(Item::Polyline {
            points: vec![(px, area.bottom), (px, area.bottom + TICK_LENGTH)],
            stroke: Stroke::solid(FRAME_COLOR, 1.0),
        });
        let half = text_width(&tick.label, TEXT_SCALE) / 2.0;
        if px - half > last_right + 8.0 {
            items.push(text(
                px,
                area.bottom + TICK_LENGTH + 4.0,
                tick.label.clone(),
                TEXT_SCALE,
                Anchor::Middle,
                TEXT_COLOR,
            ));
            last_right = px + half;
        }
    }
}

fn tick_labels_y(items: &mut Vec<Item>, area: &PlotArea, scale: &PixelScale, ticks: &[Tick]) {
    for tick in ticks {
        let Some(py) = scale.to_pixel(tick.value) else {
            continue;
        };
        let py = crisp(py);
        items.push(Item::Polyline {
            points: vec![(area.left - TICK_LENGTH, py), (area.left, py)],
            stroke: Stroke::solid(FRAME_COLOR, 1.0),
        });
        items.push(text(
            area.left - TICK_LENGTH - 4.0,
            py - GLYPH_SIZE / 2.0,
            fit_text(&tick.label, TEXT_SCALE, PLOT_LEFT - 36.0),
            TEXT_SCALE,
            Anchor::End,
            TEXT_COLOR,
        ));
    }
}

fn axis_titles(items: &mut Vec<Item>, area: &PlotArea, x_label: &str, y_label: &str) {
    if !x_label.is_empty() {
        items.push(text(
            (area.left + area.right) / 2.0,
            area.bottom + TICK_LENGTH + 4.0 + LINE_HEIGHT + 8.0,
            fit_text(x_label, TEXT_SCALE, area.width()),
            TEXT_SCALE,
            Anchor::Middle,
            TEXT_COLOR,
        ));
    }
    if !y_label.is_empty() {
        items.push(Item::Text(Text {
            x: OUTER_PAD,
            y: (area.top + area.bottom) / 2.0,
            content: fit_text(y_label, TEXT_SCALE, area.height()),
            scale: TEXT_SCALE,
            anchor: Anchor::Middle,
            color: TEXT_COLOR,
            vertical: true,
        }));
    }
}

/// Series legend, right-aligned in a row above the marker labels: a short line sample and the
/// label for each series.
fn legend(items: &mut Vec<Item>, area: &PlotArea, y: f64, panel: &SpectrumPanel) {
    const SAMPLE: f64 = 22.0;
    const SAMPLE_GAP: f64 = 6.0;
    const ENTRY_GAP: f64 = 20.0;
    let entries: Vec<_> = panel
        .series
        .iter()
        .filter(|s| !s.label.is_empty())
        .map(|s| (fit_text(&s.label, TEXT_SCALE, 240.0), s.color))
        .collect();
    let mut right = area.right;
    for (label, color) in entries.iter().rev() {
        let width = text_width(label, TEXT_SCALE);
        let label_left = right - width;
        let sample_right = label_left - SAMPLE_GAP;
        let sample_left = sample_right - SAMPLE;
        if sample_left < area.left {
            break;
        }
        let mid = crisp(y + GLYPH_SIZE / 2.0 - 1.0);
        items.push(Item::Polyline {
            points: vec![(sample_left, mid), (sample_right, mid)],
            stroke: Stroke::solid(*color, 2.5),
        });
        items.push(text(
            label_left,
            y,
            label.clone(),
            TEXT_SCALE,
            Anchor::Start,
            TEXT_COLOR,
        ));
        right = sample_left - ENTRY_GAP;
    }
}

/// The viridis colour map (perceptually uniform, readable in grey and by colour-blind
/// readers), sampled at nine points and interpolated linearly.
pub(crate) fn viridis(t: f64) -> Color {
    const STOPS: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 44, 122),
        (59, 81, 139),
        (44, 113, 142),
        (33, 145, 140),
        (39, 173, 129),
        (92, 200, 99),
        (170, 220, 50),
        (253, 231, 37),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let pos = t * (STOPS.len() - 1) as f64;
    let i = (pos.floor() as usize).min(STOPS.len() - 2);
    let f = pos - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * f).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    Color::rgb(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Cells of a heatmap row as drawn: `(first_cell, last_cell_exclusive, value)` spans, merging
/// neighbours when there are more cells than pixels (the merged value is their maximum, so the
/// strongest band stays visible).
fn row_spans(values: &[f64], pixel_width: f64) -> Vec<(usize, usize, f64)> {
    let n = values.len();
    let max_cells = (pixel_width / MIN_CELL_WIDTH).floor().max(1.0) as usize;
    let per_span = n.div_ceil(max_cells).max(1);
    (0..n)
        .step_by(per_span)
        .map(|start| {
            let end = (start + per_span).min(n);
            let value = values[start..end]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(f64::NAN, f64::max);
            (start, end, value)
        })
        .collect()
}

fn heatmap_panel(panel: &HeatmapPanel, top: f64, items: &mut Vec<Item>) {
    let area = PlotArea {
        left: PLOT_LEFT,
        right: FIGURE_WIDTH - PLOT_RIGHT_PAD - COLOR_BAR_AREA,
        top: top + 4.0 + LINE_HEIGHT + 10.0,
        bottom: (top + PANEL_HEIGHT - 52.0).round(),
    };
    let x_max = if panel.x_max.is_finite() && panel.x_max > 0.0 {
        panel.x_max
    } else {
        1.0
    };
    let x_scale = PixelScale {
        axis: Axis::linear((0.0, x_max)),
        start: area.left,
        end: area.right,
    };

    // Colour scale: from zero (or the minimum, if negative) to the maximum.
    let value_axis = Axis::linear(
        finite_range(panel.rows.iter().flat_map(|r| r.values.iter().copied()))
            .map(|(lo, hi)| (lo.min(0.0), hi))
            .unwrap_or((0.0, 1.0)),
    );
    let color_of = |v: f64| match value_axis.fraction(v) {
        Some(f) => viridis(f),
        None => MISSING_CELL,
    };

    // Panel title, and what the outline marks.
    items.push(text(
        area.left,
        top + 4.0,
        fit_text(&panel.title, TEXT_SCALE, area.width() / 2.0),
        TEXT_SCALE,
        Anchor::Start,
        TEXT_COLOR,
    ));

    let row_count = panel.rows.len();
    let row_height = area.height() / row_count.max(1) as f64;
    let row_edge = |i: usize| (area.top + i as f64 * row_height).round();

    if row_count == 0 {
        items.push(Item::Rect {
            x: area.left,
            y: area.top,
            width: area.width(),
            height: area.height(),
            fill: Some(MISSING_CELL),
            stroke: None,
            crisp: true,
        });
        items.push(text(
            (area.left + area.right) / 2.0,
            (area.top + area.bottom) / 2.0 - GLYPH_SIZE / 2.0,
            String::from("no data"),
            TEXT_SCALE,
            Anchor::Middle,
            TEXT_COLOR,
        ));
    }

    // Cells, snapped to whole pixels so neighbours meet without seams.
    for (r, row) in panel.rows.iter().enumerate() {
        let (y0, y1) = (row_edge(r), row_edge(r + 1));
        let n = row.values.len();
        if n == 0 {
            items.push(Item::Rect {
                x: area.left,
                y: y0,
                width: area.width(),
                height: y1 - y0,
                fill: Some(MISSING_CELL),
                stroke: None,
                crisp: true,
            });
            continue;
        }
        let cell_edge = |i: usize| (area.left + i as f64 * area.width() / n as f64).round();
        for (start, end, value) in row_spans(&row.values, area.width()) {
            let (x0, x1) = (cell_edge(start), cell_edge(end));
            if x1 > x0 && y1 > y0 {
                items.push(Item::Rect {
                    x: x0,
                    y: y0,
                    width: x1 - x0,
                    height: y1 - y0,
                    fill: Some(color_of(value)),
                    stroke: None,
                    crisp: true,
                });
            }
        }
    }

    // Row labels, thinned when rows are too short to hold one each.
    let label_every = (LINE_HEIGHT / row_height).ceil().max(1.0) as usize;
    for (r, row) in panel.rows.iter().enumerate().step_by(label_every) {
        let centre = (row_edge(r) + row_edge(r + 1)) / 2.0;
        items.push(text(
            area.left - 6.0,
            centre - GLYPH_SIZE / 2.0,
            fit_text(&row.label, TEXT_SCALE, PLOT_LEFT - 24.0),
            TEXT_SCALE,
            Anchor::End,
            TEXT_COLOR,
        ));
    }

    // The chosen band: a dark outline with a light inner edge, visible on any colour.
    if let Some((r, c)) = panel.highlight {
        if let Some(row) = panel.rows.get(r).filter(|row| c < row.values.len()) {
            let n = row.values.len();
            let x0 = (area.left + c as f64 * area.width() / n as f64).round();
            let x1 = (area.left + (c + 1) as f64 * area.width() / n as f64).round();
            let (y0, y1) = (row_edge(r), row_edge(r + 1));
            let width = (x1 - x0).max(2.0);
            let height = (y1 - y0).max(2.0);
            items.push(Item::Rect {
                x: x0 - 1.5,
                y: y0 - 1.5,
                width: width + 3.0,
                height: height + 3.0,
                fill: None,
                stroke: Some(Stroke::solid(Color::BLACK, 3.0)),
                crisp: false,
            });
            items.push(Item::Rect {
                x: x0 + 0.5,
                y: y0 + 0.5,
                width: width - 1.0,
                height: height - 1.0,
                fill: None,
                stroke: Some(Stroke::solid(Color::WHITE, 1.0)),
                crisp: false,
            });
            let band = x_max / n as f64;
            let from = band * c as f64;
            let to = band * (c + 1) as f64;
            let value = row.values[c];
            let unit = unit_in(&panel.x_label).map_or(String::new(), |u| format!(" {u}"));
            let caption = format!(
                "outlined: row {}, {}-{}{unit}, {} = {}",
                row.label,
                format_number(from, band / 10.0),
                format_number(to, band / 10.0),
                panel.value_label,
                format_number(value, value.abs() / 100.0),
            );
            items.push(text(
                area.right,
                top + 4.0,
                fit_text(&caption, TEXT_SCALE, area.width() / 2.0 - 8.0),
                TEXT_SCALE,
                Anchor::End,
                TEXT_COLOR,
            ));
        }
    }

    frame(items, &area);
    let x_ticks = x_scale.axis.ticks(((area.width() / 90.0) as usize).max(2));
    tick_labels_x(items, &area, &x_scale, &x_ticks);
    axis_titles(items, &area, &panel.x_label, "");
    color_bar(items, &area, value_axis, &panel.value_label);
}

/// A vertical colour bar right of the heatmap, with ticks and its label.
fn color_bar(items: &mut Vec<Item>, area: &PlotArea, values: Axis, label: &str) {
    let bar = PlotArea {
        left: area.right + 24.0,
        right: area.right + 24.0 + COLOR_BAR_WIDTH,
        top: area.top,
        bottom: area.bottom,
    };
    let step_edge =
        |i: usize| (bar.bottom - i as f64 * bar.height() / COLOR_BAR_STEPS as f64).round();
    for i in 0..COLOR_BAR_STEPS {
        let (y_bottom, y_top) = (step_edge(i), step_edge(i + 1));
        if y_bottom > y_top {
            items.push(Item::Rect {
                x: bar.left,
                y: y_top,
                width: bar.width(),
                height: y_bottom - y_top,
                fill: Some(viridis((i as f64 + 0.5) / COLOR_BAR_STEPS as f64)),
                stroke: None,
                crisp: true,
            });
        }
    }
    frame(items, &bar);
    let scale = PixelScale {
        axis: values,
        start: bar.bottom,
        end: bar.top,
    };
    let mut widest: f64 = 0.0;
    for tick in values.ticks(6) {
        let Some(py) = scale.to_pixel(tick.value) else {
            continue;
        };
        let py = crisp(py);
        items.push(Item::Polyline {
            points: vec![(bar.right, py), (bar.right + TICK_LENGTH, py)],
            stroke: Stroke::solid(FRAME_COLOR, 1.0),
        });
        widest = widest.max(text_width(&tick.label, TEXT_SCALE));
        items.push(text(
            bar.right + TICK_LENGTH + 4.0,
            py - GLYPH_SIZE / 2.0,
            tick.label,
            TEXT_SCALE,
            Anchor::Start,
            TEXT_COLOR,
        ));
    }
    if !label.is_empty() {
        items.push(Item::Text(Text {
            x: (bar.right + TICK_LENGTH + 4.0 + widest + 8.0).min(FIGURE_WIDTH - GLYPH_SIZE - 4.0),
            y: (bar.top + bar.bottom) / 2.0,
            content: fit_text(label, TEXT_SCALE, bar.height()),
            scale: TEXT_SCALE,
            anchor: Anchor::Middle,
            color: TEXT_COLOR,
            vertical: true,
        }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_that_collide_go_to_new_rows() {
        let (placed, rows) = stagger_labels(vec![
            (100.0, "BPFO".into(), Color::BLUE),
            (300.0, "2×BPFO".into(), Color::BLUE),
            (110.0, "BPFI".into(), Color::BLUE),
        ]);
        assert_eq!(rows, 2);
        let rows_by_label: Vec<_> = placed.iter().map(|p| (p.text.as_str(), p.row)).collect();
        assert_eq!(rows_by_label, [("BPFO", 0), ("2×BPFO", 0), ("BPFI", 1)]);
    }

    #[test]
    fn labels_beyond_the_rows_are_left_out() {
        let crowd = (0..20).map(|i| (500.0 + f64::from(i), format!("L{i}"), Color::BLUE));
        let (placed, rows) = stagger_labels(crowd.collect());
        assert_eq!(rows, MAX_MARKER_ROWS);
        assert_eq!(placed.len(), MAX_MARKER_ROWS);
        assert_eq!(placed[0].text, "L0");
    }

    #[test]
    fn many_cells_merge_keeping_the_maximum() {
        let mut values = vec![0.0; 10_000];
        values[7_777] = 5.0;
        let spans = row_spans(&values, 1000.0);
        assert!(spans.len() <= 1000);
        assert!(spans
            .iter()
            .any(|&(a, b, v)| (a..b).contains(&7_777) && v == 5.0));
    }

    #[test]
    fn units_come_from_axis_labels() {
        assert_eq!(unit_in("frequency (Hz)"), Some("Hz"));
        assert_eq!(unit_in("frequency"), None);
        assert_eq!(unit_in("x ()"), None);
        assert_eq!(unit_in(")"), None);
    }

    #[test]
    fn text_is_shortened_to_fit() {
        assert_eq!(fit_text("abcdefgh", 1, 48.0), "abc...");
        assert_eq!(fit_text("abc", 1, 48.0), "abc");
        assert_eq!(fit_text("abc", 1, 0.0), "");
    }

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), Color::rgb(68, 1, 84));
        assert_eq!(viridis(1.0), Color::rgb(253, 231, 37));
        assert_eq!(viridis(f64::NAN), Color::rgb(68, 1, 84));
    }
}
