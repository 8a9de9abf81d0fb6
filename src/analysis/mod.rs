//! The sans-IO analysis core (DESIGN.md "Data flow"): samples in, results out.
//!
//! Nothing here reads a clock, a file or a socket, and nothing here is async: the daemon, the
//! replay and `bearingd analyze` drive the same code with samples in sample time, so their
//! results cannot disagree. Buffers are owned and preallocated; the rolling path does not
//! allocate per hop.

pub mod settings;

pub use settings::{AnalysisSettings, BandSelection};
