#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
//! The bearingd sensor wire format, and the two state machines at its ends.
//!
//! Sensor nodes send accelerometer samples over CAN (classic 8-byte or CAN FD 64-byte frames) or
//! iceoryx2; the daemon decodes them with this same crate, so the two sides cannot disagree on a
//! byte. The crate is `no_std`, allocates nothing and depends on `heapless` only, because the
//! same code runs in node firmware (tested by building for `thumbv7em-none-eabihf`).
//!
//! The format exists to make loss visible: every data frame carries a sequence counter and the
//! index of its first sample, and the receiver's [`SequenceTracker`] turns them into "in order",
//! "gap of N samples", "duplicate", "old" or "node restarted", so that a gap is never bridged
//! silently. Sample rate, scale and the node's identity travel in periodic metadata frames, not
//! only in the daemon's config. The byte layouts are written down in `docs/WIRE_FORMAT.md` and as
//! a DBC file, `config/bearingd.dbc`, that standard CAN tools load.
//!
//! # Layout
//!
//! - [`id`]: the 11-bit CAN identifier plan (which id carries which frame, and why in that
//!   priority order).
//! - [`frame`]: the decoded frames ([`Frame`], [`DataFrame`], [`Metadata`], [`SpeedFrame`]) and
//!   the receiver's [`MetadataAssembler`].
//! - [`codec`]: [`encode`] and [`decode`], with [`EncodeError`] and [`DecodeError`].
//! - [`node`]: [`SensorNode`], the sampling state machine of a node: samples in, frames out,
//!   through a bounded queue whose overflow is counted.
//! - [`tracker`]: [`SequenceTracker`], the receiver's per-(node, axis) loss and restart detector.

pub mod codec;
pub mod frame;
pub mod id;
pub mod node;
pub mod tracker;

pub use codec::{decode, encode, DecodeError, EncodeError};
pub use frame::{
    AxisSet, DataFrame, DevicePage, FirmwareVersion, Frame, FrameKind, Metadata, MetadataAssembler,
    MetadataPage, NodeInfo, SpeedFrame, SpeedSource, StreamPage, PROTOCOL_VERSION,
};
pub use id::{CanId, MessageKind};
pub use node::{ConfigError, NodeConfig, NodeStats, PushError, Pushed, SensorNode};
pub use tracker::{Observation, SequenceTracker, TrackerCounters};
