//! What the daemon has to tell its operator while it runs: typed events, handed to a callback
//! the caller gives ([`Events`]). The daemon never prints; the command line decides how each
//! event reads (`crate::cli`), tests can collect them.

use super::state::{StateError, StateLoaded};
use crate::mcap_log::McapLogError;
use crate::messages::ChannelId;
use crate::pipeline::ChannelStatus;
#[cfg(feature = "shm")]
use crate::sinks::alerts::AlertError;
use crate::sinks::mcap::{LogNotice, RecoveryReport};
use crate::sinks::systemd::NotifyError;
use std::path::PathBuf;
use std::sync::Arc;

/// Where the daemon's events go; called from any of its threads.
pub type Events = Arc<dyn Fn(DaemonEvent) + Send + Sync>;

/// An event handler that drops every event (for library callers that want none).
pub fn ignore_events() -> Events {
    Arc::new(|_| {})
}

/// Events that keep what they were told, one `Debug` line each (for tests that check what
/// the operator is told).
#[cfg(test)]
pub fn kept_events() -> (Events, Arc<std::sync::Mutex<Vec<String>>>) {
    let kept = Arc::new(std::sync::Mutex::new(Vec::new()));
    let events: Events = {
        let kept = kept.clone();
        #[allow(clippy::unwrap_used)]
        Arc::new(move |event| kept.lock().unwrap().push(format!("{event:?}")))
    };
    (events, kept)
}

/// Something the operator should know.
#[derive(Debug)]
pub enum DaemonEvent {
    /// A data directory's lock file named a previous owner that did not stop cleanly (killed,
    /// or the power went): its lock was free and is now this process's.
    StaleLockTakenOver { path: PathBuf, previous: String },
    /// A file a crash left unfinished was recovered at start.
    Recovered(RecoveryReport),
    /// What the MCAP log tells: retention deleted the oldest files (the disk budget,
    /// `outputs.mcap_disk_budget_mb`), a write failed and logging is paused (a full disk), it
    /// goes on.
    Log(LogNotice),
    /// The MCAP log's first file is open.
    LoggingTo(PathBuf),
    /// The CPUs' wake-up latency is capped at `latency_us` µs while bearingd runs
    /// (`outputs.cpu_wakeup_latency_us`).
    CpuLatencyCapped { latency_us: u32 },
    /// A request on the PM QoS device (`outputs.cpu_wakeup_latency_us`, or
    /// `outputs.cpu_awake_during_analysis` at the start or later) could not be held; bearingd
    /// runs on without it.
    CpuLatencyRefused(super::cpu_latency::CpuLatencyError),
    /// The kernel gives transparent huge pages but glibc was not told to put the heap in them:
    /// these `GLIBC_TUNABLES` are missing ([`super::heap_pages`]). Said once, at the start of
    /// a run at real time.
    HeapInSmallPages { missing: Vec<&'static str> },
    /// The iceoryx2 root was this user's but readable by others (made by an earlier bearingd
    /// or by iceoryx2, `0750`): it is now `0700`.
    IoxRootTightened { root: PathBuf, from: u32 },
    /// The alert service is up.
    /// `reopened`: the service was this user's previous run's, kept alive by connected
    /// subscribers, and of our shape: opened again, not created (issue 32).
    AlertsOn {
        service: String,
        root: PathBuf,
        reopened: bool,
    },
    /// A dead iceoryx2 node under the root (a killed daemon's, or a killed publisher's): its
    /// resources were removed at start, or could not be.
    #[cfg(feature = "shm")]
    DeadIoxNode {
        root: PathBuf,
        node: crate::iox::DeadNode,
    },
    /// The iceoryx2 nodes under the root could not be listed to find dead ones.
    #[cfg(feature = "shm")]
    DeadIoxNodesUnknown(String),
    /// This bearingd was built without iceoryx2: flags go to the log only.
    NoAlertService,
    /// iceoryx2 refused an alert.
    #[cfg(feature = "shm")]
    AlertFailed(AlertError),
    /// A twin re-fit request of `channel` (its window ending at `dropped_end_sample`) was
    /// still waiting when the channel asked again: that fit is not made. `total` so far.
    TwinFitDropped {
        channel: ChannelId,
        dropped_end_sample: u64,
        total: u64,
    },
    /// The fleet bridge's notices (connected, broker unreachable or refusing, queue full, its
    /// summary at the stop), one line each.
    Fleet(String),
    /// A live source stopped with an error (`source` names it: `CAN source`, `iceoryx2 source
    /// bearingd/accel/<sensor>`).
    SourceStopped { source: String, error: String },
    /// A source task ended abnormally (it panicked or was cancelled).
    SourceTaskFailed(String),
    /// Sample blocks of a channel the config does not know were skipped.
    UnknownChannel { channel: ChannelId, blocks: u64 },
    /// The health baselines kept across restarts were loaded at start.
    StateLoaded(StateLoaded),
    /// No saved state in this directory: the baselines are learned from the start.
    NoState(PathBuf),
    /// The health baselines kept across restarts could not be read (they are learned again),
    /// or could not be saved at stop.
    State(StateError),
    /// systemd could not be notified (said once).
    Notify(NotifyError),
    /// Every channel's state, every `outputs.status_interval_s` (when status lines are asked
    /// for).
    Status(Vec<ChannelStatus>),
    /// A message of a replayed log could not be read; the replay goes on.
    ReplayUnreadable(McapLogError),
    /// A replay's progress, every [`crate::daemon::ReplayOptions::progress_every`].
    ReplayProgress {
        sample_seconds: f64,
        bytes_read: u64,
        bytes_total: u64,
        raw_blocks: u64,
        flag_changes: usize,
    },
}
