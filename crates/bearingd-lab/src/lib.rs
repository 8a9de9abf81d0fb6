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
//! - [`learned`]: training the learned diagnosis (candle): the trainable network and the
//!   training loop; the service's `bearingd::learned` runs what it writes.
//!
//! The service's rooms this crate's modules use by their usual paths (`crate::analysis`, ...),
//! re-exported below: all of them sit under every room above.

pub mod cli;
pub mod learned;

pub use bearingd::{analysis, bearing, random, twin};
