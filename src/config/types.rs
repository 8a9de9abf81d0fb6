//! The validated configuration. Every value here has passed its checks: consumers use it as
//! is, without re-checking ranges or parsing strings.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::analysis::iso::SeveritySettings;
use crate::analysis::AnalysisSettings;
use crate::bearing::BearingGeometry;
use crate::messages::SpeedSource;

/// A complete, validated configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// At least one sensor; ids, CAN nodes and iceoryx2 services are unique.
    pub sensors: Vec<SensorConfig>,
    /// Settings of the analysis core (`[analysis]`).
    pub analysis: AnalysisSettings,
    /// How often the resonance band is chosen again, in seconds (`analysis.band_period_s`).
    /// Kept here because [`AnalysisSettings`] has no field for it yet.
    pub band_period_s: f64,
    /// The most signal, in seconds, a channel's evidence (each band selection's whole-record
    /// analysis, whose verdict the flags follow) spans: the samples since the channel's last
    /// gap or restart, up to this (`analysis.evidence_horizon_s`). Logs written before it
    /// existed read as the 10 s those versions analysed.
    #[serde(default = "default_evidence_horizon_s")]
    pub evidence_horizon_s: f64,
    /// The signal-model twin (`[twin]`).
    pub twin: TwinConfig,
    /// Fault-flag thresholds and the health baseline (`[thresholds]`).
    pub thresholds: ThresholdConfig,
    /// Where results go (`[outputs]`).
    pub outputs: OutputConfig,
    /// The fleet bridge over MQTT (`[fleet]`); `None` when it is off (the default).
    pub fleet: Option<FleetConfig>,
    /// The machine group and foundation of the ISO velocity zones (`[severity]`). Logs written
    /// before the section existed have none: read as the default.
    #[serde(default)]
    pub severity: SeveritySettings,
    /// The detectors turned on by a `[detectors.<name>]` section, with their settings. Logs
    /// written before the list existed have none.
    #[serde(default)]
    pub detectors: crate::analysis::detectors::DetectorSettings,
}

impl Config {
    /// The sample rate of every sensor, by id.
    pub fn sample_rates(&self) -> std::collections::HashMap<String, f64> {
        self.sensors
            .iter()
            .map(|s| (s.id.clone(), s.sample_rate_hz))
            .collect()
    }

    /// How many channels (sensor axes) the config analyses.
    pub fn channel_count(&self) -> usize {
        self.sensors.iter().map(|s| s.axes.len()).sum()
    }
}

/// One accelerometer (`[[sensors]]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorConfig {
    /// Unique, `[a-z0-9_-]{1,32}`; names MCAP channels and iceoryx2 services.
    pub id: String,
    /// Where the samples come from, with that transport's settings.
    pub transport: Transport,
    /// Sample rate, in Hz; in (0, 1 000 000].
    pub sample_rate_hz: f64,
    /// Acceleration of one integer count on the wire, in g; positive.
    pub scale_g_per_count: f64,
    /// 1 to 3 distinct axis names, in the order the sensor sends them.
    pub axes: Vec<String>,
    /// The monitored bearing, resolved from the catalog or from custom geometry.
    pub bearing: BearingGeometry,
    /// How the shaft speed is known.
    pub speed: Speed,
}

impl SensorConfig {
    /// Half the sample rate, in Hz.
    pub fn nyquist_hz(&self) -> f64 {
        self.sample_rate_hz / 2.0
    }
}

/// Where a sensor's samples come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Transport {
    /// The in-process simulated sensor node.
    Sim(SimConfig),
    /// SocketCAN.
    Can(CanConfig),
    /// iceoryx2 shared memory, from a local acquisition process.
    Shm(ShmConfig),
}

/// `[sensors.can]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CanConfig {
    /// SocketCAN interface, e.g. `can0`; at most 15 bytes (the kernel's limit).
    pub interface: String,
    /// The sensor node's id on the bus, 0..=15.
    pub node_id: u8,
    /// CAN FD frames instead of classic CAN.
    pub fd: bool,
}

/// `[sensors.shm]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShmConfig {
    /// iceoryx2 service carrying the samples; starts with `bearingd/`.
    pub service: String,
}

/// `[sensors.sim]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimConfig {
    /// The fault the simulated bearing develops.
    pub fault: SimFault,
    /// Sample time at which the fault appears, in seconds; >= 0.
    pub onset_s: f64,
    /// Impact amplitude relative to the model's nominal fault, in [0, 100]; 0 = no impacts.
    pub severity: f64,
    /// Standard deviation of the added white noise, in g; in [0, 100].
    pub noise_g: f64,
    /// Amplitude of the once-per-revolution (imbalance) tone, in g; in [0, 100]. Logs written
    /// before the key existed have none: read as the default, what the simulator made then.
    #[serde(default = "default_imbalance_g")]
    pub imbalance_g: f64,
    /// Seed of the simulator's random numbers (noise, slip jitter).
    pub seed: u64,
}

fn default_imbalance_g() -> f64 {
    SimConfig::default().imbalance_g
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            fault: SimFault::Outer,
            onset_s: 30.0,
            severity: 1.0,
            noise_g: 0.05,
            imbalance_g: 0.05,
            seed: 1,
        }
    }
}

/// Which fault the simulator produces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SimFault {
    None,
    Outer,
    Inner,
    Ball,
}

/// How a sensor's shaft speed is known (`[sensors.speed]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "source", rename_all = "snake_case")]
pub enum Speed {
    /// A constant speed, in revolutions per minute; in (0, 100 000).
    Fixed { rpm: f64 },
    /// Measured: the sensor's speed frames (`source = "can"`; the iceoryx2 transport carries
    /// the same frames). Until the first frame the channel uses `nominal_rpm` if given, else it
    /// scores no fault and says so.
    #[serde(rename = "can")]
    Frames {
        /// The speed to assume until the first speed frame; in (0, 100 000).
        nominal_rpm: Option<f64>,
        /// The highest speed the channel analyses (its envelope spectrum is sized for the fault
        /// harmonics at this speed); above `nominal_rpm`, below 100 000. A frame above it (or
        /// "not available", or 0) leaves the channel without a usable speed until the next.
        max_rpm: f64,
    },
    /// Estimated from the vibration within `rpm·(1 ± search)`, at every band selection.
    Estimate {
        /// The nominal speed, in revolutions per minute; in (0, 100 000).
        rpm: f64,
        /// Relative half-width of the search; in (0, 0.3].
        search: f64,
    },
}

impl Speed {
    /// The speed the channel assumes at its start, rpm; `None` while it must wait for a speed
    /// frame. (An estimating channel starts at its nominal speed, but scores nothing before its
    /// first band selection, which estimates first.)
    pub fn initial_rpm(&self) -> Option<f64> {
        match *self {
            Speed::Fixed { rpm } | Speed::Estimate { rpm, .. } => Some(rpm),
            Speed::Frames { nominal_rpm, .. } => nominal_rpm,
        }
    }

    /// The highest speed the channel analyses, rpm.
    pub fn max_rpm(&self) -> f64 {
        match *self {
            Speed::Fixed { rpm } => rpm,
            Speed::Frames { max_rpm, .. } => max_rpm,
            Speed::Estimate { rpm, search } => rpm * (1.0 + search),
        }
    }

    /// Where the speed comes from (the config's `source`).
    pub fn source(&self) -> SpeedSource {
        match self {
            Speed::Fixed { .. } => SpeedSource::Fixed,
            Speed::Frames { .. } => SpeedSource::Can,
            Speed::Estimate { .. } => SpeedSource::Estimate,
        }
    }
}

/// Default `max_rpm` of `source = "can"` with a nominal speed: this factor times it.
pub(crate) const DEFAULT_MAX_RPM_FACTOR: f64 = 1.5;
/// Default `search` of `source = "estimate"`: ±5 %.
pub(crate) const DEFAULT_SPEED_SEARCH: f64 = 0.05;

/// `[twin]`: the signal-model twin's re-fit schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TwinConfig {
    /// Sample time between re-fits, in seconds.
    pub refit_period_s: f64,
    /// Length of signal each fit uses, in seconds.
    pub window_s: f64,
    /// Whether the Hammerstein–Wiener model (seed 003) is re-identified with each fit.
    #[serde(default = "default_hw_enabled")]
    pub hw_enabled: bool,
    /// Output state order of the HW model.
    #[serde(default)]
    pub hw_order: usize,
    /// Newest samples of the fit's signal the HW model is identified on.
    #[serde(default = "default_hw_samples")]
    pub hw_samples: usize,
    /// HW fits that form a channel's healthy baseline.
    #[serde(default = "default_hw_baseline_fits")]
    pub hw_baseline_fits: u64,
    /// A learned model (`bearingd train`) whose opinion of each re-fit's signal is logged with
    /// the twin's fit, combined with the envelope evidence (docs/PHYSICS.md, "Learned diagnosis"); none: off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learned_model: Option<std::path::PathBuf>,
}

// Logs written before the HW keys existed read as the defaults.
fn default_hw_enabled() -> bool {
    true
}
fn default_hw_samples() -> usize {
    2560
}
fn default_hw_baseline_fits() -> u64 {
    10
}

impl Default for TwinConfig {
    fn default() -> Self {
        TwinConfig {
            refit_period_s: 10.0,
            window_s: 1.0,
            hw_enabled: default_hw_enabled(),
            hw_order: 0,
            hw_samples: default_hw_samples(),
            hw_baseline_fits: default_hw_baseline_fits(),
            learned_model: None,
        }
    }
}

/// `[thresholds]`: fault flags (ok, watch, alarm) with hysteresis, and the health baseline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThresholdConfig {
    /// Fault score at which a flag rises to watch.
    pub watch_score: f64,
    /// Fault score at which a flag rises to alarm; above `watch_score`.
    pub alarm_score: f64,
    /// A flag falls back once its score is below `clear_ratio` × its threshold; in (0, 1).
    pub clear_ratio: f64,
    /// How long the score must stay above a threshold before the flag rises, in seconds
    /// (the daemon converts it to samples).
    pub on_delay_s: f64,
    /// How long the score must stay below the clear level before the flag falls, in seconds.
    pub off_delay_s: f64,
    /// Windows that form the health-stage baseline; at least 5.
    pub baseline_windows: usize,
    /// Standard deviations above the baseline that mark a change of health stage.
    pub sigma: f64,
    /// Sample time per point of the RMS trend, in seconds.
    #[serde(default = "default_trend_point_s")]
    pub trend_point_s: f64,
    /// Points of the RMS trend fitted (the newest).
    #[serde(default = "default_trend_points")]
    pub trend_points: usize,
}

// Logs written before the trend keys existed read as the defaults.
fn default_trend_point_s() -> f64 {
    60.0
}
fn default_trend_points() -> usize {
    30
}

impl Default for ThresholdConfig {
    fn default() -> Self {
        ThresholdConfig {
            watch_score: 5.0,
            alarm_score: 10.0,
            clear_ratio: 0.8,
            on_delay_s: 5.0,
            off_delay_s: 30.0,
            baseline_windows: 30,
            sigma: 3.0,
            trend_point_s: default_trend_point_s(),
            trend_points: default_trend_points(),
        }
    }
}

/// `[outputs]`: files, services and status.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputConfig {
    /// Persistent state (baselines, band choices).
    pub state_dir: PathBuf,
    /// MCAP log files.
    pub mcap_dir: PathBuf,
    /// An MCAP file is closed and a new one started at this size, in MiB (2^20 bytes).
    pub mcap_max_file_mb: u64,
    /// ...or at this age, in seconds.
    pub mcap_max_file_s: f64,
    /// Seconds of data between two forced writes (fsync) of the open MCAP file to the disk:
    /// what a power cut can lose. 0 forces every flush (every second of data).
    #[serde(default = "default_fsync_interval_s")]
    pub mcap_fsync_interval_s: f64,
    /// Disk space MCAP files may use before the oldest are deleted, in MiB; at least twice
    /// `mcap_max_file_mb` (one open file plus one finished).
    pub mcap_disk_budget_mb: u64,
    /// iceoryx2 service for fault alerts; starts with `bearingd/`.
    pub alerts_service: String,
    /// iceoryx2 root directory; absolute, not under `/tmp` or `/var/tmp`.
    pub iceoryx2_root: PathBuf,
    /// How often status is reported (systemd STATUS, stdout), in seconds.
    pub status_interval_s: f64,
    /// How often the learned state (health baselines) is saved to `state_dir` while running,
    /// in seconds of wall-clock time; it is also saved at every stop.
    pub state_save_interval_s: f64,
    /// The CPUs' wake-up latency bearingd caps while it runs, in µs (Linux PM QoS,
    /// `/dev/cpu_dma_latency`); `None`: the kernel's idle policy.
    #[serde(default)]
    pub cpu_wakeup_latency_us: Option<u32>,
    /// Idle CPUs kept awake (PM QoS 0 µs) from a block's hand-over to the analysis until it
    /// is analysed, so that the alert's subscriber wakes on a CPU that is already awake.
    #[serde(default = "default_cpu_awake_during_analysis")]
    pub cpu_awake_during_analysis: bool,
}

impl OutputConfig {
    /// `mcap_max_file_mb` in bytes.
    pub fn mcap_max_file_bytes(&self) -> u64 {
        self.mcap_max_file_mb.saturating_mul(1 << 20)
    }

    /// `mcap_disk_budget_mb` in bytes.
    pub fn mcap_disk_budget_bytes(&self) -> u64 {
        self.mcap_disk_budget_mb.saturating_mul(1 << 20)
    }
}

/// Logs from before `cpu_awake_during_analysis` read as the default.
fn default_cpu_awake_during_analysis() -> bool {
    true
}

/// Logs from before `mcap_fsync_interval_s` read as the default.
fn default_fsync_interval_s() -> f64 {
    5.0
}

impl Default for OutputConfig {
    fn default() -> Self {
        OutputConfig {
            state_dir: PathBuf::from("/var/lib/bearingd"),
            mcap_dir: PathBuf::from("/var/log/bearingd"),
            mcap_max_file_mb: 256,
            mcap_max_file_s: 3600.0,
            mcap_fsync_interval_s: default_fsync_interval_s(),
            mcap_disk_budget_mb: 4096,
            alerts_service: "bearingd/alerts".to_string(),
            iceoryx2_root: PathBuf::from("/run/bearingd/iceoryx2"),
            status_interval_s: 5.0,
            state_save_interval_s: 60.0,
            cpu_wakeup_latency_us: None,
            cpu_awake_during_analysis: default_cpu_awake_during_analysis(),
        }
    }
}

/// Defaults of `[analysis]` keys that [`AnalysisSettings`] does not hold.
pub(crate) const DEFAULT_BAND_PERIOD_S: f64 = 20.0;
/// Defaults of sensor keys.
pub(crate) const DEFAULT_SCALE_G_PER_COUNT: f64 = 0.000488;
pub(crate) const DEFAULT_AXIS: &str = "radial";
pub(crate) const DEFAULT_CAN_INTERFACE: &str = "can0";

/// Where the broker is, and whether to speak TLS to it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Broker {
    /// `mqtts://`: TLS (rustls).
    pub tls: bool,
    pub host: String,
    pub port: u16,
}

impl std::fmt::Display for Broker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let scheme = if self.tls { "mqtts" } else { "mqtt" };
        write!(f, "{scheme}://{}:{}", self.host, self.port)
    }
}

/// The validated `[fleet]` section (present only when `enabled = true`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FleetConfig {
    pub broker: Broker,
    /// Sparkplug group id: 1 to 64 of `A-Z a-z 0-9 - _ .`.
    pub group_id: String,
    /// Sparkplug edge node id (this box), same characters.
    pub node_id: String,
    /// MQTT client id; default `bearingd-<node_id>`.
    pub client_id: String,
    pub username: Option<String>,
    /// A file whose first line is the password (kept out of the config, which is readable by
    /// all).
    pub password_file: Option<PathBuf>,
    /// CA certificates (PEM) to trust for `mqtts://`; without it, the system's roots.
    pub ca_file: Option<PathBuf>,
    /// Client certificate chain and key (PEM), for brokers that authenticate clients by
    /// certificate.
    pub client_cert_file: Option<PathBuf>,
    pub client_key_file: Option<PathBuf>,
    /// Seconds of sample time between two data records of a channel (flag and stage changes go
    /// at once).
    pub publish_period_s: f64,
    /// MQTT keep-alive, in seconds: how soon the broker notices a dead link and sends the
    /// NDEATH (after 1.5 × this).
    pub keep_alive_s: f64,
    /// The store-and-forward queue's directory; default `<state_dir>/fleet`.
    pub queue_dir: PathBuf,
    /// The queue's size limit, in MiB; when full, the oldest records are dropped and counted.
    pub queue_max_mb: f64,
    /// The Sparkplug 3.0 primary host whose STATE (`spBv1.0/STATE/<id>`) gates publishing:
    /// births and data only while it is online, records queued meanwhile. `None`: publish
    /// whenever connected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub primary_host_id: Option<String>,
}

impl FleetConfig {
    pub fn queue_max_bytes(&self) -> u64 {
        (self.queue_max_mb * (1u64 << 20) as f64) as u64
    }
}

/// Seconds of history a channel's evidence spans unless configured (and in logs written before
/// the key existed).
pub const DEFAULT_EVIDENCE_HORIZON_S: f64 = 10.0;

fn default_evidence_horizon_s() -> f64 {
    DEFAULT_EVIDENCE_HORIZON_S
}
