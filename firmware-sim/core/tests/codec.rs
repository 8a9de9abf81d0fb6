//! encode/decode: round trips at the boundaries, exact bytes, every error, and a sweep of every
//! identifier × every length × random payloads that must never panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use bearing_wire::codec::{ExpectedLength, MetadataField, SpeedField};
use bearing_wire::id::{CanId, MessageKind};
use bearing_wire::{
    decode, encode, AxisSet, DecodeError, DevicePage, EncodeError, FirmwareVersion, Frame,
    FrameKind, Metadata, MetadataPage, SpeedFrame, SpeedSource, StreamPage,
};
use common::{data, truncated, XorShift};

const KINDS: [FrameKind; 2] = [FrameKind::Classic, FrameKind::Fd];

fn round_trip(frame: &Frame, kind: FrameKind) -> (u16, Vec<u8>) {
    let mut out = [0xAAu8; 64];
    let (id, len) = encode(frame, kind, &mut out).unwrap_or_else(|e| panic!("{frame:?}: {e}"));
    let decoded = decode(u32::from(id), &out[..len]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(decoded, truncated(frame, kind), "kind {kind:?}");
    (id, out[..len].to_vec())
}

fn stream(rate: u32, axes: u8, kind: FrameKind) -> MetadataPage {
    MetadataPage::Stream(StreamPage {
        sample_rate_hz: rate,
        axes: AxisSet::from_bits(axes).unwrap(),
        data_kind: kind,
    })
}

fn device(scale: f32, fw: (u8, u8, u8)) -> MetadataPage {
    MetadataPage::Device(DevicePage {
        scale_g_per_count: scale,
        firmware: FirmwareVersion {
            major: fw.0,
            minor: fw.1,
            patch: fw.2,
        },
    })
}

#[test]
fn data_frames_round_trip_at_the_boundaries() {
    let extremes = [i16::MIN, i16::MAX, 0, -1, 1];
    for kind in KINDS {
        for node in [0, 7, 15] {
            for axis in [0, 3] {
                for sequence in [0, 1, 0xFF, 0x100, u16::MAX] {
                    for first_sample in [0, 1, 0x00FF_FFFF, 0x0100_0000, u32::MAX] {
                        for n in [1, kind.max_samples()] {
                            let samples: Vec<i16> =
                                (0..n).map(|i| extremes[i % extremes.len()]).collect();
                            let f = Frame::Data(data(node, axis, sequence, first_sample, &samples));
                            let (id, bytes) = round_trip(&f, kind);
                            let base = match kind {
                                FrameKind::Classic => 0x140,
                                FrameKind::Fd => 0x100,
                            };
                            assert_eq!(id, base + 16 * u16::from(axis) + u16::from(node));
                            let expected_len = match kind {
                                FrameKind::Classic => 4 + 2 * n,
                                FrameKind::Fd => 64,
                            };
                            assert_eq!(bytes.len(), expected_len);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn metadata_and_speed_round_trip_at_the_boundaries_in_both_kinds() {
    let pages = [
        stream(1, 0b0001, FrameKind::Classic),
        stream(u32::MAX, 0b1111, FrameKind::Fd),
        stream(25_600, 0b0111, FrameKind::Fd),
        device(f32::MIN_POSITIVE, (0, 0, 0)),
        device(f32::from_bits(1), (255, 255, 255)), // smallest subnormal: finite and > 0
        device(f32::MAX, (1, 2, 3)),
        device(1.0 / 16384.0, (0, 9, 1)),
    ];
    for kind in KINDS {
        for node in [0, 15] {
            for page in pages {
                let (id, bytes) = round_trip(&Frame::Metadata(Metadata { node, page }), kind);
                assert_eq!(id, 0x1F0 + u16::from(node));
                assert_eq!(bytes.len(), 8);
            }
            for source in [SpeedSource::Tachometer, SpeedSource::Drive] {
                for sequence in [0, 255] {
                    for centi_rpm in [None, Some(0), Some(148_000), Some(u32::MAX - 1)] {
                        let f = Frame::Speed(SpeedFrame {
                            node,
                            sequence,
                            source,
                            centi_rpm,
                        });
                        let (id, bytes) = round_trip(&f, kind);
                        assert_eq!(id, 0x180 + u16::from(node));
                        assert_eq!(bytes.len(), 8);
                    }
                }
            }
        }
    }
}

#[test]
fn bytes_are_little_endian_where_the_docs_say() {
    let mut out = [0u8; 64];
    let f = Frame::Data(data(5, 2, 0x0102, 0x0304_0506, &[0x0708, -2]));
    let (id, len) = encode(&f, FrameKind::Fd, &mut out).unwrap();
    assert_eq!((id, len), (0x125, 64));
    assert_eq!(
        &out[..12],
        &[0x02, 0x01, 0x06, 0x05, 0x04, 0x03, 2, 0, 0x08, 0x07, 0xFE, 0xFF]
    );
    assert!(out[12..64].iter().all(|&b| b == 0), "padding is zero");

    let (id, len) = encode(&f, FrameKind::Classic, &mut out).unwrap();
    assert_eq!((id, len), (0x165, 8));
    assert_eq!(&out[..8], &[0x02, 0x06, 0x05, 0x04, 0x08, 0x07, 0xFE, 0xFF]);

    let m = Frame::Metadata(Metadata {
        node: 3,
        page: stream(25_600, 0b0111, FrameKind::Fd),
    });
    let (id, len) = encode(&m, FrameKind::Classic, &mut out).unwrap();
    assert_eq!((id, len), (0x1F3, 8));
    assert_eq!(&out[..8], &[0x10, 0x00, 0x64, 0x00, 0x00, 0x07, 0x01, 0x00]);

    let m = Frame::Metadata(Metadata {
        node: 3,
        page: device(1.0, (1, 2, 3)),
    });
    encode(&m, FrameKind::Fd, &mut out).unwrap();
    assert_eq!(&out[..8], &[0x11, 0x00, 0x00, 0x80, 0x3F, 1, 2, 3]);

    let s = Frame::Speed(SpeedFrame {
        node: 9,
        sequence: 7,
        source: SpeedSource::Drive,
        centi_rpm: Some(179_700),
    });
    let (id, len) = encode(&s, FrameKind::Classic, &mut out).unwrap();
    assert_eq!((id, len), (0x189, 8));
    assert_eq!(&out[..8], &[7, 1, 0xF4, 0xBD, 0x02, 0x00, 0, 0]);
}

#[test]
fn encode_refuses_what_decode_would_refuse() {
    let mut out = [0u8; 64];
    let enc = |f: &Frame, kind| encode(f, kind, &mut [0u8; 64]).unwrap_err();
    assert_eq!(
        enc(&Frame::Data(data(16, 0, 0, 0, &[1])), FrameKind::Fd),
        EncodeError::NodeOutOfRange(16)
    );
    assert_eq!(
        enc(&Frame::Data(data(0, 4, 0, 0, &[1])), FrameKind::Fd),
        EncodeError::AxisOutOfRange(4)
    );
    assert_eq!(
        enc(&Frame::Data(data(0, 0, 0, 0, &[])), FrameKind::Classic),
        EncodeError::NoSamples
    );
    assert_eq!(
        enc(
            &Frame::Data(data(0, 0, 0, 0, &[1, 2, 3])),
            FrameKind::Classic
        ),
        EncodeError::TooManySamples {
            kind: FrameKind::Classic,
            max: 2,
            got: 3
        }
    );
    assert_eq!(
        enc(&Frame::Data(data(0, 0, 0, 0, &[0; 29])), FrameKind::Fd),
        EncodeError::TooManySamples {
            kind: FrameKind::Fd,
            max: 28,
            got: 29
        }
    );
    let meta = |page| Frame::Metadata(Metadata { node: 1, page });
    assert_eq!(
        enc(&meta(stream(0, 1, FrameKind::Fd)), FrameKind::Fd),
        EncodeError::BadMetadata {
            field: MetadataField::SampleRate,
            value: 0
        }
    );
    assert_eq!(
        enc(&meta(stream(100, 0, FrameKind::Fd)), FrameKind::Fd),
        EncodeError::BadMetadata {
            field: MetadataField::Axes,
            value: 0
        }
    );
    for scale in [0.0, -0.0, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(
            enc(&meta(device(scale, (1, 0, 0))), FrameKind::Classic),
            EncodeError::BadMetadata {
                field: MetadataField::Scale,
                value: scale.to_bits()
            }
        );
    }
    let speed = Frame::Speed(SpeedFrame {
        node: 0,
        sequence: 0,
        source: SpeedSource::Tachometer,
        centi_rpm: Some(u32::MAX),
    });
    assert_eq!(enc(&speed, FrameKind::Fd), EncodeError::SpeedOutOfRange);
    assert_eq!(
        encode(
            &Frame::Metadata(Metadata {
                node: 16,
                page: device(1.0, (0, 0, 0))
            }),
            FrameKind::Fd,
            &mut out
        ),
        Err(EncodeError::NodeOutOfRange(16))
    );
}

/// The lengths each layout accepts.
fn valid_lengths(message: MessageKind) -> &'static [usize] {
    match message {
        MessageKind::Data {
            kind: FrameKind::Classic,
            ..
        } => &[6, 8],
        MessageKind::Data {
            kind: FrameKind::Fd,
            ..
        } => &[64],
        MessageKind::Speed | MessageKind::Metadata => &[8],
    }
}

#[test]
fn every_wrong_length_of_every_id_is_reported_as_such() {
    for raw in 0u32..=0x7FF {
        for len in 0..=64usize {
            let bytes = [0u8; 64];
            let result = decode(raw, &bytes[..len]);
            let Some(id) = CanId::parse(raw) else {
                assert_eq!(result, Err(DecodeError::UnknownId(raw)));
                continue;
            };
            let valid = valid_lengths(id.message);
            if valid.contains(&len) {
                assert!(
                    !matches!(result, Err(DecodeError::WrongLength { .. })),
                    "{raw:#x} len {len}: {result:?}"
                );
            } else {
                let expected = match valid {
                    [a] => ExpectedLength::Exactly(*a),
                    [a, b] => ExpectedLength::Either(*a, *b),
                    _ => unreachable!(),
                };
                assert_eq!(
                    result,
                    Err(DecodeError::WrongLength {
                        id: raw as u16,
                        expected,
                        got: len
                    })
                );
            }
        }
    }
}

#[test]
fn every_bad_field_value_is_reported_with_its_offset() {
    // FD sample count.
    for count in (0..=255u8).filter(|c| *c == 0 || *c > 28) {
        let mut bytes = [0u8; 64];
        bytes[6] = count;
        let err = decode(0x100, &bytes).unwrap_err();
        assert_eq!(err, DecodeError::BadSampleCount { id: 0x100, count });
        assert_eq!(err.offset(), Some(6));
    }
    let good_stream = [0x10, 0x00, 0x64, 0, 0, 0x01, 0x00, 0];
    let good_device = [0x11, 0, 0, 0x80, 0x3F, 1, 0, 0];
    assert!(decode(0x1F2, &good_stream).is_ok());
    assert!(decode(0x1F2, &good_device).is_ok());
    let bad = |field, value| {
        Err::<Frame, _>(DecodeError::BadMetadata {
            id: 0x1F2,
            field,
            value,
        })
    };
    // Protocol version: every nibble but 1, on both pages.
    for version in (0..16u8).filter(|v| *v != 1) {
        for page in [good_stream, good_device] {
            let mut b = page;
            b[0] = (b[0] & 0x0F) | (version << 4);
            assert_eq!(
                decode(0x1F2, &b),
                bad(MetadataField::ProtocolVersion, u32::from(version))
            );
        }
    }
    for page in 2..16u8 {
        let mut b = good_stream;
        b[0] = 0x10 | page;
        assert_eq!(decode(0x1F2, &b), bad(MetadataField::Page, u32::from(page)));
    }
    let mut b = good_stream;
    b[1..5].fill(0);
    assert_eq!(decode(0x1F2, &b), bad(MetadataField::SampleRate, 0));
    for axes in (0..=255u8).filter(|a| *a == 0 || *a > 0x0F) {
        let mut b = good_stream;
        b[5] = axes;
        assert_eq!(decode(0x1F2, &b), bad(MetadataField::Axes, u32::from(axes)));
    }
    for kind in 2..=255u8 {
        let mut b = good_stream;
        b[6] = kind;
        assert_eq!(
            decode(0x1F2, &b),
            bad(MetadataField::DataKind, u32::from(kind))
        );
    }
    for scale in [
        0.0f32,
        -0.0,
        -1e-6,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ] {
        let mut b = good_device;
        b[1..5].copy_from_slice(&scale.to_le_bytes());
        assert_eq!(
            decode(0x1F2, &b),
            bad(MetadataField::Scale, scale.to_bits())
        );
    }
    for source in 2..=255u8 {
        let b = [0, source, 0, 0, 0, 0, 0, 0];
        let err = decode(0x18A, &b).unwrap_err();
        assert_eq!(
            err,
            DecodeError::BadSpeed {
                id: 0x18A,
                field: SpeedField::Source,
                value: u32::from(source)
            }
        );
        assert_eq!(err.offset(), Some(1));
    }
}

#[test]
fn error_messages_name_the_frame_id_and_the_byte() {
    let msg = |id, bytes: &[u8]| decode(id, bytes).unwrap_err().to_string();
    let m = msg(0x1F3, &[0x20, 0, 0, 0, 0, 0, 0, 0]);
    assert!(m.contains("frame 0x1f3 (metadata, node 3)"), "{m}");
    assert!(m.contains("byte 0 (protocol_version) = 2"), "{m}");
    let m = msg(0x1F3, &[0x11, 0, 0, 0xC0, 0x7F, 0, 0, 0]);
    assert!(m.contains("byte 1 (scale_g_per_count) = NaN"), "{m}");
    let m = msg(0x1F3, &[0x10, 0, 0, 0, 0, 1, 0, 0]);
    assert!(m.contains("byte 1 (sample_rate_hz) = 0"), "{m}");
    let m = msg(0x1F3, &[0x10, 1, 0, 0, 0, 0x30, 0, 0]);
    assert!(m.contains("byte 5 (axes) = 0x30"), "{m}");
    let m = msg(0x1F3, &[0x10, 1, 0, 0, 0, 1, 9, 0]);
    assert!(m.contains("byte 6 (data_kind) = 9"), "{m}");
    let m = msg(0x1F3, &[0x15, 1, 0, 0, 0, 1, 9, 0]);
    assert!(m.contains("byte 0 (page) = 5"), "{m}");
    let m = msg(0x13F, &[0u8; 64]);
    assert!(
        m.contains("frame 0x13f (FD data, node 15, axis 3): byte 6 (sample_count) = 0"),
        "{m}"
    );
    let m = msg(0x140, &[0u8; 7]);
    assert_eq!(
        m,
        "frame 0x140 (classic data, node 0, axis 0): 7 bytes, expected 6 or 8"
    );
    let m = msg(0x18F, &[0, 7, 0, 0, 0, 0, 0, 0]);
    assert!(
        m.contains("frame 0x18f (speed, node 15): byte 1 (source) = 7"),
        "{m}"
    );
    let m = msg(0x7FF, &[]);
    assert!(m.contains("CAN id 0x7ff is not a bearingd frame"), "{m}");
    let m = msg(0x8000_0140, &[]);
    assert!(m.contains("0x80000140 is not an 11-bit"), "{m}");
    let e = decode(0x142, &[0; 3]).unwrap_err();
    assert_eq!((e.can_id(), e.offset()), (0x142, None));
}

fn layout_of(raw: u32) -> Option<FrameKind> {
    match CanId::parse(raw)?.message {
        MessageKind::Data { kind, .. } => Some(kind),
        // Metadata and speed have one layout; the kind is irrelevant.
        MessageKind::Speed | MessageKind::Metadata => Some(FrameKind::Classic),
    }
}

/// Every id, every length, random bytes: no panic, and whatever decodes re-encodes to the same
/// id and length and decodes to the same frame again.
#[test]
fn random_bytes_never_panic_and_what_decodes_is_canonical() {
    let mut rng = XorShift::new(0x5EED_0001);
    let mut accepted = 0u64;
    let mut ids: Vec<u32> = (0..=0x7FF).collect();
    ids.extend((0..64).map(|_| rng.next_u32()));
    for &raw in &ids {
        let valid = CanId::parse(raw).map_or(&[][..], |id| valid_lengths(id.message));
        for len in 0..=64usize {
            // Many payloads where the length is right, a few where it is not.
            let rounds = if valid.contains(&len) { 64 } else { 2 };
            for round in 0..rounds {
                let mut bytes = [0u8; 64];
                rng.fill(&mut bytes[..len]);
                if round % 2 == 0 && len >= 7 {
                    // Make plausible frames common: valid version nibble, small page and
                    // count, so the sweep reaches past the first checks.
                    bytes[0] = 0x10 | (bytes[0] & 1);
                    bytes[6] = 1 + bytes[6] % 28;
                    bytes[5] &= 0x0F;
                    bytes[1] &= 1;
                }
                let Ok(frame) = decode(raw, &bytes[..len]) else {
                    continue;
                };
                accepted += 1;
                let kind = layout_of(raw).unwrap();
                let mut out = [0u8; 64];
                let (id, out_len) = encode(&frame, kind, &mut out)
                    .unwrap_or_else(|e| panic!("{raw:#x} {:02x?}: {e}", &bytes[..len]));
                assert_eq!((u32::from(id), out_len), (raw, len));
                assert_eq!(decode(raw, &out[..out_len]), Ok(frame));
            }
        }
    }
    assert!(
        accepted > 5000,
        "sweep reached only {accepted} valid frames"
    );
}

/// Random valid frames: encode then decode gives the frame back (up to the counter bits the
/// layout drops).
#[test]
fn random_valid_frames_round_trip() {
    let mut rng = XorShift::new(42);
    for _ in 0..20_000 {
        let kind = KINDS[rng.below(2) as usize];
        let node = rng.below(16) as u8;
        let frame = match rng.below(3) {
            0 => {
                let n = 1 + rng.below(kind.max_samples() as u64) as usize;
                let samples: Vec<i16> = (0..n).map(|_| rng.next_u64() as i16).collect();
                Frame::Data(data(
                    node,
                    rng.below(4) as u8,
                    rng.next_u64() as u16,
                    rng.next_u32(),
                    &samples,
                ))
            }
            1 => Frame::Metadata(Metadata {
                node,
                page: if rng.below(2) == 0 {
                    stream(
                        1 + rng.below(u64::from(u32::MAX)) as u32,
                        1 + rng.below(15) as u8,
                        KINDS[rng.below(2) as usize],
                    )
                } else {
                    let scale = f32::from_bits(rng.next_u32() & 0x7FFF_FFFF);
                    if !scale.is_finite() || scale == 0.0 {
                        continue;
                    }
                    let fw = rng.next_u32().to_le_bytes();
                    device(scale, (fw[0], fw[1], fw[2]))
                },
            }),
            _ => Frame::Speed(SpeedFrame {
                node,
                sequence: rng.next_u64() as u8,
                source: [SpeedSource::Tachometer, SpeedSource::Drive][rng.below(2) as usize],
                centi_rpm: Some(rng.next_u32()).filter(|&c| c != u32::MAX),
            }),
        };
        round_trip(&frame, kind);
    }
}
