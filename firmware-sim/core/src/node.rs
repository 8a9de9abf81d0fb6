//! The sensor node's side: samples in, frames out.
//!
//! [`SensorNode`] is sans-IO: the firmware (or the simulator) pushes ADC counts per axis as they
//! arrive, and pops finished frames when the bus can take one. Between the two sits a bounded
//! queue of `N` frames. When it is full the *oldest* frame is dropped (live data is worth more
//! than stale data, and the queue's latency stays bounded) and the drop is counted in
//! [`NodeStats`] and in the [`Pushed`] report of the call that caused it. The dropped frame's
//! sequence number and sample indices stay used, so the receiver sees the loss as a gap too:
//! a drop is never silent on either side of the bus.
//!
//! Each axis has its own sequence counter and sample index, both starting at 0 and wrapping.
//! Metadata pages are queued before the first sample and then every `metadata_period_samples`
//! samples of the node's lowest axis (the reference axis), so a receiver that joins late
//! learns rate and scale within one period. [`SensorNode::reset`] models a restart: counters
//! back to 0, pending samples and queued frames lost (and counted).

use heapless::{Deque, Vec};

use crate::frame::{
    AxisSet, DataFrame, DevicePage, FirmwareVersion, Frame, NodeInfo, SpeedFrame, SpeedSource,
    StreamPage, SAMPLES_CAPACITY, SPEED_NOT_AVAILABLE,
};
use crate::id::{FrameKind, AXIS_COUNT, NODE_COUNT};

/// What a node is and how it streams.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeConfig {
    /// Node id, `0..16`.
    pub node: u8,
    /// Axes streamed; not empty.
    pub axes: AxisSet,
    /// Data-frame layout.
    pub data_kind: FrameKind,
    /// Sample rate of every axis, Hz; not 0.
    pub sample_rate_hz: u32,
    /// g per ADC count; finite and positive.
    pub scale_g_per_count: f32,
    /// Firmware version reported in metadata.
    pub firmware: FirmwareVersion,
    /// Reference-axis samples between two metadata bursts; not 0. One second's worth
    /// (`sample_rate_hz`) is the intended value.
    pub metadata_period_samples: u32,
}

impl NodeConfig {
    /// The description this node sends in its metadata.
    pub fn info(&self) -> NodeInfo {
        NodeInfo {
            node: self.node,
            stream: StreamPage {
                sample_rate_hz: self.sample_rate_hz,
                axes: self.axes,
                data_kind: self.data_kind,
            },
            device: DevicePage {
                scale_g_per_count: self.scale_g_per_count,
                firmware: self.firmware,
            },
        }
    }

    fn validate(&self) -> Result<(), ConfigError> {
        if self.node >= NODE_COUNT {
            return Err(ConfigError::NodeOutOfRange(self.node));
        }
        if self.axes.is_empty() {
            return Err(ConfigError::NoAxes);
        }
        if self.sample_rate_hz == 0 {
            return Err(ConfigError::ZeroSampleRate);
        }
        if !self.scale_g_per_count.is_finite() || self.scale_g_per_count <= 0.0 {
            return Err(ConfigError::BadScale(self.scale_g_per_count));
        }
        if self.metadata_period_samples == 0 {
            return Err(ConfigError::ZeroMetadataPeriod);
        }
        Ok(())
    }
}

/// Why a [`NodeConfig`] is refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConfigError {
    /// Node id not in `0..16`.
    NodeOutOfRange(u8),
    /// No axis to stream.
    NoAxes,
    /// Sample rate 0.
    ZeroSampleRate,
    /// Scale not finite and positive.
    BadScale(f32),
    /// Metadata period 0.
    ZeroMetadataPeriod,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ConfigError::NodeOutOfRange(n) => {
                write!(f, "node id {n} out of range 0..={}", NODE_COUNT - 1)
            }
            ConfigError::NoAxes => write!(f, "no axis configured"),
            ConfigError::ZeroSampleRate => write!(f, "sample rate is 0 Hz"),
            ConfigError::BadScale(s) => write!(f, "scale {s} g/count is not finite and > 0"),
            ConfigError::ZeroMetadataPeriod => write!(f, "metadata period is 0 samples"),
        }
    }
}

impl core::error::Error for ConfigError {}

/// Why samples were refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PushError {
    /// The axis is not in the node's [`NodeConfig::axes`]; nothing was taken.
    AxisNotConfigured(u8),
}

impl core::fmt::Display for PushError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PushError::AxisNotConfigured(a) => write!(f, "axis {a} is not configured"),
        }
    }
}

impl core::error::Error for PushError {}

/// What one call put into the queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[must_use = "a non-zero `dropped` means frames were lost to queue overflow"]
pub struct Pushed {
    /// Frames added to the queue (data, metadata or speed).
    pub queued: usize,
    /// Frames dropped from the queue's front to make room, during this call.
    pub dropped: usize,
}

impl Pushed {
    fn add(&mut self, other: Pushed) {
        self.queued += other.queued;
        self.dropped += other.dropped;
    }
}

/// Running totals since the node was created (a reset does not clear them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NodeStats {
    /// Samples taken, all axes.
    pub samples: u64,
    /// Data frames completed (queued, whether or not dropped later).
    pub data_frames: u64,
    /// Metadata frames produced.
    pub metadata_frames: u64,
    /// Speed frames produced.
    pub speed_frames: u64,
    /// Frames of any kind dropped because the queue was full.
    pub frames_dropped: u64,
    /// Of those, data frames.
    pub data_frames_dropped: u64,
    /// Samples in the dropped data frames.
    pub samples_dropped: u64,
    /// Resets.
    pub resets: u64,
    /// Frames that were queued when a reset happened (lost with it).
    pub frames_lost_on_reset: u64,
    /// Samples lost with a reset: those pending in unfinished frames plus those in queued ones.
    pub samples_lost_on_reset: u64,
}

#[derive(Debug, Clone, Default)]
struct AxisState {
    sequence: u16,
    /// Index of the next sample to be taken.
    next_sample: u32,
    pending: Vec<i16, SAMPLES_CAPACITY>,
}

/// A sensor node's sampling and packing state machine, with a queue of up to `N` frames.
#[derive(Debug)]
pub struct SensorNode<const N: usize> {
    config: NodeConfig,
    reference_axis: u8,
    axes: [AxisState; AXIS_COUNT as usize],
    /// Reference-axis samples left before the next metadata burst; 0 means "before the next
    /// sample".
    until_metadata: u32,
    speed_sequence: u8,
    queue: Deque<Frame, N>,
    stats: NodeStats,
}

impl<const N: usize> SensorNode<N> {
    /// A node that has taken no sample yet.
    pub fn new(config: NodeConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        let reference_axis = config.axes.first().ok_or(ConfigError::NoAxes)?;
        Ok(SensorNode {
            config,
            reference_axis,
            axes: Default::default(),
            until_metadata: 0,
            speed_sequence: 0,
            queue: Deque::new(),
            stats: NodeStats::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &NodeConfig {
        &self.config
    }

    /// Running totals.
    pub fn stats(&self) -> NodeStats {
        self.stats
    }

    /// Frames waiting in the queue.
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// Samples of `axis` taken but not yet in a frame (0 for an axis not configured).
    pub fn pending(&self, axis: u8) -> usize {
        self.axis_state(axis).map_or(0, |s| s.pending.len())
    }

    /// Index the next sample of `axis` will get.
    pub fn next_sample(&self, axis: u8) -> Option<u32> {
        self.axis_state(axis).map(|s| s.next_sample)
    }

    fn axis_state(&self, axis: u8) -> Option<&AxisState> {
        if self.config.axes.contains(axis) {
            self.axes.get(usize::from(axis))
        } else {
            None
        }
    }

    /// The oldest queued frame, if any.
    pub fn pop_frame(&mut self) -> Option<Frame> {
        self.queue.pop_front()
    }

    /// Takes one sample of `axis`.
    pub fn push_sample(&mut self, axis: u8, sample: i16) -> Result<Pushed, PushError> {
        self.push_samples(axis, core::slice::from_ref(&sample))
    }

    /// Takes consecutive samples of `axis`. Finished frames go to the queue; a full frame is
    /// finished as soon as its last sample arrives.
    pub fn push_samples(&mut self, axis: u8, samples: &[i16]) -> Result<Pushed, PushError> {
        if !self.config.axes.contains(axis) {
            return Err(PushError::AxisNotConfigured(axis));
        }
        let per_frame = self.config.data_kind.max_samples();
        let mut report = Pushed::default();
        for &sample in samples {
            if axis == self.reference_axis {
                if self.until_metadata == 0 {
                    let r = self.queue_metadata();
                    report.add(r);
                    self.until_metadata = self.config.metadata_period_samples;
                }
                self.until_metadata -= 1;
            }
            let state = &mut self.axes[usize::from(axis)];
            // `pending` never holds more than `per_frame` (<= its capacity) samples: it is
            // emptied below as soon as it reaches `per_frame`.
            let _ = state.pending.push(sample);
            state.next_sample = state.next_sample.wrapping_add(1);
            self.stats.samples += 1;
            if state.pending.len() >= per_frame {
                report.add(self.finish_frame(axis));
            }
        }
        Ok(report)
    }

    /// Sends the samples pending on every axis in short frames now, instead of waiting for
    /// full ones (for a clean stop; a streaming node never needs it).
    pub fn flush(&mut self) -> Pushed {
        let mut report = Pushed::default();
        for axis in self.config.axes.iter() {
            if !self.axes[usize::from(axis)].pending.is_empty() {
                report.add(self.finish_frame(axis));
            }
        }
        report
    }

    /// Queues a speed frame (for a node with a tachometer input, or a drive gateway).
    /// `centi_rpm` is hundredths of rpm, `None` when no valid value is available; a value of
    /// `u32::MAX` is reserved on the wire and is sent as "not available".
    pub fn push_speed(&mut self, source: SpeedSource, centi_rpm: Option<u32>) -> Pushed {
        let frame = SpeedFrame {
            node: self.config.node,
            sequence: self.speed_sequence,
            source,
            centi_rpm: centi_rpm.filter(|&c| c != SPEED_NOT_AVAILABLE),
        };
        self.speed_sequence = self.speed_sequence.wrapping_add(1);
        self.stats.speed_frames += 1;
        self.enqueue(Frame::Speed(frame))
    }

    /// Restarts the node: every axis's sequence and sample index go back to 0, samples pending
    /// and frames queued are lost (and counted in [`NodeStats`]), and metadata is sent again
    /// before the next sample.
    pub fn reset(&mut self) {
        let mut lost_samples = 0u64;
        for state in self.axes.iter_mut() {
            lost_samples += state.pending.len() as u64;
            *state = AxisState::default();
        }
        while let Some(frame) = self.queue.pop_front() {
            self.stats.frames_lost_on_reset += 1;
            if let Frame::Data(d) = frame {
                lost_samples += d.samples.len() as u64;
            }
        }
        self.stats.samples_lost_on_reset += lost_samples;
        self.stats.resets += 1;
        self.until_metadata = 0;
        self.speed_sequence = 0;
    }

    fn queue_metadata(&mut self) -> Pushed {
        let mut report = Pushed::default();
        for frame in self.config.info().frames() {
            self.stats.metadata_frames += 1;
            report.add(self.enqueue(frame));
        }
        report
    }

    fn finish_frame(&mut self, axis: u8) -> Pushed {
        let state = &mut self.axes[usize::from(axis)];
        let samples = core::mem::take(&mut state.pending);
        let frame = DataFrame {
            node: self.config.node,
            axis,
            sequence: state.sequence,
            first_sample: state.next_sample.wrapping_sub(samples.len() as u32),
            samples,
        };
        state.sequence = state.sequence.wrapping_add(1);
        self.stats.data_frames += 1;
        self.enqueue(Frame::Data(frame))
    }

    /// Appends `frame`, dropping the oldest frame first if the queue is full.
    fn enqueue(&mut self, frame: Frame) -> Pushed {
        let mut report = Pushed::default();
        if self.queue.is_full() {
            if let Some(old) = self.queue.pop_front() {
                self.count_drop(&old);
                report.dropped += 1;
            }
        }
        match self.queue.push_back(frame) {
            Ok(()) => report.queued += 1,
            // Unreachable (room was just made, and heapless refuses `N == 0` at compile time),
            // but if it ever happens the frame is still counted, not lost silently.
            Err(frame) => {
                self.count_drop(&frame);
                report.dropped += 1;
            }
        }
        report
    }

    fn count_drop(&mut self, frame: &Frame) {
        self.stats.frames_dropped += 1;
        if let Frame::Data(d) = frame {
            self.stats.data_frames_dropped += 1;
            self.stats.samples_dropped += d.samples.len() as u64;
        }
    }
}
