//! What makes a log file self-describing: MCAP metadata records at the start of every file,
//! so that a file read years later, on another machine, says what it holds without the config
//! it was recorded with.
//!
//! Records (all values are strings, as MCAP metadata is):
//! - `bearingd.run`: `version`, `host`, `run_id` (the run's start as ns since the epoch, the
//!   same in every file of a run), `log_time_origin_ns` and `log_time_origin_utc` (the
//!   wall-clock time of sample 0: log time = origin + sample index / sample rate),
//!   `time_base`.
//! - `bearingd.config`: `json`, the resolved configuration.
//! - `bearingd.channel`, one per sensor axis: `channel`, `topic`, `sample_rate_hz`, `unit`
//!   (`g`), `scale_g_per_count`, `bearing` (name) and `bearing_geometry` (JSON).
//! - `bearingd.state`: `baselines_json` and `channels`: the health baselines the run started
//!   with (loaded from `baselines.json`; `[]` when it learns from scratch), so that a replay
//!   starts every run where the daemon did.
//! - `bearingd.file`: `sequence` (1 for the first file of the run, 2 after the first
//!   rotation, ...) and `opened_at_utc`; written by the logger itself.

use crate::analysis::health::{baselines_to_json, Baseline};
use crate::config::Config;
use crate::mcap_log::files::utc_text;
use crate::mcap_log::header::{
    CHANNEL_RECORD, CONFIG_RECORD, FILE_RECORD, RUN_RECORD, STATE_RECORD,
};
use crate::messages::ChannelId;
use std::collections::BTreeMap;

/// One metadata record: name and key/value pairs.
pub type MetadataRecord = (String, BTreeMap<String, String>);

fn record(name: &str, pairs: impl IntoIterator<Item = (&'static str, String)>) -> MetadataRecord {
    (
        name.to_string(),
        pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
    )
}

/// The records every file of a run carries (all but `bearingd.file`), for `config` and a log
/// whose sample 0 is at `origin_ns`, in the run that started at `run_id` with `baselines`.
pub fn run_records(
    config: &Config,
    origin_ns: u64,
    run_id: u64,
    baselines: &BTreeMap<ChannelId, Baseline>,
) -> Vec<MetadataRecord> {
    let mut records = vec![
        record(
            RUN_RECORD,
            [
                ("version", env!("CARGO_PKG_VERSION").to_string()),
                ("host", host_name()),
                ("run_id", run_id.to_string()),
                ("log_time_origin_ns", origin_ns.to_string()),
                ("log_time_origin_utc", utc_text(origin_ns)),
                (
                    "time_base",
                    "log_time = log_time_origin_ns + sample index / sample_rate_hz, in ns since \
                     the Unix epoch (UTC)"
                        .to_string(),
                ),
            ],
        ),
        record(
            CONFIG_RECORD,
            [(
                "json",
                serde_json::to_string(config).unwrap_or_else(|e| format!("unserialisable: {e}")),
            )],
        ),
    ];
    records.push(record(
        STATE_RECORD,
        [
            (
                "baselines_json",
                baselines_to_json(baselines).unwrap_or_else(|e| format!("unserialisable: {e}")),
            ),
            ("channels", baselines.len().to_string()),
        ],
    ));
    for sensor in &config.sensors {
        for axis in &sensor.axes {
            let channel = format!("{}/{axis}", sensor.id);
            records.push(record(
                CHANNEL_RECORD,
                [
                    ("topic", format!("/raw/{channel}")),
                    ("channel", channel),
                    ("sample_rate_hz", sensor.sample_rate_hz.to_string()),
                    ("unit", "g".to_string()),
                    ("scale_g_per_count", sensor.scale_g_per_count.to_string()),
                    ("bearing", sensor.bearing.name.clone()),
                    (
                        "bearing_geometry",
                        serde_json::to_string(&sensor.bearing).unwrap_or_default(),
                    ),
                ],
            ));
        }
    }
    records
}

/// The `bearingd.file` record of the `sequence`-th file of a run, opened at `opened_at_ns`.
pub fn file_record(sequence: u64, opened_at_ns: u64) -> MetadataRecord {
    record(
        FILE_RECORD,
        [
            ("sequence", sequence.to_string()),
            ("opened_at_utc", utc_text(opened_at_ns)),
        ],
    )
}

/// This machine's name, as the kernel has it (`unknown` when it cannot be read).
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .ok()
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".to_string())
}
