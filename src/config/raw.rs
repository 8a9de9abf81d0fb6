//! The raw form: what the file says, read by serde without judgement.
//!
//! Every table denies unknown keys (a misspelt key must not silently fall back to a default),
//! and every leaf is `Option<Loose<T>>`: `None` when the key is absent (the validator applies the
//! default or reports it missing), [`Loose::WrongType`] when it holds the wrong TOML type. So a
//! string where a number belongs does not stop serde; the validator reports it together with
//! every other problem.

use serde::de::{DeserializeOwned, Deserializer};
use serde::Deserialize;

/// A value as written: either of the expected TOML type, or not.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Loose<T> {
    Value(T),
    /// The key held another type; `found` describes what, for the message
    /// (e.g. `the string "fast"`).
    WrongType {
        found: String,
    },
}

impl<'de, T: DeserializeOwned> Deserialize<'de> for Loose<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let value = toml::Value::deserialize(deserializer)?;
        let found = describe(&value);
        Ok(match T::deserialize(value) {
            Ok(v) => Loose::Value(v),
            Err(_) => Loose::WrongType { found },
        })
    }
}

/// A leaf key: absent, or present with the right or the wrong type.
pub(crate) type Field<T> = Option<Loose<T>>;

/// Describes a TOML value for an error message, short enough for one line.
fn describe(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => {
            let mut shown: String = s.chars().take(40).collect();
            if shown.len() < s.len() {
                shown.push('…');
            }
            format!("the string {shown:?}")
        }
        toml::Value::Integer(i) => format!("the whole number {i}"),
        toml::Value::Float(f) => format!("the number {f}"),
        toml::Value::Boolean(b) => format!("the boolean {b}"),
        toml::Value::Datetime(d) => format!("the date-time {d}"),
        toml::Value::Array(a) => format!("a list of {} item(s)", a.len()),
        toml::Value::Table(_) => "a table".to_string(),
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(crate) struct RawConfig {
    pub sensors: Vec<RawSensor>,
    pub analysis: RawAnalysis,
    pub twin: RawTwin,
    pub thresholds: RawThresholds,
    pub outputs: RawOutputs,
    pub fleet: RawFleet,
    pub severity: RawSeverity,
    /// `[detectors.<name>]`: read by serde into the detectors' own settings
    /// ([`crate::analysis::detectors`]), checked there.
    pub detectors: crate::analysis::detectors::DetectorSettings,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSensor {
    pub id: Field<String>,
    pub transport: Field<String>,
    pub sample_rate_hz: Field<f64>,
    pub scale_g_per_count: Field<f64>,
    pub axes: Field<Vec<String>>,
    pub bearing: Field<String>,
    pub speed: Option<RawSpeed>,
    pub can: Option<RawCan>,
    pub shm: Option<RawShm>,
    pub sim: Option<RawSim>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSpeed {
    /// `"fixed"`, `"can"` or `"estimate"`.
    pub source: Field<String>,
    pub rpm: Field<f64>,
    /// `"can"` only.
    pub max_rpm: Field<f64>,
    /// `"estimate"` only.
    pub search: Field<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCan {
    pub interface: Field<String>,
    pub node_id: Field<i64>,
    pub fd: Field<bool>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawShm {
    pub service: Field<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSim {
    pub fault: Field<String>,
    pub onset_s: Field<f64>,
    pub severity: Field<f64>,
    pub noise_g: Field<f64>,
    pub imbalance_g: Field<f64>,
    pub seed: Field<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAnalysis {
    pub window_s: Field<f64>,
    pub overlap: Field<f64>,
    pub averages: Field<i64>,
    pub band_selection: Field<String>,
    pub band_hz: Field<Vec<f64>>,
    pub refine_band_by_snr: Field<bool>,
    pub band_period_s: Field<f64>,
    pub evidence_horizon_s: Field<f64>,
    pub min_band_hz: Field<f64>,
    pub fault_tolerance: Field<f64>,
    pub harmonics: Field<i64>,
    pub false_alarm_rate: Field<f64>,
    pub min_fault_score: Field<f64>,
    pub min_score_ratio: Field<f64>,
    pub lone_fault_score: Field<f64>,
    pub lone_score_ratio: Field<f64>,
    pub agreement_probability: Field<f64>,
    pub agreement_fault_score: Field<f64>,
    pub agreement_score_ratio: Field<f64>,
    pub agreement_significance_relief: Field<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTwin {
    pub refit_period_s: Field<f64>,
    pub window_s: Field<f64>,
    pub hw_enabled: Field<bool>,
    pub hw_order: Field<i64>,
    pub hw_samples: Field<i64>,
    pub hw_baseline_fits: Field<i64>,
    pub learned_model: Field<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawThresholds {
    pub watch_score: Field<f64>,
    pub alarm_score: Field<f64>,
    pub clear_ratio: Field<f64>,
    pub on_delay_s: Field<f64>,
    pub off_delay_s: Field<f64>,
    pub baseline_windows: Field<i64>,
    pub sigma: Field<f64>,
    pub trend_point_s: Field<f64>,
    pub trend_points: Field<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawOutputs {
    pub state_dir: Field<String>,
    pub mcap_dir: Field<String>,
    pub mcap_max_file_mb: Field<i64>,
    pub mcap_max_file_s: Field<f64>,
    pub mcap_fsync_interval_s: Field<f64>,
    pub mcap_disk_budget_mb: Field<i64>,
    pub alerts_service: Field<String>,
    pub iceoryx2_root: Field<String>,
    pub status_interval_s: Field<f64>,
    pub state_save_interval_s: Field<f64>,
    pub cpu_wakeup_latency_us: Field<i64>,
    pub cpu_awake_during_analysis: Field<bool>,
}

/// `[severity]`: the machine the ISO 10816-3 / 20816-3 velocity zones are judged for.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSeverity {
    pub machine_group: Field<i64>,
    pub foundation: Field<String>,
}

/// `[fleet]`: the fleet bridge over MQTT Sparkplug B.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFleet {
    pub enabled: Field<bool>,
    pub broker: Field<String>,
    pub group_id: Field<String>,
    pub node_id: Field<String>,
    pub client_id: Field<String>,
    pub username: Field<String>,
    pub password_file: Field<String>,
    pub ca_file: Field<String>,
    pub client_cert_file: Field<String>,
    pub client_key_file: Field<String>,
    pub publish_period_s: Field<f64>,
    pub keep_alive_s: Field<f64>,
    pub queue_dir: Field<String>,
    pub queue_max_mb: Field<f64>,
    pub primary_host_id: Field<String>,
}
