//! Alerts: how other programs on the box learn that a fault flag changed.
//!
//! Each flag change of the pipeline becomes one [`Alert`] (raised, escalated, relaxed,
//! cleared), numbered, with its confidence and the twin's error, published on the iceoryx2
//! service `outputs.alerts_service` (default `bearingd/alerts`). `bearingd alerts` and
//! `examples/alerts_subscriber.py` subscribe. Layout, codes and service shape:
//! `docs/ALERTS.md`.
//!
//! - [`payload`]: the `#[repr(C)]` record and its readable view.
//! - [`tracker`]: flag changes → alerts (sans-IO).
//! - [`service`]: the iceoryx2 publisher and subscriber.

pub mod payload;
#[cfg(feature = "shm")]
pub mod service;
pub mod tracker;

pub use payload::{Alert, AlertState, AlertView};
pub use tracker::AlertTracker;

/// What the daemon's alert publisher did, for its summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PublisherSummary {
    pub published: u64,
    /// Alerts that found the queue to the publisher thread full (never expected: alerts are
    /// rare and the thread only copies them).
    pub dropped: u64,
}
