//! The Sparkplug B edge node, sans-IO: topics, the birth and death certificates, `bdSeq` and
//! `seq`, device births and deaths, and the rebirth command. It says *what* to publish; the
//! bridge publishes it.
//!
//! Sparkplug 3.0 rules kept here:
//! - topics `spBv1.0/<group>/<type>/<node>[/<device>]`;
//! - the NDEATH is registered as the MQTT Will at CONNECT and carries the session's `bdSeq`;
//!   the NBIRTH that follows carries the same `bdSeq`, `seq` 0 and the `Node Control/Rebirth`
//!   metric; every later message of the session has the next `seq` (255 wraps to 0);
//! - a device is born (DBIRTH, every metric) before its first DDATA, and dies (DDEATH) when
//!   its sensor is lost; an NCMD with `Node Control/Rebirth = true` repeats the births;
//! - every metric of a birth carries its name and an alias unique within the node, and DDATA
//!   carries the alias alone (6.4.4): a typical DDATA is 42 % smaller (docs/FLEET.md).
//!
//! The aliases are a function of the births' order, not state: the NBIRTH's metrics are 0, 1,
//! …, then each device in the book's order takes one alias per catalog metric and one for
//! `bearingd/Record`. So every rebirth and every session declares the same aliases, a lone
//! DBIRTH (a device born again after its sensor came back) needs nothing remembered, and the
//! queue keeps names, which stay valid when the configured channels change across a restart.
//!
//! Where bearingd departs from the letter of the specification, on purpose (docs/FLEET.md):
//! DDATA goes at QoS 1 (the specification asks QoS 0), because the broker's PUBACK is the only
//! evidence that a record arrived, and store-and-forward rests on it. Records sent after a
//! reconnect that were made before it carry `is_historical` on every metric, and each DDATA
//! carries its queue record number (`bearingd/Record`) so that a resend is recognisable.

use super::metrics::{MetricBook, Record};
use super::sparkplug::{DataType, Metric, Payload, Value};

pub const NAMESPACE: &str = "spBv1.0";
/// The metric a host sets to ask for a rebirth.
pub const REBIRTH: &str = "Node Control/Rebirth";
/// The metric carrying the queue record number in every DDATA.
pub const RECORD: &str = "bearingd/Record";
/// The alias of [`REBIRTH`] (the NBIRTH's second metric, after `bdSeq`).
pub const REBIRTH_ALIAS: u64 = 1;

/// MQTT quality of service of a message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Qos {
    AtMostOnce,
    AtLeastOnce,
}

/// One message to publish.
#[derive(Debug, Clone, PartialEq)]
pub struct Publish {
    pub topic: String,
    pub payload: Vec<u8>,
    pub qos: Qos,
    /// The queue record it carries (DDATA); acknowledged when the broker acknowledges this.
    pub record: Option<u64>,
}

/// Sparkplug message types bearingd sends or reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    NBirth,
    NDeath,
    NData,
    NCmd,
    DBirth,
    DDeath,
    DData,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::NBirth => "NBIRTH",
            Kind::NDeath => "NDEATH",
            Kind::NData => "NDATA",
            Kind::NCmd => "NCMD",
            Kind::DBirth => "DBIRTH",
            Kind::DDeath => "DDEATH",
            Kind::DData => "DDATA",
        }
    }
}

/// A command from a host application.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    Rebirth,
}

/// The edge node's session state.
pub struct EdgeNode {
    group: String,
    node: String,
    bd_seq: u64,
    next_seq: u64,
    /// Per device (the book's order): born in this session and not dead since.
    born: Vec<bool>,
    /// Node metrics beyond the required ones, for the NBIRTH (name, value).
    properties: Vec<(String, Value)>,
    /// Queued metrics left out of their DDATA because no birth declares them (records of
    /// another bearingd version): counted, for the stop summary.
    left_out_metrics: u64,
}

impl EdgeNode {
    /// `bd_seq` is the birth/death sequence of the session about to connect.
    pub fn new(group: &str, node: &str, devices: usize, bd_seq: u64) -> Self {
        EdgeNode {
            group: group.to_string(),
            node: node.to_string(),
            bd_seq: bd_seq % 256,
            next_seq: 0,
            born: vec![false; devices],
            properties: Vec::new(),
            left_out_metrics: 0,
        }
    }

    /// Node metrics sent in every NBIRTH (e.g. the bearingd version). Set before the first
    /// births: the devices' aliases follow the NBIRTH's.
    pub fn set_properties(&mut self, properties: Vec<(String, Value)>) {
        self.properties = properties;
    }

    pub fn bd_seq(&self) -> u64 {
        self.bd_seq
    }

    pub fn topic(&self, kind: Kind, device: Option<&str>) -> String {
        match device {
            Some(d) => format!(
                "{NAMESPACE}/{}/{}/{}/{d}",
                self.group,
                kind.name(),
                self.node
            ),
            None => format!("{NAMESPACE}/{}/{}/{}", self.group, kind.name(), self.node),
        }
    }

    /// The NCMD topic to subscribe to.
    pub fn command_topic(&self) -> String {
        self.topic(Kind::NCmd, None)
    }

    /// Starts a new session: the next `bdSeq` (after the previous session's CONNECT was
    /// accepted), every device unborn.
    pub fn next_session(&mut self) {
        self.bd_seq = (self.bd_seq + 1) % 256;
        self.born.iter_mut().for_each(|b| *b = false);
        self.next_seq = 0;
    }

    /// The NDEATH, to register as the Will before connecting and to publish on a clean stop.
    pub fn death(&self, now_ms: u64) -> Publish {
        let payload = Payload {
            timestamp: Some(now_ms),
            metrics: vec![Metric::named(
                "bdSeq",
                DataType::UInt64,
                now_ms,
                Some(&Value::UInt64(self.bd_seq)),
            )],
            ..Payload::default()
        };
        Publish {
            topic: self.topic(Kind::NDeath, None),
            payload: payload.to_bytes(),
            qos: Qos::AtLeastOnce,
            record: None,
        }
    }

    /// The alias of a device's metric: `index` in the book's catalog, and
    /// `book.metric_count()` for `bearingd/Record`. Devices follow the NBIRTH's metrics.
    fn device_alias(&self, book: &MetricBook, device: usize, index: usize) -> u64 {
        let nbirth_metrics = 2 + self.properties.len() as u64;
        let per_device = book.metric_count() as u64 + 1;
        nbirth_metrics + device as u64 * per_device + index as u64
    }

    fn seq(&mut self) -> u64 {
        let seq = self.next_seq;
        self.next_seq = (self.next_seq + 1) % 256;
        seq
    }

    /// The NBIRTH and a DBIRTH per device (at the session's start, and on a rebirth command);
    /// then a DDEATH for each device whose sensor is lost.
    pub fn births(&mut self, book: &MetricBook, now_ms: u64) -> Vec<Publish> {
        self.next_seq = 0;
        let mut metrics = vec![
            Metric::named(
                "bdSeq",
                DataType::UInt64,
                now_ms,
                Some(&Value::UInt64(self.bd_seq)),
            ),
            Metric::named(
                REBIRTH,
                DataType::Boolean,
                now_ms,
                Some(&Value::Boolean(false)),
            ),
        ];
        for (name, value) in &self.properties {
            metrics.push(Metric::named(name, value.datatype(), now_ms, Some(value)));
        }
        for (alias, m) in (0u64..).zip(&mut metrics) {
            m.alias = Some(alias);
        }
        let seq = self.seq();
        let mut out = vec![Publish {
            topic: self.topic(Kind::NBirth, None),
            payload: Payload {
                timestamp: Some(now_ms),
                metrics,
                seq: Some(seq),
                ..Payload::default()
            }
            .to_bytes(),
            qos: Qos::AtMostOnce,
            record: None,
        }];
        for device in 0..self.born.len() {
            out.push(self.device_birth(book, device, now_ms));
            if book.is_lost(device) {
                out.push(self.device_death(book, device, now_ms));
            }
        }
        out
    }

    fn device_birth(&mut self, book: &MetricBook, device: usize, now_ms: u64) -> Publish {
        let id = book
            .device_ids()
            .nth(device)
            .unwrap_or_default()
            .to_string();
        self.born[device] = true;
        let seq = self.seq();
        Publish {
            topic: self.topic(Kind::DBirth, Some(&id)),
            payload: Payload {
                timestamp: Some(now_ms),
                metrics: {
                    // Every metric a DDATA may carry is declared at birth, the record number too.
                    let mut metrics = book.birth_metrics(device, now_ms);
                    metrics.push(Metric::named(RECORD, DataType::UInt64, now_ms, None));
                    for (index, m) in metrics.iter_mut().enumerate() {
                        m.alias = Some(self.device_alias(book, device, index));
                    }
                    metrics
                },
                seq: Some(seq),
                ..Payload::default()
            }
            .to_bytes(),
            qos: Qos::AtMostOnce,
            record: None,
        }
    }

    fn device_death(&mut self, book: &MetricBook, device: usize, now_ms: u64) -> Publish {
        let id = book
            .device_ids()
            .nth(device)
            .unwrap_or_default()
            .to_string();
        self.born[device] = false;
        let seq = self.seq();
        Publish {
            topic: self.topic(Kind::DDeath, Some(&id)),
            payload: Payload {
                timestamp: Some(now_ms),
                metrics: Vec::new(),
                seq: Some(seq),
                ..Payload::default()
            }
            .to_bytes(),
            qos: Qos::AtMostOnce,
            record: None,
        }
    }

    /// The DDATA of a queued record (`number`), preceded by a DBIRTH if its device is not
    /// born, and followed by a DDEATH if the record says its sensor is lost. `historical`:
    /// the record was made before this session began. `None` for a record of a device the
    /// book does not know (the config changed across a restart). The DDATA's metrics carry
    /// their aliases instead of their names; a metric the catalog no longer has (a record
    /// queued by another bearingd version) is left out, since no birth declares it.
    pub fn data(
        &mut self,
        book: &MetricBook,
        record: &Record,
        number: u64,
        historical: bool,
        now_ms: u64,
    ) -> Option<Vec<Publish>> {
        let device = book.device_index(&record.device)?;
        let mut out = Vec::new();
        if !self.born[device] {
            out.push(self.device_birth(book, device, now_ms));
        }
        let mut payload = record.payload.clone();
        let lost = payload.metrics.iter().any(|m| {
            m.name.as_deref() == Some("Sensor/Lost") && m.value() == Some(Value::Boolean(true))
        });
        let queued = payload.metrics.len();
        payload.metrics.retain_mut(|m| {
            let index = m.name.as_deref().and_then(|name| book.metric_index(name));
            m.alias = index.map(|i| self.device_alias(book, device, i));
            m.name = None;
            m.is_historical = historical.then_some(true);
            index.is_some()
        });
        self.left_out_metrics += (queued - payload.metrics.len()) as u64;
        let mut numbered = Metric::named(
            RECORD,
            DataType::UInt64,
            payload.timestamp.unwrap_or(now_ms),
            Some(&Value::UInt64(number)),
        );
        numbered.name = None;
        numbered.alias = Some(self.device_alias(book, device, book.metric_count()));
        payload.metrics.push(numbered);
        payload.seq = Some(self.seq());
        out.push(Publish {
            topic: self.topic(Kind::DData, Some(&record.device)),
            payload: payload.to_bytes(),
            qos: Qos::AtLeastOnce,
            record: Some(number),
        });
        if lost {
            out.push(self.device_death(book, device, now_ms));
        }
        Some(out)
    }

    /// DDEATHs of the born devices, then the NDEATH: a clean stop.
    pub fn stop(&mut self, book: &MetricBook, now_ms: u64) -> Vec<Publish> {
        let mut out: Vec<Publish> = (0..self.born.len())
            .filter(|d| self.born[*d])
            .collect::<Vec<_>>()
            .into_iter()
            .map(|d| self.device_death(book, d, now_ms))
            .collect();
        out.push(self.death(now_ms));
        out
    }

    /// Queued metrics left out of their DDATA so far, since no birth declares them.
    pub fn left_out_metrics(&self) -> u64 {
        self.left_out_metrics
    }

    /// Reads an NCMD payload; the rebirth metric may be named or go by its alias.
    pub fn command(&self, payload: &[u8]) -> Option<Command> {
        let payload = Payload::from_bytes(payload).ok()?;
        payload
            .metrics
            .iter()
            .any(|m| {
                let rebirth = match m.name.as_deref() {
                    Some(name) => name == REBIRTH,
                    None => m.alias == Some(REBIRTH_ALIAS),
                };
                rebirth && m.value() == Some(Value::Boolean(true))
            })
            .then_some(Command::Rebirth)
    }
}

/// Encodes a record for the disk queue: the device id's length (u16 LE), the id, then the
/// payload without a seq.
pub fn encode_record(record: &Record) -> Vec<u8> {
    let id = record.device.as_bytes();
    let mut out = Vec::with_capacity(2 + id.len() + 512);
    out.extend_from_slice(&(id.len() as u16).to_le_bytes());
    out.extend_from_slice(id);
    out.extend_from_slice(&record.payload.to_bytes());
    out
}

/// The inverse of [`encode_record`]; `None` for bytes that are not a record.
pub fn decode_record(bytes: &[u8]) -> Option<Record> {
    let len = u16::from_le_bytes(bytes.get(0..2)?.try_into().ok()?) as usize;
    let device = std::str::from_utf8(bytes.get(2..2 + len)?)
        .ok()?
        .to_string();
    let payload = Payload::from_bytes(bytes.get(2 + len..)?).ok()?;
    Some(Record { device, payload })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sinks::fleet::metrics::{Observation, Observed};

    fn book() -> MetricBook {
        MetricBook::new(vec!["m.radial".into(), "m.axial".into()], 1000)
    }

    fn decode(p: &Publish) -> Payload {
        Payload::from_bytes(&p.payload).unwrap()
    }

    fn metric<'a>(payload: &'a Payload, name: &str) -> Option<&'a Metric> {
        payload
            .metrics
            .iter()
            .find(|m| m.name.as_deref() == Some(name))
    }

    fn window(device: usize, at_ms: u64) -> Observation {
        Observation {
            device,
            at_ms,
            what: Observed::Window {
                rpm: Some(1772.0),
                rms_g: 0.5,
                peak_g: 1.5,
                crest: 3.0,
                kurtosis: 3.0,
                scores: [1.0; 4],
            },
        }
    }

    #[test]
    fn a_session_is_will_then_birth_with_the_same_bdseq_and_seq_from_zero() {
        let mut book = book();
        let mut node = EdgeNode::new("plant", "edge-1", 2, 7);
        let will = node.death(1);
        assert_eq!(will.topic, "spBv1.0/plant/NDEATH/edge-1");
        assert_eq!(will.qos, Qos::AtLeastOnce);
        let will = decode(&will);
        assert_eq!(will.seq, None, "NDEATH has no seq");
        assert_eq!(
            metric(&will, "bdSeq").unwrap().value(),
            Some(Value::UInt64(7))
        );

        let births = node.births(&book, 2);
        let topics: Vec<&str> = births.iter().map(|p| p.topic.as_str()).collect();
        assert_eq!(
            topics,
            [
                "spBv1.0/plant/NBIRTH/edge-1",
                "spBv1.0/plant/DBIRTH/edge-1/m.radial",
                "spBv1.0/plant/DBIRTH/edge-1/m.axial"
            ]
        );
        let nbirth = decode(&births[0]);
        assert_eq!(nbirth.seq, Some(0));
        assert_eq!(
            metric(&nbirth, "bdSeq").unwrap().value(),
            Some(Value::UInt64(7))
        );
        assert_eq!(
            metric(&nbirth, REBIRTH).unwrap().value(),
            Some(Value::Boolean(false))
        );
        assert_eq!(decode(&births[1]).seq, Some(1));
        assert_eq!(decode(&births[2]).seq, Some(2));
        assert_eq!(decode(&births[1]).metrics.len(), book.metric_count() + 1);
        assert!(metric(&decode(&births[1]), RECORD).is_some());

        // Data continues the seq, wrapping after 255.
        let record = book.observe(window(0, 10)).unwrap();
        let numbered = metric(&decode(&births[1]), RECORD).unwrap().alias;
        let mut seqs = Vec::new();
        for n in 0..300u64 {
            let out = node.data(&book, &record, n, false, 20).unwrap();
            assert_eq!(out.len(), 1);
            assert_eq!(out[0].record, Some(n));
            assert_eq!(out[0].topic, "spBv1.0/plant/DDATA/edge-1/m.radial");
            let payload = decode(&out[0]);
            let number = payload.metrics.iter().find(|m| m.alias == numbered);
            assert_eq!(number.unwrap().value(), Some(Value::UInt64(n)));
            seqs.push(payload.seq.unwrap());
        }
        assert_eq!(seqs[0], 3);
        assert_eq!(seqs[252], 255);
        assert_eq!(seqs[253], 0);

        // The next session: bdSeq + 1, births from seq 0 again, devices born anew.
        node.next_session();
        assert_eq!(
            decode(&node.death(3)).metrics[0].value(),
            Some(Value::UInt64(8))
        );
        let births = node.births(&book, 4);
        assert_eq!(decode(&births[0]).seq, Some(0));
        assert_eq!(
            metric(&decode(&births[0]), "bdSeq").unwrap().value(),
            Some(Value::UInt64(8))
        );
    }

    #[test]
    fn bdseq_wraps_at_256() {
        let mut node = EdgeNode::new("g", "n", 0, 255);
        node.next_session();
        assert_eq!(node.bd_seq(), 0);
    }

    #[test]
    fn historical_records_are_marked_and_an_unborn_device_is_born_first() {
        let mut book = book();
        let mut node = EdgeNode::new("g", "n", 2, 0);
        let record = book.observe(window(1, 10)).unwrap();
        let out = node.data(&book, &record, 5, true, 20).unwrap();
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].topic, "spBv1.0/g/DBIRTH/n/m.axial");
        let numbered = metric(&decode(&out[0]), RECORD).unwrap().alias;
        let data = decode(&out[1]);
        assert!(data
            .metrics
            .iter()
            .filter(|m| m.alias != numbered)
            .all(|m| m.is_historical == Some(true)));
        assert_eq!(data.timestamp, Some(10), "the original time");
        // A record of a device no longer configured is refused.
        let stranger = Record {
            device: "old.x".into(),
            payload: record.payload.clone(),
        };
        assert!(node.data(&book, &stranger, 6, true, 20).is_none());
    }

    #[test]
    fn a_lost_sensor_kills_its_device_and_a_clean_stop_kills_all() {
        let mut book = book();
        let mut node = EdgeNode::new("g", "n", 2, 0);
        node.births(&book, 0);
        let lost = book
            .observe(Observation {
                device: 0,
                at_ms: 5,
                what: Observed::SensorLost(true),
            })
            .unwrap();
        let out = node.data(&book, &lost, 0, false, 6).unwrap();
        let topics: Vec<&str> = out.iter().map(|p| p.topic.as_str()).collect();
        assert_eq!(
            topics,
            ["spBv1.0/g/DDATA/n/m.radial", "spBv1.0/g/DDEATH/n/m.radial"]
        );
        // At the next birth the lost device is born and dies again at once.
        let births = node.births(&book, 7);
        let topics: Vec<&str> = births.iter().map(|p| p.topic.as_str()).collect();
        assert_eq!(
            topics,
            [
                "spBv1.0/g/NBIRTH/n",
                "spBv1.0/g/DBIRTH/n/m.radial",
                "spBv1.0/g/DDEATH/n/m.radial",
                "spBv1.0/g/DBIRTH/n/m.axial"
            ]
        );
        let stop = node.stop(&book, 8);
        let topics: Vec<&str> = stop.iter().map(|p| p.topic.as_str()).collect();
        assert_eq!(topics, ["spBv1.0/g/DDEATH/n/m.axial", "spBv1.0/g/NDEATH/n"]);
    }

    #[test]
    fn a_rebirth_command_is_recognised() {
        let node = EdgeNode::new("g", "n", 0, 0);
        let ask = |value: bool| {
            Payload {
                timestamp: Some(1),
                metrics: vec![Metric::named(
                    REBIRTH,
                    DataType::Boolean,
                    1,
                    Some(&Value::Boolean(value)),
                )],
                ..Payload::default()
            }
            .to_bytes()
        };
        assert_eq!(node.command(&ask(true)), Some(Command::Rebirth));
        assert_eq!(node.command(&ask(false)), None);
        assert_eq!(node.command(b"\xff\xff not protobuf"), None);
        // A host may ask by the alias the NBIRTH declared instead of the name.
        let mut by_alias = Payload::from_bytes(&ask(true)).unwrap();
        by_alias.metrics[0].name = None;
        by_alias.metrics[0].alias = Some(REBIRTH_ALIAS);
        assert_eq!(node.command(&by_alias.to_bytes()), Some(Command::Rebirth));
        by_alias.metrics[0].alias = Some(0);
        assert_eq!(node.command(&by_alias.to_bytes()), None, "bdSeq's alias");
    }

    /// Alias → (topic, name) of every metric of a node's births; panics on a metric without an
    /// alias or an alias declared twice.
    fn aliases_of(births: &[Publish]) -> std::collections::HashMap<u64, (String, String)> {
        let mut declared = std::collections::HashMap::new();
        for birth in births.iter().filter(|p| p.topic.contains("BIRTH")) {
            for m in decode(birth).metrics {
                let name = m.name.clone().expect("a birth names its metrics");
                let alias = m.alias.unwrap_or_else(|| panic!("{name} has no alias"));
                let before = declared.insert(alias, (birth.topic.clone(), name));
                assert!(before.is_none(), "alias {alias} declared twice: {before:?}");
            }
        }
        declared
    }

    #[test]
    fn births_declare_an_alias_per_metric_unique_in_the_node_and_ddata_carries_only_it() {
        let mut book = book();
        let mut node = EdgeNode::new("g", "n", 2, 0);
        node.set_properties(vec![("Properties/v".into(), Value::String("1".into()))]);
        let births = node.births(&book, 1);
        let declared = aliases_of(&births);
        assert_eq!(declared.len(), 3 + 2 * (book.metric_count() + 1));
        assert_eq!(
            declared[&REBIRTH_ALIAS],
            ("spBv1.0/g/NBIRTH/n".to_string(), REBIRTH.to_string())
        );
        // A rebirth, and a lone DBIRTH after a lost sensor, declare the same aliases.
        assert_eq!(aliases_of(&node.births(&book, 2)), declared);
        let lost = book
            .observe(Observation {
                device: 1,
                at_ms: 3,
                what: Observed::SensorLost(true),
            })
            .unwrap();
        node.data(&book, &lost, 0, false, 3).unwrap();
        let back = book
            .observe(Observation {
                device: 1,
                at_ms: 4,
                what: Observed::SensorLost(false),
            })
            .unwrap();
        let out = node.data(&book, &back, 1, false, 4).unwrap();
        assert_eq!(out[0].topic, "spBv1.0/g/DBIRTH/n/m.axial");
        for m in decode(&out[0]).metrics {
            let alias = m.alias.unwrap();
            assert_eq!(declared[&alias].1, m.name.unwrap());
        }
        // DDATA: aliases of its own device's DBIRTH, no names, the record number included.
        let record = book.observe(window(1, 2000)).unwrap();
        let data = decode(
            node.data(&book, &record, 2, false, 2000)
                .unwrap()
                .last()
                .unwrap(),
        );
        let mut names = Vec::new();
        for m in &data.metrics {
            assert_eq!(m.name, None, "{m:?}");
            let (topic, name) = &declared[&m.alias.expect("an alias")];
            assert_eq!(topic, "spBv1.0/g/DBIRTH/n/m.axial");
            names.push(name.as_str());
        }
        assert!(
            names.contains(&"Vibration/RMS_g") && names.contains(&RECORD),
            "{names:?}"
        );
        // A queued metric the catalog no longer has is left out, not sent undeclared.
        let mut stale = record.clone();
        stale.payload.metrics[0].name = Some("Gone/Metric".into());
        let data = decode(
            node.data(&book, &stale, 3, false, 2001)
                .unwrap()
                .last()
                .unwrap(),
        );
        assert_eq!(data.metrics.len(), record.payload.metrics.len());
        assert_eq!(node.left_out_metrics(), 1);
        assert!(data
            .metrics
            .iter()
            .all(|m| declared.contains_key(&m.alias.unwrap())));
    }

    #[test]
    fn records_round_trip_through_their_queue_form() {
        let mut book = book();
        let record = book.observe(window(0, 10)).unwrap();
        assert_eq!(decode_record(&encode_record(&record)), Some(record));
        assert_eq!(decode_record(b"\x05\x00ab"), None);
    }
}
