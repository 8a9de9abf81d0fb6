//! The picture of a sweep: detection probability against SNR, one line per fault type, one
//! panel per path, drawn with the project's plot code.

use super::summary::{Path, Summary};
use crate::messages::FaultKind;
use crate::plot::{Color, Figure, Series, SpectrumPanel};

/// Pd vs SNR per fault type (the simulator-default noise level has no SNR of its own and is
/// left out; the table shows it).
pub fn pd_figure(summary: &Summary, sweep_name: &str) -> Figure {
    let snrs: Vec<(String, f64)> = summary
        .noise_levels
        .iter()
        .filter_map(|label| {
            let db = label.strip_suffix(" dB")?.parse::<f64>().ok()?;
            Some((label.clone(), db))
        })
        .collect();
    let x: Vec<f64> = snrs.iter().map(|(_, db)| *db).collect();
    let mut figure = Figure::new(format!(
        "Detection probability vs SNR ({sweep_name} sweep, {} runs)",
        summary.runs
    ))
    .with_note("SNR: fault RMS over broadband noise RMS (white + shaft-modulated), dB")
    .with_note("each point: every severity, speed and bearing at that SNR");
    for p in &summary.paths {
        let y_label = match p.path {
            Path::Record => "Pd, analyze (verdict)",
            Path::Monitor => "Pd, monitor (flag)",
        };
        let mut panel = SpectrumPanel::new("SNR (dB)", y_label, x.clone());
        panel.series.push(Series {
            label: "Pd = 1".into(),
            y: vec![1.0; x.len()],
            color: Color::LIGHT_GREY,
        });
        for (kind, color) in FaultKind::ALL.into_iter().zip(Color::CYCLE) {
            let y = snrs
                .iter()
                .map(|(label, _)| {
                    p.pd.get(kind.name())
                        .and_then(|row| row.get(label))
                        .and_then(|rate| rate.fraction())
                        .unwrap_or(f64::NAN)
                })
                .collect();
            panel.series.push(Series {
                label: kind.name().into(),
                y,
                color,
            });
        }
        let fa = p.false_alarms_per_record;
        figure = figure.with_note(format!(
            "{}: false alarms on healthy records {}/{}, confident wrong {}",
            match p.path {
                Path::Record => "analyze",
                Path::Monitor => "monitor",
            },
            fa.hits,
            fa.trials,
            p.confident_wrong
        ));
        figure = figure.with_panel(panel);
    }
    figure
}
