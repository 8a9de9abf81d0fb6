//! The seam between the pipeline and its sinks.

use crate::messages::PipelineMessage;

/// A consumer of the pipeline's messages. The daemon calls it on a thread of its own (the sink
/// thread of `run`, the replay's loop), in the order the pipeline emitted the messages.
pub trait Sink: Send {
    /// Takes one message. A sink that fails keeps the error for [`finish`](Self::finish) and
    /// goes on: one bad write must not stop the analysis.
    fn write(&mut self, message: &PipelineMessage);
    /// Flushes and closes; called once at shutdown.
    fn finish(&mut self) -> Result<(), SinkError>;
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
