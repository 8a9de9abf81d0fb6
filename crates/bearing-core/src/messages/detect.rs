//! What a detector says, in one shape every consumer can handle without knowing the detector:
//! its records ([`Record`]: a reading, or a change of one of its flags, [`FlagRecord`]) and the
//! one list of detectors (the `detectors!` invocation at the end of this file) that makes
//! [`DetectorMessage`], the pipeline's single message variant for all of them.
//!
//! Why here and not in `analysis` (where issue 31's design put it): [`PipelineMessage`] must
//! name every detector's messages, and `messages` is the bottom room that the analysis, the
//! MCAP log and every sink build on (`src/lib.rs` "# Layout"); a list in `analysis` would make
//! `messages` depend on a room above it. So the message half of a detector lives here (its
//! records in a file of their own, `messages/detect/<name>.rs`), the computing half in
//! `analysis`.
//!
//! What is generic then (no per-detector code): the MCAP log's topics, schemas, encoding and
//! decoding ([`RecordKind`]), late flag changes, the accessors (`channel`, `end_sample`),
//! alerts (score, confidence, the code and name of [`FlagSpec`]), `bearingd alerts`' and
//! `run`'s flag lines, the status flags and the fleet's metrics ([`MetricSpec`]).
//!
//! A new detector: its records in `messages/detect/<name>.rs` (the [`Record`] and
//! [`FlagRecord`] impls), one line in `detectors!`, its computation in `analysis` (a
//! `ChannelDetector`, listed in `analysis::detectors`; docs/ARCHITECTURE.md "Where a new part
//! goes").
//!
//! Dispatch: one `match` per message (generated) to a `&dyn` [`AnyRecord`]: a vtable call per
//! low-rate message (a reading every half second per channel), no allocation, and far less
//! generated code than one static arm per consumer.

use std::fmt::Debug;

use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::{ChannelId, FlagLevel, PipelineMessage};

pub mod machine;
pub mod velocity;

/// A flag of a detector: how alerts, status lines and the command line name it, and its code in
/// the iceoryx2 alert (1–4 are the bearing faults).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FlagSpec {
    /// The wire name (`iso_zone`).
    pub name: &'static str,
    /// The alert's `fault` code.
    pub code: u8,
    /// What the flag's score is, for people (`ISO velocity`), and its unit (`mm/s`).
    pub score_name: &'static str,
    pub unit: &'static str,
}

/// What a metric of a detector's reading holds (the fleet's Sparkplug data type).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MetricKind {
    Text,
    Double,
}

/// A metric a detector's reading publishes to the fleet (`ISO20816/Zone`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MetricSpec {
    pub name: &'static str,
    pub kind: MetricKind,
    /// A change goes out at once, not at the next publish period (a new zone).
    pub urgent: bool,
}

/// One metric's value, as a reading gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MetricValue<'a> {
    Text(&'a str),
    Double(f64),
}

/// Where a record is and when: what every consumer needs to route or time it. Object safe.
pub trait Stamped {
    fn channel(&self) -> &ChannelId;
    /// One past the last sample the record covers.
    fn end_sample(&self) -> u64;
    /// Puts the record on `channel`: a detector makes its records without knowing its
    /// channel's name, the pipeline stamps them.
    fn set_channel(&mut self, channel: ChannelId);
}

/// Implements [`Stamped`] for records with the usual `channel` and `end_sample` fields.
macro_rules! stamped_by_fields {
    ($($record:ty),+ $(,)?) => {$(
        impl $crate::messages::detect::Stamped for $record {
            fn channel(&self) -> &ChannelId {
                &self.channel
            }

            fn end_sample(&self) -> u64 {
                self.end_sample
            }

            fn set_channel(&mut self, channel: ChannelId) {
                self.channel = channel;
            }
        }
    )+};
}
pub(crate) use stamped_by_fields;

/// One message type of a detector, logged as JSON on `/<TOPIC>/<sensor>/<axis>`.
pub trait Record:
    Stamped + Serialize + DeserializeOwned + JsonSchema + Clone + PartialEq + Debug + Send + 'static
{
    /// The topic family (`velocity` → `/velocity/<sensor>/<axis>`).
    const TOPIC: &'static str;
    /// The MCAP schema name (`bearingd.Velocity`).
    const SCHEMA: &'static str;
    /// The flags a flag record reports (none for a reading).
    const FLAGS: &'static [FlagSpec] = &[];
    /// The fleet metrics the record fills (none for a flag record: the alert carries flags).
    const METRICS: &'static [MetricSpec] = &[];

    /// Gives the value of each metric, by index in [`Record::METRICS`].
    fn metrics(&self, _out: &mut dyn FnMut(usize, MetricValue<'_>)) {}

    /// The record as a flag change, if it is one (flag records return `Some(self)`).
    fn as_flag(&self) -> Option<&dyn FlagRecord> {
        None
    }

    /// What the channel's status line shows of the reading, as `(key, value)`
    /// (`("iso", "B(2.10mm/s)")`); `None`: nothing.
    fn status(&self) -> Option<(&'static str, String)> {
        None
    }
}

/// A record that reports a change of one of the detector's flags: what alerts, status, the
/// `/state` snapshot and replay comparisons need. Object safe.
pub trait FlagRecord: Stamped {
    /// Which flag changed.
    fn flag(&self) -> &'static FlagSpec;
    /// Its level before and after.
    fn change(&self) -> (FlagLevel, FlagLevel);
    /// The alert's score, in the flag's unit.
    fn score(&self) -> f64;
    /// The alert's confidence: 1 for a measurement against a fixed limit.
    fn confidence(&self) -> f64 {
        1.0
    }
    /// What the change rests on, in a few words for people (`run` prints it).
    fn evidence(&self) -> String;
}

/// What a detector emits: a reading, or a change of one of its flags.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Emitted<R, F> {
    Reading(R),
    Flag(F),
}

/// Which of a detector's two record types.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    Reading,
    Flag,
}

/// A detector's record type as a value: the key of its MCAP channel and schema.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RecordKind {
    pub detector: DetectorId,
    pub role: Role,
}

/// What the MCAP log needs of one record type, without naming it.
#[derive(Clone, Copy)]
pub struct RecordInfo {
    pub topic: &'static str,
    pub schema: &'static str,
    pub flags: &'static [FlagSpec],
    pub metrics: &'static [MetricSpec],
    /// The JSON Schema of the record as serde writes it, from the given generator's settings.
    pub json_schema: fn(SchemaGenerator) -> Schema,
    pub decode: fn(&[u8]) -> serde_json::Result<DetectorMessage>,
}

impl RecordInfo {
    fn of<R: Record + Into<DetectorMessage>>() -> RecordInfo {
        RecordInfo {
            topic: R::TOPIC,
            schema: R::SCHEMA,
            flags: R::FLAGS,
            metrics: R::METRICS,
            json_schema: |generator| generator.into_root_schema_for::<R>(),
            decode: |bytes| serde_json::from_slice::<R>(bytes).map(Into::into),
        }
    }
}

/// A record whose type is not named: how the generic consumers see one.
pub trait AnyRecord: Stamped {
    /// Writes the record's JSON (serde's form, the wire form) into `out`.
    fn write_json(&self, out: &mut Vec<u8>) -> serde_json::Result<()>;
    fn as_flag(&self) -> Option<&dyn FlagRecord>;
    fn metrics(&self, out: &mut dyn FnMut(usize, MetricValue<'_>));
    fn status(&self) -> Option<(&'static str, String)>;
}

impl<R: Record> AnyRecord for R {
    fn write_json(&self, out: &mut Vec<u8>) -> serde_json::Result<()> {
        serde_json::to_writer(out, self)
    }

    fn as_flag(&self) -> Option<&dyn FlagRecord> {
        Record::as_flag(self)
    }

    fn metrics(&self, out: &mut dyn FnMut(usize, MetricValue<'_>)) {
        Record::metrics(self, out)
    }

    fn status(&self) -> Option<(&'static str, String)> {
        Record::status(self)
    }
}

impl RecordKind {
    /// Every registered record type, readings and flags.
    pub fn all() -> impl Iterator<Item = RecordKind> {
        DetectorId::ALL.iter().flat_map(|&detector| {
            [Role::Reading, Role::Flag].map(|role| RecordKind { detector, role })
        })
    }

    /// The record type whose MCAP schema is `name`.
    pub fn from_schema_name(name: &str) -> Option<RecordKind> {
        RecordKind::all().find(|kind| kind.info().schema == name)
    }

    /// Where the record type's metrics begin in [`all_metrics`].
    pub fn first_metric(self) -> usize {
        RecordKind::all()
            .take_while(|kind| *kind != self)
            .map(|kind| kind.info().metrics.len())
            .sum()
    }

    /// Flag changes may be held while the log is paused and written late.
    pub fn can_be_late(self) -> bool {
        self.role == Role::Flag
    }
}

/// Every registered detector's flags, in registry order.
pub fn all_flags() -> impl Iterator<Item = &'static FlagSpec> {
    RecordKind::all().flat_map(|kind| kind.info().flags)
}

/// Every registered detector's fleet metrics, in registry order ([`METRIC_COUNT`] of them).
pub fn all_metrics() -> impl Iterator<Item = &'static MetricSpec> {
    RecordKind::all().flat_map(|kind| kind.info().metrics)
}

/// The detector flag with the alert code `code`.
pub fn flag_by_code(code: u8) -> Option<&'static FlagSpec> {
    all_flags().find(|flag| flag.code == code)
}

impl DetectorMessage {
    /// The message's fleet metrics, by index in [`all_metrics`].
    pub fn metrics(&self, out: &mut dyn FnMut(usize, MetricValue<'_>)) {
        let (kind, record) = self.record();
        let first = kind.first_metric();
        record.metrics(&mut |i, value| out(first + i, value));
    }

    pub fn channel(&self) -> &ChannelId {
        self.record().1.channel()
    }

    pub fn end_sample(&self) -> u64 {
        self.record().1.end_sample()
    }

    /// The message as a flag change, if it is one.
    pub fn as_flag(&self) -> Option<&dyn FlagRecord> {
        self.record().1.as_flag()
    }

    /// What the channel's status line shows of the message ([`Record::status`]).
    pub fn status(&self) -> Option<(&'static str, String)> {
        self.record().1.status()
    }
}

/// The one list of detectors: `Name { reading: Type, flag: Type }` per detector. Generates
/// [`DetectorMessage`] (a variant per detector), [`DetectorId`], `From` each record type into
/// [`DetectorMessage`] and [`PipelineMessage`], [`RecordKind::info`] and
/// [`DetectorMessage::record`].
macro_rules! detectors {
    ($($name:ident { reading: $reading:ty, flag: $flag:ty }),+ $(,)?) => {
        /// Every registered detector's messages: one pipeline variant for all of them.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        pub enum DetectorMessage {
            $($name(Emitted<$reading, $flag>)),+
        }

        /// A registered detector.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum DetectorId {
            $($name),+
        }

        impl DetectorId {
            pub const ALL: &'static [DetectorId] = &[$(DetectorId::$name),+];
        }

        /// How many fleet metrics the detectors publish ([`all_metrics`]), for fixed slots.
        pub const METRIC_COUNT: usize =
            0 $(+ <$reading as Record>::METRICS.len() + <$flag as Record>::METRICS.len())+;

        impl RecordKind {
            /// Topic, schema, JSON Schema and decoder of the record type.
            pub fn info(self) -> RecordInfo {
                match (self.detector, self.role) {
                    $(
                        (DetectorId::$name, Role::Reading) => RecordInfo::of::<$reading>(),
                        (DetectorId::$name, Role::Flag) => RecordInfo::of::<$flag>(),
                    )+
                }
            }
        }

        impl DetectorMessage {
            /// The message's record type and the record.
            pub fn record(&self) -> (RecordKind, &dyn AnyRecord) {
                match self {
                    $(
                        DetectorMessage::$name(Emitted::Reading(r)) => (
                            RecordKind { detector: DetectorId::$name, role: Role::Reading },
                            r,
                        ),
                        DetectorMessage::$name(Emitted::Flag(f)) => (
                            RecordKind { detector: DetectorId::$name, role: Role::Flag },
                            f,
                        ),
                    )+
                }
            }

            /// Puts the message on `channel` ([`Stamped::set_channel`]).
            pub fn set_channel(&mut self, channel: ChannelId) {
                match self {
                    $(
                        DetectorMessage::$name(Emitted::Reading(r)) => r.set_channel(channel),
                        DetectorMessage::$name(Emitted::Flag(f)) => f.set_channel(channel),
                    )+
                }
            }
        }

        $(
            impl From<$reading> for DetectorMessage {
                fn from(r: $reading) -> Self {
                    DetectorMessage::$name(Emitted::Reading(r))
                }
            }
            impl From<$flag> for DetectorMessage {
                fn from(f: $flag) -> Self {
                    DetectorMessage::$name(Emitted::Flag(f))
                }
            }
            impl From<$reading> for PipelineMessage {
                fn from(r: $reading) -> Self {
                    PipelineMessage::Detector(r.into())
                }
            }
            impl From<$flag> for PipelineMessage {
                fn from(f: $flag) -> Self {
                    PipelineMessage::Detector(f.into())
                }
            }
        )+
    };
}

detectors! {
    Velocity { reading: super::VelocityMessage, flag: super::VelocityFlagMessage },
    Machine { reading: machine::MachineMessage, flag: machine::MachineFlagMessage },
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{FaultKind, IsoZone, VelocityFlagMessage, VelocityMessage};

    fn channel() -> ChannelId {
        ChannelId {
            sensor: "motor-de".into(),
            axis: "radial".into(),
        }
    }

    fn samples() -> Vec<DetectorMessage> {
        vec![
            VelocityMessage {
                channel: channel(),
                end_sample: 32_768,
                rms_mm_s: 3.7,
                zone: IsoZone::C,
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
                zone: IsoZone::C,
                watch_mm_s: 2.8,
                alarm_mm_s: 4.5,
            }
            .into(),
        ]
    }

    #[test]
    fn every_record_type_has_its_own_topic_and_schema_and_is_found_by_it() {
        let kinds: Vec<RecordKind> = RecordKind::all().collect();
        assert_eq!(kinds.len(), 2 * DetectorId::ALL.len());
        for (i, kind) in kinds.iter().enumerate() {
            let info = kind.info();
            assert_eq!(RecordKind::from_schema_name(info.schema), Some(*kind));
            for other in &kinds[i + 1..] {
                assert_ne!(info.topic, other.info().topic);
                assert_ne!(info.schema, other.info().schema);
            }
        }
        assert_eq!(RecordKind::from_schema_name("bearingd.Flag"), None);
    }

    #[test]
    fn flags_have_codes_after_the_faults_and_names_of_their_own() {
        let flags: Vec<&FlagSpec> = all_flags().collect();
        assert!(!flags.is_empty());
        for (i, flag) in flags.iter().enumerate() {
            assert!(
                flag.code > FaultKind::ALL.len() as u8,
                "{flag:?}: 1–4 are the faults"
            );
            assert!(FaultKind::ALL.iter().all(|f| f.name() != flag.name));
            assert_eq!(flag_by_code(flag.code), Some(*flag));
            for other in &flags[i + 1..] {
                assert_ne!(flag.code, other.code);
                assert_ne!(flag.name, other.name);
            }
        }
        assert_eq!(flag_by_code(1), None);
    }

    #[test]
    fn metrics_are_numbered_across_the_registry() {
        assert_eq!(all_metrics().count(), METRIC_COUNT);
        for message in samples() {
            let (kind, _) = message.record();
            let mut seen = Vec::new();
            message.metrics(&mut |index, _| seen.push(index));
            let first = kind.first_metric();
            let expected: Vec<usize> = (first..first + kind.info().metrics.len()).collect();
            assert_eq!(seen, expected, "{kind:?}");
        }
    }

    #[test]
    fn a_message_reads_back_from_its_json_and_only_flag_changes_are_flags() {
        for message in samples() {
            let (kind, record) = message.record();
            let mut json = Vec::new();
            record.write_json(&mut json).expect("JSON");
            let read = (kind.info().decode)(&json).expect("decodes");
            assert_eq!(read, message);
            assert_eq!(message.channel(), &channel());
            assert_eq!(message.as_flag().is_some(), kind.role == Role::Flag);
            assert_eq!(kind.can_be_late(), kind.role == Role::Flag);
        }
        let flag = samples().pop().expect("a flag sample");
        let flag = flag.as_flag().expect("a flag");
        assert_eq!(flag.flag().name, "iso_zone");
        assert_eq!(flag.change(), (FlagLevel::Ok, FlagLevel::Watch));
        assert_eq!((flag.score(), flag.confidence()), (3.7, 1.0));
    }
}
