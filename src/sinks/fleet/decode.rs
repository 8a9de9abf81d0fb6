//! Sparkplug B messages back to readable JSON, for `bearingd fleet-decode` (fed by any MQTT
//! client, e.g. `mosquitto_sub -F '%t %x'`) and for tests.

use super::sparkplug::{Payload, Value};
use serde_json::{json, Map, Value as Json};

/// Why a line could not be decoded.
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    #[error("expected `TOPIC HEX-PAYLOAD` (mosquitto_sub -F '%t %x'), found {0:?}")]
    Shape(String),
    #[error("the payload is not hexadecimal: {0}")]
    Hex(String),
    #[error("the payload is not a Sparkplug B payload: {0}")]
    Protobuf(#[from] prost::DecodeError),
}

/// Decodes one message: its topic and payload bytes.
pub fn decode_message(topic: &str, payload: &[u8]) -> Result<Json, DecodeError> {
    let decoded = Payload::from_bytes(payload)?;
    let parts: Vec<&str> = topic.split('/').collect();
    let mut out = Map::new();
    out.insert("topic".into(), json!(topic));
    if parts.len() >= 4 && parts[0] == "spBv1.0" {
        out.insert("group".into(), json!(parts[1]));
        out.insert("type".into(), json!(parts[2]));
        out.insert("node".into(), json!(parts[3]));
        if let Some(device) = parts.get(4) {
            out.insert("device".into(), json!(device));
        }
    }
    out.insert("seq".into(), json!(decoded.seq));
    out.insert("timestamp".into(), json!(decoded.timestamp));
    out.insert("bytes".into(), json!(payload.len()));
    let mut metrics = Map::new();
    for m in &decoded.metrics {
        let name = m
            .name
            .clone()
            .or_else(|| m.alias.map(|a| format!("#{a}")))
            .unwrap_or_default();
        let value = match m.value() {
            Some(Value::UInt64(x)) => json!(x),
            Some(Value::Double(x)) => json!(x),
            Some(Value::Boolean(x)) => json!(x),
            Some(Value::String(x)) => json!(x),
            None => Json::Null,
        };
        let entry = if m.is_historical == Some(true) {
            json!({"value": value, "historical": true, "timestamp": m.timestamp})
        } else {
            value
        };
        metrics.insert(name, entry);
    }
    out.insert("metrics".into(), Json::Object(metrics));
    Ok(Json::Object(out))
}

/// Decodes a line `TOPIC HEX` as `mosquitto_sub -F '%t %x'` prints it.
pub fn decode_line(line: &str) -> Result<Json, DecodeError> {
    let (topic, hex) = line
        .trim()
        .rsplit_once(' ')
        .ok_or_else(|| DecodeError::Shape(line.chars().take(80).collect()))?;
    decode_message(topic, &from_hex(hex)?)
}

fn from_hex(hex: &str) -> Result<Vec<u8>, DecodeError> {
    if !hex.len().is_multiple_of(2) {
        return Err(DecodeError::Hex(format!("odd length {}", hex.len())));
    }
    (0..hex.len())
        .step_by(2)
        .map(|i| {
            u8::from_str_radix(hex.get(i..i + 2).unwrap_or(""), 16)
                .map_err(|e| DecodeError::Hex(format!("at {i}: {e}")))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sinks::fleet::sparkplug::{DataType, Metric};

    #[test]
    fn a_mosquitto_sub_line_decodes_to_named_metrics() {
        let payload = Payload {
            timestamp: Some(5),
            metrics: vec![
                Metric::named(
                    "Vibration/RMS_g",
                    DataType::Double,
                    5,
                    Some(&Value::Double(0.5)),
                ),
                Metric::named("ISO20816/Zone", DataType::String, 5, None),
            ],
            seq: Some(9),
            ..Payload::default()
        };
        let hex: String = payload
            .to_bytes()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        let out = decode_line(&format!("spBv1.0/g/DDATA/n/m.radial {hex}")).unwrap();
        assert_eq!(out["type"], "DDATA");
        assert_eq!(out["device"], "m.radial");
        assert_eq!(out["seq"], 9);
        assert_eq!(out["metrics"]["Vibration/RMS_g"], 0.5);
        assert_eq!(out["metrics"]["ISO20816/Zone"], Json::Null);
        assert!(decode_line("no-payload").is_err());
        assert!(decode_line("t 0g").is_err());
    }
}
