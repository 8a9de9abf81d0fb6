//! The one reading of the system clock, for the edges of the daemon: an input's arrival, the
//! log's origin, an alert's run id, the fleet bridge's timestamps. Its own room at the bottom of
//! the house so that sources and sinks share it without one importing the other; the analysis,
//! the pipeline and the log writer never call it (a replay must not depend on when it runs).

/// The system clock in nanoseconds since the Unix epoch, for the edges of the daemon (an
/// input's arrival, the log's origin, an alert's run id, the fleet bridge's timestamps); never called by the analysis, the
/// pipeline or the log writer.
pub fn wall_clock_now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
        .unwrap_or(0)
}
