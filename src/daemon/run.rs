//! `bearingd run`: sources → the analysis thread → the sink thread, with the twin's re-fits on
//! their own thread and status on the async side.
//!
//! [`run`] is a sequence of named steps: prepare the state directory and the iceoryx2 root,
//! lock the data directories, open the sources' devices, assemble the sinks
//! ([`super::sinks`]: the alert service, the fleet bridge, the log last, so that a refused
//! start leaves no file), start the threads, start the sources, supervise until a stop, stop
//! in order. Each thread owns its state and talks to the others over bounded channels only:
//!
//! - async (tokio): sources, signals, status. Sources send into the analysis queue
//!   ([`ANALYSIS_QUEUE`]) and wait when it is full (`Block`): an in-process source is simply
//!   slowed; a transport source then backs up into its own buffer, where a loss shows as an
//!   exact sequence gap.
//! - analysis thread (`threads::AnalysisThread`): owns the [`Pipeline`] and the immediate sinks (the
//!   alert publisher); hands each output to the immediate sinks as it comes, so the pipeline's
//!   alerts are published on this thread (iceoryx2's send does not block), hands each input's
//!   messages and alerts to the sink queue (`Block`) once they are all out, and hands twin
//!   requests to the re-fit
//!   hand-over ([`crate::pipeline::twin_queue`]: one slot per channel, served in turn; a request
//!   still waiting when its channel asks again is dropped, counted and reported). Band
//!   selections run on the pipeline's own worker thread ([`crate::pipeline::bands`]). Each input carries the wall-clock time its
//!   source completed it ([`Arrived`]); alerts carry that time of the block that decided them,
//!   so their latency includes any wait in the queue. The analysis never sees it. After every
//!   input it publishes the channels' status on a `watch` channel (the latest value only).
//! - alert keeper thread: updates the alert publisher's connections, so that a late
//!   subscriber is handed the history ([`crate::sinks::alerts::service`]). Alerts skip the
//!   sink queue so that MCAP compression never delays them.
//! - re-fit thread: [`TwinWorker`]; its fits (the twin's, then the HW model's) go back to the
//!   analysis thread through a bounded hand-over (two slots per channel, plus two; the re-fit
//!   thread waits when it is full), and
//!   the analysis thread passes them on to the sinks, so that the sink queue has one producer.
//! - sink thread: the queued sinks (log, fleet bridge, flag printer); it owns the files, so
//!   flushing and finishing them at shutdown happens there.
//!
//! Every thread but the analysis thread runs at a lower CPU priority
//! ([`crate::pipeline::priority`]), so that the daemon's own background work never preempts
//! the thread that decides alerts.
//!
//! Stopping: the sources end (a signal, `--duration`, or all of them finished); their sender
//! closing ends the analysis thread, which closes the re-fit queue, takes the last fits and
//! closes the sink queue, which ends the sink thread.

use super::cpu_latency::{CpuLatencyCap, CpusAwake, CPU_LATENCY_DEVICE};
use super::events::{DaemonEvent, Events};
use super::heap_pages::{self, HeapPages};
use super::lock::{DirLock, LockError};
use super::sinks::{assemble, SinkPlan, SinkStart, SinkStartError, Sinks};
use super::state::load_baselines;
use super::threads::{refit_thread, sink_thread, AnalysisThread, SinkEnds};
use crate::analysis::agreement::Witness;
use crate::clock::wall_clock_now_ns;
use crate::config::{Config, Transport};
use crate::messages::{FlagMessage, PipelineMessage};
use crate::pipeline::load_learned;
use crate::pipeline::twin_queue::twin_requests;
use crate::pipeline::{ChannelStatus, Pipeline, SinkError, SinkItem, TwinWorker};
use crate::sinks::systemd::{keep_alive, status_text, Notifier};
use crate::sources::live::{can_interfaces, shm_sensors};
#[cfg(any(feature = "can", feature = "shm"))]
use crate::sources::live::{forward, SENSOR_TIMEOUT};
use crate::sources::sim::SimSource;
use crate::sources::{AnalysisInbox, Arrived, HandOverWatch};
use std::path::{Path, PathBuf};
use std::sync::{mpsc, Arc};
use std::time::Duration;
use tokio::sync::{mpsc as async_mpsc, watch};
use tokio::task::JoinSet;

/// How `run` should behave beyond the config.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Stop after this much sample time (seconds); `None`: until a signal.
    pub duration_s: Option<f64>,
    /// Pace simulated sensors at real time (`true`) or as fast as the analysis allows.
    pub realtime: bool,
    /// Report every channel's status ([`DaemonEvent::Status`]) every `status_interval_s`.
    pub status_lines: bool,
}

/// Why `run` could not start or had to stop.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[cfg(feature = "can")]
    #[error("source: {0}")]
    Can(#[from] crate::sources::can::CanSourceError),
    #[error("source: {what}: this bearingd was built without the `{feature}` feature")]
    NotBuilt { what: String, feature: &'static str },
    #[error("{path}: cannot create the directory: {source}; check its permissions or set outputs.state_dir / outputs.mcap_dir")]
    Directory {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Locked(#[from] LockError),
    #[error("data directory refused: {0}")]
    UnsafeDir(#[from] crate::fsafe::UnsafeDir),
    #[error("{0} (the default root is under $XDG_RUNTIME_DIR, else /run/bearingd; outputs.iceoryx2_root sets another)")]
    IoxRoot(crate::fsafe::UnsafeDir),
    #[error(transparent)]
    Sinks(#[from] SinkStartError),
    #[error("cannot start the {what} thread: {source}")]
    ThreadSpawn {
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error("the {what} thread panicked (its message is in the log above)")]
    ThreadPanicked { what: &'static str },
    #[error("sink thread failed: {0}")]
    Sink(#[from] SinkError),
    #[error("twin.learned_model: {0}")]
    Learned(#[from] crate::learned::ModelError),
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
    /// Alerts iceoryx2 refused (reported as they happen).
    pub alerts_failed: u64,
    /// How long after their input arrived the published alerts were in the service (the
    /// daemon's part of their latency; the subscribers' wake-up comes on top).
    pub alerts_in_service: Option<crate::sinks::alerts::DelaySpread>,
}

/// Inputs waiting for the analysis thread, at most.
pub const ANALYSIS_QUEUE: usize = 64;
/// Messages waiting for the sink thread, at most.
pub const SINK_QUEUE: usize = 1024;
/// Length of a simulated sensor's block, in seconds of sample time.
const SIM_BLOCK_S: f64 = 0.1;

/// Runs until `shutdown` resolves, the duration is reached or every source has ended, into the
/// sinks of `plan` ([`SinkPlan::run`]); what the operator should know goes to `events`.
pub async fn run(
    config: Config,
    options: RunOptions,
    plan: SinkPlan,
    events: Events,
    shutdown: impl std::future::Future<Output = ()>,
) -> Result<RunSummary, RunError> {
    // Everything that can refuse the start comes before the log, which `assemble` opens last:
    // a refused start must not leave an empty log behind (one per restart, issue 32).
    let state_dir = prepare_state_dir(&config)?;
    prepare_iox_root(&config, &events)?;
    let _locks = lock_data_dirs(&config, &events)?;
    let can_sources = open_can_sources(&config)?;
    let learned = load_learned(&config.twin)?;
    // The learned state before the log, which records what the run started with.
    let (baselines, loaded) = load_baselines(&state_dir);
    match loaded {
        Ok(Some(loaded)) => events(DaemonEvent::StateLoaded(loaded)),
        Ok(None) => events(DaemonEvent::NoState(state_dir.clone())),
        Err(problem) => events(DaemonEvent::State(problem)),
    }
    // Wall time of sample 0: the log's time base and the fleet bridge's; it also names the
    // run, in the log's metadata and in every alert.
    let origin_ns = wall_clock_now_ns();
    let start = SinkStart {
        run_id: origin_ns,
        origin_ns,
        baselines: &baselines,
    };
    let Sinks {
        immediate,
        queued,
        alerts,
    } = assemble(&config, plan, &start, &events)?;
    let _cpu_latency = cap_cpu_latency(&config, &events);
    let pipeline = Pipeline::new(
        &config,
        &baselines,
        learned.clone().map(|m| m as Arc<dyn Witness>),
    )
    .with_run_id(origin_ns);

    let (input_tx, input_rx) = async_mpsc::channel::<Arrived>(ANALYSIS_QUEUE);
    let (sink_tx, sink_rx) = mpsc::sync_channel::<SinkItem>(SINK_QUEUE);
    let (request_tx, request_rx) = twin_requests();
    // Two messages per request at most (the twin's fit, the HW model's).
    let (fit_tx, fit_rx) = mpsc::sync_channel::<PipelineMessage>(2 * config.channel_count() + 2);
    let (status_tx, status_rx) = watch::channel(pipeline.status());

    let sink = spawn("sink", move || sink_thread(queued, &sink_rx))?;
    let worker = TwinWorker::new(&config.twin, learned);
    let refit = spawn("twin", move || refit_thread(worker, &request_rx, &fit_tx))?;
    let cpus_awake = cpus_awake_during_analysis(&config, options.realtime, &events);
    if options.realtime {
        if let HeapPages::Small { missing } = heap_pages::this_process() {
            events(DaemonEvent::HeapInSmallPages { missing });
        }
    }
    // The sources wake the idle CPUs as they hand a block over; the analysis lets them halt.
    let inputs = AnalysisInbox::new(
        input_tx,
        cpus_awake
            .clone()
            .map(|cpus| Arc::new(cpus) as Arc<dyn HandOverWatch>),
    );
    let analysis = AnalysisThread {
        pipeline,
        sinks: SinkEnds {
            immediate,
            queue: sink_tx,
            pending: Vec::new(),
        },
        inputs: input_rx,
        twin_requests: Some(request_tx),
        fits: fit_rx,
        status: status_tx,
        requests_skipped: 0,
        state_dir,
        state_every: Duration::from_secs_f64(config.outputs.state_save_interval_s),
        state_saved: std::time::Instant::now(),
        events: events.clone(),
        cpus_awake,
    };
    let analysis = spawn("analysis", move || analysis.run())?;

    let (stop_tx, stop_rx) = watch::channel(false);
    let mut sources = JoinSet::new();
    let live = start_live_sources(
        &config,
        can_sources,
        &inputs,
        &stop_rx,
        &mut sources,
        &events,
    )?;
    start_simulated(&config, &options, &inputs, &stop_rx, &mut sources);
    // A weak handle on the analysis queue, to see whether inputs wait there; it does not keep
    // the queue open, so the analysis thread still ends when the sources do.
    let analysis_queue = inputs.downgrade();
    drop(inputs);

    supervise(
        &config,
        &options,
        live,
        &mut sources,
        status_rx.clone(),
        analysis_queue,
        &events,
        shutdown,
    )
    .await;
    let _ = stop_tx.send(true);
    while let Some(finished) = sources.join_next().await {
        if let Err(e) = finished {
            events(DaemonEvent::SourceTaskFailed(e.to_string()));
        }
    }
    // The sources' senders are gone: the analysis thread ends, which ends the re-fit thread
    // and then the sink thread.
    let analysis = join("analysis", analysis)?;
    let twin_fits = join("twin re-fit", refit)?;
    let (flags, messages) = join("sink", sink)??;
    analysis.immediate_sinks?;
    let channels = status_rx.borrow().clone();
    let alerts = alerts.as_ref().and_then(|slot| slot.get().copied());
    Ok(RunSummary {
        channels,
        flags,
        messages,
        twin_fits,
        twin_requests_skipped: analysis.requests_skipped,
        alerts_published: alerts.map_or(0, |s| s.published),
        alerts_failed: alerts.map_or(0, |s| s.failed),
        alerts_in_service: alerts.and_then(|s| s.in_service),
    })
}

/// Caps the CPUs' wake-up latency if the config asks to, for as long as the cap is kept; a
/// cap that cannot be held is reported and the run goes on without it.
fn cap_cpu_latency(config: &Config, events: &Events) -> Option<CpuLatencyCap> {
    let latency_us = config.outputs.cpu_wakeup_latency_us?;
    match CpuLatencyCap::hold(Path::new(CPU_LATENCY_DEVICE), latency_us) {
        Ok(cap) => {
            events(DaemonEvent::CpuLatencyCapped { latency_us });
            Some(cap)
        }
        Err(error) => {
            events(DaemonEvent::CpuLatencyRefused(error));
            None
        }
    }
}

/// The request of `outputs.cpu_awake_during_analysis` if the config keeps it on and the run is
/// paced at real time (with `--fast` the analysis never waits for anything, and the CPUs would
/// poll throughout); one that cannot be opened is reported and the run goes on without it.
fn cpus_awake_during_analysis(
    config: &Config,
    realtime: bool,
    events: &Events,
) -> Option<CpusAwake> {
    if !(config.outputs.cpu_awake_during_analysis && realtime) {
        return None;
    }
    CpusAwake::open(Path::new(CPU_LATENCY_DEVICE))
        .map_err(|error| events(DaemonEvent::CpuLatencyRefused(error)))
        .ok()
}

/// Creates `outputs.state_dir` if it is missing (0750); refuses it if others can write in it.
fn prepare_state_dir(config: &Config) -> Result<PathBuf, RunError> {
    let state_dir = config.outputs.state_dir.clone();
    prepare_data_dir(&state_dir)?;
    Ok(state_dir)
}

/// Creates `dir` if it is missing (0750) and refuses it if other users could plant files in
/// it ([`crate::fsafe::check_private_dir`]).
fn prepare_data_dir(dir: &Path) -> Result<(), RunError> {
    crate::fsafe::create_dir_all(dir).map_err(|source| RunError::Directory {
        path: dir.to_path_buf(),
        source,
    })?;
    crate::fsafe::check_private_dir(dir)?;
    Ok(())
}

/// Makes `outputs.iceoryx2_root` this user's private directory ([`crate::fsafe::prepare_private_root`])
/// before iceoryx2, which would follow a link there and create it `0750`, touches it.
fn prepare_iox_root(config: &Config, events: &Events) -> Result<(), RunError> {
    if !cfg!(feature = "shm") {
        return Ok(()); // no iceoryx2 in this build: the root is never used
    }
    let root = &config.outputs.iceoryx2_root;
    match crate::fsafe::prepare_private_root(root).map_err(RunError::IoxRoot)? {
        crate::fsafe::RootPrepared::Tightened { from } => events(DaemonEvent::IoxRootTightened {
            root: root.clone(),
            from,
        }),
        crate::fsafe::RootPrepared::Created | crate::fsafe::RootPrepared::Ready => {}
    }
    Ok(())
}

/// Locks the log and state directories (one owner each) before anything in them is opened;
/// the locks are held until `run` returns.
fn lock_data_dirs(config: &Config, events: &Events) -> Result<Vec<DirLock>, RunError> {
    let dirs = [&config.outputs.mcap_dir, &config.outputs.state_dir];
    let mut locks: Vec<DirLock> = Vec::new();
    let mut locked: Vec<PathBuf> = Vec::new();
    for dir in dirs {
        prepare_data_dir(dir)?;
        let same = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.clone());
        if locked.contains(&same) {
            continue;
        }
        let lock = DirLock::acquire(dir)?;
        if let Some(previous) = &lock.taken_over_from {
            events(DaemonEvent::StaleLockTakenOver {
                path: lock.path().to_path_buf(),
                previous: previous.clone(),
            });
        }
        locked.push(same);
        locks.push(lock);
    }
    Ok(locks)
}

/// Starts a named thread of the daemon.
fn spawn<T: Send + 'static>(
    what: &'static str,
    body: impl FnOnce() -> T + Send + 'static,
) -> Result<std::thread::JoinHandle<T>, RunError> {
    std::thread::Builder::new()
        .name(format!("bearingd-{what}"))
        .spawn(body)
        .map_err(|source| RunError::ThreadSpawn { what, source })
}

/// Waits for a thread of the daemon; its panic becomes an error.
fn join<T>(what: &'static str, thread: std::thread::JoinHandle<T>) -> Result<T, RunError> {
    thread.join().map_err(|_| RunError::ThreadPanicked { what })
}

/// A CAN interface of the config with its socket open, not yet read.
#[cfg(feature = "can")]
struct OpenedCan {
    interface: String,
    map: crate::sources::live::NodeMap,
    source: crate::sources::can::CanSource,
}

/// Without the `can` feature there is nothing to open.
#[cfg(not(feature = "can"))]
enum OpenedCan {}

/// Opens the socket of every CAN interface of the config, so that a missing interface is an
/// error before anything is written (the log's first file is opened after this).
fn open_can_sources(config: &Config) -> Result<Vec<OpenedCan>, RunError> {
    let mut opened = Vec::new();
    for (interface, map) in can_interfaces(config) {
        #[cfg(feature = "can")]
        {
            use crate::sources::can;
            let source = can::open(can::CanSourceConfig {
                interface: interface.clone(),
                silence_timeout: SENSOR_TIMEOUT,
                receive_buffer_bytes: 4 << 20,
                capture: None,
                capture_frames: 0,
                stats_interval: Some(Duration::from_secs_f64(config.outputs.status_interval_s)),
            })?;
            opened.push(OpenedCan {
                interface,
                map,
                source,
            });
        }
        #[cfg(not(feature = "can"))]
        {
            let _ = (map, &mut opened);
            return Err(RunError::NotBuilt {
                what: format!("CAN interface {interface}"),
                feature: "can",
            });
        }
    }
    Ok(opened)
}

/// Starts the SocketCAN sources opened by [`open_can_sources`] and the iceoryx2 sources of
/// the config; `true` if there is any.
fn start_live_sources(
    config: &Config,
    can_sources: Vec<OpenedCan>,
    inputs: &AnalysisInbox,
    stop: &watch::Receiver<bool>,
    tasks: &mut JoinSet<()>,
    events: &Events,
) -> Result<bool, RunError> {
    #[cfg_attr(not(any(feature = "can", feature = "shm")), allow(unused_mut))]
    let mut any = false;
    // Each source's counters go to the log (`/ingest/<source>`) at the status interval.
    #[cfg_attr(not(feature = "shm"), allow(unused_variables))]
    let status_interval = Duration::from_secs_f64(config.outputs.status_interval_s);
    #[cfg_attr(not(any(feature = "can", feature = "shm")), allow(unused_variables))]
    let stopped = |mut stop: watch::Receiver<bool>| async move {
        let _ = stop.wait_for(|s| *s).await;
    };
    for opened in can_sources {
        #[cfg(feature = "can")]
        {
            any = true;
            let OpenedCan {
                interface,
                map,
                source,
            } = opened;
            let (events_tx, events_rx) = async_mpsc::channel(ANALYSIS_QUEUE);
            let shutdown = stopped(stop.clone());
            let events = events.clone();
            tasks.spawn(async move {
                if let Err(e) = source.run(events_tx, shutdown).await {
                    events(DaemonEvent::SourceStopped {
                        source: "CAN source".into(),
                        error: e.to_string(),
                    });
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
        match opened {}
    }
    for (sensor, map) in shm_sensors(config) {
        #[cfg(feature = "shm")]
        {
            any = true;
            use crate::sources::{handoff::WhenFull, shm};
            let source = shm::ShmSourceConfig {
                sensor: sensor.clone(),
                iox: crate::iox::IoxSettings::with_root(&config.outputs.iceoryx2_root),
                silence_timeout: SENSOR_TIMEOUT,
                // Back-pressure: the publisher's own strategy decides what a slow daemon
                // costs (a waiting publisher loses nothing; a discarding one, exact gaps).
                handoff_capacity: 64,
                when_full: WhenFull::Block,
                stats_interval: Some(status_interval),
            };
            let (events_tx, events_rx) = async_mpsc::channel(ANALYSIS_QUEUE);
            let shutdown = stopped(stop.clone());
            let name = format!("shm-{sensor}");
            let events = events.clone();
            tasks.spawn(async move {
                if let Err(e) = shm::run(source, events_tx, shutdown).await {
                    events(DaemonEvent::SourceStopped {
                        source: format!("iceoryx2 source {}", crate::iox::sensor_service(&sensor)),
                        error: e.to_string(),
                    });
                }
            });
            tasks.spawn(forward(events_rx, map, name, inputs.clone()));
        }
        #[cfg(not(feature = "shm"))]
        {
            let _ = (map, inputs, stop, tasks, events);
            return Err(RunError::NotBuilt {
                what: format!("iceoryx2 sensor {sensor}"),
                feature: "shm",
            });
        }
    }
    Ok(any)
}

/// Starts the simulated sensors of the config, if any, as one task.
fn start_simulated(
    config: &Config,
    options: &RunOptions,
    inputs: &AnalysisInbox,
    stop: &watch::Receiver<bool>,
    tasks: &mut JoinSet<()>,
) {
    let sims: Vec<SimSource> = config
        .sensors
        .iter()
        .filter_map(|sensor| match &sensor.transport {
            Transport::Sim(sim) => Some(SimSource::new(sensor, sim, SIM_BLOCK_S)),
            _ => None,
        })
        .collect();
    if !sims.is_empty() {
        tasks.spawn(feed_simulated(
            sims,
            inputs.clone(),
            options.clone(),
            stop.clone(),
        ));
    }
}

/// Feeds the simulated sensors' blocks, paced at real time or as fast as the queue takes them,
/// until `--duration` or until `stop` turns true (a signal): like the live sources, it must end
/// for the shutdown to go on (without it SIGTERM never stopped a run with a simulated sensor).
///
/// In real time the sensors are out of phase, as independent sensor nodes are: of `n` sensors,
/// the k-th delivers its block k/n of a block period after the first. In phase, every block of
/// a period would reach the analysis thread at once, and the last sensor's window would wait
/// behind all the others' (docs/PERFORMANCE.md, alert latency). The samples are the same
/// either way: only when they are handed over changes.
async fn feed_simulated(
    mut sims: Vec<SimSource>,
    inputs: AnalysisInbox,
    options: RunOptions,
    mut stop: watch::Receiver<bool>,
) {
    let turns = sims.len().max(1);
    let mut ticker = tokio::time::interval(Duration::from_secs_f64(SIM_BLOCK_S / turns as f64));
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut turn = 0;
    loop {
        if *stop.borrow() {
            return;
        }
        // In real time one sensor per tick, in turn; as fast as possible, all at once.
        let due = if options.realtime {
            tokio::select! {
                _ = ticker.tick() => {},
                _ = stop.changed() => return,
            }
            let due = turn..turn + 1;
            turn = (turn + 1) % turns;
            due
        } else {
            0..sims.len()
        };
        for sim in sims.get_mut(due).into_iter().flatten() {
            for input in sim.next_blocks() {
                if !inputs.hand_over(input).await {
                    return;
                }
            }
        }
        let done = options.duration_s.is_some_and(|d| {
            sims.iter()
                .all(|s| s.next_sample() as f64 >= d * s.sample_rate_hz())
        });
        if done || sims.is_empty() {
            return;
        }
        if !options.realtime {
            tokio::task::yield_now().await;
        }
    }
}

/// Tells systemd the daemon is ready, then waits for the end (every source finished, a
/// signal, or `--duration` of a live run), reporting status and keeping the watchdog fed;
/// tells systemd the daemon is stopping.
#[allow(clippy::too_many_arguments)]
async fn supervise(
    config: &Config,
    options: &RunOptions,
    live: bool,
    sources: &mut JoinSet<()>,
    status: watch::Receiver<Vec<ChannelStatus>>,
    analysis_queue: async_mpsc::WeakSender<Arrived>,
    events: &Events,
    shutdown: impl std::future::Future<Output = ()>,
) {
    let interval = Duration::from_secs_f64(config.outputs.status_interval_s);
    // systemd (Type=notify): ready once the log is open, the threads run and the sources are
    // started. A no-op without $NOTIFY_SOCKET.
    let (notifier, problem) = Notifier::from_env();
    let report = |problem| events(DaemonEvent::Notify(problem));
    if let Some(problem) = problem {
        report(problem);
    }
    if let Err(problem) = notifier.ready() {
        report(problem);
    }
    let mut progress = status.clone();
    let supervise = keep_alive(
        &notifier,
        interval,
        || status_text(&status.borrow()),
        // The watchdog rule: alive if the analysis thread took an input since the last check
        // (it publishes the status after every input), or if no input waits for it (a silent
        // sensor is reported as lost, not cured by a restart). Inputs waiting and no progress
        // for the whole WatchdogSec: no more pings.
        || {
            let progressed = progress.has_changed().unwrap_or(false);
            progress.mark_unchanged();
            let idle = analysis_queue
                .upgrade()
                .is_none_or(|queue| queue.capacity() == queue.max_capacity());
            progressed || idle
        },
        report,
    );
    let status_lines = report_status(status.clone(), interval, options.status_lines, events);
    let live_deadline = async {
        match options.duration_s.filter(|_| live) {
            Some(seconds) => tokio::time::sleep(Duration::from_secs_f64(seconds)).await,
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        _ = async { while sources.join_next().await.is_some() {} } => {},
        _ = shutdown => {},
        _ = live_deadline => {},
        _ = status_lines => {},
        _ = supervise => {},
    }
    if let Err(problem) = notifier.stopping() {
        report(problem);
    }
}

/// Every channel's status every `interval` as [`DaemonEvent::Status`] (never resolves).
async fn report_status(
    status: watch::Receiver<Vec<ChannelStatus>>,
    interval: Duration,
    enabled: bool,
    events: &Events,
) {
    if !enabled {
        return std::future::pending().await;
    }
    let mut ticker = tokio::time::interval(interval.max(Duration::from_millis(100)));
    ticker.tick().await;
    loop {
        ticker.tick().await;
        let board = status.borrow().clone();
        events(DaemonEvent::Status(board));
    }
}

#[cfg(test)]
mod tests;
