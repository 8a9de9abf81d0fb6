//! The text summary of `bearingd analyze`: the verdict in plain words first (for the
//! technician, [`super::plain`]), then the evidence for the engineer.

use super::{AnalyzeReport, SpeedSource};
use crate::messages::FaultKind;
use std::fmt::Write;

/// Renders the report as a few aligned lines of text.
pub fn render_text(r: &AnalyzeReport) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "VERDICT: {}", r.summary);
    let speed_from = match r.rpm_source {
        SpeedSource::File => "from the file",
        SpeedSource::Given => "given",
        SpeedSource::DataSetDefault => "the data set's constant speed",
        SpeedSource::Simulation => "simulated",
    };
    let g = &r.bearing_geometry;
    let _ = writeln!(out, "{}  [{}]", r.file, r.channel);
    let _ = writeln!(
        out,
        "  {:.0} Hz, {:.2} s, {:.1} rpm ({speed_from}); bearing {} (z={}, d={} mm, D={} mm, α={}°)",
        r.fs_hz,
        r.duration_s,
        r.rpm,
        r.bearing,
        g.rolling_elements,
        g.element_diameter_mm,
        g.pitch_diameter_mm,
        g.contact_angle_deg
    );
    let f = &r.fault_frequencies_hz;
    let _ = writeln!(
        out,
        "  fault frequencies: BPFO {:.1} Hz, BPFI {:.1} Hz, 2xBSF {:.1} Hz, FTF {:.2} Hz, shaft {:.2} Hz",
        f.bpfo, f.bpfi, f.two_bsf, f.ftf, f.shaft
    );
    // The header's band is the one reported (its spectrum is the one shown); a fault scored in
    // another band says so in its row, and the header says why they differ.
    let own_bands = if r.hypotheses.iter().any(|h| h.band_hz != r.band_hz) {
        "; each fault below is scored in the band that shows it best"
    } else {
        ""
    };
    let _ = writeln!(
        out,
        "  band {:.0}–{:.0} Hz: {}; {} windows of {} samples{own_bands}",
        r.band_hz[0], r.band_hz[1], r.band_selection.reason, r.windows_averaged, r.window_samples
    );
    let _ = writeln!(
        out,
        "  how far each fault's frequencies stand above the noise floor (×; {} harmonics and their sidebands, ±{:.0} % slip), how likely noise alone gives that (p), and whether it is named (it needs p ≤ {:.0e}, ≥ {:.1}×, and {:.1}× any other detected fault once the strongest is explained; or, alone, ≥ {:.1}× and {:.1}× every other):",
        r.thresholds.harmonics,
        r.thresholds.fault_tolerance * 100.0,
        r.thresholds.false_alarm_rate,
        r.thresholds.min_fault_score,
        r.thresholds.min_score_ratio,
        r.thresholds.lone_fault_score,
        r.thresholds.lone_score_ratio
    );
    for h in &r.hypotheses {
        let bar_len = (h.score.max(1.0).log2() * 4.0).round().clamp(0.0, 40.0) as usize;
        let sidebands = h
            .sideband_score
            .map(|s| format!("  sidebands {s:.1}"))
            .unwrap_or_default();
        let named = match &h.why_not {
            None => "named".to_string(),
            Some(why) => format!("not named: {why}"),
        };
        let _ = writeln!(
            out,
            "    {:<11} {:>7.1}  p=10^-{:<5.1} {:<40} in {:.0}–{:.0} Hz{}  {named}",
            h.fault.name(),
            h.score,
            h.significance,
            "#".repeat(bar_len),
            h.band_hz[0],
            h.band_hz[1],
            sidebands
        );
    }
    if let Some(t) = &r.twin {
        let p = &t.params;
        let _ = writeln!(
            out,
            "  twin ({:.1} ms): {} fits best in {:.0}–{:.0} Hz, error {:.3} (margin {:.3}): a {:.3} g, B {:.0}/s, f_n {:.0} Hz, f_d {:.2} Hz (slip {:+.2} %), jitter {:.2} %",
            t.fit_ms,
            t.hypothesis.name(),
            t.band_hz[0],
            t.band_hz[1],
            t.error,
            t.margin,
            p.a,
            p.decay_per_s,
            p.f_n,
            p.f_d,
            p.slip * 100.0,
            p.jitter * 100.0
        );
        let errors: Vec<String> = t
            .fits
            .iter()
            .map(|f| format!("{} {:.3}", f.fault.name(), f.error))
            .collect();
        let _ = writeln!(out, "    errors per hypothesis: {}", errors.join(", "));
        let _ = writeln!(
            out,
            "    unexplained: {:.0} % of the envelope spectrum's energy; largest residual peak {:.1} Hz; time residual {:.2}",
            t.residual.energy_ratio * 100.0,
            t.residual.largest_peak_hz,
            t.residual.time_energy_ratio
        );
        let _ = writeln!(out, "    {}", t.note);
    }
    if let Some(l) = r.learned.as_ref().filter(|l| l.opinion.segments > 0) {
        let probabilities: Vec<String> = l
            .opinion
            .probabilities
            .iter()
            .map(|(class, p)| format!("{} {:.0} %", class.name(), 100.0 * p))
            .collect();
        let _ = writeln!(
            out,
            "  learned ({}, {} segments): {}; the envelope alone: {}",
            l.opinion.model,
            l.opinion.segments,
            probabilities.join(", "),
            l.envelope_diagnosis
        );
    }
    let race_fault = [FaultKind::OuterRace, FaultKind::InnerRace]
        .iter()
        .any(|f| f.name() == r.diagnosis);
    match (&r.defect_size_mm, &r.defect_size_note) {
        (Some(size), _) => {
            let _ = writeln!(
                out,
                "  defect size: {:.2} ± {:.2} mm (entry to exit {:.3} ms over {} impacts; {})",
                size.value, size.uncertainty, size.delay_ms, size.impacts, size.method
            );
        }
        (None, Some(note)) if race_fault => {
            let _ = writeln!(out, "  defect size: not reported: {note}");
        }
        _ => {}
    }
    let i = &r.indicators;
    let _ = writeln!(
        out,
        "  indicators: RMS {:.4} g, peak {:.3} g, crest {:.2}, kurtosis {:.2}",
        i.rms, i.peak, i.crest, i.kurtosis
    );
    if let Some(v) = &r.velocity {
        let _ = writeln!(out, "  {}", v.summary());
    }
    for line in &r.detector_lines {
        let _ = writeln!(out, "  {line}");
    }
    for note in &r.notes {
        let _ = writeln!(out, "  note: {note}");
    }
    for w in &r.warnings {
        let _ = writeln!(out, "  warning: {w}");
    }
    let _ = writeln!(
        out,
        "  diagnosis: {} (confidence {:.2}): {}",
        r.diagnosis.to_uppercase(),
        r.confidence,
        r.reason
    );
    out
}
