//! Sources: everything that turns sensor data into the pipeline's inputs, in sample time.
//!
//! - [`can`] (feature `can`), [`shm`] (feature `shm`): the transports; [`live`] maps their
//!   events onto the config's channels for `bearingd run`.
//! - [`sim`]: the in-process simulated sensor node (the twin's signal model).
//! - [`replay`]: the raw samples and measured speeds of MCAP logs.
//! - [`Arrived`]: an input with the wall-clock time it arrived ([`crate::clock`]), handed to the
//!   analysis through an [`AnalysisInbox`].
//!
//! Why this module exists apart from the analysis core: the core is sans-IO (no socket, no
//! clock, no async runtime), so something must own the sockets, the shared memory, the
//! timeouts and the queues. These adapters do, and nothing else: they hand (CAN id, bytes)
//! pairs to the one shared [`assemble::Assembler`], which decodes them with the `bearing-wire`
//! crate and reports [`IngestEvent`]s (samples, gaps, restarts, sensor lost/back, speed,
//! metadata, malformed frames) and [`IngestStats`].
//!
//! The transports:
//!
//! - [`can`] (feature `can`): SocketCAN (classic and FD) on tokio.
//! - [`shm`] (feature `shm`): iceoryx2 publish-subscribe `bearingd/accel/<sensor>`, on its own
//!   thread (iceoryx2 ports are not `Send`), woken by an iceoryx2 event, handing batches to
//!   the async side through a bounded [`handoff`] queue.
//!   The payload (`FrameBatch` of CAN-shaped frames) is [`crate::iox`]'s.
//!
//! Queue policies (every drop is counted): frames lost before the assembler (a full socket
//! buffer, a full hand-off queue) reappear as exact sequence gaps; the event channel after the
//! assembler never drops: a source waits for its consumer, which pushes the loss back to the
//! transport's buffer where it is counted as a gap. Sensor silence is timed here, with tokio
//! time, never in the analysis core. More in docs/INGEST.md.

pub mod assemble;
#[cfg(feature = "can")]
pub mod can;
pub mod handoff;
pub mod live;
pub mod replay;
#[cfg(feature = "shm")]
pub mod shm;
pub mod sim;

pub use assemble::{
    Assembler, IngestEvent, IngestStats, MalformedCounts, MalformedKind, SampleBlock, StreamSummary,
};
pub use live::{AnalysisInbox, Arrived, HandOverWatch};

use std::collections::BTreeMap;
use std::time::Duration;
use tokio::time::Instant;

/// What a source returns when it stops: its counters and per-stream totals.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct SourceSummary {
    pub stats: IngestStats,
    pub streams: Vec<StreamSummary>,
}

/// Per-node "last heard" times, to report a node silent for longer than a timeout. Uses
/// tokio's clock so tests can pause time.
#[derive(Debug)]
pub struct SilenceWatch {
    timeout: Duration,
    last_heard: BTreeMap<u8, Instant>,
}

impl SilenceWatch {
    pub fn new(timeout: Duration) -> SilenceWatch {
        SilenceWatch {
            timeout,
            last_heard: BTreeMap::new(),
        }
    }

    pub fn timeout(&self) -> Duration {
        self.timeout
    }

    /// Records that every node in `nodes` was heard at `now`.
    pub fn heard(&mut self, node: u8, now: Instant) {
        self.last_heard.insert(node, now);
    }

    /// Reports nodes silent for longer than the timeout to `assembler` (once per silence).
    pub fn check(&mut self, now: Instant, assembler: &mut Assembler, out: &mut Vec<IngestEvent>) {
        for (&node, &heard) in &self.last_heard {
            if now.saturating_duration_since(heard) > self.timeout {
                assembler.sensor_lost(node, out);
            }
        }
    }
}

/// The node a frame belongs to, from its CAN id (for the silence watch), if the id is ours.
pub fn node_of(can_id: u32) -> Option<u8> {
    bearing_wire::CanId::parse(can_id).map(|id| id.node)
}

/// Where a source's events go: bounded; a full channel makes the source wait (see the module
/// docs for why waiting here is the policy that never loses samples silently).
pub type EventSender = tokio::sync::mpsc::Sender<IngestEvent>;

/// When a source reports its counters ([`IngestEvent::Stats`]): every `every`, with tokio's
/// clock; never when `every` is `None`.
pub struct StatsTimer(Option<tokio::time::Interval>);

impl StatsTimer {
    pub fn new(every: Option<Duration>) -> StatsTimer {
        StatsTimer(every.filter(|d| !d.is_zero()).map(|every| {
            let mut interval = tokio::time::interval_at(Instant::now() + every, every);
            interval.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            interval
        }))
    }

    pub fn enabled(&self) -> bool {
        self.0.is_some()
    }

    /// Resolves at the next report time (never when disabled).
    pub async fn tick(&mut self) {
        match &mut self.0 {
            Some(interval) => {
                interval.tick().await;
            }
            None => std::future::pending().await,
        }
    }
}
