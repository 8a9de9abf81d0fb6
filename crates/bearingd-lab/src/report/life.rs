//! What `bearingd trend` tells its user about a bearing's life: one [`LifeReport`] feeds the JSON
//! document, the text summary and the figure (stage timeline with RMS, kurtosis, HW residual and
//! fault score, and the RMS trend with its band), so they always agree.

use crate::life::{LifePoint, StageEvent, TrendHindsight};
use crate::messages::HealthStage;
use crate::plot::{Color, Figure, Marker, Series, Shade, SpectrumPanel};
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

/// A bearing's life as `trend` saw it.
#[derive(Debug, Clone, Serialize)]
pub struct LifeReport {
    pub path: String,
    pub channel: String,
    pub settings: LifeSettingsReport,
    /// Stage changes in order.
    pub events: Vec<StageEvent>,
    pub points: Vec<LifePoint>,
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
        let hw = last
            .hw_residual_percent
            .map_or("n/a".into(), |r| format!("{r:.1} %"));
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

/// The figure: four panels over life time (hours), stages shaded, stage changes marked.
pub fn life_figure(report: &LifeReport) -> Figure {
    let hours: Vec<f64> = report.points.iter().map(|p| p.time_s / 3600.0).collect();
    let end_h = hours.last().copied().unwrap_or(0.0);
    // Stage shading: from each change to the next (learning from the start).
    let mut spans: Vec<(HealthStage, f64)> = vec![(HealthStage::Learning, 0.0)];
    spans.extend(report.events.iter().map(|e| (e.to, e.time_s / 3600.0)));
    let shades: Vec<Shade> = spans
        .iter()
        .enumerate()
        .filter_map(|(i, &(stage, from))| {
            let to = spans.get(i + 1).map_or(end_h, |s| s.1);
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
            x: e.time_s / 3600.0,
            label: e.to.name().into(),
            color: match e.to {
                HealthStage::Failing => Color::VERMILLION,
                HealthStage::Degrading => Color::ORANGE,
                _ => Color::BLUISH_GREEN,
            },
            dashed: true,
        })
        .collect();
    let dress = |mut panel: SpectrumPanel| {
        panel.shaded = shades.clone();
        panel.markers = markers.clone();
        panel
    };
    let pick = |f: &dyn Fn(&LifePoint) -> Option<f64>| -> Vec<f64> {
        report
            .points
            .iter()
            .map(|p| f(p).unwrap_or(f64::NAN))
            .collect()
    };

    // RMS, with the newest trend and its band carried forward to its crossing or horizon.
    let trend = report.points.iter().rev().find_map(|p| p.trend);
    let mut rms_x = hours.clone();
    let mut rms = pick(&|p| Some(p.rms));
    let mut tracked = pick(&|p| Some(p.rms_tracked));
    let mut limit = pick(&|p| p.rms_limit);
    let (mut fit, mut lo, mut hi) = (vec![f64::NAN; rms_x.len()], rms.clone(), rms.clone());
    lo.fill(f64::NAN);
    hi.fill(f64::NAN);
    if let Some(t) = trend {
        let window = report.settings.trend_window.min(report.points.len());
        let first = report.points.len() - window;
        for i in first..report.points.len() {
            let (f, l, h) = t.band_at(report.points[i].time_s);
            (fit[i], lo[i], hi[i]) = (f, l, h);
        }
        let until = t.latest_s.or(t.crossing_s).unwrap_or(t.horizon_s);
        let steps = 40;
        for k in 1..=steps {
            let time = t.now_s + (until - t.now_s) * f64::from(k) / f64::from(steps);
            let (f, l, h) = t.band_at(time);
            rms_x.push(time / 3600.0);
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
    let mut rms_panel = dress(SpectrumPanel::new("life time (h)", "RMS (g)", rms_x));
    rms_panel.log_y = true;
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

    let mut kurtosis = dress(SpectrumPanel::new(
        "life time (h)",
        "kurtosis",
        hours.clone(),
    ));
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
    let mut hw = dress(SpectrumPanel::new(
        "life time (h)",
        "HW residual (% NRMSE)",
        hours.clone(),
    ));
    hw.series = vec![Series {
        label: "HW free-run residual, order 0".into(),
        y: pick(&|p| p.hw_residual_percent),
        color: Color::BLUISH_GREEN,
    }];
    let mut score = dress(SpectrumPanel::new(
        "life time (h)",
        "envelope fault score",
        hours,
    ));
    score.series = vec![Series {
        label: "strongest fault score".into(),
        y: pick(&|p| p.fault_score),
        color: Color::REDDISH_PURPLE,
    }];

    let mut figure = Figure::new(format!("Life of {} [{}]", report.path, report.channel));
    let time_left = time_left_panel(report, &shades, &markers);
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
        "{} snapshots; stages: {}",
        report.points.len(),
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
    figure.with_panel(kurtosis).with_panel(hw).with_panel(score)
}

/// Each snapshot's predicted time to the threshold with its band, and (in hindsight) the time
/// that was really left; `None` when no snapshot had a trend.
fn time_left_panel(
    report: &LifeReport,
    shades: &[Shade],
    markers: &[Marker],
) -> Option<SpectrumPanel> {
    report.points.iter().find(|p| p.trend.is_some())?;
    let hours: Vec<f64> = report.points.iter().map(|p| p.time_s / 3600.0).collect();
    let minutes = |f: &dyn Fn(&crate::analysis::degradation::TrendFit) -> Option<f64>| {
        report
            .points
            .iter()
            .map(|p| {
                p.trend
                    .and_then(|t| f(&t).map(|at| (at - t.now_s) / 60.0))
                    .unwrap_or(f64::NAN)
            })
            .collect::<Vec<f64>>()
    };
    let mut panel = SpectrumPanel::new("life time (h)", "time to threshold (min)", hours);
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
            y: report
                .points
                .iter()
                .map(|p| match p.trend {
                    Some(_) if p.time_s <= h.crossed_s => (h.crossed_s - p.time_s) / 60.0,
                    _ => f64::NAN,
                })
                .collect(),
            color: Color::BLACK,
        });
    }
    Some(panel)
}
