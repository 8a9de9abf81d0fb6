//! A heatmap panel (rows of band values, e.g. the kurtogram): cells merged when there are
//! more than pixels, the chosen cell outlined with its caption, and the colour bar.

use super::axes::{axis_titles, frame, tick_labels_x, TICK_LENGTH, Y_TICK_LABEL_WIDTH};
use super::{crisp, fitted, text, text_width, Anchor, Item, PlotArea, Stroke, Text};
use super::{
    BELOW_PLOT, FIGURE_WIDTH, LINE_HEIGHT, PANEL_HEIGHT, PLOT_LEFT, PLOT_RIGHT_PAD, TEXT_HEIGHT,
};
use super::{FRAME_COLOR, GLYPH_SIZE, OUTER_PAD, TEXT_COLOR, TEXT_SCALE};
use crate::plot::figure::{Color, HeatmapPanel};
use crate::plot::layout::{finite_range, format_number, Axis, PixelScale};

/// Heatmap cells narrower than this many pixels are merged (showing the column maximum).
const MIN_CELL_WIDTH: f64 = 1.0;
/// Space right of a heatmap for the colour bar, its ticks and its label.
const COLOR_BAR_AREA: f64 = 170.0;
const COLOR_BAR_WIDTH: f64 = 18.0;
const COLOR_BAR_STEPS: usize = 96;
const MISSING_CELL: Color = Color::rgb(200, 200, 200);

/// The unit in an axis label written as "name (unit)", e.g. "Hz" in "frequency (Hz)".
fn unit_in(label: &str) -> Option<&str> {
    let inner = label.trim_end().strip_suffix(')')?;
    let unit = &inner[inner.rfind('(')? + 1..];
    (!unit.trim().is_empty()).then(|| unit.trim())
}

/// The viridis colour map (perceptually uniform, readable in grey and by colour-blind
/// readers), sampled at nine points and interpolated linearly.
fn viridis(t: f64) -> Color {
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

pub(super) fn heatmap_panel(panel: &HeatmapPanel, top: f64, items: &mut Vec<Item>) {
    let area = PlotArea {
        left: PLOT_LEFT,
        right: FIGURE_WIDTH - PLOT_RIGHT_PAD - COLOR_BAR_AREA,
        // Two rows above the plot: the panel's title, then what the outline marks.
        top: top + 4.0 + 2.0 * LINE_HEIGHT + 10.0,
        bottom: (top + PANEL_HEIGHT - BELOW_PLOT).round(),
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

    // Panel title, across the plot and the colour bar.
    let header_width = FIGURE_WIDTH - OUTER_PAD - area.left;
    let (title, scale) = fitted(&panel.title, TEXT_SCALE, header_width);
    items.push(text(
        area.left,
        top + 4.0,
        title,
        scale,
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
            (area.top + area.bottom) / 2.0 - TEXT_HEIGHT / 2.0,
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
        let (label, scale) = fitted(&row.label, TEXT_SCALE, Y_TICK_LABEL_WIDTH);
        items.push(text(
            area.left - 6.0,
            centre - GLYPH_SIZE * f64::from(scale) / 2.0,
            label,
            scale,
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
            let (caption, scale) = fitted(&caption, TEXT_SCALE, header_width);
            items.push(text(
                area.left,
                top + 4.0 + LINE_HEIGHT,
                caption,
                scale,
                Anchor::Start,
                TEXT_COLOR,
            ));
        }
    }

    frame(items, &area);
    let x_ticks = x_scale.axis.ticks(((area.width() / 90.0) as usize).max(2));
    tick_labels_x(items, &area, &x_scale, &x_ticks);
    axis_titles(items, &area, &panel.x_label, &panel.y_label);
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
            py - TEXT_HEIGHT / 2.0,
            tick.label,
            TEXT_SCALE,
            Anchor::Start,
            TEXT_COLOR,
        ));
    }
    if !label.is_empty() {
        let (content, scale) = fitted(label, TEXT_SCALE, bar.height());
        items.push(Item::Text(Text {
            x: (bar.right + TICK_LENGTH + 4.0 + widest + 8.0).min(FIGURE_WIDTH - TEXT_HEIGHT - 4.0),
            y: (bar.top + bar.bottom) / 2.0,
            content,
            scale,
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
    fn viridis_ends() {
        assert_eq!(viridis(0.0), Color::rgb(68, 1, 84));
        assert_eq!(viridis(1.0), Color::rgb(253, 231, 37));
        assert_eq!(viridis(f64::NAN), Color::rgb(68, 1, 84));
    }
}
