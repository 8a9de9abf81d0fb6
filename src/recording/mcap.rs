//! The MCAP logs `bearingd run` writes, read as a recording of one channel.
//!
//! What the log states is used, and said: the sample rate travels in every raw block, the
//! scale to g too; the shaft speed is on `/speed/<sensor>/<axis>` (speed frames or estimates)
//! or, for a fixed speed, in the indicators the daemon logged (`/indicators/...`, the speed it
//! scored with). The bearing's geometry is not in the log yet; the caller decides (see
//! `offline`). Blocks are joined in log order; gaps, overlaps (a sensor restart) and a change
//! of sample rate are counted and reported, an unfinished file (a crash) is read as far as it
//! is valid, with a warning.
//!
//! For a life over logs (`trend`), [`read_log`] also gives what the recording alone cannot:
//! the log's wall-clock anchor (`log_time_origin_ns` of its `bearingd.run` record), the runs of
//! contiguous samples (so that a gap is shown as one, not joined over), and the HW fits the
//! daemon logged on `/hw/<sensor>/<axis>` (so that they are not identified again).
//!
//! Coupling: only [`crate::mcap_log::read_messages`], [`crate::mcap_log::read_header`] and the
//! message types; the log reader may move (the module "house"), this file should not need to.

use super::{Recording, RecordingError, RecordingFormat, SampleUnit};
use crate::mcap_log::{read_header, read_messages, LoggedMessage};
use crate::messages::PipelineMessage;
use std::collections::BTreeSet;
use std::path::Path;

/// Most samples of one channel kept (2^24: 11 minutes at 25.6 kHz, 128 MiB): `analyze` holds
/// the record in memory. Longer logs are analysed over their first part, with a warning.
const MAX_SAMPLES: usize = 1 << 24;

/// A speed the log states: for a channel, from a sample on.
struct StatedSpeed {
    channel: String,
    from_sample: u64,
    rpm: f64,
    /// `can`, `estimate`, or `indicators` (the speed a score was computed with).
    source: String,
}

/// The chosen channel's samples as they are joined.
struct Joined {
    name: String,
    fs_hz: f64,
    first_sample: u64,
    next_sample: u64,
    samples: Vec<f64>,
    /// Samples of this channel in the log beyond what was kept.
    dropped_samples: u64,
    gaps: u64,
    missing_samples: u64,
    overlaps: u64,
    rate_change: Option<(u64, f64)>,
    /// Runs of contiguous samples, in the order they were kept.
    segments: Vec<Segment>,
}

/// Samples `[offset, offset + len)` of the joined recording are the log's samples
/// `[first_sample, first_sample + len)`, with no gap and no step back inside.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    pub offset: usize,
    pub first_sample: u64,
    pub len: usize,
}

/// One HW fit the daemon logged for the channel (`/hw/<sensor>/<axis>`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoggedHwFit {
    /// One past the last sample of the fit's signal (the log's sample count).
    pub end_sample: u64,
    /// `100·(1 − NRMSE)` of its free run (%); `None` when the daemon could identify no model.
    pub accuracy_simulation: Option<f64>,
}

/// What places a log's samples in time, beside its recording.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogPlacement {
    /// Wall-clock time of the log's sample 0, ns since the epoch (`log_time_origin_ns`);
    /// `None` for a log without the `bearingd.run` record (an older bearingd).
    pub origin_ns: Option<u64>,
    /// The run's id: the same in every file of one run of the daemon.
    pub run_id: Option<u64>,
    /// The runs of contiguous samples of `recording.samples`, in order.
    pub segments: Vec<Segment>,
    /// The HW fits the daemon logged for this channel, in log order.
    pub hw_fits: Vec<LoggedHwFit>,
    /// `twin.hw_enabled` of the configuration the log records: whether the daemon fitted the
    /// HW model at all (a file may hold no fit yet: cut before the first re-fit); `None` when
    /// the log does not say.
    pub hw_enabled: Option<bool>,
}

impl Joined {
    fn push(&mut self, first_sample: u64, fs_hz: f64, scale: f64, counts: &[i32]) {
        if self.rate_change.is_some() || self.samples.len() >= MAX_SAMPLES {
            self.dropped_samples += counts.len() as u64;
            return;
        }
        if fs_hz != self.fs_hz {
            self.rate_change = Some((first_sample, fs_hz));
            self.dropped_samples += counts.len() as u64;
            return;
        }
        if first_sample > self.next_sample {
            self.gaps += 1;
            self.missing_samples += first_sample - self.next_sample;
        } else if first_sample < self.next_sample {
            self.overlaps += 1;
        }
        let room = MAX_SAMPLES - self.samples.len();
        let take = counts.len().min(room);
        match self.segments.last_mut() {
            Some(last) if first_sample == self.next_sample => last.len += take,
            _ => self.segments.push(Segment {
                offset: self.samples.len(),
                first_sample,
                len: take,
            }),
        }
        self.samples
            .extend(counts[..take].iter().map(|&c| f64::from(c) * scale));
        self.dropped_samples += (counts.len() - take) as u64;
        self.next_sample = first_sample + counts.len() as u64;
    }
}

fn matches(wanted: &str, name: &str) -> bool {
    let wanted = wanted.trim_start_matches('/');
    let wanted = wanted.strip_prefix("raw/").unwrap_or(wanted);
    wanted.eq_ignore_ascii_case(name)
}

pub(super) fn channels(path: &Path) -> Result<Vec<String>, RecordingError> {
    let mut names = BTreeSet::new();
    let mut first_error = None;
    for item in read_messages(&[path]) {
        match item {
            Ok(LoggedMessage {
                message: PipelineMessage::Raw(b),
                ..
            }) => {
                names.insert(b.channel.to_string());
            }
            Ok(_) => {}
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    match (names.is_empty(), first_error) {
        (true, Some(e)) => Err(bad_log(path, &e)),
        _ => Ok(names.into_iter().collect()),
    }
}

fn bad_log(path: &Path, e: &crate::mcap_log::McapLogError) -> RecordingError {
    let text = e.to_string();
    let shown = path.display().to_string();
    let detail = text
        .strip_prefix(&shown)
        .map(|t| t.trim_start_matches(':').trim_start())
        .unwrap_or(&text);
    RecordingError::BadLog {
        path: path.to_path_buf(),
        detail: format!(
            "{detail}; check that it is a log written by bearingd run or import (an unfinished one is read as far as it is valid)"
        ),
    }
}

pub(super) fn read(path: &Path, selector: Option<&str>) -> Result<Recording, RecordingError> {
    read_log(path, selector).map(|log| log.0)
}

/// Reads the log at `path` ([`read`]) with its anchor, runs of samples and logged HW fits.
pub fn read_log(
    path: &Path,
    selector: Option<&str>,
) -> Result<(Recording, LogPlacement), RecordingError> {
    let mut reader = read_messages(&[path]);
    let mut hw_fits: Vec<(String, LoggedHwFit)> = Vec::new();
    let mut joined: Option<Joined> = None;
    let mut others = BTreeSet::new();
    let mut speeds: Vec<StatedSpeed> = Vec::new();
    let mut errors = 0u64;
    let mut first_error = None;
    for item in reader.by_ref() {
        let logged = match item {
            Ok(logged) => logged,
            Err(e) => {
                errors += 1;
                first_error.get_or_insert(e);
                continue;
            }
        };
        match logged.message {
            PipelineMessage::Raw(block) => {
                let name = block.channel.to_string();
                let wanted = match (selector, &joined) {
                    (Some(s), _) => matches(s, &name),
                    (None, Some(j)) => j.name == name,
                    (None, None) => true,
                };
                if !wanted {
                    others.insert(name);
                    continue;
                }
                let j = joined.get_or_insert_with(|| Joined {
                    name,
                    fs_hz: block.sample_rate_hz,
                    first_sample: block.first_sample,
                    next_sample: block.first_sample,
                    samples: Vec::new(),
                    dropped_samples: 0,
                    gaps: 0,
                    missing_samples: 0,
                    overlaps: 0,
                    rate_change: None,
                    segments: Vec::new(),
                });
                j.push(
                    block.first_sample,
                    block.sample_rate_hz,
                    block.scale_g_per_count,
                    &block.counts,
                );
            }
            PipelineMessage::Speed(s) => speeds.extend(s.rpm.map(|rpm| StatedSpeed {
                channel: s.channel.to_string(),
                from_sample: s.end_sample,
                rpm,
                source: s.source.name().into(),
            })),
            PipelineMessage::Indicators(i) => speeds.push(StatedSpeed {
                channel: i.channel.to_string(),
                from_sample: i.end_sample,
                rpm: i.rpm,
                source: "indicators".into(),
            }),
            PipelineMessage::Hw(h) => hw_fits.push((
                h.channel.to_string(),
                LoggedHwFit {
                    end_sample: h.end_sample,
                    accuracy_simulation: (h.problem.is_none() && h.accuracy_simulation.is_finite())
                        .then_some(h.accuracy_simulation),
                },
            )),
            _ => {}
        }
    }
    let Some(j) = joined else {
        let unreadable = reader
            .summary()
            .files
            .iter()
            .find_map(|f| f.no_message_reason());
        if let Some(why) = unreadable {
            return Err(RecordingError::BadLog {
                path: path.to_path_buf(),
                detail: format!("{why}; analyse a log written by bearingd run or import"),
            });
        }
        if let (Some(e), true) = (&first_error, others.is_empty()) {
            return Err(bad_log(path, e));
        }
        return match selector {
            Some(wanted) if !others.is_empty() => Err(RecordingError::ChannelNotFound {
                path: path.to_path_buf(),
                kind: "channel",
                wanted: wanted.to_string(),
                available: others.into_iter().collect(),
            }),
            _ => Err(RecordingError::Empty {
                path: path.to_path_buf(),
                detail: "the log holds no raw samples (no /raw/<sensor>/<axis> topic); analyse a log written by bearingd run or import".to_string(),
            }),
        };
    };
    if selector.is_none() && !others.is_empty() {
        let mut all: Vec<String> = others.into_iter().collect();
        all.push(j.name.clone());
        all.sort();
        return Err(RecordingError::AmbiguousLogChannel {
            path: path.to_path_buf(),
            channels: all,
        });
    }
    let mut warnings = Vec::new();
    let summary = reader.summary();
    if summary.unfinished_files() > 0 {
        warnings.push(format!(
            "the log is unfinished (bearingd did not close it: a crash or a copy taken while it ran); read up to its last complete chunk, {} byte(s) could not be read",
            summary.unreadable_bytes()
        ));
    }
    if errors > 0 {
        let first = first_error.map(|e| e.to_string()).unwrap_or_default();
        warnings.push(format!(
            "{errors} message(s) could not be decoded and were skipped; the first: {first}"
        ));
    }
    if j.gaps > 0 {
        warnings.push(format!(
            "{} gap(s) in the samples ({} sample(s) missing, lost before logging); the blocks were joined end to end",
            j.gaps, j.missing_samples
        ));
    }
    if j.overlaps > 0 {
        warnings.push(format!(
            "{} time(s) the sample count went back (a sensor restart); the blocks were joined end to end",
            j.overlaps
        ));
    }
    if let Some((at, fs)) = j.rate_change {
        warnings.push(format!(
            "the sample rate changes from {} Hz to {fs} Hz at sample {at}; analysed the part before",
            j.fs_hz
        ));
    } else if j.dropped_samples > 0 {
        warnings.push(format!(
            "analysed the first {:.0} s of the channel; the log holds {:.0} s more (replay it with bearingd replay to follow it through time)",
            j.samples.len() as f64 / j.fs_hz,
            j.dropped_samples as f64 / j.fs_hz
        ));
    }
    let end = j.first_sample + j.samples.len() as u64;
    let rpm = speed_of(&speeds, j.first_sample, end, &j.name, &mut warnings);
    let fs_hz = (j.fs_hz.is_finite() && j.fs_hz > 0.0).then_some(j.fs_hz);
    // The header is read again from the start: it stops at the first message, so it costs a
    // chunk at most. A log without it (an older bearingd) has no anchor.
    let header = read_header(path).ok();
    let hw_fits = hw_fits
        .into_iter()
        .filter(|(channel, _)| *channel == j.name)
        .map(|(_, fit)| fit)
        .collect();
    let placement = LogPlacement {
        origin_ns: header.as_ref().and_then(|h| h.origin_ns),
        run_id: header.as_ref().and_then(|h| h.run_id),
        segments: j.segments,
        hw_fits,
        hw_enabled: header
            .as_ref()
            .and_then(|h| h.config_json.as_deref())
            .and_then(|json| serde_json::from_str::<serde_json::Value>(json).ok())
            .and_then(|config| config["twin"]["hw_enabled"].as_bool()),
    };
    let recording = Recording {
        path: path.to_path_buf(),
        format: RecordingFormat::McapLog,
        channel: j.name,
        fs_hz,
        rpm,
        samples: j.samples,
        warnings,
        unit: SampleUnit::G,
        notes: Vec::new(),
    };
    Ok((recording, placement))
}

/// The speed over samples `[start, end)` of `channel`: the median of the speeds stated on its
/// speed topic up to `end`, else of those its indicators were computed with; a warning says
/// which and how much it varied.
fn speed_of(
    speeds: &[StatedSpeed],
    start: u64,
    end: u64,
    channel: &str,
    warnings: &mut Vec<String>,
) -> Option<f64> {
    let usable = |s: &&StatedSpeed| {
        s.channel == channel && s.from_sample <= end && s.rpm.is_finite() && s.rpm > 0.0
    };
    let stated: Vec<&StatedSpeed> = speeds
        .iter()
        .filter(usable)
        .filter(|s| s.source != "indicators")
        .collect();
    let (chosen, from) = if stated.is_empty() {
        let scored: Vec<&StatedSpeed> = speeds
            .iter()
            .filter(usable)
            .filter(|s| s.source == "indicators" && s.from_sample > start)
            .collect();
        (
            scored,
            format!("/indicators/{channel} (the speed the daemon scored with)"),
        )
    } else {
        let sources: BTreeSet<&str> = stated.iter().map(|s| s.source.as_str()).collect();
        let sources: Vec<&str> = sources.into_iter().collect();
        (stated, format!("/speed/{channel} ({})", sources.join(", ")))
    };
    let mut sorted: Vec<f64> = chosen.iter().map(|s| s.rpm).collect();
    if sorted.is_empty() {
        return None;
    }
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
    if hi > lo * 1.01 {
        warnings.push(format!(
            "the speed varies from {lo:.1} to {hi:.1} rpm over the log ({from}); analysed at the median {median:.1} rpm: fault lines blur where it differs by more than the slip tolerance, give --rpm or analyse a shorter log"
        ));
    } else {
        warnings.push(format!("speed {median:.1} rpm from {from}"));
    }
    Some(median)
}
