//! The live sources of `bearingd run`: the SocketCAN and iceoryx2 sources of this room, with
//! their events mapped from (node, axis) to the config's channels.
//!
//! One task per CAN interface (several nodes share a bus) and per iceoryx2 sensor. A source
//! waits when the analysis queue is full, which pushes the loss back into the transport's own
//! buffer, where it is counted as an exact sequence gap.

use super::{IngestEvent, IngestStats};
use crate::config::{Config, SensorConfig, Transport};
use crate::messages::{ChannelId, IngestMessage};
use crate::pipeline::Input;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

/// How long a node may stay silent before it is reported lost.
pub const SENSOR_TIMEOUT: Duration = Duration::from_secs(2);

/// Which sensor and axis names a node's streams belong to.
#[derive(Debug, Clone, Default)]
pub struct NodeMap {
    nodes: BTreeMap<u8, (String, Vec<String>)>,
}

impl NodeMap {
    fn insert(&mut self, node: u8, sensor: &SensorConfig) {
        self.nodes
            .insert(node, (sensor.id.clone(), sensor.axes.clone()));
    }

    /// The pipeline's input for a source's event; `None` for events the pipeline does not
    /// need (metadata, malformed frames: counted by the source).
    pub fn to_input(&self, event: IngestEvent) -> Option<Input> {
        let channel = |node: u8, axis: u8| {
            self.nodes.get(&node).and_then(|(sensor, axes)| {
                axes.get(usize::from(axis)).map(|a| ChannelId {
                    sensor: sensor.clone(),
                    axis: a.clone(),
                })
            })
        };
        match event {
            IngestEvent::Samples(block) => Some(Input::Samples {
                channel: channel(block.node, block.axis)?,
                first_sample: block.first_sample,
                scale_g_per_count: f64::from(block.scale_g_per_count),
                counts: block.samples,
            }),
            IngestEvent::Restart {
                node,
                axis,
                first_sample,
            } => Some(Input::Restart {
                channel: channel(node, axis)?,
                first_sample,
            }),
            IngestEvent::SensorLost { node } => Some(Input::SensorLost {
                sensor: self.nodes.get(&node)?.0.clone(),
            }),
            IngestEvent::SensorBack { node } => Some(Input::SensorBack {
                sensor: self.nodes.get(&node)?.0.clone(),
            }),
            IngestEvent::Speed { node, rpm, .. } => Some(Input::Speed {
                sensor: self.nodes.get(&node)?.0.clone(),
                rpm: rpm.map(f64::from),
            }),
            // A gap shows in the next block's first sample; the monitor reports it there.
            _ => None,
        }
    }
}

/// The CAN interfaces of the config, each with the nodes on it.
pub fn can_interfaces(config: &Config) -> BTreeMap<String, NodeMap> {
    let mut buses: BTreeMap<String, NodeMap> = BTreeMap::new();
    for sensor in &config.sensors {
        if let Transport::Can(can) = &sensor.transport {
            buses
                .entry(can.interface.clone())
                .or_default()
                .insert(can.node_id, sensor);
        }
    }
    buses
}

/// The iceoryx2 sensors of the config: the sensor name of its service and its map (every
/// node on the service is the sensor).
pub fn shm_sensors(config: &Config) -> Vec<(String, NodeMap)> {
    config
        .sensors
        .iter()
        .filter_map(|sensor| match &sensor.transport {
            Transport::Shm(shm) => {
                let name = crate::iox::sensor_of_service(&shm.service)
                    .unwrap_or(&sensor.id)
                    .to_string();
                let mut map = NodeMap::default();
                for node in 0..=15 {
                    map.insert(node, sensor);
                }
                Some((name, map))
            }
            _ => None,
        })
        .collect()
}

/// An input as it enters the analysis queue, with the wall-clock time (ns since the Unix
/// epoch) at which its source completed it. The analysis never reads the time; `run` stamps it
/// on the alerts the input causes, so that their latency counts the wait in the queue too.
#[derive(Debug, Clone)]
pub struct Arrived {
    pub input: Input,
    pub wall_ns: u64,
}

impl Arrived {
    /// `input`, stamped now (the one wall-clock reading on the way in).
    pub fn now(input: Input) -> Arrived {
        Arrived {
            input,
            wall_ns: crate::clock::wall_clock_now_ns(),
        }
    }
}

/// Told of each input once it is in the analysis queue: `run` wakes the idle CPUs there
/// (`daemon::cpu_latency`), on the source's time rather than the analysis'.
pub trait HandOverWatch: Send + Sync {
    fn handed_over(&self);
}

/// The sources' end of the analysis queue: stamps each input as it arrives ([`Arrived`]),
/// waits while the queue is full (no input is dropped here), then tells the watch, if any.
/// Every input reaches the analysis through it, so the watch hears of each one.
#[derive(Clone)]
pub struct AnalysisInbox {
    queue: tokio::sync::mpsc::Sender<Arrived>,
    watch: Option<Arc<dyn HandOverWatch>>,
}

impl AnalysisInbox {
    pub fn new(
        queue: tokio::sync::mpsc::Sender<Arrived>,
        watch: Option<Arc<dyn HandOverWatch>>,
    ) -> AnalysisInbox {
        AnalysisInbox { queue, watch }
    }

    /// Hands `input` over; `false` once the analysis has ended (the input is not taken).
    pub async fn hand_over(&self, input: Input) -> bool {
        if self.queue.send(Arrived::now(input)).await.is_err() {
            return false;
        }
        if let Some(watch) = &self.watch {
            watch.handed_over();
        }
        true
    }

    /// A handle that sees whether inputs wait in the queue without keeping it open.
    pub fn downgrade(&self) -> tokio::sync::mpsc::WeakSender<Arrived> {
        self.queue.downgrade()
    }
}

/// Forwards a source's events to the analysis queue until either side ends. Sample blocks of
/// nodes or axes the config does not know are skipped and counted; the source's counters
/// ([`IngestEvent::Stats`]) go on as [`Input::Ingest`] for the log, named `source`.
pub async fn forward(
    mut events: tokio::sync::mpsc::Receiver<IngestEvent>,
    map: NodeMap,
    source: String,
    inputs: AnalysisInbox,
) {
    let mut dropped_blocks = 0u64;
    while let Some(event) = events.recv().await {
        let input = match event {
            IngestEvent::Stats(stats) => Some(Input::Ingest(ingest_message(
                &source,
                &stats,
                dropped_blocks,
            ))),
            IngestEvent::Samples(_) => {
                let input = map.to_input(event);
                dropped_blocks += u64::from(input.is_none());
                input
            }
            other => map.to_input(other),
        };
        if let Some(input) = input {
            if !inputs.hand_over(input).await {
                return;
            }
        }
    }
}

/// The logged form of a source's counters.
pub fn ingest_message(source: &str, stats: &IngestStats, dropped_blocks: u64) -> IngestMessage {
    IngestMessage {
        source: source.to_string(),
        frames: stats.frames,
        samples: stats.samples,
        gaps: stats.gaps,
        missing_samples: stats.missing_samples,
        malformed: stats.malformed.total(),
        restarts: stats.restarts,
        dropped_blocks,
        speed_frames: stats.speed_frames,
        sensor_lost: stats.sensor_lost,
        handoff_dropped: stats.handoff_dropped,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Counts the hand-overs, and what the queue held when each was told.
    #[derive(Default)]
    struct Counting {
        told: AtomicUsize,
        queued_when_told: AtomicUsize,
        queue: std::sync::OnceLock<tokio::sync::mpsc::WeakSender<Arrived>>,
    }

    impl HandOverWatch for Counting {
        fn handed_over(&self) {
            self.told.fetch_add(1, Ordering::SeqCst);
            let queued = self
                .queue
                .get()
                .and_then(|q| q.upgrade())
                .map_or(0, |q| q.max_capacity() - q.capacity());
            self.queued_when_told.store(queued, Ordering::SeqCst);
        }
    }

    fn lost() -> Input {
        Input::SensorLost {
            sensor: "motor-de".into(),
        }
    }

    #[tokio::test]
    async fn the_watch_hears_of_an_input_once_it_is_in_the_queue() {
        let (queue, mut taken) = tokio::sync::mpsc::channel(4);
        let watch = Arc::new(Counting::default());
        let _ = watch.queue.set(queue.downgrade());
        let inbox = AnalysisInbox::new(queue, Some(watch.clone() as Arc<dyn HandOverWatch>));
        assert!(inbox.hand_over(lost()).await);
        assert_eq!(watch.told.load(Ordering::SeqCst), 1);
        assert_eq!(watch.queued_when_told.load(Ordering::SeqCst), 1);
        let arrived = taken.recv().await.expect("the input");
        assert!(matches!(arrived.input, Input::SensorLost { .. }));
        assert!(arrived.wall_ns > 0, "stamped as it arrived");
    }

    #[tokio::test]
    async fn an_input_the_ended_analysis_cannot_take_is_not_told() {
        let (queue, taken) = tokio::sync::mpsc::channel(4);
        drop(taken);
        let watch = Arc::new(Counting::default());
        let inbox = AnalysisInbox::new(queue, Some(watch.clone() as Arc<dyn HandOverWatch>));
        assert!(!inbox.hand_over(lost()).await);
        assert_eq!(watch.told.load(Ordering::SeqCst), 0);
    }
}
