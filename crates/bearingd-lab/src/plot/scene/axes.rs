//! What every panel draws around its data: the grid, the frame, tick marks with their labels,
//! and the axis titles.

use super::{crisp, fitted, text, text_width, wrap_text, Anchor, Item, PlotArea, Stroke, Text};
use super::{FRAME_COLOR, GRID_COLOR, LINE_HEIGHT, OUTER_PAD, PLOT_LEFT, TEXT_COLOR, TEXT_HEIGHT};
use super::{GLYPH_SIZE, TEXT_SCALE};
use crate::plot::layout::{PixelScale, Tick};

pub(super) fn grid(
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

pub(super) fn frame(items: &mut Vec<Item>, area: &PlotArea) {
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

pub(super) const TICK_LENGTH: f64 = 5.0;

/// Room for a y tick label: the plot's left margin less the two-line y title and gaps.
pub(super) const Y_TICK_LABEL_WIDTH: f64 = PLOT_LEFT - 2.0 * OUTER_PAD - 2.0 * TEXT_HEIGHT - 20.0;

pub(super) fn tick_labels_x(
    items: &mut Vec<Item>,
    area: &PlotArea,
    scale: &PixelScale,
    ticks: &[Tick],
) {
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

pub(super) fn tick_labels_y(
    items: &mut Vec<Item>,
    area: &PlotArea,
    scale: &PixelScale,
    ticks: &[Tick],
) {
    for tick in ticks {
        let Some(py) = scale.to_pixel(tick.value) else {
            continue;
        };
        let py = crisp(py);
        items.push(Item::Polyline {
            points: vec![(area.left - TICK_LENGTH, py), (area.left, py)],
            stroke: Stroke::solid(FRAME_COLOR, 1.0),
        });
        let (label, scale) = fitted(&tick.label, TEXT_SCALE, Y_TICK_LABEL_WIDTH);
        items.push(text(
            area.left - TICK_LENGTH - 4.0,
            py - GLYPH_SIZE * f64::from(scale) / 2.0,
            label,
            scale,
            Anchor::End,
            TEXT_COLOR,
        ));
    }
}

pub(super) fn axis_titles(items: &mut Vec<Item>, area: &PlotArea, x_label: &str, y_label: &str) {
    if !x_label.is_empty() {
        let (label, scale) = fitted(x_label, TEXT_SCALE, area.width());
        items.push(text(
            (area.left + area.right) / 2.0,
            area.bottom + TICK_LENGTH + 4.0 + LINE_HEIGHT + 8.0,
            label,
            scale,
            Anchor::Middle,
            TEXT_COLOR,
        ));
    }
    // The y title reads bottom to top, on at most two lines beside each other, or four in
    // the smaller font when two lines of the body font cannot hold it.
    let (scale, max_lines) = if wrap_text(y_label, TEXT_SCALE, area.height()).len() <= 2 {
        (TEXT_SCALE, 2)
    } else {
        (1, 4)
    };
    let lines = wrap_text(y_label, scale, area.height());
    let shown = lines.len().min(max_lines);
    for (i, line) in lines.iter().take(shown).enumerate() {
        let (line, scale) = if i + 1 == shown && lines.len() > shown {
            fitted(&lines[i..].join(" "), scale, area.height())
        } else {
            (line.clone(), scale)
        };
        if line.is_empty() {
            continue;
        }
        items.push(Item::Text(Text {
            x: OUTER_PAD + i as f64 * (GLYPH_SIZE * f64::from(scale) + 4.0),
            y: (area.top + area.bottom) / 2.0,
            content: line,
            scale,
            anchor: Anchor::Middle,
            color: TEXT_COLOR,
            vertical: true,
        }));
    }
}
