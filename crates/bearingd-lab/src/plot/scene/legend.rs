//! A spectrum panel's legend: one entry per series, then what the marker colours, line styles
//! and shading mean, laid out left to right in rows above the marker labels (never over the
//! data), a new row starting when an entry would pass the plot's right edge.

use super::{crisp, fitted, text, text_width, Anchor, Item, Stroke};
use super::{LINE_HEIGHT, TEXT_COLOR, TEXT_HEIGHT, TEXT_SCALE};
use crate::plot::figure::{Color, LegendEntry, LegendSample, SpectrumPanel};

const SAMPLE: f64 = 28.0;
const SAMPLE_GAP: f64 = 6.0;
const ENTRY_GAP: f64 = 24.0;

/// A legend entry placed: its sample's left edge, its row, the text and its scale.
pub(super) struct PlacedEntry {
    left: f64,
    row: usize,
    text: String,
    scale: u32,
    color: Color,
    sample: LegendSample,
}

/// The legend of `panel` laid out between `left` and `right`; returns the entries and the
/// number of rows they take (0 for an empty legend).
pub(super) fn layout(panel: &SpectrumPanel, left: f64, right: f64) -> (Vec<PlacedEntry>, usize) {
    let series = panel.series.iter().map(|s| LegendEntry {
        label: s.label.clone(),
        color: s.color,
        sample: LegendSample::Line,
    });
    let entries = series
        .chain(panel.legend.iter().cloned())
        .filter(|e| !e.label.is_empty());
    let mut placed: Vec<PlacedEntry> = Vec::new();
    let (mut x, mut row) = (left, 0);
    for entry in entries {
        let (text, scale) = fitted(&entry.label, TEXT_SCALE, right - left - SAMPLE - SAMPLE_GAP);
        let width = SAMPLE + SAMPLE_GAP + text_width(&text, scale);
        if x > left && x + width > right {
            row += 1;
            x = left;
        }
        placed.push(PlacedEntry {
            left: x,
            row,
            text,
            scale,
            color: entry.color,
            sample: entry.sample,
        });
        x += width + ENTRY_GAP;
    }
    let rows = if placed.is_empty() { 0 } else { row + 1 };
    (placed, rows)
}

/// Draws the entries laid out by [`layout`], the first row's top at `top`.
pub(super) fn draw(items: &mut Vec<Item>, entries: &[PlacedEntry], top: f64) {
    for entry in entries {
        let y = top + entry.row as f64 * LINE_HEIGHT;
        let (x0, x1) = (entry.left, entry.left + SAMPLE);
        let mid = crisp(y + TEXT_HEIGHT / 2.0 - 1.0);
        items.push(match entry.sample {
            LegendSample::Line | LegendSample::DashedLine => Item::Polyline {
                points: vec![(x0, mid), (x1, mid)],
                stroke: Stroke {
                    color: entry.color,
                    width: 2.5,
                    dash: (entry.sample == LegendSample::DashedLine).then_some((5.0, 4.0)),
                },
            },
            LegendSample::Band => Item::Rect {
                x: x0,
                y: y + 1.0,
                width: SAMPLE,
                height: TEXT_HEIGHT - 2.0,
                fill: Some(entry.color),
                stroke: None,
                crisp: false,
            },
        });
        let text_top = y + (TEXT_HEIGHT - super::GLYPH_SIZE * f64::from(entry.scale)) / 2.0;
        items.push(text(
            x1 + SAMPLE_GAP,
            text_top,
            entry.text.clone(),
            entry.scale,
            Anchor::Start,
            TEXT_COLOR,
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::figure::Series;

    #[test]
    fn entries_flow_into_new_rows_at_the_right_edge() {
        let mut panel = SpectrumPanel::new("x", "y", vec![0.0, 1.0]);
        panel.series.push(Series {
            label: "measured".into(),
            y: vec![0.0, 1.0],
            color: Color::BLACK,
        });
        for label in ["BPFO outer race", "BPFI inner race", ""] {
            panel.legend.push(LegendEntry {
                label: label.into(),
                color: Color::BLUE,
                sample: LegendSample::Band,
            });
        }
        // "measured" takes 28 + 6 + 128 = 162 px, the next entries 274 px each.
        let (placed, rows) = layout(&panel, 0.0, 500.0);
        let rows_of: Vec<_> = placed.iter().map(|e| (e.text.as_str(), e.row)).collect();
        assert_eq!(
            rows_of,
            [
                ("measured", 0),
                ("BPFO outer race", 0),
                ("BPFI inner race", 1)
            ]
        );
        assert_eq!(rows, 2);
        assert_eq!(placed[1].left, 162.0 + ENTRY_GAP);
        assert_eq!(placed[2].left, 0.0);
        assert_eq!(
            layout(&SpectrumPanel::new("x", "y", vec![]), 0.0, 500.0).1,
            0
        );
    }
}
