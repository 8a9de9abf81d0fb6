//! The standard's side: machine groups, foundations, the zone boundaries of each, and the
//! measurement band a machine's speed calls for.

use crate::analysis::flags::FlagSettings;
use crate::messages::IsoZone;
use serde::{Deserialize, Serialize};

/// Standard gravity, m/s² per g.
pub const G: f64 = 9.806_65;

/// The machine groups of ISO 10816-3 / 20816-3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MachineGroup {
    /// Group 1: large machines, rated power above 300 kW (electrical machines with shaft
    /// height H ≥ 315 mm).
    Large,
    /// Group 2: medium-sized machines, 15 kW to 300 kW (electrical machines with
    /// 160 mm ≤ H < 315 mm).
    Medium,
}

impl MachineGroup {
    /// The group's number in the standard.
    pub fn number(self) -> u8 {
        match self {
            MachineGroup::Large => 1,
            MachineGroup::Medium => 2,
        }
    }

    /// Group 1 or 2.
    pub fn from_number(n: i64) -> Option<Self> {
        match n {
            1 => Some(MachineGroup::Large),
            2 => Some(MachineGroup::Medium),
            _ => None,
        }
    }
}

/// The support of the machine: rigid (lowest natural frequency of machine and support above
/// 1.25 × the main excitation) or flexible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Foundation {
    Rigid,
    Flexible,
}

impl Foundation {
    pub fn name(self) -> &'static str {
        match self {
            Foundation::Rigid => "rigid",
            Foundation::Flexible => "flexible",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "rigid" => Some(Foundation::Rigid),
            "flexible" => Some(Foundation::Flexible),
            _ => None,
        }
    }
}

/// IsoZone boundaries, velocity RMS in mm/s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ZoneLimits {
    pub ab_mm_s: f64,
    pub bc_mm_s: f64,
    pub cd_mm_s: f64,
}

impl ZoneLimits {
    /// The boundaries of ISO 10816-3:2009 Annex A, Tables A.1 (group 1) and A.2 (group 2),
    /// kept by ISO 20816-3:2022 for these groups (docs/ISO.md).
    pub fn of(group: MachineGroup, foundation: Foundation) -> Self {
        let (ab_mm_s, bc_mm_s, cd_mm_s) = match (group, foundation) {
            (MachineGroup::Large, Foundation::Rigid) => (2.3, 4.5, 7.1),
            (MachineGroup::Large, Foundation::Flexible) => (3.5, 7.1, 11.0),
            (MachineGroup::Medium, Foundation::Rigid) => (1.4, 2.8, 4.5),
            (MachineGroup::Medium, Foundation::Flexible) => (2.3, 4.5, 7.1),
        };
        ZoneLimits {
            ab_mm_s,
            bc_mm_s,
            cd_mm_s,
        }
    }

    /// The zone of a velocity RMS; a value on a boundary belongs to the zone above.
    pub fn zone(&self, v_mm_s: f64) -> IsoZone {
        if v_mm_s < self.ab_mm_s {
            IsoZone::A
        } else if v_mm_s < self.bc_mm_s {
            IsoZone::B
        } else if v_mm_s < self.cd_mm_s {
            IsoZone::C
        } else {
            IsoZone::D
        }
    }

    /// Flag thresholds for zone C (watch) and zone D (alarm), with the fault flags' clear
    /// ratio and delays: the daemon's zone flag is a [`crate::analysis::flags::FaultFlag`] fed with
    /// the velocity RMS.
    pub fn flag_settings(&self, like: &FlagSettings) -> FlagSettings {
        FlagSettings {
            watch_score: self.bc_mm_s,
            alarm_score: self.cd_mm_s,
            ..*like
        }
    }
}

/// Which machine is measured: its group and foundation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeveritySettings {
    pub group: MachineGroup,
    pub foundation: Foundation,
}

impl Default for SeveritySettings {
    /// Group 2 on a rigid foundation: the medium-sized motor bearingd is made for, with the
    /// strictest boundaries of group 2.
    fn default() -> Self {
        SeveritySettings {
            group: MachineGroup::Medium,
            foundation: Foundation::Rigid,
        }
    }
}

/// Machines slower than this use the 2 Hz lower band limit.
pub const SLOW_MACHINE_RPM: f64 = 600.0;

/// The measurement band of the standard, Hz: 10–1000, or 2–1000 below 600 rpm.
pub fn band_hz(rpm: f64) -> (f64, f64) {
    if rpm < SLOW_MACHINE_RPM {
        (2.0, 1000.0)
    } else {
        (10.0, 1000.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zones_of_each_group_and_foundation() {
        let medium_rigid = ZoneLimits::of(MachineGroup::Medium, Foundation::Rigid);
        assert_eq!(
            [0.5, 1.4, 2.0, 2.8, 4.49, 4.5].map(|v| medium_rigid.zone(v)),
            [
                IsoZone::A,
                IsoZone::B,
                IsoZone::B,
                IsoZone::C,
                IsoZone::C,
                IsoZone::D
            ]
        );
        let large_flexible = ZoneLimits::of(MachineGroup::Large, Foundation::Flexible);
        assert_eq!(
            (
                large_flexible.ab_mm_s,
                large_flexible.bc_mm_s,
                large_flexible.cd_mm_s
            ),
            (3.5, 7.1, 11.0)
        );
        assert_eq!(large_flexible.zone(10.0), IsoZone::C);
        assert_eq!(
            ZoneLimits::of(MachineGroup::Large, Foundation::Rigid).zone(4.0),
            IsoZone::B
        );
        assert_eq!(
            ZoneLimits::of(MachineGroup::Medium, Foundation::Flexible).zone(7.1),
            IsoZone::D
        );
    }
}
