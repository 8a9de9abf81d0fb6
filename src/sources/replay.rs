//! The replay source: the raw samples of MCAP logs, in file order, as the pipeline's inputs,
//! as fast as the consumer takes them or paced at a multiple of real time.
//!
//! Logged speed frames (`/speed/…` with source `can`) come back as [`Input::LoggedSpeed`] at
//! their own samples, so a channel whose speed comes from speed frames sees the same speeds
//! at the same samples as the live run did. Truncated files are read up to their last complete
//! chunk ([`crate::mcap_log::reader`]); what could not be read is counted there and each
//! unreadable message is handed on as an error, never a panic.
//!
//! Which files, in which order, as which runs, with which settings: [`plan`].

pub mod plan;

use crate::mcap_log::{read_messages, LogReader, McapLogError, ReadSummary};
use crate::messages::{ChannelId, PipelineMessage};
use crate::pipeline::Input;
use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What the replay has read so far.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReplayCounters {
    /// Raw blocks of known channels handed on.
    pub raw_blocks: u64,
    pub samples: u64,
    /// The furthest sample time reached, in seconds.
    pub sample_seconds: f64,
    /// Channels in the logs that the config does not know (skipped), in order of appearance.
    pub unknown_channels: Vec<String>,
    /// Bytes of the files read so far.
    pub bytes_read: u64,
    /// The log time of sample 0, as the first raw block's log time tells it
    /// (`log_time - first_sample / rate`): the time base of a log without metadata.
    pub first_block_origin_ns: Option<u64>,
}

/// Logged inputs of `paths` for the channels the pipeline knows.
pub struct ReplaySource {
    reader: LogReader,
    known: BTreeSet<ChannelId>,
    /// Sample rate per sensor (the config's; a block's own when its sensor is not there).
    rates: HashMap<String, f64>,
    /// `Some(k)`: sample time runs `k` times faster than real time.
    speed: Option<f64>,
    started: Instant,
    counters: ReplayCounters,
}

impl ReplaySource {
    /// `known`: the pipeline's channels; `rates`: sample rate per sensor; `speed`: `None` as
    /// fast as possible, `Some(1.0)` real time.
    pub fn open(
        paths: &[PathBuf],
        known: impl IntoIterator<Item = ChannelId>,
        rates: HashMap<String, f64>,
        speed: Option<f64>,
    ) -> ReplaySource {
        ReplaySource {
            reader: read_messages(paths),
            known: known.into_iter().collect(),
            rates,
            speed: speed.filter(|s| *s > 0.0),
            started: Instant::now(),
            counters: ReplayCounters::default(),
        }
    }

    pub fn counters(&self) -> &ReplayCounters {
        &self.counters
    }

    /// What was read and what could not be, so far (complete once the source is exhausted).
    pub fn read_summary(&self) -> &ReadSummary {
        self.reader.summary()
    }

    /// When replaying at a chosen speed, waits until the wall clock catches up with the sample
    /// time read so far.
    fn pace(&self) {
        if let Some(speed) = self.speed {
            let due = Duration::from_secs_f64(self.counters.sample_seconds / speed);
            if let Some(wait) = due.checked_sub(self.started.elapsed()) {
                std::thread::sleep(wait);
            }
        }
    }
}

impl Iterator for ReplaySource {
    type Item = Result<Input, McapLogError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let next = self.reader.next();
            self.counters.bytes_read = self.reader.bytes_read();
            let logged = match next? {
                Ok(logged) => logged,
                Err(e) => return Some(Err(e)),
            };
            let log_time = logged.log_time;
            let block = match logged.message {
                PipelineMessage::Raw(block) => block,
                // Measured speeds are inputs like the raw samples; the pipeline uses them if the
                // sensor's speed source is `can`, at their logged samples.
                PipelineMessage::Speed(speed) => return Some(Ok(Input::LoggedSpeed(speed))),
                _ => continue,
            };
            if !self.known.contains(&block.channel) {
                let name = block.channel.to_string();
                if !self.counters.unknown_channels.contains(&name) {
                    self.counters.unknown_channels.push(name);
                }
                continue;
            }
            let end = block.end_sample();
            let fs = self
                .rates
                .get(&block.channel.sensor)
                .copied()
                .unwrap_or(block.sample_rate_hz);
            if self.counters.first_block_origin_ns.is_none() {
                // The log's time base used the rate it was recorded at.
                let logged_fs = Some(block.sample_rate_hz)
                    .filter(|r| *r > 0.0)
                    .unwrap_or(fs);
                let since_origin = (block.first_sample as f64 / logged_fs * 1e9) as u64;
                self.counters.first_block_origin_ns = Some(log_time.saturating_sub(since_origin));
            }
            self.counters.raw_blocks += 1;
            self.counters.samples += block.counts.len() as u64;
            self.counters.sample_seconds = self.counters.sample_seconds.max(end as f64 / fs);
            let counts = block
                .counts
                .iter()
                .map(|&c| c.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16)
                .collect();
            self.pace();
            return Some(Ok(Input::Samples {
                channel: block.channel,
                first_sample: block.first_sample,
                scale_g_per_count: block.scale_g_per_count,
                counts,
            }));
        }
    }
}
