//! The running service, wiring only: `bearingd run` ([`run`]) and `bearingd replay`
//! ([`replay`]) put sources, the pipeline and sinks together, start and stop them.
//!
//! - [`run`]: threads, queues, shutdown and status of `bearingd run`.
//! - `threads`: the analysis, re-fit and sink threads of `run`.
//! - [`replay`]: logged raw samples through the same pipeline, into the same sinks.
//! - [`sinks`]: which sinks a run or a replay gets, assembled in one place.
//! - [`events`]: what the daemon tells its operator, as typed events for the caller to show
//!   (the daemon never prints).
//! - [`cpu_latency`]: the CPUs' wake-up latency held down while it runs (an alert's latency).
//! - [`heap_pages`]: whether the analysis' memory can be in huge pages (an alert's latency on
//!   a VM), and what to set if not.
//! - [`lock`]: one owner per data directory (an advisory lock taken before anything is opened).
//! - [`state`]: what is kept across restarts (the health baselines).

pub mod cpu_latency;
pub mod events;
pub mod heap_pages;
pub mod lock;
pub mod replay;
pub mod run;
pub mod sinks;
pub mod state;
mod threads;

pub use events::{ignore_events, DaemonEvent, Events};
pub use replay::{replay, BaselinesFrom, Gap, ReplayError, ReplayOptions, ReplaySummary, RunStart};
pub use run::{run, RunError, RunOptions, RunSummary};
pub use sinks::{assemble, SinkPlan, SinkStart, SinkStartError, Sinks};
