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
//! # Example: node to receiver
//!
//! ```
//! use bearing_wire::{
//!     decode, encode, AxisSet, CanId, FirmwareVersion, Frame, FrameKind, MessageKind,
//!     MetadataAssembler, NodeConfig, Observation, SensorNode, SequenceTracker,
//! };
//!
//! // The node: one axis, CAN FD frames, metadata once per second.
//! let mut node: SensorNode<32> = SensorNode::new(NodeConfig {
//!     node: 2,
//!     axes: AxisSet::from_axes(&[0]).unwrap(),
//!     data_kind: FrameKind::Fd,
//!     sample_rate_hz: 25_600,
//!     scale_g_per_count: 1.0 / 4096.0,
//!     firmware: FirmwareVersion { major: 1, minor: 0, patch: 0 },
//!     metadata_period_samples: 25_600,
//! })
//! .unwrap();
//! let pushed = node.push_samples(0, &[100; 56]).unwrap();
//! assert_eq!(pushed.dropped, 0);
//!
//! // The receiver: decode every frame; track each (node, axis) stream.
//! let mut info = MetadataAssembler::new();
//! let mut tracker = SequenceTracker::new(FrameKind::Fd);
//! let mut bytes = [0u8; 64];
//! while let Some(frame) = node.pop_frame() {
//!     let (id, len) = encode(&frame, FrameKind::Fd, &mut bytes).unwrap();
//!     // ...the bus...
//!     match decode(u32::from(id), &bytes[..len]).unwrap() {
//!         Frame::Metadata(m) => {
//!             info.apply(&m);
//!         }
//!         Frame::Data(d) => {
//!             let obs = tracker.observe(&d);
//!             assert!(matches!(obs, Observation::Start { .. } | Observation::InOrder { .. }));
//!         }
//!         Frame::Speed(_) => {}
//!     }
//! }
//! assert_eq!(info.info().unwrap().stream.sample_rate_hz, 25_600);
//! assert_eq!(tracker.next_sample(), Some(56));
//! assert!(matches!(
//!     CanId::parse(0x102).unwrap().message,
//!     MessageKind::Data { kind: FrameKind::Fd, axis: 0 }
//! ));
//! ```
//!
//! # Layout
//!
//! Top to bottom; a module uses only modules listed below it (`scripts/module_deps.py` checks
//! this in CI, and that there is no import cycle).
//!
//! - [`tracker`]: [`SequenceTracker`], the receiver's per-(node, axis) loss and restart detector.
//! - [`node`]: [`SensorNode`], the sampling state machine of a node: samples in, frames out,
//!   through a bounded queue whose overflow is counted.
//! - [`codec`]: [`encode`] and [`decode`], with [`EncodeError`] and [`DecodeError`].
//! - [`frame`]: the decoded frames ([`Frame`], [`DataFrame`], [`Metadata`], [`SpeedFrame`]) and
//!   the receiver's [`MetadataAssembler`].
//! - [`id`]: the 11-bit CAN identifier plan (which id carries which frame, and why in that
//!   priority order).

pub mod codec;
pub mod frame;
pub mod id;
pub mod node;
pub mod tracker;

pub use codec::{decode, encode, DecodeError, EncodeError};
pub use frame::{
    AxisSet, DataFrame, DevicePage, FirmwareVersion, Frame, Metadata, MetadataAssembler,
    MetadataPage, NodeInfo, SpeedFrame, SpeedSource, StreamPage, PROTOCOL_VERSION,
};
pub use id::{CanId, FrameKind, MessageKind};
pub use node::{ConfigError, NodeConfig, NodeStats, PushError, Pushed, SensorNode};
pub use tracker::{Observation, SequenceTracker, TrackerCounters};
