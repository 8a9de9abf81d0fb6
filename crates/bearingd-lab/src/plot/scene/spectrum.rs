//! A spectrum panel: series thinned to the pixel columns, shaded bands, marker lines with
//! labels staggered over a few rows so that neighbours stay readable, and the legend.

use super::axes::{axis_titles, frame, grid, tick_labels_x, tick_labels_y};
use super::legend;
use super::TEXT_SCALE;
use super::{crisp, fitted, text, text_width, Anchor, Item, PlotArea, Stroke};
use super::{
    BELOW_PLOT, FIGURE_WIDTH, LINE_HEIGHT, PANEL_HEIGHT, PLOT_LEFT, PLOT_RIGHT_PAD, TEXT_HEIGHT,
};
use crate::plot::figure::{Color, SpectrumPanel};
use crate::plot::layout::{decimate_min_max, finite_range, Axis, PixelScale};

/// Marker labels are staggered over at most this many rows above the plot.
const MAX_MARKER_ROWS: usize = 4;

/// A marker label placed in one of the staggered rows above the plot.
struct PlacedLabel {
    x: f64,
    text: String,
    scale: u32,
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
        let (text, scale) = fitted(&label, TEXT_SCALE, 320.0);
        let width = text_width(&text, scale);
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
                scale,
                row,
                color,
                marker_x,
            });
        }
    }
    let rows_used = rows.iter().filter(|r| !r.is_empty()).count();
    (placed, rows_used)
}

/// Can `label`'s leader run down to the plot without crossing a label in a row below it? If
/// not it is left out: the label's colour and place still tie it to its marker line, and no
/// line is drawn through another label's text.
fn leader_is_clear(label: &PlacedLabel, all: &[PlacedLabel]) -> bool {
    all.iter()
        .filter(|other| other.row < label.row)
        .all(|other| {
            let right = other.x + text_width(&other.text, other.scale);
            label.marker_x < other.x - 1.0 || label.marker_x > right + 1.0
        })
}

pub(super) fn spectrum_panel(panel: &SpectrumPanel, top: f64, items: &mut Vec<Item>) {
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
    let levels = panel.levels.iter().map(|l| l.y).filter(|y| y.is_finite());
    let visible_y = thinned.iter().flatten().map(|&(_, y)| y).chain(levels);
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

    // Vertical budget: legend rows, marker label rows, plot, tick labels, x label.
    let legend_y = top + 4.0;
    let (legend, legend_rows) = legend::layout(panel, plot_left, plot_right);
    let labels_top = legend_y + legend_rows as f64 * LINE_HEIGHT + 6.0;
    let area = PlotArea {
        left: plot_left,
        right: plot_right,
        top: (labels_top + label_rows as f64 * LINE_HEIGHT + 6.0).round(),
        bottom: (top + PANEL_HEIGHT - BELOW_PLOT).round(),
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
        if leader_is_clear(label, &labels) {
            items.push(Item::Polyline {
                points: vec![(leader_x, y + TEXT_HEIGHT + 2.0), (leader_x, area.top)],
                stroke: Stroke {
                    color: label.color.with_alpha(label.color.a / 2),
                    width: 1.0,
                    dash: Some((1.0, 2.0)),
                },
            });
        }
        items.push(text(
            label.x,
            y,
            label.text.clone(),
            label.scale,
            Anchor::Start,
            label.color,
        ));
    }

    // The series themselves, a line per run between breaks (NaN values).
    for (series, points) in panel.series.iter().zip(&thinned) {
        for run in points.split(|p| p.1.is_nan()) {
            let pixels: Vec<(f64, f64)> = run
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
    }

    reference_lines(items, &area, &y_scale, panel);
    frame(items, &area);
    tick_labels_x(items, &area, &x_scale, &x_ticks);
    tick_labels_y(items, &area, &y_scale, &y_ticks);
    axis_titles(items, &area, &panel.x_label, &panel.y_label);
    legend::draw(items, &legend, legend_y);
}

/// The panel's horizontal reference lines, each labelled above its line at the right end of
/// the plot (below it when there is no room above). A label that would overlap one placed
/// before it is left out; its line is still drawn.
fn reference_lines(
    items: &mut Vec<Item>,
    area: &PlotArea,
    y_scale: &PixelScale,
    panel: &SpectrumPanel,
) {
    let height = TEXT_HEIGHT;
    let mut taken: Vec<(f64, f64)> = Vec::new();
    for level in &panel.levels {
        let Some(py) = y_scale.to_pixel(level.y) else {
            continue;
        };
        if !(area.top..=area.bottom).contains(&py) {
            continue;
        }
        let py = crisp(py);
        items.push(Item::Polyline {
            points: vec![(area.left, py), (area.right, py)],
            stroke: Stroke {
                color: level.color,
                width: 1.5,
                dash: level.dashed.then_some((8.0, 4.0)),
            },
        });
        let above = py - height - 3.0;
        let y = if above >= area.top + 2.0 {
            above
        } else {
            py + 3.0
        };
        if y + height > area.bottom
            || taken
                .iter()
                .any(|&(a, b)| y < b + 2.0 && a < y + height + 2.0)
        {
            continue;
        }
        taken.push((y, y + height));
        let (label, scale) = fitted(&level.label, TEXT_SCALE, area.width() / 2.0);
        items.push(text(
            area.right - 6.0,
            y,
            label,
            scale,
            Anchor::End,
            level.color,
        ));
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
    fn no_leader_is_drawn_through_a_label_below_it() {
        // "degrading" at 300 takes row 0; "failing" at 306 goes to row 1, and its leader
        // would cross "degrading": it is left out. "healthy", far away, keeps its leader.
        let (placed, rows) = stagger_labels(vec![
            (100.0, "healthy".into(), Color::BLUE),
            (300.0, "degrading".into(), Color::BLUE),
            (306.0, "failing".into(), Color::BLUE),
        ]);
        assert_eq!(rows, 2);
        let clear: Vec<_> = placed
            .iter()
            .map(|p| (p.text.as_str(), p.row, leader_is_clear(p, &placed)))
            .collect();
        assert_eq!(
            clear,
            [
                ("healthy", 0, true),
                ("degrading", 0, true),
                ("failing", 1, false)
            ]
        );
    }

    #[test]
    fn labels_beyond_the_rows_are_left_out() {
        let crowd = (0..20).map(|i| (500.0 + f64::from(i), format!("L{i}"), Color::BLUE));
        let (placed, rows) = stagger_labels(crowd.collect());
        assert_eq!(rows, MAX_MARKER_ROWS);
        assert_eq!(placed.len(), MAX_MARKER_ROWS);
        assert_eq!(placed[0].text, "L0");
    }
}
