//! What `bearingd trend` tells its user about a bearing's life: one [`LifeReport`] feeds the JSON
//! document, the text summary and the figure (stage timeline with RMS, kurtosis, HW residual and
//! fault score, and the RMS trend with its band), so they always agree.

use crate::life::{HwFrom, LifePoint, StageEvent, TrendHindsight};
use crate::messages::HealthStage;
use crate::plot::{Color, Figure, LegendEntry, LegendSample, Marker, Series, Shade, SpectrumPanel};
use serde::Serialize;
use std::fmt::Write as _;

/// The settings the life was tracked with, as reported.
#[derive(Debug, Clone, Serialize)]
pub struct LifeSettingsReport {
    pub baseline_snapshots: u64,
    pub sigma: f64,
    pub confirm_snapshots: u32,
    pub smoothing: usize,
    pub trend_window: usize,
    pub confidence: f64,
    pub threshold_rms: Option<f64>,
}

/// A file that was not used, and why (the message names the file and the fix).
#[derive(Debug, Clone, Serialize)]
pub struct SkippedFile {
    pub file: String,
    pub error: String,
}

/// A stretch of time without samples between two snapshots of logs (between runs, or
/// samples lost): the plot's lines break there.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LifeGap {
    /// The snapshot before the gap and the one after it.
    pub after: String,
    pub before: String,
    /// Life time (s) of the last sample before the gap and of the first after it.
    pub from_s: f64,
    pub to_s: f64,
}

/// A bearing's life as `trend` saw it.
#[derive(Debug, Clone, Serialize)]
pub struct LifeReport {
    pub path: String,
    pub channel: String,
    pub settings: LifeSettingsReport,
    /// Stage changes in order.
    pub events: Vec<StageEvent>,
    pub points: Vec<LifePoint>,
    /// Stretches without samples, in time order (logs only).
    pub gaps: Vec<LifeGap>,
    /// The RMS trend's estimates judged against the crossing they predicted.
    pub hindsight: Option<TrendHindsight>,
    /// Files that looked like snapshots but could not be used.
    pub skipped: Vec<SkippedFile>,
    /// Files in the directory that are not snapshots (e.g. a manifest).
    pub ignored: Vec<String>,
    /// Assumptions and limits the user should know (e.g. no speed: no fault score).
    pub notes: Vec<String>,
}

impl LifeReport {
    /// Seconds from the first to the last snapshot.
    pub fn span_s(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.time_s)
    }

    /// Fraction of the observed life at time `t` (0 at the first snapshot, 1 at the last).
    pub fn life_fraction(&self, t: f64) -> f64 {
        let span = self.span_s();
        if span > 0.0 {
            t / span
        } else {
            0.0
        }
    }
}

/// `1.53 h`, `12.0 min` or `40 s`: a duration in the unit that reads best.
pub fn duration_text(s: f64) -> String {
    let a = s.abs();
    if a >= 2.0 * 3600.0 {
        format!("{:.2} h", s / 3600.0)
    } else if a >= 120.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{s:.0} s")
    }
}

/// The text summary.
pub fn render_life_text(report: &LifeReport) -> String {
    let mut out = String::new();
    let n = report.points.len();
    let _ = writeln!(
        out,
        "{}  [{}]: {n} snapshots over {}",
        report.path,
        report.channel,
        duration_text(report.span_s())
    );
    let s = &report.settings;
    let _ = writeln!(
        out,
        "  tracker: the daemon's health stages; baseline the first {} snapshots, {}σ, {} in a row, running median of {} (docs/HEALTH.md)",
        s.baseline_snapshots, s.sigma, s.confirm_snapshots, s.smoothing
    );
    let _ = writeln!(out, "  stages:");
    let first = report.points.first();
    let mut rows: Vec<(HealthStage, f64, &str, String)> = Vec::new();
    if let Some(p) = first {
        rows.push((HealthStage::Learning, p.time_s, &p.source, String::new()));
    }
    for e in &report.events {
        let point = report.points.get(e.snapshot);
        let limit = match e.to {
            HealthStage::Healthy => point
                .and_then(|p| p.kurtosis_limit)
                .map(|l| format!("kurtosis limit {l:.2}")),
            HealthStage::Failing => point
                .and_then(|p| p.rms_limit)
                .map(|l| format!("RMS limit {l:.3} g")),
            _ => None,
        };
        rows.push((e.to, e.time_s, &e.source, limit.unwrap_or_default()));
    }
    for (stage, t, source, extra) in rows {
        let _ = writeln!(
            out,
            "    {:<10} from {:>10} ({:>5.1} % of the observed life)  {source}  {extra}",
            stage.name(),
            duration_text(t),
            100.0 * report.life_fraction(t)
        );
    }
    if let Some(last) = report.points.last() {
        // A daemon log has a fit every re-fit: the newest one when the last snapshot has none.
        let hw = match (
            last.hw_residual_percent,
            report
                .points
                .iter()
                .rev()
                .find_map(|p| p.hw_residual_percent.map(|r| (r, p.time_s))),
        ) {
            (Some(r), _) => format!("{r:.1} %"),
            (None, Some((r, t))) => format!("{r:.1} % (the newest fit, at {})", duration_text(t)),
            (None, None) => "n/a".into(),
        };
        let score = match (last.fault_score, last.fault) {
            (Some(s), Some(f)) => format!("{s:.1} ({})", f.name()),
            _ => "n/a".into(),
        };
        let _ = writeln!(
            out,
            "  last snapshot: {}; RMS {:.3} g, kurtosis {:.2}, HW residual {hw}, envelope fault score {score}",
            last.stage.name(),
            last.rms,
            last.kurtosis
        );
        let _ = writeln!(out, "  {}", trend_text(last, s.trend_window));
    }
    if let Some(h) = &report.hindsight {
        let _ = writeln!(out, "  {}", hindsight_text(h));
    }
    for gap in &report.gaps {
        let _ = writeln!(
            out,
            "  gap: no samples from {} to {} ({}), between {} and {}",
            duration_text(gap.from_s),
            duration_text(gap.to_s),
            duration_text(gap.to_s - gap.from_s),
            gap.after,
            gap.before
        );
    }
    for note in &report.notes {
        let _ = writeln!(out, "  note: {note}");
    }
    if !report.ignored.is_empty() {
        let _ = writeln!(
            out,
            "  ignored {} file(s) that are not snapshots: {}",
            report.ignored.len(),
            report.ignored.join(", ")
        );
    }
    if !report.skipped.is_empty() {
        let _ = writeln!(
            out,
            "  skipped {} file(s) that could not be used:",
            report.skipped.len()
        );
        for s in &report.skipped {
            let _ = writeln!(out, "    {}", s.error);
        }
    }
    out
}

fn trend_text(point: &LifePoint, window: usize) -> String {
    let Some(t) = point.trend else {
        return match point.stage {
            HealthStage::Learning | HealthStage::Healthy => {
                "trend: none while healthy (no threshold yet; give --threshold-g for one)".into()
            }
            _ => "trend: none yet (the failure limit is learned over the first snapshots of degradation)".into(),
        };
    };
    let growth = match t.doubling_s {
        Some(d) => format!("RMS doubles every {}", duration_text(d)),
        None => "RMS is not growing".into(),
    };
    let when = match (t.time_to_threshold_s(), t.earliest_s, t.latest_s) {
        (Some(0.0), _, _) => format!("it is at or above {:.3} g now", t.threshold),
        (Some(left), lo, hi) => format!(
            "reaches {:.3} g in {} ({:.0} % band: {} to {})",
            t.threshold,
            duration_text(left),
            100.0 * t.confidence,
            lo.map_or("?".into(), |lo| duration_text(lo - t.now_s)),
            hi.map_or(
                format!("beyond {}", duration_text(t.horizon_s - t.now_s)),
                |hi| duration_text(hi - t.now_s)
            ),
        ),
        (None, Some(lo), _) => format!(
            "does not reach {:.3} g within {} on the fit (band: from {})",
            t.threshold,
            duration_text(t.horizon_s - t.now_s),
            duration_text(lo - t.now_s)
        ),
        (None, None, _) => format!(
            "does not reach {:.3} g within {}",
            t.threshold,
            duration_text(t.horizon_s - t.now_s)
        ),
    };
    format!("trend (exponential fit over the last {window} snapshots): {growth}; {when}")
}

fn hindsight_text(h: &TrendHindsight) -> String {
    let mut text = format!(
        "hindsight: RMS crossed {:.3} g at {}; {} trend estimates before, {} predicted a crossing",
        h.threshold,
        duration_text(h.crossed_s),
        h.estimates,
        h.predicted
    );
    if let (Some(lead), Some(err)) = (h.first_lead_s, h.first_error_s) {
        let _ = write!(
            text,
            "; the first {} ahead, off by {}",
            duration_text(lead),
            duration_text(err)
        );
    }
    if let (Some(lead), Some(err)) = (h.last_lead_s, h.last_error_s) {
        let _ = write!(
            text,
            "; the last {} ahead, off by {}",
            duration_text(lead),
            duration_text(err)
        );
    }
    match h.first_in_band_lead_s {
        Some(lead) => {
            let _ = write!(
                text,
                "; the band first held the crossing {} ahead",
                duration_text(lead)
            );
        }
        None => text.push_str("; no band held the crossing"),
    }
    text
}

fn stage_color(stage: HealthStage) -> Option<Color> {
    match stage {
        HealthStage::Learning => Some(Color::LIGHT_GREY.with_alpha(120)),
        HealthStage::Healthy => None,
        HealthStage::Degrading => Some(Color::ORANGE.with_alpha(50)),
        HealthStage::Failing => Some(Color::VERMILLION.with_alpha(60)),
    }
}

/// Said on the figure, instead of a flat panel, when the fault score never leaves its floor.
const FLAT_SCORE_NOTE: &str =
    "no fault-score panel: 1.0 (its floor) on every snapshot, no fault line above the noise (docs/HEALTH.md)";

/// The life time axis: seconds per unit and the unit's name, chosen by the life's span.
fn time_unit(span_s: f64) -> (f64, &'static str) {
    if span_s >= 2.0 * 3600.0 {
        (3600.0, "h")
    } else if span_s >= 120.0 {
        (60.0, "min")
    } else {
        (1.0, "s")
    }
}

/// The places along a panel's x axis: a snapshot (its index) or a break (`None`, at a time
/// in s) where the lines stop, in the middle of each gap.
#[derive(Clone)]
struct Slots(Vec<(Option<usize>, f64)>);

impl Slots {
    /// Every snapshot, with a break in each gap.
    fn of(report: &LifeReport) -> Slots {
        let mut gaps = report.gaps.iter().peekable();
        let mut slots = Vec::new();
        for (i, p) in report.points.iter().enumerate() {
            while let Some(g) = gaps.next_if(|g| g.to_s <= p.time_s) {
                slots.push((None, 0.5 * (g.from_s + g.to_s)));
            }
            slots.push((Some(i), p.time_s));
        }
        Slots(slots)
    }

    /// Only the snapshots `keep` accepts (and the breaks).
    fn only(&self, keep: impl Fn(usize) -> bool) -> Slots {
        Slots(
            self.0
                .iter()
                .copied()
                .filter(|(i, _)| i.is_none_or(&keep))
                .collect(),
        )
    }

    fn x(&self, unit_s: f64) -> Vec<f64> {
        self.0.iter().map(|(_, t)| t / unit_s).collect()
    }

    /// `values` (one per snapshot) along the slots, NaN at the breaks.
    fn y(&self, values: &[f64]) -> Vec<f64> {
        self.0
            .iter()
            .map(|(i, _)| i.and_then(|i| values.get(i).copied()).unwrap_or(f64::NAN))
            .collect()
    }
}

/// The figure: panels over life time, stages shaded, stage changes marked, lines broken at
/// the gaps; a panel only when it has something to show (no HW residual with `--no-hw`, no
/// fault score without a speed).
pub fn life_figure(report: &LifeReport) -> Figure {
    let (unit_s, unit) = time_unit(report.span_s());
    let x_label = format!("life time ({unit})");
    let slots = Slots::of(report);
    let x = slots.x(unit_s);
    let end_x = x.last().copied().unwrap_or(0.0);
    // Stage shading: from each change to the next (learning from the start); the last to
    // beyond the end (clipped to the plot), so that it covers a trend drawn past the end.
    let mut spans: Vec<(HealthStage, f64)> = vec![(HealthStage::Learning, 0.0)];
    spans.extend(report.events.iter().map(|e| (e.to, e.time_s / unit_s)));
    let shades: Vec<Shade> = spans
        .iter()
        .enumerate()
        .filter_map(|(i, &(stage, from))| {
            let to = spans.get(i + 1).map_or(4.0 * end_x + 1.0, |s| s.1);
            stage_color(stage).map(|color| Shade {
                x0: from,
                x1: to,
                color,
            })
        })
        .collect();
    let markers: Vec<Marker> = report
        .events
        .iter()
        .map(|e| Marker {
            x: e.time_s / unit_s,
            label: e.to.name().into(),
            color: match e.to {
                HealthStage::Failing => Color::VERMILLION,
                HealthStage::Degrading => Color::ORANGE,
                _ => Color::BLUISH_GREEN,
            },
            dashed: true,
        })
        .collect();
    let panel = |y_label: &str, x: Vec<f64>| {
        let mut panel = SpectrumPanel::new(x_label.clone(), y_label, x);
        panel.shaded = shades.clone();
        panel.markers = markers.clone();
        panel
    };
    let values = |f: &dyn Fn(&LifePoint) -> Option<f64>| -> Vec<f64> {
        report
            .points
            .iter()
            .map(|p| f(p).unwrap_or(f64::NAN))
            .collect()
    };
    let pick = |f: &dyn Fn(&LifePoint) -> Option<f64>| slots.y(&values(f));

    // RMS, with the newest trend and its band carried forward to its crossing or horizon.
    let trend = report.points.iter().rev().find_map(|p| p.trend);
    let mut rms_x = x.clone();
    let mut rms = pick(&|p| Some(p.rms));
    let mut tracked = pick(&|p| Some(p.rms_tracked));
    let mut limit = pick(&|p| p.rms_limit);
    let (mut fit, mut lo, mut hi) = (
        vec![f64::NAN; report.points.len()],
        vec![f64::NAN; report.points.len()],
        vec![f64::NAN; report.points.len()],
    );
    if let Some(t) = trend {
        let window = report.settings.trend_window.min(report.points.len());
        let first = report.points.len() - window;
        for i in first..report.points.len() {
            (fit[i], lo[i], hi[i]) = t.band_at(report.points[i].time_s);
        }
    }
    let (mut fit, mut lo, mut hi) = (slots.y(&fit), slots.y(&lo), slots.y(&hi));
    if let Some(t) = trend {
        let until = t.latest_s.or(t.crossing_s).unwrap_or(t.horizon_s);
        let steps = 40;
        for k in 1..=steps {
            let time = t.now_s + (until - t.now_s) * f64::from(k) / f64::from(steps);
            let (f, l, h) = t.band_at(time);
            rms_x.push(time / unit_s);
            for (v, x) in [
                (&mut fit, f),
                (&mut lo, l),
                (&mut hi, h),
                (&mut rms, f64::NAN),
                (&mut tracked, f64::NAN),
            ] {
                v.push(x);
            }
            limit.push(t.threshold);
        }
    }
    let mut rms_panel = panel("RMS (g)", rms_x);
    rms_panel.log_y = true;
    // What the shading means, once, on the top panel (the same stages shade every panel).
    for stage in [
        HealthStage::Learning,
        HealthStage::Degrading,
        HealthStage::Failing,
    ] {
        if let Some(color) = stage_color(stage).filter(|_| spans.iter().any(|s| s.0 == stage)) {
            rms_panel.legend.push(LegendEntry {
                label: match stage {
                    HealthStage::Learning => "shaded: learning the baseline".into(),
                    _ => format!("shaded: {}", stage.name()),
                },
                color,
                sample: LegendSample::Band,
            });
        }
    }
    rms_panel.series = vec![
        Series {
            label: "RMS".into(),
            y: rms,
            color: Color::GREY,
        },
        Series {
            label: "tracked (median)".into(),
            y: tracked,
            color: Color::BLUE,
        },
        Series {
            label: "failure limit".into(),
            y: limit,
            color: Color::VERMILLION,
        },
    ];
    if trend.is_some() {
        let band = format!("{:.0} % band", 100.0 * report.settings.confidence);
        rms_panel.series.extend([
            Series {
                label: "trend".into(),
                y: fit,
                color: Color::REDDISH_PURPLE,
            },
            Series {
                label: band,
                y: lo,
                color: Color::SKY_BLUE,
            },
            Series {
                label: String::new(),
                y: hi,
                color: Color::SKY_BLUE,
            },
        ]);
    }

    let mut kurtosis = panel("kurtosis", x.clone());
    kurtosis.log_y = true;
    kurtosis.series = vec![
        Series {
            label: "kurtosis".into(),
            y: pick(&|p| Some(p.kurtosis)),
            color: Color::GREY,
        },
        Series {
            label: "tracked (median)".into(),
            y: pick(&|p| Some(p.kurtosis_tracked)),
            color: Color::BLUE,
        },
        Series {
            label: "healthy limit".into(),
            y: pick(&|p| p.kurtosis_limit),
            color: Color::ORANGE,
        },
    ];

    let mut figure = Figure::new(format!("Life of {} [{}]", report.path, report.channel));
    let time_left = time_left_panel(report, &slots, (unit_s, &x_label), &shades, &markers);
    let stages: Vec<String> = report
        .events
        .iter()
        .map(|e| {
            format!(
                "{} at {:.1} %",
                e.to.name(),
                100.0 * report.life_fraction(e.time_s)
            )
        })
        .collect();
    figure = figure.with_note(format!(
        "{} snapshots{}; stages: {}",
        report.points.len(),
        match report.gaps.len() {
            0 => String::new(),
            n => format!(", {n} gap(s) (lines break there)"),
        },
        if stages.is_empty() {
            "none".into()
        } else {
            stages.join(", ")
        }
    ));
    if let Some(last) = report.points.last() {
        figure = figure.with_note(trend_text(last, report.settings.trend_window));
    }
    figure = figure.with_panel(rms_panel);
    if let Some(panel) = time_left {
        figure = figure.with_panel(panel);
    }
    figure = figure.with_panel(kurtosis);

    // The HW residual over the snapshots that have one (a daemon log has one per re-fit).
    let hw_values = values(&|p| p.hw_residual_percent);
    if hw_values.iter().any(|v| v.is_finite()) {
        let hw_slots = slots.only(|i| hw_values[i].is_finite());
        let logged = report.points.iter().any(|p| p.hw_from == Some(HwFrom::Log));
        let mut hw = panel("HW residual (% NRMSE)", hw_slots.x(unit_s));
        // The same time axis as the other panels, though the fits may be sparse.
        hw.x_range = Some((x.first().copied().unwrap_or(0.0), end_x));
        hw.series = vec![Series {
            label: if logged {
                "HW residual (daemon's fits)".into()
            } else {
                "HW free-run residual, order 0".into()
            },
            y: hw_slots.y(&hw_values),
            color: Color::BLUISH_GREEN,
        }];
        figure = figure.with_panel(hw);
    }
    // A score that never leaves its floor would draw a flat line: said in a note instead.
    let scores = values(&|p| p.fault_score);
    let scored = scores.iter().filter(|v| v.is_finite());
    if scored.clone().all(|&v| v <= 1.0) {
        if scored.count() > 0 {
            figure = figure.with_note(FLAT_SCORE_NOTE);
        }
    } else {
        let mut score = panel("envelope fault score", x);
        score.series = vec![Series {
            label: "strongest fault score".into(),
            y: slots.y(&scores),
            color: Color::REDDISH_PURPLE,
        }];
        figure = figure.with_panel(score);
    }
    figure
}

/// Each snapshot's predicted time to the threshold with its band, and (in hindsight) the time
/// that was really left; `None` when no snapshot had a trend.
fn time_left_panel(
    report: &LifeReport,
    slots: &Slots,
    (unit_s, x_label): (f64, &str),
    shades: &[Shade],
    markers: &[Marker],
) -> Option<SpectrumPanel> {
    report.points.iter().find(|p| p.trend.is_some())?;
    let minutes = |f: &dyn Fn(&crate::analysis::degradation::TrendFit) -> Option<f64>| {
        let per_point: Vec<f64> = report
            .points
            .iter()
            .map(|p| {
                p.trend
                    .and_then(|t| f(&t).map(|at| (at - t.now_s) / 60.0))
                    .unwrap_or(f64::NAN)
            })
            .collect();
        slots.y(&per_point)
    };
    let mut panel = SpectrumPanel::new(x_label, "time to threshold (min)", slots.x(unit_s));
    panel.shaded = shades.to_vec();
    panel.markers = markers.to_vec();
    panel.series = vec![
        Series {
            label: "predicted".into(),
            y: minutes(&|t| t.crossing_s),
            color: Color::REDDISH_PURPLE,
        },
        Series {
            label: format!("{:.0} % band", 100.0 * report.settings.confidence),
            y: minutes(&|t| t.earliest_s),
            color: Color::SKY_BLUE,
        },
        Series {
            label: String::new(),
            y: minutes(&|t| t.latest_s),
            color: Color::SKY_BLUE,
        },
    ];
    if let Some(h) = &report.hindsight {
        panel.series.push(Series {
            label: "really left (hindsight)".into(),
            y: slots.y(&report
                .points
                .iter()
                .map(|p| match p.trend {
                    Some(_) if p.time_s <= h.crossed_s => (h.crossed_s - p.time_s) / 60.0,
                    _ => f64::NAN,
                })
                .collect::<Vec<f64>>()),
            color: Color::BLACK,
        });
    }
    Some(panel)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::Panel;

    fn point(i: usize, time_s: f64, hw: Option<f64>, score: Option<f64>) -> LifePoint {
        LifePoint {
            source: format!("s{i}"),
            time_s,
            rms: 0.1,
            kurtosis: 3.0,
            rms_tracked: 0.1,
            kurtosis_tracked: 3.0,
            hw_residual_percent: hw,
            hw_from: hw.map(|_| HwFrom::Log),
            fault_score: score,
            fault: None,
            stage: HealthStage::Learning,
            kurtosis_limit: None,
            rms_limit: None,
            trend: None,
        }
    }

    fn report(points: Vec<LifePoint>, gaps: Vec<LifeGap>) -> LifeReport {
        LifeReport {
            path: "logs".into(),
            channel: "s/x".into(),
            settings: LifeSettingsReport {
                baseline_snapshots: 15,
                sigma: 3.0,
                confirm_snapshots: 3,
                smoothing: 3,
                trend_window: 12,
                confidence: 0.9,
                threshold_rms: None,
            },
            events: Vec::new(),
            points,
            gaps,
            hindsight: None,
            skipped: Vec::new(),
            ignored: Vec::new(),
            notes: Vec::new(),
        }
    }

    fn y_labels(figure: &Figure) -> Vec<String> {
        figure
            .panels
            .iter()
            .filter_map(|p| match p {
                Panel::Spectrum(s) => Some(s.y_label.clone()),
                Panel::Heatmap(_) => None,
            })
            .collect()
    }

    #[test]
    fn a_panel_is_drawn_only_when_it_has_something_to_show() {
        let bare = report(
            (0..5).map(|i| point(i, i as f64, None, None)).collect(),
            vec![],
        );
        let figure = life_figure(&bare);
        assert_eq!(y_labels(&figure), ["RMS (g)", "kurtosis"]);
        // The legend names the shading of the stages this life went through, and no other.
        let legend: Vec<&str> = match &figure.panels[0] {
            Panel::Spectrum(s) => s.legend.iter().map(|e| e.label.as_str()).collect(),
            Panel::Heatmap(_) => Vec::new(),
        };
        assert_eq!(legend, ["shaded: learning the baseline"]);
        let full = report(
            (0..5)
                .map(|i| point(i, i as f64, (i == 2).then_some(12.0), Some(2.0)))
                .collect(),
            vec![],
        );
        assert_eq!(
            y_labels(&life_figure(&full)),
            [
                "RMS (g)",
                "kurtosis",
                "HW residual (% NRMSE)",
                "envelope fault score"
            ]
        );
        // A score at its floor on every snapshot: a note, not a flat panel.
        let flat = report(
            (0..5)
                .map(|i| point(i, i as f64, None, Some(1.0)))
                .collect(),
            vec![],
        );
        let figure = life_figure(&flat);
        assert_eq!(y_labels(&figure), ["RMS (g)", "kurtosis"]);
        assert!(figure
            .notes
            .iter()
            .any(|n| n.starts_with("no fault-score panel")));
    }

    #[test]
    fn the_lines_break_in_a_gap() {
        let points = vec![
            point(0, 0.0, None, None),
            point(1, 1.0, None, None),
            point(2, 100.0, None, None),
            point(3, 101.0, None, None),
        ];
        let gap = LifeGap {
            after: "s1".into(),
            before: "s2".into(),
            from_s: 2.0,
            to_s: 100.0,
        };
        let figure = life_figure(&report(points, vec![gap]));
        let Panel::Spectrum(rms) = &figure.panels[0] else {
            panic!("the RMS panel first");
        };
        assert_eq!(rms.x, [0.0, 1.0, 51.0, 100.0, 101.0]);
        let y = &rms.series[0].y;
        assert!(y[2].is_nan() && y.iter().filter(|v| v.is_nan()).count() == 1);
        assert!(figure.notes.iter().any(|n| n.contains("1 gap(s)")));
    }
}
