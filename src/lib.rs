//! bearingd: watches a rolling-element bearing from its vibration.
//!
//! # Layout
//!
//! - [`analysis`]: the sans-IO diagnosis core. Samples in, results out; it owns its buffers and
//!   knows no clock, no file, no async runtime, so `run`, `replay` and `analyze` share it and
//!   cannot disagree.
//! - [`bearing`]: bearing geometry, the catalog of named bearings, fault frequencies.
//! - [`config`]: the TOML configuration, parsed raw then validated into typed settings, with
//!   every problem reported at once.
//! - [`recording`]: readers for recorded data (CWRU `.mat`, PRONOSTIA and plain CSV, IMS text,
//!   WAV) that turn a file into samples plus what the file says about itself.
//! - [`offline`]: one recording analysed end to end (`bearingd analyze` as a library call).
//! - [`report`]: what `analyze` shows: JSON, text and the figure, from one report.
//! - [`plot`]: pictures of spectra and kurtograms (PNG and SVG), drawn without system fonts.
//! - [`mcap_log`]: the MCAP log: chunked, compressed files with a decodable schema per topic,
//!   rotation and a disk budget, crash recovery, and the reader that replay uses.
//! - [`twin`]: the signal-model twin of a defective bearing (simulation now, fitting later).
//! - [`ingest`]: sources (SocketCAN, iceoryx2) that turn sensor frames into sample blocks in
//!   sample time, counting gaps, restarts, silent sensors and malformed frames.
//! - [`sinks`]: where results leave the box: the fleet bridge (MQTT Sparkplug B with
//!   store-and-forward).
//! - [`cli`]: the `bearingd` command line; the only place that prints, exits, or uses `anyhow`.
//!
//! Data flow and the reasons behind it: `docs/ARCHITECTURE.md`.

pub mod alerts;
pub mod analysis;
pub mod bearing;
pub mod cli;
pub mod config;
pub mod daemon;
pub mod ingest;
pub mod mcap_log;
pub mod offline;
pub mod plot;
pub mod recording;
pub mod report;
pub mod sinks;
pub mod twin;
