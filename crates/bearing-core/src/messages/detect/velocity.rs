//! The ISO 10816-3 / 20816-3 velocity detector's messages (`analysis::iso` computes them): the
//! reading on `/velocity/<sensor>/<axis>` and the zone flag's changes on
//! `/velocity_flags/<sensor>/<axis>`, registered in [`super::detect`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{stamped_by_fields, FlagRecord, FlagSpec, MetricKind, MetricSpec, MetricValue, Record};
use crate::messages::{ChannelId, FlagLevel, IsoZone};

/// How status lines, the command line and alerts name the velocity zone flag (beside the
/// fault kinds' names).
pub const VELOCITY_FLAG_NAME: &str = "iso_zone";

/// The ISO 10816-3 / 20816-3 velocity severity of the last few windows (every half window of
/// the velocity analysis: 0.64 s at 25.6 kHz). Topic `/velocity/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VelocityMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    /// Velocity RMS in the band, mm/s, integrated from the acceleration and averaged over
    /// `windows_averaged` windows.
    pub rms_mm_s: f64,
    /// The zone of `rms_mm_s` for the configured machine group and foundation.
    pub zone: IsoZone,
    /// The standard's band, Hz: [10, 1000], or [2, 1000] below 600 rpm.
    pub band_hz: [f64; 2],
    pub windows_averaged: usize,
    /// The zone flag's level after this reading (`watch` from zone C, `alarm` from zone D, with
    /// the fault flags' hysteresis and delays).
    pub flag: FlagLevel,
}

/// The velocity zone flag changed state. Topic `/velocity_flags/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VelocityFlagMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub from: FlagLevel,
    pub to: FlagLevel,
    /// Velocity RMS, mm/s, and its zone, of the reading that changed the flag.
    pub rms_mm_s: f64,
    pub zone: IsoZone,
    /// The zone boundaries the flag is judged against, mm/s: B/C (watch) and C/D (alarm).
    pub watch_mm_s: f64,
    pub alarm_mm_s: f64,
}

/// The zone flag: alert code 5, scored in mm/s.
pub const ISO_ZONE_FLAG: FlagSpec = FlagSpec {
    name: VELOCITY_FLAG_NAME,
    code: 5,
    score_name: "ISO velocity",
    unit: "mm/s",
};

stamped_by_fields!(VelocityMessage, VelocityFlagMessage);

impl Record for VelocityMessage {
    const TOPIC: &'static str = "velocity";
    const SCHEMA: &'static str = "bearingd.Velocity";
    const METRICS: &'static [MetricSpec] = &[
        MetricSpec {
            name: "ISO20816/Zone",
            kind: MetricKind::Text,
            urgent: true,
        },
        MetricSpec {
            name: "ISO20816/VelocityRMS_mm_s",
            kind: MetricKind::Double,
            urgent: false,
        },
    ];

    fn metrics(&self, out: &mut dyn FnMut(usize, MetricValue<'_>)) {
        out(0, MetricValue::Text(self.zone.name()));
        out(1, MetricValue::Double(self.rms_mm_s));
    }

    fn status(&self) -> Option<(&'static str, String)> {
        Some(("iso", format!("{}({:.2}mm/s)", self.zone, self.rms_mm_s)))
    }
}

impl Record for VelocityFlagMessage {
    const TOPIC: &'static str = "velocity_flags";
    const SCHEMA: &'static str = "bearingd.VelocityFlag";
    const FLAGS: &'static [FlagSpec] = &[ISO_ZONE_FLAG];

    fn as_flag(&self) -> Option<&dyn FlagRecord> {
        Some(self)
    }
}

impl FlagRecord for VelocityFlagMessage {
    fn flag(&self) -> &'static FlagSpec {
        &ISO_ZONE_FLAG
    }

    fn change(&self) -> (FlagLevel, FlagLevel) {
        (self.from, self.to)
    }

    /// The velocity RMS: a measurement against the standard's boundary (confidence 1).
    fn score(&self) -> f64 {
        self.rms_mm_s
    }

    fn evidence(&self) -> String {
        format!(
            "ISO velocity {:.2} mm/s, zone {}; C from {}, D from {} mm/s",
            self.rms_mm_s, self.zone, self.watch_mm_s, self.alarm_mm_s
        )
    }
}
