//! `bearingd run`: sources → the analysis thread → the sink thread, with the twin's re-fits on
//! their own thread and status on the async side.
//!
//! Threads and queues (every queue bounded, its policy declared):
//! - async (tokio): sources, signals, status lines. Sources send into the analysis queue and
//!   wait when it is full (`Block`): an in-process source is simply slowed; a transport source
//!   then backs up into its own buffer, where a loss shows as an exact sequence gap.
//! - analysis thread: the [`Pipeline`]; hands messages to the sink queue (`Block`), flag changes
//!   as alerts to the alert queue (`DropNewest`, counted and reported; alerts are rare), and
//!   twin requests to the re-fit queue (`DropNewest`: a request that finds the re-fit thread
//!   busy is skipped and counted; the next period brings a fresh one). Each input carries the
//!   wall-clock time its source completed it ([`Arrived`]); alerts carry that time of the
//!   block that decided them, so their latency includes any wait in the queue. The analysis
//!   never sees it.
//! - alert thread: the iceoryx2 publisher of `outputs.alerts_service` ([`crate::alerts`]).
//!   Alerts skip the sink queue so that MCAP compression never delays them.
//! - re-fit thread: [`TwinWorker`]; its results go to the sink queue, and back to the analysis
//!   thread (status, alert confidence) through a hand-over list that holds at most the fits of
//!   one request per channel.
//! - sink thread: the sinks (log, flag printer); it owns the files, so flushing and finishing
//!   them at shutdown happens there.

use super::live_source::{can_interfaces, forward, shm_sensors, Arrived, SENSOR_TIMEOUT};
use super::mcap_sink::McapSink;
use super::messages::{ChannelId, FlagMessage, PipelineMessage, TwinMessage};
use super::notify::{keep_alive, Notifier};
use super::pipeline::{ChannelStatus, Output, Pipeline, TwinRequest};
use super::sim_source::SimSource;
use super::twin_worker::TwinWorker;
#[cfg(feature = "shm")]
use crate::alerts::tracker::history_size_for;
use crate::alerts::tracker::AlertTracker;
use crate::analysis::health::Baseline;
use crate::config::{Config, Transport};
use crate::mcap_log::{wall_clock_now_ns, LoggerConfig};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};

/// How `run` should behave beyond the config.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Stop after this much sample time (seconds); `None`: until a signal.
    pub duration_s: Option<f64>,
    /// Pace simulated sensors at real time (`true`) or as fast as the analysis allows.
    pub realtime: bool,
    /// Print a status line per channel every `status_interval_s`.
    pub status_lines: bool,
}

/// Why `run` could not start or had to stop.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("source: {0}")]
    Source(String),
    #[error("{path}: cannot create the directory: {source}; check its permissions or set outputs.state_dir / outputs.mcap_dir")]
    Directory {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("MCAP log: {0}")]
    Log(String),
    #[error("alerts: {0}")]
    Alerts(String),
    #[error("{0}")]
    Fleet(String),
    #[error("{what} thread failed: {detail}")]
    Thread { what: &'static str, detail: String },
}

/// What a run did, for the summary on exit.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunSummary {
    pub channels: Vec<ChannelStatus>,
    pub flags: Vec<FlagMessage>,
    pub messages: u64,
    pub twin_fits: u64,
    pub twin_requests_skipped: u64,
    /// Alerts published on the iceoryx2 alert service.
    pub alerts_published: u64,
    /// Alerts that found the alert queue full (reported as they happen).
    pub alerts_dropped: u64,
}

/// A consumer of pipeline messages on the sink thread.
pub trait Sink: Send {
    fn write(&mut self, message: &PipelineMessage);
    /// Flush and close; called once at shutdown.
    fn finish(&mut self) -> Result<(), String>;
}

const ANALYSIS_QUEUE: usize = 64;
const SINK_QUEUE: usize = 1024;
/// Length of a simulated sensor's block, in seconds of sample time.
const SIM_BLOCK_S: f64 = 0.1;

/// Runs until `shutdown` resolves or the duration is reached.
pub async fn run(
    config: Config,
    options: RunOptions,
    mut sinks: Vec<Box<dyn Sink>>,
    shutdown: impl std::future::Future<Output = ()>,
) -> Result<RunSummary, RunError> {
    let sims: Vec<SimSource> = config
        .sensors
        .iter()
        .filter_map(|sensor| match &sensor.transport {
            Transport::Sim(sim) => Some(SimSource::new(sensor, sim, SIM_BLOCK_S)),
            _ => None,
        })
        .collect();
    let state_dir = config.outputs.state_dir.clone();
    std::fs::create_dir_all(&state_dir).map_err(|source| RunError::Directory {
        path: state_dir.clone(),
        source,
    })?;
    let rates = config
        .sensors
        .iter()
        .map(|s| (s.id.clone(), s.sample_rate_hz))
        .collect();
    // Wall time of sample 0: the log's time base, and the fleet bridge's.
    let origin_ns = wall_clock_now_ns();
    let (mcap, recovered) = McapSink::open(logger_config(&config), rates, origin_ns)
        .map_err(|e| RunError::Log(e.to_string()))?;
    for report in &recovered {
        eprintln!(
            "bearingd: recovered {}: {} messages kept, {} bytes unreadable{}",
            report.path.display(),
            report.messages_recovered,
            report.unreadable_bytes,
            report
                .problem
                .as_ref()
                .map(|(at, why)| format!(" (from byte {at}: {why})"))
                .unwrap_or_default()
        );
    }
    if let Some(path) = mcap.current_path() {
        eprintln!("bearingd: logging to {}", path.display());
    }
    sinks.push(Box::new(mcap));
    if let Some(fleet) = crate::sinks::fleet::FleetSink::start(&config, origin_ns)
        .map_err(|e| RunError::Fleet(e.to_string()))?
    {
        sinks.push(Box::new(fleet));
    }
    let baselines = load_baselines(&state_dir);
    let pipeline = Pipeline::new(&config, &baselines);
    let status_board = Arc::new(Mutex::new(pipeline.status()));
    // Fits made on the re-fit thread, waiting for the analysis thread to take them.
    let fresh_twins: Arc<Mutex<Vec<TwinMessage>>> = Arc::default();
    let alerts = start_alerts(&config)?;
    let skipped = Arc::new(AtomicU64::new(0));
    // Liveness for systemd's watchdog: the analysis thread bumps it after every input, the
    // notify task reads it. An atomic, not the status board, because it must advance even when
    // an input changes no status (a SensorLost, a short block).
    let heartbeat = Arc::new(AtomicU64::new(0));

    let (input_tx, mut input_rx) = tokio::sync::mpsc::channel::<Arrived>(ANALYSIS_QUEUE);
    let (sink_tx, sink_rx) = mpsc::sync_channel::<PipelineMessage>(SINK_QUEUE);
    let (twin_tx, twin_rx) = mpsc::sync_channel::<TwinRequest>(1);

    // The analysis thread.
    let analysis = {
        let sink_tx = sink_tx.clone();
        let status_board = status_board.clone();
        let fresh_twins = fresh_twins.clone();
        let skipped = skipped.clone();
        let heartbeat = heartbeat.clone();
        let state_dir = state_dir.clone();
        std::thread::Builder::new()
            .name("bearingd-analysis".into())
            .spawn(move || {
                let mut pipeline = pipeline;
                let mut alerts = alerts;
                while let Some(arrived) = input_rx.blocking_recv() {
                    let arrived_ns = arrived.wall_ns;
                    pipeline.handle(arrived.input, &mut |output| match output {
                        Output::Message(m) => {
                            if let Some((tracker, publisher)) = alerts.as_mut() {
                                tracker.observe(&m, arrived_ns, &mut |a| publisher.send(a));
                            }
                            let _ = sink_tx.send(m);
                        }
                        Output::Twin(request) => {
                            if twin_tx.try_send(request).is_err() {
                                skipped.fetch_add(1, Ordering::Relaxed);
                            }
                        }
                    });
                    let fits = fresh_twins
                        .lock()
                        .map(|mut f| std::mem::take(&mut *f))
                        .unwrap_or_default();
                    for fit in &fits {
                        pipeline.note_twin(&fit.channel, &fit.hypothesis, fit.error);
                        if let Some((tracker, _)) = alerts.as_mut() {
                            tracker.note_twin(fit);
                        }
                    }
                    if let Ok(mut board) = status_board.lock() {
                        *board = pipeline.status();
                    }
                    heartbeat.fetch_add(1, Ordering::Relaxed);
                }
                save_baselines(&state_dir, &pipeline.baselines());
                for (channel, blocks) in pipeline.unknown_channels() {
                    eprintln!("bearingd: {blocks} blocks of {channel} skipped: no such sensor/axis in the config");
                }
                alerts.map(|(_, publisher)| publisher.finish())
            })
            .map_err(|e| RunError::Thread {
                what: "analysis",
                detail: e.to_string(),
            })?
    };
    // The twin's re-fit thread.
    let refit = {
        let sink_tx = sink_tx.clone();
        let fresh_twins = fresh_twins.clone();
        std::thread::Builder::new()
            .name("bearingd-twin".into())
            .spawn(move || {
                let mut worker = TwinWorker::default();
                let mut fits = 0u64;
                while let Ok(request) = twin_rx.recv() {
                    if let Some(message) = worker.refit(&request) {
                        if let Ok(mut fresh) = fresh_twins.lock() {
                            // At most one pending fit per channel: a newer one replaces it.
                            fresh.retain(|f| f.channel != message.channel);
                            fresh.push(TwinMessage {
                                residual: Vec::new(),
                                ..message.clone()
                            });
                        }
                        fits += 1;
                        let _ = sink_tx.send(PipelineMessage::Twin(message));
                    }
                }
                fits
            })
            .map_err(|e| RunError::Thread {
                what: "twin re-fit",
                detail: e.to_string(),
            })?
    };
    drop(sink_tx);
    // The sink thread.
    let sink = std::thread::Builder::new()
        .name("bearingd-sink".into())
        .spawn(move || {
            let mut flags = Vec::new();
            let mut messages = 0u64;
            let mut errors = Vec::new();
            while let Ok(message) = sink_rx.recv() {
                messages += 1;
                if let PipelineMessage::Flag(flag) = &message {
                    flags.push(flag.clone());
                }
                for sink in sinks.iter_mut() {
                    sink.write(&message);
                }
            }
            for sink in sinks.iter_mut() {
                if let Err(e) = sink.finish() {
                    errors.push(e);
                }
            }
            (flags, messages, errors)
        })
        .map_err(|e| RunError::Thread {
            what: "sink",
            detail: e.to_string(),
        })?;

    // Sources and status on the async side.
    let (stop_tx, stop_rx) = tokio::sync::watch::channel(false);
    let mut sources = tokio::task::JoinSet::new();
    let live = start_live_sources(&config, &input_tx, &stop_rx, &mut sources)?;
    if !sims.is_empty() {
        sources.spawn(feed_simulated(
            sims,
            input_tx.clone(),
            options.clone(),
            stop_rx.clone(),
        ));
    }
    // A weak handle on the analysis queue, to see whether inputs wait there; it does not keep
    // the queue open, so the analysis thread still ends when the sources do.
    let analysis_queue = input_tx.downgrade();
    drop(input_tx);
    // systemd (Type=notify): ready once the log is open, the threads run and the sources are
    // started. A no-op without $NOTIFY_SOCKET.
    let notifier = Notifier::from_env();
    notifier.ready();
    let mut last_beat = 0;
    let supervise = keep_alive(
        &notifier,
        std::time::Duration::from_secs_f64(config.outputs.status_interval_s),
        || {
            status_board
                .lock()
                .map(|b| systemd_status(&b))
                .unwrap_or_default()
        },
        // The watchdog rule: alive if the analysis thread took an input since the last check,
        // or if no input waits for it (a silent sensor is reported as lost, not cured by a
        // restart). Inputs waiting and no progress for the whole WatchdogSec: no more pings.
        || {
            let beat = heartbeat.load(Ordering::Relaxed);
            let progressed = beat != last_beat;
            last_beat = beat;
            let idle = analysis_queue
                .upgrade()
                .is_none_or(|queue| queue.capacity() == queue.max_capacity());
            progressed || idle
        },
    );
    let status = print_status(
        status_board.clone(),
        config.outputs.status_interval_s,
        options.status_lines,
    );
    let live_deadline = async {
        match options.duration_s.filter(|_| live) {
            Some(seconds) => tokio::time::sleep(std::time::Duration::from_secs_f64(seconds)).await,
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        _ = async { while sources.join_next().await.is_some() {} } => {},
        _ = shutdown => {},
        _ = live_deadline => {},
        _ = status => {},
        _ = supervise => {},
    }
    notifier.stopping();
    let _ = stop_tx.send(true);
    while let Some(finished) = sources.join_next().await {
        if let Err(e) = finished {
            eprintln!("bearingd: a source task failed: {e}");
        }
    }
    // Dropping the sources' sender (inside `feed`) ends the analysis thread, which ends the
    // re-fit thread, which ends the sink thread.
    let alert_summary = analysis.join().map_err(|_| RunError::Thread {
        what: "analysis",
        detail: "panicked".into(),
    })?;
    let twin_fits = refit.join().map_err(|_| RunError::Thread {
        what: "twin re-fit",
        detail: "panicked".into(),
    })?;
    let (flags, messages, errors) = sink.join().map_err(|_| RunError::Thread {
        what: "sink",
        detail: "panicked".into(),
    })?;
    if let Some(error) = errors.into_iter().next() {
        return Err(RunError::Thread {
            what: "sink",
            detail: error,
        });
    }
    let channels = status_board.lock().map(|b| b.clone()).unwrap_or_default();
    Ok(RunSummary {
        channels,
        flags,
        messages,
        twin_fits,
        twin_requests_skipped: skipped.load(Ordering::Relaxed),
        alerts_published: alert_summary.map_or(0, |s| s.published),
        alerts_dropped: alert_summary.map_or(0, |s| s.dropped),
    })
}

/// The alert service's publisher and the tracker that feeds it.
#[cfg(feature = "shm")]
type Alerts = (AlertTracker, crate::alerts::service::AlertPublisher);

/// Creates the alert service `outputs.alerts_service` under `outputs.iceoryx2_root` (the file
/// prefix from `$BEARINGD_IOX_PREFIX`, for isolated tests) and the tracker.
#[cfg(feature = "shm")]
fn start_alerts(config: &Config) -> Result<Option<Alerts>, RunError> {
    use crate::alerts::service::{AlertPublisher, AlertServiceSettings};
    use crate::ingest::shm::IoxSettings;
    let channels: usize = config.sensors.iter().map(|s| s.axes.len()).sum();
    let history = history_size_for(channels);
    let settings = AlertServiceSettings {
        service: config.outputs.alerts_service.clone(),
        iox: IoxSettings {
            prefix: std::env::var("BEARINGD_IOX_PREFIX").ok(),
            root_path: Some(config.outputs.iceoryx2_root.display().to_string()),
        },
    };
    let publisher = AlertPublisher::start(settings.clone(), history)
        .map_err(|e| RunError::Alerts(e.to_string()))?;
    eprintln!(
        "bearingd: alerts on iceoryx2 service {} (root {})",
        settings.service,
        config.outputs.iceoryx2_root.display()
    );
    let rates = config
        .sensors
        .iter()
        .map(|s| (s.id.clone(), s.sample_rate_hz))
        .collect();
    let tracker = AlertTracker::new(wall_clock_now_ns(), history, &config.analysis, rates);
    Ok(Some((tracker, publisher)))
}

/// Without iceoryx2 (the `shm` feature) there is no alert service; flags still go to the log.
#[cfg(not(feature = "shm"))]
type Alerts = (AlertTracker, NoPublisher);

#[cfg(not(feature = "shm"))]
struct NoPublisher;

#[cfg(not(feature = "shm"))]
impl NoPublisher {
    fn send(&self, _: crate::alerts::Alert) {}
    fn finish(self) -> crate::alerts::PublisherSummary {
        crate::alerts::PublisherSummary::default()
    }
}

#[cfg(not(feature = "shm"))]
fn start_alerts(_config: &Config) -> Result<Option<Alerts>, RunError> {
    eprintln!("bearingd: built without the `shm` feature: no iceoryx2 alerts are published");
    Ok(None)
}

/// Starts the SocketCAN and iceoryx2 sources of the config; `true` if there is any.
fn start_live_sources(
    config: &Config,
    inputs: &tokio::sync::mpsc::Sender<Arrived>,
    stop: &tokio::sync::watch::Receiver<bool>,
    tasks: &mut tokio::task::JoinSet<()>,
) -> Result<bool, RunError> {
    #[cfg_attr(not(any(feature = "can", feature = "shm")), allow(unused_mut))]
    let mut any = false;
    // Each source's counters go to the log (`/ingest/<source>`) at the status interval.
    let status_interval = std::time::Duration::from_secs_f64(config.outputs.status_interval_s);
    let stopped = |mut stop: tokio::sync::watch::Receiver<bool>| async move {
        let _ = stop.wait_for(|s| *s).await;
    };
    for (interface, map) in can_interfaces(config) {
        #[cfg(feature = "can")]
        {
            any = true;
            use crate::ingest::can;
            let source = can::open(can::CanSourceConfig {
                interface: interface.clone(),
                silence_timeout: SENSOR_TIMEOUT,
                receive_buffer_bytes: 4 << 20,
                capture: None,
                capture_frames: 0,
                stats_interval: Some(status_interval),
            })
            .map_err(|e| RunError::Source(e.to_string()))?;
            let (events_tx, events_rx) = tokio::sync::mpsc::channel(ANALYSIS_QUEUE);
            let shutdown = stopped(stop.clone());
            tasks.spawn(async move {
                if let Err(e) = source.run(events_tx, shutdown).await {
                    eprintln!("bearingd: CAN source stopped: {e}");
                }
            });
            tasks.spawn(forward(
                events_rx,
                map,
                format!("can-{interface}"),
                inputs.clone(),
            ));
        }
        #[cfg(not(feature = "can"))]
        {
            let _ = (map, inputs, stopped);
            return Err(RunError::Source(format!(
                "CAN interface {interface}: this bearingd was built without the `can` feature"
            )));
        }
    }
    for (sensor, map) in shm_sensors(config) {
        #[cfg(feature = "shm")]
        {
            any = true;
            use crate::ingest::{handoff::WhenFull, shm};
            let source = shm::ShmSourceConfig {
                sensor: sensor.clone(),
                iox: shm::IoxSettings {
                    prefix: std::env::var("BEARINGD_IOX_PREFIX").ok(),
                    root_path: Some(config.outputs.iceoryx2_root.display().to_string()),
                },
                silence_timeout: SENSOR_TIMEOUT,
                handoff_capacity: 64,
                when_full: WhenFull::DropOldest,
                stats_interval: Some(status_interval),
            };
            let (events_tx, events_rx) = tokio::sync::mpsc::channel(ANALYSIS_QUEUE);
            let shutdown = stopped(stop.clone());
            let name = format!("shm-{sensor}");
            tasks.spawn(async move {
                if let Err(e) = shm::run(source, events_tx, shutdown).await {
                    eprintln!("bearingd: iceoryx2 source bearingd/accel/{sensor} stopped: {e}");
                }
            });
            tasks.spawn(forward(events_rx, map, name, inputs.clone()));
        }
        #[cfg(not(feature = "shm"))]
        {
            let _ = (map, inputs, stopped);
            return Err(RunError::Source(format!(
                "iceoryx2 sensor {sensor}: this bearingd was built without the `shm` feature"
            )));
        }
    }
    Ok(any)
}

/// Feeds the simulated sensors' blocks, paced at real time or as fast as the queue takes them,
/// until `--duration` or until `stop` turns true (a signal): like the live sources, it must end
/// for the shutdown to go on (without it SIGTERM never stopped a run with a simulated sensor).
async fn feed_simulated(
    mut sims: Vec<SimSource>,
    tx: tokio::sync::mpsc::Sender<Arrived>,
    options: RunOptions,
    mut stop: tokio::sync::watch::Receiver<bool>,
) {
    let mut ticker = tokio::time::interval(std::time::Duration::from_secs_f64(SIM_BLOCK_S));
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        if *stop.borrow() {
            return;
        }
        if options.realtime {
            tokio::select! {
                _ = ticker.tick() => {},
                _ = stop.changed() => return,
            }
        }
        for sim in sims.iter_mut() {
            for input in sim.next_blocks() {
                if tx.send(Arrived::now(input)).await.is_err() {
                    return;
                }
            }
        }
        let done = options.duration_s.is_some_and(|d| {
            sims.iter()
                .all(|s| s.next_sample() as f64 >= d * sim_rate(s))
        });
        if done || sims.is_empty() {
            return;
        }
        if !options.realtime {
            tokio::task::yield_now().await;
        }
    }
}

fn sim_rate(sim: &SimSource) -> f64 {
    sim.sample_rate_hz()
}

/// A status line per channel every `interval_s` (never resolves).
async fn print_status(board: Arc<Mutex<Vec<ChannelStatus>>>, interval_s: f64, enabled: bool) {
    if !enabled {
        return std::future::pending().await;
    }
    let mut ticker = tokio::time::interval(std::time::Duration::from_secs_f64(interval_s.max(0.1)));
    ticker.tick().await;
    loop {
        ticker.tick().await;
        let lines: Vec<String> = board
            .lock()
            .map(|b| b.iter().map(status_line).collect())
            .unwrap_or_default();
        for line in lines {
            println!("{line}");
        }
    }
}

/// One channel's status in one line.
pub fn status_line(s: &ChannelStatus) -> String {
    let band = s.band_hz.map_or("learning".to_string(), |b| {
        format!("{:.0}-{:.0} Hz", b[0], b[1])
    });
    let top = s.top_fault.map_or("-".to_string(), |f| {
        format!("{} {:.1}", f.name(), s.top_score)
    });
    let twin = match (&s.twin_hypothesis, s.twin_error) {
        (Some(h), Some(e)) => format!("{h} err {e:.3}"),
        _ => "-".into(),
    };
    let flags: Vec<String> = crate::analysis::FaultKind::ALL
        .iter()
        .zip(&s.flags)
        .filter(|(_, l)| l.name() != "ok")
        .map(|(k, l)| format!("{}={}", k.name(), l.name()))
        .collect();
    let rpm = match (s.rpm, s.speed_source) {
        (Some(rpm), "fixed") => format!("{rpm:.0}"),
        (Some(rpm), source) => format!("{rpm:.0}({source})"),
        (None, "estimate") => "?(no estimate yet: scoring waits)".to_string(),
        (None, _) => "?(no usable speed frame: scoring waits)".to_string(),
    };
    format!(
        "{} t={:.1}s rpm={} band={} top={} twin={} stage={} flags={}{}",
        s.channel,
        s.seconds,
        rpm,
        band,
        top,
        twin,
        s.stage.name(),
        if flags.is_empty() {
            "ok".to_string()
        } else {
            flags.join(",")
        },
        if s.sensor_lost { " SENSOR LOST" } else { "" }
    )
}

/// The one-line `STATUS=` for systemd (`systemctl status`): channel count, then per channel its
/// sample time, health stage and raised flags; shorter than [`status_line`].
fn systemd_status(board: &[ChannelStatus]) -> String {
    let channels: Vec<String> = board
        .iter()
        .map(|s| {
            let flags: Vec<String> = crate::analysis::FaultKind::ALL
                .iter()
                .zip(&s.flags)
                .filter(|(_, l)| l.name() != "ok")
                .map(|(k, l)| format!("{}={}", k.name(), l.name()))
                .collect();
            let flags = if flags.is_empty() {
                "ok".to_string()
            } else {
                flags.join(",")
            };
            let lost = if s.sensor_lost { " SENSOR LOST" } else { "" };
            format!(
                "{} t={:.1}s {} {flags}{lost}",
                s.channel,
                s.seconds,
                s.stage.name()
            )
        })
        .collect();
    let plural = if board.len() == 1 { "" } else { "s" };
    format!("{} channel{plural}; {}", board.len(), channels.join("; "))
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

const BASELINES_FILE: &str = "baselines.json";

/// Health baselines kept across restarts; a missing or unreadable file starts afresh (and says so).
pub fn load_baselines(state_dir: &Path) -> BTreeMap<ChannelId, Baseline> {
    let path = state_dir.join(BASELINES_FILE);
    let Ok(text) = std::fs::read_to_string(&path) else {
        return BTreeMap::new();
    };
    match serde_json::from_str::<Vec<(ChannelId, Baseline)>>(&text) {
        Ok(list) => list.into_iter().collect(),
        Err(e) => {
            eprintln!(
                "bearingd: warning: {}: unreadable ({e}); health baselines are learned again",
                path.display()
            );
            BTreeMap::new()
        }
    }
}

fn save_baselines(state_dir: &Path, baselines: &BTreeMap<ChannelId, Baseline>) {
    let path = state_dir.join(BASELINES_FILE);
    let temporary = state_dir.join(format!("{BASELINES_FILE}.new"));
    let list: Vec<_> = baselines.iter().collect();
    let written = serde_json::to_string_pretty(&list)
        .map_err(std::io::Error::other)
        .and_then(|text| std::fs::write(&temporary, text))
        .and_then(|_| std::fs::rename(&temporary, &path));
    if let Err(e) = written {
        eprintln!(
            "bearingd: warning: {}: cannot save the health baselines: {e}",
            path.display()
        );
    }
}
