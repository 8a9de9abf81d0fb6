//! `[severity]`: the machine the ISO 10816-3 / 20816-3 velocity zones are judged for.

use super::*;
use crate::analysis::iso::{Foundation, MachineGroup, SeveritySettings};

impl Checker {
    pub(super) fn severity(&mut self, raw: &RawSeverity) -> Option<SeveritySettings> {
        let d = SeveritySettings::default();
        let group_fix = "use 1 (above 300 kW, or shaft height 315 mm and more) or 2 (15 to \
                         300 kW, shaft height 160 to 315 mm), e.g. machine_group = 2";
        let group = self
            .integer(
                "severity.machine_group",
                &raw.machine_group,
                i64::from(d.group.number()),
                1,
                2,
                group_fix,
            )
            .and_then(MachineGroup::from_number);
        let foundation_fix = "use \"rigid\" or \"flexible\", e.g. foundation = \"rigid\"";
        let foundation = self
            .or_default(
                "severity.foundation",
                &raw.foundation,
                d.foundation.name().to_string(),
                foundation_fix,
            )
            .and_then(|name| {
                self.choice(
                    "severity.foundation",
                    &name,
                    "foundation",
                    &[
                        ("rigid", Foundation::Rigid),
                        ("flexible", Foundation::Flexible),
                    ],
                    foundation_fix,
                )
            });
        Some(SeveritySettings {
            group: group?,
            foundation: foundation?,
        })
    }
}
