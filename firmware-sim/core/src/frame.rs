//! The decoded form of every frame, independent of the bytes.
//!
//! These types hold full-width counters (`u16` sequence, `u32` sample index) on both sides of
//! the wire. The classic layout carries only their low bits (8 and 24); the encoder truncates
//! and the receiver's [`SequenceTracker`](crate::SequenceTracker) extends them again, so the
//! node never has to know which layout its counters will travel in.

use heapless::Vec;

use crate::id::{FrameKind, AXIS_COUNT};

/// Version of the wire protocol described here, sent in the high nibble of byte 0 of every
/// metadata page (so `1..=15`). A receiver refuses metadata of any other version rather than
/// guess at its layout.
pub const PROTOCOL_VERSION: u8 = 1;

/// Capacity of [`DataFrame::samples`]. Bigger than any layout carries (see
/// [`FrameKind::max_samples`]) so that one type serves both.
pub const SAMPLES_CAPACITY: usize = 31;

/// A set of axis ids (bit `a` set means axis `a` is streamed). Only the low
/// [`AXIS_COUNT`] bits may be set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AxisSet(u8);

impl AxisSet {
    /// Bits that may be set.
    pub const VALID_BITS: u8 = (1 << AXIS_COUNT) - 1;

    /// The set with these bits, or `None` if a bit above the last axis is set.
    pub const fn from_bits(bits: u8) -> Option<AxisSet> {
        if bits & !Self::VALID_BITS != 0 {
            None
        } else {
            Some(AxisSet(bits))
        }
    }

    /// The set of the given axes; `None` if one is out of range.
    pub fn from_axes(axes: &[u8]) -> Option<AxisSet> {
        let mut bits = 0u8;
        for &axis in axes {
            if axis >= AXIS_COUNT {
                return None;
            }
            bits |= 1 << axis;
        }
        Some(AxisSet(bits))
    }

    /// The raw bits.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// Whether `axis` is in the set.
    pub const fn contains(self, axis: u8) -> bool {
        axis < AXIS_COUNT && self.0 & (1 << axis) != 0
    }

    /// Number of axes in the set.
    pub const fn count(self) -> u32 {
        self.0.count_ones()
    }

    /// Whether the set is empty.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The lowest axis in the set.
    pub const fn first(self) -> Option<u8> {
        if self.0 == 0 {
            None
        } else {
            Some(self.0.trailing_zeros() as u8)
        }
    }

    /// The axes in ascending order.
    pub fn iter(self) -> impl Iterator<Item = u8> {
        (0..AXIS_COUNT).filter(move |&a| self.contains(a))
    }
}

/// Samples of one axis: the payload of every data frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DataFrame {
    /// Sending node, `0..16`; travels in the CAN id.
    pub node: u8,
    /// Axis, `0..4`; travels in the CAN id.
    pub axis: u8,
    /// Per-(node, axis) frame counter, wrapping; the classic layout carries its low 8 bits.
    pub sequence: u16,
    /// Index of the first sample in the node's per-axis sample count since its start,
    /// wrapping; the classic layout carries its low 24 bits.
    pub first_sample: u32,
    /// The samples, in ADC counts (multiply by the metadata scale for g). Never empty on the
    /// wire; at most [`FrameKind::max_samples`] of the layout used.
    pub samples: Vec<i16, SAMPLES_CAPACITY>,
}

/// Firmware version of a node, `major.minor.patch`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FirmwareVersion {
    /// Incompatible changes.
    pub major: u8,
    /// Compatible additions.
    pub minor: u8,
    /// Fixes.
    pub patch: u8,
}

/// Metadata page 0: how to read the node's data frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamPage {
    /// Sample rate of every axis, Hz; never 0.
    pub sample_rate_hz: u32,
    /// Axes the node streams; never empty.
    pub axes: AxisSet,
    /// Layout of the node's data frames.
    pub data_kind: FrameKind,
}

/// Metadata page 1: what the counts mean and which firmware produced them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DevicePage {
    /// Acceleration per ADC count, g; finite and positive.
    pub scale_g_per_count: f32,
    /// Firmware version.
    pub firmware: FirmwareVersion,
}

/// One page of a node's metadata. Everything a receiver needs does not fit in 8 bytes, so the
/// metadata message is multiplexed by its first byte; a node sends all pages back to back.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MetadataPage {
    /// Page 0.
    Stream(StreamPage),
    /// Page 1.
    Device(DevicePage),
}

impl MetadataPage {
    /// The multiplexer value (byte 0) of this page.
    pub const fn index(&self) -> u8 {
        match self {
            MetadataPage::Stream(_) => 0,
            MetadataPage::Device(_) => 1,
        }
    }
}

/// Number of metadata pages.
pub const METADATA_PAGES: u8 = 2;

/// A metadata frame: one page of one node's description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metadata {
    /// Sending node; travels in the CAN id.
    pub node: u8,
    /// The page.
    pub page: MetadataPage,
}

/// Where a speed measurement comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpeedSource {
    /// A once-per-revolution tachometer or encoder on the shaft.
    Tachometer,
    /// The drive (VFD) reporting its output speed.
    Drive,
}

impl SpeedSource {
    /// Wire value.
    pub const fn code(self) -> u8 {
        match self {
            SpeedSource::Tachometer => 0,
            SpeedSource::Drive => 1,
        }
    }

    /// Inverse of [`SpeedSource::code`].
    pub const fn from_code(code: u8) -> Option<SpeedSource> {
        match code {
            0 => Some(SpeedSource::Tachometer),
            1 => Some(SpeedSource::Drive),
            _ => None,
        }
    }
}

/// Wire value of [`SpeedFrame::centi_rpm`] meaning "speed not available".
pub const SPEED_NOT_AVAILABLE: u32 = u32::MAX;

/// Shaft speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpeedFrame {
    /// Sending node; travels in the CAN id.
    pub node: u8,
    /// Per-node speed frame counter, wrapping.
    pub sequence: u8,
    /// Where the value comes from.
    pub source: SpeedSource,
    /// Speed in hundredths of rpm; `None` when the source has no valid value (tachometer
    /// signal lost, drive not reporting). `Some(u32::MAX)` cannot be encoded.
    pub centi_rpm: Option<u32>,
}

impl SpeedFrame {
    /// Speed in rpm, if available.
    pub fn rpm(&self) -> Option<f32> {
        self.centi_rpm.map(|c| c as f32 / 100.0)
    }
}

/// Any frame of the protocol.
#[derive(Debug, Clone, PartialEq)]
pub enum Frame {
    /// Samples of one axis.
    Data(DataFrame),
    /// One metadata page.
    Metadata(Metadata),
    /// Shaft speed.
    Speed(SpeedFrame),
}

impl Frame {
    /// The sending node.
    pub fn node(&self) -> u8 {
        match self {
            Frame::Data(d) => d.node,
            Frame::Metadata(m) => m.node,
            Frame::Speed(s) => s.node,
        }
    }
}

/// A node's complete description, assembled from its metadata pages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeInfo {
    /// Node id.
    pub node: u8,
    /// Page 0.
    pub stream: StreamPage,
    /// Page 1.
    pub device: DevicePage,
}

impl NodeInfo {
    /// The metadata frames that describe this node, in page order.
    pub fn frames(&self) -> [Frame; METADATA_PAGES as usize] {
        [
            Frame::Metadata(Metadata {
                node: self.node,
                page: MetadataPage::Stream(self.stream),
            }),
            Frame::Metadata(Metadata {
                node: self.node,
                page: MetadataPage::Device(self.device),
            }),
        ]
    }
}

/// Receiver side: collects metadata pages of one node until a full [`NodeInfo`] is known, and
/// keeps it current as pages repeat.
#[derive(Debug, Clone, Copy, Default)]
pub struct MetadataAssembler {
    node: Option<u8>,
    stream: Option<StreamPage>,
    device: Option<DevicePage>,
}

impl MetadataAssembler {
    /// An assembler that knows nothing yet.
    pub const fn new() -> MetadataAssembler {
        MetadataAssembler {
            node: None,
            stream: None,
            device: None,
        }
    }

    /// Takes one page. Returns the node's description when every page has been seen (the
    /// latest of each). A page of another node than the first one seen restarts assembly.
    pub fn apply(&mut self, metadata: &Metadata) -> Option<NodeInfo> {
        if self.node != Some(metadata.node) {
            *self = MetadataAssembler {
                node: Some(metadata.node),
                ..MetadataAssembler::new()
            };
        }
        match metadata.page {
            MetadataPage::Stream(s) => self.stream = Some(s),
            MetadataPage::Device(d) => self.device = Some(d),
        }
        self.info()
    }

    /// The description, if every page has been seen.
    pub fn info(&self) -> Option<NodeInfo> {
        Some(NodeInfo {
            node: self.node?,
            stream: self.stream?,
            device: self.device?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_set_bounds() {
        assert_eq!(AxisSet::from_bits(0x10), None);
        let s = AxisSet::from_axes(&[0, 2]).unwrap();
        assert_eq!(s.bits(), 0b101);
        assert_eq!(s.count(), 2);
        assert_eq!(s.first(), Some(0));
        assert!(s.contains(2) && !s.contains(1) && !s.contains(9));
        let mut axes = s.iter();
        assert_eq!(
            (axes.next(), axes.next(), axes.next()),
            (Some(0), Some(2), None)
        );
        assert_eq!(AxisSet::from_axes(&[4]), None);
        assert_eq!(AxisSet::default().first(), None);
    }

    #[test]
    fn assembler_needs_every_page_and_follows_one_node() {
        let info = NodeInfo {
            node: 3,
            stream: StreamPage {
                sample_rate_hz: 25_600,
                axes: AxisSet::from_bits(0b111).unwrap(),
                data_kind: FrameKind::Fd,
            },
            device: DevicePage {
                scale_g_per_count: 1.0 / 2048.0,
                firmware: FirmwareVersion {
                    major: 1,
                    minor: 2,
                    patch: 3,
                },
            },
        };
        let [a, b] = info.frames();
        let (Frame::Metadata(a), Frame::Metadata(b)) = (a, b) else {
            unreachable!()
        };
        let mut asm = MetadataAssembler::new();
        assert_eq!(asm.apply(&a), None);
        assert_eq!(asm.apply(&b), Some(info));
        let other = Metadata { node: 4, ..a };
        assert_eq!(asm.apply(&other), None);
    }
}
