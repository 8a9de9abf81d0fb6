//! From the raw form to [`Config`]: every check, every problem collected.
//!
//! Each key is checked on its own first (type, range); a check that involves two keys runs
//! only when both passed, so that one mistake is reported once, not again as the cause of a
//! second. Each message ends with how to fix it; the hints live next to the checks.

use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

use crate::analysis::{AnalysisSettings, BandSelection};
use crate::bearing::{BearingError, BearingGeometry};

use super::error::ConfigProblem;
use super::raw::{
    Field, Loose, RawAnalysis, RawCan, RawConfig, RawOutputs, RawSensor, RawShm, RawSim, RawSpeed,
    RawThresholds, RawTwin,
};
use super::types::{
    CanConfig, Config, OutputConfig, SensorConfig, ShmConfig, SimConfig, SimFault, Speed,
    ThresholdConfig, Transport, TwinConfig, DEFAULT_AXIS, DEFAULT_BAND_PERIOD_S,
    DEFAULT_CAN_INTERFACE, DEFAULT_MAX_RPM_FACTOR, DEFAULT_SCALE_G_PER_COUNT, DEFAULT_SPEED_SEARCH,
};

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
    let twin = check.twin(&raw.twin);
    let thresholds = check.thresholds(&raw.thresholds);
    let outputs = check.outputs(&raw.outputs, &sensors);
    let fleet = check.fleet(&raw.fleet, outputs.as_ref().map(|o| o.state_dir.as_path()));

    let sensors: Option<Vec<SensorConfig>> = sensors.into_iter().map(|s| s.config).collect();
    match (sensors, analysis, twin, thresholds, outputs, fleet) {
        (
            Some(sensors),
            Some((analysis, band_period_s)),
            Some(twin),
            Some(thresholds),
            Some(outputs),
            Some(fleet),
        ) if check.problems.is_empty() => Ok(Config {
            sensors,
            analysis,
            band_period_s,
            twin,
            thresholds,
            outputs,
            fleet,
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
pub(super) trait Expected: Clone {
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
pub(super) enum Got<T> {
    Missing,
    /// Wrong type; already reported.
    Invalid,
    Value(T),
}

/// The allowed range of a number; `lo`/`hi` may be infinite.
#[derive(Clone, Copy)]
pub(super) struct Limits {
    lo: f64,
    lo_open: bool,
    hi: f64,
    hi_open: bool,
}

impl Limits {
    /// `(lo, hi]`
    pub(super) const fn above_to(lo: f64, hi: f64) -> Self {
        Limits {
            lo,
            lo_open: true,
            hi,
            hi_open: false,
        }
    }
    /// `[lo, hi]`
    pub(super) const fn within(lo: f64, hi: f64) -> Self {
        Limits {
            lo,
            lo_open: false,
            hi,
            hi_open: false,
        }
    }
    /// `(lo, hi)`
    pub(super) const fn between(lo: f64, hi: f64) -> Self {
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
            Some(id) => format!("bearingd/accel/{id}"),
            None => "bearingd/accel/<id>".to_string(),
        }
    }
}

#[derive(Default)]
pub(super) struct Checker {
    pub(super) problems: Vec<ConfigProblem>,
}

impl Checker {
    pub(super) fn problem(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.problems.push(ConfigProblem::new(key, message));
    }

    pub(super) fn get<T: Expected>(&mut self, key: &str, field: &Field<T>, fix: &str) -> Got<T> {
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
    pub(super) fn or_default<T: Expected>(
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
    pub(super) fn in_limits(
        &mut self,
        key: &str,
        value: f64,
        limits: Limits,
        fix: &str,
    ) -> Option<f64> {
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
    pub(super) fn number(
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

    fn sensors(&mut self, raw: &[RawSensor]) -> Vec<CheckedSensor> {
        if raw.is_empty() {
            self.problem(
                "sensors",
                "no sensor is configured; add a [[sensors]] section with at least id, \
                 transport, sample_rate_hz, bearing and [sensors.speed] rpm, e.g. the one in \
                 config/bearingd.toml (`bearingd run` without --config runs it)",
            );
        }
        let checked: Vec<CheckedSensor> = raw
            .iter()
            .enumerate()
            .map(|(i, sensor)| self.sensor(i, sensor))
            .collect();
        self.unique_sensor_ids(&checked);
        self.unique_can_nodes(&checked);
        self.unique_shm_services(&checked);
        checked
    }

    fn sensor(&mut self, i: usize, raw: &RawSensor) -> CheckedSensor {
        let at = |key: &str| format!("sensors[{i}].{key}");

        let id = self.sensor_id(&at("id"), &raw.id);
        let transport_fix = "use \"sim\", \"can\" or \"shm\", e.g. transport = \"can\"";
        let kind = self
            .required(
                &at("transport"),
                &raw.transport,
                " (how the samples arrive)",
                transport_fix,
            )
            .and_then(|name| {
                self.choice(
                    &at("transport"),
                    &name,
                    "transport",
                    &[("sim", Kind::Sim), ("can", Kind::Can), ("shm", Kind::Shm)],
                    transport_fix,
                )
            });

        let sample_rate_hz = self.sample_rate(&at("sample_rate_hz"), &raw.sample_rate_hz);

        let scale_g_per_count = self.number(
            &at("scale_g_per_count"),
            &raw.scale_g_per_count,
            DEFAULT_SCALE_G_PER_COUNT,
            Limits::above_to(0.0, 1000.0),
            "give the acceleration in g of one count on the wire, e.g. 0.000488 for ±16 g over \
             16 bits",
        );

        let axes = self.axes(&at("axes"), &raw.axes);

        let bearing = self.bearing(&at("bearing"), &raw.bearing);

        let speed = self.speed(&at("speed"), raw.speed.as_ref(), kind);

        let transport = match kind {
            Some(kind) => self.transport(i, kind, id.as_deref(), raw),
            None => {
                // The transport is unusable; still check whatever transport tables are there,
                // so that their mistakes surface in this round too.
                if let Some(sim) = &raw.sim {
                    self.sim(&at("sim"), Some(sim));
                }
                if let Some(can) = &raw.can {
                    self.can(&at("can"), can);
                }
                if raw.shm.is_some() {
                    self.shm(&at("shm"), id.as_deref(), raw.shm.as_ref());
                }
                None
            }
        };
        let shm_service = match &transport {
            Some(Transport::Shm(shm)) => Some(shm.service.clone()),
            _ => None,
        };

        let config = (|| {
            Some(SensorConfig {
                id: id.clone()?,
                transport: transport?,
                sample_rate_hz: sample_rate_hz?,
                scale_g_per_count: scale_g_per_count?,
                axes: axes?,
                bearing: bearing?,
                speed: speed?,
            })
        })();
        CheckedSensor {
            index: i,
            config,
            id,
            sample_rate_hz,
            shm_service,
        }
    }

    fn sensor_id(&mut self, key: &str, field: &Field<String>) -> Option<String> {
        let fix = "give a short name of lowercase letters, digits, '-' and '_', e.g. id = \
                   \"motor-de\"";
        let id = self.required(
            key,
            field,
            " (it names the sensor's MCAP channels and iceoryx2 services)",
            fix,
        )?;
        let length = id.chars().count();
        if id.is_empty() {
            self.problem(key, format!("the id is empty; {fix}"));
            None
        } else if length > MAX_ID_LEN {
            self.problem(
                key,
                format!("{id:?} has {length} characters, more than {MAX_ID_LEN}; {fix}"),
            );
            None
        } else if !id.chars().all(is_name_char) {
            self.problem(
                key,
                format!(
                    "{id:?} contains characters other than a-z, 0-9, '-' and '_' (the id is \
                     used in MCAP channel and iceoryx2 service names); {fix}"
                ),
            );
            None
        } else {
            Some(id)
        }
    }

    fn sample_rate(&mut self, key: &str, field: &Field<f64>) -> Option<f64> {
        let fix = "give the sensor's sample rate in Hz, e.g. 25600";
        let rate = self.required(
            key,
            field,
            " (a wrong rate shifts every fault frequency, so there is no default)",
            fix,
        )?;
        if !rate.is_finite() || rate <= 0.0 {
            self.problem(key, format!("{rate} is not a sample rate; {fix}"));
            None
        } else if rate > 1_000_000.0 {
            self.problem(
                key,
                format!("{rate} Hz is above the limit of 1000000 Hz; {fix}"),
            );
            None
        } else {
            Some(rate)
        }
    }

    fn axes(&mut self, key: &str, field: &Field<Vec<String>>) -> Option<Vec<String>> {
        let fix = "give 1 to 3 distinct axis names of lowercase letters, digits, '-' and '_', \
                   e.g. axes = [\"radial\"] or axes = [\"x\", \"y\", \"z\"]";
        let axes = self.or_default(key, field, vec![DEFAULT_AXIS.to_string()], fix)?;
        let mut ok = true;
        if axes.is_empty() || axes.len() > 3 {
            self.problem(
                key,
                format!("{} axes given, but a sensor has 1 to 3; {fix}", axes.len()),
            );
            ok = false;
        }
        for (j, axis) in axes.iter().enumerate() {
            if axis.is_empty()
                || axis.chars().count() > MAX_ID_LEN
                || !axis.chars().all(is_name_char)
            {
                self.problem(
                    format!("{key}[{j}]"),
                    format!(
                        "{axis:?} is not an axis name (1 to {MAX_ID_LEN} of a-z, 0-9, '-', '_'); \
                         {fix}"
                    ),
                );
                ok = false;
            } else if let Some(first) = axes[..j].iter().position(|a| a == axis) {
                self.problem(
                    format!("{key}[{j}]"),
                    format!("{axis:?} is already {key}[{first}]; {fix}"),
                );
                ok = false;
            }
        }
        ok.then_some(axes)
    }

    fn bearing(&mut self, key: &str, field: &Field<String>) -> Option<BearingGeometry> {
        let example = "\"z=9,d=7.94mm,D=39.04mm,alpha=0\"";
        let catalog = BearingGeometry::catalog_names().join(", ");
        let fix =
            format!("use a catalog name ({catalog}) or custom geometry, e.g. bearing = {example}");
        let text = self.required(
            key,
            field,
            " (its geometry sets the fault frequencies)",
            &fix,
        )?;
        match BearingGeometry::parse(&text) {
            Ok(geometry) => Some(geometry),
            Err(BearingError::UnknownName { name, .. }) => {
                self.problem(key, format!("unknown bearing {name:?}; {fix}"));
                None
            }
            Err(BearingError::BadGeometry { text, problem }) => {
                self.problem(
                    key,
                    format!(
                        "bad custom geometry {text:?}: {problem}; give z (rolling elements), \
                         d and D (element and pitch diameters, mm or in) and alpha (contact \
                         angle, degrees), e.g. bearing = {example}"
                    ),
                );
                None
            }
        }
    }

    fn speed(&mut self, key: &str, raw: Option<&RawSpeed>, kind: Option<Kind>) -> Option<Speed> {
        let rpm_key = format!("{key}.rpm");
        let rpm_fix = "give the shaft speed in revolutions per minute under [sensors.speed], \
                       e.g. rpm = 1772";
        let Some(raw) = raw else {
            self.problem(
                rpm_key,
                format!(
                    "missing (the fault frequencies scale with the shaft speed, so there is no \
                     default); {rpm_fix}"
                ),
            );
            return None;
        };
        let source_key = format!("{key}.source");
        let source_fix = "use source = \"fixed\" with rpm = the shaft speed, \"can\" for the \
                          sensor's speed frames, or \"estimate\" with rpm = the nominal speed";
        let source = self.or_default(&source_key, &raw.source, "fixed".to_string(), source_fix)?;
        let speed_limits = Limits::between(0.0, 100_000.0);
        // A key the chosen source does not read would be silently ignored: refuse it.
        let unused = |check: &mut Self, name: &str, present: bool, readers: &str| {
            if present {
                check.problem(
                    format!("{key}.{name}"),
                    format!(
                        "{name} is read only with {readers}, so with source = {source:?} it \
                         would be ignored; remove it or change the source"
                    ),
                );
            }
        };
        match source.as_str() {
            "fixed" => {
                unused(self, "max_rpm", raw.max_rpm.is_some(), "source = \"can\"");
                unused(
                    self,
                    "search",
                    raw.search.is_some(),
                    "source = \"estimate\"",
                );
                let rpm = self.required(
                    &rpm_key,
                    &raw.rpm,
                    " (source = \"fixed\" needs the speed)",
                    rpm_fix,
                )?;
                let rpm = self.in_limits(&rpm_key, rpm, speed_limits, rpm_fix)?;
                (raw.max_rpm.is_none() && raw.search.is_none()).then_some(Speed::Fixed { rpm })
            }
            "can" => {
                unused(
                    self,
                    "search",
                    raw.search.is_some(),
                    "source = \"estimate\"",
                );
                if kind == Some(Kind::Sim) {
                    self.problem(
                        &source_key,
                        "the simulated sensor (transport = \"sim\") sends no speed frames; use \
                         source = \"fixed\" or \"estimate\", or a \"can\" or \"shm\" sensor",
                    );
                }
                let nominal_fix = "give the speed to assume until the first speed frame, e.g. \
                                   rpm = 1772, or leave rpm out to score nothing until then";
                let nominal = match self.get(&rpm_key, &raw.rpm, nominal_fix) {
                    Got::Missing => Some(None),
                    Got::Invalid => None,
                    Got::Value(rpm) => self
                        .in_limits(&rpm_key, rpm, speed_limits, nominal_fix)
                        .map(Some),
                };
                let max_key = format!("{key}.max_rpm");
                let max_fix = "give the highest shaft speed the machine runs at, e.g. max_rpm = \
                               3600 (the envelope spectrum is sized for its fault harmonics)";
                let max_rpm = match (self.get(&max_key, &raw.max_rpm, max_fix), nominal) {
                    (Got::Value(max), _) => self.in_limits(&max_key, max, speed_limits, max_fix),
                    (Got::Missing, Some(Some(rpm))) => Some(rpm * DEFAULT_MAX_RPM_FACTOR),
                    (Got::Missing, Some(None)) => {
                        self.problem(
                            &max_key,
                            format!(
                                "missing: without a nominal rpm there is no default for the \
                                 highest speed; {max_fix}"
                            ),
                        );
                        None
                    }
                    _ => None,
                };
                let (nominal_rpm, max_rpm) = (nominal?, max_rpm?);
                if let Some(rpm) = nominal_rpm.filter(|&rpm| rpm >= max_rpm) {
                    self.problem(
                        &max_key,
                        format!(
                            "max_rpm {max_rpm} is not above the nominal rpm {rpm}; raise max_rpm \
                             or lower rpm"
                        ),
                    );
                    return None;
                }
                (kind != Some(Kind::Sim) && raw.search.is_none()).then_some(Speed::Frames {
                    nominal_rpm,
                    max_rpm,
                })
            }
            "estimate" => {
                unused(self, "max_rpm", raw.max_rpm.is_some(), "source = \"can\"");
                let rpm = self.required(
                    &rpm_key,
                    &raw.rpm,
                    " (source = \"estimate\" searches near the nominal speed)",
                    "give the nominal shaft speed in revolutions per minute, e.g. rpm = 1772",
                )?;
                let rpm = self.in_limits(&rpm_key, rpm, speed_limits, rpm_fix)?;
                let search = self.number(
                    &format!("{key}.search"),
                    &raw.search,
                    DEFAULT_SPEED_SEARCH,
                    Limits::above_to(0.0, 0.3),
                    "give the relative half-width of the search around rpm, e.g. search = 0.05 \
                     for ±5 %",
                )?;
                raw.max_rpm
                    .is_none()
                    .then_some(Speed::Estimate { rpm, search })
            }
            other => {
                self.problem(
                    source_key,
                    format!("unknown speed source {other:?}; {source_fix}"),
                );
                None
            }
        }
    }

    /// The transport and its table; tables of other transports are refused.
    fn transport(
        &mut self,
        i: usize,
        kind: Kind,
        id: Option<&str>,
        raw: &RawSensor,
    ) -> Option<Transport> {
        let present = [
            (Kind::Sim, raw.sim.is_some()),
            (Kind::Can, raw.can.is_some()),
            (Kind::Shm, raw.shm.is_some()),
        ];
        let mut misplaced = false;
        for (other, is_present) in present {
            if is_present && other != kind {
                self.problem(
                    format!("sensors[{i}].{}", other.name()),
                    format!(
                        "[sensors.{table}] {purpose}, but this sensor's transport is {kind:?}, \
                         so it would be ignored; remove [sensors.{table}] or set transport = \
                         \"{table}\"",
                        table = other.name(),
                        purpose = other.purpose(),
                        kind = kind.name(),
                    ),
                );
                misplaced = true;
            }
        }
        let transport = match kind {
            Kind::Sim => self
                .sim(&format!("sensors[{i}].sim"), raw.sim.as_ref())
                .map(Transport::Sim),
            Kind::Can => match &raw.can {
                Some(can) => self
                    .can(&format!("sensors[{i}].can"), can)
                    .map(Transport::Can),
                None => {
                    self.problem(
                        format!("sensors[{i}].can"),
                        "missing: transport = \"can\" needs to know which bus and node to \
                         listen to; add a [sensors.can] section after this sensor's lines, \
                         e.g. interface = \"can0\" and node_id = 1",
                    );
                    None
                }
            },
            Kind::Shm => self
                .shm(&format!("sensors[{i}].shm"), id, raw.shm.as_ref())
                .map(Transport::Shm),
        };
        if misplaced {
            None
        } else {
            transport
        }
    }

    fn can(&mut self, key: &str, raw: &RawCan) -> Option<CanConfig> {
        let interface_key = format!("{key}.interface");
        let interface_fix = "give the SocketCAN interface name, e.g. interface = \"can0\" (or \
                             \"vcan0\" for a virtual bus)";
        let interface = self
            .or_default(
                &interface_key,
                &raw.interface,
                DEFAULT_CAN_INTERFACE.to_string(),
                interface_fix,
            )
            .and_then(|name| {
                let fine = !name.is_empty()
                    && name.len() <= MAX_CAN_INTERFACE_LEN
                    && name != "."
                    && name != ".."
                    && !name.contains(['/', ':'])
                    && !name.chars().any(|c| c.is_whitespace() || c.is_control());
                if fine {
                    Some(name)
                } else {
                    self.problem(
                        &interface_key,
                        format!(
                            "{name:?} is not a network interface name (1 to \
                             {MAX_CAN_INTERFACE_LEN} bytes, no '/', ':' or spaces); \
                             {interface_fix}"
                        ),
                    );
                    None
                }
            });

        let node_key = format!("{key}.node_id");
        let node_fix = "give the sensor node's id on the bus, 0 to 15, e.g. node_id = 1";
        let node_id = self
            .required(
                &node_key,
                &raw.node_id,
                " (nodes on one bus must differ, so there is no default)",
                node_fix,
            )
            .and_then(|n| self.integer_in(&node_key, n, 0, 15, node_fix))
            .and_then(|n| u8::try_from(n).ok());

        let fd = self.or_default(
            &format!("{key}.fd"),
            &raw.fd,
            false,
            "use fd = true for CAN FD frames or fd = false for classic CAN",
        );
        Some(CanConfig {
            interface: interface?,
            node_id: node_id?,
            fd: fd?,
        })
    }

    fn shm(&mut self, key: &str, id: Option<&str>, raw: Option<&RawShm>) -> Option<ShmConfig> {
        let service_key = format!("{key}.service");
        let fix = "give an iceoryx2 service name under bearingd/, e.g. service = \
                   \"bearingd/accel/motor-de\", or leave it out for bearingd/accel/<id>";
        let field = raw.and_then(|raw| raw.service.clone());
        let service = match self.get(&service_key, &field, fix) {
            Got::Missing => format!("bearingd/accel/{}", id?),
            Got::Invalid => return None,
            Got::Value(service) => service,
        };
        self.service_name(&service_key, service, fix)
            .map(|service| ShmConfig { service })
    }

    fn sim(&mut self, key: &str, raw: Option<&RawSim>) -> Option<SimConfig> {
        let defaults = SimConfig::default();
        let empty = RawSim::default();
        let raw = raw.unwrap_or(&empty);
        let fault_key = format!("{key}.fault");
        let fault_fix = "use \"none\", \"outer\", \"inner\" or \"ball\", e.g. fault = \"outer\"";
        let fault = self
            .or_default(
                &fault_key,
                &raw.fault,
                name_of(SIM_FAULTS, defaults.fault).to_string(),
                fault_fix,
            )
            .and_then(|name| {
                self.choice(&fault_key, &name, "simulated fault", SIM_FAULTS, fault_fix)
            });
        let onset_s = self.number(
            &format!("{key}.onset_s"),
            &raw.onset_s,
            defaults.onset_s,
            Limits::within(0.0, f64::INFINITY),
            "give the sample time, in seconds from the start, at which the fault appears, \
             e.g. onset_s = 30.0",
        );
        let severity = self.number(
            &format!("{key}.severity"),
            &raw.severity,
            defaults.severity,
            Limits::within(0.0, 100.0),
            "give the impact amplitude relative to the nominal fault, e.g. severity = 1.0 \
             (0 = no impacts)",
        );
        let noise_g = self.number(
            &format!("{key}.noise_g"),
            &raw.noise_g,
            defaults.noise_g,
            Limits::within(0.0, 100.0),
            "give the standard deviation of the added noise in g, e.g. noise_g = 0.05",
        );
        let seed_fix = "give a whole number of 0 or more, e.g. seed = 1";
        let seed = self
            .integer(
                &format!("{key}.seed"),
                &raw.seed,
                i64::try_from(defaults.seed).unwrap_or(i64::MAX),
                0,
                i64::MAX,
                seed_fix,
            )
            .and_then(|s| u64::try_from(s).ok());
        Some(SimConfig {
            fault: fault?,
            onset_s: onset_s?,
            severity: severity?,
            noise_g: noise_g?,
            seed: seed?,
        })
    }

    /// iceoryx2 service names: under `bearingd/`, segments of `[A-Za-z0-9_.-]`.
    fn service_name(&mut self, key: &str, service: String, fix: &str) -> Option<String> {
        let why = if !service.starts_with("bearingd/") {
            Some("does not start with bearingd/ (every bearingd service lives there)")
        } else if service.len() > MAX_SERVICE_LEN {
            Some("is longer than 255 bytes")
        } else if service.split('/').any(str::is_empty) {
            Some("has an empty segment (a doubled or trailing '/')")
        } else if !service
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.-/".contains(c))
        {
            Some("contains characters other than A-Z, a-z, 0-9, '_', '.', '-' and '/'")
        } else {
            None
        };
        match why {
            Some(why) => {
                self.problem(key, format!("{service:?} {why}; {fix}"));
                None
            }
            None => Some(service),
        }
    }

    fn unique_sensor_ids(&mut self, sensors: &[CheckedSensor]) {
        let mut first: HashMap<&str, usize> = HashMap::new();
        for (i, sensor) in sensors.iter().enumerate() {
            let Some(id) = sensor.id.as_deref() else {
                continue;
            };
            match first.get(id) {
                Some(&earlier) => self.problem(
                    format!("sensors[{i}].id"),
                    format!(
                        "{id:?} is also the id of sensors[{earlier}]; give each sensor its own \
                         id, e.g. id = \"{id}-2\""
                    ),
                ),
                None => {
                    first.insert(id, i);
                }
            }
        }
    }

    fn unique_can_nodes(&mut self, sensors: &[CheckedSensor]) {
        let mut first: HashMap<(&str, u8), usize> = HashMap::new();
        for (i, sensor) in sensors.iter().enumerate() {
            let Some(Transport::Can(can)) = sensor.config.as_ref().map(|c| &c.transport) else {
                continue;
            };
            match first.get(&(can.interface.as_str(), can.node_id)) {
                Some(&earlier) => self.problem(
                    format!("sensors[{i}].can.node_id"),
                    format!(
                        "node {} on {} is also sensors[{earlier}]'s node, and their frames \
                         could not be told apart; give each sensor on one bus its own node_id",
                        can.node_id, can.interface
                    ),
                ),
                None => {
                    first.insert((can.interface.as_str(), can.node_id), i);
                }
            }
        }
    }

    fn unique_shm_services(&mut self, sensors: &[CheckedSensor]) {
        let mut first: HashMap<&str, usize> = HashMap::new();
        for (i, sensor) in sensors.iter().enumerate() {
            let Some(service) = sensor.shm_service.as_deref() else {
                continue;
            };
            match first.get(service) {
                Some(&earlier) => self.problem(
                    format!("sensors[{i}].shm.service"),
                    format!(
                        "{service:?} is also sensors[{earlier}]'s service, so their samples \
                         would mix; give each sensor its own service, e.g. service = {:?}",
                        if sensor.default_service() == service {
                            format!("{service}-2")
                        } else {
                            sensor.default_service()
                        }
                    ),
                ),
                None => {
                    first.insert(service, i);
                }
            }
        }
    }

    // ---------------------------------------------------------------------------- analysis

    fn analysis(
        &mut self,
        raw: &RawAnalysis,
        sensors: &[CheckedSensor],
    ) -> Option<(AnalysisSettings, f64)> {
        let d = AnalysisSettings::default();
        let window_s = self.number(
            "analysis.window_s",
            &raw.window_s,
            d.window_s,
            Limits::above_to(0.05, 10.0),
            "give the envelope-spectrum window length in seconds, e.g. window_s = 1.0",
        );
        let overlap = self.number(
            "analysis.overlap",
            &raw.overlap,
            d.overlap,
            Limits::within(0.0, 0.9),
            "give the overlap of successive windows as a fraction, e.g. overlap = 0.5 for 50 %",
        );
        let averages = self
            .integer(
                "analysis.averages",
                &raw.averages,
                i64::try_from(d.averages).unwrap_or(8),
                1,
                64,
                "give how many window spectra are averaged, e.g. averages = 8",
            )
            .and_then(|n| usize::try_from(n).ok());
        let band_selection = self.band_selection(raw, sensors);
        let refine_band_by_snr = self.or_default(
            "analysis.refine_band_by_snr",
            &raw.refine_band_by_snr,
            d.refine_band_by_snr,
            "use true to refine the band by fault-band SNR, or false to keep the first choice",
        );
        let band_period_s = self.number(
            "analysis.band_period_s",
            &raw.band_period_s,
            DEFAULT_BAND_PERIOD_S,
            Limits::above_to(0.0, DAY_S),
            "give how often the band is chosen again, in seconds, e.g. band_period_s = 20.0",
        );
        let min_band_hz = self.min_band(&raw.min_band_hz, sensors);
        let fault_tolerance = self.number(
            "analysis.fault_tolerance",
            &raw.fault_tolerance,
            d.fault_tolerance,
            Limits::above_to(0.0, 0.1),
            "give the relative search tolerance around each fault frequency, e.g. \
             fault_tolerance = 0.02 for ±2 %",
        );
        let harmonics = self
            .integer(
                "analysis.harmonics",
                &raw.harmonics,
                i64::try_from(d.harmonics).unwrap_or(3),
                1,
                10,
                "give how many harmonics of each fault frequency count, e.g. harmonics = 3",
            )
            .and_then(|n| usize::try_from(n).ok());
        let min_fault_score = self.number(
            "analysis.min_fault_score",
            &raw.min_fault_score,
            d.min_fault_score,
            Limits::above_to(0.0, f64::INFINITY),
            "give the smallest fault score that makes a diagnosis, e.g. min_fault_score = 15.0",
        );
        let min_score_ratio = self.number(
            "analysis.min_score_ratio",
            &raw.min_score_ratio,
            d.min_score_ratio,
            Limits::within(1.0, f64::INFINITY),
            "give how many times the best fault score must exceed the runner-up, at least 1, \
             e.g. min_score_ratio = 2.0",
        );
        Some((
            AnalysisSettings {
                window_s: window_s?,
                overlap: overlap?,
                averages: averages?,
                band_selection: band_selection?,
                refine_band_by_snr: refine_band_by_snr?,
                min_band_hz: min_band_hz?,
                fault_tolerance: fault_tolerance?,
                harmonics: harmonics?,
                min_fault_score: min_fault_score?,
                min_score_ratio: min_score_ratio?,
            },
            band_period_s?,
        ))
    }

    fn band_selection(
        &mut self,
        raw: &RawAnalysis,
        sensors: &[CheckedSensor],
    ) -> Option<BandSelection> {
        let key = "analysis.band_selection";
        let fix = "use \"kurtogram\", \"gk\" or \"fixed\", e.g. band_selection = \"gk\"";
        #[derive(Clone, Copy, PartialEq)]
        enum Method {
            Kurtogram,
            Gk,
            Fixed,
        }
        let method = self
            .or_default(
                key,
                &raw.band_selection,
                match AnalysisSettings::default().band_selection {
                    BandSelection::Kurtogram => "kurtogram",
                    BandSelection::GiniKurtosis => "gk",
                    BandSelection::Fixed { .. } => "fixed",
                }
                .to_string(),
                fix,
            )
            .and_then(|name| {
                self.choice(
                    key,
                    &name,
                    "band selection",
                    &[
                        ("kurtogram", Method::Kurtogram),
                        ("gk", Method::Gk),
                        ("fixed", Method::Fixed),
                    ],
                    fix,
                )
            });

        let band_key = "analysis.band_hz";
        let band_fix = "give [low, high] in Hz with low < high, e.g. band_hz = [2000.0, 4000.0]";
        let band = match self.get(band_key, &raw.band_hz, band_fix) {
            Got::Missing => None,
            Got::Invalid => return None,
            Got::Value(band) => Some(band),
        };
        match (method?, band) {
            (Method::Kurtogram, None) => Some(BandSelection::Kurtogram),
            (Method::Gk, None) => Some(BandSelection::GiniKurtosis),
            (Method::Kurtogram | Method::Gk, Some(_)) => {
                self.problem(
                    band_key,
                    "band_hz is only used with band_selection = \"fixed\", and this file \
                     chooses the band automatically; remove band_hz, or set band_selection = \
                     \"fixed\" to use it",
                );
                None
            }
            (Method::Fixed, None) => {
                self.problem(
                    band_key,
                    format!("missing: band_selection = \"fixed\" needs the band; {band_fix}"),
                );
                None
            }
            (Method::Fixed, Some(band)) => {
                let (lo_hz, hi_hz) = self.fixed_band(band_key, &band, band_fix, sensors)?;
                Some(BandSelection::Fixed { lo_hz, hi_hz })
            }
        }
    }

    fn fixed_band(
        &mut self,
        key: &str,
        band: &[f64],
        fix: &str,
        sensors: &[CheckedSensor],
    ) -> Option<(f64, f64)> {
        let &[lo, hi] = band else {
            self.problem(
                key,
                format!(
                    "has {} numbers, not 2 (low and high edge); {fix}",
                    band.len()
                ),
            );
            return None;
        };
        if !lo.is_finite() || !hi.is_finite() {
            self.problem(key, format!("[{lo}, {hi}] has a non-finite edge; {fix}"));
            return None;
        }
        if lo < 0.0 || lo >= hi {
            self.problem(
                key,
                format!("[{lo}, {hi}] is not a band: it needs 0 <= low < high; {fix}"),
            );
            return None;
        }
        let mut below_nyquist = true;
        for sensor in sensors {
            let Some(rate) = sensor.sample_rate_hz else {
                continue;
            };
            let nyquist = rate / 2.0;
            if hi >= nyquist {
                self.problem(
                    key,
                    format!(
                        "the upper edge {hi} Hz is not below the Nyquist frequency {nyquist} Hz \
                         of {}; lower it below {nyquist} Hz, e.g. band_hz = [{lo}, {}]",
                        sensor.named(&format!("sampled at {rate} Hz")),
                        suggest_below(lo, nyquist),
                    ),
                );
                below_nyquist = false;
            }
        }
        below_nyquist.then_some((lo, hi))
    }

    fn min_band(&mut self, field: &Field<f64>, sensors: &[CheckedSensor]) -> Option<Option<f64>> {
        let key = "analysis.min_band_hz";
        let fix = "give the narrowest band the kurtogram may choose, in Hz, e.g. min_band_hz = \
                   600.0, or leave it out for three times the highest fault frequency";
        let value = match self.get(key, field, fix) {
            Got::Missing => return Some(None),
            Got::Invalid => return None,
            Got::Value(v) => v,
        };
        let value = self.in_limits(key, value, Limits::above_to(0.0, f64::INFINITY), fix)?;
        let mut fits = true;
        for sensor in sensors {
            let Some(rate) = sensor.sample_rate_hz else {
                continue;
            };
            let nyquist = rate / 2.0;
            if value >= nyquist {
                self.problem(
                    key,
                    format!(
                        "{value} Hz is not below the Nyquist frequency {nyquist} Hz of {}, so \
                         no band would fit; lower it below {nyquist} Hz or leave it out",
                        sensor.named(&format!("sampled at {rate} Hz"))
                    ),
                );
                fits = false;
            }
        }
        fits.then_some(Some(value))
    }

    // ------------------------------------------------------------------------ twin, flags

    fn twin(&mut self, raw: &RawTwin) -> Option<TwinConfig> {
        let d = TwinConfig::default();
        let refit_period_s = self.number(
            "twin.refit_period_s",
            &raw.refit_period_s,
            d.refit_period_s,
            Limits::above_to(0.0, DAY_S),
            "give the sample time between twin re-fits in seconds, e.g. refit_period_s = 10.0",
        );
        let window_s = self.number(
            "twin.window_s",
            &raw.window_s,
            d.window_s,
            Limits::above_to(0.05, 10.0),
            "give the length of signal each twin fit uses in seconds, e.g. window_s = 1.0",
        );
        Some(TwinConfig {
            refit_period_s: refit_period_s?,
            window_s: window_s?,
        })
    }

    fn thresholds(&mut self, raw: &RawThresholds) -> Option<ThresholdConfig> {
        let d = ThresholdConfig::default();
        let watch_score = self.number(
            "thresholds.watch_score",
            &raw.watch_score,
            d.watch_score,
            Limits::above_to(0.0, f64::INFINITY),
            "give the fault score at which a flag rises to watch, e.g. watch_score = 15.0",
        );
        let alarm_fix = "give the fault score at which a flag rises to alarm, above \
                         watch_score, e.g. alarm_score = 15.0";
        let alarm_score = self.number(
            "thresholds.alarm_score",
            &raw.alarm_score,
            d.alarm_score,
            Limits::above_to(0.0, f64::INFINITY),
            alarm_fix,
        );
        let alarm_score = match (watch_score, alarm_score) {
            (Some(watch), Some(alarm)) if alarm <= watch => {
                self.problem(
                    "thresholds.alarm_score",
                    format!(
                        "{alarm} is not above watch_score = {watch}, so a flag could never be \
                         in watch; raise alarm_score above {watch} or lower watch_score"
                    ),
                );
                None
            }
            (_, alarm) => alarm,
        };
        let clear_ratio = self.number(
            "thresholds.clear_ratio",
            &raw.clear_ratio,
            d.clear_ratio,
            Limits::between(0.0, 1.0),
            "give the fraction of its threshold below which a flag clears, between 0 and 1 \
             (exclusive), e.g. clear_ratio = 0.8",
        );
        let on_delay_s = self.number(
            "thresholds.on_delay_s",
            &raw.on_delay_s,
            d.on_delay_s,
            Limits::within(0.0, DAY_S),
            "give how long, in seconds, a score must stay above a threshold before the flag \
             rises, e.g. on_delay_s = 5.0",
        );
        let off_delay_s = self.number(
            "thresholds.off_delay_s",
            &raw.off_delay_s,
            d.off_delay_s,
            Limits::within(0.0, DAY_S),
            "give how long, in seconds, a score must stay below the clear level before the \
             flag falls, e.g. off_delay_s = 30.0",
        );
        let baseline_windows = self
            .integer(
                "thresholds.baseline_windows",
                &raw.baseline_windows,
                i64::try_from(d.baseline_windows).unwrap_or(30),
                5,
                100_000,
                "give how many analysis windows form the health baseline, at least 5, e.g. \
                 baseline_windows = 30",
            )
            .and_then(|n| usize::try_from(n).ok());
        let sigma = self.number(
            "thresholds.sigma",
            &raw.sigma,
            d.sigma,
            Limits::above_to(0.0, 100.0),
            "give how many standard deviations above the baseline mark a new health stage, \
             e.g. sigma = 3.0",
        );
        Some(ThresholdConfig {
            watch_score: watch_score?,
            alarm_score: alarm_score?,
            clear_ratio: clear_ratio?,
            on_delay_s: on_delay_s?,
            off_delay_s: off_delay_s?,
            baseline_windows: baseline_windows?,
            sigma: sigma?,
        })
    }

    // ------------------------------------------------------------------------------ outputs

    fn outputs(&mut self, raw: &RawOutputs, sensors: &[CheckedSensor]) -> Option<OutputConfig> {
        let d = OutputConfig::default();
        let state_dir = self.directory(
            "outputs.state_dir",
            &raw.state_dir,
            &d.state_dir,
            "give the directory for persistent state (baselines, band choices), e.g. \
             state_dir = \"/var/lib/bearingd\"",
        );
        let mcap_dir = self.directory(
            "outputs.mcap_dir",
            &raw.mcap_dir,
            &d.mcap_dir,
            "give the directory for MCAP log files, e.g. mcap_dir = \"/var/log/bearingd\"",
        );
        let max_mb = i64::try_from(d.mcap_max_file_mb).unwrap_or(256);
        let mcap_max_file_mb = self
            .integer(
                "outputs.mcap_max_file_mb",
                &raw.mcap_max_file_mb,
                max_mb,
                1,
                1 << 20,
                "give the size in MiB at which an MCAP file is closed and the next begun, \
                 e.g. mcap_max_file_mb = 256",
            )
            .and_then(|n| u64::try_from(n).ok());
        let mcap_max_file_s = self.number(
            "outputs.mcap_max_file_s",
            &raw.mcap_max_file_s,
            d.mcap_max_file_s,
            Limits::within(1.0, 7.0 * DAY_S),
            "give the age in seconds at which an MCAP file is closed and the next begun, e.g. \
             mcap_max_file_s = 3600",
        );
        let budget_fix = "give the disk space in MiB that MCAP files may fill before the \
                          oldest is deleted, at least twice mcap_max_file_mb, e.g. \
                          mcap_disk_budget_mb = 4096";
        let budget = self
            .integer(
                "outputs.mcap_disk_budget_mb",
                &raw.mcap_disk_budget_mb,
                i64::try_from(d.mcap_disk_budget_mb).unwrap_or(4096),
                1,
                i64::MAX,
                budget_fix,
            )
            .and_then(|n| u64::try_from(n).ok());
        let mcap_disk_budget_mb = match (budget, mcap_max_file_mb) {
            (Some(budget), Some(max)) if budget < max.saturating_mul(2) => {
                self.problem(
                    "outputs.mcap_disk_budget_mb",
                    format!(
                        "{budget} MiB is less than twice mcap_max_file_mb (2 × {max} = {} MiB), \
                         but the budget must hold the open file plus at least one finished \
                         one; raise mcap_disk_budget_mb to at least {} or lower \
                         mcap_max_file_mb",
                        max.saturating_mul(2),
                        max.saturating_mul(2),
                    ),
                );
                None
            }
            (budget, _) => budget,
        };
        let alerts_key = "outputs.alerts_service";
        let alerts_fix = "give an iceoryx2 service name under bearingd/, e.g. alerts_service = \
                          \"bearingd/alerts\"";
        let alerts_service = self
            .or_default(
                alerts_key,
                &raw.alerts_service,
                d.alerts_service,
                alerts_fix,
            )
            .and_then(|service| self.service_name(alerts_key, service, alerts_fix))
            .and_then(|service| self.service_name(alerts_key, service, alerts_fix));
        if let Some(service) = &alerts_service {
            for sensor in sensors {
                if sensor.shm_service.as_ref() == Some(service) {
                    let suggestion = if sensor.default_service() == *service {
                        "bearingd/accel/<id>".to_string()
                    } else {
                        sensor.default_service()
                    };
                    self.problem(
                        format!("sensors[{}].shm.service", sensor.index),
                        format!(
                            "{service:?} is also outputs.alerts_service, so samples and alerts \
                             would share a service; give the sensor its own, e.g. service = \
                             {suggestion:?}"
                        ),
                    );
                }
            }
        }
        let iceoryx2_root = self.iceoryx2_root(&raw.iceoryx2_root, &d.iceoryx2_root);
        let status_interval_s = self.number(
            "outputs.status_interval_s",
            &raw.status_interval_s,
            d.status_interval_s,
            Limits::above_to(0.0, 3600.0),
            "give how often status is reported, in seconds, e.g. status_interval_s = 5.0",
        );
        Some(OutputConfig {
            state_dir: state_dir?,
            mcap_dir: mcap_dir?,
            mcap_max_file_mb: mcap_max_file_mb?,
            mcap_max_file_s: mcap_max_file_s?,
            mcap_disk_budget_mb: mcap_disk_budget_mb?,
            alerts_service: alerts_service?,
            iceoryx2_root: iceoryx2_root?,
            status_interval_s: status_interval_s?,
        })
    }

    fn directory(
        &mut self,
        key: &str,
        field: &Field<String>,
        default: &Path,
        fix: &str,
    ) -> Option<PathBuf> {
        let text = self.or_default(key, field, default.to_string_lossy().into_owned(), fix)?;
        if text.trim().is_empty() || text.contains('\0') {
            self.problem(key, format!("{text:?} is not a directory path; {fix}"));
            None
        } else {
            Some(PathBuf::from(text))
        }
    }

    fn iceoryx2_root(&mut self, field: &Field<String>, default: &Path) -> Option<PathBuf> {
        let key = "outputs.iceoryx2_root";
        let fix = "move it to a directory outside /tmp and /var/tmp, e.g. iceoryx2_root = \
                   \"/run/bearingd/iceoryx2\"";
        let path = self.directory(key, field, default, fix)?;
        if !path.is_absolute() {
            self.problem(
                key,
                format!(
                    "{:?} is a relative path, but subscribers in other processes must find the \
                     same directory; give an absolute path, e.g. iceoryx2_root = \
                     \"/run/bearingd/iceoryx2\"",
                    path.display().to_string()
                ),
            );
            return None;
        }
        if path.components().any(|c| c == Component::ParentDir) {
            self.problem(
                key,
                format!(
                    "{:?} contains '..'; give a plain absolute path, e.g. iceoryx2_root = \
                     \"/run/bearingd/iceoryx2\"",
                    path.display().to_string()
                ),
            );
            return None;
        }
        if let Some(tmp) = ["/tmp", "/var/tmp"]
            .into_iter()
            .find(|tmp| path.starts_with(tmp))
        {
            self.problem(
                key,
                format!(
                    "{:?} is under {tmp}: systemd's PrivateTmp= gives the service its own \
                     {tmp}, which would hide iceoryx2's files from subscribers in other \
                     processes; {fix}",
                    path.display().to_string()
                ),
            );
            return None;
        }
        let length = path.as_os_str().len();
        if length > MAX_IOX_ROOT_LEN {
            self.problem(
                key,
                format!(
                    "{:?} is {length} bytes long, more than {MAX_IOX_ROOT_LEN}: iceoryx2 puts \
                     Unix sockets below it whose paths must fit in 108 bytes (a subscriber \
                     could not wait for alerts); {fix}",
                    path.display().to_string()
                ),
            );
            return None;
        }
        Some(path)
    }
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
