//! The configuration a log records (its `bearingd.config` metadata record), read back for
//! `replay` and `analyze`: the log carries the settings it was recorded with.

use super::Config;

/// The configuration a log was recorded with, from its `bearingd.config` record. It was
/// validated when it was written; a damaged or hand-edited record is checked here for what
/// the analysis divides by or sizes buffers with, so that it is refused, not a panic.
pub fn config_from_log(json: &str) -> Result<Config, String> {
    let config: Config = serde_json::from_str(json)
        .map_err(|e| format!("its bearingd.config record is not a bearingd config: {e}"))?;
    let mut problems = Vec::new();
    let mut check = |ok: bool, what: String| {
        if !ok {
            problems.push(what);
        }
    };
    let positive = |x: f64| x.is_finite() && x > 0.0;
    check(!config.sensors.is_empty(), "no sensor".into());
    for s in &config.sensors {
        check(
            positive(s.sample_rate_hz) && s.sample_rate_hz <= 1e6,
            format!("sensor {}: sample_rate_hz {}", s.id, s.sample_rate_hz),
        );
        check(
            positive(s.scale_g_per_count),
            format!("sensor {}: scale_g_per_count", s.id),
        );
        check(!s.axes.is_empty(), format!("sensor {}: no axis", s.id));
        check(
            positive(s.speed.max_rpm()),
            format!("sensor {}: speed", s.id),
        );
    }
    let a = &config.analysis;
    check(
        positive(a.window_s) && a.window_s <= 60.0,
        "analysis.window_s".into(),
    );
    check((0.0..1.0).contains(&a.overlap), "analysis.overlap".into());
    check(
        (1..=1024).contains(&a.averages) && (1..=100).contains(&a.harmonics),
        "analysis.averages or harmonics".into(),
    );
    check(
        positive(config.band_period_s),
        "analysis.band_period_s".into(),
    );
    check(
        positive(config.evidence_horizon_s) && config.evidence_horizon_s <= 3600.0,
        "analysis.evidence_horizon_s".into(),
    );
    check(
        positive(config.twin.refit_period_s) && positive(config.twin.window_s),
        "twin".into(),
    );
    check(
        config.thresholds.baseline_windows >= 1,
        "thresholds.baseline_windows".into(),
    );
    if problems.is_empty() {
        Ok(config)
    } else {
        Err(format!(
            "its bearingd.config record has unusable values: {}",
            problems.join(", ")
        ))
    }
}
