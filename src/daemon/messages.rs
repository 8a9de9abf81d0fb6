//! What the daemon's pipeline hands to its sinks (the MCAP log, alerts, status), one type per
//! MCAP channel. Each carries the channel it belongs to and its position in **sample time**
//! (`end_sample`: one past the last sample the result covers), so that a replay reproduces
//! them at the same sample times.
//!
//! These types are also the log's schema: raw samples go to MCAP as protobuf (compact and
//! lossless: the integers the sensor sent plus its scale), everything else as JSON (low rate,
//! readable anywhere).

use serde::{Deserialize, Serialize};

/// Identifies one analysed signal: a sensor (node) and one of its axes.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ChannelId {
    /// The sensor's id from the config (e.g. `motor-de`).
    pub sensor: String,
    /// The axis name from the config (e.g. `radial`).
    pub axis: String,
}

impl std::fmt::Display for ChannelId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
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

/// The averaged squared-envelope spectrum, at a low rate. Topic `/spectrum/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpectrumMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub band_hz: [f64; 2],
    pub bin_hz: f64,
    pub windows_averaged: usize,
    /// Amplitude per bin from 0 Hz, g².
    pub amplitude: Vec<f32>,
}

/// Indicators and fault scores of the newest window. Topic `/indicators/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TwinMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub hypothesis: String,
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
}

/// A fault flag changed state. Topic `/flags/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlagMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    /// `outer_race`, `inner_race`, `ball`, `cage`.
    pub fault: String,
    /// `ok`, `watch`, `alarm`.
    pub from: String,
    pub to: String,
    pub score: f64,
    pub fault_frequency_hz: f64,
}

/// Something about the sensor or the bearing's life changed. Topic `/health/<sensor>/<axis>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HealthMessage {
    pub channel: ChannelId,
    pub end_sample: u64,
    /// `lost`, `back`, `gap`, `restart`, `saturation`, `flat_line`, `stage`.
    pub kind: String,
    /// For `stage`: `learning`, `healthy`, `degrading`, `failing`.
    pub stage: Option<String>,
    pub detail: String,
}

/// The shaft speed a channel uses from `end_sample` on (every speed frame, every estimate).
/// Topic `/speed/<sensor>/<axis>`. A replay feeds the measured ones (`source = "can"`) back at
/// their samples, so its flags equal the live run's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedMessage {
    pub channel: ChannelId,
    /// The sample from which the speed applies.
    pub end_sample: u64,
    /// `can` (a speed frame) or `estimate` (estimated from the spectrum).
    pub source: String,
    /// The speed as given: the frame's value (`null`: "not available") or the estimate, rpm.
    pub given_rpm: Option<f64>,
    /// The speed the channel scores with from here; `null` when the given one is not usable
    /// (not available, 0, above `max_rpm`): the channel then scores nothing.
    pub rpm: Option<f64>,
}

/// Counters of one source since the daemon started, every `outputs.status_interval_s` and
/// when the source stops. Topic `/ingest/<source>`, `<source>` `can-<interface>` or
/// `shm-<sensor>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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

/// Everything the pipeline emits, in the order it emits it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum PipelineMessage {
    Raw(RawBlock),
    Spectrum(SpectrumMessage),
    Indicators(IndicatorsMessage),
    Twin(TwinMessage),
    Flag(FlagMessage),
    Health(HealthMessage),
    Ingest(IngestMessage),
    Speed(SpeedMessage),
}
