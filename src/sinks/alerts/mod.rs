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
//! - [`sequence`]: a subscriber's check of sequence numbers (sans-IO): losses, duplicates,
//!   restarts, and jumps that cannot be trusted.
//! - [`service`]: the iceoryx2 publisher and subscriber.
//! - [`AlertSink`]: the tracker and the publisher as the daemon drives them, on the analysis
//!   thread: an alert leaves as soon as it is decided, never behind the MCAP log or another
//!   thread's wake-up.

pub mod payload;
pub mod sequence;
#[cfg(feature = "shm")]
pub mod service;
pub mod tracker;
#[cfg(feature = "shm")]
mod verify;

pub use payload::{Alert, AlertState, AlertView};
#[cfg(feature = "shm")]
pub use service::{AlertError, AlertPublisher, AlertServiceSettings};
pub use tracker::AlertTracker;

/// What the daemon's alert publisher did, for its summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PublisherSummary {
    pub published: u64,
    /// Alerts iceoryx2 refused to send (each reported as it happened).
    pub failed: u64,
}

/// The alert service as the daemon drives it: the tracker (flag changes → alerts) and the
/// publisher of `outputs.alerts_service`.
#[cfg(feature = "shm")]
pub struct AlertSink {
    tracker: AlertTracker,
    publisher: AlertPublisher,
}

#[cfg(feature = "shm")]
impl AlertSink {
    /// Creates the service for `config`'s channels (a history deep enough for all of them, see
    /// [`tracker::history_size_for`]) under `iox`; `run_id` numbers this daemon run.
    pub fn start(
        config: &crate::config::Config,
        iox: crate::iox::IoxSettings,
        run_id: u64,
    ) -> Result<AlertSink, AlertError> {
        let history = tracker::history_size_for(config.channel_count());
        let settings = AlertServiceSettings {
            service: config.outputs.alerts_service.clone(),
            iox,
        };
        let publisher = AlertPublisher::start(settings, history)?;
        let tracker = AlertTracker::new(run_id, history, &config.analysis, config.sample_rates());
        Ok(AlertSink { tracker, publisher })
    }

    /// Takes one pipeline message; publishes the alerts it causes, stamped `wall_time_ns`. An
    /// alert iceoryx2 refuses goes to `failed`.
    pub fn observe(
        &mut self,
        message: &crate::messages::PipelineMessage,
        wall_time_ns: u64,
        failed: &mut impl FnMut(AlertError),
    ) {
        let publisher = &mut self.publisher;
        self.tracker.observe(message, wall_time_ns, &mut |alert| {
            if let Err(e) = publisher.send(alert) {
                failed(e);
            }
        });
    }

    /// Whether the service was a previous run's of this user, reopened (see
    /// [`AlertPublisher::reopened`]).
    pub fn reopened(&self) -> bool {
        self.publisher.reopened
    }

    /// Takes a twin fit made on the re-fit thread (its confidence weighs in on later alerts).
    pub fn note_twin(&mut self, fit: &crate::messages::TwinMessage) {
        self.tracker.note_twin(fit);
    }

    /// Closes the ports and reports.
    pub fn finish(self) -> PublisherSummary {
        self.publisher.finish()
    }
}
