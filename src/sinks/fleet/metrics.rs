//! What each monitored channel (a Sparkplug *device*) reports, and when: the metric catalog,
//! the latest value of every metric, and the rule that turns observations into data records.
//!
//! Sans-IO and clock-free: every observation carries its own time (sample time mapped to
//! milliseconds since the epoch, as the MCAP log maps it), and the publish period is counted on
//! that clock. So a run with `--fast` publishes once per second of *sample* time, and a replay
//! would publish the same records.
//!
//! The rule (Sparkplug's "report by exception", paced):
//! - a record holds the metrics whose value changed since the device's last record;
//! - it is made when `period_ms` has passed since the last one, or at once when a flag, the
//!   health stage or the sensor's presence changes (those must never wait for the period).

use super::sparkplug::{DataType, Metric, Payload, Value};
use crate::messages::detect::{all_metrics, MetricKind, MetricValue, METRIC_COUNT};
use crate::messages::{FaultKind, FlagLevel, HealthStage};

/// One device's identity: `<sensor>.<axis>` (Sparkplug ids must not hold `/`, `+`, `#`; sensor
/// and axis names hold none, nor `.`).
pub fn device_id(sensor: &str, axis: &str) -> String {
    format!("{sensor}.{axis}")
}

/// What the bridge learns from the pipeline about one device (by index in the catalog's
/// device list), with the time it refers to in milliseconds since the epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    pub device: usize,
    pub at_ms: u64,
    pub what: Observed,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Observed {
    /// Indicators and fault scores of one analysis window.
    Window {
        rpm: Option<f64>,
        rms_g: f64,
        peak_g: f64,
        crest: f64,
        kurtosis: f64,
        /// Envelope-spectrum scores in [`FaultKind::ALL`] order.
        scores: [f64; 4],
    },
    /// A fault flag changed level (`ok`, `watch`, `alarm`).
    Flag {
        fault: FaultKind,
        level: FlagLevel,
        score: f64,
        confidence: f64,
    },
    /// The health stage changed.
    Stage(HealthStage),
    /// A twin fit.
    Twin {
        hypothesis: FaultKind,
        error: f64,
        margin: f64,
        /// Fit error per hypothesis: outer race, inner race, ball.
        errors: [f64; 3],
        residual_energy_ratio: f64,
        residual_peak_hz: f64,
    },
    /// A re-identification of the HW model (seed 003): its free-run accuracy (%) and its
    /// drift against the channel's baseline (`None` while the baseline is learned).
    Hw {
        accuracy: f64,
        residual_drift_sigma: Option<f64>,
        parameter_drift: Option<f64>,
    },
    /// A point of the RMS trend: the predicted time to the failure limit and the band's
    /// earliest (`None`: no prediction).
    Trend {
        time_to_limit_s: Option<f64>,
        earliest_s: Option<f64>,
    },
    /// The speed the channel scores with (`None`: none usable).
    Speed(Option<f64>),
    /// The sensor went silent (`true`) or came back.
    SensorLost(bool),
    /// A detector's reading (the ISO 20816 velocity zone and RMS, …): values by index in
    /// `messages::detect::all_metrics` (`None`: not a finite number).
    Detector(Vec<(usize, Option<Value>)>),
}

impl Observed {
    /// The metrics of a detector's reading; `None` when it has none (a flag change: its alert
    /// carries it).
    pub fn of_detector(message: &crate::messages::DetectorMessage) -> Option<Observed> {
        let mut values = Vec::new();
        message.metrics(&mut |index, value| {
            let value = match value {
                MetricValue::Text(text) => Some(Value::String(text.to_string())),
                MetricValue::Double(x) => x.is_finite().then_some(Value::Double(x)),
            };
            values.push((index, value));
        });
        (!values.is_empty()).then_some(Observed::Detector(values))
    }
}

/// The metric catalog of a device, in the order of [`Slot`]s.
struct Catalog {
    names: Vec<(String, DataType)>,
}

// Positions of the fixed metrics in the catalog.
const LOST: usize = 0;
const STAGE: usize = 1;
const RPM: usize = 2;
const RMS: usize = 3;
const PEAK: usize = 4;
const CREST: usize = 5;
const KURTOSIS: usize = 6;
const DETECTORS: usize = 7; // every registered detector's metrics, METRIC_COUNT of them
const TWIN_HYPOTHESIS: usize = DETECTORS + METRIC_COUNT;
const TWIN_ERROR: usize = TWIN_HYPOTHESIS + 1;
const TWIN_MARGIN: usize = TWIN_HYPOTHESIS + 2;
const TWIN_RESIDUAL_ENERGY: usize = TWIN_HYPOTHESIS + 3;
const TWIN_RESIDUAL_PEAK: usize = TWIN_HYPOTHESIS + 4;
const TWIN_ERRORS: usize = TWIN_HYPOTHESIS + 5; // three: outer race, inner race, ball
const HW_ACCURACY: usize = TWIN_HYPOTHESIS + 8;
const HW_RESIDUAL_DRIFT: usize = TWIN_HYPOTHESIS + 9;
const HW_PARAMETER_DRIFT: usize = TWIN_HYPOTHESIS + 10;
const TIME_TO_LIMIT: usize = TWIN_HYPOTHESIS + 11;
const TIME_TO_LIMIT_EARLIEST: usize = TWIN_HYPOTHESIS + 12;
const FAULTS: usize = TWIN_HYPOTHESIS + 13; // per fault kind: flag, confidence, score
const PER_FAULT: usize = 3;

impl Catalog {
    fn new() -> Self {
        use DataType::{Boolean, Double, String as Text};
        let mut names: Vec<(String, DataType)> = [
            ("Sensor/Lost", Boolean),
            ("Health/Stage", Text),
            ("Speed/RPM", Double),
            ("Vibration/RMS_g", Double),
            ("Vibration/Peak_g", Double),
            ("Vibration/Crest", Double),
            ("Vibration/Kurtosis", Double),
        ]
        .into_iter()
        .map(|(n, t)| (n.to_string(), t))
        .collect();
        debug_assert_eq!(names.len(), DETECTORS);
        names.extend(all_metrics().map(|m| {
            let datatype = match m.kind {
                MetricKind::Text => Text,
                MetricKind::Double => Double,
            };
            (m.name.to_string(), datatype)
        }));
        names.extend(
            [
                ("Twin/Hypothesis", Text),
                ("Twin/Error", Double),
                ("Twin/Margin", Double),
                ("Twin/ResidualEnergyRatio", Double),
                ("Twin/ResidualPeak_Hz", Double),
                ("Twin/Error/outer_race", Double),
                ("Twin/Error/inner_race", Double),
                ("Twin/Error/ball", Double),
                ("HW/Accuracy", Double),
                ("HW/ResidualDrift_sigma", Double),
                ("HW/ParameterDrift", Double),
                ("Health/TimeToLimit_s", Double),
                ("Health/TimeToLimitEarliest_s", Double),
            ]
            .into_iter()
            .map(|(n, t)| (n.to_string(), t)),
        );
        debug_assert_eq!(names.len(), FAULTS);
        for fault in FaultKind::ALL {
            let f = fault.name();
            names.push((format!("Fault/{f}/Flag"), Text));
            names.push((format!("Fault/{f}/Confidence"), Double));
            names.push((format!("Fault/{f}/Score"), Double));
        }
        Catalog { names }
    }
}

fn fault_slot(fault: FaultKind, member: usize) -> usize {
    let index = FaultKind::ALL.iter().position(|f| *f == fault).unwrap_or(0);
    FAULTS + index * PER_FAULT + member
}

/// A metric's latest value (`None`: not known yet, sent as null) and whether it changed since
/// the device's last record.
#[derive(Debug, Clone, PartialEq)]
struct Slot {
    value: Option<Value>,
    at_ms: u64,
    changed: bool,
}

struct Device {
    id: String,
    slots: Vec<Slot>,
    /// Time of the device's last record; `None` before the first.
    last_record_ms: Option<u64>,
    /// A flag, stage or presence change waits in the slots: make a record now.
    urgent: bool,
    lost: bool,
}

/// A device's data record: what goes to the disk queue and, with a seq, out as DDATA.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    pub device: String,
    pub payload: Payload,
}

/// The latest value of every metric of every device, and the records they produce.
pub struct MetricBook {
    catalog: Catalog,
    devices: Vec<Device>,
    period_ms: u64,
}

impl MetricBook {
    /// `devices`: device ids in a fixed order (observations name them by index).
    pub fn new(devices: Vec<String>, period_ms: u64) -> Self {
        let catalog = Catalog::new();
        let blank: Vec<Slot> = catalog
            .names
            .iter()
            .map(|_| Slot {
                value: None,
                at_ms: 0,
                changed: false,
            })
            .collect();
        let devices = devices
            .into_iter()
            .map(|id| {
                let mut slots = blank.clone();
                // The pipeline starts every flag at ok, and a configured sensor as present.
                for fault in FaultKind::ALL {
                    slots[fault_slot(fault, 0)].value = Some(Value::String("ok".into()));
                }
                slots[LOST].value = Some(Value::Boolean(false));
                Device {
                    id,
                    slots,
                    last_record_ms: None,
                    urgent: false,
                    lost: false,
                }
            })
            .collect();
        MetricBook {
            catalog,
            devices,
            period_ms: period_ms.max(1),
        }
    }

    pub fn device_ids(&self) -> impl Iterator<Item = &str> {
        self.devices.iter().map(|d| d.id.as_str())
    }

    pub fn device_index(&self, id: &str) -> Option<usize> {
        self.devices.iter().position(|d| d.id == id)
    }

    /// Whether the device's sensor is lost now.
    pub fn is_lost(&self, device: usize) -> bool {
        self.devices.get(device).is_some_and(|d| d.lost)
    }

    /// Every metric of the device with its latest value (null where none yet), for a DBIRTH.
    pub fn birth_metrics(&self, device: usize, now_ms: u64) -> Vec<Metric> {
        let Some(d) = self.devices.get(device) else {
            return Vec::new();
        };
        self.catalog
            .names
            .iter()
            .zip(&d.slots)
            .map(|((name, datatype), slot)| {
                let at = if slot.value.is_some() {
                    slot.at_ms
                } else {
                    now_ms
                };
                Metric::named(name, *datatype, at, slot.value.as_ref())
            })
            .collect()
    }

    /// Takes one observation; returns the device's record when one is due.
    pub fn observe(&mut self, o: Observation) -> Option<Record> {
        let period = self.period_ms;
        let device = self.devices.get_mut(o.device)?;
        let at = o.at_ms;
        let mut set = |slot: usize, value: Option<Value>| {
            let s = &mut device.slots[slot];
            // NaN never equals itself: compare the bits so that a NaN does not count as news.
            let same = match (&s.value, &value) {
                (Some(Value::Double(a)), Some(Value::Double(b))) => a.to_bits() == b.to_bits(),
                (a, b) => a == b,
            };
            if !same {
                s.value = value;
                s.changed = true;
            }
            s.at_ms = at;
            !same
        };
        let double = |x: f64| x.is_finite().then_some(Value::Double(x));
        let mut urgent = false;
        match o.what {
            Observed::Window {
                rpm,
                rms_g,
                peak_g,
                crest,
                kurtosis,
                scores,
            } => {
                set(RPM, rpm.and_then(double));
                set(RMS, double(rms_g));
                set(PEAK, double(peak_g));
                set(CREST, double(crest));
                set(KURTOSIS, double(kurtosis));
                for (fault, score) in FaultKind::ALL.iter().zip(scores) {
                    set(fault_slot(*fault, 2), double(score));
                }
            }
            Observed::Flag {
                fault,
                level,
                score,
                confidence,
            } => {
                set(
                    fault_slot(fault, 0),
                    Some(Value::String(level.name().into())),
                );
                set(fault_slot(fault, 1), double(confidence));
                set(fault_slot(fault, 2), double(score));
                urgent = true;
            }
            Observed::Stage(stage) => {
                set(STAGE, Some(Value::String(stage.name().into())));
                urgent = true;
            }
            Observed::Twin {
                hypothesis,
                error,
                margin,
                errors,
                residual_energy_ratio,
                residual_peak_hz,
            } => {
                set(
                    TWIN_HYPOTHESIS,
                    Some(Value::String(hypothesis.name().into())),
                );
                set(TWIN_ERROR, double(error));
                set(TWIN_MARGIN, double(margin));
                set(TWIN_RESIDUAL_ENERGY, double(residual_energy_ratio));
                set(TWIN_RESIDUAL_PEAK, double(residual_peak_hz));
                for (k, e) in errors.into_iter().enumerate() {
                    set(TWIN_ERRORS + k, double(e));
                }
            }
            Observed::Hw {
                accuracy,
                residual_drift_sigma,
                parameter_drift,
            } => {
                set(HW_ACCURACY, double(accuracy));
                set(HW_RESIDUAL_DRIFT, residual_drift_sigma.and_then(double));
                set(HW_PARAMETER_DRIFT, parameter_drift.and_then(double));
            }
            Observed::Trend {
                time_to_limit_s,
                earliest_s,
            } => {
                set(TIME_TO_LIMIT, time_to_limit_s.and_then(double));
                set(TIME_TO_LIMIT_EARLIEST, earliest_s.and_then(double));
            }
            Observed::Speed(rpm) => {
                set(RPM, rpm.and_then(double));
            }
            Observed::SensorLost(lost) => {
                set(LOST, Some(Value::Boolean(lost)));
                device.lost = lost;
                urgent = true;
            }
            Observed::Detector(values) => {
                for (index, value) in values {
                    let changed = set(DETECTORS + index, value);
                    urgent |= changed && all_metrics().nth(index).is_some_and(|spec| spec.urgent);
                }
            }
        }
        device.urgent |= urgent;
        let due = device.last_record_ms.is_none_or(|last| at >= last + period);
        if !(device.urgent || due) {
            return None;
        }
        self.take_record(o.device, at)
    }

    /// The changed metrics of a device as a record (with the time `at_ms`), if any changed.
    fn take_record(&mut self, device: usize, at_ms: u64) -> Option<Record> {
        let d = self.devices.get_mut(device)?;
        d.urgent = false;
        let metrics: Vec<Metric> = self
            .catalog
            .names
            .iter()
            .zip(d.slots.iter_mut())
            .filter(|(_, slot)| slot.changed)
            .map(|((name, datatype), slot)| {
                slot.changed = false;
                Metric::named(name, *datatype, slot.at_ms, slot.value.as_ref())
            })
            .collect();
        if metrics.is_empty() {
            return None;
        }
        d.last_record_ms = Some(at_ms);
        Some(Record {
            device: d.id.clone(),
            payload: Payload {
                timestamp: Some(at_ms),
                metrics,
                seq: None,
                uuid: None,
                body: None,
            },
        })
    }

    /// The number of metrics of a device.
    pub fn metric_count(&self) -> usize {
        self.catalog.names.len()
    }

    /// A metric's position in the catalog (the order of [`MetricBook::birth_metrics`]).
    pub fn metric_index(&self, name: &str) -> Option<usize> {
        self.catalog.names.iter().position(|(n, _)| n == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window(at_ms: u64, rms: f64) -> Observation {
        Observation {
            device: 0,
            at_ms,
            what: Observed::Window {
                rpm: Some(1772.0),
                rms_g: rms,
                peak_g: 3.0 * rms,
                crest: 3.0,
                kurtosis: 3.1,
                scores: [1.0, 2.0, 3.0, 4.0],
            },
        }
    }

    fn names(record: &Record) -> Vec<&str> {
        record
            .payload
            .metrics
            .iter()
            .filter_map(|m| m.name.as_deref())
            .collect()
    }

    #[test]
    fn records_come_once_per_period_of_observation_time_with_the_changed_metrics() {
        let mut book = MetricBook::new(vec!["m.radial".into()], 1000);
        // The first window makes a record at once (nothing was sent yet).
        let first = book.observe(window(10_000, 0.5)).unwrap();
        assert_eq!(first.device, "m.radial");
        assert_eq!(first.payload.timestamp, Some(10_000));
        assert!(names(&first).contains(&"Vibration/RMS_g"));
        assert!(names(&first).contains(&"Fault/cage/Score"));
        // Windows every 500 ms: a record every second, not every window.
        let mut records = Vec::new();
        for k in 1..=6u64 {
            if let Some(r) = book.observe(window(10_000 + 500 * k, 0.5 + k as f64)) {
                records.push(r);
            }
        }
        let times: Vec<u64> = records
            .iter()
            .map(|r| r.payload.timestamp.unwrap())
            .collect();
        assert_eq!(times, [11_000, 12_000, 13_000]);
        // Only what changed: the scores and the speed did not.
        assert_eq!(
            names(&records[0]),
            ["Vibration/RMS_g", "Vibration/Peak_g"],
            "{records:?}"
        );
    }

    #[test]
    fn a_flag_change_is_recorded_at_once_with_its_confidence() {
        let mut book = MetricBook::new(vec!["m.radial".into()], 1000);
        book.observe(window(0, 0.5)).unwrap();
        let flag = book
            .observe(Observation {
                device: 0,
                at_ms: 100,
                what: Observed::Flag {
                    fault: FaultKind::OuterRace,
                    level: FlagLevel::Alarm,
                    score: 40.0,
                    confidence: 0.9,
                },
            })
            .expect("a flag change must not wait for the period");
        assert_eq!(flag.payload.timestamp, Some(100));
        let by_name = |n: &str| {
            flag.payload
                .metrics
                .iter()
                .find(|m| m.name.as_deref() == Some(n))
                .and_then(|m| m.value())
        };
        assert_eq!(
            by_name("Fault/outer_race/Flag"),
            Some(Value::String("alarm".into()))
        );
        assert_eq!(
            by_name("Fault/outer_race/Confidence"),
            Some(Value::Double(0.9))
        );
        // A stage change and a lost sensor too.
        assert!(book
            .observe(Observation {
                device: 0,
                at_ms: 150,
                what: Observed::Stage(HealthStage::Degrading),
            })
            .is_some());
        let lost = book
            .observe(Observation {
                device: 0,
                at_ms: 160,
                what: Observed::SensorLost(true),
            })
            .unwrap();
        assert_eq!(names(&lost), ["Sensor/Lost"]);
        assert!(book.is_lost(0));
    }

    #[test]
    fn the_birth_holds_every_metric_with_nulls_where_nothing_is_known() {
        let mut book = MetricBook::new(vec!["a.x".into(), "a.y".into()], 1000);
        let birth = book.birth_metrics(1, 5);
        assert_eq!(birth.len(), book.metric_count());
        let zone = birth
            .iter()
            .find(|m| m.name.as_deref() == Some("ISO20816/Zone"))
            .unwrap();
        assert_eq!(
            zone.is_null,
            Some(true),
            "the ISO zone slot waits for a value"
        );
        assert_eq!(zone.datatype, Some(DataType::String as u32));
        let flag = birth
            .iter()
            .find(|m| m.name.as_deref() == Some("Fault/ball/Flag"))
            .unwrap();
        assert_eq!(flag.value(), Some(Value::String("ok".into())));
        // Once an ISO zone is observed, the slot is filled and a zone change is urgent.
        let iso = |zone: &str, at| Observation {
            device: 1,
            at_ms: at,
            what: Observed::Detector(vec![
                (0, Some(Value::String(zone.into()))),
                (1, Some(Value::Double(2.0))),
            ]),
        };
        assert!(book.observe(iso("B", 10)).is_some());
        assert!(
            book.observe(iso("B", 20)).is_none(),
            "same zone within the period"
        );
        assert!(book.observe(iso("C", 30)).is_some(), "a new zone at once");
        let birth = book.birth_metrics(1, 40);
        let zone = birth
            .iter()
            .find(|m| m.name.as_deref() == Some("ISO20816/Zone"))
            .unwrap();
        assert_eq!(zone.value(), Some(Value::String("C".into())));
        assert_eq!(zone.timestamp, Some(30));
    }

    #[test]
    fn non_finite_values_go_out_as_null() {
        let mut book = MetricBook::new(vec!["m.r".into()], 1000);
        let r = book
            .observe(Observation {
                device: 0,
                at_ms: 0,
                what: Observed::Twin {
                    hypothesis: FaultKind::OuterRace,
                    error: f64::NAN,
                    margin: 0.1,
                    errors: [0.1, f64::INFINITY, 0.3],
                    residual_energy_ratio: 0.2,
                    residual_peak_hz: 10.0,
                },
            })
            .unwrap();
        let inner = r
            .payload
            .metrics
            .iter()
            .find(|m| m.name.as_deref() == Some("Twin/Error/inner_race"));
        // Null from the start: unchanged, so not in the record.
        assert!(inner.is_none());
        assert!(!r
            .payload
            .metrics
            .iter()
            .any(|m| matches!(m.value(), Some(Value::Double(x)) if !x.is_finite())));
        assert!(r
            .payload
            .metrics
            .iter()
            .any(|m| m.name.as_deref() == Some("Twin/Margin")));
    }
}
