//! Bytes ⇄ [`Frame`]: the layouts of `docs/WIRE_FORMAT.md`, all little-endian.
//!
//! Decoding is total: any identifier and any byte slice give either a frame or a
//! [`DecodeError`] naming the identifier and the offending byte; nothing panics. Encoding
//! refuses what decoding would refuse, so `decode(encode(f))` succeeds for every frame
//! `encode` accepts, and gives `f` back up to the counter bits the layout drops.
//!
//! Bytes marked *reserved* are written as 0 and ignored when read, so that a later compatible
//! revision can use them without breaking older receivers.

use core::fmt;

use heapless::Vec;

use crate::frame::{
    AxisSet, DataFrame, DevicePage, FirmwareVersion, Frame, Metadata, MetadataPage, SpeedFrame,
    SpeedSource, StreamPage, PROTOCOL_VERSION, SAMPLES_CAPACITY, SPEED_NOT_AVAILABLE,
};
use crate::id::{CanId, FrameKind, MessageKind, AXIS_COUNT, NODE_COUNT};

/// Length of an FD data frame (CAN FD DLC 15).
pub const FD_DATA_LEN: usize = 64;
/// Length of a classic data frame with two samples (one sample: 6).
pub const CLASSIC_DATA_LEN: usize = 8;
/// Length of a metadata page.
pub const METADATA_LEN: usize = 8;
/// Length of a speed frame.
pub const SPEED_LEN: usize = 8;

/// Offset of the first sample in a classic data frame.
const CLASSIC_HEADER: usize = 4;
/// Offset of the first sample in an FD data frame.
const FD_HEADER: usize = 8;
/// Offset of the sample-count byte in an FD data frame.
const FD_COUNT_OFFSET: usize = 6;

/// A metadata field that can hold an invalid value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MetadataField {
    /// Byte 0, low nibble: page number.
    Page,
    /// Byte 0, high nibble: protocol version.
    ProtocolVersion,
    /// Page 0, bytes 1..5: sample rate, Hz.
    SampleRate,
    /// Page 0, byte 5: axis mask.
    Axes,
    /// Page 0, byte 6: data-frame layout.
    DataKind,
    /// Page 1, bytes 1..5: scale, g per count (`f32`; the error value is its bit pattern).
    Scale,
}

impl MetadataField {
    /// Byte offset of the field in the page.
    pub const fn offset(self) -> usize {
        match self {
            MetadataField::Page | MetadataField::ProtocolVersion => 0,
            MetadataField::SampleRate | MetadataField::Scale => 1,
            MetadataField::Axes => 5,
            MetadataField::DataKind => 6,
        }
    }

    /// Field name as in the DBC and the docs.
    pub const fn name(self) -> &'static str {
        match self {
            MetadataField::Page => "page",
            MetadataField::ProtocolVersion => "protocol_version",
            MetadataField::SampleRate => "sample_rate_hz",
            MetadataField::Axes => "axes",
            MetadataField::DataKind => "data_kind",
            MetadataField::Scale => "scale_g_per_count",
        }
    }
}

/// A speed field that can hold an invalid value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpeedField {
    /// Byte 1: source.
    Source,
}

impl SpeedField {
    /// Byte offset of the field.
    pub const fn offset(self) -> usize {
        match self {
            SpeedField::Source => 1,
        }
    }

    /// Field name as in the DBC and the docs.
    pub const fn name(self) -> &'static str {
        match self {
            SpeedField::Source => "source",
        }
    }
}

/// The lengths a frame may have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ExpectedLength {
    /// Exactly this many bytes.
    Exactly(usize),
    /// One of two lengths.
    Either(usize, usize),
}

impl fmt::Display for ExpectedLength {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExpectedLength::Exactly(n) => write!(f, "{n}"),
            ExpectedLength::Either(a, b) => write!(f, "{a} or {b}"),
        }
    }
}

/// Why bytes are not a valid frame. Every variant names the CAN id; those about a field name
/// its byte offset too (see [`DecodeError::offset`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecodeError {
    /// The identifier is not in the bearingd block (or is not an 11-bit identifier).
    UnknownId(u32),
    /// The identifier is known, the length is not one its layout has.
    WrongLength {
        /// CAN id.
        id: u16,
        /// What the layout allows.
        expected: ExpectedLength,
        /// What arrived.
        got: usize,
    },
    /// FD data frame whose sample count (byte 6) is 0 or more than 28.
    BadSampleCount {
        /// CAN id.
        id: u16,
        /// The count byte.
        count: u8,
    },
    /// A metadata field holds a value the protocol does not allow.
    BadMetadata {
        /// CAN id.
        id: u16,
        /// Which field.
        field: MetadataField,
        /// The value found (an `f32`'s bits for [`MetadataField::Scale`]).
        value: u32,
    },
    /// A speed field holds a value the protocol does not allow.
    BadSpeed {
        /// CAN id.
        id: u16,
        /// Which field.
        field: SpeedField,
        /// The value found.
        value: u32,
    },
}

impl DecodeError {
    /// The CAN id of the refused frame.
    pub fn can_id(&self) -> u32 {
        match *self {
            DecodeError::UnknownId(id) => id,
            DecodeError::WrongLength { id, .. }
            | DecodeError::BadSampleCount { id, .. }
            | DecodeError::BadMetadata { id, .. }
            | DecodeError::BadSpeed { id, .. } => u32::from(id),
        }
    }

    /// Byte offset of the offending field, if the error is about one field.
    pub fn offset(&self) -> Option<usize> {
        match *self {
            DecodeError::UnknownId(_) | DecodeError::WrongLength { .. } => None,
            DecodeError::BadSampleCount { .. } => Some(FD_COUNT_OFFSET),
            DecodeError::BadMetadata { field, .. } => Some(field.offset()),
            DecodeError::BadSpeed { field, .. } => Some(field.offset()),
        }
    }
}

/// Writes "frame 0x1f3 (metadata, node 3)".
struct FrameName(u16);

impl fmt::Display for FrameName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "frame {:#05x}", self.0)?;
        match CanId::parse(u32::from(self.0)) {
            Some(CanId {
                node,
                message: MessageKind::Data { kind, axis },
            }) => {
                let kind = match kind {
                    FrameKind::Classic => "classic data",
                    FrameKind::Fd => "FD data",
                };
                write!(f, " ({kind}, node {node}, axis {axis})")
            }
            Some(CanId {
                node,
                message: MessageKind::Speed,
            }) => write!(f, " (speed, node {node})"),
            Some(CanId {
                node,
                message: MessageKind::Metadata,
            }) => write!(f, " (metadata, node {node})"),
            None => Ok(()),
        }
    }
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            DecodeError::UnknownId(id) if id > 0x7FF => write!(
                f,
                "CAN id {id:#x} is not an 11-bit standard id; bearingd frames use 0x100..=0x1ff"
            ),
            DecodeError::UnknownId(id) => write!(
                f,
                "CAN id {id:#05x} is not a bearingd frame (data 0x100..=0x17f, speed \
                 0x180..=0x18f, metadata 0x1f0..=0x1ff)"
            ),
            DecodeError::WrongLength { id, expected, got } => {
                write!(f, "{}: {got} bytes, expected {expected}", FrameName(id))
            }
            DecodeError::BadSampleCount { id, count } => write!(
                f,
                "{}: byte {FD_COUNT_OFFSET} (sample_count) = {count}, expected 1..={}",
                FrameName(id),
                FrameKind::Fd.max_samples()
            ),
            DecodeError::BadMetadata { id, field, value } => {
                write!(
                    f,
                    "{}: byte {} ({}) = ",
                    FrameName(id),
                    field.offset(),
                    field.name()
                )?;
                match field {
                    MetadataField::Page => {
                        write!(f, "{value}, expected a page number 0..=1")
                    }
                    MetadataField::ProtocolVersion => write!(
                        f,
                        "{value}, this decoder speaks protocol version {PROTOCOL_VERSION} only"
                    ),
                    MetadataField::SampleRate => write!(f, "{value}, expected a rate > 0 Hz"),
                    MetadataField::Axes => write!(
                        f,
                        "{value:#04x}, expected a non-empty mask of axes 0..={}",
                        AXIS_COUNT - 1
                    ),
                    MetadataField::DataKind => {
                        write!(f, "{value}, expected 0 (classic) or 1 (FD)")
                    }
                    MetadataField::Scale => write!(
                        f,
                        "{} (bits {value:#010x}), expected a finite scale > 0 g/count",
                        f32::from_bits(value)
                    ),
                }
            }
            DecodeError::BadSpeed { id, field, value } => match field {
                SpeedField::Source => write!(
                    f,
                    "{}: byte {} ({}) = {value}, expected 0 (tachometer) or 1 (drive)",
                    FrameName(id),
                    field.offset(),
                    field.name()
                ),
            },
        }
    }
}

impl core::error::Error for DecodeError {}

/// Why a frame cannot be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EncodeError {
    /// Node id not in `0..16`.
    NodeOutOfRange(u8),
    /// Axis id not in `0..4`.
    AxisOutOfRange(u8),
    /// A data frame without samples.
    NoSamples,
    /// More samples than the layout carries.
    TooManySamples {
        /// Layout asked for.
        kind: FrameKind,
        /// Its capacity.
        max: usize,
        /// Samples in the frame.
        got: usize,
    },
    /// A metadata value the decoder would refuse (same meaning as in [`DecodeError`]).
    BadMetadata {
        /// Which field.
        field: MetadataField,
        /// The value.
        value: u32,
    },
    /// `Some(u32::MAX)` speed: that value means "not available" on the wire.
    SpeedOutOfRange,
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            EncodeError::NodeOutOfRange(n) => {
                write!(f, "node id {n} out of range 0..={}", NODE_COUNT - 1)
            }
            EncodeError::AxisOutOfRange(a) => {
                write!(f, "axis id {a} out of range 0..={}", AXIS_COUNT - 1)
            }
            EncodeError::NoSamples => write!(f, "data frame without samples"),
            EncodeError::TooManySamples { kind, max, got } => {
                write!(
                    f,
                    "{got} samples do not fit a {kind:?} data frame (max {max})"
                )
            }
            EncodeError::BadMetadata { field, value } => {
                write!(
                    f,
                    "metadata field {} has invalid value {value:#x}",
                    field.name()
                )
            }
            EncodeError::SpeedOutOfRange => write!(
                f,
                "speed {SPEED_NOT_AVAILABLE} centi-rpm is reserved for \"not available\""
            ),
        }
    }
}

impl core::error::Error for EncodeError {}

/// Encodes `frame` into `out`; returns the 11-bit CAN id and the frame length (the DLC's byte
/// count). `kind` chooses the layout of data frames; metadata and speed frames have one 8-byte
/// layout that travels on classic and FD buses alike, so `kind` does not affect them.
///
/// Only `out[..len]` is written; padding and reserved bytes in it are zeroed. Sequence and
/// first-sample values wider than the layout's fields are truncated to their low bits: they are
/// wrapping counters, and the receiver extends them again.
pub fn encode(
    frame: &Frame,
    kind: FrameKind,
    out: &mut [u8; 64],
) -> Result<(u16, usize), EncodeError> {
    match frame {
        Frame::Data(d) => encode_data(d, kind, out),
        Frame::Metadata(m) => encode_metadata(m, out),
        Frame::Speed(s) => encode_speed(s, out),
    }
}

fn id_of(node: u8, message: MessageKind) -> Result<u16, EncodeError> {
    if node >= NODE_COUNT {
        return Err(EncodeError::NodeOutOfRange(node));
    }
    if let MessageKind::Data { axis, .. } = message {
        if axis >= AXIS_COUNT {
            return Err(EncodeError::AxisOutOfRange(axis));
        }
    }
    // Both parts are in range, so the id exists.
    CanId { node, message }
        .raw()
        .ok_or(EncodeError::NodeOutOfRange(node))
}

fn encode_data(
    d: &DataFrame,
    kind: FrameKind,
    out: &mut [u8; 64],
) -> Result<(u16, usize), EncodeError> {
    let id = id_of(d.node, MessageKind::Data { kind, axis: d.axis })?;
    let n = d.samples.len();
    if n == 0 {
        return Err(EncodeError::NoSamples);
    }
    if n > kind.max_samples() {
        return Err(EncodeError::TooManySamples {
            kind,
            max: kind.max_samples(),
            got: n,
        });
    }
    let (header, len) = match kind {
        FrameKind::Classic => {
            out[0] = d.sequence as u8;
            out[1..4].copy_from_slice(&d.first_sample.to_le_bytes()[..3]);
            (CLASSIC_HEADER, CLASSIC_HEADER + 2 * n)
        }
        FrameKind::Fd => {
            out[0..2].copy_from_slice(&d.sequence.to_le_bytes());
            out[2..6].copy_from_slice(&d.first_sample.to_le_bytes());
            out[FD_COUNT_OFFSET] = n as u8;
            out[7] = 0;
            (FD_HEADER, FD_DATA_LEN)
        }
    };
    let body = &mut out[header..len];
    body.fill(0);
    for (chunk, s) in body.chunks_exact_mut(2).zip(d.samples.iter()) {
        chunk.copy_from_slice(&s.to_le_bytes());
    }
    Ok((id, len))
}

fn check_stream(s: &StreamPage) -> Result<(), (MetadataField, u32)> {
    if s.sample_rate_hz == 0 {
        return Err((MetadataField::SampleRate, 0));
    }
    if s.axes.is_empty() {
        return Err((MetadataField::Axes, u32::from(s.axes.bits())));
    }
    Ok(())
}

fn check_scale(scale: f32) -> Result<(), (MetadataField, u32)> {
    // `!(x > 0.0)` also refuses NaN.
    if !scale.is_finite() || scale <= 0.0 {
        return Err((MetadataField::Scale, scale.to_bits()));
    }
    Ok(())
}

fn encode_metadata(m: &Metadata, out: &mut [u8; 64]) -> Result<(u16, usize), EncodeError> {
    let id = id_of(m.node, MessageKind::Metadata)?;
    let bad = |(field, value)| EncodeError::BadMetadata { field, value };
    let out = &mut out[..METADATA_LEN];
    out[0] = m.page.index() | (PROTOCOL_VERSION << 4);
    match &m.page {
        MetadataPage::Stream(s) => {
            check_stream(s).map_err(bad)?;
            out[1..5].copy_from_slice(&s.sample_rate_hz.to_le_bytes());
            out[5] = s.axes.bits();
            out[6] = s.data_kind.code();
            out[7] = 0;
        }
        MetadataPage::Device(d) => {
            check_scale(d.scale_g_per_count).map_err(bad)?;
            out[1..5].copy_from_slice(&d.scale_g_per_count.to_le_bytes());
            out[5] = d.firmware.major;
            out[6] = d.firmware.minor;
            out[7] = d.firmware.patch;
        }
    }
    Ok((id, METADATA_LEN))
}

fn encode_speed(s: &SpeedFrame, out: &mut [u8; 64]) -> Result<(u16, usize), EncodeError> {
    let id = id_of(s.node, MessageKind::Speed)?;
    let centi = match s.centi_rpm {
        None => SPEED_NOT_AVAILABLE,
        Some(SPEED_NOT_AVAILABLE) => return Err(EncodeError::SpeedOutOfRange),
        Some(c) => c,
    };
    out[0] = s.sequence;
    out[1] = s.source.code();
    out[2..6].copy_from_slice(&centi.to_le_bytes());
    out[6] = 0;
    out[7] = 0;
    Ok((id, SPEED_LEN))
}

/// Decodes one frame. `can_id` is the bare identifier (SocketCAN users mask off the EFF, RTR
/// and ERR flag bits first; any value above `0x7FF` is refused as [`DecodeError::UnknownId`]).
/// `data` is the payload, whose length must be one the identifier's layout has.
pub fn decode(can_id: u32, data: &[u8]) -> Result<Frame, DecodeError> {
    let parsed = CanId::parse(can_id).ok_or(DecodeError::UnknownId(can_id))?;
    // `parse` only accepts ids <= 0x7FF.
    let id = can_id as u16;
    let node = parsed.node;
    let wrong_length = |expected| DecodeError::WrongLength {
        id,
        expected,
        got: data.len(),
    };
    match parsed.message {
        MessageKind::Data {
            kind: FrameKind::Classic,
            axis,
        } => {
            let n = match data.len() {
                6 => 1,
                CLASSIC_DATA_LEN => 2,
                _ => {
                    return Err(wrong_length(ExpectedLength::Either(6, CLASSIC_DATA_LEN)));
                }
            };
            let first_sample = u32::from_le_bytes([data[1], data[2], data[3], 0]);
            Ok(Frame::Data(DataFrame {
                node,
                axis,
                sequence: u16::from(data[0]),
                first_sample,
                samples: read_samples(&data[CLASSIC_HEADER..CLASSIC_HEADER + 2 * n]),
            }))
        }
        MessageKind::Data {
            kind: FrameKind::Fd,
            axis,
        } => {
            if data.len() != FD_DATA_LEN {
                return Err(wrong_length(ExpectedLength::Exactly(FD_DATA_LEN)));
            }
            let count = data[FD_COUNT_OFFSET];
            let n = usize::from(count);
            if n == 0 || n > FrameKind::Fd.max_samples() {
                return Err(DecodeError::BadSampleCount { id, count });
            }
            Ok(Frame::Data(DataFrame {
                node,
                axis,
                sequence: u16::from_le_bytes([data[0], data[1]]),
                first_sample: u32::from_le_bytes([data[2], data[3], data[4], data[5]]),
                samples: read_samples(&data[FD_HEADER..FD_HEADER + 2 * n]),
            }))
        }
        MessageKind::Speed => {
            if data.len() != SPEED_LEN {
                return Err(wrong_length(ExpectedLength::Exactly(SPEED_LEN)));
            }
            let source = SpeedSource::from_code(data[1]).ok_or(DecodeError::BadSpeed {
                id,
                field: SpeedField::Source,
                value: u32::from(data[1]),
            })?;
            let centi = u32::from_le_bytes([data[2], data[3], data[4], data[5]]);
            Ok(Frame::Speed(SpeedFrame {
                node,
                sequence: data[0],
                source,
                centi_rpm: (centi != SPEED_NOT_AVAILABLE).then_some(centi),
            }))
        }
        MessageKind::Metadata => {
            if data.len() != METADATA_LEN {
                return Err(wrong_length(ExpectedLength::Exactly(METADATA_LEN)));
            }
            let bad = |(field, value)| DecodeError::BadMetadata { id, field, value };
            let version = data[0] >> 4;
            if version != PROTOCOL_VERSION {
                return Err(bad((MetadataField::ProtocolVersion, u32::from(version))));
            }
            let word = u32::from_le_bytes([data[1], data[2], data[3], data[4]]);
            let page = match data[0] & 0x0F {
                0 => {
                    let axes = AxisSet::from_bits(data[5])
                        .ok_or(bad((MetadataField::Axes, u32::from(data[5]))))?;
                    let data_kind = FrameKind::from_code(data[6])
                        .ok_or(bad((MetadataField::DataKind, u32::from(data[6]))))?;
                    let stream = StreamPage {
                        sample_rate_hz: word,
                        axes,
                        data_kind,
                    };
                    check_stream(&stream).map_err(bad)?;
                    MetadataPage::Stream(stream)
                }
                1 => {
                    let scale = f32::from_bits(word);
                    check_scale(scale).map_err(bad)?;
                    MetadataPage::Device(DevicePage {
                        scale_g_per_count: scale,
                        firmware: FirmwareVersion {
                            major: data[5],
                            minor: data[6],
                            patch: data[7],
                        },
                    })
                }
                page => return Err(bad((MetadataField::Page, u32::from(page)))),
            };
            Ok(Frame::Metadata(Metadata { node, page }))
        }
    }
}

/// Reads little-endian `i16`s. Callers pass at most `2 * FrameKind::Fd.max_samples()` bytes,
/// which is below the vector's capacity; the loop stops rather than panics if that ever changes.
fn read_samples(bytes: &[u8]) -> Vec<i16, SAMPLES_CAPACITY> {
    let mut samples = Vec::new();
    for c in bytes.chunks_exact(2) {
        if samples.push(i16::from_le_bytes([c[0], c[1]])).is_err() {
            break;
        }
    }
    samples
}
