//! The log's schemas, one per topic family, built in code so that no `protoc` and no build
//! script are needed:
//!
//! - raw samples: protobuf `bearingd.RawBlock` (schema encoding `protobuf`, schema data a
//!   serialized `google.protobuf.FileDescriptorSet`, schema name the fully qualified message
//!   name; message encoding `protobuf`). `counts` is `repeated sint32` packed: zig-zag varints
//!   keep small signed counts at one or two bytes before compression, and are exact.
//! - everything else: JSON (schema encoding `jsonschema` with a JSON Schema of the struct;
//!   message encoding `json`), since those are low rate and readable by anything.
//!
//! Floats in JSON messages: `serde_json` writes a non-finite `f64`/`f32` as `null`, so every
//! number field's schema admits `null`.

use prost::Message as _;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{
    DescriptorProto, FieldDescriptorProto, FieldOptions, FileDescriptorProto, FileDescriptorSet,
};
use serde_json::{json, Value};

use crate::messages::{ChannelId, PipelineMessage, RawBlock};

/// Schema name (fully qualified protobuf message name) of raw blocks.
pub const RAW_BLOCK_SCHEMA: &str = "bearingd.RawBlock";

/// The protobuf form of [`ChannelId`] (`bearingd.ChannelId`).
#[derive(Clone, PartialEq, prost::Message)]
pub struct ChannelIdPb {
    #[prost(string, tag = "1")]
    pub sensor: String,
    #[prost(string, tag = "2")]
    pub axis: String,
}

/// The protobuf form of [`RawBlock`] (`bearingd.RawBlock`): the same fields, `counts` as packed
/// `sint32`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct RawBlockPb {
    #[prost(message, optional, tag = "1")]
    pub channel: Option<ChannelIdPb>,
    #[prost(uint64, tag = "2")]
    pub first_sample: u64,
    #[prost(double, tag = "3")]
    pub sample_rate_hz: f64,
    #[prost(double, tag = "4")]
    pub scale_g_per_count: f64,
    #[prost(sint32, repeated, packed = "true", tag = "5")]
    pub counts: Vec<i32>,
}

impl RawBlockPb {
    /// Encodes `block` into `out` (cleared first) without an intermediate copy of the counts'
    /// vector beyond the one prost's owned struct needs.
    pub fn encode_block(block: &RawBlock, out: &mut Vec<u8>) {
        let pb = RawBlockPb {
            channel: Some(ChannelIdPb {
                sensor: block.channel.sensor.clone(),
                axis: block.channel.axis.clone(),
            }),
            first_sample: block.first_sample,
            sample_rate_hz: block.sample_rate_hz,
            scale_g_per_count: block.scale_g_per_count,
            counts: block.counts.clone(),
        };
        out.clear();
        out.reserve(pb.encoded_len());
        // Encoding into a Vec cannot run out of space.
        let _ = pb.encode(out);
    }

    /// Back to the pipeline's type; `None` if the channel is missing.
    pub fn into_block(self) -> Option<RawBlock> {
        let channel = self.channel?;
        Some(RawBlock {
            channel: ChannelId {
                sensor: channel.sensor,
                axis: channel.axis,
            },
            first_sample: self.first_sample,
            sample_rate_hz: self.sample_rate_hz,
            scale_g_per_count: self.scale_g_per_count,
            counts: self.counts,
        })
    }
}

fn field(name: &str, number: i32, ty: Type, label: Label) -> FieldDescriptorProto {
    FieldDescriptorProto {
        name: Some(name.to_string()),
        number: Some(number),
        label: Some(label as i32),
        r#type: Some(ty as i32),
        json_name: Some(name.to_string()),
        ..Default::default()
    }
}

/// The serialized `FileDescriptorSet` of `bearingd/raw_block.proto` (proto3, package
/// `bearingd`, messages `ChannelId` and `RawBlock`), matching [`RawBlockPb`] field for field.
pub fn raw_block_descriptor_set() -> Vec<u8> {
    let channel_id = DescriptorProto {
        name: Some("ChannelId".into()),
        field: vec![
            field("sensor", 1, Type::String, Label::Optional),
            field("axis", 2, Type::String, Label::Optional),
        ],
        ..Default::default()
    };
    let mut channel = field("channel", 1, Type::Message, Label::Optional);
    channel.type_name = Some(".bearingd.ChannelId".into());
    let mut counts = field("counts", 5, Type::Sint32, Label::Repeated);
    counts.options = Some(FieldOptions {
        packed: Some(true),
        ..Default::default()
    });
    let raw_block = DescriptorProto {
        name: Some("RawBlock".into()),
        field: vec![
            channel,
            field("first_sample", 2, Type::Uint64, Label::Optional),
            field("sample_rate_hz", 3, Type::Double, Label::Optional),
            field("scale_g_per_count", 4, Type::Double, Label::Optional),
            counts,
        ],
        ..Default::default()
    };
    let file = FileDescriptorProto {
        name: Some("bearingd/raw_block.proto".into()),
        package: Some("bearingd".into()),
        message_type: vec![channel_id, raw_block],
        syntax: Some("proto3".into()),
        ..Default::default()
    };
    FileDescriptorSet { file: vec![file] }.encode_to_vec()
}

/// The JSON message kinds: topic family, schema name, JSON Schema.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JsonKind {
    Spectrum,
    Indicators,
    Twin,
    Flag,
    Health,
    Ingest,
    Speed,
}

impl JsonKind {
    pub const ALL: [JsonKind; 7] = [
        JsonKind::Spectrum,
        JsonKind::Indicators,
        JsonKind::Twin,
        JsonKind::Flag,
        JsonKind::Health,
        JsonKind::Ingest,
        JsonKind::Speed,
    ];

    /// The schema name recorded in the file (also Foxglove's datatype name).
    pub fn schema_name(self) -> &'static str {
        match self {
            JsonKind::Spectrum => "bearingd.Spectrum",
            JsonKind::Indicators => "bearingd.Indicators",
            JsonKind::Twin => "bearingd.Twin",
            JsonKind::Flag => "bearingd.Flag",
            JsonKind::Health => "bearingd.Health",
            JsonKind::Ingest => "bearingd.Ingest",
            JsonKind::Speed => "bearingd.Speed",
        }
    }

    pub fn from_schema_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.schema_name() == name)
    }

    /// The JSON Schema (draft 2020-12) of the message struct.
    pub fn json_schema(self) -> Value {
        let num = || json!({"type": ["number", "null"]});
        let uint = || json!({"type": "integer", "minimum": 0});
        let string = || json!({"type": "string"});
        let band = || json!({"type": "array", "items": {"type": ["number", "null"]}, "minItems": 2, "maxItems": 2, "description": "[low, high] Hz"});
        let floats = || json!({"type": "array", "items": {"type": ["number", "null"]}});
        let channel = || {
            json!({
                "type": "object",
                "properties": {"sensor": {"type": "string"}, "axis": {"type": "string"}},
                "required": ["sensor", "axis"]
            })
        };
        let (title, props): (&str, Value) = match self {
            JsonKind::Spectrum => (
                "bearingd.Spectrum",
                json!({
                    "channel": channel(), "end_sample": uint(), "band_hz": band(),
                    "bin_hz": num(), "windows_averaged": uint(), "amplitude": floats()
                }),
            ),
            JsonKind::Indicators => (
                "bearingd.Indicators",
                json!({
                    "channel": channel(), "end_sample": uint(), "rpm": num(), "band_hz": band(),
                    "rms": num(), "peak": num(), "crest": num(), "kurtosis": num(),
                    "score_outer_race": num(), "score_inner_race": num(),
                    "score_ball": num(), "score_cage": num()
                }),
            ),
            JsonKind::Twin => (
                "bearingd.Twin",
                json!({
                    "channel": channel(), "end_sample": uint(), "hypothesis": string(),
                    "error": num(), "margin": num(), "error_outer_race": num(),
                    "error_inner_race": num(), "error_ball": num(), "a": num(),
                    "decay_per_s": num(), "f_n": num(), "f_d": num(), "jitter": num(),
                    "residual_energy_ratio": num(), "residual_peak_hz": num(),
                    "residual_bin_hz": num(), "residual": floats()
                }),
            ),
            JsonKind::Flag => (
                "bearingd.Flag",
                json!({
                    "channel": channel(), "end_sample": uint(), "fault": string(),
                    "from": string(), "to": string(), "score": num(),
                    "fault_frequency_hz": num()
                }),
            ),
            JsonKind::Health => (
                "bearingd.Health",
                json!({
                    "channel": channel(), "end_sample": uint(), "kind": string(),
                    "stage": {"type": ["string", "null"]}, "detail": string()
                }),
            ),
            JsonKind::Ingest => (
                "bearingd.Ingest",
                json!({
                    "source": string(), "frames": uint(), "samples": uint(), "gaps": uint(),
                    "missing_samples": uint(), "malformed": uint(), "restarts": uint(),
                    "dropped_blocks": uint(), "speed_frames": uint(), "sensor_lost": uint(),
                    "handoff_dropped": uint()
                }),
            ),
            JsonKind::Speed => (
                "bearingd.Speed",
                json!({
                    "channel": channel(), "end_sample": uint(), "source": string(),
                    "given_rpm": num(), "rpm": num()
                }),
            ),
        };
        let required: Vec<&String> = props
            .as_object()
            .map(|m| m.keys().collect())
            .unwrap_or_default();
        json!({
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": title,
            "type": "object",
            "properties": props,
            "required": required,
        })
    }
}

/// Serializes `message` into `payload` and its topic into `topic`; returns the JSON kind, or
/// `None` for raw (protobuf).
pub fn encode(
    message: &PipelineMessage,
    topic: &mut String,
    payload: &mut Vec<u8>,
) -> Option<JsonKind> {
    use std::fmt::Write as _;
    payload.clear();
    // Serializing these plain structs into a Vec cannot fail (no maps with non-string keys).
    let (kind, r) = match message {
        PipelineMessage::Raw(b) => {
            let _ = write!(topic, "/raw/{}/{}", b.channel.sensor, b.channel.axis);
            RawBlockPb::encode_block(b, payload);
            return None;
        }
        PipelineMessage::Spectrum(m) => {
            let _ = write!(topic, "/spectrum/{}/{}", m.channel.sensor, m.channel.axis);
            (JsonKind::Spectrum, serde_json::to_writer(&mut *payload, m))
        }
        PipelineMessage::Indicators(m) => {
            let _ = write!(topic, "/indicators/{}/{}", m.channel.sensor, m.channel.axis);
            (
                JsonKind::Indicators,
                serde_json::to_writer(&mut *payload, m),
            )
        }
        PipelineMessage::Twin(m) => {
            let _ = write!(topic, "/twin/{}/{}", m.channel.sensor, m.channel.axis);
            (JsonKind::Twin, serde_json::to_writer(&mut *payload, m))
        }
        PipelineMessage::Flag(m) => {
            let _ = write!(topic, "/flags/{}/{}", m.channel.sensor, m.channel.axis);
            (JsonKind::Flag, serde_json::to_writer(&mut *payload, m))
        }
        PipelineMessage::Health(m) => {
            let _ = write!(topic, "/health/{}/{}", m.channel.sensor, m.channel.axis);
            (JsonKind::Health, serde_json::to_writer(&mut *payload, m))
        }
        PipelineMessage::Ingest(m) => {
            let _ = write!(topic, "/ingest/{}", m.source);
            (JsonKind::Ingest, serde_json::to_writer(&mut *payload, m))
        }
        PipelineMessage::Speed(m) => {
            let _ = write!(topic, "/speed/{}/{}", m.channel.sensor, m.channel.axis);
            (JsonKind::Speed, serde_json::to_writer(&mut *payload, m))
        }
    };
    debug_assert!(r.is_ok());
    Some(kind)
}
