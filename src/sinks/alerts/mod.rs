//! Alerts: how other programs on the box learn that a fault flag changed.
//!
//! The pipeline decides each alert once (`pipeline::alerts`: raised, escalated, relaxed,
//! cleared, numbered, with its confidence and the twin's error); [`AlertSink`] publishes it on
//! the iceoryx2 service `outputs.alerts_service` (default `bearingd/alerts`). `bearingd
//! alerts` and `examples/alerts_subscriber.py` subscribe. Layout, codes and service shape:
//! `docs/ALERTS.md`.
//!
//! - [`payload`]: the `#[repr(C)]` record and its readable view.
//! - [`delay`]: how long after its input each alert was in the service (the daemon's part of
//!   its latency), for the run's summary.
//! - [`sequence`]: a subscriber's check of sequence numbers (sans-IO): losses, duplicates,
//!   restarts, and jumps that cannot be trusted.
//! - [`service`]: the iceoryx2 publisher and subscriber.
//! - [`AlertSink`]: the publisher as a [`Sink`](crate::pipeline::Sink) that `run` calls on the
//!   analysis thread: an alert leaves as soon as it is decided, never behind the MCAP log or
//!   another thread's wake-up.

pub mod delay;
pub mod payload;
pub mod sequence;
#[cfg(feature = "shm")]
pub mod service;
#[cfg(feature = "shm")]
mod verify;

pub use delay::DelaySpread;
pub use payload::{Alert, AlertState, AlertView};
#[cfg(feature = "shm")]
pub use service::{AlertError, AlertPublisher, AlertServiceSettings};

/// What the daemon's alert publisher did, for its summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PublisherSummary {
    pub published: u64,
    /// Alerts iceoryx2 refused to send (each reported as it happened).
    pub failed: u64,
    /// How long after their input arrived the published alerts were in the service; `None`
    /// when none was published.
    pub in_service: Option<DelaySpread>,
}

/// Where an [`AlertSink`] leaves its [`PublisherSummary`] when it finishes, for whoever
/// assembled it (the sink itself is boxed among the others).
pub type SummarySlot = std::sync::Arc<std::sync::OnceLock<PublisherSummary>>;

/// The publisher of `outputs.alerts_service` as a sink: each alert of the pipeline, stamped
/// with the wall time its input arrived ([`Sink::arrived`](crate::pipeline::Sink::arrived)),
/// sent at once. An alert iceoryx2 refuses is reported as it happens (`on_failure`) and
/// counted; it does not fail the sink.
#[cfg(feature = "shm")]
pub struct AlertSink {
    publisher: Option<AlertPublisher>,
    /// When the source completed the input whose alerts come next; `None` before the first.
    arrived_ns: Option<u64>,
    on_failure: Box<dyn FnMut(AlertError) + Send>,
    summary: SummarySlot,
}

#[cfg(feature = "shm")]
impl AlertSink {
    /// Creates the service for `config`'s channels (a history deep enough for all of them, see
    /// [`history_size_for`](crate::pipeline::alerts::history_size_for)) under `iox`;
    /// `on_failure` hears each alert iceoryx2 refuses.
    pub fn start(
        config: &crate::config::Config,
        iox: crate::iox::IoxSettings,
        on_failure: impl FnMut(AlertError) + Send + 'static,
    ) -> Result<AlertSink, AlertError> {
        let history = crate::pipeline::alerts::history_size_for(config.channel_count());
        let settings = AlertServiceSettings {
            service: config.outputs.alerts_service.clone(),
            iox,
        };
        Ok(AlertSink {
            publisher: Some(AlertPublisher::start(settings, history)?),
            arrived_ns: None,
            on_failure: Box::new(on_failure),
            summary: SummarySlot::default(),
        })
    }

    /// Whether the service was a previous run's of this user, reopened (see
    /// [`AlertPublisher::reopened`]).
    pub fn reopened(&self) -> bool {
        self.publisher.as_ref().is_some_and(|p| p.reopened)
    }

    /// Where the summary will be once the sink has finished.
    pub fn summary(&self) -> SummarySlot {
        std::sync::Arc::clone(&self.summary)
    }
}

#[cfg(feature = "shm")]
impl crate::pipeline::Sink for AlertSink {
    fn write(&mut self, _message: &crate::messages::PipelineMessage) {}

    fn alert(&mut self, alert: &crate::messages::AlertMessage) {
        let Some(publisher) = self.publisher.as_mut() else {
            return;
        };
        let wall_time_ns = self
            .arrived_ns
            .unwrap_or_else(crate::clock::wall_clock_now_ns);
        if let Err(e) = publisher.send(Alert::of_message(alert, wall_time_ns)) {
            (self.on_failure)(e);
        }
    }

    fn arrived(&mut self, wall_time_ns: u64) {
        self.arrived_ns = Some(wall_time_ns);
    }

    /// Closes the ports; the summary goes to [`summary`](AlertSink::summary).
    fn finish(&mut self) -> Result<(), crate::pipeline::SinkError> {
        if let Some(publisher) = self.publisher.take() {
            let _ = self.summary.set(publisher.finish());
        }
        Ok(())
    }
}
