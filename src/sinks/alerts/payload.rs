//! The alert as it travels over iceoryx2: one fixed-size `#[repr(C)]` record, versioned, with an
//! explicit type name so that subscribers in other crates or languages (the Python example in
//! `examples/alerts_subscriber.py`) declare the same layout and are matched by iceoryx2.
//!
//! Why no strings or enums of Rust's choosing: a ctypes or C struct must be able to mirror it
//! field by field, so names are fixed byte arrays (NUL-padded ASCII) and states are small
//! integer codes listed here and in `docs/ALERTS.md`. The fields are ordered from the widest
//! to the narrowest so there is no padding to get wrong.

use crate::config::MAX_ID_LEN;
use crate::messages::detect::{all_flags, flag_by_code};
use crate::messages::{AlertMessage, AlertSubject, FaultKind, FlagLevel, ISO_ZONE_FLAG};
#[cfg(feature = "shm")]
use iceoryx2::prelude::ZeroCopySend;
use serde::Serialize;

/// Layout version of [`Alert`]; a subscriber must refuse any other value.
pub const ALERT_VERSION: u32 = 1;

/// Bytes for a sensor id or an axis name: the config's longest id (ASCII), NUL-padded.
pub const NAME_BYTES: usize = MAX_ID_LEN;

pub use crate::messages::AlertState;

fn state_of_code(code: u8) -> Option<AlertState> {
    AlertState::ALL.into_iter().find(|s| *s as u8 == code)
}

/// Code of a fault kind in [`Alert::fault`]: 1 outer race, 2 inner race, 3 ball, 4 cage.
pub fn fault_code(fault: FaultKind) -> u8 {
    match fault {
        FaultKind::OuterRace => 1,
        FaultKind::InnerRace => 2,
        FaultKind::Ball => 3,
        FaultKind::Cage => 4,
    }
}

/// Code in [`Alert::fault`] of the ISO velocity zone flag (watch in zone C, alarm in zone D):
/// `score` is then the velocity RMS in mm/s, `fault_frequency_hz` and `twin_error` NaN.
pub const ISO_ZONE_CODE: u8 = ISO_ZONE_FLAG.code;

/// Code in [`Alert::fault`] of the flag an alert is about: a fault kind's, or the code a
/// detector's flag declares (5 and up; `messages::detect`).
pub fn subject_code(subject: AlertSubject) -> u8 {
    match subject {
        AlertSubject::Fault(fault) => fault_code(fault),
        AlertSubject::Detector(flag) => flag.code,
    }
}

/// The wire name of a code of [`Alert::fault`]: a fault kind's (`outer_race`, …) or a
/// detector flag's (`iso_zone`, …).
fn subject_of_code(code: u8) -> Option<&'static str> {
    let fault = FaultKind::ALL.into_iter().find(|f| fault_code(*f) == code);
    fault
        .map(FaultKind::name)
        .or_else(|| flag_by_code(code).map(|flag| flag.name))
}

/// Code of a flag level in [`Alert::severity`]: 0 ok, 1 watch, 2 alarm.
pub fn severity_code(level: FlagLevel) -> u8 {
    match level {
        FlagLevel::Ok => 0,
        FlagLevel::Watch => 1,
        FlagLevel::Alarm => 2,
    }
}

fn severity_of_code(code: u8) -> Option<FlagLevel> {
    [FlagLevel::Ok, FlagLevel::Watch, FlagLevel::Alarm]
        .into_iter()
        .find(|l| severity_code(*l) == code)
}

/// One alert. 144 bytes, 8-byte aligned, no padding.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "shm", derive(ZeroCopySend), type_name("bearingd::Alert"))]
#[repr(C)]
pub struct Alert {
    /// 1 for the first alert a daemon run publishes, +1 for each next one. A subscriber that
    /// sees a gap has lost alerts (its buffer overflowed) and must say so.
    pub sequence: u64,
    /// Identifies the daemon run (its start, ns since the Unix epoch); a new value means the
    /// daemon restarted and `sequence` starts again at 1.
    pub run_id: u64,
    /// One past the last sample of the window that decided the change, in the channel's
    /// sample time (the same position the MCAP log's `/flags` message has).
    pub end_sample: u64,
    /// When the daemon's source completed the block that completed that window (assembled
    /// it from CAN or iceoryx2 frames, or generated it for a simulated sensor), ns since the
    /// Unix epoch. Receipt time minus this is the alert's latency.
    pub wall_time_ns: u64,
    pub sample_rate_hz: f64,
    /// The fault frequency the flag watches (BPFO, BPFI, 2BSF or FTF) at the current speed, Hz.
    pub fault_frequency_hz: f64,
    /// The fault's envelope-spectrum score when the flag changed.
    pub score: f64,
    /// 0.5 (undecided) to 1: how clearly this fault's score stands above the thresholds and
    /// the other faults' scores, raised when the twin's best fit agrees and lowered when it
    /// does not (the rule of `analyze`).
    pub confidence: f64,
    /// The twin's fit error for this fault's hypothesis (0 perfect); NaN before the first fit.
    pub twin_error: f64,
    /// [`ALERT_VERSION`].
    pub version: u32,
    /// An [`AlertState`] code.
    pub state: u8,
    /// A fault code, see [`fault_code`], or [`ISO_ZONE_CODE`].
    pub fault: u8,
    /// Severity now, see [`severity_code`]; 0 when cleared.
    pub severity: u8,
    /// Severity before this change.
    pub previous_severity: u8,
    /// Sensor id, ASCII, NUL-padded.
    pub sensor: [u8; NAME_BYTES],
    /// Axis name, ASCII, NUL-padded.
    pub axis: [u8; NAME_BYTES],
}

const _: () = assert!(std::mem::size_of::<Alert>() == 144);
const _: () = assert!(std::mem::align_of::<Alert>() == 8);

/// Copies an id into a fixed field; ids longer than the field are cut (the config never
/// allows them).
pub fn name_field(name: &str) -> [u8; NAME_BYTES] {
    let mut field = [0u8; NAME_BYTES];
    for (slot, byte) in field.iter_mut().zip(name.bytes()) {
        *slot = byte;
    }
    field
}

fn name_of_field(field: &[u8; NAME_BYTES]) -> String {
    let end = field.iter().position(|b| *b == 0).unwrap_or(NAME_BYTES);
    String::from_utf8_lossy(&field[..end]).into_owned()
}

/// Why a received [`Alert`] cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AlertDecodeError {
    #[error("alert layout version {0}, but this bearingd reads version {ALERT_VERSION}: use the bearingd that matches the daemon")]
    Version(u32),
    #[error("alert #{sequence}: unknown {field} code {code}")]
    Code {
        sequence: u64,
        field: &'static str,
        code: u8,
    },
}

/// An alert in readable form: what `bearingd alerts --json` prints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AlertView {
    pub sequence: u64,
    pub run_id: u64,
    pub sensor: String,
    pub axis: String,
    pub fault: &'static str,
    pub state: AlertState,
    pub severity: &'static str,
    pub previous_severity: &'static str,
    pub confidence: f64,
    pub score: f64,
    pub fault_frequency_hz: f64,
    /// `None` before the twin's first fit.
    pub twin_error: Option<f64>,
    pub end_sample: u64,
    pub sample_time_s: f64,
    pub wall_time_ns: u64,
}

impl Alert {
    /// The record of the pipeline's `alert`, sent at `wall_time_ns` (when the source completed
    /// the block that decided it); a missing frequency or twin error is NaN.
    pub fn of_message(alert: &AlertMessage, wall_time_ns: u64) -> Alert {
        Alert {
            sequence: alert.sequence,
            run_id: alert.run_id,
            end_sample: alert.end_sample,
            wall_time_ns,
            sample_rate_hz: alert.sample_rate_hz,
            fault_frequency_hz: alert.fault_frequency_hz.unwrap_or(f64::NAN),
            score: alert.score,
            confidence: alert.confidence,
            twin_error: alert.twin_error.unwrap_or(f64::NAN),
            version: ALERT_VERSION,
            state: alert.state as u8,
            fault: subject_code(alert.subject),
            severity: severity_code(alert.severity),
            previous_severity: severity_code(alert.previous_severity),
            sensor: name_field(&alert.channel.sensor),
            axis: name_field(&alert.channel.axis),
        }
    }

    /// Decodes the codes; refuses other layout versions and unknown codes.
    pub fn view(&self) -> Result<AlertView, AlertDecodeError> {
        if self.version != ALERT_VERSION {
            return Err(AlertDecodeError::Version(self.version));
        }
        let bad = |field, code| AlertDecodeError::Code {
            sequence: self.sequence,
            field,
            code,
        };
        let state = state_of_code(self.state).ok_or(bad("state", self.state))?;
        let fault = subject_of_code(self.fault).ok_or(bad("fault", self.fault))?;
        let severity = severity_of_code(self.severity).ok_or(bad("severity", self.severity))?;
        let previous = severity_of_code(self.previous_severity)
            .ok_or(bad("previous_severity", self.previous_severity))?;
        Ok(AlertView {
            sequence: self.sequence,
            run_id: self.run_id,
            sensor: name_of_field(&self.sensor),
            axis: name_of_field(&self.axis),
            fault,
            state,
            severity: severity.name(),
            previous_severity: previous.name(),
            confidence: self.confidence,
            score: self.score,
            fault_frequency_hz: self.fault_frequency_hz,
            twin_error: self.twin_error.is_finite().then_some(self.twin_error),
            end_sample: self.end_sample,
            sample_time_s: if self.sample_rate_hz > 0.0 {
                self.end_sample as f64 / self.sample_rate_hz
            } else {
                f64::NAN
            },
            wall_time_ns: self.wall_time_ns,
        })
    }
}

impl AlertView {
    /// One line for people: what, where, how sure, and where in the signal.
    pub fn line(&self) -> String {
        let head = format!(
            "#{} {}/{} {} {} ({} → {})",
            self.sequence,
            self.sensor,
            self.axis,
            self.fault,
            self.state.name(),
            self.previous_severity,
            self.severity
        );
        if let Some(flag) = all_flags().find(|flag| flag.name == self.fault) {
            return format!(
                "{head}: {} {:.2} {}, t = {:.1} s",
                flag.score_name, self.score, flag.unit, self.sample_time_s
            );
        }
        let twin = self.twin_error.map_or("no twin fit yet".to_string(), |e| {
            format!("twin error {e:.3}")
        });
        format!(
            "{head}: score {:.1} at {:.1} Hz, confidence {:.2}, {}, t = {:.1} s",
            self.score, self.fault_frequency_hz, self.confidence, twin, self.sample_time_s
        )
    }
}

/// A raised outer-race alert of sensor `s` for the alert tests: `run_id` and `sequence` as
/// given, its end sample 100 per sequence number (saturating: the tests also send `u64::MAX`).
#[cfg(test)]
pub(crate) fn test_alert(run_id: u64, sequence: u64) -> Alert {
    Alert {
        sequence,
        run_id,
        end_sample: sequence.saturating_mul(100),
        wall_time_ns: 0,
        sample_rate_hz: 12_000.0,
        fault_frequency_hz: 107.0,
        score: 30.0,
        confidence: 0.9,
        twin_error: 0.25, // not NaN: the tests compare alerts with ==
        version: ALERT_VERSION,
        state: AlertState::Raised as u8,
        fault: 1,
        severity: 1,
        previous_severity: 0,
        sensor: name_field("s"),
        axis: name_field("radial"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_has_no_padding_and_round_trips() {
        let offsets = [
            std::mem::offset_of!(Alert, sequence),
            std::mem::offset_of!(Alert, twin_error),
            std::mem::offset_of!(Alert, version),
            std::mem::offset_of!(Alert, previous_severity),
            std::mem::offset_of!(Alert, sensor),
            std::mem::offset_of!(Alert, axis),
        ];
        assert_eq!(offsets, [0, 64, 72, 79, 80, 112]);
        let alert = Alert {
            sequence: 7,
            run_id: 1,
            end_sample: 25_600,
            wall_time_ns: 5,
            sample_rate_hz: 25_600.0,
            fault_frequency_hz: 107.4,
            score: 31.0,
            confidence: 0.9,
            twin_error: f64::NAN,
            version: ALERT_VERSION,
            state: AlertState::Raised as u8,
            fault: fault_code(FaultKind::OuterRace),
            severity: severity_code(FlagLevel::Watch),
            previous_severity: 0,
            sensor: name_field("motor-de"),
            axis: name_field("radial"),
        };
        let view = alert.view().unwrap();
        assert_eq!(view.sensor, "motor-de");
        assert_eq!(view.fault, "outer_race");
        assert_eq!(view.state, AlertState::Raised);
        assert_eq!(view.twin_error, None);
        assert_eq!(view.sample_time_s, 1.0);
        let bad = Alert {
            version: 2,
            ..alert
        };
        assert_eq!(bad.view(), Err(AlertDecodeError::Version(2)));
        let bad = Alert { fault: 9, ..alert };
        assert!(bad.view().is_err());
    }

    #[test]
    fn a_pipeline_alert_becomes_the_record_with_the_wall_time_stamped() {
        let message = AlertMessage {
            sequence: 3,
            run_id: 77,
            channel: crate::messages::ChannelId {
                sensor: "motor-de".into(),
                axis: "radial".into(),
            },
            end_sample: 51_200,
            sample_rate_hz: 25_600.0,
            subject: AlertSubject::Fault(FaultKind::InnerRace),
            state: AlertState::Escalated,
            severity: FlagLevel::Alarm,
            previous_severity: FlagLevel::Watch,
            score: 55.0,
            confidence: 0.8,
            fault_frequency_hz: Some(162.0),
            twin_error: None,
        };
        let alert = Alert::of_message(&message, 123);
        assert_eq!((alert.wall_time_ns, alert.version), (123, ALERT_VERSION));
        assert!(alert.twin_error.is_nan());
        let view = alert.view().unwrap();
        assert_eq!(
            (view.sequence, view.run_id, view.end_sample),
            (3, 77, 51_200)
        );
        assert_eq!(
            (view.sensor.as_str(), view.axis.as_str()),
            ("motor-de", "radial")
        );
        assert_eq!(
            (view.fault, view.state),
            ("inner_race", AlertState::Escalated)
        );
        assert_eq!((view.severity, view.previous_severity), ("alarm", "watch"));
        assert_eq!((view.score, view.confidence), (55.0, 0.8));
        assert_eq!((view.fault_frequency_hz, view.sample_time_s), (162.0, 2.0));
        let zone = Alert::of_message(
            &AlertMessage {
                subject: AlertSubject::ISO_ZONE,
                fault_frequency_hz: None,
                ..message
            },
            0,
        );
        assert_eq!(zone.fault, ISO_ZONE_CODE);
        assert!(zone.fault_frequency_hz.is_nan());
    }

    #[test]
    fn states_follow_the_flag_change() {
        use FlagLevel::*;
        assert_eq!(AlertState::of_change(Ok, Watch), AlertState::Raised);
        assert_eq!(AlertState::of_change(Ok, Alarm), AlertState::Raised);
        assert_eq!(AlertState::of_change(Watch, Alarm), AlertState::Escalated);
        assert_eq!(AlertState::of_change(Alarm, Watch), AlertState::Relaxed);
        assert_eq!(AlertState::of_change(Alarm, Ok), AlertState::Cleared);
    }
}
