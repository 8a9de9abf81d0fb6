//! The running service (`bearingd run`, `bearingd replay`): sources → per-channel analysis →
//! sinks.
//!
//! - [`live_source`]: the SocketCAN and iceoryx2 sources mapped onto the config's channels.
//! - [`mcap_sink`]: the MCAP log as a sink (time mapping, flushes, recovery at start).
//! - [`replay`]: logged raw samples through the same pipeline.
//! - [`notify`]: the systemd notify protocol (READY, STATUS, WATCHDOG, STOPPING).
//! - [`pipeline`]: the analysis stage shared by `run` and `replay` (sample time only).
//! - [`run`]: threads, queues, shutdown and status of `bearingd run`.
//! - [`sim_source`]: the in-process simulated sensor node.
//! - [`twin_worker`]: the twin's periodic re-fit.

pub mod live_source;
pub mod mcap_sink;
pub mod notify;
pub mod pipeline;
pub mod replay;
pub mod run;
pub mod sim_source;
pub mod twin_worker;
