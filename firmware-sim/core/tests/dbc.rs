//! Keeps `config/bearingd.dbc` and `tests/data/example_frames.txt` true to the code.
//!
//! The DBC is rendered here from the id plan and the layouts, and compared with the committed
//! file; the example frames are encoded by the real encoder and written as hex with the signal
//! values a DBC decoder must find in them. `tests/check_dbc.py` then loads the DBC with
//! `cantools` and decodes (and re-encodes) every example, so a third-party tool is checked
//! against our bytes. After an intended change, regenerate both files with
//!
//! ```sh
//! BEARING_WIRE_BLESS=1 cargo test -p bearing-wire --test dbc
//! ```
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::fmt::Write as _;
use std::path::PathBuf;

use bearing_wire::id::{
    CanId, MessageKind, AXIS_COUNT, DATA_CLASSIC_BASE, DATA_FD_BASE, METADATA_BASE, NODE_COUNT,
    SPEED_BASE,
};
use bearing_wire::{
    decode, encode, AxisSet, DevicePage, FirmwareVersion, Frame, FrameKind, Metadata, MetadataPage,
    SpeedFrame, SpeedSource, StreamPage, PROTOCOL_VERSION,
};
use common::data;

fn repo_file(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Compares `path` with `rendered`; rewrites it instead when `BEARING_WIRE_BLESS` is set.
fn check_or_bless(path: PathBuf, rendered: &str) {
    if std::env::var_os("BEARING_WIRE_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, rendered).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; run with BEARING_WIRE_BLESS=1", path.display()));
    if committed != rendered {
        let line = committed
            .lines()
            .zip(rendered.lines())
            .position(|(a, b)| a != b)
            .map_or(
                committed.lines().count().min(rendered.lines().count()),
                |l| l,
            );
        panic!(
            "{} is stale (first difference at line {}); if the change is intended, run \
             BEARING_WIRE_BLESS=1 cargo test -p bearing-wire --test dbc",
            path.display(),
            line + 1
        );
    }
}

fn sensor(node: u8) -> String {
    format!("SENSOR_{node:02}")
}

fn message_name(id: CanId) -> String {
    match id.message {
        MessageKind::Data {
            kind: FrameKind::Fd,
            axis,
        } => format!("DATA_FD_N{:02}_A{axis}", id.node),
        MessageKind::Data {
            kind: FrameKind::Classic,
            axis,
        } => format!("DATA_CL_N{:02}_A{axis}", id.node),
        MessageKind::Speed => format!("SPEED_N{:02}", id.node),
        MessageKind::Metadata => format!("METADATA_N{:02}", id.node),
    }
}

/// One `SG_` line. `start` is the little-endian start bit (the LSB's bit number).
#[allow(clippy::too_many_arguments)] // one parameter per field of the SG_ line
fn signal(
    out: &mut String,
    name: &str,
    mux: &str,
    start: u32,
    len: u32,
    signed: bool,
    scale: &str,
    range: (&str, &str),
    unit: &str,
) {
    let sign = if signed { '-' } else { '+' };
    writeln!(
        out,
        " SG_ {name} {mux}: {start}|{len}@1{sign} ({scale},0) [{}|{}] \"{unit}\" BEARINGD",
        range.0, range.1
    )
    .unwrap();
}

fn render_dbc() -> String {
    let mut d = String::new();
    let mut comments = String::new();
    let mut values = String::new();
    let mut valtypes = String::new();
    let mut formats = String::new();

    writeln!(d, "VERSION \"bearingd wire protocol {PROTOCOL_VERSION}\"\n").unwrap();
    d.push_str(
        "NS_ :\n\tNS_DESC_\n\tCM_\n\tBA_DEF_\n\tBA_\n\tVAL_\n\tBA_DEF_DEF_\n\tSIG_VALTYPE_\n\n",
    );
    d.push_str("BS_:\n\n");
    d.push_str("BU_: BEARINGD");
    for node in 0..NODE_COUNT {
        write!(d, " {}", sensor(node)).unwrap();
    }
    d.push_str("\n\n");

    // Data frames: FD then classic, by id.
    for (kind, base) in [
        (FrameKind::Fd, DATA_FD_BASE),
        (FrameKind::Classic, DATA_CLASSIC_BASE),
    ] {
        for axis in 0..AXIS_COUNT {
            for node in 0..NODE_COUNT {
                let id = CanId {
                    node,
                    message: MessageKind::Data { kind, axis },
                };
                let raw = id.raw().unwrap();
                assert_eq!(raw, base + 16 * u16::from(axis) + u16::from(node));
                let name = message_name(id);
                let (len, seq_bits, idx_bits, samples_at, n) = match kind {
                    FrameKind::Fd => (64, 16, 32, 64, 28),
                    FrameKind::Classic => (8, 8, 24, 32, 2),
                };
                writeln!(d, "BO_ {raw} {name}: {len} {}", sensor(node)).unwrap();
                let seq_max = ((1u64 << seq_bits) - 1).to_string();
                let idx_max = ((1u64 << idx_bits) - 1).to_string();
                signal(
                    &mut d,
                    "sequence",
                    "",
                    0,
                    seq_bits,
                    false,
                    "1",
                    ("0", &seq_max),
                    "",
                );
                signal(
                    &mut d,
                    "first_sample",
                    "",
                    seq_bits,
                    idx_bits,
                    false,
                    "1",
                    ("0", &idx_max),
                    "sample",
                );
                if kind == FrameKind::Fd {
                    signal(
                        &mut d,
                        "sample_count",
                        "",
                        48,
                        8,
                        false,
                        "1",
                        ("1", "28"),
                        "",
                    );
                }
                for i in 0..n {
                    signal(
                        &mut d,
                        &format!("sample_{i:02}"),
                        "",
                        samples_at + 16 * i,
                        16,
                        true,
                        "1",
                        ("-32768", "32767"),
                        "count",
                    );
                }
                d.push('\n');
                let (what, bits) = match kind {
                    FrameKind::Fd => ("CAN FD data frame", "16-bit sequence, 32-bit"),
                    FrameKind::Classic => {
                        ("Classic data frame", "8-bit sequence, low 24 bits of the")
                    }
                };
                writeln!(
                    comments,
                    "CM_ BO_ {raw} \"{what}: node {node}, axis {axis}; {bits} first-sample index, \
                     samples in ADC counts (g = count * metadata scale_g_per_count).\";"
                )
                .unwrap();
                if kind == FrameKind::Fd {
                    writeln!(formats, "BA_ \"VFrameFormat\" BO_ {raw} 14;").unwrap();
                    writeln!(
                        comments,
                        "CM_ SG_ {raw} sample_count \"Valid samples; sample_NN at and above it are padding (0).\";"
                    )
                    .unwrap();
                }
            }
        }
    }

    for node in 0..NODE_COUNT {
        let id = CanId {
            node,
            message: MessageKind::Speed,
        };
        let raw = id.raw().unwrap();
        assert_eq!(raw, SPEED_BASE + u16::from(node));
        writeln!(d, "BO_ {raw} {}: 8 {}", message_name(id), sensor(node)).unwrap();
        signal(&mut d, "sequence", "", 0, 8, false, "1", ("0", "255"), "");
        signal(&mut d, "source", "", 8, 8, false, "1", ("0", "1"), "");
        signal(
            &mut d,
            "speed",
            "",
            16,
            32,
            false,
            "0.01",
            ("0", "42949672.94"),
            "rpm",
        );
        d.push('\n');
        writeln!(
            comments,
            "CM_ BO_ {raw} \"Shaft speed reported by node {node}.\";"
        )
        .unwrap();
        writeln!(
            comments,
            "CM_ SG_ {raw} speed \"Raw 0xFFFFFFFF means not available.\";"
        )
        .unwrap();
        writeln!(values, "VAL_ {raw} source 1 \"drive\" 0 \"tachometer\" ;").unwrap();
        writeln!(values, "VAL_ {raw} speed 4294967295 \"not_available\" ;").unwrap();
    }

    for node in 0..NODE_COUNT {
        let id = CanId {
            node,
            message: MessageKind::Metadata,
        };
        let raw = id.raw().unwrap();
        assert_eq!(raw, METADATA_BASE + u16::from(node));
        writeln!(d, "BO_ {raw} {}: 8 {}", message_name(id), sensor(node)).unwrap();
        signal(&mut d, "page", "M ", 0, 4, false, "1", ("0", "1"), "");
        let v = PROTOCOL_VERSION.to_string();
        signal(
            &mut d,
            "protocol_version",
            "",
            4,
            4,
            false,
            "1",
            (&v, &v),
            "",
        );
        signal(
            &mut d,
            "sample_rate_hz",
            "m0 ",
            8,
            32,
            false,
            "1",
            ("1", "4294967295"),
            "Hz",
        );
        for axis in 0..AXIS_COUNT {
            let name = format!("axis_{axis}");
            signal(
                &mut d,
                &name,
                "m0 ",
                40 + u32::from(axis),
                1,
                false,
                "1",
                ("0", "1"),
                "",
            );
        }
        signal(
            &mut d,
            "data_kind",
            "m0 ",
            48,
            8,
            false,
            "1",
            ("0", "1"),
            "",
        );
        signal(
            &mut d,
            "scale_g_per_count",
            "m1 ",
            8,
            32,
            true,
            "1",
            ("0", "0"),
            "g/count",
        );
        for (i, part) in ["major", "minor", "patch"].iter().enumerate() {
            let name = format!("firmware_{part}");
            signal(
                &mut d,
                &name,
                "m1 ",
                40 + 8 * i as u32,
                8,
                false,
                "1",
                ("0", "255"),
                "",
            );
        }
        d.push('\n');
        writeln!(
            comments,
            "CM_ BO_ {raw} \"Metadata of node {node}, multiplexed by page: page 0 = stream \
             (sample rate, axes, data-frame kind), page 1 = device (scale, firmware).\";"
        )
        .unwrap();
        writeln!(valtypes, "SIG_VALTYPE_ {raw} scale_g_per_count : 1;").unwrap();
        writeln!(values, "VAL_ {raw} data_kind 1 \"fd\" 0 \"classic\" ;").unwrap();
    }

    writeln!(
        d,
        "CM_ \"bearingd sensor wire protocol {PROTOCOL_VERSION}, little-endian. Layouts, id \
         plan and rules: docs/WIRE_FORMAT.md. Generated by firmware-sim/core/tests/dbc.rs; do \
         not edit by hand.\";"
    )
    .unwrap();
    d.push_str(&comments);
    d.push_str(
        "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\
         \"J1939PG\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\
         \"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"StandardCAN_FD\",\
         \"ExtendedCAN_FD\";\n",
    );
    d.push_str("BA_DEF_ \"BusType\" STRING ;\n");
    d.push_str("BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n");
    d.push_str("BA_DEF_DEF_ \"BusType\" \"CAN FD\";\n");
    d.push_str("BA_ \"BusType\" \"CAN FD\";\n");
    d.push_str(&formats);
    d.push_str(&values);
    d.push_str(&valtypes);
    d
}

#[test]
fn dbc_file_is_current() {
    check_or_bless(repo_file("../../config/bearingd.dbc"), &render_dbc());
}

/// Example frames covering every message kind and layout, with boundary values.
fn examples() -> Vec<(Frame, FrameKind)> {
    let ramp: Vec<i16> = (0..28)
        .map(|i| match i {
            0 => i16::MIN,
            1 => i16::MAX,
            _ => (i as i16 - 14) * 1000,
        })
        .collect();
    vec![
        (Frame::Data(data(0, 0, 0, 0, &ramp)), FrameKind::Fd),
        (
            Frame::Data(data(15, 3, u16::MAX, u32::MAX, &[-1, 0, 1])),
            FrameKind::Fd,
        ),
        (
            Frame::Data(data(3, 1, 0x1234, 0x0ABC_DEF0, &ramp[..27])),
            FrameKind::Fd,
        ),
        (
            Frame::Data(data(0, 0, 255, 0x00FF_FFFF, &[i16::MIN, i16::MAX])),
            FrameKind::Classic,
        ),
        (
            Frame::Data(data(15, 3, 0x0102, 0x0345_6789, &[-2, 300])),
            FrameKind::Classic,
        ),
        (Frame::Data(data(7, 2, 9, 18, &[-77])), FrameKind::Classic),
        (
            Frame::Metadata(Metadata {
                node: 3,
                page: MetadataPage::Stream(StreamPage {
                    sample_rate_hz: 25_600,
                    axes: AxisSet::from_bits(0b0111).unwrap(),
                    data_kind: FrameKind::Fd,
                }),
            }),
            FrameKind::Fd,
        ),
        (
            Frame::Metadata(Metadata {
                node: 15,
                page: MetadataPage::Stream(StreamPage {
                    sample_rate_hz: u32::MAX,
                    axes: AxisSet::from_bits(0b1000).unwrap(),
                    data_kind: FrameKind::Classic,
                }),
            }),
            FrameKind::Classic,
        ),
        (
            Frame::Metadata(Metadata {
                node: 3,
                page: MetadataPage::Device(DevicePage {
                    scale_g_per_count: 1.0 / 4096.0,
                    firmware: FirmwareVersion {
                        major: 1,
                        minor: 22,
                        patch: 255,
                    },
                }),
            }),
            FrameKind::Fd,
        ),
        (
            Frame::Metadata(Metadata {
                node: 0,
                page: MetadataPage::Device(DevicePage {
                    scale_g_per_count: 0.000_123_4,
                    firmware: FirmwareVersion::default(),
                }),
            }),
            FrameKind::Classic,
        ),
        (
            Frame::Speed(SpeedFrame {
                node: 3,
                sequence: 200,
                source: SpeedSource::Tachometer,
                centi_rpm: Some(179_712),
            }),
            FrameKind::Classic,
        ),
        (
            Frame::Speed(SpeedFrame {
                node: 15,
                sequence: 0,
                source: SpeedSource::Drive,
                centi_rpm: None,
            }),
            FrameKind::Fd,
        ),
    ]
}

/// The raw signal values (as the DBC names them) a decoder must find in `frame`.
fn signals(frame: &Frame, kind: FrameKind) -> Vec<(String, String)> {
    let mut s: Vec<(String, String)> = Vec::new();
    let mut put = |k: &str, v: String| s.push((k.to_string(), v));
    match frame {
        Frame::Data(d) => {
            let (seq, idx) = match kind {
                FrameKind::Fd => (d.sequence, d.first_sample),
                FrameKind::Classic => (d.sequence & 0xFF, d.first_sample & 0xFF_FFFF),
            };
            put("sequence", seq.to_string());
            put("first_sample", idx.to_string());
            if kind == FrameKind::Fd {
                put("sample_count", d.samples.len().to_string());
            }
            for i in 0..kind.max_samples() {
                // FD padding decodes as samples of value 0; a short classic frame lacks them.
                match (d.samples.get(i), kind) {
                    (Some(v), _) => put(&format!("sample_{i:02}"), v.to_string()),
                    (None, FrameKind::Fd) => put(&format!("sample_{i:02}"), "0".into()),
                    (None, FrameKind::Classic) => {}
                }
            }
        }
        Frame::Metadata(m) => {
            put("page", m.page.index().to_string());
            put("protocol_version", PROTOCOL_VERSION.to_string());
            match m.page {
                MetadataPage::Stream(st) => {
                    put("sample_rate_hz", st.sample_rate_hz.to_string());
                    for a in 0..AXIS_COUNT {
                        put(
                            &format!("axis_{a}"),
                            u8::from(st.axes.contains(a)).to_string(),
                        );
                    }
                    put("data_kind", st.data_kind.code().to_string());
                }
                MetadataPage::Device(dv) => {
                    // Rust prints the shortest decimal that reads back as the same f32.
                    put("scale_g_per_count", format!("{:?}", dv.scale_g_per_count));
                    put("firmware_major", dv.firmware.major.to_string());
                    put("firmware_minor", dv.firmware.minor.to_string());
                    put("firmware_patch", dv.firmware.patch.to_string());
                }
            }
        }
        Frame::Speed(sp) => {
            put("sequence", sp.sequence.to_string());
            put("source", sp.source.code().to_string());
            put("speed", sp.centi_rpm.unwrap_or(u32::MAX).to_string());
        }
    }
    s
}

fn render_examples() -> String {
    let mut out = String::from(
        "# Example frames encoded by bearing-wire, and the raw signal values a decoder of\n\
         # config/bearingd.dbc must find in them (scaling off, choices off).\n\
         # Generated by firmware-sim/core/tests/dbc.rs; checked by tests/check_dbc.py.\n\
         # can_id data_hex {\"signal\": raw_value, ...}\n",
    );
    for (frame, kind) in examples() {
        let mut bytes = [0u8; 64];
        let (id, len) = encode(&frame, kind, &mut bytes).unwrap();
        assert!(decode(u32::from(id), &bytes[..len]).is_ok());
        let hex: String = bytes[..len].iter().map(|b| format!("{b:02x}")).collect();
        let json: Vec<String> = signals(&frame, kind)
            .into_iter()
            .map(|(k, v)| format!("\"{k}\": {v}"))
            .collect();
        writeln!(out, "{id:03x} {hex} {{{}}}", json.join(", ")).unwrap();
    }
    out
}

#[test]
fn example_frames_file_is_current() {
    let rendered = render_examples();
    print!("{rendered}");
    check_or_bless(repo_file("tests/data/example_frames.txt"), &rendered);
}
