//! The Sparkplug B payload, as prost structs written by hand from the specification (no
//! protoc, no build script), with the same field numbers as `proto/sparkplug_b.proto`. Only
//! what bearingd writes and reads is declared: a decoder skips the other fields, so the
//! structs read any Sparkplug B payload for the fields they know.
//!
//! The tests decode these structs' bytes with Python's protobuf package against the `.proto`
//! compiled by protoc, which keeps both in step.

use prost::Message as _;

/// `org.eclipse.tahu.protobuf.Payload`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct Payload {
    /// Milliseconds since the Unix epoch.
    #[prost(uint64, optional, tag = "1")]
    pub timestamp: Option<u64>,
    #[prost(message, repeated, tag = "2")]
    pub metrics: Vec<Metric>,
    /// 0..=255; absent in NDEATH.
    #[prost(uint64, optional, tag = "3")]
    pub seq: Option<u64>,
    #[prost(string, optional, tag = "4")]
    pub uuid: Option<String>,
    #[prost(bytes = "vec", optional, tag = "5")]
    pub body: Option<Vec<u8>>,
}

/// `Payload.Metric`, without metadata, properties, data sets and templates.
#[derive(Clone, PartialEq, prost::Message)]
pub struct Metric {
    #[prost(string, optional, tag = "1")]
    pub name: Option<String>,
    #[prost(uint64, optional, tag = "2")]
    pub alias: Option<u64>,
    /// Milliseconds since the Unix epoch.
    #[prost(uint64, optional, tag = "3")]
    pub timestamp: Option<u64>,
    /// A [`DataType`] number.
    #[prost(uint32, optional, tag = "4")]
    pub datatype: Option<u32>,
    #[prost(bool, optional, tag = "5")]
    pub is_historical: Option<bool>,
    #[prost(bool, optional, tag = "6")]
    pub is_transient: Option<bool>,
    #[prost(bool, optional, tag = "7")]
    pub is_null: Option<bool>,
    #[prost(oneof = "MetricValue", tags = "10, 11, 12, 13, 14, 15, 16")]
    pub value: Option<MetricValue>,
}

/// The scalar members of `Metric.value`.
#[derive(Clone, PartialEq, prost::Oneof)]
pub enum MetricValue {
    #[prost(uint32, tag = "10")]
    Int(u32),
    #[prost(uint64, tag = "11")]
    Long(u64),
    #[prost(float, tag = "12")]
    Float(f32),
    #[prost(double, tag = "13")]
    Double(f64),
    #[prost(bool, tag = "14")]
    Boolean(bool),
    #[prost(string, tag = "15")]
    String(String),
    #[prost(bytes = "vec", tag = "16")]
    Bytes(Vec<u8>),
}

/// The metric data types bearingd uses (Sparkplug 3.0, 6.4.16), with their numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum DataType {
    UInt64 = 8,
    Double = 10,
    Boolean = 11,
    String = 12,
}

impl DataType {
    pub fn name(self) -> &'static str {
        match self {
            DataType::UInt64 => "UInt64",
            DataType::Double => "Double",
            DataType::Boolean => "Boolean",
            DataType::String => "String",
        }
    }
}

/// A metric's value as bearingd holds it before encoding; `None` values go out as `is_null`.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    UInt64(u64),
    Double(f64),
    Boolean(bool),
    String(String),
}

impl Value {
    pub fn datatype(&self) -> DataType {
        match self {
            Value::UInt64(_) => DataType::UInt64,
            Value::Double(_) => DataType::Double,
            Value::Boolean(_) => DataType::Boolean,
            Value::String(_) => DataType::String,
        }
    }
}

impl Metric {
    /// A named metric with its type, timestamp and value (`None`: `is_null`).
    pub fn named(name: &str, datatype: DataType, timestamp_ms: u64, value: Option<&Value>) -> Self {
        Metric {
            name: Some(name.to_string()),
            alias: None,
            timestamp: Some(timestamp_ms),
            datatype: Some(datatype as u32),
            is_historical: None,
            is_transient: None,
            is_null: value.is_none().then_some(true),
            value: value.map(|v| match v {
                Value::UInt64(x) => MetricValue::Long(*x),
                Value::Double(x) => MetricValue::Double(*x),
                Value::Boolean(x) => MetricValue::Boolean(*x),
                Value::String(x) => MetricValue::String(x.clone()),
            }),
        }
    }

    /// The value as bearingd reads it (what `fleet-decode` and the rebirth command need).
    pub fn value(&self) -> Option<Value> {
        match self.value.as_ref()? {
            MetricValue::Int(x) => Some(Value::UInt64(u64::from(*x))),
            MetricValue::Long(x) => Some(Value::UInt64(*x)),
            MetricValue::Float(x) => Some(Value::Double(f64::from(*x))),
            MetricValue::Double(x) => Some(Value::Double(*x)),
            MetricValue::Boolean(x) => Some(Value::Boolean(*x)),
            MetricValue::String(x) => Some(Value::String(x.clone())),
            MetricValue::Bytes(_) => None,
        }
    }
}

impl Payload {
    pub fn to_bytes(&self) -> Vec<u8> {
        self.encode_to_vec()
    }

    /// Decodes a payload; the error names what was wrong with the bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Payload, prost::DecodeError> {
        Payload::decode(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_round_trip_with_null_and_every_type() {
        let payload = Payload {
            timestamp: Some(1_700_000_000_000),
            metrics: vec![
                Metric::named("a", DataType::UInt64, 5, Some(&Value::UInt64(7))),
                Metric::named("b", DataType::Double, 6, Some(&Value::Double(0.25))),
                Metric::named("c", DataType::Boolean, 7, Some(&Value::Boolean(true))),
                Metric::named(
                    "d",
                    DataType::String,
                    8,
                    Some(&Value::String("alarm".into())),
                ),
                Metric::named("e", DataType::Double, 9, None),
            ],
            seq: Some(3),
            uuid: None,
            body: None,
        };
        let back = Payload::from_bytes(&payload.to_bytes()).unwrap();
        assert_eq!(back, payload);
        assert_eq!(back.metrics[4].is_null, Some(true));
        assert_eq!(back.metrics[4].value(), None);
        assert_eq!(back.metrics[3].value(), Some(Value::String("alarm".into())));
    }

    #[test]
    fn field_numbers_are_those_of_the_specification() {
        // Hand-assembled bytes: Payload.seq (3) = 5, Metric (2) { name (1) = "x",
        // datatype (4) = 10, double_value (13) = 1.0 }.
        let mut bytes = vec![0x18, 0x05, 0x12, 0x0e, 0x0a, 0x01, b'x', 0x20, 0x0a, 0x69];
        bytes.extend_from_slice(&1.0f64.to_le_bytes());
        let payload = Payload::from_bytes(&bytes).unwrap();
        assert_eq!(payload.seq, Some(5));
        assert_eq!(payload.metrics[0].name.as_deref(), Some("x"));
        assert_eq!(payload.metrics[0].datatype, Some(DataType::Double as u32));
        assert_eq!(payload.metrics[0].value(), Some(Value::Double(1.0)));
    }
}
