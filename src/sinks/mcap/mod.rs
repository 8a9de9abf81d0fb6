//! The MCAP log as a sink: the writer with rotation and a disk budget ([`writer`]), the
//! start-up recovery of files a crash left unfinished ([`recover`]), and [`McapSink`], which
//! maps sample time to log time, flushes the open chunk every second of data (a crash loses at
//! most that), forces it to the disk every `mcap_fsync_interval_s` of data (what a power cut
//! loses), recovers unfinished files at start, and finishes the file at shutdown. It also
//! begins every file opened by rotation with the current state (`/state`), writes a `/log`
//! note for each retention deletion, and pauses logging when a write fails (a full disk)
//! without stopping the pipeline, resuming when the directory has room ([`LogNotice`]); the
//! flag changes and health events of the pause are held ([`late`]) and written first then,
//! marked late. The
//! format itself (schemas, topics, file names, reading back) is [`crate::mcap_log`]; what each
//! file says about itself in MCAP metadata records is [`metadata`]; a recording written as
//! such a log (`import`, `dataset`, `evaluate --recordings`) is [`raw_log`].

pub mod late;
pub mod metadata;
pub mod raw_log;
pub mod recover;
pub mod writer;

pub use late::{LateBacklog, LateCounts};
pub use recover::{
    is_finished, recover_directory, recover_file, RecoveryAction, RecoveryReport, QUARANTINE_DIR,
};
pub use writer::{enforce_budget, LogStats, LoggerConfig, McapLogger, RetentionReport, TopicStats};

use crate::analysis::health::Baseline;
use crate::config::Config;
use crate::mcap_log::schema::{LogLevel, StateSnapshot};
use crate::mcap_log::McapLogError;
use crate::messages::detect::Emitted;
use crate::messages::{
    ChannelId, DetectorMessage, FlagMessage, HealthMessage, PipelineMessage, TwinMessage,
    VelocityFlagMessage,
};
use crate::pipeline::{Sink, SinkError};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Nanoseconds of log time between two flushes.
const FLUSH_EVERY_NS: u64 = 1_000_000_000;
/// While logging is paused (a full disk), how often (log time) free space is looked at.
const RETRY_EVERY_NS: u64 = 1_000_000_000;

/// What the log tells its owner (the daemon says it to the operator).
#[derive(Debug, Clone)]
pub enum LogNotice {
    /// Retention deleted the oldest files (at start, or after a rotation).
    Retention(RetentionReport),
    /// Writing the open file failed (a full disk): it is left unfinished (recovered later),
    /// logging is paused; the analysis and the alerts go on.
    Paused {
        path: PathBuf,
        error: String,
        /// Log time of the last flush that reached the file: a crash-safe prefix up to here.
        flushed_until_ns: u64,
    },
    /// Logging goes on in `path` after a pause.
    Resumed {
        path: PathBuf,
        /// Messages the pipeline made while paused, not logged.
        messages_not_logged: u64,
        /// Log time from the last flush before the pause to the first message logged after it.
        seconds_not_logged: f64,
    },
    /// The flag changes and health events decided during the pause (and those logged since the
    /// last flush before it, lost with the unwritten chunk) were written in `path` at the
    /// resume, marked late; `dropped` did not fit in memory.
    LateWritten {
        path: PathBuf,
        written: LateCounts,
        dropped: LateCounts,
    },
    /// The daemon stopped while logging was still paused: what was held for the log was
    /// never written.
    LateLost {
        held: LateCounts,
        dropped: LateCounts,
    },
    /// A file left by a pause was recovered (or could not be, and waits for the next start).
    PausedFileRecovered(RecoveryReport),
    PausedFileNotRecovered {
        path: PathBuf,
        error: String,
    },
}

/// A pause of the log after a write failed.
struct Pause {
    /// Log time of the last flush that reached the disk before the failure.
    flushed_until_ns: u64,
    messages: u64,
    next_try_ns: u64,
    /// Files left unfinished by the failure, to recover when there is room.
    abandoned: Vec<PathBuf>,
    /// Flag changes and health events to write first when logging resumes.
    late: LateBacklog,
}

/// The current state per channel (last flag change per fault, last health per kind, last
/// twin fit, last ISO zone flag change), which begins every file opened by rotation.
#[derive(Default)]
struct CurrentState {
    flags: BTreeMap<String, FlagMessage>,
    health: BTreeMap<String, HealthMessage>,
    twin: BTreeMap<String, TwinMessage>,
    velocity_flags: BTreeMap<String, VelocityFlagMessage>,
}

impl CurrentState {
    fn note(&mut self, message: &PipelineMessage) {
        match message {
            PipelineMessage::Flag(m) => {
                self.flags
                    .insert(format!("{}/{:?}", m.channel, m.fault), m.clone());
            }
            PipelineMessage::Health(m) => {
                self.health
                    .insert(format!("{}/{:?}", m.channel, m.kind), m.clone());
            }
            PipelineMessage::Twin(m) => {
                self.twin.insert(m.channel.to_string(), m.clone());
            }
            // The snapshot's field for the ISO zone flag, which readers of `/state` know.
            PipelineMessage::Detector(DetectorMessage::Velocity(Emitted::Flag(m))) => {
                self.velocity_flags.insert(m.channel.to_string(), m.clone());
            }
            _ => {}
        }
    }

    fn snapshot(&self) -> StateSnapshot {
        StateSnapshot {
            flags: self.flags.values().cloned().collect(),
            health: self.health.values().cloned().collect(),
            twin: self.twin.values().cloned().collect(),
            velocity_flags: self.velocity_flags.values().cloned().collect(),
        }
    }
}

pub struct McapSink {
    logger: Option<McapLogger>,
    /// Log time of sample 0 of every channel, ns since the epoch.
    origin_ns: u64,
    /// Sample rate per sensor, to turn sample indices into time.
    rates: HashMap<String, f64>,
    next_flush_ns: u64,
    /// When the open file is next forced to the disk (`None`: never).
    next_sync_ns: Option<u64>,
    last_ns: u64,
    /// Log time of the last flush that reached the file.
    flushed_ns: u64,
    errors: Vec<McapLogError>,
    pub messages: u64,
    state: CurrentState,
    /// Flag changes and health events logged since the last flush that reached the file: a
    /// failure loses them with the open chunk, so a pause holds them to write late.
    since_flush: LateBacklog,
    pause: Option<Pause>,
    /// Told of retention, pauses and resumptions (the operator must know).
    on_notice: Box<dyn Fn(&LogNotice) + Send>,
}

impl McapSink {
    /// Recovers what a crash left in `config.dir`, then opens a new file. `origin_ns` is the
    /// log time of sample 0 (the daemon's start, or the original run's for a replay).
    pub fn open(
        config: LoggerConfig,
        rates: HashMap<String, f64>,
        origin_ns: u64,
    ) -> Result<(Self, Vec<RecoveryReport>), McapLogError> {
        crate::fsafe::create_dir_all(&config.dir).map_err(|source| McapLogError::Io {
            path: config.dir.clone(),
            op: "create the log directory",
            source,
        })?;
        let recovered = recover_directory(&config.dir)?;
        let next_sync_ns = config.fsync_every_ns.map(|every| origin_ns + every);
        let logger = McapLogger::create(config, origin_ns)?;
        Ok((
            McapSink {
                logger: Some(logger),
                origin_ns,
                rates,
                next_flush_ns: origin_ns + FLUSH_EVERY_NS,
                next_sync_ns,
                last_ns: origin_ns,
                flushed_ns: origin_ns,
                errors: Vec::new(),
                messages: 0,
                state: CurrentState::default(),
                since_flush: LateBacklog::default(),
                pause: None,
                on_notice: Box::new(|_| {}),
            },
            recovered,
        ))
    }

    /// [`open`](Self::open) with the log settings of `config`'s `[outputs]`, its sensors'
    /// sample rates, and the metadata that makes each file self-describing
    /// ([`metadata::run_records`]; the run is named by `origin_ns` and starts with
    /// `baselines`).
    pub fn for_config(
        config: &Config,
        origin_ns: u64,
        baselines: &BTreeMap<ChannelId, Baseline>,
    ) -> Result<(Self, Vec<RecoveryReport>), McapLogError> {
        McapSink::for_run(config, origin_ns, origin_ns, baselines)
    }

    /// [`for_config`](Self::for_config) for a run named `run_id` (a replay keeps the
    /// original run's id and origin, so that its log is dated as the original was).
    pub fn for_run(
        config: &Config,
        origin_ns: u64,
        run_id: u64,
        baselines: &BTreeMap<ChannelId, Baseline>,
    ) -> Result<(Self, Vec<RecoveryReport>), McapLogError> {
        let logger = LoggerConfig {
            metadata: metadata::run_records(config, origin_ns, run_id, baselines),
            ..logger_config(config)
        };
        McapSink::open(logger, config.sample_rates(), origin_ns)
    }

    /// Calls `notice` for what the operator must know: the retention pass at start (now, and
    /// written as a `/log` note in the first file), those after each rotation, and pauses of
    /// the log for a full disk.
    pub fn on_notice(mut self, notice: impl Fn(&LogNotice) + Send + 'static) -> Self {
        let startup = self
            .logger
            .as_mut()
            .and_then(McapLogger::take_startup_retention);
        self.on_notice = Box::new(notice);
        if let Some(startup) = startup {
            let at = self.origin_ns;
            self.retention_done(startup, at);
        }
        self
    }

    pub fn current_path(&self) -> Option<&Path> {
        self.logger.as_ref().and_then(|l| l.current_path())
    }

    /// The open logger's counters (`None` once finished).
    pub fn log_stats(&self) -> Option<&LogStats> {
        self.logger.as_ref().map(McapLogger::stats)
    }

    /// The message's log time: the time of its sample at its sensor's rate. A raw block is
    /// logged at its first sample (a replay of a log without metadata takes its time base from
    /// that), every other message at its end sample; a source's counters, which have no sample,
    /// at the newest log time.
    fn log_time(&self, message: &PipelineMessage) -> u64 {
        let sample = match message {
            PipelineMessage::Raw(m) => Some(m.first_sample),
            _ => message.end_sample(),
        };
        let (Some(channel), Some(sample)) = (message.channel(), sample) else {
            return self.last_ns;
        };
        let fs = self.rates.get(&channel.sensor).copied().unwrap_or(1.0);
        self.origin_ns + (sample as f64 / fs * 1e9) as u64
    }

    /// Says a retention pass that deleted files (or skipped names that are not its own files),
    /// in the journal (the notice) and as one `/log` note per deleted file in the open file.
    fn retention_done(&mut self, report: RetentionReport, at_ns: u64) {
        if report.deleted.is_empty() && report.skipped.is_empty() {
            return;
        }
        if let Some(logger) = self.logger.as_mut() {
            for path in &report.deleted {
                let text = format!(
                    "retention: deleted {} to keep the logs within the disk budget \
                     (outputs.mcap_disk_budget_mb); {} bytes deleted in this pass, {} bytes of \
                     logs left",
                    path.display(),
                    report.bytes_deleted,
                    report.total_bytes_after
                );
                if let Err(e) = logger.note(LogLevel::Info, &text, at_ns) {
                    self.errors.push(e);
                }
            }
        }
        (self.on_notice)(&LogNotice::Retention(report));
    }

    /// Finishes the open file and opens the next, which begins with the current state.
    fn rotate(&mut self, at_ns: u64) -> Result<(), McapLogError> {
        let Some(logger) = self.logger.as_mut() else {
            return Ok(());
        };
        let report = logger.rotate(at_ns)?;
        // The previous file was finished: what was logged in it is on the disk.
        self.since_flush.clear();
        logger.write_state(&self.state.snapshot(), at_ns)?;
        self.retention_done(report, at_ns);
        Ok(())
    }

    /// A write to the log failed: the file is given up (left for recovery) and logging
    /// pauses until there is room again; the pipeline goes on.
    fn pause(&mut self, error: &McapLogError, at_ns: u64) {
        let abandoned = self.logger.as_mut().and_then(McapLogger::abandon);
        let pause = self.pause.get_or_insert_with(|| Pause {
            flushed_until_ns: self.flushed_ns,
            messages: 0,
            next_try_ns: at_ns,
            abandoned: Vec::new(),
            late: LateBacklog::default(),
        });
        pause.next_try_ns = at_ns + RETRY_EVERY_NS;
        // What was logged since the last flush went with the open chunk: it comes first.
        let held = std::mem::replace(&mut pause.late, std::mem::take(&mut self.since_flush));
        pause.late.append(held);
        if let Some(path) = abandoned {
            pause.abandoned.push(path.clone());
            (self.on_notice)(&LogNotice::Paused {
                path,
                error: with_causes(error),
                flushed_until_ns: pause.flushed_until_ns,
            });
        }
    }

    /// While paused: counts the message, and at most once a second of log time, when the log
    /// directory has room again, recovers the files left by the failure and opens a new one.
    /// `true` once logging goes on.
    fn try_resume(&mut self, at_ns: u64) -> bool {
        let (Some(pause), Some(logger)) = (self.pause.as_mut(), self.logger.as_mut()) else {
            return true;
        };
        if at_ns < pause.next_try_ns {
            pause.messages += 1;
            return false;
        }
        pause.next_try_ns = at_ns + RETRY_EVERY_NS;
        let needed = 2 * logger.config().chunk_size + (1 << 20);
        if free_bytes(&logger.config().dir).is_some_and(|free| free < needed) {
            pause.messages += 1;
            return false;
        }
        let notices = recover_abandoned(std::mem::take(&mut pause.abandoned));
        let mut retention = Vec::new();
        let opened = logger
            .reopen(at_ns)
            .and_then(|()| logger.write_state(&self.state.snapshot(), at_ns))
            .and_then(|()| write_late(logger, &pause.late, at_ns, &mut retention))
            .and_then(|()| logger.flush());
        for notice in &notices {
            (self.on_notice)(notice);
        }
        if opened.is_err() {
            // Still no room after all (the free space was taken meanwhile): paused again.
            if let Some(path) = logger.abandon() {
                pause.abandoned.push(path);
            }
            pause.messages += 1;
            return false;
        }
        let seconds = at_ns.saturating_sub(pause.flushed_until_ns) as f64 / 1e9;
        let messages = pause.messages;
        let late = std::mem::take(&mut pause.late);
        let text = format!(
            "logging resumed after a write failure (full disk?): {messages} messages of the \
             pipeline were not logged, {seconds:.1} s of signal from the last flush before the \
             failure"
        );
        let noted = logger.note(LogLevel::Warning, &text, at_ns);
        let path = logger
            .current_path()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        self.pause = None;
        if let Err(e) = noted {
            self.pause(&e, at_ns);
            return false;
        }
        self.flushed_ns = at_ns;
        self.messages += late.held().total();
        (self.on_notice)(&LogNotice::Resumed {
            path: path.clone(),
            messages_not_logged: messages,
            seconds_not_logged: seconds,
        });
        if !late.is_empty() {
            (self.on_notice)(&LogNotice::LateWritten {
                path,
                written: late.held(),
                dropped: late.dropped(),
            });
        }
        for report in retention {
            self.retention_done(report, at_ns);
        }
        true
    }
}

/// Writes what a pause held, at `at_ns` (the resume) after a `/log` note saying what follows:
/// each message as decided (its time as `publish_time`), marked late. A rotation on the way
/// (not expected: the file was just opened) leaves its retention report in `retention`.
fn write_late(
    logger: &mut McapLogger,
    late: &LateBacklog,
    at_ns: u64,
    retention: &mut Vec<RetentionReport>,
) -> Result<(), McapLogError> {
    if late.is_empty() {
        return Ok(());
    }
    let (held, dropped) = (late.held(), late.dropped());
    let text = format!(
        "{} flag changes and {} health events decided during the pause follow, written late \
         (\"late\": true; publish_time = when decided, log_time = now); {} flag changes and {} \
         health events dropped for lack of room in memory (the /state snapshot has the latest)",
        held.flags, held.health, dropped.flags, dropped.health
    );
    logger.note(LogLevel::Warning, &text, at_ns)?;
    for message in late.iter() {
        retention.extend(logger.log_late(&message.message, at_ns, message.decided_ns)?);
    }
    Ok(())
}

/// An error's message followed by those of its causes that it does not already say (the
/// `mcap` crate's I/O error hides the OS's reason, e.g. "No space left on device").
fn with_causes(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut cause = error.source();
    while let Some(inner) = cause {
        let said = inner.to_string();
        if !text.contains(&said) {
            text.push_str(": ");
            text.push_str(&said);
        }
        cause = inner.source();
    }
    text
}

/// Recovers the files a pause left unfinished; what became of each.
fn recover_abandoned(paths: Vec<PathBuf>) -> Vec<LogNotice> {
    paths
        .into_iter()
        .map(|path| match recover_file(&path) {
            Ok(report) => LogNotice::PausedFileRecovered(report),
            Err(e) => LogNotice::PausedFileNotRecovered {
                path,
                error: e.to_string(),
            },
        })
        .collect()
}

/// Free bytes for an unprivileged writer in `dir`'s file system; `None` if it cannot be told.
fn free_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let path = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut stat = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `path` is a NUL-terminated string that outlives the call; `stat` is written by
    // statvfs before it is read, and only read when the call succeeded.
    #[allow(unsafe_code)]
    let stat = unsafe {
        if libc::statvfs(path.as_ptr(), stat.as_mut_ptr()) != 0 {
            return None;
        }
        stat.assume_init()
    };
    // The field types are u32 on some 32-bit targets (arm edge boxes), u64 here.
    #[allow(clippy::useless_conversion)]
    let (blocks, size) = (u64::from(stat.f_bavail), u64::from(stat.f_frsize));
    Some(blocks.saturating_mul(size))
}

impl Sink for McapSink {
    fn write(&mut self, message: &PipelineMessage) {
        let time = self.log_time(message);
        self.last_ns = self.last_ns.max(time);
        let resumed = self.pause.is_none() || self.try_resume(self.last_ns);
        if resumed {
            self.log(message, time);
        } else if let Some(pause) = self.pause.as_mut() {
            pause.late.push(message, time);
        }
        self.state.note(message);
    }

    fn finish(&mut self) -> Result<(), SinkError> {
        if let Some(pause) = self.pause.take() {
            if !pause.late.is_empty() {
                (self.on_notice)(&LogNotice::LateLost {
                    held: pause.late.held(),
                    dropped: pause.late.dropped(),
                });
            }
            for notice in recover_abandoned(pause.abandoned) {
                (self.on_notice)(&notice);
            }
        }
        let finished = self.logger.take().map(|l| l.finish());
        if let Some(Err(e)) = finished {
            self.errors.push(e);
        }
        let count = self.errors.len();
        let mut errors = std::mem::take(&mut self.errors).into_iter();
        match errors.next() {
            None => Ok(()),
            Some(first) => Err(SinkError {
                sink: "MCAP log",
                count,
                first: Box::new(first),
            }),
        }
    }
}

impl McapSink {
    /// Logs one message: rotates first when due (the next file begins with the current
    /// state), never writes a log time before the open file's start (a twin fit finished after
    /// a rotation over a window before it keeps that window's time as its `publish_time`), and
    /// flushes every second of data. A write that fails pauses the log.
    fn log(&mut self, message: &PipelineMessage, time: u64) {
        let due = self
            .logger
            .as_ref()
            .is_some_and(|logger| logger.needs_rotation(time));
        if due {
            if let Err(e) = self.rotate(time) {
                self.pause(&e, time);
                return;
            }
        }
        let Some(logger) = self.logger.as_mut() else {
            return;
        };
        let log_time = time.max(logger.current_file_start().unwrap_or(0));
        // A rotation inside `log` cannot happen (it was checked just above at the same time);
        // were there one, its retention is still said.
        match logger.log(message, log_time, time) {
            Ok(rotated) => {
                self.messages += 1;
                self.since_flush.push(message, time);
                if let Some(report) = rotated {
                    self.retention_done(report, log_time);
                }
            }
            Err(e) => return self.pause(&e, time),
        }
        if self.last_ns >= self.next_flush_ns {
            self.next_flush_ns = self.last_ns + FLUSH_EVERY_NS;
            let sync = self.next_sync_ns.is_some_and(|at| self.last_ns >= at);
            let Some(logger) = self.logger.as_mut() else {
                return;
            };
            let done = if sync {
                self.next_sync_ns = logger
                    .config()
                    .fsync_every_ns
                    .map(|every| self.last_ns + every);
                logger.sync()
            } else {
                logger.flush()
            };
            match done {
                Ok(()) => {
                    self.flushed_ns = self.last_ns;
                    self.since_flush.clear();
                }
                Err(e) => self.pause(&e, time),
            }
        }
    }
}

/// The MCAP logger's settings from `[outputs]`.
pub fn logger_config(config: &Config) -> LoggerConfig {
    let o = &config.outputs;
    LoggerConfig {
        max_file_bytes: o.mcap_max_file_bytes(),
        max_file_duration_ns: (o.mcap_max_file_s * 1e9) as u64,
        disk_budget_bytes: o.mcap_disk_budget_bytes(),
        chunk_size: (1u64 << 19).min(o.mcap_max_file_bytes() / 4).max(4096),
        fsync_every_ns: Some((o.mcap_fsync_interval_s * 1e9) as u64),
        ..LoggerConfig::new(o.mcap_dir.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{ChannelId, HealthKind, HealthMessage};

    fn health_at(end_sample: u64) -> PipelineMessage {
        PipelineMessage::Health(HealthMessage {
            channel: ChannelId {
                sensor: "s".into(),
                axis: "radial".into(),
            },
            end_sample,
            kind: HealthKind::Gap,
            stage: None,
            detail: String::new(),
        })
    }

    #[test]
    fn the_open_file_is_forced_to_the_disk_on_the_configured_period() {
        let dir = tempfile::tempdir().unwrap();
        let config = LoggerConfig {
            fsync_every_ns: Some(3_000_000_000),
            ..LoggerConfig::new(dir.path())
        };
        let rates = HashMap::from([("s".to_string(), 1000.0)]);
        let origin = 1_700_000_000_000_000_000;
        let (mut sink, _) = McapSink::open(config, rates, origin).unwrap();
        // 20 s of data, a message every 100 ms (100 samples at 1 kHz); after each message,
        // (flushes, fsyncs) so far.
        let counts: Vec<(u64, u64)> = (1..=200)
            .map(|k| {
                sink.write(&health_at(k * 100));
                let stats = sink.log_stats().unwrap();
                (stats.flushes, stats.syncs)
            })
            .collect();
        // Flushed at every whole second of data, forced to the disk at every third.
        assert_eq!(counts[199], (20, 6), "fsyncs at 3, 6, 9, 12, 15, 18 s");
        assert_eq!(
            counts[28],
            (2, 0),
            "2.9 s: flushed at 1 and 2 s, no fsync yet"
        );
        assert_eq!(
            counts[29],
            (3, 1),
            "3.0 s: the first fsync, with the third flush"
        );
        assert_eq!(counts[58], (5, 1));
        assert_eq!(counts[59], (6, 2));
        sink.finish().unwrap();
    }
}
