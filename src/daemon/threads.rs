//! The daemon's three threads besides the async side (see [`super::run`] for how they are
//! wired and stopped): the analysis thread, which owns the pipeline and hands its outputs to
//! the immediate sinks as they come and to the sink queue once an input is done; the re-fit
//! thread; and the sink thread. Each owns its state and talks to the others over bounded
//! channels only.

use super::cpu_latency::CpusAwake;
use super::events::{DaemonEvent, Events};
use super::state::save_baselines;
use crate::messages::{FlagMessage, PipelineMessage};
use crate::pipeline::twin_queue::{TwinRequestQueue, TwinRequests};
use crate::pipeline::{ChannelStatus, Output, Pipeline, Sink, SinkError, SinkItem, TwinWorker};
use crate::sources::Arrived;
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;
use tokio::sync::{mpsc as async_mpsc, watch};

/// What the analysis thread reports when it ends.
pub(super) struct AnalysisSummary {
    pub(super) requests_skipped: u64,
    /// How the immediate sinks finished.
    pub(super) immediate_sinks: Result<(), SinkError>,
}

/// The analysis thread's ends toward the sinks: the immediate sinks (the alert publisher),
/// handed each output as it comes, and the sink queue, handed an input's outputs once they are
/// all out (a send wakes the sink thread: not before an alert has left).
pub(super) struct SinkEnds {
    pub(super) immediate: Vec<Box<dyn Sink>>,
    pub(super) queue: mpsc::SyncSender<SinkItem>,
    /// The current input's outputs, for the queue. A few per input; reused.
    pub(super) pending: Vec<SinkItem>,
}

impl SinkEnds {
    /// The next outputs are those of an input its source completed at `wall_ns`.
    fn arrived(&mut self, wall_ns: u64) {
        for sink in &mut self.immediate {
            sink.arrived(wall_ns);
        }
    }

    /// To the immediate sinks now, to the queue at the next [`flush`](Self::flush).
    fn take(&mut self, item: SinkItem) {
        for sink in &mut self.immediate {
            item.deliver_to(sink.as_mut());
        }
        self.pending.push(item);
    }

    /// Hands what was taken to the sink queue, in order (waits while the queue is full).
    fn flush(&mut self) {
        for item in self.pending.drain(..) {
            let _ = self.queue.send(item);
        }
    }

    /// Finishes the immediate sinks (the queued ones finish on the sink thread, once the
    /// queue closes with this).
    fn finish(mut self) -> Result<(), SinkError> {
        self.flush();
        let mut first_error = None;
        for sink in &mut self.immediate {
            if let Err(e) = sink.finish() {
                first_error.get_or_insert(e);
            }
        }
        first_error.map_or(Ok(()), Err)
    }
}

/// The analysis thread's state: the pipeline, the immediate sinks and its ends of the queues.
pub(super) struct AnalysisThread {
    pub(super) pipeline: Pipeline,
    pub(super) sinks: SinkEnds,
    pub(super) inputs: async_mpsc::Receiver<Arrived>,
    /// `None` once the inputs have ended (closing the re-fit queue).
    pub(super) twin_requests: Option<TwinRequests>,
    pub(super) fits: mpsc::Receiver<PipelineMessage>,
    pub(super) status: watch::Sender<Vec<ChannelStatus>>,
    pub(super) requests_skipped: u64,
    pub(super) state_dir: PathBuf,
    /// `outputs.state_save_interval_s`: the baselines are saved this often (wall-clock time,
    /// on this thread, outside the analysis) and at the stop.
    pub(super) state_every: Duration,
    pub(super) state_saved: std::time::Instant,
    pub(super) events: Events,
    /// `outputs.cpu_awake_during_analysis`: idle CPUs kept awake while a block is analysed;
    /// `None` when off or refused.
    pub(super) cpus_awake: Option<CpusAwake>,
}

impl AnalysisThread {
    pub(super) fn run(mut self) -> AnalysisSummary {
        while let Some(arrived) = self.inputs.blocking_recv() {
            self.analyse(arrived);
            while let Ok(fit) = self.fits.try_recv() {
                self.take_fit(fit);
            }
            self.status.send_replace(self.pipeline.status());
            if self.state_saved.elapsed() >= self.state_every {
                self.state_saved = std::time::Instant::now();
                self.save_state();
            }
        }
        self.stop()
    }

    /// Saves the learned state; a failure is reported, the run goes on.
    fn save_state(&self) {
        if let Err(problem) = save_baselines(&self.state_dir, &self.pipeline.baselines()) {
            (self.events)(DaemonEvent::State(problem));
        }
    }

    /// One input through the pipeline; its outputs to the immediate sinks and the re-fit as
    /// they come, then, in their order, to the sink queue.
    fn analyse(&mut self, arrived: Arrived) {
        let Arrived { input, wall_ns } = arrived;
        self.deliver(wall_ns, |pipeline, mut out| {
            pipeline.handle(input, &mut out)
        });
        self.let_cpus_halt();
    }

    /// The input is analysed: the idle CPUs, woken when it was handed over, may halt again once
    /// every input handed over is; a request the kernel refuses is said once and not made again.
    fn let_cpus_halt(&mut self) {
        let Some(cpus) = self.cpus_awake.as_ref() else {
            return;
        };
        if let Some(error) = cpus.analysed() {
            self.cpus_awake = None;
            (self.events)(DaemonEvent::CpuLatencyRefused(error));
        }
    }

    /// Runs `step` on the pipeline and delivers its outputs (`wall_ns`: when its input arrived).
    fn deliver(&mut self, wall_ns: u64, step: impl FnOnce(&mut Pipeline, &mut dyn FnMut(Output))) {
        let AnalysisThread {
            pipeline,
            sinks,
            twin_requests,
            requests_skipped,
            events,
            ..
        } = self;
        sinks.arrived(wall_ns);
        step(pipeline, &mut |output| match output {
            Output::Message(message) => sinks.take(SinkItem::Message(message)),
            Output::Alert(alert) => sinks.take(SinkItem::Alert(alert)),
            Output::Twin(request) => {
                let (channel, end_sample) = (request.channel.clone(), request.end_sample);
                let dropped = match twin_requests.as_ref() {
                    Some(queue) => queue.put(request).map(|old| old.end_sample),
                    None => Some(end_sample),
                };
                if let Some(dropped_end_sample) = dropped {
                    *requests_skipped += 1;
                    events(DaemonEvent::TwinFitDropped {
                        channel,
                        dropped_end_sample,
                        total: *requests_skipped,
                    });
                }
            }
        });
        sinks.flush();
    }

    /// A message of the re-fit thread: a twin's fit into the pipeline (the channel's status,
    /// the confidence of later alerts); every one to the sinks.
    fn take_fit(&mut self, fit: PipelineMessage) {
        if let PipelineMessage::Twin(twin) = &fit {
            self.pipeline.note_twin(twin);
        }
        self.sinks.take(SinkItem::Message(fit));
        self.sinks.flush();
    }

    /// The inputs have ended: the channels' last verdict on the evidence not yet analysed (as a
    /// replay of this run ends), the last fits, the baselines, the unknown channels, the alerts.
    fn stop(mut self) -> AnalysisSummary {
        self.deliver(crate::clock::wall_clock_now_ns(), |pipeline, mut out| {
            pipeline.finish(&mut out)
        });
        // Closing the re-fit queue ends the re-fit thread once it has handed over its last fit.
        self.twin_requests = None;
        while let Ok(fit) = self.fits.recv() {
            self.take_fit(fit);
        }
        self.status.send_replace(self.pipeline.status());
        self.save_state();
        for (channel, blocks) in self.pipeline.unknown_channels() {
            (self.events)(DaemonEvent::UnknownChannel {
                channel: channel.clone(),
                blocks: *blocks,
            });
        }
        AnalysisSummary {
            requests_skipped: self.requests_skipped,
            immediate_sinks: self.sinks.finish(),
        }
    }
}

/// The re-fit thread: one request at a time, each re-fit handed back to the analysis thread.
/// Returns the number of twin fits made.
pub(super) fn refit_thread(
    mut worker: TwinWorker,
    requests: &TwinRequestQueue,
    fits: &mpsc::SyncSender<PipelineMessage>,
) -> u64 {
    crate::pipeline::priority::idle_this_thread();
    let mut made = 0u64;
    let mut open = true;
    while open {
        let Some(request) = requests.take() else {
            break;
        };
        worker.refit(&request, &mut |fit| {
            made += u64::from(matches!(fit, PipelineMessage::Twin(_)));
            open &= fits.send(fit).is_ok();
        });
    }
    made
}

/// The sink thread: every message and alert to every queued sink, then finishes them. Returns
/// the flag changes and the number of messages (alerts not counted).
pub(super) fn sink_thread(
    mut sinks: Vec<Box<dyn Sink>>,
    items: &mpsc::Receiver<SinkItem>,
) -> Result<(Vec<FlagMessage>, u64), SinkError> {
    crate::pipeline::priority::idle_this_thread();
    let mut flags = Vec::new();
    let mut count = 0u64;
    while let Ok(item) = items.recv() {
        if let SinkItem::Message(message) = &item {
            count += 1;
            if let PipelineMessage::Flag(flag) = message {
                flags.push(flag.clone());
            }
        }
        for sink in sinks.iter_mut() {
            item.deliver_to(sink.as_mut());
        }
    }
    let mut first_error = None;
    for sink in sinks.iter_mut() {
        if let Err(e) = sink.finish() {
            first_error.get_or_insert(e);
        }
    }
    match first_error {
        None => Ok((flags, count)),
        Some(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::super::run::SINK_QUEUE;
    use super::*;
    use crate::config::Config;
    use crate::messages::{AlertMessage, AlertState, AlertSubject, ChannelId, FaultKind};
    use crate::messages::{FlagLevel, HealthKind, HealthMessage};
    use std::sync::{Arc, Mutex};

    /// What an immediate sink saw: each item's kind, the wall time it was told last, and
    /// whether the sink queue held anything yet.
    type Seen = Arc<Mutex<Vec<(&'static str, Option<u64>, bool)>>>;

    /// An immediate sink that looks into the sink queue as it is handed each item.
    struct Watching {
        queue: Arc<Mutex<mpsc::Receiver<SinkItem>>>,
        arrived: Option<u64>,
        seen: Seen,
    }

    impl Watching {
        fn note(&mut self, kind: &'static str) {
            let queued = self.queue.lock().unwrap().try_recv().is_ok();
            self.seen.lock().unwrap().push((kind, self.arrived, queued));
        }
    }

    impl Sink for Watching {
        fn write(&mut self, _: &PipelineMessage) {
            self.note("message");
        }
        fn alert(&mut self, _: &AlertMessage) {
            self.note("alert");
        }
        fn arrived(&mut self, wall_time_ns: u64) {
            self.arrived = Some(wall_time_ns);
        }
        fn finish(&mut self) -> Result<(), SinkError> {
            Ok(())
        }
    }

    /// An analysis thread on the embedded default whose one immediate sink is `immediate`.
    fn analysis_thread(
        immediate: Box<dyn Sink>,
        queue: mpsc::SyncSender<SinkItem>,
    ) -> AnalysisThread {
        let config = Config::default_embedded().unwrap();
        let pipeline = Pipeline::new(&config, &Default::default(), None);
        let (_, inputs) = async_mpsc::channel(1);
        let (_, fits) = mpsc::sync_channel(1);
        let (status, _) = watch::channel(pipeline.status());
        AnalysisThread {
            pipeline,
            sinks: SinkEnds {
                immediate: vec![immediate],
                queue,
                pending: Vec::new(),
            },
            inputs,
            twin_requests: None,
            fits,
            status,
            requests_skipped: 0,
            state_dir: bearingd_testdata::scratch_dir("analysis-thread"),
            state_every: Duration::MAX,
            state_saved: std::time::Instant::now(),
            events: super::super::ignore_events(),
            cpus_awake: None,
        }
    }

    fn channel() -> ChannelId {
        ChannelId {
            sensor: "motor-de".into(),
            axis: "radial".into(),
        }
    }

    #[test]
    fn the_immediate_sink_has_the_alert_before_the_sink_queue_has_anything() {
        let (queue, queued) = mpsc::sync_channel(SINK_QUEUE);
        let queued = Arc::new(Mutex::new(queued));
        let seen = Seen::default();
        let watching = Watching {
            queue: queued.clone(),
            arrived: None,
            seen: seen.clone(),
        };
        let mut thread = analysis_thread(Box::new(watching), queue);
        let health = PipelineMessage::Health(HealthMessage {
            channel: channel(),
            end_sample: 2560,
            kind: HealthKind::Gap,
            stage: None,
            detail: String::new(),
        });
        let alert = AlertMessage {
            sequence: 1,
            run_id: 9,
            channel: channel(),
            end_sample: 2560,
            sample_rate_hz: 25_600.0,
            subject: AlertSubject::Fault(FaultKind::OuterRace),
            state: AlertState::Raised,
            severity: FlagLevel::Watch,
            previous_severity: FlagLevel::Ok,
            score: 30.0,
            confidence: 0.9,
            fault_frequency_hz: Some(107.0),
            twin_error: None,
        };
        // An input whose source completed it at 42 gives a message, then an alert.
        thread.deliver(42, |_, out| {
            out(Output::Message(health.clone()));
            out(Output::Alert(alert.clone()));
        });
        assert_eq!(
            *seen.lock().unwrap(),
            [("message", Some(42), false), ("alert", Some(42), false)]
        );
        // Then the queue has both, in order.
        let queued = queued.lock().unwrap();
        assert_eq!(queued.try_recv(), Ok(SinkItem::Message(health)));
        assert_eq!(queued.try_recv(), Ok(SinkItem::Alert(alert)));
        assert!(queued.try_recv().is_err());
    }

    /// An immediate sink whose finish fails.
    struct Failing;

    impl Sink for Failing {
        fn write(&mut self, _: &PipelineMessage) {}
        fn finish(&mut self) -> Result<(), SinkError> {
            Err(SinkError {
                sink: "failing",
                count: 1,
                first: "it could not close".into(),
            })
        }
    }

    #[test]
    fn the_stop_finishes_the_immediate_sinks_and_reports_their_failure() {
        let (queue, queued) = mpsc::sync_channel(SINK_QUEUE);
        let thread = analysis_thread(Box::new(Failing), queue);
        let summary = thread.stop();
        let failed = summary.immediate_sinks.unwrap_err();
        assert_eq!(failed.sink, "failing");
        // The sink queue is closed: the sink thread ends.
        while queued.try_recv().is_ok() {}
        assert_eq!(queued.try_recv(), Err(mpsc::TryRecvError::Disconnected));
    }

    /// An immediate sink that keeps nothing.
    struct Discarding;

    impl Sink for Discarding {
        fn write(&mut self, _: &PipelineMessage) {}
        fn finish(&mut self) -> Result<(), SinkError> {
            Ok(())
        }
    }

    fn sensor_lost() -> Arrived {
        Arrived {
            input: crate::pipeline::Input::SensorLost {
                sensor: "motor-de".into(),
            },
            wall_ns: 1,
        }
    }

    #[test]
    fn the_cpus_woken_at_the_hand_over_may_halt_once_the_block_is_analysed() {
        use crate::sources::HandOverWatch as _;
        let (queue, _queued) = mpsc::sync_channel(SINK_QUEUE);
        let mut thread = analysis_thread(Box::new(Discarding), queue);
        let device = bearingd_testdata::scratch_dir("cpus-awake").join("cpu_dma_latency");
        std::fs::write(&device, b"").unwrap();
        let cpus = CpusAwake::open(&device).unwrap();
        thread.cpus_awake = Some(cpus.clone());
        cpus.handed_over();
        thread.analyse(sensor_lost());
        // What the PM QoS device was told, in order: 0 µs at the hand-over, then no constraint.
        let told = std::fs::read(&device).unwrap();
        assert_eq!(told[..4], 0i32.to_ne_bytes());
        assert_eq!(told[4..], 2_000_000_000i32.to_ne_bytes());
    }

    #[test]
    fn a_refused_awake_request_is_said_once_and_not_made_again() {
        use crate::sources::HandOverWatch as _;
        let (queue, _queued) = mpsc::sync_channel(SINK_QUEUE);
        let mut thread = analysis_thread(Box::new(Discarding), queue);
        let (events, kept) = crate::daemon::events::kept_events();
        thread.events = events;
        // Every write to /dev/full fails (no space).
        let cpus = CpusAwake::open(std::path::Path::new("/dev/full")).unwrap();
        thread.cpus_awake = Some(cpus.clone());
        cpus.handed_over();
        thread.analyse(sensor_lost());
        cpus.handed_over();
        thread.analyse(sensor_lost());
        assert!(thread.cpus_awake.is_none());
        let kept = kept.lock().unwrap();
        let refused = kept.iter().filter(|e| e.contains("CpuLatencyRefused"));
        assert_eq!(refused.count(), 1, "{kept:?}");
    }
}
