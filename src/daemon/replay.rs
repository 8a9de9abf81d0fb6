//! `bearingd replay`: the replay source ([`ReplaySource`]) through the same [`Pipeline`] as
//! the live run, into the same sinks, on one thread, run by run ([`ReplayPlan`]).
//!
//! - A run boundary (another run id: the daemon stopped or crashed and started again) starts
//!   a new pipeline and new sinks, as the restarted daemon did: its sample time starts again
//!   at 0, and its output log is dated with its own wall-clock origin. Every run's pipeline
//!   starts from the health baselines the daemon loaded at that start (the log's
//!   `bearingd.state` record); a log without that record (an older bearingd) starts from the
//!   baselines the previous run reached, the nearest stand-in, and the summary says which.
//! - A gap inside a run (a channel's next raw block starts after where the last one ended:
//!   frames lost live, a damaged chunk, a missing file) is reported with its length and does
//!   not reset anything: the channel's windows restart after it, exactly as the live pipeline
//!   did for a gap it saw, so flags before and after stay those of the live run.
//! - Truncated files are read up to their last complete chunk, and the summary says how much
//!   could not be read.
//!
//! The twin's re-fits run inline here (the live run does them on their own thread): they do
//! not influence flags, so the flags of a replay equal the live run's at the same samples.
//!
//! A run's end is the end of its evidence: the channels decide once more on what they have not
//! analysed yet ([`Pipeline::finish`]), as the daemon does when it stops cleanly. So an imported
//! recording ends on `analyze`'s verdict of the same samples.

use super::events::{DaemonEvent, Events};
use crate::analysis::agreement::Witness;
use crate::analysis::health::{baselines_from_json, Baseline};
use crate::config::Config;
use crate::mcap_log::ReadSummary;
use crate::messages::{ChannelId, FlagMessage, PipelineMessage};
use crate::pipeline::load_learned;
use crate::pipeline::{Input, Output, Pipeline, Sink, SinkError, SinkItem, TwinWorker};
use crate::sources::replay::plan::{PlannedRun, ReplayPlan};
use crate::sources::replay::ReplaySource;
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How to replay.
#[derive(Debug, Clone, Default)]
pub struct ReplayOptions {
    /// `None`: as fast as possible; `Some(1.0)`: real time; `Some(10.0)`: ten times faster.
    pub speed: Option<f64>,
    /// Report progress ([`DaemonEvent::ReplayProgress`]) this often; `None`: never.
    pub progress_every: Option<Duration>,
}

/// Where a run of the replay starts, for whoever opens its sinks.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunStart {
    /// The original run's id; `None` for files without metadata.
    pub run_id: Option<u64>,
    /// Wall-clock time of the run's sample 0: from its metadata, else from its first raw
    /// block's log time, else 0.
    pub origin_ns: u64,
    /// The run's first file.
    pub first_file: PathBuf,
    /// Where the health baselines the run starts with came from.
    pub baselines_from: BaselinesFrom,
    /// Those baselines (the replay's own log records them, as the daemon's did).
    #[serde(skip)]
    pub baselines: BTreeMap<ChannelId, Baseline>,
}

impl RunStart {
    /// What the run's sinks need ([`super::sinks::assemble`]): its id (the original run's, or
    /// its origin for files without metadata), origin and baselines.
    pub fn sink_start(&self) -> super::sinks::SinkStart<'_> {
        super::sinks::SinkStart {
            run_id: self.run_id.unwrap_or(self.origin_ns),
            origin_ns: self.origin_ns,
            baselines: &self.baselines,
        }
    }
}

/// Where a replayed run's starting health baselines came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BaselinesFrom {
    /// The run's `bearingd.state` record: what the daemon loaded at that start.
    Log,
    /// The log has no such record: those the previous run of the replay reached.
    PreviousRun,
    /// No record and no run before: learned from scratch.
    None,
    /// The run's record does not read (said, never silent): as without a record.
    UnreadableRecord,
}

impl BaselinesFrom {
    /// The start of `run`, after the runs before it reached `reached` (`None` for the first).
    fn choose(
        run: &PlannedRun,
        reached: Option<&BTreeMap<ChannelId, Baseline>>,
    ) -> (BaselinesFrom, BTreeMap<ChannelId, Baseline>) {
        let otherwise = || reached.cloned().unwrap_or_default();
        match run.start_baselines_json.as_deref().map(baselines_from_json) {
            Some(Ok(logged)) => (BaselinesFrom::Log, logged),
            Some(Err(_)) => (BaselinesFrom::UnreadableRecord, otherwise()),
            None if reached.is_some() => (BaselinesFrom::PreviousRun, otherwise()),
            None => (BaselinesFrom::None, BTreeMap::new()),
        }
    }
}

/// Gives the sinks of a run, once its time origin is known.
pub type OpenSinks<'a> = dyn FnMut(&RunStart) -> Result<Vec<Box<dyn Sink>>, SinkError> + 'a;

/// Samples missing inside a run between two raw blocks of one channel.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Gap {
    pub run_id: Option<u64>,
    pub channel: String,
    /// The first missing sample.
    pub at_sample: u64,
    pub missing_samples: u64,
    pub seconds: f64,
}

/// At most this many gaps are kept one by one (all are counted).
const GAPS_KEPT: usize = 1000;

#[derive(Debug)]
pub struct ReplaySummary {
    pub raw_blocks: u64,
    pub samples: u64,
    pub flags: Vec<FlagMessage>,
    pub read: ReadSummary,
    pub unknown_channels: Vec<String>,
    pub elapsed: Duration,
    /// Seconds of signal replayed, summed over runs.
    pub sample_seconds: f64,
    /// Every run replayed, in order; from the second on, each is a boundary.
    pub runs: Vec<RunStart>,
    /// The first [`GAPS_KEPT`] gaps inside runs.
    pub gaps: Vec<Gap>,
    pub gap_count: u64,
    pub gap_seconds: f64,
}

/// Why a replay failed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error(transparent)]
    Sink(#[from] SinkError),
    #[error("twin.learned_model of the replay's config: {0}; give --config with the model's path on this machine, or without the key")]
    Learned(#[from] crate::learned::ModelError),
}

/// Replays the runs of `plan` with `config`'s sensors; `open_sinks` gives the sinks of each
/// run (called at its first output, when its time origin is known).
pub fn replay(
    plan: &ReplayPlan,
    config: &Config,
    options: &ReplayOptions,
    open_sinks: &mut OpenSinks<'_>,
    events: &Events,
) -> Result<ReplaySummary, ReplayError> {
    let started = Instant::now();
    let mut summary = ReplaySummary {
        raw_blocks: 0,
        samples: 0,
        flags: Vec::new(),
        read: ReadSummary::default(),
        unknown_channels: Vec::new(),
        elapsed: Duration::ZERO,
        sample_seconds: 0.0,
        runs: Vec::new(),
        gaps: Vec::new(),
        gap_count: 0,
        gap_seconds: 0.0,
    };
    let mut progress = Progress {
        every: options.progress_every,
        last: started,
        bytes_before: 0,
        bytes_total: plan.bytes(),
    };
    let mut reached: Option<BTreeMap<ChannelId, Baseline>> = None;
    for run in &plan.runs {
        let start = BaselinesFrom::choose(run, reached.as_ref());
        let mut replayed = RunReplay::new(run, plan, config, start, options)?;
        let result = replayed.go(open_sinks, &mut summary, &mut progress, events);
        reached = Some(replayed.pipeline.baselines());
        let counters = replayed.source.counters().clone();
        progress.bytes_before += counters.bytes_read;
        summary.raw_blocks += counters.raw_blocks;
        summary.samples += counters.samples;
        summary.sample_seconds += counters.sample_seconds;
        for name in counters.unknown_channels {
            if !summary.unknown_channels.contains(&name) {
                summary.unknown_channels.push(name);
            }
        }
        summary
            .read
            .files
            .extend(replayed.source.read_summary().files.iter().cloned());
        result?;
    }
    summary.elapsed = started.elapsed();
    Ok(summary)
}

/// When to report progress, and how far the files before this run went.
struct Progress {
    every: Option<Duration>,
    last: Instant,
    bytes_before: u64,
    bytes_total: u64,
}

/// One run: its source, a pipeline of its own, and its sinks once opened.
struct RunReplay<'a> {
    run: &'a PlannedRun,
    source: ReplaySource,
    pipeline: Pipeline,
    sinks: Option<Vec<Box<dyn Sink>>>,
    worker: TwinWorker,
    /// Per channel: the sample after its last raw block, and its sample rate.
    next_sample: HashMap<ChannelId, u64>,
    rates: HashMap<String, f64>,
    first_file: PathBuf,
    baselines_from: BaselinesFrom,
    start_baselines: BTreeMap<ChannelId, Baseline>,
}

impl<'a> RunReplay<'a> {
    fn new(
        run: &'a PlannedRun,
        plan: &ReplayPlan,
        config: &Config,
        (baselines_from, start_baselines): (BaselinesFrom, BTreeMap<ChannelId, Baseline>),
        options: &ReplayOptions,
    ) -> Result<Self, ReplayError> {
        let learned = load_learned(&config.twin)?;
        // The alerts are numbered as the original run's (its id; the first block's time for
        // files without metadata is not known yet: their origin, if any).
        let pipeline = Pipeline::new(
            config,
            &start_baselines,
            learned.clone().map(|m| m as Arc<dyn Witness>),
        )
        .with_run_id(run.run_id.or(run.origin_ns).unwrap_or(0));
        let worker = TwinWorker::new(&config.twin, learned);
        let paths = plan.paths(run);
        let source = ReplaySource::open(
            &paths,
            pipeline.channels().cloned().collect::<Vec<_>>(),
            config.sample_rates(),
            options.speed,
        );
        Ok(RunReplay {
            run,
            source,
            pipeline,
            sinks: None,
            worker,
            next_sample: HashMap::new(),
            rates: config.sample_rates(),
            first_file: paths.first().cloned().unwrap_or_default(),
            baselines_from,
            start_baselines,
        })
    }

    fn go(
        &mut self,
        open_sinks: &mut OpenSinks<'_>,
        summary: &mut ReplaySummary,
        progress: &mut Progress,
        events: &Events,
    ) -> Result<(), ReplayError> {
        let mut outputs = Vec::new();
        while let Some(item) = self.source.next() {
            let input = match item {
                Ok(input) => input,
                Err(e) => {
                    events(DaemonEvent::ReplayUnreadable(e));
                    continue;
                }
            };
            self.note_gap(&input, summary);
            self.pipeline
                .handle(input, &mut |output| outputs.push(output));
            if !outputs.is_empty() && self.sinks.is_none() {
                self.open(open_sinks, summary)?;
            }
            for output in outputs.drain(..) {
                self.deliver(output, &mut summary.flags);
            }
            if progress.every.is_some_and(|e| progress.last.elapsed() >= e) {
                progress.last = Instant::now();
                let read = self.source.counters();
                events(DaemonEvent::ReplayProgress {
                    sample_seconds: summary.sample_seconds + read.sample_seconds,
                    bytes_read: progress.bytes_before + read.bytes_read,
                    bytes_total: progress.bytes_total,
                    raw_blocks: summary.raw_blocks + read.raw_blocks,
                    flag_changes: summary.flags.len(),
                });
            }
        }
        // The run's end: the channels decide on the evidence they have not analysed yet, as
        // the live daemon does when it stops cleanly.
        self.pipeline.finish(&mut |output| outputs.push(output));
        if !outputs.is_empty() && self.sinks.is_none() {
            self.open(open_sinks, summary)?;
        }
        for output in outputs.drain(..) {
            self.deliver(output, &mut summary.flags);
        }
        let Some(sinks) = self.sinks.as_mut() else {
            return Ok(());
        };
        let mut first_error = None;
        for sink in sinks.iter_mut() {
            if let Err(e) = sink.finish() {
                first_error.get_or_insert(e);
            }
        }
        match first_error {
            Some(e) => Err(e.into()),
            None => Ok(()),
        }
    }

    fn open(
        &mut self,
        open_sinks: &mut OpenSinks<'_>,
        summary: &mut ReplaySummary,
    ) -> Result<(), ReplayError> {
        let start = RunStart {
            run_id: self.run.run_id,
            origin_ns: self
                .run
                .origin_ns
                .or(self.source.counters().first_block_origin_ns)
                .unwrap_or(0),
            first_file: self.first_file.clone(),
            baselines_from: self.baselines_from,
            // The pipeline holds its own copy since it was made; this one goes to the sinks.
            baselines: std::mem::take(&mut self.start_baselines),
        };
        self.sinks = Some(open_sinks(&start)?);
        summary.runs.push(start);
        Ok(())
    }

    /// Records a gap when a channel's block starts past where its last one ended.
    fn note_gap(&mut self, input: &Input, summary: &mut ReplaySummary) {
        let Input::Samples {
            channel,
            first_sample,
            counts,
            ..
        } = input
        else {
            return;
        };
        let end = first_sample + counts.len() as u64;
        let Some(expected) = self.next_sample.insert(channel.clone(), end) else {
            return;
        };
        if *first_sample > expected {
            let missing = first_sample - expected;
            let fs = self.rates.get(&channel.sensor).copied().unwrap_or(1.0);
            let seconds = missing as f64 / fs;
            summary.gap_count += 1;
            summary.gap_seconds += seconds;
            if summary.gaps.len() < GAPS_KEPT {
                summary.gaps.push(Gap {
                    run_id: self.run.run_id,
                    channel: channel.to_string(),
                    at_sample: expected,
                    missing_samples: missing,
                    seconds,
                });
            }
        }
    }

    /// One output of the pipeline: a message or an alert to every sink, a twin request fitted
    /// now (the twin's fit, then the HW model's, as the daemon's re-fit thread hands them on;
    /// the twin's into the pipeline too, as the daemon's analysis thread takes it).
    fn deliver(&mut self, output: Output, flags: &mut Vec<FlagMessage>) {
        let RunReplay {
            sinks,
            pipeline,
            worker,
            ..
        } = self;
        let mut hand_over = |item: SinkItem| {
            if let SinkItem::Message(PipelineMessage::Flag(flag)) = &item {
                flags.push(flag.clone());
            }
            for sink in sinks.iter_mut().flatten() {
                item.deliver_to(sink.as_mut());
            }
        };
        match output {
            Output::Message(message) => hand_over(SinkItem::Message(message)),
            Output::Alert(alert) => hand_over(SinkItem::Alert(alert)),
            Output::Twin(request) => worker.refit(&request, &mut |fit| {
                if let PipelineMessage::Twin(twin) = &fit {
                    pipeline.note_twin(twin);
                }
                hand_over(SinkItem::Message(fit));
            }),
        }
    }
}
