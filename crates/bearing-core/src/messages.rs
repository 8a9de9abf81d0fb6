//! The vocabulary of the pipeline: the typed kinds (fault, flag level, health stage and event,
//! speed source) and the messages the per-channel pipeline hands to its sinks (the MCAP log,
//! alerts, status), one type per MCAP channel. Owned by no adapter: the analysis, the pipeline,
//! the sources and the sinks all speak it, and only the edges encode it (the MCAP log as JSON
//! or protobuf, iceoryx2 alerts as integer codes, the command line as text).
//!
//! Why typed: a kind is decided once, where it happens, and every consumer matches on it; no
//! string is parsed back inside the process. The wire form in the MCAP log is the snake_case
//! name of each variant (`outer_race`, `alarm`, `flat_line`, …), the same strings the log has
//! always had, so existing readers (Python, Foxglove) keep working.
//!
//! Each message carries the channel it belongs to and its position in **sample time**
//! (`end_sample`: one past the last sample the result covers), so that a replay reproduces
//! them at the same sample times. Raw samples go to MCAP as protobuf (compact and lossless: the
//! integers the sensor sent plus its scale), everything else as JSON (low rate, readable
//! anywhere).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::fmt;

pub mod detect;
mod stamp;

pub use detect::velocity::{
    VelocityFlagMessage, VelocityMessage, ISO_ZONE_FLAG, VELOCITY_FLAG_NAME,
};
pub use detect::DetectorMessage;

/// Implements `Display` as the variant's wire name (`name()`), so text output and the log agree.
macro_rules! display_as_name {
    ($($kind:ty),*) => {$(
        impl fmt::Display for $kind {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
    )*};
}

pub use crate::bearing::FaultKind;

/// A fault flag's level: `ok | watch | alarm`, ordered by severity.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum FlagLevel {
    Ok,
    Watch,
    Alarm,
}

impl FlagLevel {
    pub const ALL: [FlagLevel; 3] = [FlagLevel::Ok, FlagLevel::Watch, FlagLevel::Alarm];

    /// The wire name: `ok`, `watch`, `alarm`.
    pub fn name(self) -> &'static str {
        match self {
            FlagLevel::Ok => "ok",
            FlagLevel::Watch => "watch",
            FlagLevel::Alarm => "alarm",
        }
    }
}

/// The bearing's stage of life (MODELS.md §7).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum HealthStage {
    /// Learning the healthy baseline.
    Learning,
    Healthy,
    /// Kurtosis beyond the healthy baseline: impacts have appeared.
    Degrading,
    /// RMS beyond its level at the start of degradation: the damage has spread.
    Failing,
}

impl HealthStage {
    /// The wire name: `learning`, `healthy`, `degrading`, `failing`.
    pub fn name(self) -> &'static str {
        match self {
            HealthStage::Learning => "learning",
            HealthStage::Healthy => "healthy",
            HealthStage::Degrading => "degrading",
            HealthStage::Failing => "failing",
        }
    }
}

/// What a [`HealthMessage`] reports.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum HealthKind {
    /// The source has not heard the sensor within its timeout.
    Lost,
    /// The sensor sends again.
    Back,
    /// Samples are missing.
    Gap,
    /// The sensor node restarted.
    Restart,
    /// The signal clips at the sensor's range.
    Saturation,
    /// The signal stopped moving.
    FlatLine,
    /// The health stage changed ([`HealthMessage::stage`] says to which).
    Stage,
    /// The analysis bands were re-selected.
    Bands,
}

impl HealthKind {
    /// The wire name: `lost`, `back`, `gap`, `restart`, `saturation`, `flat_line`, `stage`,
    /// `bands`.
    pub fn name(self) -> &'static str {
        match self {
            HealthKind::Lost => "lost",
            HealthKind::Back => "back",
            HealthKind::Gap => "gap",
            HealthKind::Restart => "restart",
            HealthKind::Saturation => "saturation",
            HealthKind::FlatLine => "flat_line",
            HealthKind::Stage => "stage",
            HealthKind::Bands => "bands",
        }
    }
}

/// Where a channel's shaft speed comes from (config `sensors[].speed.source`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SpeedSource {
    /// A fixed speed from the config.
    Fixed,
    /// Speed frames of the sensor node (a tachometer on the bus).
    Can,
    /// Estimated from the spectrum near a nominal speed.
    Estimate,
}

impl SpeedSource {
    /// The wire name: `fixed`, `can`, `estimate`.
    pub fn name(self) -> &'static str {
        match self {
            SpeedSource::Fixed => "fixed",
            SpeedSource::Can => "can",
            SpeedSource::Estimate => "estimate",
        }
    }
}

/// An evaluation zone of ISO 10816-3 / 20816-3 for the machine's velocity RMS: A newly
/// commissioned, B unrestricted long-term operation, C limited operation (plan a repair), D
/// damage likely. The wire name is the letter (`"A"` … `"D"`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
pub enum IsoZone {
    A,
    B,
    C,
    D,
}

impl IsoZone {
    /// The wire name: `A`, `B`, `C`, `D`.
    pub fn name(self) -> &'static str {
        match self {
            IsoZone::A => "A",
            IsoZone::B => "B",
            IsoZone::C => "C",
            IsoZone::D => "D",
        }
    }

    /// What the standard says the zone means, in a few words.
    pub fn meaning(self) -> &'static str {
        match self {
            IsoZone::A => "newly commissioned",
            IsoZone::B => "unrestricted long-term operation",
            IsoZone::C => "not for long-term operation: plan a repair",
            IsoZone::D => "severe enough to cause damage",
        }
    }
}

display_as_name!(FlagLevel, HealthStage, HealthKind, SpeedSource, IsoZone);

/// Identifies one analysed signal: a sensor (node) and one of its axes.
#[derive(
    Debug, Clone, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
pub struct ChannelId {
    /// The sensor's id from the config (e.g. `motor-de`).
    pub sensor: String,
    /// The axis name from the config (e.g. `radial`).
    pub axis: String,
}

impl fmt::Display for ChannelId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.sensor, self.axis)
    }
}

/// A block of raw samples exactly as the sensor sent them. MCAP topic `/raw/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RawBlock {
    pub channel: ChannelId,
    /// Index of the first sample in the channel's sample time.
    pub first_sample: u64,
    pub sample_rate_hz: f64,
    /// Acceleration in g per count.
    pub scale_g_per_count: f64,
    /// The integer counts as sent (i16 on the wire).
    pub counts: Vec<i32>,
}

impl RawBlock {
    /// One past the block's last sample, in the channel's sample time.
    pub fn end_sample(&self) -> u64 {
        self.first_sample + self.counts.len() as u64
    }
}

/// The averaged squared-envelope spectrum, at a low rate. Topic `/spectrum/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SpectrumMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub band_hz: [f64; 2],
    pub bin_hz: f64,
    pub windows_averaged: usize,
    /// Amplitude per bin from 0 Hz, g².
    pub amplitude: Vec<f32>,
    /// The frequency of each bin of `amplitude`, Hz (`i × bin_hz`): the x axis a plot of the
    /// spectrum needs (Foxglove's Plot panel plots `amplitude[:]` against `frequency_hz[:]`).
    /// Absent in logs of older versions (read as empty).
    #[serde(default)]
    pub frequency_hz: Vec<f32>,
}

impl SpectrumMessage {
    /// A spectrum message whose `frequency_hz` is filled from `bin_hz`, one per amplitude.
    pub fn new(
        channel: ChannelId,
        end_sample: u64,
        band_hz: [f64; 2],
        bin_hz: f64,
        windows_averaged: usize,
        amplitude: Vec<f32>,
    ) -> Self {
        let frequency_hz = (0..amplitude.len())
            .map(|i| (i as f64 * bin_hz) as f32)
            .collect();
        SpectrumMessage {
            channel,
            end_sample,
            band_hz,
            bin_hz,
            windows_averaged,
            amplitude,
            frequency_hz,
        }
    }
}

/// Indicators and fault scores of the newest window. Topic `/indicators/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct IndicatorsMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub rpm: f64,
    pub band_hz: [f64; 2],
    pub rms: f64,
    pub peak: f64,
    pub crest: f64,
    pub kurtosis: f64,
    pub score_outer_race: f64,
    pub score_inner_race: f64,
    pub score_ball: f64,
    pub score_cage: f64,
}

/// The twin's latest fit. Topic `/twin/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TwinMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    /// The fault hypothesis that fits best.
    pub hypothesis: FaultKind,
    pub error: f64,
    pub margin: f64,
    pub error_outer_race: f64,
    pub error_inner_race: f64,
    pub error_ball: f64,
    pub a: f64,
    pub decay_per_s: f64,
    pub f_n: f64,
    pub f_d: f64,
    pub jitter: f64,
    pub residual_energy_ratio: f64,
    pub residual_peak_hz: f64,
    /// Residual envelope spectrum (measured − twin) of the best hypothesis, amplitude per bin.
    pub residual_bin_hz: f64,
    pub residual: Vec<f32>,
    /// The learned model's opinion of the same signal (`twin.learned_model`); absent when off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learned: Option<LearnedOpinionMessage>,
}

/// A learned model's opinion of a twin re-fit's signal, and what it settles with the envelope
/// evidence (docs/PHYSICS.md, "Learned diagnosis"): it may confirm the fault the envelope ranks
/// first (clearly and significantly) while no flag names one; the flags stay the envelope's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LearnedOpinionMessage {
    pub segments: usize,
    /// Most probable first; `fault` null: healthy.
    pub probabilities: Vec<ClassProbability>,
    /// The fault the combination names where the envelope alone names none; null otherwise.
    pub confirms: Option<FaultKind>,
    /// Whether the network's most probable class is what the envelope (or the combination)
    /// says.
    pub agrees: bool,
    /// Why the network gave no opinion (an error of its own); null when it gave one.
    pub problem: Option<String>,
}

/// One class of a learned opinion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ClassProbability {
    /// null: healthy.
    pub fault: Option<FaultKind>,
    pub probability: f64,
}

/// The Hammerstein–Wiener model of seed 003 (docs/HW.md), re-identified with each twin fit on
/// the last `twin.hw_samples` samples of the fit's signal, warm-started from the channel's
/// previous model; its time residuals and its drift against the channel's healthy baseline.
/// Topic `/hw/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct HwMessage {
    pub channel: ChannelId,
    /// One past the last sample of the twin fit's signal.
    pub end_sample: u64,
    /// Sample of the first residual value (the virtual states start here).
    pub first_sample: u64,
    pub fs_hz: f64,
    /// Output state order `n` (the model predicts `a⁽ⁿ⁾` from `a⁽ⁿ⁺¹⁾…`).
    pub order: usize,
    /// Where the median filter sits in the states' chain: `raw_once` or `each_order`.
    pub states: String,
    /// Why no model was identified (a flat or too short signal); the other fields are then
    /// empty or null.
    pub problem: Option<String>,
    /// Whether the identification started from the channel's previous model.
    pub warm_start: bool,
    /// Levenberg–Marquardt iterations taken.
    pub iterations: usize,
    /// `100·(1 − NRMSE)` of the free-run simulation, %.
    pub accuracy_simulation: f64,
    /// `100·(1 − NRMSE)` of the one-step-ahead prediction of the model's linear ARX part (the
    /// identification's starting point), %.
    pub accuracy_one_step: f64,
    /// Per input `a⁽ⁿ⁺ⁱ⁾`: numerator `b₀…` and denominator `f₁…` (monic, `1 + f₁q⁻¹ + …`) of
    /// its transfer function, on normalised signals.
    pub numerators: Vec<Vec<f64>>,
    pub denominators: Vec<Vec<f64>>,
    /// Largest pole radius per input.
    pub pole_radius: Vec<f64>,
    /// Output polynomial `c₀, c₁ = 1, c₂, …`.
    pub output_polynomial: Vec<f64>,
    /// Normalisation of the output: `a⁽ⁿ⁾ = mean + scale · y`.
    pub output_mean: f64,
    pub output_scale: f64,
    /// Measured minus simulated output per sample, in units of `output_scale`.
    pub residual_simulation: Vec<f32>,
    /// Measured minus the ARX part's one-step-ahead prediction per sample, in units of
    /// `output_scale`.
    pub residual_one_step: Vec<f32>,
    /// Fits in the channel's healthy baseline so far (it is complete at `twin.hw_baseline_fits`).
    pub baseline_fits: u64,
    /// Free-run NRMSE (%) against its baseline, in baseline standard deviations; null while
    /// the baseline is learned.
    pub residual_drift_sigma: Option<f64>,
    /// Distance of the parameters (numerators, denominators, polynomial) from their baseline
    /// mean, relative to the mean's length; null while the baseline is learned.
    pub parameter_drift: Option<f64>,
}

/// The channel's RMS trend with its health stage (issue 13 item 5), one point per
/// `thresholds.trend_point_s` of sample time: the point (median window RMS of the span) and,
/// once the bearing is degrading and the failure limit is learned, the exponential trend of
/// the newest `thresholds.trend_points` points with the time it predicts to the limit and its
/// uncertainty band (docs/HEALTH.md). Topic `/trend/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TrendMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub stage: HealthStage,
    /// The point: median window RMS over the span, g.
    pub rms: f64,
    /// Points in the fit's window.
    pub points: usize,
    /// The failure limit (g) the time is predicted for; null before it is known.
    pub threshold: Option<f64>,
    /// Growth rate of `ln RMS` per second; null without a fit.
    pub rate_per_s: Option<f64>,
    /// Time for the RMS to double at that rate, s; null when it is not growing.
    pub doubling_s: Option<f64>,
    /// Predicted time from now to the limit, s; with the band's earliest and latest; null when
    /// not within the look-ahead (ten spans of the fitted window).
    pub time_to_threshold_s: Option<f64>,
    pub earliest_s: Option<f64>,
    pub latest_s: Option<f64>,
    /// Two-sided coverage of the band, e.g. 0.9.
    pub confidence: f64,
}

/// A fault flag changed state. Topic `/flags/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FlagMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub fault: FaultKind,
    pub from: FlagLevel,
    pub to: FlagLevel,
    pub score: f64,
    pub fault_frequency_hz: f64,
    /// The largest score of the other faults in the same window: what the alert's confidence
    /// weighs the flag's score against. Absent from logs written before 2026-11-26.
    #[serde(default)]
    pub runner_up_score: Option<f64>,
}

/// Something about the sensor or the bearing's life changed. Topic `/health/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct HealthMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub kind: HealthKind,
    /// For [`HealthKind::Stage`]: the new stage.
    pub stage: Option<HealthStage>,
    pub detail: String,
}

/// The shaft speed a channel uses from `end_sample` on (every speed frame, every estimate).
/// Topic `/speed/<sensor>/<axis>`. A replay feeds the measured ones (`source = "can"`) back at
/// their samples, so its flags equal the live run's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SpeedMessage {
    pub channel: ChannelId,
    /// The sample from which the speed applies.
    pub end_sample: u64,
    /// [`SpeedSource::Can`] (a speed frame) or [`SpeedSource::Estimate`].
    pub source: SpeedSource,
    /// The speed as given: the frame's value (`null`: "not available") or the estimate, rpm.
    pub given_rpm: Option<f64>,
    /// The speed the channel scores with from here; `null` when the given one is not usable
    /// (not available, 0, above `max_rpm`): the channel then scores nothing.
    pub rpm: Option<f64>,
}

/// Counters of one source since the daemon started, every `outputs.status_interval_s` and
/// when the source stops. Topic `/ingest/<source>`, `<source>` `can-<interface>` or
/// `shm-<sensor>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct IngestMessage {
    pub source: String,
    /// Frames received, valid or not.
    pub frames: u64,
    /// Samples delivered in blocks.
    pub samples: u64,
    pub gaps: u64,
    /// Samples the nodes sent that never arrived (the gaps' sizes).
    pub missing_samples: u64,
    /// Frames refused (every kind; `bearingd ingest --json` shows them by kind).
    pub malformed: u64,
    pub restarts: u64,
    /// Sample blocks of nodes or axes the config does not know, skipped.
    pub dropped_blocks: u64,
    pub speed_frames: u64,
    pub sensor_lost: u64,
    /// Transport batches dropped at a full hand-off queue (iceoryx2; also visible as gaps).
    pub handoff_dropped: u64,
}

/// Everything the pipeline emits, in the order it emits it. Where and when a message is (its
/// channel, its end sample) is asked with [`PipelineMessage::channel`] and
/// [`PipelineMessage::end_sample`] (`messages/stamp.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum PipelineMessage {
    Raw(RawBlock),
    Spectrum(SpectrumMessage),
    Indicators(IndicatorsMessage),
    Twin(TwinMessage),
    Hw(HwMessage),
    Trend(TrendMessage),
    Flag(FlagMessage),
    Health(HealthMessage),
    Ingest(IngestMessage),
    Speed(SpeedMessage),
    /// A registered detector's reading or flag change (ISO velocity, …): see [`detect`].
    Detector(DetectorMessage),
}

/// What happened to the alert of one (channel, flag).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum AlertState {
    /// The flag left `ok`.
    Raised = 1,
    /// Its severity went up (watch → alarm).
    Escalated = 2,
    /// Its severity went down but the flag is still up (alarm → watch).
    Relaxed = 3,
    /// The flag is back to `ok`: the alert is no longer active.
    Cleared = 4,
    /// Nothing changed: an active alert sent again so that it stays in the alert service's
    /// history for subscribers that connect later.
    Repeated = 5,
}

impl AlertState {
    pub const ALL: [AlertState; 5] = [
        AlertState::Raised,
        AlertState::Escalated,
        AlertState::Relaxed,
        AlertState::Cleared,
        AlertState::Repeated,
    ];

    pub fn name(self) -> &'static str {
        match self {
            AlertState::Raised => "raised",
            AlertState::Escalated => "escalated",
            AlertState::Relaxed => "relaxed",
            AlertState::Cleared => "cleared",
            AlertState::Repeated => "repeated",
        }
    }

    /// The state of a flag change from `from` to `to`.
    pub fn of_change(from: FlagLevel, to: FlagLevel) -> AlertState {
        match (from, to) {
            (FlagLevel::Ok, _) => AlertState::Raised,
            (_, FlagLevel::Ok) => AlertState::Cleared,
            _ if to > from => AlertState::Escalated,
            _ => AlertState::Relaxed,
        }
    }
}

/// Which flag an alert is about: a bearing fault kind's, or a registered detector's (the ISO
/// velocity zone, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AlertSubject {
    Fault(FaultKind),
    Detector(&'static detect::FlagSpec),
}

impl AlertSubject {
    /// The ISO velocity zone flag's subject.
    pub const ISO_ZONE: AlertSubject = AlertSubject::Detector(&ISO_ZONE_FLAG);

    /// The wire name: a fault kind's (`outer_race`, …) or the detector flag's (`iso_zone`).
    pub fn name(self) -> &'static str {
        match self {
            AlertSubject::Fault(fault) => fault.name(),
            AlertSubject::Detector(flag) => flag.name,
        }
    }
}

/// A flag change as an alert, decided once by the pipeline (`pipeline::alerts`) right after
/// the flag's message: numbered, with its confidence. Not logged (the MCAP log has the flag
/// itself, and the alert follows from it); the iceoryx2 publisher stamps the wall time and
/// sends it (`docs/ALERTS.md`), the fleet bridge takes its confidence.
#[derive(Debug, Clone, PartialEq)]
pub struct AlertMessage {
    /// 1 for the first alert of a run, +1 for each next one.
    pub sequence: u64,
    /// The run that numbers it (the daemon's start, ns since the epoch).
    pub run_id: u64,
    pub channel: ChannelId,
    /// The flag's `end_sample`.
    pub end_sample: u64,
    pub sample_rate_hz: f64,
    pub subject: AlertSubject,
    pub state: AlertState,
    pub severity: FlagLevel,
    pub previous_severity: FlagLevel,
    /// The fault's envelope-spectrum score; for the velocity zone, the velocity RMS in mm/s.
    pub score: f64,
    /// 0.5 (undecided) to 1: how clearly the score stands above the thresholds and the other
    /// faults' scores, moved by the twin's latest fit; 1 for the velocity zone (a measurement).
    pub confidence: f64,
    /// The frequency the fault's flag watches; `None` for the velocity zone.
    pub fault_frequency_hz: Option<f64>,
    /// The twin's fit error for this fault's hypothesis; `None` before the channel's first fit
    /// and where the twin has no hypothesis (cage, velocity zone).
    pub twin_error: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spectrum_has_a_frequency_per_bin_and_one_of_an_older_log_reads_without_them() {
        let channel = ChannelId {
            sensor: "motor-de".into(),
            axis: "radial".into(),
        };
        let m = SpectrumMessage::new(channel, 10, [1.0, 2.0], 0.78125, 3, vec![1.0, 2.0, 3.0]);
        assert_eq!(m.frequency_hz, [0.0, 0.78125, 1.5625]);
        // A spectrum as versions before `frequency_hz` wrote it.
        let old = r#"{"channel":{"sensor":"s","axis":"a"},"end_sample":5,"band_hz":[1.0,2.0],
            "bin_hz":0.5,"windows_averaged":2,"amplitude":[1.0]}"#;
        let read: SpectrumMessage = serde_json::from_str(old).unwrap();
        assert_eq!((read.amplitude.len(), read.frequency_hz.len()), (1, 0));
    }
}
