//! The one place where decoded wire frames become sample blocks and events, for every
//! transport.
//!
//! CAN and iceoryx2 both deliver (CAN id, bytes) pairs; both pass them to an [`Assembler`],
//! which decodes them with `bearing_wire::decode`, keeps each node's metadata with a
//! `MetadataAssembler` and each (node, axis) stream's position with a `SequenceTracker`, and
//! answers with [`IngestEvent`]s. Keeping it here, and sans-IO (no socket, no clock), means the
//! two sources cannot differ in what they call a gap, a restart or a malformed frame, and it is
//! tested without either transport.
//!
//! Rules it keeps:
//! - A gap is never bridged: a [`IngestEvent::Gap`] (exact sample count) comes before the block
//!   that follows it, and blocks carry their stream position, so a consumer can never glue two
//!   blocks across a hole without seeing it.
//! - Data before a node's complete metadata is dropped and counted (`frames_before_metadata`):
//!   a block without sample rate and scale cannot be analysed. It is not fed to the tracker, so
//!   the first block after the metadata is a clean start, not a hidden splice.
//! - Sensor silence is measured by the source (the assembler has no clock): the source calls
//!   [`Assembler::sensor_lost`], which resynchronises the node's trackers; the next frame of that
//!   node brings [`IngestEvent::SensorBack`].

use bearing_wire::{
    decode, DataFrame, DecodeError, Frame, FrameKind, MetadataAssembler, NodeInfo, Observation,
    SequenceTracker, SpeedSource,
};
use serde::Serialize;
use std::collections::BTreeMap;

/// Consecutive samples of one (node, axis) stream, in sample time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SampleBlock {
    pub node: u8,
    pub axis: u8,
    /// Stream position of `samples[0]` (64-bit, never wraps; see `SequenceTracker`).
    pub first_sample: u64,
    pub sample_rate_hz: u32,
    /// Acceleration in g = count × scale.
    pub scale_g_per_count: f32,
    /// ADC counts as the node sent them.
    pub samples: Vec<i16>,
}

/// Why a frame was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MalformedKind {
    UnknownId,
    WrongLength,
    BadSampleCount,
    BadMetadata,
    BadSpeed,
    /// A data frame for an axis the node's metadata does not announce.
    UnannouncedAxis,
    /// An iceoryx2 batch with a bad header (version, count).
    BadBatch,
}

impl MalformedKind {
    fn of(error: &DecodeError) -> MalformedKind {
        match error {
            DecodeError::UnknownId(_) => MalformedKind::UnknownId,
            DecodeError::WrongLength { .. } => MalformedKind::WrongLength,
            DecodeError::BadSampleCount { .. } => MalformedKind::BadSampleCount,
            DecodeError::BadMetadata { .. } => MalformedKind::BadMetadata,
            DecodeError::BadSpeed { .. } => MalformedKind::BadSpeed,
        }
    }
}

/// What a source reports, in arrival order.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum IngestEvent {
    Samples(SampleBlock),
    /// Samples missing before `at_sample` (exactly `missing_samples` of them).
    Gap {
        node: u8,
        axis: u8,
        /// Stream position of the first missing sample.
        at_sample: u64,
        missing_samples: u64,
        lost_frames: u32,
    },
    /// The node restarted; its stream positions start again at `first_sample` (0 unless the
    /// first frames after the restart were lost).
    Restart {
        node: u8,
        axis: u8,
        first_sample: u64,
    },
    /// No frame of the node for longer than the source's timeout.
    SensorLost {
        node: u8,
    },
    /// A node reported lost sends again.
    SensorBack {
        node: u8,
    },
    Speed {
        node: u8,
        /// Shaft speed, rpm; `None` when the node says it is not available.
        rpm: Option<f32>,
        source: SpeedSourceName,
    },
    /// A node's complete description, when first seen or when it changes.
    Metadata {
        node: u8,
        sample_rate_hz: u32,
        axes: u8,
        fd: bool,
        scale_g_per_count: f32,
        firmware: String,
    },
    /// A frame was refused and dropped.
    Malformed {
        can_id: u32,
        kind: MalformedKind,
        /// The decoder's message (names the frame id and byte offset).
        detail: String,
    },
    /// The source's counters so far; periodically and when it stops, if the source was asked
    /// to (the daemon logs them). Not made by the assembler.
    Stats(IngestStats),
}

/// Where a speed value comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpeedSourceName {
    Tachometer,
    Drive,
}

/// Malformed frames by kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct MalformedCounts {
    pub unknown_id: u64,
    pub wrong_length: u64,
    pub bad_sample_count: u64,
    pub bad_metadata: u64,
    pub bad_speed: u64,
    pub unannounced_axis: u64,
    pub bad_batch: u64,
}

impl MalformedCounts {
    fn count(&mut self, kind: MalformedKind) {
        let slot = match kind {
            MalformedKind::UnknownId => &mut self.unknown_id,
            MalformedKind::WrongLength => &mut self.wrong_length,
            MalformedKind::BadSampleCount => &mut self.bad_sample_count,
            MalformedKind::BadMetadata => &mut self.bad_metadata,
            MalformedKind::BadSpeed => &mut self.bad_speed,
            MalformedKind::UnannouncedAxis => &mut self.unannounced_axis,
            MalformedKind::BadBatch => &mut self.bad_batch,
        };
        *slot += 1;
    }

    pub fn total(&self) -> u64 {
        self.unknown_id
            + self.wrong_length
            + self.bad_sample_count
            + self.bad_metadata
            + self.bad_speed
            + self.unannounced_axis
            + self.bad_batch
    }
}

/// Running totals of one source. Every frame that does not become samples is in one of these
/// counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct IngestStats {
    /// Frames received (valid or not).
    pub frames: u64,
    pub data_frames: u64,
    pub metadata_frames: u64,
    pub speed_frames: u64,
    /// Samples delivered in blocks.
    pub samples: u64,
    pub gaps: u64,
    /// Sum of the gaps' sizes: samples the node sent that never arrived.
    pub missing_samples: u64,
    pub lost_frames: u64,
    pub restarts: u64,
    pub duplicates: u64,
    /// Frames behind their stream's position (dropped).
    pub old_frames: u64,
    pub sequence_mismatches: u64,
    /// Data frames dropped because their node's metadata was not complete yet.
    pub frames_before_metadata: u64,
    pub malformed: MalformedCounts,
    pub sensor_lost: u64,
    pub sensor_back: u64,
    /// Transport batches dropped at a full hand-off queue (drop-oldest); their frames show up
    /// as gaps as well.
    pub handoff_dropped: u64,
}

/// Per-(node, axis) totals, for reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct StreamSummary {
    pub node: u8,
    pub axis: u8,
    pub fd: bool,
    pub samples: u64,
    /// Position after the last sample delivered.
    pub next_sample: Option<u64>,
    pub gaps: u64,
    pub missing_samples: u64,
    pub restarts: u64,
}

#[derive(Debug, Default)]
struct NodeState {
    metadata: MetadataAssembler,
    /// Last complete description reported, to report changes only.
    reported: Option<NodeInfo>,
    lost: bool,
}

/// Decodes frames, tracks streams, produces events; see the [module docs](self).
#[derive(Debug, Default)]
pub struct Assembler {
    nodes: BTreeMap<u8, NodeState>,
    streams: BTreeMap<(u8, u8, bool), SequenceTracker>,
    stream_samples: BTreeMap<(u8, u8, bool), u64>,
    stats: IngestStats,
}

impl Assembler {
    pub fn new() -> Assembler {
        Assembler::default()
    }

    pub fn stats(&self) -> IngestStats {
        IngestStats {
            // Counted by the trackers; summed here so one struct holds every counter.
            sequence_mismatches: self
                .streams
                .values()
                .map(|t| t.counters().sequence_mismatches)
                .sum(),
            ..self.stats
        }
    }

    /// Counts a transport batch dropped before it reached the assembler.
    pub fn count_handoff_drop(&mut self, batches: u64) {
        self.stats.handoff_dropped += batches;
    }

    /// Counts a transport batch refused as a whole.
    pub fn refuse_batch(&mut self, detail: String, out: &mut Vec<IngestEvent>) {
        self.stats.malformed.count(MalformedKind::BadBatch);
        out.push(IngestEvent::Malformed {
            can_id: 0,
            kind: MalformedKind::BadBatch,
            detail,
        });
    }

    /// Per-stream totals, ordered by node and axis.
    pub fn streams(&self) -> Vec<StreamSummary> {
        self.streams
            .iter()
            .map(|(&(node, axis, fd), tracker)| {
                let counters = tracker.counters();
                StreamSummary {
                    node,
                    axis,
                    fd,
                    samples: self
                        .stream_samples
                        .get(&(node, axis, fd))
                        .copied()
                        .unwrap_or(0),
                    next_sample: tracker.next_sample(),
                    gaps: counters.gaps,
                    missing_samples: counters.missing_samples,
                    restarts: counters.restarts,
                }
            })
            .collect()
    }

    /// Takes one received frame (`can_id` with the SocketCAN flag bits already masked off) and
    /// appends what it means to `out`. Consecutive samples of one stream are merged into the
    /// last block in `out`, so a caller that passes a whole read batch gets one block per
    /// stream, not one per frame.
    pub fn push(&mut self, can_id: u32, bytes: &[u8], out: &mut Vec<IngestEvent>) {
        self.stats.frames += 1;
        let frame = match decode(can_id, bytes) {
            Ok(frame) => frame,
            Err(error) => {
                let kind = MalformedKind::of(&error);
                self.stats.malformed.count(kind);
                out.push(IngestEvent::Malformed {
                    can_id,
                    kind,
                    detail: error.to_string(),
                });
                return;
            }
        };
        let node = frame.node();
        let state = self.nodes.entry(node).or_default();
        if state.lost {
            state.lost = false;
            self.stats.sensor_back += 1;
            out.push(IngestEvent::SensorBack { node });
        }
        match frame {
            Frame::Metadata(metadata) => {
                self.stats.metadata_frames += 1;
                if let Some(info) = state.metadata.apply(&metadata) {
                    if state.reported != Some(info) {
                        state.reported = Some(info);
                        out.push(metadata_event(&info));
                    }
                }
            }
            Frame::Speed(speed) => {
                self.stats.speed_frames += 1;
                out.push(IngestEvent::Speed {
                    node,
                    rpm: speed.rpm(),
                    source: match speed.source {
                        SpeedSource::Tachometer => SpeedSourceName::Tachometer,
                        SpeedSource::Drive => SpeedSourceName::Drive,
                    },
                });
            }
            Frame::Data(data) => {
                self.stats.data_frames += 1;
                let fd = bytes.len() > 8;
                self.push_data(&data, fd, can_id, out);
            }
        }
    }

    fn push_data(&mut self, data: &DataFrame, fd: bool, can_id: u32, out: &mut Vec<IngestEvent>) {
        let Some(info) = self.nodes.get(&data.node).and_then(|n| n.metadata.info()) else {
            self.stats.frames_before_metadata += 1;
            return;
        };
        if !info.stream.axes.contains(data.axis) {
            self.stats.malformed.count(MalformedKind::UnannouncedAxis);
            out.push(IngestEvent::Malformed {
                can_id,
                kind: MalformedKind::UnannouncedAxis,
                detail: format!(
                    "frame {can_id:#05x} (data, node {}): axis {} is not in the node's metadata axes {:#06b}",
                    data.node,
                    data.axis,
                    info.stream.axes.bits()
                ),
            });
            return;
        }
        let key = (data.node, data.axis, fd);
        let kind = if fd {
            FrameKind::Fd
        } else {
            FrameKind::Classic
        };
        let tracker = self
            .streams
            .entry(key)
            .or_insert_with(|| SequenceTracker::new(kind));
        let observation = tracker.observe(data);
        let (node, axis) = (data.node, data.axis);
        let position = match observation {
            Observation::Start { first_sample } | Observation::InOrder { first_sample } => {
                first_sample
            }
            Observation::Gap {
                first_sample,
                missing_samples,
                lost_frames,
            } => {
                self.stats.gaps += 1;
                self.stats.missing_samples += missing_samples;
                self.stats.lost_frames += u64::from(lost_frames);
                out.push(IngestEvent::Gap {
                    node,
                    axis,
                    at_sample: first_sample.saturating_sub(missing_samples),
                    missing_samples,
                    lost_frames,
                });
                first_sample
            }
            Observation::Restart { first_sample } => {
                self.stats.restarts += 1;
                out.push(IngestEvent::Restart {
                    node,
                    axis,
                    first_sample,
                });
                first_sample
            }
            Observation::Duplicate => {
                self.stats.duplicates += 1;
                return;
            }
            Observation::Old { .. } => {
                self.stats.old_frames += 1;
                return;
            }
        };
        let count = data.samples.len() as u64;
        self.stats.samples += count;
        *self.stream_samples.entry(key).or_insert(0) += count;
        if let Some(IngestEvent::Samples(block)) = out.last_mut() {
            let contiguous = block.node == node
                && block.axis == axis
                && block.first_sample + block.samples.len() as u64 == position
                && block.sample_rate_hz == info.stream.sample_rate_hz
                && block.scale_g_per_count == info.device.scale_g_per_count;
            if contiguous {
                block.samples.extend_from_slice(&data.samples);
                return;
            }
        }
        out.push(IngestEvent::Samples(SampleBlock {
            node,
            axis,
            first_sample: position,
            sample_rate_hz: info.stream.sample_rate_hz,
            scale_g_per_count: info.device.scale_g_per_count,
            samples: data.samples.to_vec(),
        }));
    }

    /// The source saw nothing from `node` for longer than its timeout: reports it once and
    /// resynchronises the node's streams (positions after the silence start afresh rather than
    /// being guessed across it).
    pub fn sensor_lost(&mut self, node: u8, out: &mut Vec<IngestEvent>) {
        let Some(state) = self.nodes.get_mut(&node) else {
            return;
        };
        if state.lost {
            return;
        }
        state.lost = true;
        self.stats.sensor_lost += 1;
        for (_, tracker) in self
            .streams
            .range_mut((node, 0, false)..=(node, u8::MAX, true))
        {
            tracker.resync();
        }
        out.push(IngestEvent::SensorLost { node });
    }

    /// Nodes seen so far and not currently lost.
    pub fn live_nodes(&self) -> impl Iterator<Item = u8> + '_ {
        self.nodes
            .iter()
            .filter(|(_, s)| !s.lost)
            .map(|(&node, _)| node)
    }
}

fn metadata_event(info: &NodeInfo) -> IngestEvent {
    let firmware = info.device.firmware;
    IngestEvent::Metadata {
        node: info.node,
        sample_rate_hz: info.stream.sample_rate_hz,
        axes: info.stream.axes.bits(),
        fd: info.stream.data_kind == FrameKind::Fd,
        scale_g_per_count: info.device.scale_g_per_count,
        firmware: format!("{}.{}.{}", firmware.major, firmware.minor, firmware.patch),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bearing_wire::{encode, AxisSet, FirmwareVersion, NodeConfig, SensorNode};

    fn node(kind: FrameKind) -> SensorNode<256> {
        SensorNode::new(NodeConfig {
            node: 3,
            axes: AxisSet::from_axes(&[0, 1]).unwrap(),
            data_kind: kind,
            sample_rate_hz: 25_600,
            scale_g_per_count: 1.0 / 2048.0,
            firmware: FirmwareVersion {
                major: 0,
                minor: 1,
                patch: 0,
            },
            metadata_period_samples: 25_600,
        })
        .unwrap()
    }

    fn wire(node: &mut SensorNode<256>, kind: FrameKind) -> Vec<(u32, Vec<u8>)> {
        let mut frames = Vec::new();
        let mut buf = [0u8; 64];
        while let Some(frame) = node.pop_frame() {
            let (id, len) = encode(&frame, kind, &mut buf).unwrap();
            frames.push((u32::from(id), buf[..len].to_vec()));
        }
        frames
    }

    fn run(assembler: &mut Assembler, frames: &[(u32, Vec<u8>)]) -> Vec<IngestEvent> {
        let mut out = Vec::new();
        for (id, bytes) in frames {
            assembler.push(*id, bytes, &mut out);
        }
        out
    }

    fn samples_of(events: &[IngestEvent], axis: u8) -> Vec<(u64, Vec<i16>)> {
        events
            .iter()
            .filter_map(|e| match e {
                IngestEvent::Samples(b) if b.axis == axis => {
                    Some((b.first_sample, b.samples.clone()))
                }
                _ => None,
            })
            .collect()
    }

    #[test]
    fn contiguous_frames_merge_into_one_block_per_stream_run() {
        for kind in [FrameKind::Classic, FrameKind::Fd] {
            let mut n = node(kind);
            let x: Vec<i16> = (0..280).collect();
            let _ = n.push_samples(0, &x).unwrap();
            let mut a = Assembler::new();
            let events = run(&mut a, &wire(&mut n, kind));
            assert!(matches!(events[0], IngestEvent::Metadata { node: 3, .. }));
            let blocks = samples_of(&events, 0);
            assert_eq!(blocks, vec![(0, x.clone())], "{kind:?}");
            assert_eq!(a.stats().samples, 280);
            assert_eq!(a.stats().gaps, 0);
        }
    }

    #[test]
    fn a_lost_frame_is_a_gap_event_never_a_splice() {
        let mut n = node(FrameKind::Fd);
        let _ = n.push_samples(0, &[7; 28 * 4]).unwrap();
        let mut frames = wire(&mut n, FrameKind::Fd);
        // metadata (2 frames) then 4 data frames; lose the third data frame.
        frames.remove(4);
        let mut a = Assembler::new();
        let events = run(&mut a, &frames);
        let gap = events
            .iter()
            .find(|e| matches!(e, IngestEvent::Gap { .. }))
            .unwrap();
        assert_eq!(
            *gap,
            IngestEvent::Gap {
                node: 3,
                axis: 0,
                at_sample: 56,
                missing_samples: 28,
                lost_frames: 1
            }
        );
        let blocks = samples_of(&events, 0);
        assert_eq!(blocks.len(), 2);
        assert_eq!((blocks[0].0, blocks[0].1.len()), (0, 56));
        assert_eq!((blocks[1].0, blocks[1].1.len()), (84, 28));
        assert_eq!(a.stats().missing_samples, 28);
    }

    #[test]
    fn restart_malformed_and_early_data_are_counted() {
        let mut n = node(FrameKind::Classic);
        let _ = n.push_samples(0, &[1; 20]).unwrap();
        let mut frames = wire(&mut n, FrameKind::Classic);
        // Data of node 3 before any metadata: drop the metadata pair and replay one data frame
        // to a fresh assembler first.
        let mut a = Assembler::new();
        let mut out = Vec::new();
        a.push(frames[2].0, &frames[2].1, &mut out);
        assert_eq!(a.stats().frames_before_metadata, 1);
        assert!(out.is_empty());
        // Malformed: unknown id, wrong length.
        a.push(0x7FF, &[0; 8], &mut out);
        a.push(frames[2].0, &frames[2].1[..3], &mut out);
        assert_eq!(a.stats().malformed.unknown_id, 1);
        assert_eq!(a.stats().malformed.wrong_length, 1);
        // Then the full stream, a restart, and the stream again.
        n.reset();
        let _ = n.push_samples(0, &[2; 10]).unwrap();
        frames.extend(wire(&mut n, FrameKind::Classic));
        out.clear();
        for (id, bytes) in &frames {
            a.push(*id, bytes, &mut out);
        }
        assert_eq!(a.stats().restarts, 1);
        assert!(out.contains(&IngestEvent::Restart {
            node: 3,
            axis: 0,
            first_sample: 0
        }));
        assert_eq!(a.stats().samples, 30);
    }

    #[test]
    fn silence_resyncs_and_reports_back() {
        let mut n = node(FrameKind::Fd);
        let _ = n.push_samples(0, &[1; 56]).unwrap();
        let mut a = Assembler::new();
        let mut out = run(&mut a, &wire(&mut n, FrameKind::Fd));
        a.sensor_lost(3, &mut out);
        a.sensor_lost(3, &mut out);
        assert_eq!(a.stats().sensor_lost, 1);
        // The node went on sampling while the link was down; those frames never arrived.
        let _ = n.push_samples(0, &[1; 280]).unwrap();
        let _ = wire(&mut n, FrameKind::Fd);
        let _ = n.push_samples(0, &[1; 28]).unwrap();
        out.clear();
        let events = run(&mut a, &wire(&mut n, FrameKind::Fd));
        assert_eq!(events[0], IngestEvent::SensorBack { node: 3 });
        // After a resync the stream starts afresh at the frame's own index.
        assert_eq!(samples_of(&events, 0)[0].0, 56 + 280);
        assert_eq!(a.stats().gaps, 0);
    }

    #[test]
    fn unannounced_axis_is_malformed() {
        let mut n = node(FrameKind::Fd);
        let _ = n.push_samples(0, &[1; 28]).unwrap();
        let mut frames = wire(&mut n, FrameKind::Fd);
        let data = frames.last().unwrap().clone();
        // Same bytes on axis 2's id (0x100 + 16*2 + 3): node 3 announced axes 0 and 1 only.
        frames.push((0x100 + 32 + 3, data.1));
        let mut a = Assembler::new();
        run(&mut a, &frames);
        assert_eq!(a.stats().malformed.unannounced_axis, 1);
    }
}
