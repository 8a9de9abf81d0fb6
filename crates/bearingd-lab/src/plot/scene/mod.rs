//! Turns a [`Figure`] into a [`Scene`]: a flat list of drawing primitives in pixel
//! coordinates. Every placement decision (margins, ticks, legends, label staggering, colour
//! mapping, decimation) is made here once; the SVG and PNG renderers only translate primitives.
//!
//! The files: this one holds the primitives, the shared sizes and the figure's header;
//! `spectrum` and `heatmap` lay out one panel each, on the frame, grid, ticks and axis
//! titles of `axes`.

mod axes;
mod heatmap;
mod legend;
mod spectrum;

use super::figure::{Color, Figure, Panel};
use super::PlotError;
use heatmap::heatmap_panel;
use spectrum::spectrum_panel;

/// Width of one glyph cell at text scale 1, in pixels (the 8×8 bitmap font; the SVG uses a
/// monospace font sized to the same advance).
pub(crate) const GLYPH_SIZE: f64 = 8.0;

/// Figure width in pixels.
const FIGURE_WIDTH: f64 = 1600.0;
/// Height of one panel in pixels.
const PANEL_HEIGHT: f64 = 480.0;
/// More panels than this would make an unreasonably tall image.
pub(crate) const MAX_PANELS: usize = 16;
/// Notes beyond this many lines are summarised as "... n more lines" (an analysis figure has
/// three or four notes of at most three lines each).
const MAX_NOTE_LINES: usize = 12;

const OUTER_PAD: f64 = 16.0;
const PLOT_LEFT: f64 = 176.0;
const PLOT_RIGHT_PAD: f64 = 40.0;
const LINE_HEIGHT: f64 = 22.0;
const TITLE_SCALE: u32 = 3;
const TEXT_SCALE: u32 = 2;
/// Height (and glyph advance) of body text in pixels.
const TEXT_HEIGHT: f64 = GLYPH_SIZE * TEXT_SCALE as f64;

const TEXT_COLOR: Color = Color::rgb(30, 30, 30);
/// Space below a panel's plot for the tick labels and the x axis title.
const BELOW_PLOT: f64 = 72.0;

const MUTED_TEXT: Color = Color::rgb(80, 80, 80);
const FRAME_COLOR: Color = Color::rgb(60, 60, 60);
const GRID_COLOR: Color = Color::rgb(228, 228, 228);

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

impl Scene {
    /// The box each non-empty text covers, as the PNG renderer draws it.
    pub(crate) fn text_boxes(&self) -> Vec<super::TextBox> {
        self.items
            .iter()
            .filter_map(|item| match item {
                Item::Text(t) if !t.content.is_empty() => Some(t),
                _ => None,
            })
            .map(|t| {
                let length = text_width(&t.content, t.scale);
                let thickness = GLYPH_SIZE * f64::from(t.scale);
                let before = length * t.anchor.offset_fraction();
                let (left, top, right, bottom) = if t.vertical {
                    (t.x, t.y + before - length, t.x + thickness, t.y + before)
                } else {
                    (t.x - before, t.y, t.x - before + length, t.y + thickness)
                };
                super::TextBox {
                    content: t.content.clone(),
                    left,
                    top,
                    right,
                    bottom,
                }
            })
            .collect()
    }
}

/// Width in pixels of `text` at `scale`.
pub(crate) fn text_width(text: &str, scale: u32) -> f64 {
    text.chars().count() as f64 * GLYPH_SIZE * f64::from(scale)
}

/// Characters of the 8×8 font that fit `max_width` pixels at `scale`.
fn capacity(scale: u32, max_width: f64) -> usize {
    (max_width / (GLYPH_SIZE * f64::from(scale)))
        .floor()
        .max(0.0) as usize
}

/// `text` and the scale to set it at so that it fits `max_width` pixels: `scale` if it fits,
/// else half of it (down to the 8 px font) rather than cutting it. Only a text too long even
/// at 8 px is cut, ending in "...": a last resort for labels no figure of ours makes (our
/// longest labels fit at the full scale; the half scale doubles the room).
fn fitted(text: &str, scale: u32, max_width: f64) -> (String, u32) {
    let length = text.chars().count();
    let mut scale = scale.max(1);
    while length > capacity(scale, max_width) && scale > 1 {
        scale = (scale / 2).max(1);
    }
    let room = capacity(scale, max_width);
    if length <= room {
        return (text.to_string(), scale);
    }
    let cut = if room <= 3 {
        text.chars().take(room).collect()
    } else {
        let mut short: String = text.chars().take(room - 3).collect();
        short.push_str("...");
        short
    };
    (cut, scale)
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

/// `text` broken at spaces into lines of at most `max_width` pixels at `scale`; a word longer
/// than a line is cut into pieces. Nothing is dropped.
pub(super) fn wrap_text(text: &str, scale: u32, max_width: f64) -> Vec<String> {
    let capacity = ((max_width / (GLYPH_SIZE * f64::from(scale))).floor() as usize).max(1);
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ').filter(|w| !w.is_empty()) {
        let chars: Vec<char> = word.chars().collect();
        for piece in chars.chunks(capacity) {
            let needed = line.chars().count() + usize::from(!line.is_empty()) + piece.len();
            let piece: String = piece.iter().collect();
            if !line.is_empty() && needed > capacity {
                lines.push(std::mem::take(&mut line));
            }
            if !line.is_empty() {
                line.push(' ');
            }
            line.push_str(&piece);
        }
    }
    if !line.is_empty() || lines.is_empty() {
        lines.push(line);
    }
    lines
}

/// Title and notes, wrapped to the figure's width; returns the y where panels start.
fn header(figure: &Figure, items: &mut Vec<Item>) -> f64 {
    let max_width = FIGURE_WIDTH - 2.0 * OUTER_PAD;
    let mut y = OUTER_PAD;
    for line in wrap_text(&figure.title, TITLE_SCALE, max_width) {
        items.push(text(
            OUTER_PAD,
            y,
            line,
            TITLE_SCALE,
            Anchor::Start,
            TEXT_COLOR,
        ));
        y += GLYPH_SIZE * f64::from(TITLE_SCALE) + 6.0;
    }
    y += 6.0;
    let mut lines: Vec<String> = figure
        .notes
        .iter()
        .flat_map(|note| wrap_text(note, TEXT_SCALE, max_width))
        .collect();
    if lines.len() > MAX_NOTE_LINES {
        let more = lines.len() - (MAX_NOTE_LINES - 1);
        lines.truncate(MAX_NOTE_LINES - 1);
        lines.push(format!("... {more} more lines"));
    }
    for line in lines {
        items.push(text(
            OUTER_PAD,
            y,
            line,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_shrunk_to_fit_and_cut_only_past_the_smallest_font() {
        let s = |text: &str, scale: u32| (String::from(text), scale);
        assert_eq!(fitted("abc", 2, 48.0), s("abc", 2));
        assert_eq!(fitted("abcdef", 2, 48.0), s("abcdef", 1));
        assert_eq!(fitted("abcdefgh", 2, 48.0), s("abc...", 1));
        assert_eq!(fitted("abc", 2, 0.0), s("", 1));
    }

    #[test]
    fn text_is_wrapped_at_spaces_without_loss() {
        assert_eq!(wrap_text("ab cd ef", 1, 40.0), ["ab cd", "ef"]);
        assert_eq!(wrap_text("abcdefgh", 1, 24.0), ["abc", "def", "gh"]);
        assert_eq!(wrap_text("", 1, 24.0), [""]);
    }
}
