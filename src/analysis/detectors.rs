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
use super::velocity::VelocityDetector;

/// Which detectors run, with their settings.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DetectorSettings {
    /// The ISO 10816-3 / 20816-3 velocity zones. Configured by the top-level `[severity]`
    /// (older than this list, and always on in the daemon), so not a `[detectors]` section.
    #[serde(skip)]
    pub severity: Option<SeveritySettings>,
}

impl DetectorSettings {
    /// The detectors of one channel.
    pub fn build(&self, context: &mut ChannelContext<'_>) -> Vec<Box<dyn ChannelDetector>> {
        let mut detectors: Vec<Box<dyn ChannelDetector>> = Vec::new();
        if let Some(severity) = self.severity {
            detectors.push(Box::new(VelocityDetector::new(severity, context)));
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
        DetectorSettings::default()
    }

    /// What each detector that is on says of a whole record (`analyze`).
    pub fn analyze_record(&self, _record: &RecordView<'_>) -> Vec<RecordFindings> {
        Vec::new()
    }

    /// Every problem of the settings as `(key under [detectors], what is wrong and the fix)`.
    pub fn problems(&self) -> Vec<(String, String)> {
        Vec::new()
    }
}
