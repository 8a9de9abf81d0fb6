//! The one list of the detectors the channel monitor runs besides the bearing-fault scores:
//! their settings (`None`: off), how each is built and how its settings are checked. A new
//! detector adds a field here and a line in [`DetectorSettings::build`] and
//! [`DetectorSettings::problems`]; its records go in `messages::detect`'s list.
//!
//! Config: each field is the section `[detectors.<field>]` of the daemon's file, read by serde
//! (unknown keys and wrong types are reported by `config` with the rest); a section present
//! (even empty) turns its detector on with the defaults of the keys it leaves out.

use serde::{Deserialize, Serialize};

use super::detect::{ChannelContext, ChannelDetector, RecordFindings, RecordView};
use super::iso::SeveritySettings;
use super::machine::{MachineDetector, MachineFaultSettings};
use super::velocity::VelocityDetector;

/// Which detectors run, with their settings.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DetectorSettings {
    /// The ISO 10816-3 / 20816-3 velocity zones. Configured by the top-level `[severity]`
    /// (older than this list, and always on in the daemon), so not a `[detectors]` section.
    #[serde(skip)]
    pub severity: Option<SeveritySettings>,
    /// Unbalance, misalignment and looseness at shaft orders ([`super::machine`]).
    pub machine_faults: Option<MachineFaultSettings>,
}

impl DetectorSettings {
    /// The detectors of one channel.
    pub fn build(&self, context: &mut ChannelContext<'_>) -> Vec<Box<dyn ChannelDetector>> {
        let mut detectors: Vec<Box<dyn ChannelDetector>> = Vec::new();
        if let Some(severity) = self.severity {
            detectors.push(Box::new(VelocityDetector::new(severity, context)));
        }
        if let Some(machine) = self.machine_faults {
            let severity = self.severity.unwrap_or_default();
            detectors.push(Box::new(MachineDetector::new(machine, severity, context)));
        }
        detectors
    }

    /// The same with the velocity zones judged for `severity` (the daemon's `[severity]`, or
    /// `analyze --machine-group/--foundation`).
    pub fn with_severity(mut self, severity: SeveritySettings) -> DetectorSettings {
        self.severity = Some(severity);
        self
    }

    /// Every detector that judges whole records on, with its defaults: what `analyze` runs.
    pub fn for_records() -> DetectorSettings {
        DetectorSettings {
            machine_faults: Some(MachineFaultSettings::default()),
            ..DetectorSettings::default()
        }
    }

    /// What each detector that is on says of a whole record (`analyze`).
    pub fn analyze_record(&self, record: &RecordView<'_>) -> Vec<RecordFindings> {
        let severity = self.severity.unwrap_or_default();
        let mut found = Vec::new();
        if let Some(machine) = &self.machine_faults {
            found.push(machine.analyze_record(record, &severity));
        }
        found
    }

    /// Every problem of the settings as `(key under [detectors], what is wrong and the fix)`.
    pub fn problems(&self) -> Vec<(String, String)> {
        let mut problems = Vec::new();
        let mut section = |name: &str, found: Vec<(&'static str, String)>| {
            problems.extend(
                found
                    .into_iter()
                    .map(|(key, problem)| (format!("{name}.{key}"), problem)),
            )
        };
        if let Some(machine) = &self.machine_faults {
            section("machine_faults", machine.problems());
        }
        problems
    }
}
