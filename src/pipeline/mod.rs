//! The per-channel pipeline, shared by `run` and `replay`: inputs in sample time (sample blocks
//! and sensor events, whatever their source) → one [`ChannelMonitor`] per channel →
//! [`Output`]s: messages for the sinks, and requests for the twin's re-fit ([`refit`]).
//!
//! Synchronous and single-threaded on purpose: it runs on its own thread in `run` and in
//! `replay` alike, and its outputs depend only on its inputs, so a replay of the logged raw
//! samples gives the same flags at the same samples.
//!
//! One exception to "single-threaded": band selections run on the [`bands`] worker thread,
//! their results used a fixed sample-time delay ([`band_delay_s`]) after they started, so the
//! outputs still depend only on the inputs.
//!
//! Alerts are decided here, once ([`alerts`]): each flag change is followed at once by its
//! [`Output::Alert`], numbered and weighed, for every sink that wants it.
//!
//! [`Sink`] is the seam to the sinks: the pipeline's messages and alerts go to whatever
//! implements it (the MCAP log, the alert publisher, the fleet bridge, the command line's flag
//! printer), and the pipeline knows none of them.

pub mod alerts;
pub mod bands;
pub mod priority;
pub mod refit;
mod sink;
pub mod twin_queue;

pub use refit::{load_learned, TwinWorker};
pub use sink::{Sink, SinkError, SinkItem};

use crate::analysis::agreement::Witness;
use crate::analysis::flags::FlagSettings;
use crate::analysis::health::Baseline;
use crate::analysis::monitor::{ChannelMonitor, MonitorEvent, MonitorSettings, TrendSettings};
use crate::analysis::speed::{SpeedMode, SpeedSearch};
use crate::analysis::Band;
use crate::bearing::FaultFrequencies;
use crate::config::{Config, SensorConfig, Speed};
use crate::messages::detect::all_flags;
use crate::messages::{
    AlertMessage, ChannelId, FaultKind, FlagLevel, FlagMessage, HealthKind, HealthMessage,
    HealthStage, IndicatorsMessage, IngestMessage, PipelineMessage, RawBlock, SpectrumMessage,
    SpeedMessage, SpeedSource, TrendMessage, TwinMessage,
};
use alerts::{history_size_for, pass_on, AlertTracker};
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

/// What the pipeline consumes.
#[derive(Debug, Clone)]
pub enum Input {
    /// Consecutive integer counts of one channel starting at `first_sample`.
    Samples {
        channel: ChannelId,
        first_sample: u64,
        scale_g_per_count: f64,
        counts: Vec<i16>,
    },
    /// The source has not heard the sensor for longer than its timeout, or hears it again.
    SensorLost {
        sensor: String,
    },
    SensorBack {
        sensor: String,
    },
    /// The sensor (node) restarted: its sample positions start again.
    Restart {
        channel: ChannelId,
        first_sample: u64,
    },
    /// A speed frame of the sensor (`rpm` `None`: "not available"). It takes effect at each
    /// of the sensor's channels at the sample that channel has reached; ignored unless the
    /// sensor's speed source is `can`.
    Speed {
        sensor: String,
        rpm: Option<f64>,
    },
    /// A logged measured speed (a replay): takes effect at its own sample.
    LoggedSpeed(SpeedMessage),
    /// A live source's counters, passed on to the sinks (the log) in order with the data.
    Ingest(IngestMessage),
}

/// A request for the twin's re-fit, handed to the re-fit thread.
#[derive(Debug, Clone)]
pub struct TwinRequest {
    pub channel: ChannelId,
    pub end_sample: u64,
    pub fs_hz: f64,
    pub freqs: FaultFrequencies,
    /// Bands of the outer-race, inner-race and ball hypotheses.
    pub bands: [Band; 3],
    pub samples: Vec<f32>,
    /// The fault of the channel's highest raised flag (none when every flag is ok), and the
    /// fault its latest verdict named by agreement with the learned model: what the learned
    /// opinion logged with the fit is compared with.
    pub flagged: Option<FaultKind>,
    pub agreed: Option<FaultKind>,
}

/// The fault of a channel's highest raised flag; `None` when every flag is ok.
fn flagged_fault(monitor: &ChannelMonitor) -> Option<FaultKind> {
    let levels = monitor.flag_levels();
    (0..4)
        .filter(|&i| levels[i] != FlagLevel::Ok)
        .max_by_key(|&i| levels[i])
        .map(|i| FaultKind::ALL[i])
}

/// What the pipeline produces.
#[derive(Debug, Clone)]
pub enum Output {
    Message(PipelineMessage),
    /// The alert of the flag change just emitted (and any repeats it causes).
    Alert(AlertMessage),
    Twin(TwinRequest),
}

/// The latest state of a channel, for status lines, systemd's status and the exit summary.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelStatus {
    pub channel: ChannelId,
    /// The speed the channel scores with; `None` while it has none (see `speed_source`).
    pub rpm: Option<f64>,
    pub speed_source: SpeedSource,
    pub samples: u64,
    pub seconds: f64,
    pub band_hz: Option<[f64; 2]>,
    pub top_fault: Option<FaultKind>,
    pub top_score: f64,
    pub flags: [FlagLevel; 4],
    pub stage: HealthStage,
    pub gaps: u64,
    pub missing_samples: u64,
    pub twin_hypothesis: Option<FaultKind>,
    pub twin_error: Option<f64>,
    pub sensor_lost: bool,
    pub flag_changes: u64,
    /// What the detectors' latest readings show, by key (`("iso", "B(2.10mm/s)")`), in the
    /// order they first came.
    pub readings: Vec<(&'static str, String)>,
    /// Every registered detector's flags by name, in registry order (the velocity zone flag
    /// `iso_zone`: watch in zone C, alarm in zone D).
    pub detector_flags: Vec<(&'static str, FlagLevel)>,
}

impl ChannelStatus {
    /// A channel before its first sample: every flag ok, the registry's detector flags too.
    pub fn new(
        channel: ChannelId,
        rpm: Option<f64>,
        speed_source: SpeedSource,
        stage: HealthStage,
    ) -> Self {
        ChannelStatus {
            channel,
            rpm,
            speed_source,
            samples: 0,
            seconds: 0.0,
            band_hz: None,
            top_fault: None,
            top_score: 0.0,
            flags: [FlagLevel::Ok; 4],
            stage,
            gaps: 0,
            missing_samples: 0,
            twin_hypothesis: None,
            twin_error: None,
            sensor_lost: false,
            flag_changes: 0,
            readings: Vec::new(),
            detector_flags: all_flags().map(|f| (f.name, FlagLevel::Ok)).collect(),
        }
    }

    /// The raised flags as `fault=level` joined by commas (`outer_race=alarm,ball=watch`, the
    /// velocity zone flag as `iso_zone=watch`), or `ok` when none is raised.
    pub fn flags_summary(&self) -> String {
        let raised: Vec<String> = FaultKind::ALL
            .iter()
            .map(|f| f.name())
            .zip(&self.flags)
            .chain(
                self.detector_flags
                    .iter()
                    .map(|(name, level)| (*name, level)),
            )
            .filter(|(_, level)| **level != FlagLevel::Ok)
            .map(|(fault, level)| format!("{fault}={level}"))
            .collect();
        if raised.is_empty() {
            "ok".to_string()
        } else {
            raised.join(",")
        }
    }

    /// Keeps `text` as the latest reading shown under `key`.
    fn set_reading(&mut self, key: &'static str, text: String) {
        match self.readings.iter_mut().find(|(k, _)| *k == key) {
            Some((_, shown)) => *shown = text,
            None => self.readings.push((key, text)),
        }
    }

    /// Sets the level of the detector flag `name`.
    fn set_detector_flag(&mut self, name: &str, to: FlagLevel) {
        for (flag, level) in &mut self.detector_flags {
            if *flag == name {
                *level = to;
            }
        }
    }
}

struct Channel {
    monitor: ChannelMonitor,
    fs_hz: f64,
    status: ChannelStatus,
    next_spectrum: u64,
    next_twin: u64,
}

/// The analysis stage.
pub struct Pipeline {
    channels: BTreeMap<ChannelId, Channel>,
    /// Blocks of channels the config does not know, per channel: skipped, counted, reported.
    unknown: BTreeMap<ChannelId, u64>,
    /// Seconds of sample time between two logged spectra (Foxglove plots below ~60 Hz).
    spectrum_every_s: f64,
    twin_period_s: f64,
    twin_window_s: f64,
    alerts: AlertTracker,
}

/// The monitor settings of one sensor: the config's durations turned into samples.
///
/// `turn` of `turns` staggers the channel's band selections and window ends among the daemon's
/// channels ([`MonitorSettings::band_phase_samples`], [`MonitorSettings::window_stagger`]).
pub fn monitor_settings(
    config: &Config,
    sensor: &SensorConfig,
    turn: usize,
    turns: usize,
) -> MonitorSettings {
    let fs = sensor.sample_rate_hz;
    let t = &config.thresholds;
    let samples = |seconds: f64| (seconds * fs).round().max(0.0) as u64;
    MonitorSettings {
        fs_hz: fs,
        analysis: config.analysis.clone(),
        band_period_samples: samples(config.band_period_s),
        band_phase_samples: samples(config.band_period_s * turn as f64 / turns.max(1) as f64),
        window_stagger: (turn, turns.max(1)),
        band_history_samples: samples(band_history_s(config)) as usize,
        flags: FlagSettings {
            watch_score: t.watch_score,
            alarm_score: t.alarm_score,
            clear_ratio: t.clear_ratio,
            on_delay_samples: samples(t.on_delay_s),
            off_delay_samples: samples(t.off_delay_s),
        },
        baseline_windows: t.baseline_windows as u64,
        sigma: t.sigma,
        trend: TrendSettings {
            point_s: t.trend_point_s,
            points: t.trend_points,
            ..TrendSettings::default()
        },
        clip_count: i32::from(i16::MAX),
        flat_line_samples: samples(1.0),
        speed: match sensor.speed {
            Speed::Fixed { .. } => SpeedMode::Fixed,
            Speed::Frames {
                nominal_rpm,
                max_rpm,
            } => SpeedMode::Given {
                known_at_start: nominal_rpm.is_some(),
                max_shaft_hz: max_rpm / 60.0,
            },
            Speed::Estimate { rpm, search } => SpeedMode::Estimate(SpeedSearch {
                nominal_hz: rpm / 60.0,
                range: search,
            }),
        },
        detectors: config.detectors.clone().with_severity(config.severity),
    }
}

/// Seconds of sample time between two logged spectra.
const SPECTRUM_EVERY_S: f64 = 1.0;

/// Seconds of signal a band selection (and the verdict the flags follow) analyses at most: the
/// evidence horizon.
pub fn band_history_s(config: &Config) -> f64 {
    config.evidence_horizon_s
}

/// Seconds of sample time to a channel's first band selection: one band period, or the
/// evidence horizon if that fills first (as the monitor schedules it).
pub fn first_selection_s(config: &Config) -> f64 {
    config.band_period_s.min(config.evidence_horizon_s)
}

/// Seconds of sample time from a band selection's start (on the worker thread) to the sample
/// where its bands are used: 2 s, or half the band period if that is shorter. Long enough for
/// the worker to finish the selections of many channels (30–100 ms each) before the analysis
/// needs them; short against the band period (default 20 s) and the flags' delays.
pub fn band_delay_s(config: &Config) -> f64 {
    (config.band_period_s / 2.0).min(MAX_BAND_DELAY_S)
}

const MAX_BAND_DELAY_S: f64 = 2.0;

/// Seconds of sample time between the first band selections of two channels (a selection
/// takes 30–100 ms; each holds a copy of its channel's history until it is done).
const FIRST_SELECTION_SPACING_S: f64 = 0.25;

impl Channel {
    /// A speed given from outside, at `at_sample` of this channel.
    fn speed_at(
        &mut self,
        id: &ChannelId,
        at_sample: u64,
        rpm: Option<f64>,
        spectrum_every_s: f64,
        out: &mut impl FnMut(Output),
    ) {
        self.drive(id, spectrum_every_s, out, |monitor, mut on_event| {
            monitor.set_speed_at(at_sample, rpm.map(|r| r / 60.0), &mut on_event)
        });
    }

    /// Runs `step` on the channel's monitor with its events turned into the pipeline's outputs,
    /// then takes the flags into the channel's status.
    fn drive(
        &mut self,
        id: &ChannelId,
        spectrum_every_s: f64,
        out: &mut impl FnMut(Output),
        step: impl FnOnce(&mut ChannelMonitor, &mut dyn FnMut(MonitorEvent)),
    ) {
        let fs = self.fs_hz;
        let Channel {
            monitor,
            status,
            next_spectrum,
            ..
        } = self;
        step(monitor, &mut |event| {
            handle_event(id, fs, spectrum_every_s, next_spectrum, status, event, out)
        });
        self.status.flags = self.monitor.flag_levels();
    }
}

impl Pipeline {
    /// One monitor per (sensor, axis); `baselines` resumes health stages kept across restarts;
    /// `witness` (the learned model) is heard by every channel's verdicts when
    /// `analysis.agreement_*` is set.
    pub fn new(
        config: &Config,
        baselines: &BTreeMap<ChannelId, Baseline>,
        witness: Option<Arc<dyn Witness>>,
    ) -> Self {
        let mut channels = BTreeMap::new();
        let turns: usize = config.sensors.iter().map(|s| s.axes.len()).sum();
        let mut turn = 0;
        let worker = bands::BandWorker::start(turns);
        for sensor in &config.sensors {
            // Without a starting speed the channel waits (nothing is scored); its frequencies
            // are then those at the highest speed, for sizing only.
            let start_rpm = sensor
                .speed
                .initial_rpm()
                .unwrap_or_else(|| sensor.speed.max_rpm());
            let freqs = sensor.bearing.fault_frequencies(start_rpm / 60.0);
            for axis in &sensor.axes {
                let id = ChannelId {
                    sensor: sensor.id.clone(),
                    axis: axis.clone(),
                };
                let mut monitor = ChannelMonitor::new(
                    monitor_settings(config, sensor, turn, turns),
                    freqs,
                    baselines.get(&id).cloned(),
                );
                if let Some(witness) = &witness {
                    monitor = monitor.with_witness(Arc::clone(witness));
                }
                if let Some(worker) = &worker {
                    // The channels' first selections (all due when their histories fill) take
                    // turns, FIRST_SELECTION_SPACING_S apart (within one band period), so that
                    // the worker is not handed every channel's history at once.
                    let fs = sensor.sample_rate_hz;
                    let spacing_s =
                        FIRST_SELECTION_SPACING_S.min(config.band_period_s / turns.max(1) as f64);
                    monitor = monitor.with_band_selector(
                        Box::new(worker.selector()),
                        (band_delay_s(config) * fs).round() as u64,
                        (spacing_s * turn as f64 * fs).round() as u64,
                    );
                }
                turn += 1;
                let status = ChannelStatus::new(
                    id.clone(),
                    monitor.shaft_hz().map(|hz| hz * 60.0),
                    sensor.speed.source(),
                    monitor.health().stage(),
                );
                let fs_hz = sensor.sample_rate_hz;
                channels.insert(
                    id,
                    Channel {
                        monitor,
                        fs_hz,
                        status,
                        next_spectrum: 0,
                        next_twin: (first_selection_s(config) * fs_hz) as u64,
                    },
                );
            }
        }
        Pipeline {
            channels,
            unknown: BTreeMap::new(),
            spectrum_every_s: SPECTRUM_EVERY_S,
            twin_period_s: config.twin.refit_period_s,
            twin_window_s: config.twin.window_s,
            alerts: AlertTracker::new(
                0,
                history_size_for(turns),
                &config.analysis,
                config.sample_rates(),
            ),
        }
    }

    /// Names the run its alerts belong to (their `run_id`; 0 unless named).
    pub fn with_run_id(mut self, run_id: u64) -> Self {
        self.alerts.set_run_id(run_id);
        self
    }

    /// Channels that sent blocks the config does not know, with the number of blocks skipped.
    pub fn unknown_channels(&self) -> &BTreeMap<ChannelId, u64> {
        &self.unknown
    }

    pub fn channels(&self) -> impl Iterator<Item = &ChannelId> {
        self.channels.keys()
    }

    pub fn status(&self) -> Vec<ChannelStatus> {
        self.channels.values().map(|c| c.status.clone()).collect()
    }

    pub fn baselines(&self) -> BTreeMap<ChannelId, Baseline> {
        self.channels
            .iter()
            .map(|(id, c)| (id.clone(), c.monitor.health().baseline().clone()))
            .collect()
    }

    /// Takes a twin fit made for a request of this pipeline: into the channel's status, and
    /// into the confidence of its later alerts.
    pub fn note_twin(&mut self, fit: &TwinMessage) {
        if let Some(c) = self.channels.get_mut(&fit.channel) {
            c.status.twin_hypothesis = Some(fit.hypothesis);
            c.status.twin_error = Some(fit.error);
        }
        self.alerts.note_twin(fit);
    }

    /// Handles one input; unknown channels are reported, not analysed.
    pub fn handle(&mut self, input: Input, out: &mut impl FnMut(Output)) {
        let alerts = &mut self.alerts;
        let out = &mut |output| pass_on(alerts, output, out);
        match input {
            Input::Samples {
                channel,
                first_sample,
                scale_g_per_count,
                counts,
            } => {
                let spectrum_every_s = self.spectrum_every_s;
                let (twin_period_s, twin_window_s) = (self.twin_period_s, self.twin_window_s);
                let Some(c) = self.channels.get_mut(&channel) else {
                    *self.unknown.entry(channel).or_default() += 1;
                    return;
                };
                out(Output::Message(PipelineMessage::Raw(RawBlock {
                    channel: channel.clone(),
                    first_sample,
                    sample_rate_hz: c.fs_hz,
                    scale_g_per_count,
                    counts: counts.iter().map(|&c| i32::from(c)).collect(),
                })));
                c.drive(&channel, spectrum_every_s, out, |monitor, mut on_event| {
                    monitor.push_counts(first_sample, &counts, scale_g_per_count, &mut on_event)
                });
                let fs = c.fs_hz;
                c.status.samples = c.monitor.next_sample();
                c.status.seconds = c.status.samples as f64 / fs;
                c.status.flags = c.monitor.flag_levels();
                c.status.stage = c.monitor.health().stage();
                if c.monitor.bands().is_none() {
                    c.status.band_hz = None;
                }
                if let Some(bands) = c.monitor.bands().filter(|_| c.monitor.shaft_hz().is_some()) {
                    if c.monitor.next_sample() >= c.next_twin {
                        c.next_twin = c.monitor.next_sample() + (twin_period_s * fs) as u64;
                        out(Output::Twin(TwinRequest {
                            channel: channel.clone(),
                            end_sample: c.monitor.next_sample(),
                            fs_hz: fs,
                            freqs: *c.monitor.frequencies(),
                            bands: [bands[0], bands[1], bands[2]],
                            samples: c.monitor.recent_samples((twin_window_s * fs) as usize),
                            flagged: flagged_fault(&c.monitor),
                            agreed: c.monitor.agreed_fault(),
                        }));
                    }
                }
            }
            Input::Speed { sensor, rpm } => {
                let spectrum_every_s = self.spectrum_every_s;
                for (id, c) in self
                    .channels
                    .iter_mut()
                    .filter(|(id, _)| id.sensor == sensor)
                {
                    let at = c.monitor.next_sample();
                    c.speed_at(id, at, rpm, spectrum_every_s, out);
                }
            }
            Input::LoggedSpeed(logged) => {
                let spectrum_every_s = self.spectrum_every_s;
                if logged.source == SpeedSource::Can {
                    if let Some(c) = self.channels.get_mut(&logged.channel) {
                        c.speed_at(
                            &logged.channel,
                            logged.end_sample,
                            logged.given_rpm,
                            spectrum_every_s,
                            out,
                        );
                    }
                }
            }
            Input::Ingest(message) => out(Output::Message(PipelineMessage::Ingest(message))),
            Input::SensorLost { sensor } => sensor_event(&mut self.channels, &sensor, true, out),
            Input::SensorBack { sensor } => sensor_event(&mut self.channels, &sensor, false, out),
            Input::Restart {
                channel,
                first_sample,
            } => {
                if let Some(c) = self.channels.get(&channel) {
                    out(Output::Message(PipelineMessage::Health(HealthMessage {
                        channel: channel.clone(),
                        end_sample: c.monitor.next_sample(),
                        kind: HealthKind::Restart,
                        stage: None,
                        detail: format!(
                            "the sensor node restarted; its samples start again at {first_sample}"
                        ),
                    })));
                }
            }
        }
    }

    /// The end of the input (a replay run's end, a clean stop): every channel decides once more
    /// on the evidence it has not yet analysed ([`ChannelMonitor::finish`]), so its flags end
    /// on the verdict of everything it saw.
    pub fn finish(&mut self, out: &mut impl FnMut(Output)) {
        let spectrum_every_s = self.spectrum_every_s;
        let alerts = &mut self.alerts;
        let out = &mut |output| pass_on(alerts, output, out);
        for (id, c) in &mut self.channels {
            c.drive(id, spectrum_every_s, out, |monitor, mut on_event| {
                monitor.finish(&mut on_event)
            });
        }
    }
}

/// A sensor lost or back: a health message for each of its channels.
fn sensor_event(
    channels: &mut BTreeMap<ChannelId, Channel>,
    sensor: &str,
    lost: bool,
    out: &mut impl FnMut(Output),
) {
    for (id, c) in channels.iter_mut().filter(|(id, _)| id.sensor == sensor) {
        c.status.sensor_lost = lost;
        out(Output::Message(PipelineMessage::Health(HealthMessage {
            channel: id.clone(),
            end_sample: c.monitor.next_sample(),
            kind: if lost {
                HealthKind::Lost
            } else {
                HealthKind::Back
            },
            stage: None,
            detail: if lost {
                "no frame from the sensor within its timeout".into()
            } else {
                "the sensor sends again".into()
            },
        })));
    }
}

fn handle_event(
    channel: &ChannelId,
    fs: f64,
    spectrum_every_s: f64,
    next_spectrum: &mut u64,
    status: &mut ChannelStatus,
    event: MonitorEvent,
    out: &mut impl FnMut(Output),
) {
    let message = match event {
        MonitorEvent::Window(w) => {
            let top = (0..4)
                .max_by(|&a, &b| w.scores[a].score.total_cmp(&w.scores[b].score))
                .unwrap_or(0);
            status.top_fault = Some(FaultKind::ALL[top]);
            status.top_score = w.scores[top].score;
            status.band_hz = Some([w.bands[top].lo_hz, w.bands[top].hi_hz]);
            // A window before the bands are known has no spectrum yet: nothing to log, and the
            // first spectrum is logged as soon as there is one (the schedule starts there).
            if w.end_sample >= *next_spectrum && !w.spectrum.is_empty() {
                *next_spectrum = w.end_sample + (spectrum_every_s * fs) as u64;
                out(Output::Message(PipelineMessage::Spectrum(
                    SpectrumMessage::new(
                        channel.clone(),
                        w.end_sample,
                        [w.spectrum_band.lo_hz, w.spectrum_band.hi_hz],
                        w.bin_hz,
                        w.windows_averaged,
                        w.spectrum.to_vec(),
                    ),
                )));
            }
            PipelineMessage::Indicators(IndicatorsMessage {
                channel: channel.clone(),
                end_sample: w.end_sample,
                rpm: status.rpm.unwrap_or(f64::NAN),
                band_hz: [w.bands[top].lo_hz, w.bands[top].hi_hz],
                rms: w.indicators.rms,
                peak: w.indicators.peak,
                crest: w.indicators.crest,
                kurtosis: w.indicators.kurtosis,
                score_outer_race: w.scores[0].score,
                score_inner_race: w.scores[1].score,
                score_ball: w.scores[2].score,
                score_cage: w.scores[3].score,
            })
        }
        MonitorEvent::Flag {
            fault,
            change,
            score,
            frequency_hz,
            runner_up,
        } => {
            status.flag_changes += 1;
            PipelineMessage::Flag(FlagMessage {
                channel: channel.clone(),
                end_sample: change.at_sample,
                fault,
                from: change.from,
                to: change.to,
                score,
                fault_frequency_hz: frequency_hz,
                runner_up_score: Some(runner_up),
            })
        }
        MonitorEvent::Detector(mut message) => {
            message.set_channel(channel.clone());
            if let Some((key, text)) = message.status() {
                status.set_reading(key, text);
            }
            if let Some(flag) = message.as_flag() {
                status.set_detector_flag(flag.flag().name, flag.change().1);
            }
            PipelineMessage::Detector(message)
        }
        MonitorEvent::Trend { point, stage } => PipelineMessage::Trend(TrendMessage {
            channel: channel.clone(),
            end_sample: point.end_sample,
            stage,
            rms: point.rms,
            points: point.points,
            threshold: point.fit.map(|f| f.threshold),
            rate_per_s: point.fit.map(|f| f.rate_per_s),
            doubling_s: point.fit.and_then(|f| f.doubling_s),
            time_to_threshold_s: point.fit.and_then(|f| f.time_to_threshold_s()),
            earliest_s: point.fit.and_then(|f| f.earliest_s.map(|t| t - f.now_s)),
            latest_s: point.fit.and_then(|f| f.latest_s.map(|t| t - f.now_s)),
            confidence: point.confidence,
        }),
        MonitorEvent::Stage(change) => PipelineMessage::Health(HealthMessage {
            channel: channel.clone(),
            end_sample: change.at_sample,
            kind: HealthKind::Stage,
            stage: Some(change.to),
            detail: format!("health stage {} → {}", change.from, change.to),
        }),
        MonitorEvent::Sensor {
            condition,
            active,
            at_sample,
        } => PipelineMessage::Health(HealthMessage {
            channel: channel.clone(),
            end_sample: at_sample,
            kind: condition.into(),
            stage: None,
            detail: if active {
                format!("{} started", HealthKind::from(condition))
            } else {
                format!("{} ended", HealthKind::from(condition))
            },
        }),
        MonitorEvent::Gap { at_sample, missing } => {
            status.gaps += 1;
            status.missing_samples += missing;
            PipelineMessage::Health(HealthMessage {
                channel: channel.clone(),
                end_sample: at_sample,
                kind: HealthKind::Gap,
                stage: None,
                detail: format!(
                    "{missing} samples missing; the analysis windows restart after the gap"
                ),
            })
        }
        MonitorEvent::Speed {
            at_sample,
            shaft_hz,
            given_hz,
            estimated,
        } => {
            status.rpm = shaft_hz.map(|hz| hz * 60.0);
            PipelineMessage::Speed(SpeedMessage {
                channel: channel.clone(),
                end_sample: at_sample,
                source: if estimated {
                    SpeedSource::Estimate
                } else {
                    SpeedSource::Can
                },
                given_rpm: given_hz.map(|hz| hz * 60.0),
                rpm: shaft_hz.map(|hz| hz * 60.0),
            })
        }
        MonitorEvent::Bands {
            at_sample,
            bands,
            selected,
            evidence,
            evidence_from,
        } => PipelineMessage::Health(HealthMessage {
            channel: channel.clone(),
            end_sample: at_sample,
            kind: HealthKind::Bands,
            stage: None,
            detail: format!(
                "bands re-selected: outer {} inner {} ball {} cage {} (method's choice {}){}",
                bands[0],
                bands[1],
                bands[2],
                bands[3],
                selected,
                evidence.map_or(String::new(), |e| format!(
                    "; {}",
                    e.describe((at_sample.saturating_sub(evidence_from)) as f64 / fs)
                ))
            ),
        }),
    };
    out(Output::Message(message));
}
