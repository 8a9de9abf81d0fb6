//! The picture of an analysis: the envelope spectrum with the fault frequencies and their
//! harmonics marked (tolerance shaded), and the kurtogram with the band that was used.

use crate::analysis::iso::VelocitySeverity;
use crate::analysis::{BandSelection, RecordAnalysis};
use crate::messages::FaultKind;
use crate::plot::{
    Color, Figure, HeatmapPanel, HeatmapRow, LegendEntry, LegendSample, Level, Marker, Series,
    Shade, SpectrumPanel,
};
use crate::twin::diagnose::TwinDiagnosis;
use bearingd::report::AnalyzeReport;

fn fault_color(kind: FaultKind) -> Color {
    match kind {
        FaultKind::OuterRace => Color::VERMILLION,
        FaultKind::InnerRace => Color::BLUE,
        FaultKind::Ball => Color::BLUISH_GREEN,
        FaultKind::Cage => Color::REDDISH_PURPLE,
    }
}

/// The figure of `bearingd analyze --plot`.
pub fn analysis_figure(
    report: &AnalyzeReport,
    analysis: &RecordAnalysis,
    twin: Option<&TwinDiagnosis>,
) -> Figure {
    let spectrum = analysis.spectrum();
    let x: Vec<f64> = spectrum.frequencies().collect();
    let x_max = x.last().copied().unwrap_or(0.0);
    let mut panel = SpectrumPanel::new(
        "envelope frequency (Hz)",
        "squared-envelope amplitude (g²)",
        x,
    );
    panel.series.push(Series {
        label: format!(
            "measured, band {:.0}–{:.0} Hz",
            report.band_hz[0], report.band_hz[1]
        ),
        y: spectrum.amplitude.iter().map(|&v| f64::from(v)).collect(),
        color: Color::BLACK,
    });
    panel.log_y = true;
    panel.x_range = Some((0.0, x_max));
    let shaft = analysis.frequencies.shaft;
    fault_markers(
        &mut panel,
        analysis,
        report.thresholds.harmonics,
        report.thresholds.fault_tolerance,
        x_max,
    );

    let use_gk = matches!(report_selection(report), Some(BandSelection::GiniKurtosis));
    let mut rows = Vec::new();
    let mut highlight = None;
    for (row, level) in analysis.scan.levels.iter().enumerate() {
        let bands: Vec<(usize, _)> = analysis
            .scan
            .bands
            .iter()
            .enumerate()
            .filter(|(_, b)| b.level == *level)
            .collect();
        for (cell, (index, _)) in bands.iter().enumerate() {
            if *index == analysis.reported_band_index {
                highlight = Some((row, cell));
            }
        }
        rows.push(HeatmapRow {
            label: format!("{level}"),
            values: bands
                .iter()
                .map(|(_, b)| if use_gk { b.gk } else { b.kurtosis })
                .collect(),
        });
    }
    let heatmap = HeatmapPanel {
        title: format!(
            "{} per band of the kurtogram tree (level per row)",
            if use_gk {
                "GK index"
            } else {
                "spectral kurtosis"
            }
        ),
        x_label: "frequency (Hz)".into(),
        x_max: analysis.fs_hz / 2.0,
        rows,
        highlight,
        value_label: if use_gk {
            "GK index".into()
        } else {
            "kurtosis".into()
        },
        y_label: "level k: Δf=fs/2^(k+1)".into(),
    };

    let figure = Figure::new(format!("{} [{}]", report.file, report.channel))
        .with_note(format!(
            "diagnosis: {} (confidence {:.2}) - {}",
            report.diagnosis, report.confidence, report.reason
        ))
        .with_note(format!(
            "{:.0} rpm, bearing {}, band {:.0}-{:.0} Hz: {}",
            report.rpm,
            report.bearing,
            report.band_hz[0],
            report.band_hz[1],
            report.band_selection.reason
        ))
        .with_panel(panel);
    let figure = match &report.velocity {
        Some(velocity) => figure
            .with_note(velocity.summary())
            .with_panel(velocity_panel(velocity, shaft)),
        None => figure,
    };
    let figure = match twin {
        Some(twin) => figure.with_panel(twin_panel(
            twin,
            analysis,
            report.thresholds.fault_tolerance,
        )),
        None => figure,
    };
    figure.with_panel(heatmap)
}

/// Marks every harmonic of each fault frequency up to `x_max`, and the shaft frequency. The
/// harmonics the diagnosis scores (orders up to `scored`) get their tolerance band shaded and
/// a full-strength line; the others a paler line. Fundamentals come first so that their
/// labels win a crowded spot (the scene drops labels that would collide; the lines stay).
fn fault_markers(
    panel: &mut SpectrumPanel,
    analysis: &RecordAnalysis,
    scored: usize,
    tolerance: f64,
    x_max: f64,
) {
    /// A guard against a fault frequency so low that its harmonics would fill the axis.
    const MAX_ORDER: usize = 200;
    let diagnosed = analysis.diagnosis.verdict.fault();
    let kinds = [FaultKind::OuterRace, FaultKind::InnerRace, FaultKind::Ball];
    fault_legend(panel, analysis, &kinds, scored, tolerance, x_max);
    panel.markers.push(Marker {
        x: analysis.frequencies.shaft,
        label: "1x shaft".into(),
        color: Color::GREY,
        dashed: true,
    });
    for order in 1..=MAX_ORDER {
        let mut any = false;
        for kind in kinds {
            let f = kind.frequency(&analysis.frequencies);
            let at = order as f64 * f;
            if !(f > 0.0 && at.is_finite() && at <= x_max) {
                continue;
            }
            any = true;
            let color = fault_color(kind);
            let label = if order == 1 {
                kind.frequency_label().to_string()
            } else {
                format!("{} x{order}", kind.frequency_label())
            };
            let is_scored = order <= scored;
            panel.markers.push(Marker {
                x: at,
                label,
                color: if is_scored {
                    color
                } else {
                    color.with_alpha(110)
                },
                dashed: diagnosed != Some(kind),
            });
            if is_scored {
                panel.shaded.push(Shade {
                    x0: at * (1.0 - tolerance),
                    x1: at * (1.0 + tolerance),
                    color: color.with_alpha(40),
                });
            }
        }
        if !any {
            break;
        }
    }
}

/// The legend of the fault markers: each fault's colour (solid for the diagnosed fault, dashed
/// for the others), the paler lines of harmonics the diagnosis does not score, and the
/// shaded tolerance windows of those it does.
fn fault_legend(
    panel: &mut SpectrumPanel,
    analysis: &RecordAnalysis,
    kinds: &[FaultKind],
    scored: usize,
    tolerance: f64,
    x_max: f64,
) {
    let diagnosed = analysis.diagnosis.verdict.fault();
    for &kind in kinds {
        let f = kind.frequency(&analysis.frequencies);
        if !(f > 0.0 && f <= x_max) {
            continue;
        }
        let is_diagnosed = diagnosed == Some(kind);
        panel.legend.push(LegendEntry {
            label: format!(
                "{} {}{}",
                kind.frequency_label(),
                kind.name().replace('_', " "),
                if is_diagnosed { " (diagnosed)" } else { "" }
            ),
            color: fault_color(kind),
            sample: if is_diagnosed {
                LegendSample::Line
            } else {
                LegendSample::DashedLine
            },
        });
    }
    panel.legend.push(LegendEntry {
        label: format!("pale: harmonic above x{scored}, not scored"),
        color: Color::GREY.with_alpha(110),
        sample: LegendSample::Line,
    });
    panel.legend.push(LegendEntry {
        label: format!("shaded: ±{:.0} % window scored", tolerance * 100.0),
        color: Color::GREY.with_alpha(60),
        sample: LegendSample::Band,
    });
}

/// The velocity spectrum the ISO 10816-3 value sums (RMS per bin, in the standard's band),
/// with the shaft harmonics marked: where the velocity comes from (unbalance at 1x,
/// misalignment at 2x, or broadband).
fn velocity_panel(v: &VelocitySeverity, shaft_hz: f64) -> SpectrumPanel {
    let x: Vec<f64> = (0..v.per_bin_mm2_s2.len())
        .map(|k| k as f64 * v.bin_hz)
        .collect();
    let x_max = (v.band_hz[1] * 1.05).min(x.last().copied().unwrap_or(0.0));
    let mut panel = SpectrumPanel::new("frequency (Hz)", "velocity RMS per bin (mm/s)", x);
    panel.x_range = Some((0.0, x_max));
    panel.series.push(Series {
        label: format!(
            "velocity {:.2} mm/s RMS, zone {}",
            v.rms_mm_s,
            v.zone.name()
        ),
        y: v.per_bin_mm2_s2.iter().map(|p| p.sqrt()).collect(),
        color: Color::BLUE,
    });
    panel.shaded.push(Shade {
        x0: v.band_hz[0],
        x1: v.band_hz[1],
        color: Color::GREY.with_alpha(25),
    });
    panel.legend.push(LegendEntry {
        label: format!(
            "shaded: ISO band {:.0}-{:.0} Hz",
            v.band_hz[0], v.band_hz[1]
        ),
        color: Color::GREY.with_alpha(60),
        sample: LegendSample::Band,
    });
    // The zone boundaries apply to the overall RMS (the root of the sum over the bins): the
    // overall value is drawn with them, and one bin alone reaching a line reaches that zone.
    let l = &v.limits;
    for (y, name, color) in [
        (l.ab_mm_s, "A/B", Color::BLUISH_GREEN),
        (l.bc_mm_s, "B/C", Color::ORANGE),
        (l.cd_mm_s, "C/D", Color::VERMILLION),
    ] {
        panel.levels.push(Level {
            y,
            label: format!("ISO zone {name} {y} mm/s"),
            color,
            dashed: true,
        });
    }
    panel.levels.push(Level {
        y: v.rms_mm_s,
        label: format!("overall {:.2} mm/s RMS", v.rms_mm_s),
        color: Color::BLUE,
        dashed: false,
    });
    for order in 1..=3 {
        let at = order as f64 * shaft_hz;
        if at > x_max {
            break;
        }
        panel.markers.push(Marker {
            x: at,
            label: format!("{order}x shaft"),
            color: Color::GREY,
            dashed: true,
        });
    }
    panel
}

/// The best twin's envelope spectrum over the measured one, in the twin's band and range.
fn twin_panel(twin: &TwinDiagnosis, analysis: &RecordAnalysis, tolerance: f64) -> SpectrumPanel {
    let fit = twin.best_fit();
    let x: Vec<f64> = (0..twin.twin.len())
        .map(|k| k as f64 * twin.bin_hz)
        .collect();
    let x_max = x.last().copied().unwrap_or(0.0);
    let mut panel = SpectrumPanel::new("envelope frequency (Hz)", "amplitude (g²)", x);
    panel.log_y = true;
    panel.x_range = Some((0.0, x_max));
    panel.series.push(Series {
        label: format!(
            "measured, band {:.0}–{:.0} Hz",
            fit.band.lo_hz, fit.band.hi_hz
        ),
        y: twin.measured.clone(),
        color: Color::BLACK,
    });
    panel.series.push(Series {
        label: format!("twin: {} (error {:.3})", fit.fault.name(), fit.error),
        y: twin.twin.clone(),
        color: fault_color(fit.fault),
    });
    let f = fit.params.f_d;
    let nominal = fit.fault.frequency(&analysis.frequencies);
    panel.legend.push(LegendEntry {
        label: format!(
            "{} of the twin and its harmonics",
            fit.fault.frequency_label()
        ),
        color: fault_color(fit.fault),
        sample: LegendSample::DashedLine,
    });
    panel.legend.push(LegendEntry {
        label: format!(
            "shaded: ±{:.0} % around the nominal {}",
            tolerance * 100.0,
            fit.fault.frequency_label()
        ),
        color: fault_color(fit.fault).with_alpha(60),
        sample: LegendSample::Band,
    });
    for order in 1..=10 {
        let at = order as f64 * f;
        if at > x_max {
            break;
        }
        let label = if order == 1 {
            fit.fault.frequency_label().to_string()
        } else {
            format!("x{order}")
        };
        panel.markers.push(Marker {
            x: at,
            label,
            color: fault_color(fit.fault),
            dashed: true,
        });
        let nominal_at = order as f64 * nominal;
        panel.shaded.push(Shade {
            x0: nominal_at * (1.0 - tolerance),
            x1: nominal_at * (1.0 + tolerance),
            color: fault_color(fit.fault).with_alpha(30),
        });
    }
    panel
}

fn report_selection(report: &AnalyzeReport) -> Option<BandSelection> {
    match report.band_selection.method {
        "gk" => Some(BandSelection::GiniKurtosis),
        "kurtogram" => Some(BandSelection::Kurtogram),
        _ => None,
    }
}
