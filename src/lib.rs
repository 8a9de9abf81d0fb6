//! bearingd: watches a rolling-element bearing from its vibration.
//!
//! # Layout
//!
//! The rooms, top to bottom: a room uses only rooms listed below it, never one above
//! (`scripts/module_deps.py` checks this in CI, and that there is no import cycle).
//!
//! - [`cli`]: the `bearingd` command line; the only place that prints, exits, or turns typed errors
//!   into messages for people. Lab commands are handed to the `bearingd-lab` binary
//!   (crates/bearingd-lab, which uses this library and is never linked into the service): training,
//!   simulation, the physics twin, the detector evaluation (`bearingd evaluate`), a bearing's
//!   life (`bearingd trend`) and every picture (`bearingd analyze --plot`).
//! - [`daemon`]: wiring only: `run` and `replay` lock the data dir, start sources, the pipeline
//!   and sinks, and stop them; what happens is reported as typed events, never printed.
//! - [`sources`]: SocketCAN, iceoryx2, the simulated sensor and MCAP replay → sample blocks in
//!   sample time, counting gaps, restarts, silent sensors and malformed frames.
//! - [`sinks`]: where the pipeline's messages go: the MCAP log writer, iceoryx2 alerts, the
//!   systemd notify protocol, the fleet bridge (MQTT Sparkplug B with store-and-forward).
//! - [`offline`]: one recording analysed end to end (`bearingd analyze` as a library call).
//! - [`report`]: what `analyze` shows: JSON and text from one report (the figure of the same
//!   report is drawn by the lab, `bearingd analyze --plot`).
//! - [`pipeline`]: the per-channel pipeline shared by `run` and `replay`, its outputs, the twin's
//!   re-fit requests (served per channel in turn), the band-selection worker and the
//!   [`Sink`](pipeline::Sink) trait, the seam to the sinks.
//! - [`config`]: the TOML configuration, parsed raw then validated into typed settings (one file
//!   per section), with every problem reported at once.
//! - [`learned`]: the learned diagnosis (seed 001): a denoising autoencoder + 1-D CNN trained
//!   only on synthetic records (`bearingd train`, in the lab crate `bearingd-lab`), run here by a
//!   plain forward pass; an extra opinion that the envelope evidence must back
//!   (`analyze --learned`, `twin.learned_model`). From the `bearing-core` crate, like [`twin`],
//!   [`analysis`] and [`messages`].
//! - [`iox`]: iceoryx2 service names, the file prefix and the root, in one place (the
//!   `bearing-iox` crate, shared with the publishers).
//! - [`twin`]: the twins of a defective bearing: the signal model (simulation and online fits)
//!   and the Hammerstein–Wiener identification (`twin::hw`). The 6-DOF physics model, its
//!   calibration and the labelled synthetic data sets are the lab's (`bearingd_lab::twin`).
//!   From `bearing-core`.
//! - [`analysis`]: the sans-IO diagnosis core. Samples in, results out; it owns its buffers and
//!   knows no clock, no file, no async runtime, so `run`, `replay` and `analyze` share it and
//!   cannot disagree. It is the `bearing-core` crate's (with [`messages`], [`twin`] and
//!   [`learned`]), built for speed where the service is built for size.
//! - [`recording`]: readers for recorded data (CWRU `.mat`, PRONOSTIA and plain CSV, IMS text,
//!   WAV) that turn a file into samples plus what the file says about itself.
//! - [`mcap_log`]: the MCAP log's format: topics, schemas, file names, the bounded scanner and
//!   the reader (the writer is a sink, the replay a source).
//! - [`messages`]: the vocabulary every room above speaks: typed faults, flags, health stages,
//!   speed sources and the pipeline's messages, with the one list of detectors whose messages
//!   the pipeline carries ([`messages::detect`]); MCAP and iceoryx2 encode them at the edge
//!   (from `bearing-core`).
//! - [`bearing`]: bearing geometry, the catalog of named bearings, fault frequencies and the
//!   fault kinds (from the `bearing-signal` crate, shared with `firmware-sim`).
//! - [`machine_fault`]: the machine faults beside the bearing (unbalance, misalignment,
//!   looseness) and their patterns at shaft orders, which the simulator makes and the analysis
//!   names (from `bearing-signal`).
//! - [`random`]: seeded random numbers (ChaCha8), the same on every machine, for the simulator
//!   and for tests at every level (from `bearing-signal`).
//! - [`clock`]: the one reading of the system clock, for the daemon's edges (sources, sinks).
//! - [`fsafe`]: safe file creation in the data directories: no link followed where bearingd
//!   writes, modes 0750/0640 whatever the umask, data directories others can write refused.
//!
//! Data flow and the reasons behind it: `docs/ARCHITECTURE.md`.

pub use bearing_core::analysis;
pub use bearing_signal::bearing;
pub mod cli;
pub mod clock;
pub mod config;
pub mod daemon;
pub mod fsafe;
pub mod iox;
pub use bearing_core::learned;
pub use bearing_signal::machine_fault;
pub mod mcap_log;
pub use bearing_core::messages;
pub mod offline;
pub mod pipeline;
pub use bearing_signal::random;
pub mod recording;
pub mod report;
pub mod sinks;
pub mod sources;
pub use bearing_core::twin;
