//! The seam between the pipeline and its sinks.

use crate::messages::{AlertMessage, PipelineMessage};

/// A consumer of the pipeline's messages and alerts, in the order the pipeline emitted them.
/// `run` calls its queued sinks (the log, the fleet bridge, the flag printer) on the sink
/// thread and its immediate sinks (the alert publisher) on the analysis thread, before the
/// input's messages go to the sink queue; the replay calls them all on its one thread.
/// Assembled per config in `daemon::sinks`.
pub trait Sink: Send {
    /// Takes one message. A sink that fails keeps the error for [`finish`](Self::finish) and
    /// goes on: one bad write must not stop the analysis.
    fn write(&mut self, message: &PipelineMessage);
    /// Takes one alert, right after the flag change it was decided from. Most sinks ignore
    /// alerts: the flag itself is their record (the MCAP log has `/flags`).
    fn alert(&mut self, _alert: &AlertMessage) {}
    /// The wall-clock time (ns since the epoch) at which the source completed the input whose
    /// messages and alerts come next: `run` tells its immediate sinks, so that a sink stamping
    /// wall time (the alert publisher) counts an alert's latency from its evidence's arrival.
    /// The pipeline itself knows no clock.
    fn arrived(&mut self, _wall_time_ns: u64) {}
    /// Flushes and closes; called once at shutdown.
    fn finish(&mut self) -> Result<(), SinkError>;
}

/// What goes to the sinks, in the pipeline's order: a message, or an alert decided from one.
// Messages are nearly every item and are not boxed (an allocation each); an alert is rare,
// so the room it leaves unused in the queue costs nothing worth a box either.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum SinkItem {
    Message(PipelineMessage),
    Alert(AlertMessage),
}

impl SinkItem {
    /// Hands it to `sink` ([`Sink::write`] or [`Sink::alert`]).
    pub fn deliver_to(&self, sink: &mut dyn Sink) {
        match self {
            SinkItem::Message(message) => sink.write(message),
            SinkItem::Alert(alert) => sink.alert(alert),
        }
    }
}

/// What went wrong in a sink over its life, reported when it finishes: the first error as the
/// sink's own type (the cause chain stays intact), and how many there were.
#[derive(Debug, thiserror::Error)]
#[error("{sink}: {count} error(s), the first: {first}")]
pub struct SinkError {
    /// Which sink (`MCAP log`).
    pub sink: &'static str,
    pub count: usize,
    #[source]
    pub first: Box<dyn std::error::Error + Send + Sync + 'static>,
}
