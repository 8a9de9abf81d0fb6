//! The CAN identifier plan.
//!
//! All frames use 11-bit standard identifiers inside one block, `0x100..=0x1FF`, so that a
//! single acceptance filter (`id 0x100`, `mask 0x700`) passes every bearingd frame and nothing
//! else. Inside the block the identifier is `base(kind) + offset`, with the node id (0..=15) in
//! the low four bits and, for data frames, the axis (0..=3) in the next two bits:
//!
//! | kind            | base    | identifier                     | range           |
//! |-----------------|---------|--------------------------------|-----------------|
//! | data, CAN FD    | `0x100` | `0x100 + 16 * axis + node`     | `0x100..=0x13F` |
//! | data, classic   | `0x140` | `0x140 + 16 * axis + node`     | `0x140..=0x17F` |
//! | speed           | `0x180` | `0x180 + node`                 | `0x180..=0x18F` |
//! | metadata        | `0x1F0` | `0x1F0 + node`                 | `0x1F0..=0x1FF` |
//!
//! A lower identifier wins arbitration, so data frames (the only frames with a deadline: the
//! node's transmit queue is finite and the stream never pauses) beat speed frames, which beat
//! metadata. `0x190..=0x1EF` is left free for future kinds of middle priority.

/// Number of sensor nodes that can share one bus: node ids are `0..NODE_COUNT`.
pub const NODE_COUNT: u8 = 16;
/// Number of axes a node can stream: axis ids are `0..AXIS_COUNT`.
pub const AXIS_COUNT: u8 = 4;

/// Which data-frame layout a node sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameKind {
    /// Classic CAN: 8 bytes, 2 samples, 8-bit sequence, 24-bit sample index.
    Classic,
    /// CAN FD: 64 bytes, up to 28 samples, 16-bit sequence, 32-bit sample index.
    Fd,
}

impl FrameKind {
    /// Most samples one data frame of this layout carries.
    pub const fn max_samples(self) -> usize {
        match self {
            FrameKind::Classic => 2,
            FrameKind::Fd => 28,
        }
    }

    /// Bits of the sequence counter that travel on the wire.
    pub const fn sequence_bits(self) -> u32 {
        match self {
            FrameKind::Classic => 8,
            FrameKind::Fd => 16,
        }
    }

    /// Bits of the first-sample index that travel on the wire.
    pub const fn index_bits(self) -> u32 {
        match self {
            FrameKind::Classic => 24,
            FrameKind::Fd => 32,
        }
    }

    /// The value of the metadata `data_kind` byte.
    pub const fn code(self) -> u8 {
        match self {
            FrameKind::Classic => 0,
            FrameKind::Fd => 1,
        }
    }

    /// Inverse of [`FrameKind::code`].
    pub const fn from_code(code: u8) -> Option<FrameKind> {
        match code {
            0 => Some(FrameKind::Classic),
            1 => Some(FrameKind::Fd),
            _ => None,
        }
    }
}

/// First identifier of CAN FD data frames.
pub const DATA_FD_BASE: u16 = 0x100;
/// First identifier of classic-CAN data frames.
pub const DATA_CLASSIC_BASE: u16 = 0x140;
/// First identifier of speed frames.
pub const SPEED_BASE: u16 = 0x180;
/// First identifier of metadata frames.
pub const METADATA_BASE: u16 = 0x1F0;

/// Acceptance filter identifier that, with [`FILTER_MASK`], passes exactly the bearingd block.
pub const FILTER_ID: u16 = 0x100;
/// Acceptance filter mask for [`FILTER_ID`].
pub const FILTER_MASK: u16 = 0x700;

/// What an identifier in the bearingd block carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MessageKind {
    /// Samples of one axis, in the given frame layout.
    Data {
        /// Classic (8-byte) or FD (64-byte) layout.
        kind: FrameKind,
        /// Axis id, `0..AXIS_COUNT`.
        axis: u8,
    },
    /// Shaft speed.
    Speed,
    /// One page of the node's metadata.
    Metadata,
}

/// An identifier of the bearingd block, split into its parts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanId {
    /// Sending node, `0..NODE_COUNT`.
    pub node: u8,
    /// What the frame carries.
    pub message: MessageKind,
}

impl CanId {
    /// Splits a raw identifier; `None` for anything outside the bearingd block (including
    /// extended identifiers and values with SocketCAN flag bits set).
    pub fn parse(raw: u32) -> Option<CanId> {
        if raw > 0x7FF {
            return None;
        }
        let raw = raw as u16;
        let node = (raw & 0x0F) as u8;
        let message = match raw {
            0x100..=0x13F => MessageKind::Data {
                kind: FrameKind::Fd,
                axis: ((raw - DATA_FD_BASE) >> 4) as u8,
            },
            0x140..=0x17F => MessageKind::Data {
                kind: FrameKind::Classic,
                axis: ((raw - DATA_CLASSIC_BASE) >> 4) as u8,
            },
            0x180..=0x18F => MessageKind::Speed,
            0x1F0..=0x1FF => MessageKind::Metadata,
            _ => return None,
        };
        Some(CanId { node, message })
    }

    /// The raw 11-bit identifier, or `None` if the node or axis is out of range.
    pub fn raw(self) -> Option<u16> {
        if self.node >= NODE_COUNT {
            return None;
        }
        let node = u16::from(self.node);
        match self.message {
            MessageKind::Data { kind, axis } => {
                if axis >= AXIS_COUNT {
                    return None;
                }
                let base = match kind {
                    FrameKind::Classic => DATA_CLASSIC_BASE,
                    FrameKind::Fd => DATA_FD_BASE,
                };
                Some(base + 16 * u16::from(axis) + node)
            }
            MessageKind::Speed => Some(SPEED_BASE + node),
            MessageKind::Metadata => Some(METADATA_BASE + node),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_identifier_round_trips_and_the_filter_matches_exactly_the_block() {
        let mut known = 0;
        for raw in 0u32..=0x7FF {
            let parsed = CanId::parse(raw);
            let in_block = (raw as u16) & FILTER_MASK == FILTER_ID;
            if let Some(id) = parsed {
                known += 1;
                assert!(in_block, "{raw:#x} parsed but outside the filter");
                assert_eq!(id.raw(), Some(raw as u16));
            }
        }
        // 2 layouts * 4 axes * 16 nodes + 16 speed + 16 metadata.
        assert_eq!(known, 2 * 64 + 16 + 16);
        assert_eq!(CanId::parse(0x8000_0100), None);
        assert_eq!(CanId::parse(0x800), None);
    }

    #[test]
    fn data_beats_speed_beats_metadata() {
        let worst_data = CanId {
            node: 15,
            message: MessageKind::Data {
                kind: FrameKind::Classic,
                axis: 3,
            },
        };
        let best_speed = CanId {
            node: 0,
            message: MessageKind::Speed,
        };
        let worst_speed = CanId {
            node: 15,
            message: MessageKind::Speed,
        };
        let best_meta = CanId {
            node: 0,
            message: MessageKind::Metadata,
        };
        assert!(worst_data.raw() < best_speed.raw());
        assert!(worst_speed.raw() < best_meta.raw());
    }

    #[test]
    fn out_of_range_parts_have_no_identifier() {
        assert_eq!(
            CanId {
                node: 16,
                message: MessageKind::Speed
            }
            .raw(),
            None
        );
        assert_eq!(
            CanId {
                node: 0,
                message: MessageKind::Data {
                    kind: FrameKind::Fd,
                    axis: 4
                }
            }
            .raw(),
            None
        );
    }
}
