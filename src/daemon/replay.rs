//! `bearingd replay`: the raw samples of MCAP logs through the same [`Pipeline`] as the live
//! run, as fast as possible or at a chosen speed, into the same sinks. Truncated files are read
//! up to their last complete chunk, and the summary says how much could not be read.
//!
//! Logged speed frames (`/speed/…` with source `can`) are fed back at their samples, so a
//! channel whose speed comes from speed frames sees the same speeds at the same samples.
//!
//! The twin's re-fits run inline here (the live run does them on their own thread): they do
//! not influence flags, so the flags of a replay equal the live run's at the same samples.

use super::pipeline::{Input, Output, Pipeline};
use super::run::Sink;
use super::twin_worker::TwinWorker;
use crate::config::Config;
use crate::mcap_log::{read_messages, ReadSummary};
use crate::messages::{FlagMessage, PipelineMessage};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How to replay.
#[derive(Debug, Clone, Default)]
pub struct ReplayOptions {
    /// `None`: as fast as possible; `Some(1.0)`: real time; `Some(10.0)`: ten times faster.
    pub speed: Option<f64>,
    /// Print progress to stderr about once a second.
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

/// Replays `paths` (in order) with `config`'s sensors, into `sinks`.
pub fn replay(
    paths: &[PathBuf],
    config: &Config,
    options: &ReplayOptions,
    sinks: &mut [Box<dyn Sink>],
) -> Result<ReplaySummary, String> {
    let mut pipeline = Pipeline::new(config, &BTreeMap::new());
    let known: Vec<_> = pipeline.channels().cloned().collect();
    let rates: BTreeMap<String, f64> = config
        .sensors
        .iter()
        .map(|s| (s.id.clone(), s.sample_rate_hz))
        .collect();
    let mut worker = TwinWorker::default();
    let mut reader = read_messages(paths);
    let started = Instant::now();
    let mut last_progress = started;
    let (mut raw_blocks, mut samples, mut flags, mut unknown) =
        (0u64, 0u64, Vec::new(), Vec::<String>::new());
    let mut sample_seconds = 0.0f64;
    let emit = |output: Output,
                sinks: &mut [Box<dyn Sink>],
                flags: &mut Vec<FlagMessage>,
                worker: &mut TwinWorker| match output {
        Output::Message(message) => {
            if let PipelineMessage::Flag(flag) = &message {
                flags.push(flag.clone());
            }
            for sink in sinks.iter_mut() {
                sink.write(&message);
            }
        }
        Output::Twin(request) => {
            if let Some(twin) = worker.refit(&request) {
                let message = PipelineMessage::Twin(twin);
                for sink in sinks.iter_mut() {
                    sink.write(&message);
                }
            }
        }
    };
    for item in reader.by_ref() {
        let logged = match item {
            Ok(logged) => logged,
            Err(e) => {
                eprintln!("bearingd: replay: {e}");
                continue;
            }
        };
        let block = match logged.message {
            PipelineMessage::Raw(block) => block,
            // Measured speeds are inputs like the raw samples; the pipeline uses them if the
            // sensor's speed source is `can`, at their logged samples.
            PipelineMessage::Speed(speed) => {
                let mut outputs = Vec::new();
                pipeline.handle(Input::LoggedSpeed(speed), &mut |output| {
                    outputs.push(output)
                });
                for output in outputs {
                    emit(output, sinks, &mut flags, &mut worker);
                }
                continue;
            }
            _ => continue,
        };
        if !known.contains(&block.channel) {
            let name = block.channel.to_string();
            if !unknown.contains(&name) {
                unknown.push(name);
            }
            continue;
        }
        raw_blocks += 1;
        samples += block.counts.len() as u64;
        let fs = rates
            .get(&block.channel.sensor)
            .copied()
            .unwrap_or(block.sample_rate_hz);
        sample_seconds =
            sample_seconds.max((block.first_sample + block.counts.len() as u64) as f64 / fs);
        let counts = block
            .counts
            .iter()
            .map(|&c| c.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16)
            .collect();
        let input = Input::Samples {
            channel: block.channel,
            first_sample: block.first_sample,
            scale_g_per_count: block.scale_g_per_count,
            counts,
        };
        let mut outputs = Vec::new();
        pipeline.handle(input, &mut |output| outputs.push(output));
        for output in outputs {
            emit(output, sinks, &mut flags, &mut worker);
        }
        if let Some(speed) = options.speed.filter(|s| *s > 0.0) {
            let due = Duration::from_secs_f64(sample_seconds / speed);
            if let Some(wait) = due.checked_sub(started.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        if options.progress && last_progress.elapsed() >= Duration::from_secs(1) {
            last_progress = Instant::now();
            let elapsed = started.elapsed().as_secs_f64();
            eprintln!(
                "replay: {:.0} s of signal in {:.1} s ({:.0}× real time), {} blocks, {} flag changes",
                sample_seconds,
                elapsed,
                sample_seconds / elapsed.max(1e-9),
                raw_blocks,
                flags.len()
            );
        }
    }
    let mut errors = Vec::new();
    for sink in sinks.iter_mut() {
        if let Err(e) = sink.finish() {
            errors.push(e);
        }
    }
    if let Some(e) = errors.into_iter().next() {
        return Err(e);
    }
    Ok(ReplaySummary {
        raw_blocks,
        samples,
        flags,
        read: reader.summary().clone(),
        unknown_channels: unknown,
        elapsed: started.elapsed(),
        sample_seconds,
    })
}
