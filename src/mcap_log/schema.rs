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

use crate::messages::detect::RecordKind;
use crate::messages::{
    ChannelId, FlagMessage, HealthMessage, HwMessage, IndicatorsMessage, IngestMessage,
    PipelineMessage, RawBlock, SpectrumMessage, SpeedMessage, TrendMessage, TwinMessage,
    VelocityFlagMessage,
};
use schemars::generate::SchemaSettings;
use schemars::transform::transform_subschemas;
use schemars::Schema;

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

/// The JSON message kinds: topic family, schema name, JSON Schema. The bearing analysis' own
/// messages by name; every registered detector's records through [`RecordKind`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JsonKind {
    Spectrum,
    Indicators,
    Twin,
    Hw,
    Trend,
    Flag,
    Health,
    Ingest,
    Speed,
    Detector(RecordKind),
}

impl JsonKind {
    const BEARING: [JsonKind; 9] = [
        JsonKind::Spectrum,
        JsonKind::Indicators,
        JsonKind::Twin,
        JsonKind::Hw,
        JsonKind::Trend,
        JsonKind::Flag,
        JsonKind::Health,
        JsonKind::Ingest,
        JsonKind::Speed,
    ];

    /// Every JSON kind: the bearing analysis' and the detectors'.
    pub fn all() -> impl Iterator<Item = JsonKind> {
        Self::BEARING
            .into_iter()
            .chain(RecordKind::all().map(JsonKind::Detector))
    }

    /// The schema name recorded in the file (also Foxglove's datatype name).
    pub fn schema_name(self) -> &'static str {
        match self {
            JsonKind::Spectrum => "bearingd.Spectrum",
            JsonKind::Indicators => "bearingd.Indicators",
            JsonKind::Twin => "bearingd.Twin",
            JsonKind::Hw => "bearingd.Hw",
            JsonKind::Trend => "bearingd.Trend",
            JsonKind::Flag => "bearingd.Flag",
            JsonKind::Health => "bearingd.Health",
            JsonKind::Ingest => "bearingd.Ingest",
            JsonKind::Speed => "bearingd.Speed",
            JsonKind::Detector(kind) => kind.info().schema,
        }
    }

    pub fn from_schema_name(name: &str) -> Option<Self> {
        Self::all().find(|k| k.schema_name() == name)
    }

    /// The JSON Schema (draft 2020-12) of the message struct as serde writes it, generated by
    /// schemars from the struct itself (its doc comments become descriptions), inlined (no
    /// `$ref`) and titled with the schema name.
    pub fn json_schema(self) -> Value {
        let generator = SchemaSettings::draft2020_12()
            .for_serialize()
            .with(|s| s.inline_subschemas = true)
            .with_transform(nullable_numbers)
            .into_generator();
        let mut schema = match self {
            JsonKind::Spectrum => generator.into_root_schema_for::<SpectrumMessage>(),
            JsonKind::Indicators => generator.into_root_schema_for::<IndicatorsMessage>(),
            JsonKind::Twin => generator.into_root_schema_for::<TwinMessage>(),
            JsonKind::Hw => generator.into_root_schema_for::<HwMessage>(),
            JsonKind::Trend => generator.into_root_schema_for::<TrendMessage>(),
            JsonKind::Flag => generator.into_root_schema_for::<FlagMessage>(),
            JsonKind::Health => generator.into_root_schema_for::<HealthMessage>(),
            JsonKind::Ingest => generator.into_root_schema_for::<IngestMessage>(),
            JsonKind::Speed => generator.into_root_schema_for::<SpeedMessage>(),
            JsonKind::Detector(kind) => (kind.info().json_schema)(generator),
        };
        schema.insert("title".into(), self.schema_name().into());
        let mut value = schema.to_value();
        if self.can_be_late() {
            if let Some(properties) = value.get_mut("properties").and_then(Value::as_object_mut) {
                properties.insert(
                    "late".into(),
                    json!({"type": "boolean", "description": LATE_DESCRIPTION}),
                );
            }
        }
        value
    }

    /// The kinds held back while the log is paused and written late ([`encode_late`]).
    pub fn can_be_late(self) -> bool {
        match self {
            JsonKind::Flag | JsonKind::Health => true,
            JsonKind::Detector(kind) => kind.can_be_late(),
            _ => false,
        }
    }
}

const LATE_DESCRIPTION: &str = "Present (true) only when the message was decided while the log \
    was paused (a full disk) and written when it resumed: publish_time is when it was decided, \
    log_time the resume";

/// The topic of the daemon's notes about its own logs (retention, a pause for a full disk).
pub const LOG_TOPIC: &str = "/log";
/// Foxglove's well-known log message, so that Foxglove's Log panel shows the notes.
pub const LOG_SCHEMA: &str = "foxglove.Log";

/// Severity of a `/log` note, with `foxglove.Log`'s numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogLevel {
    Info = 2,
    Warning = 3,
    Error = 4,
}

/// The JSON Schema of a `foxglove.Log` message (the subset we write: every field).
pub fn log_json_schema() -> Value {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": LOG_SCHEMA,
        "description": "A note of the daemon about its logs (Foxglove's foxglove.Log)",
        "type": "object",
        "properties": {
            "timestamp": {
                "type": "object",
                "properties": {
                    "sec": {"type": "integer", "minimum": 0},
                    "nsec": {"type": "integer", "minimum": 0}
                },
                "required": ["sec", "nsec"]
            },
            "level": {
                "type": "integer",
                "description": "0 unknown, 1 debug, 2 info, 3 warning, 4 error, 5 fatal"
            },
            "message": {"type": "string"},
            "name": {"type": "string"},
            "file": {"type": "string"},
            "line": {"type": "integer", "minimum": 0}
        },
        "required": ["timestamp", "level", "message", "name", "file", "line"]
    })
}

/// One `foxglove.Log` message, serialized: `text` at `time_ns`, named `bearingd`.
pub fn log_note(level: LogLevel, text: &str, time_ns: u64) -> Vec<u8> {
    json!({
        "timestamp": {"sec": time_ns / 1_000_000_000, "nsec": time_ns % 1_000_000_000},
        "level": level as u8,
        "message": text,
        "name": "bearingd",
        "file": "",
        "line": 0
    })
    .to_string()
    .into_bytes()
}

/// The topic of the state snapshot that begins every file opened by rotation.
pub const STATE_TOPIC: &str = "/state";
/// Schema name of [`StateSnapshot`].
pub const STATE_SCHEMA: &str = "bearingd.State";

/// What the daemon holds as current when a file is opened by rotation: per channel, the last
/// flag change of each fault, the last health message of each kind and the last twin fit. It
/// is the first message of that file (log time: the file's start), so that the file can be
/// read alone; its messages are copies (their `end_sample` says when each was decided), kept
/// on their own topic so that nothing counting transitions counts them twice.
#[derive(
    Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct StateSnapshot {
    pub flags: Vec<FlagMessage>,
    pub health: Vec<HealthMessage>,
    pub twin: Vec<TwinMessage>,
    /// The last change of each channel's ISO velocity zone flag.
    pub velocity_flags: Vec<VelocityFlagMessage>,
}

impl StateSnapshot {
    /// The JSON Schema of the snapshot, generated like the other JSON kinds'.
    pub fn json_schema() -> Value {
        let generator = SchemaSettings::draft2020_12()
            .for_serialize()
            .with(|s| s.inline_subschemas = true)
            .with_transform(nullable_numbers)
            .into_generator();
        let mut schema = generator.into_root_schema_for::<StateSnapshot>();
        schema.insert("title".into(), STATE_SCHEMA.into());
        schema.to_value()
    }
}

/// `serde_json` writes a non-finite float as `null`: every `number` also admits `null`.
fn nullable_numbers(schema: &mut Schema) {
    if schema.get("type") == Some(&Value::from("number")) {
        schema.insert("type".into(), json!(["number", "null"]));
    }
    transform_subschemas(&mut nullable_numbers, schema);
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
        PipelineMessage::Hw(m) => {
            let _ = write!(topic, "/hw/{}/{}", m.channel.sensor, m.channel.axis);
            (JsonKind::Hw, serde_json::to_writer(&mut *payload, m))
        }
        PipelineMessage::Trend(m) => {
            let _ = write!(topic, "/trend/{}/{}", m.channel.sensor, m.channel.axis);
            (JsonKind::Trend, serde_json::to_writer(&mut *payload, m))
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
        PipelineMessage::Detector(m) => {
            let (kind, record) = m.record();
            let channel = record.channel();
            let _ = write!(
                topic,
                "/{}/{}/{}",
                kind.info().topic,
                channel.sensor,
                channel.axis
            );
            (JsonKind::Detector(kind), record.write_json(payload))
        }
    };
    debug_assert!(r.is_ok());
    Some(kind)
}

/// [`encode`] for a message written late, after a pause of the log: flag changes and health
/// events ([`JsonKind::can_be_late`]) carry `"late": true` after their own fields; other kinds
/// are encoded as by [`encode`].
pub fn encode_late(
    message: &PipelineMessage,
    topic: &mut String,
    payload: &mut Vec<u8>,
) -> Option<JsonKind> {
    let kind = encode(message, topic, payload);
    if kind.is_some_and(JsonKind::can_be_late) && payload.last() == Some(&b'}') {
        // Every JSON message is a non-empty object: the field goes before its closing brace.
        payload.pop();
        payload.extend_from_slice(br#","late":true}"#);
    }
    kind
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{FaultKind, FlagLevel, HealthKind, HealthStage, SpeedSource};

    fn channel() -> ChannelId {
        ChannelId {
            sensor: "motor-de".into(),
            axis: "radial".into(),
        }
    }

    /// One message of every JSON kind, with a non-finite float where the kind has one.
    fn samples() -> Vec<PipelineMessage> {
        vec![
            PipelineMessage::Spectrum(SpectrumMessage::new(
                channel(),
                1,
                [500.0, 2500.0],
                0.5,
                3,
                vec![1.0, f32::NAN],
            )),
            PipelineMessage::Indicators(IndicatorsMessage {
                channel: channel(),
                end_sample: 1,
                rpm: f64::NAN,
                band_hz: [500.0, 2500.0],
                rms: 1.0,
                peak: 2.0,
                crest: 2.0,
                kurtosis: 3.0,
                score_outer_race: 0.0,
                score_inner_race: 0.0,
                score_ball: 0.0,
                score_cage: 0.0,
            }),
            PipelineMessage::Twin(TwinMessage {
                channel: channel(),
                end_sample: 1,
                hypothesis: FaultKind::OuterRace,
                error: 0.1,
                margin: f64::INFINITY,
                error_outer_race: 0.1,
                error_inner_race: 0.2,
                error_ball: 0.3,
                a: 1.0,
                decay_per_s: 800.0,
                f_n: 3000.0,
                f_d: 107.0,
                jitter: 0.01,
                residual_energy_ratio: 0.1,
                residual_peak_hz: 50.0,
                residual_bin_hz: 0.5,
                residual: vec![0.0],
                learned: Some(crate::messages::LearnedOpinionMessage {
                    segments: 2,
                    probabilities: vec![
                        crate::messages::ClassProbability {
                            fault: Some(FaultKind::OuterRace),
                            probability: 0.9,
                        },
                        crate::messages::ClassProbability {
                            fault: None,
                            probability: 0.1,
                        },
                    ],
                    confirms: None,
                    agrees: true,
                    problem: None,
                }),
            }),
            PipelineMessage::Hw(HwMessage {
                channel: channel(),
                end_sample: 25_600,
                first_sample: 23_040,
                fs_hz: 25_600.0,
                order: 0,
                states: "raw_once".into(),
                problem: None,
                warm_start: true,
                iterations: 7,
                accuracy_simulation: 93.5,
                accuracy_one_step: f64::NAN,
                numerators: vec![vec![0.1], vec![0.2], vec![0.3]],
                denominators: vec![vec![-0.9, 0.1, 0.0]; 3],
                pole_radius: vec![0.9; 3],
                output_polynomial: vec![0.0, 1.0, 0.01, -0.001],
                output_mean: 0.0,
                output_scale: 0.2,
                residual_simulation: vec![0.5, -0.25],
                residual_one_step: vec![0.125, f32::NAN],
                baseline_fits: 10,
                residual_drift_sigma: Some(1.5),
                parameter_drift: None,
            }),
            PipelineMessage::Trend(TrendMessage {
                channel: channel(),
                end_sample: 1_536_000,
                stage: HealthStage::Degrading,
                rms: 0.25,
                points: 12,
                threshold: Some(0.4),
                rate_per_s: Some(1e-4),
                doubling_s: Some(6931.5),
                time_to_threshold_s: Some(4700.0),
                earliest_s: Some(1200.0),
                latest_s: None,
                confidence: 0.9,
            }),
            PipelineMessage::Flag(FlagMessage {
                channel: channel(),
                end_sample: 1,
                fault: FaultKind::InnerRace,
                from: FlagLevel::Ok,
                to: FlagLevel::Alarm,
                score: 9.0,
                fault_frequency_hz: 162.2,
                runner_up_score: Some(1.4),
            }),
            PipelineMessage::Health(HealthMessage {
                channel: channel(),
                end_sample: 1,
                kind: HealthKind::Stage,
                stage: Some(HealthStage::Healthy),
                detail: String::new(),
            }),
            PipelineMessage::Health(HealthMessage {
                channel: channel(),
                end_sample: 1,
                kind: HealthKind::Stage,
                stage: None,
                detail: String::new(),
            }),
            PipelineMessage::Ingest(IngestMessage {
                source: "can-vcan0".into(),
                frames: 1,
                samples: 2,
                gaps: 0,
                missing_samples: 0,
                malformed: 0,
                restarts: 0,
                dropped_blocks: 0,
                speed_frames: 0,
                sensor_lost: 0,
                handoff_dropped: 0,
            }),
            PipelineMessage::Speed(SpeedMessage {
                channel: channel(),
                end_sample: 1,
                source: SpeedSource::Can,
                given_rpm: None,
                rpm: Some(1797.0),
            }),
            crate::messages::VelocityMessage {
                channel: channel(),
                end_sample: 32_768,
                rms_mm_s: 3.7,
                zone: crate::messages::IsoZone::C,
                band_hz: [10.0, 1000.0],
                windows_averaged: 8,
                flag: FlagLevel::Watch,
            }
            .into(),
            VelocityFlagMessage {
                channel: channel(),
                end_sample: 65_536,
                from: FlagLevel::Ok,
                to: FlagLevel::Watch,
                rms_mm_s: 3.7,
                zone: crate::messages::IsoZone::C,
                watch_mm_s: 2.8,
                alarm_mm_s: 4.5,
            }
            .into(),
        ]
    }

    /// A small check of `value` against the parts of JSON Schema the generated schemas use
    /// (type, properties, required, items, enum, minItems/maxItems, minimum): enough to catch a
    /// schema that does not describe what serde writes.
    fn check(schema: &Value, value: &Value, at: &str) -> Result<(), String> {
        let Some(schema) = schema.as_object() else {
            return Ok(());
        };
        if let Some(types) = schema.get("type") {
            let allowed: Vec<&str> = match types {
                Value::String(t) => vec![t.as_str()],
                Value::Array(ts) => ts.iter().filter_map(Value::as_str).collect(),
                _ => vec![],
            };
            let actual = match value {
                Value::Null => "null",
                Value::Bool(_) => "boolean",
                Value::Number(n) if n.is_u64() || n.is_i64() => "integer",
                Value::Number(_) => "number",
                Value::String(_) => "string",
                Value::Array(_) => "array",
                Value::Object(_) => "object",
            };
            let fits =
                allowed.contains(&actual) || (actual == "integer" && allowed.contains(&"number"));
            if !fits {
                return Err(format!("{at}: {value} is not {allowed:?}"));
            }
        }
        if schema.get("const").is_some_and(|c| c != value) {
            return Err(format!("{at}: {value} is not {:?}", schema.get("const")));
        }
        if let Some(options) = schema.get("enum").and_then(Value::as_array) {
            if !options.contains(value) {
                return Err(format!("{at}: {value} not in {options:?}"));
            }
        }
        if let (Some(min), Some(n)) = (
            schema.get("minimum").and_then(Value::as_f64),
            value.as_f64(),
        ) {
            if n < min {
                return Err(format!("{at}: {n} < {min}"));
            }
        }
        for option in ["anyOf", "oneOf"] {
            if let Some(options) = schema.get(option).and_then(Value::as_array) {
                if !options.iter().any(|o| check(o, value, at).is_ok()) {
                    return Err(format!("{at}: {value} fits none of {option}"));
                }
            }
        }
        if let Value::Object(fields) = value {
            let properties = schema.get("properties").and_then(Value::as_object);
            for (key, field) in fields {
                let Some(sub) = properties.and_then(|p| p.get(key)) else {
                    return Err(format!("{at}: `{key}` is not in the schema"));
                };
                check(sub, field, &format!("{at}.{key}"))?;
            }
            for key in schema
                .get("required")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                let key = key.as_str().unwrap_or_default();
                if !fields.contains_key(key) {
                    return Err(format!("{at}: required `{key}` missing"));
                }
            }
        }
        if let Value::Array(items) = value {
            let len = items.len() as u64;
            if schema
                .get("minItems")
                .and_then(Value::as_u64)
                .is_some_and(|m| len < m)
                || schema
                    .get("maxItems")
                    .and_then(Value::as_u64)
                    .is_some_and(|m| len > m)
            {
                return Err(format!("{at}: {len} items"));
            }
            if let Some(item_schema) = schema.get("items") {
                for (i, item) in items.iter().enumerate() {
                    check(item_schema, item, &format!("{at}[{i}]"))?;
                }
            }
        }
        Ok(())
    }

    #[test]
    fn every_message_as_written_fits_its_schema() {
        for message in samples() {
            let mut topic = String::new();
            let mut payload = Vec::new();
            let kind = encode(&message, &mut topic, &mut payload).expect("a JSON kind");
            let value: Value = serde_json::from_slice(&payload).expect("JSON");
            let schema = kind.json_schema();
            assert_eq!(schema["title"], kind.schema_name());
            assert_eq!(
                schema["$schema"],
                "https://json-schema.org/draft/2020-12/schema"
            );
            assert!(!schema.to_string().contains("$ref"), "inlined: {schema}");
            check(&schema, &value, kind.schema_name()).unwrap_or_else(|e| panic!("{e}\n{schema}"));
        }
    }

    #[test]
    fn a_message_written_late_says_so_fits_its_schema_and_reads_back_the_same() {
        let mut marked = 0;
        for message in samples() {
            let (mut topic, mut payload) = (String::new(), Vec::new());
            let kind = encode_late(&message, &mut topic, &mut payload).expect("a JSON kind");
            let value: Value = serde_json::from_slice(&payload).expect("JSON");
            check(&kind.json_schema(), &value, kind.schema_name())
                .unwrap_or_else(|e| panic!("{e}"));
            let (mut on_time_topic, mut on_time) = (String::new(), Vec::new());
            encode(&message, &mut on_time_topic, &mut on_time);
            assert_eq!(topic, on_time_topic);
            if !kind.can_be_late() {
                assert_eq!(
                    payload, on_time,
                    "{topic}: only flags and health are marked"
                );
                continue;
            }
            marked += 1;
            assert_eq!(value["late"], Value::Bool(true), "{topic}");
            // Readers that do not know the field decode the same message.
            let read_back = match (&message, kind) {
                (PipelineMessage::Flag(_), _) => {
                    PipelineMessage::Flag(serde_json::from_slice(&payload).expect("a flag"))
                }
                (PipelineMessage::Health(_), _) => {
                    PipelineMessage::Health(serde_json::from_slice(&payload).expect("health"))
                }
                (_, JsonKind::Detector(record)) => PipelineMessage::Detector(
                    (record.info().decode)(&payload).expect("a detector's flag"),
                ),
                _ => panic!("{topic}: not a kind that can be late"),
            };
            assert_eq!(read_back, message);
        }
        assert_eq!(
            marked, 4,
            "the samples: a flag, two health events, a velocity flag"
        );
    }

    #[test]
    fn a_wrong_message_does_not_fit() {
        let schema = JsonKind::Flag.json_schema();
        let wrong = json!({"channel": {"sensor": "s", "axis": "a"}, "end_sample": 1,
            "fault": "banana", "from": "ok", "to": "alarm", "score": 1.0,
            "fault_frequency_hz": null});
        assert!(check(&schema, &wrong, "flag").is_err());
        let missing = json!({"source": "can-vcan0"});
        assert!(check(&JsonKind::Ingest.json_schema(), &missing, "ingest").is_err());
    }
}
