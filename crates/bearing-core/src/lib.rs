//! bearingd's sans-IO core: what a window of samples becomes, and nothing of where samples come
//! from or where results go. The pipeline's typed messages ([`messages`]), the window and record
//! analysis with the detectors and the decision ([`analysis`]), the signal-model twin and the
//! Hammerstein–Wiener model ([`twin`]) and learned diagnosis ([`learned`]): samples in, messages
//! out, no clock, no socket, no log.
//!
//! A crate of its own for two reasons. The daemon's edges (config, CLI, sinks, sources, the
//! MCAP log) can be read and changed without this code, and the other way round. And the edge
//! box's build (`cargo build --profile service`) compiles this crate for speed and the daemon
//! around it for size: the window path and the twin re-fit stay at opt-level 3 while the code
//! that runs once per config, command or connection is made small (docs/PERFORMANCE.md,
//! "Service binary"). `bearingd` re-exports the modules where they always were
//! (`bearingd::analysis`, `bearingd::messages`, ...).
//!
//! # Layout
//!
//! Top to bottom: a module uses only modules listed below it (`scripts/module_deps.py`).
//!
//! - [`learned`]: the learned diagnosis's forward pass and model files; an extra opinion the
//!   envelope evidence must back.
//! - [`twin`]: the signal-model twin (simulation and online fits) and the Hammerstein–Wiener
//!   identification (`twin::hw`).
//! - [`analysis`]: the window and record analysis, the detectors and the decision.
//! - [`messages`]: the vocabulary of the pipeline: typed faults, flags, health stages and the
//!   pipeline's messages.
//! - [`bearing`], [`machine_fault`], [`random`]: from `bearing-signal`.

pub mod analysis;
pub mod learned;
pub mod messages;
pub mod twin;

pub use bearing_signal::{bearing, machine_fault, random};
