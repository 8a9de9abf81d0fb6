//! The machine-fault detector's messages (`analysis::machine` computes them): the reading of
//! the shaft orders on `/machine/<sensor>/<axis>` and the changes of its three flags
//! (unbalance, misalignment, looseness) on `/machine_flags/<sensor>/<axis>`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{stamped_by_fields, FlagRecord, FlagSpec, MetricKind, MetricSpec, MetricValue, Record};
use crate::machine_fault::MachineFaultKind;
use crate::messages::{ChannelId, FlagLevel, IsoZone};

/// The velocity at shaft orders over the last few envelope windows, and the machine fault
/// it shows, if any. Topic `/machine/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MachineMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    /// The shaft rate the orders are taken at, Hz.
    pub shaft_hz: f64,
    /// Velocity RMS of the ISO band over the same windows, mm/s.
    pub overall_mm_s: f64,
    /// Velocity RMS of the 1×, 2× and 3× lines, mm/s.
    pub orders_mm_s: [f64; 3],
    /// The machine fault the orders show at zone C or D of its own velocity; `None`: none.
    pub fault: Option<MachineFaultKind>,
    /// That fault's velocity (its lines' RMS), mm/s, and its zone; 0 and A without a fault.
    pub fault_mm_s: f64,
    pub zone: IsoZone,
    pub windows_averaged: usize,
}

/// A machine-fault flag changed state. Topic `/machine_flags/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MachineFlagMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub kind: MachineFaultKind,
    pub from: FlagLevel,
    pub to: FlagLevel,
    /// The fault's velocity in the reading that changed the flag (0 when the pattern is gone),
    /// mm/s, and the zone boundaries it is judged against: B/C (watch) and C/D (alarm).
    pub velocity_mm_s: f64,
    pub watch_mm_s: f64,
    pub alarm_mm_s: f64,
}

/// The three flags, alert codes 6–8, in [`MachineFaultKind::ALL`] order, scored in mm/s.
pub const MACHINE_FLAGS: [FlagSpec; 3] = [
    machine_flag("unbalance", 6),
    machine_flag("misalignment", 7),
    machine_flag("looseness", 8),
];

const fn machine_flag(name: &'static str, code: u8) -> FlagSpec {
    FlagSpec {
        name,
        code,
        score_name: "velocity at shaft orders",
        unit: "mm/s",
    }
}

/// The flag of a machine fault.
pub fn machine_flag_of(kind: MachineFaultKind) -> &'static FlagSpec {
    let index = MachineFaultKind::ALL
        .iter()
        .position(|k| *k == kind)
        .unwrap_or(0);
    &MACHINE_FLAGS[index]
}

stamped_by_fields!(MachineMessage, MachineFlagMessage);

impl Record for MachineMessage {
    const TOPIC: &'static str = "machine";
    const SCHEMA: &'static str = "bearingd.Machine";
    const METRICS: &'static [MetricSpec] = &[
        MetricSpec {
            name: "Machine/Fault",
            kind: MetricKind::Text,
            urgent: true,
        },
        MetricSpec {
            name: "Machine/Velocity1x_mm_s",
            kind: MetricKind::Double,
            urgent: false,
        },
    ];

    fn metrics(&self, out: &mut dyn FnMut(usize, MetricValue<'_>)) {
        out(
            0,
            MetricValue::Text(self.fault.map_or("none", |k| k.name())),
        );
        out(1, MetricValue::Double(self.orders_mm_s[0]));
    }

    fn status(&self) -> Option<(&'static str, String)> {
        let text = match self.fault {
            Some(kind) => format!("{}({:.2}mm/s)", kind.name(), self.fault_mm_s),
            None => format!("ok(1x {:.2}mm/s)", self.orders_mm_s[0]),
        };
        Some(("machine", text))
    }
}

impl Record for MachineFlagMessage {
    const TOPIC: &'static str = "machine_flags";
    const SCHEMA: &'static str = "bearingd.MachineFlag";
    const FLAGS: &'static [FlagSpec] = &MACHINE_FLAGS;

    fn as_flag(&self) -> Option<&dyn FlagRecord> {
        Some(self)
    }
}

impl FlagRecord for MachineFlagMessage {
    fn flag(&self) -> &'static FlagSpec {
        machine_flag_of(self.kind)
    }

    fn change(&self) -> (FlagLevel, FlagLevel) {
        (self.from, self.to)
    }

    /// The fault's velocity: a measurement against the standard's boundary (confidence 1).
    fn score(&self) -> f64 {
        self.velocity_mm_s
    }

    fn evidence(&self) -> String {
        format!(
            "{} at shaft orders {:.2} mm/s; C from {}, D from {} mm/s",
            self.kind.name(),
            self.velocity_mm_s,
            self.watch_mm_s,
            self.alarm_mm_s
        )
    }
}
