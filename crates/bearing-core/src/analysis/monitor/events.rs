//! What a channel monitor tells its driver: per-hop reports, flag, stage, sensor, band,
//! detector, gap and speed events, all stamped in sample time.

use crate::analysis::band_selection::Evidence;
use crate::analysis::degradation::TrendPoint;
use crate::analysis::fault_bands::FaultScore;
use crate::analysis::flags::FlagChange;
use crate::analysis::health::StageChange;
use crate::analysis::indicators::Indicators;
use crate::analysis::Band;
use crate::messages::{DetectorMessage, FaultKind, HealthKind, HealthStage};

/// A sensor-health finding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensorCondition {
    Clipping,
    FlatLine,
}

impl From<SensorCondition> for HealthKind {
    fn from(condition: SensorCondition) -> HealthKind {
        match condition {
            SensorCondition::Clipping => HealthKind::Saturation,
            SensorCondition::FlatLine => HealthKind::FlatLine,
        }
    }
}

/// One hop's results.
pub struct WindowReport<'a> {
    pub end_sample: u64,
    pub indicators: Indicators,
    /// In [`FaultKind::ALL`] order, each from its own band.
    pub scores: &'a [FaultScore; 4],
    pub bands: &'a [Band; 4],
    /// Averaged amplitude spectrum of the band of the highest score.
    pub spectrum: &'a [f32],
    pub spectrum_band: Band,
    pub bin_hz: f64,
    pub windows_averaged: usize,
}

/// What the monitor tells its driver.
pub enum MonitorEvent<'a> {
    Window(WindowReport<'a>),
    Flag {
        fault: FaultKind,
        change: FlagChange,
        score: f64,
        frequency_hz: f64,
        /// The largest score of the other faults in the same window (at least 1e-9).
        runner_up: f64,
    },
    Stage(StageChange),
    /// A new point of the RMS trend, with the stage it was made in.
    Trend {
        point: TrendPoint,
        stage: HealthStage,
    },
    Sensor {
        condition: SensorCondition,
        active: bool,
        at_sample: u64,
    },
    /// A band selection's result: its bands and the verdict on its history (from
    /// `evidence_from` to `at_sample`), which the flags follow.
    Bands {
        at_sample: u64,
        bands: [Band; 4],
        selected: Band,
        evidence: Option<&'a Evidence>,
        evidence_from: u64,
    },
    /// A detector's reading or flag change ([`crate::analysis::detect`]); its channel is left
    /// empty for the driver to fill in.
    Detector(DetectorMessage),
    /// Samples were missing: the windows restart after the gap.
    Gap {
        at_sample: u64,
        missing: u64,
    },
    /// The shaft speed the channel uses changed (or was set again), from `at_sample` on;
    /// `shaft_hz` is `None` when it is unknown or unusable from there (see
    /// [`crate::analysis::speed::SpeedMode`]).
    Speed {
        at_sample: u64,
        shaft_hz: Option<f64>,
        /// Given to `set_speed_at` (`None` if it was "not available"); differs from
        /// `shaft_hz` when the given speed is not usable.
        given_hz: Option<f64>,
        estimated: bool,
    },
}
