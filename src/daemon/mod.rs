//! The running service (`bearingd run`, `bearingd replay`): sources → per-channel analysis →
//! sinks. Being built; the message types that flow to the sinks come first.

pub mod messages;
