//! The MCAP log as a sink: the writer with rotation and a disk budget ([`writer`]), the
//! start-up recovery of files a crash left unfinished ([`recover`]), and [`McapSink`], which
//! maps sample time to log time, flushes the open chunk every second of data (a crash loses at
//! most that), recovers unfinished files at start, and finishes the file at shutdown. The
//! format itself (schemas, topics, file names, reading back) is [`crate::mcap_log`]; what each
//! file says about itself in MCAP metadata records is [`metadata`].

pub mod metadata;
pub mod recover;
pub mod writer;

pub use recover::{
    is_finished, recover_directory, recover_file, RecoveryAction, RecoveryReport, QUARANTINE_DIR,
};
pub use writer::{enforce_budget, LogStats, LoggerConfig, McapLogger, RetentionReport, TopicStats};

use crate::config::Config;
use crate::mcap_log::McapLogError;
use crate::messages::PipelineMessage;
use crate::pipeline::{Sink, SinkError};
use std::collections::HashMap;
use std::path::Path;

/// Nanoseconds of log time between two flushes.
const FLUSH_EVERY_NS: u64 = 1_000_000_000;

pub struct McapSink {
    logger: Option<McapLogger>,
    /// Log time of sample 0 of every channel, ns since the epoch.
    origin_ns: u64,
    /// Sample rate per sensor, to turn sample indices into time.
    rates: HashMap<String, f64>,
    next_flush_ns: u64,
    last_ns: u64,
    errors: Vec<McapLogError>,
    pub messages: u64,
    /// Told of every retention pass that deleted files (the operator must know).
    on_retention: Box<dyn Fn(&RetentionReport) + Send>,
}

impl McapSink {
    /// Recovers what a crash left in `config.dir`, then opens a new file. `origin_ns` is the
    /// log time of sample 0 (the daemon's start, or the original run's for a replay).
    pub fn open(
        config: LoggerConfig,
        rates: HashMap<String, f64>,
        origin_ns: u64,
    ) -> Result<(Self, Vec<RecoveryReport>), McapLogError> {
        std::fs::create_dir_all(&config.dir).map_err(|source| McapLogError::Io {
            path: config.dir.clone(),
            op: "create the log directory",
            source,
        })?;
        let recovered = recover_directory(&config.dir)?;
        let logger = McapLogger::create(config, origin_ns)?;
        Ok((
            McapSink {
                logger: Some(logger),
                origin_ns,
                rates,
                next_flush_ns: origin_ns + FLUSH_EVERY_NS,
                last_ns: origin_ns,
                errors: Vec::new(),
                messages: 0,
                on_retention: Box::new(|_| {}),
            },
            recovered,
        ))
    }

    /// [`open`](Self::open) with the log settings of `config`'s `[outputs]`, its sensors'
    /// sample rates, and the metadata that makes each file self-describing
    /// ([`metadata::run_records`]; the run is named by `origin_ns`).
    pub fn for_config(
        config: &Config,
        origin_ns: u64,
    ) -> Result<(Self, Vec<RecoveryReport>), McapLogError> {
        let logger = LoggerConfig {
            metadata: metadata::run_records(config, origin_ns, origin_ns),
            ..logger_config(config)
        };
        McapSink::open(logger, config.sample_rates(), origin_ns)
    }

    /// Calls `report` for every retention pass that deleted files: the one at start (now) and
    /// those after each rotation.
    pub fn on_retention(mut self, report: impl Fn(&RetentionReport) + Send + 'static) -> Self {
        if let Some(startup) = self
            .logger
            .as_mut()
            .and_then(|l| l.take_startup_retention())
        {
            if !startup.deleted.is_empty() {
                report(&startup);
            }
        }
        self.on_retention = Box::new(report);
        self
    }

    pub fn current_path(&self) -> Option<&Path> {
        self.logger.as_ref().and_then(|l| l.current_path())
    }

    fn log_time(&self, message: &PipelineMessage) -> u64 {
        let at = |sensor: &str, sample: u64| {
            let fs = self.rates.get(sensor).copied().unwrap_or(1.0);
            self.origin_ns + (sample as f64 / fs * 1e9) as u64
        };
        match message {
            PipelineMessage::Raw(m) => at(&m.channel.sensor, m.first_sample),
            PipelineMessage::Spectrum(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::Indicators(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::Twin(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::Flag(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::Health(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::Speed(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::Velocity(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::VelocityFlag(m) => at(&m.channel.sensor, m.end_sample),
            PipelineMessage::Ingest(_) => self.last_ns,
        }
    }
}

impl Sink for McapSink {
    fn write(&mut self, message: &PipelineMessage) {
        let time = self.log_time(message);
        self.last_ns = self.last_ns.max(time);
        let Some(logger) = self.logger.as_mut() else {
            return;
        };
        match logger.log(message, time, time) {
            Ok(retention) => {
                self.messages += 1;
                if let Some(report) = retention.filter(|r| !r.deleted.is_empty()) {
                    (self.on_retention)(&report);
                }
            }
            Err(e) if self.errors.len() < 10 => self.errors.push(e),
            Err(_) => {}
        }
        if self.last_ns >= self.next_flush_ns {
            self.next_flush_ns = self.last_ns + FLUSH_EVERY_NS;
            if let Err(e) = logger.flush() {
                self.errors.push(e);
            }
        }
    }

    fn finish(&mut self) -> Result<(), SinkError> {
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

/// The MCAP logger's settings from `[outputs]`.
pub fn logger_config(config: &Config) -> LoggerConfig {
    let o = &config.outputs;
    LoggerConfig {
        max_file_bytes: o.mcap_max_file_bytes(),
        max_file_duration_ns: (o.mcap_max_file_s * 1e9) as u64,
        disk_budget_bytes: o.mcap_disk_budget_bytes(),
        chunk_size: (1u64 << 19).min(o.mcap_max_file_bytes() / 4).max(4096),
        ..LoggerConfig::new(o.mcap_dir.clone())
    }
}
