//! `bearingd replay`: the replay source ([`ReplaySource`]) through the same [`Pipeline`] as
//! the live run, into the same sinks, on one thread. Truncated files are read up to their last
//! complete chunk, and the summary says how much could not be read.
//!
//! The twin's re-fits run inline here (the live run does them on their own thread): they do
//! not influence flags, so the flags of a replay equal the live run's at the same samples.

use super::events::{DaemonEvent, Events};
use crate::config::Config;
use crate::mcap_log::ReadSummary;
use crate::messages::{FlagMessage, PipelineMessage};
use crate::pipeline::{Output, Pipeline, Sink, SinkError, TwinWorker};
use crate::sources::replay::ReplaySource;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How to replay.
#[derive(Debug, Clone, Default)]
pub struct ReplayOptions {
    /// `None`: as fast as possible; `Some(1.0)`: real time; `Some(10.0)`: ten times faster.
    pub speed: Option<f64>,
    /// Report progress ([`DaemonEvent::ReplayProgress`]) about once a second.
    pub progress: bool,
}

#[derive(Debug)]
pub struct ReplaySummary {
    pub raw_blocks: u64,
    pub samples: u64,
    pub flags: Vec<FlagMessage>,
    pub read: ReadSummary,
    pub unknown_channels: Vec<String>,
    pub elapsed: Duration,
    pub sample_seconds: f64,
}

/// Why a replay failed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error(transparent)]
    Sink(#[from] SinkError),
}

/// Replays `paths` (in order) with `config`'s sensors, into `sinks`.
pub fn replay(
    paths: &[PathBuf],
    config: &Config,
    options: &ReplayOptions,
    sinks: &mut [Box<dyn Sink>],
    events: &Events,
) -> Result<ReplaySummary, ReplayError> {
    let mut pipeline = Pipeline::new(config, &BTreeMap::new());
    let mut source = ReplaySource::open(
        paths,
        pipeline.channels().cloned().collect::<Vec<_>>(),
        config.sample_rates(),
        options.speed,
    );
    let mut worker = TwinWorker::default();
    let mut flags = Vec::new();
    let started = Instant::now();
    let mut last_progress = started;
    let mut outputs = Vec::new();
    while let Some(item) = source.next() {
        let input = match item {
            Ok(input) => input,
            Err(e) => {
                events(DaemonEvent::ReplayUnreadable(e));
                continue;
            }
        };
        pipeline.handle(input, &mut |output| outputs.push(output));
        for output in outputs.drain(..) {
            deliver(output, sinks, &mut flags, &mut worker);
        }
        if options.progress && last_progress.elapsed() >= Duration::from_secs(1) {
            last_progress = Instant::now();
            let read = source.counters();
            events(DaemonEvent::ReplayProgress {
                sample_seconds: read.sample_seconds,
                elapsed_s: started.elapsed().as_secs_f64(),
                raw_blocks: read.raw_blocks,
                flag_changes: flags.len(),
            });
        }
    }
    let mut first_error = None;
    for sink in sinks.iter_mut() {
        if let Err(e) = sink.finish() {
            first_error.get_or_insert(e);
        }
    }
    if let Some(e) = first_error {
        return Err(e.into());
    }
    let read = source.counters().clone();
    Ok(ReplaySummary {
        raw_blocks: read.raw_blocks,
        samples: read.samples,
        flags,
        read: source.read_summary().clone(),
        unknown_channels: read.unknown_channels,
        elapsed: started.elapsed(),
        sample_seconds: read.sample_seconds,
    })
}

/// One output of the pipeline: a message to every sink, a twin request fitted now.
fn deliver(
    output: Output,
    sinks: &mut [Box<dyn Sink>],
    flags: &mut Vec<FlagMessage>,
    worker: &mut TwinWorker,
) {
    let message = match output {
        Output::Message(message) => message,
        Output::Twin(request) => match worker.refit(&request) {
            Some(twin) => PipelineMessage::Twin(twin),
            None => return,
        },
    };
    if let PipelineMessage::Flag(flag) = &message {
        flags.push(flag.clone());
    }
    for sink in sinks.iter_mut() {
        sink.write(&message);
    }
}
