//! From the raw form to [`Config`]: every check, every problem collected.
//!
//! Each key is checked on its own first (type, range); a check that involves two keys runs
//! only when both passed, so that one mistake is reported once, not again as the cause of a
//! second. Each message ends with how to fix it; the hints live next to the checks.

mod analysis;
mod fleet;
mod outputs;
mod sensors;
mod severity;
mod thresholds;
mod transports;
mod twin;

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

use crate::analysis::{AnalysisSettings, BandSelection};
use crate::bearing::{BearingError, BearingGeometry};

use super::error::ConfigProblem;
use super::raw::{
    Field, Loose, RawAnalysis, RawCan, RawConfig, RawOutputs, RawSensor, RawSeverity, RawShm,
    RawSim, RawSpeed, RawThresholds, RawTwin,
};
use super::types::{
    CanConfig, Config, OutputConfig, SensorConfig, ShmConfig, SimConfig, SimFault, Speed,
    ThresholdConfig, Transport, TwinConfig, DEFAULT_AXIS, DEFAULT_BAND_PERIOD_S,
    DEFAULT_CAN_INTERFACE, DEFAULT_EVIDENCE_HORIZON_S, DEFAULT_MAX_RPM_FACTOR,
    DEFAULT_SCALE_G_PER_COUNT, DEFAULT_SPEED_SEARCH,
};

pub use fleet::{TLS_BUILT, TLS_NOT_BUILT};

/// Longest sensor id, in characters.
pub const MAX_ID_LEN: usize = 32;
/// Longest iceoryx2 root we accept, in bytes. iceoryx2 0.10 puts a subscriber's event
/// socket about 44 bytes plus its file prefix below the root, and a Unix socket path has at
/// most 108 bytes: roots of 64 bytes worked and 69 failed (measured); this leaves room for a
/// test's longer file prefix.
pub const MAX_IOX_ROOT_LEN: usize = 56;
/// Longest iceoryx2 service name we accept, in bytes.
const MAX_SERVICE_LEN: usize = 255;
/// The kernel's IFNAMSIZ (16) less the terminating NUL.
const MAX_CAN_INTERFACE_LEN: usize = 15;
/// One day, the longest period or delay that makes sense.
const DAY_S: f64 = 86_400.0;

pub(crate) fn validate(raw: &RawConfig) -> Result<Config, Vec<ConfigProblem>> {
    let mut check = Checker::default();
    let sensors = check.sensors(&raw.sensors);
    let analysis = check.analysis(&raw.analysis, &sensors);
    let twin = check.twin(&raw.twin, &sensors);
    let thresholds = check.thresholds(&raw.thresholds);
    let outputs = check.outputs(&raw.outputs, &sensors);
    let fleet = check.fleet(&raw.fleet, outputs.as_ref().map(|o| o.state_dir.as_path()));
    let severity = check.severity(&raw.severity);
    for (key, message) in raw.detectors.problems() {
        check.problem(format!("detectors.{key}"), message);
    }
    if let (Some((analysis, ..)), Some(twin)) = (&analysis, &twin) {
        if analysis.agreement.is_some() && twin.learned_model.is_none() {
            check.problem(
                "analysis.agreement_probability",
                "the learned model's agreement has no model to agree with; set \
                 twin.learned_model, e.g. learned_model = \
                 \"/usr/share/bearingd/models\", or remove the agreement_* keys",
            );
        }
    }

    let sensors: Option<Vec<SensorConfig>> = sensors.into_iter().map(|s| s.config).collect();
    match (
        sensors, analysis, twin, thresholds, outputs, fleet, severity,
    ) {
        (
            Some(sensors),
            Some((analysis, band_period_s, evidence_horizon_s)),
            Some(twin),
            Some(thresholds),
            Some(outputs),
            Some(fleet),
            Some(severity),
        ) if check.problems.is_empty() => Ok(Config {
            sensors,
            analysis,
            band_period_s,
            evidence_horizon_s,
            twin,
            thresholds,
            outputs,
            fleet,
            severity,
            detectors: raw.detectors.clone(),
        }),
        _ => {
            if check.problems.is_empty() {
                // Every failed check records a problem; this keeps the error non-empty should
                // one ever forget to.
                check.problem(
                    "",
                    "the configuration was refused without a recorded reason (a bug in \
                     bearingd); report it with this file",
                );
            }
            Err(check.problems)
        }
    }
}

/// Types a key may be expected to hold, named for messages.
trait Expected: Clone {
    const WHAT: &'static str;
}
impl Expected for f64 {
    const WHAT: &'static str = "a number";
}
impl Expected for i64 {
    const WHAT: &'static str = "a whole number";
}
impl Expected for bool {
    const WHAT: &'static str = "true or false";
}
impl Expected for String {
    const WHAT: &'static str = "a string in quotes";
}
impl Expected for Vec<String> {
    const WHAT: &'static str = "a list of strings";
}
impl Expected for Vec<f64> {
    const WHAT: &'static str = "a list of numbers";
}

/// What a key held.
enum Got<T> {
    Missing,
    /// Wrong type; already reported.
    Invalid,
    Value(T),
}

/// The allowed range of a number; `lo`/`hi` may be infinite.
#[derive(Clone, Copy)]
struct Limits {
    lo: f64,
    lo_open: bool,
    hi: f64,
    hi_open: bool,
}

impl Limits {
    /// `(lo, hi]`
    const fn above_to(lo: f64, hi: f64) -> Self {
        Limits {
            lo,
            lo_open: true,
            hi,
            hi_open: false,
        }
    }
    /// `[lo, hi]`
    const fn within(lo: f64, hi: f64) -> Self {
        Limits {
            lo,
            lo_open: false,
            hi,
            hi_open: false,
        }
    }
    /// `(lo, hi)`
    const fn between(lo: f64, hi: f64) -> Self {
        Limits {
            lo,
            lo_open: true,
            hi,
            hi_open: true,
        }
    }

    fn contains(&self, v: f64) -> bool {
        let above = if self.lo_open {
            v > self.lo
        } else {
            v >= self.lo
        };
        let below = if self.hi_open {
            v < self.hi
        } else {
            v <= self.hi
        };
        above && below
    }

    fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.lo.is_finite() {
            parts.push(if self.lo_open {
                format!("greater than {}", self.lo)
            } else {
                format!("at least {}", self.lo)
            });
        }
        if self.hi.is_finite() {
            parts.push(if self.hi_open {
                format!("less than {}", self.hi)
            } else {
                format!("at most {}", self.hi)
            });
        }
        parts.join(" and ")
    }
}

/// What the sensor checks leave for the checks of other sections.
struct CheckedSensor {
    /// Position in `sensors`.
    index: usize,
    /// `None` when any of its keys had a problem.
    config: Option<SensorConfig>,
    id: Option<String>,
    sample_rate_hz: Option<f64>,
    shm_service: Option<String>,
}

impl CheckedSensor {
    /// How messages name it: `sensor "motor-de" (sensors[0], <detail>)`, or
    /// `sensors[0] (<detail>)` when its id is unusable.
    fn named(&self, detail: &str) -> String {
        let index = self.index;
        match (&self.id, detail.is_empty()) {
            (Some(id), true) => format!("sensor {id:?} (sensors[{index}])"),
            (Some(id), false) => format!("sensor {id:?} (sensors[{index}], {detail})"),
            (None, true) => format!("sensors[{index}]"),
            (None, false) => format!("sensors[{index}] ({detail})"),
        }
    }

    /// The sample service it would get by default.
    fn default_service(&self) -> String {
        match &self.id {
            Some(id) => crate::iox::sensor_service(id),
            None => crate::iox::sensor_service("<id>"),
        }
    }
}

#[derive(Default)]
struct Checker {
    problems: Vec<ConfigProblem>,
}

impl Checker {
    fn problem(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.problems.push(ConfigProblem::new(key, message));
    }

    fn get<T: Expected>(&mut self, key: &str, field: &Field<T>, fix: &str) -> Got<T> {
        match field {
            None => Got::Missing,
            Some(Loose::Value(v)) => Got::Value(v.clone()),
            Some(Loose::WrongType { found }) => {
                self.problem(key, format!("expected {}, found {found}; {fix}", T::WHAT));
                Got::Invalid
            }
        }
    }

    /// The value, or the default when absent; `None` when it has the wrong type.
    fn or_default<T: Expected>(
        &mut self,
        key: &str,
        field: &Field<T>,
        default: T,
        fix: &str,
    ) -> Option<T> {
        match self.get(key, field, fix) {
            Got::Missing => Some(default),
            Got::Invalid => None,
            Got::Value(v) => Some(v),
        }
    }

    /// The value; `None` (and a problem) when absent or of the wrong type.
    fn required<T: Expected>(
        &mut self,
        key: &str,
        field: &Field<T>,
        why: &str,
        fix: &str,
    ) -> Option<T> {
        match self.get(key, field, fix) {
            Got::Missing => {
                self.problem(key, format!("missing{why}; {fix}"));
                None
            }
            Got::Invalid => None,
            Got::Value(v) => Some(v),
        }
    }

    /// Checks a number against its limits (NaN and infinities never pass).
    fn in_limits(&mut self, key: &str, value: f64, limits: Limits, fix: &str) -> Option<f64> {
        if !value.is_finite() {
            self.problem(key, format!("{value} is not a finite number; {fix}"));
            None
        } else if !limits.contains(value) {
            self.problem(
                key,
                format!(
                    "{value} is out of range: it must be {}; {fix}",
                    limits.describe()
                ),
            );
            None
        } else {
            Some(value)
        }
    }

    /// A number with a default.
    fn number(
        &mut self,
        key: &str,
        field: &Field<f64>,
        default: f64,
        limits: Limits,
        fix: &str,
    ) -> Option<f64> {
        let value = self.or_default(key, field, default, fix)?;
        self.in_limits(key, value, limits, fix)
    }

    /// A whole number with a default, in `lo..=hi`.
    fn integer(
        &mut self,
        key: &str,
        field: &Field<i64>,
        default: i64,
        lo: i64,
        hi: i64,
        fix: &str,
    ) -> Option<i64> {
        let value = self.or_default(key, field, default, fix)?;
        self.integer_in(key, value, lo, hi, fix)
    }

    fn integer_in(&mut self, key: &str, value: i64, lo: i64, hi: i64, fix: &str) -> Option<i64> {
        if (lo..=hi).contains(&value) {
            Some(value)
        } else {
            self.problem(
                key,
                format!(
                    "{value} is out of range: it must be at least {lo} and at most {hi}; {fix}"
                ),
            );
            None
        }
    }

    /// One of a fixed set of words.
    fn choice<T: Copy>(
        &mut self,
        key: &str,
        value: &str,
        what: &str,
        choices: &[(&str, T)],
        fix: &str,
    ) -> Option<T> {
        let found = choices
            .iter()
            .find(|(name, _)| *name == value)
            .map(|(_, choice)| *choice);
        if found.is_none() {
            self.problem(key, format!("unknown {what} {value:?}; {fix}"));
        }
        found
    }

    // ----------------------------------------------------------------------------- sensors
}

/// The transports, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Sim,
    Can,
    Shm,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Sim => "sim",
            Kind::Can => "can",
            Kind::Shm => "shm",
        }
    }

    fn purpose(self) -> &'static str {
        match self {
            Kind::Sim => "configures the simulated sensor",
            Kind::Can => "configures the CAN bus and node",
            Kind::Shm => "configures the iceoryx2 sample service",
        }
    }
}

/// The simulated faults, by name.
const SIM_FAULTS: &[(&str, SimFault)] = &[
    ("none", SimFault::None),
    ("outer", SimFault::Outer),
    ("inner", SimFault::Inner),
    ("ball", SimFault::Ball),
];

/// The name of `value` in a table of choices.
fn name_of<T: PartialEq>(choices: &[(&'static str, T)], value: T) -> &'static str {
    choices
        .iter()
        .find(|(_, choice)| *choice == value)
        .map_or("", |(name, _)| name)
}

fn is_name_char(c: char) -> bool {
    c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_'
}

/// A round upper band edge a little below the Nyquist frequency and above `lo`.
fn suggest_below(lo: f64, nyquist: f64) -> f64 {
    let edge = (nyquist * 0.8 / 100.0).floor() * 100.0;
    if edge > lo {
        edge
    } else {
        (lo + nyquist) / 2.0
    }
}
