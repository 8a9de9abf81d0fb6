//! Sparkplug B messages back to readable JSON, for `bearingd fleet-decode` (fed by any MQTT
//! client, e.g. `mosquitto_sub -F '%t %x'`) and for tests.
//!
//! DDATA carries metric aliases, not names; the names are those the node's births declared
//! with them. So the decoder keeps, per edge node, the aliases of its last NBIRTH and the
//! DBIRTHs since, and prints a metric it has no birth for as `#<alias>` (a subscriber started
//! after the births: a rebirth command makes the node declare them again).

use super::sparkplug::{Payload, Value};
use serde_json::{json, Map, Value as Json};
use std::collections::HashMap;

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

/// Decodes a stream of messages, remembering the aliases each node's births declare.
#[derive(Debug, Default)]
pub struct Decoder {
    /// Per `<group>/<node>`: alias → metric name.
    aliases: HashMap<String, HashMap<u64, String>>,
}

impl Decoder {
    pub fn new() -> Self {
        Decoder::default()
    }

    /// Decodes a line `TOPIC HEX` as `mosquitto_sub -F '%t %x'` prints it.
    pub fn decode_line(&mut self, line: &str) -> Result<Json, DecodeError> {
        let (topic, hex) = line
            .trim()
            .rsplit_once(' ')
            .ok_or_else(|| DecodeError::Shape(line.chars().take(80).collect()))?;
        self.decode_message(topic, &from_hex(hex)?)
    }

    /// Decodes one message: its topic and payload bytes.
    pub fn decode_message(&mut self, topic: &str, payload: &[u8]) -> Result<Json, DecodeError> {
        let mut decoded = Payload::from_bytes(payload)?;
        let parts: Vec<&str> = topic.split('/').collect();
        if let ["spBv1.0", group, kind, node, ..] = parts[..] {
            let names = self.aliases.entry(format!("{group}/{node}")).or_default();
            if kind == "NBIRTH" {
                names.clear(); // a new session, or a rebirth: its births declare anew
            }
            for m in &mut decoded.metrics {
                match (&m.name, m.alias) {
                    (Some(name), Some(alias)) if kind.ends_with("BIRTH") => {
                        names.insert(alias, name.clone());
                    }
                    (None, Some(alias)) => m.name = names.get(&alias).cloned(),
                    _ => {}
                }
            }
        }
        Ok(describe(topic, &parts, &decoded, payload.len()))
    }
}

/// The decoded message as JSON; metrics by name (`#<alias>` when the name is unknown).
fn describe(topic: &str, parts: &[&str], decoded: &Payload, bytes: usize) -> Json {
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
    out.insert("bytes".into(), json!(bytes));
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
    Json::Object(out)
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

    fn line(topic: &str, metrics: Vec<Metric>) -> String {
        let payload = Payload {
            timestamp: Some(5),
            metrics,
            seq: Some(9),
            ..Payload::default()
        };
        let hex: String = payload
            .to_bytes()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        format!("{topic} {hex}")
    }

    fn metric(name: Option<&str>, alias: u64, value: Option<&Value>) -> Metric {
        let mut m = Metric::named("", DataType::Double, 5, value);
        m.name = name.map(str::to_string);
        m.alias = Some(alias);
        m
    }

    #[test]
    fn a_mosquitto_sub_line_decodes_to_named_metrics() {
        let mut decoder = Decoder::new();
        let out = decoder
            .decode_line(&line(
                "spBv1.0/g/DDATA/n/m.radial",
                vec![
                    Metric::named(
                        "Vibration/RMS_g",
                        DataType::Double,
                        5,
                        Some(&Value::Double(0.5)),
                    ),
                    Metric::named("ISO20816/Zone", DataType::String, 5, None),
                ],
            ))
            .unwrap();
        assert_eq!(out["type"], "DDATA");
        assert_eq!(out["device"], "m.radial");
        assert_eq!(out["seq"], 9);
        assert_eq!(out["metrics"]["Vibration/RMS_g"], 0.5);
        assert_eq!(out["metrics"]["ISO20816/Zone"], Json::Null);
        assert!(decoder.decode_line("no-payload").is_err());
        assert!(decoder.decode_line("t 0g").is_err());
    }

    #[test]
    fn aliases_are_named_by_the_births_of_their_node_until_its_next_nbirth() {
        let mut decoder = Decoder::new();
        let rms = Some(&Value::Double(0.5));
        let data = |d: &mut Decoder, node: &str| {
            let topic = format!("spBv1.0/g/DDATA/{node}/m.radial");
            d.decode_line(&line(&topic, vec![metric(None, 7, rms)]))
                .unwrap()["metrics"]
                .clone()
        };
        assert_eq!(data(&mut decoder, "n")["#7"], 0.5, "no birth seen yet");
        decoder
            .decode_line(&line(
                "spBv1.0/g/NBIRTH/n",
                vec![metric(Some("bdSeq"), 0, None)],
            ))
            .unwrap();
        decoder
            .decode_line(&line(
                "spBv1.0/g/DBIRTH/n/m.radial",
                vec![metric(Some("Vibration/RMS_g"), 7, None)],
            ))
            .unwrap();
        assert_eq!(data(&mut decoder, "n")["Vibration/RMS_g"], 0.5);
        assert_eq!(
            data(&mut decoder, "other")["#7"],
            0.5,
            "another node's alias"
        );
        // A new NBIRTH forgets the aliases until its DBIRTHs declare them again.
        decoder
            .decode_line(&line(
                "spBv1.0/g/NBIRTH/n",
                vec![metric(Some("bdSeq"), 0, None)],
            ))
            .unwrap();
        assert_eq!(data(&mut decoder, "n")["#7"], 0.5);
    }
}
