//! What bearingd and its sensor simulator (`firmware-sim`) share, and nothing of the daemon:
//! bearing geometry and fault frequencies ([`bearing`]), seeded random numbers ([`random`]),
//! the signal-model simulator of a defective bearing ([`simulate`]) with the machine faults it
//! can add ([`machine_fault`]), and the readers of recorded vibration data ([`recording`]). A
//! sensor simulator needs these to make or replay a signal; it does not need the analysis, the
//! logs, the transports or the daemon, so they live here, in a crate of their own, and
//! `bearingd` re-exports them where they always were.
//!
//! The MCAP logs bearingd writes are recordings too, but their reader belongs to the log's
//! format, which lives in bearingd: [`recording::read_recording_with`] takes it as a
//! [`recording::LogReader`].

pub mod bearing;
pub mod machine_fault;
pub mod random;
pub mod recording;
pub mod simulate;
