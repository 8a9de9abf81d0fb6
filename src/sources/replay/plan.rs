//! What to replay, decided before the first sample: the files in run order, the runs they
//! form, and the settings the log was recorded with.
//!
//! Why: a replay is only faithful if it analyses with the recording's sample rate, geometry and
//! thresholds (not today's config), feeds each run's files in the order they were written
//! (whatever order the shell's glob gives), and starts afresh where the daemon restarted, since
//! sample time starts again at 0 there. All of that is in the files' metadata records
//! ([`crate::mcap_log::header`]); this module reads it and says what it found, and the caller
//! decides (and prints) what to do with a disagreement.

use crate::config::{config_from_log, Config};
use crate::mcap_log::{read_header, LogHeader, McapLogError};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The files of a replay in the order to read them, grouped into runs.
#[derive(Debug, Clone)]
pub struct ReplayPlan {
    /// In replay order: by run id, then sequence; files without metadata first, in the order
    /// given (they were written by an older bearingd, or by `bearingd import`).
    pub files: Vec<LogHeader>,
    /// The replay order is not the order given.
    pub reordered: bool,
    /// Consecutive files of one run (`files[range]`).
    pub runs: Vec<PlannedRun>,
    /// Sequence numbers missing inside a run: a file not given, or deleted by retention.
    pub missing: Vec<MissingFile>,
}

/// One run of the daemon: from a start to a stop (or crash).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlannedRun {
    /// `None`: files without metadata (treated as one run, as before metadata existed).
    pub run_id: Option<u64>,
    /// Wall-clock time of the run's sample 0, from its metadata.
    pub origin_ns: Option<u64>,
    /// The health baselines the run started with (its `bearingd.state` record), as JSON.
    pub start_baselines_json: Option<String>,
    pub files: Range<usize>,
}

/// A file of a run that is not among those given.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct MissingFile {
    pub run_id: u64,
    pub sequence: u64,
    /// The file after which it should have come.
    pub after: PathBuf,
}

impl ReplayPlan {
    /// Reads the header of every file of `paths` and orders them. Fails only when a file
    /// cannot be opened; a file whose header cannot be read is replayed as one without
    /// metadata (the reader then says how much of it was unreadable).
    pub fn new(paths: &[PathBuf]) -> Result<ReplayPlan, McapLogError> {
        let given = paths
            .iter()
            .map(|p| read_header(p))
            .collect::<Result<Vec<_>, _>>()?;
        let mut files = given.clone();
        // Stable: files without a run id keep the order given.
        files.sort_by_key(|h| h.run_id.map(|run| (run, h.sequence.unwrap_or(0))));
        let reordered = files
            .iter()
            .map(|h| &h.path)
            .ne(given.iter().map(|h| &h.path));
        let mut runs: Vec<PlannedRun> = Vec::new();
        let mut missing = Vec::new();
        for (i, file) in files.iter().enumerate() {
            match runs.last_mut() {
                Some(run) if run.run_id == file.run_id => {
                    if let (Some(run_id), Some(seq), Some(before)) =
                        (file.run_id, file.sequence, files[i - 1].sequence)
                    {
                        missing.extend((before + 1..seq).map(|sequence| MissingFile {
                            run_id,
                            sequence,
                            after: files[i - 1].path.clone(),
                        }));
                    }
                    run.files.end = i + 1;
                }
                _ => runs.push(PlannedRun {
                    run_id: file.run_id,
                    origin_ns: file.origin_ns,
                    start_baselines_json: file.start_baselines_json.clone(),
                    files: i..i + 1,
                }),
            }
        }
        Ok(ReplayPlan {
            files,
            reordered,
            runs,
            missing,
        })
    }

    /// The paths of `run`'s files, in order.
    pub fn paths(&self, run: &PlannedRun) -> Vec<PathBuf> {
        self.files[run.files.clone()]
            .iter()
            .map(|h| h.path.clone())
            .collect()
    }

    /// Total bytes of every file.
    pub fn bytes(&self) -> u64 {
        self.files.iter().map(|h| h.bytes).sum()
    }

    /// The analysis settings the files were recorded with.
    pub fn logged_settings(&self) -> LoggedSettings {
        let mut groups: Vec<(serde_json::Value, String, Vec<PathBuf>)> = Vec::new();
        let mut without = Vec::new();
        for file in &self.files {
            let Some(json) = &file.config_json else {
                without.push(file.path.clone());
                continue;
            };
            let Ok(value) = serde_json::from_str::<serde_json::Value>(json) else {
                return LoggedSettings::Unusable {
                    path: file.path.clone(),
                    problem: "its bearingd.config record is not JSON".into(),
                };
            };
            let view = analysis_view(value);
            match groups.iter_mut().find(|g| g.0 == view) {
                Some(group) => group.2.push(file.path.clone()),
                None => groups.push((view, json.clone(), vec![file.path.clone()])),
            }
        }
        match groups.len() {
            0 => LoggedSettings::Absent,
            1 => {
                let (_, json, _) = groups.remove(0);
                match config_from_log(&json) {
                    Ok(config) => LoggedSettings::Logged {
                        config: Box::new(config),
                        files_without: without,
                    },
                    Err(problem) => LoggedSettings::Unusable {
                        path: self
                            .files
                            .iter()
                            .find(|f| f.config_json.is_some())
                            .map(|f| f.path.clone())
                            .unwrap_or_default(),
                        problem,
                    },
                }
            }
            _ => LoggedSettings::Disagree(groups.into_iter().map(|g| g.2).collect()),
        }
    }
}

/// What the files say about the settings they were recorded with.
#[derive(Debug, Clone)]
pub enum LoggedSettings {
    /// Every file with metadata has the same settings; `files_without` carry none.
    Logged {
        config: Box<Config>,
        files_without: Vec<PathBuf>,
    },
    /// No file carries them (an older bearingd, `bearingd import`).
    Absent,
    /// Groups of files with different settings.
    Disagree(Vec<Vec<PathBuf>>),
    /// A file's logged settings cannot be used.
    Unusable { path: PathBuf, problem: String },
}

/// The part of a logged config that shapes the analysis: without `[outputs]`, `[fleet]` and
/// where the samples came from (a run with another data directory analysed the same way).
fn analysis_view(mut config: serde_json::Value) -> serde_json::Value {
    if let Some(object) = config.as_object_mut() {
        object.remove("outputs");
        object.remove("fleet");
        if let Some(sensors) = object.get_mut("sensors").and_then(|s| s.as_array_mut()) {
            for sensor in sensors.iter_mut().filter_map(|s| s.as_object_mut()) {
                sensor.remove("transport");
            }
        }
    }
    config
}

/// How `given` (a `--config`) differs from `logged` in what shapes the analysis, one line
/// each: per logged sensor its rate, scale, axes, bearing and speed; then each section.
pub fn differences(logged: &Config, given: &Config) -> Vec<String> {
    let mut out = Vec::new();
    for l in &logged.sensors {
        let Some(g) = given.sensors.iter().find(|g| g.id == l.id) else {
            out.push(format!(
                "sensor {} of the log is not in --config (its samples are skipped)",
                l.id
            ));
            continue;
        };
        let mut differ = |what: &str, log: String, now: String| {
            if log != now {
                out.push(format!("sensor {}: {what} {now} (log: {log})", l.id));
            }
        };
        differ(
            "sample_rate_hz",
            l.sample_rate_hz.to_string(),
            g.sample_rate_hz.to_string(),
        );
        differ(
            "scale_g_per_count",
            l.scale_g_per_count.to_string(),
            g.scale_g_per_count.to_string(),
        );
        differ("axes", l.axes.join(","), g.axes.join(","));
        differ("bearing", geometry(&l.bearing), geometry(&g.bearing));
        differ("speed", format!("{:?}", l.speed), format!("{:?}", g.speed));
    }
    for (section, same) in [
        (
            "[analysis]",
            logged.analysis == given.analysis
                && logged.band_period_s == given.band_period_s
                && logged.evidence_horizon_s == given.evidence_horizon_s,
        ),
        ("[twin]", logged.twin == given.twin),
        ("[thresholds]", logged.thresholds == given.thresholds),
        ("[severity]", logged.severity == given.severity),
    ] {
        if !same {
            out.push(format!("{section} differs"));
        }
    }
    out
}

fn geometry(b: &crate::bearing::BearingGeometry) -> String {
    format!(
        "{} (z={}, d={} mm, D={} mm, {}°)",
        b.name, b.rolling_elements, b.element_diameter_mm, b.pitch_diameter_mm, b.contact_angle_deg
    )
}

/// The file names of `paths`, comma-separated.
pub fn file_list(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| {
            p.file_name()
                .map_or(p.as_path(), Path::new)
                .display()
                .to_string()
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_default_round_trips_through_its_logged_json() {
        let config = Config::default_embedded().unwrap();
        let json = serde_json::to_string(&config).unwrap();
        assert_eq!(config_from_log(&json).unwrap(), config);
    }

    #[test]
    fn a_logged_config_with_a_zero_rate_is_refused_naming_it() {
        let mut config = Config::default_embedded().unwrap();
        config.sensors[0].sample_rate_hz = 0.0;
        let json = serde_json::to_string(&config).unwrap();
        let problem = config_from_log(&json).unwrap_err();
        assert!(problem.contains("sample_rate_hz 0"), "{problem}");
    }

    #[test]
    fn differences_name_the_rate_and_the_bearing() {
        let logged = Config::default_embedded().unwrap();
        let mut given = logged.clone();
        assert!(differences(&logged, &given).is_empty());
        given.sensors[0].sample_rate_hz = 12_800.0;
        given.sensors[0].bearing.rolling_elements = 8;
        given.thresholds.alarm_score = 12.0;
        let lines = differences(&logged, &given);
        assert_eq!(lines.len(), 3, "{lines:?}");
        assert!(lines[0].contains("sample_rate_hz 12800 (log: 25600)"));
        assert!(lines[1].contains("bearing") && lines[1].contains("z=8"));
        assert_eq!(lines[2], "[thresholds] differs");
    }
}
