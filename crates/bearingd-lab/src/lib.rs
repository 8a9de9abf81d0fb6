//! bearingd-lab: the laboratory around the bearingd service, in its own crate and binary so
//! that the service a box runs links none of it (no training library, no ODE solver, no
//! plotting, no thread pool). It uses the service's library (`bearingd`) for everything the two
//! share: the analysis, the twin's signal model, the messages, the offline analysis and the
//! command line's errors and exit codes.
//!
//! # Layout
//!
//! The rooms, top to bottom: a room uses only rooms listed below it, never one above
//! (`scripts/module_deps.py` checks this in CI, and that there is no import cycle).
//!
//! - [`cli`]: the `bearingd-lab` command line (`bearingd <lab command>` runs it too); the only
//!   place of this crate that prints or exits.
//! - [`evaluate`]: the detector-evaluation harness (`bearingd-lab evaluate`): simulated faults
//!   swept over type, severity, SNR, speed and bearing through the real pipeline, hours of
//!   healthy signal through the daemon's monitor, and recordings of a manifest through
//!   `analyze` and through the daemon's replay (in-process, as `import` + `replay` would).
//! - [`learned`]: training the learned diagnosis (candle): the trainable network and the
//!   training loop on a data set of [`twin::dataset`]; the service's `bearingd::learned` runs
//!   what it writes.
//! - [`report`]: what the lab draws and tells of the service's results: `analyze`'s figure of a
//!   record (`bearingd analyze --plot`) and a bearing's life (`bearingd trend`) as text, JSON
//!   and a figure.
//! - [`life`]: a bearing's life of snapshots, in time order, through the daemon's health tracker
//!   with the HW residual, the fault score and the RMS trend (`bearingd trend`).
//! - [`twin`]: the physics twin (6-DOF contact model, ODE integration, its calibration by a
//!   parallel differential evolution), the labelled synthetic data sets and the defect-size
//!   check on the physics twin; the service's signal-model twin re-exported beside them.
//! - [`plot`]: pictures of spectra and heatmaps (PNG and SVG), drawn without system fonts: the
//!   service links no rasterizer.
//!
//! The service's rooms this crate's modules use by their usual paths (`crate::analysis`, ...),
//! re-exported below: all of them sit under every room above.

pub mod cli;
pub mod evaluate;
pub mod learned;
pub mod life;
pub mod plot;
pub mod report;
pub mod twin;

pub use bearingd::{
    analysis, bearing, clock, config, daemon, machine_fault, messages, offline, pipeline, random,
    recording, sinks, sources,
};
