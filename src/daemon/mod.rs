//! The running service (`bearingd run`, `bearingd replay`): sources → per-channel analysis →
//! sinks.
//!
//! - [`messages`]: what flows to the sinks; the MCAP log's schema.
//! - [`pipeline`]: the analysis stage shared by `run` and `replay` (sample time only).
//! - [`run`]: threads, queues, shutdown and status of `bearingd run`.
//! - [`sim_source`]: the in-process simulated sensor node.
//! - [`twin_worker`]: the twin's periodic re-fit.

pub mod messages;
pub mod pipeline;
pub mod run;
pub mod sim_source;
pub mod twin_worker;
