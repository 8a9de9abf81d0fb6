//! The seam between the daemon and the bridge: the only file of `sinks::fleet` that knows the
//! daemon's message types and its `Sink` trait (so that moving them, e.g. to `messages.rs` and
//! `pipeline/`, touches this file alone).
//!
//! On the daemon's sink thread it turns each [`PipelineMessage`] into an [`Observation`]: the
//! channel becomes a device index, the sample position a time in milliseconds since the epoch
//! (`origin + sample / fs`, the mapping of the MCAP log). A fault flag's change is taken from
//! the pipeline's alert of it, which carries the confidence the alert service publishes
//! (decided once, in `pipeline::alerts`). Raw samples, spectra, speed frames' bookkeeping and
//! ingest counters do not leave the box.

use super::bridge::{self, BridgeError, BridgeHandle, Notices};
use super::metrics::{device_id, Observation, Observed};
use crate::config::Config;
use crate::messages::{
    AlertMessage, AlertState, AlertSubject, ChannelId, HealthKind, PipelineMessage,
};
use crate::pipeline::{Sink, SinkError};
use std::collections::HashMap;

/// The fleet bridge as a sink of `bearingd run`.
pub struct FleetSink {
    handle: Option<BridgeHandle>,
    channels: HashMap<ChannelId, usize>,
    rates: HashMap<String, f64>,
    origin_ns: u64,
    /// The bridge thread is gone (said once).
    gone: bool,
    notices: Notices,
}

impl FleetSink {
    /// Starts the bridge of `config.fleet`; `None` when the bridge is off. `origin_ns`: the
    /// wall time of sample 0 (the MCAP log's origin); `notices`: where the bridge's notices go.
    pub fn start(
        config: &Config,
        origin_ns: u64,
        notices: Notices,
    ) -> Result<Option<FleetSink>, BridgeError> {
        let Some(fleet) = config.fleet.clone() else {
            return Ok(None);
        };
        let mut channels = HashMap::new();
        let mut devices = Vec::new();
        for sensor in &config.sensors {
            for axis in &sensor.axes {
                let id = ChannelId {
                    sensor: sensor.id.clone(),
                    axis: axis.clone(),
                };
                channels.insert(id, devices.len());
                devices.push(device_id(&sensor.id, axis));
            }
        }
        let rates: HashMap<String, f64> = config
            .sensors
            .iter()
            .map(|s| (s.id.clone(), s.sample_rate_hz))
            .collect();
        notices(format!(
            "fleet: publishing {} channel(s) to {} as spBv1.0/{}/…/{} (queue {})",
            devices.len(),
            fleet.broker,
            fleet.group_id,
            fleet.node_id,
            fleet.queue_dir.display()
        ));
        let handle = bridge::start(fleet, devices, notices.clone())?;
        Ok(Some(FleetSink {
            handle: Some(handle),
            channels,
            rates,
            origin_ns,
            gone: false,
            notices,
        }))
    }

    fn at_ms(&self, channel: &ChannelId, sample: u64) -> u64 {
        let fs = self.rates.get(&channel.sensor).copied().unwrap_or(1.0);
        (self.origin_ns + (sample as f64 / fs * 1e9) as u64) / 1_000_000
    }

    /// The observation of a fault flag's change: its alert (a repeat changes nothing; the
    /// velocity zone goes as the zone metric, from its readings).
    fn flag_observation(&self, alert: &AlertMessage) -> Option<Observation> {
        let AlertSubject::Fault(fault) = alert.subject else {
            return None;
        };
        if alert.state == AlertState::Repeated {
            return None;
        }
        Some(Observation {
            device: *self.channels.get(&alert.channel)?,
            at_ms: self.at_ms(&alert.channel, alert.end_sample),
            what: Observed::Flag {
                fault,
                level: alert.severity,
                score: alert.score,
                confidence: alert.confidence,
            },
        })
    }

    fn observation(&self, message: &PipelineMessage) -> Option<Observation> {
        let what = match message {
            PipelineMessage::Indicators(m) => Observed::Window {
                rpm: m.rpm.is_finite().then_some(m.rpm),
                rms_g: m.rms,
                peak_g: m.peak,
                crest: m.crest,
                kurtosis: m.kurtosis,
                scores: [
                    m.score_outer_race,
                    m.score_inner_race,
                    m.score_ball,
                    m.score_cage,
                ],
            },
            PipelineMessage::Health(m) => match (m.kind, m.stage) {
                (HealthKind::Stage, Some(stage)) => Observed::Stage(stage),
                (HealthKind::Lost, _) => Observed::SensorLost(true),
                (HealthKind::Back, _) => Observed::SensorLost(false),
                _ => return None,
            },
            PipelineMessage::Twin(m) => Observed::Twin {
                hypothesis: m.hypothesis,
                error: m.error,
                margin: m.margin,
                errors: [m.error_outer_race, m.error_inner_race, m.error_ball],
                residual_energy_ratio: m.residual_energy_ratio,
                residual_peak_hz: m.residual_peak_hz,
            },
            PipelineMessage::Hw(m) => Observed::Hw {
                accuracy: m.accuracy_simulation,
                residual_drift_sigma: m.residual_drift_sigma,
                parameter_drift: m.parameter_drift,
            },
            PipelineMessage::Trend(m) => Observed::Trend {
                time_to_limit_s: m.time_to_threshold_s,
                earliest_s: m.earliest_s,
            },
            PipelineMessage::Speed(m) => Observed::Speed(m.rpm),
            // Every detector reading: its metrics go at the publish period, an urgent one (a new
            // ISO zone) at once. A detector's flag change has no metrics: its readings' follow
            // it (the zone metric changes first, and at once).
            PipelineMessage::Detector(m) => Observed::of_detector(m)?,
            // A fault flag goes with its alert, which comes right after it.
            PipelineMessage::Raw(_)
            | PipelineMessage::Spectrum(_)
            | PipelineMessage::Ingest(_)
            | PipelineMessage::Flag(_) => return None,
        };
        // Every message observed above has both.
        let (channel, sample) = (message.channel()?, message.end_sample()?);
        Some(Observation {
            device: *self.channels.get(channel)?,
            at_ms: self.at_ms(channel, sample),
            what,
        })
    }
}

impl FleetSink {
    fn send(&mut self, observation: Option<Observation>) {
        let Some(observation) = observation else {
            return;
        };
        let Some(handle) = self.handle.as_ref() else {
            return;
        };
        if handle.intake.blocking_send(observation).is_err() && !self.gone {
            self.gone = true;
            (self.notices)(
                "fleet: the bridge thread has stopped; nothing more is published".into(),
            );
        }
    }
}

impl Sink for FleetSink {
    fn write(&mut self, message: &PipelineMessage) {
        self.send(self.observation(message));
    }

    fn alert(&mut self, alert: &AlertMessage) {
        self.send(self.flag_observation(alert));
    }

    fn finish(&mut self) -> Result<(), SinkError> {
        let Some(handle) = self.handle.take() else {
            return Ok(());
        };
        drop(handle.intake);
        handle.thread.join().map(|_| ()).map_err(|_| SinkError {
            sink: "fleet bridge",
            count: 1,
            first: "the bridge thread panicked".into(),
        })
    }
}
