//! The receiver's side: where does a data frame go, and was anything lost before it?
//!
//! The daemon keeps one [`SequenceTracker`] per (node, axis) stream and passes it every decoded
//! data frame of that stream, in arrival order. The tracker answers with an [`Observation`]:
//! where the frame's samples sit in the stream (a 64-bit sample index that does not wrap) and
//! what happened since the previous frame, and it counts every class in [`TrackerCounters`].
//! This is how "a gap is never bridged silently" is kept: the daemon inserts exactly
//! `missing_samples` of nothing, or starts a new segment on a restart, instead of gluing frames
//! together.
//!
//! # How frames are classified
//!
//! The sample index is the authority on *where* samples go (it counts samples, so gaps are
//! exact); the sequence counter cross-checks it and counts lost frames. Both arrive truncated to
//! the layout's width (classic: 8-bit sequence, 24-bit index; FD: 16 and 32) and are compared
//! modulo that width, so wraparound needs no special case. With `e` the expected next index, `d`
//! the signed distance from `e` to the frame's index (modulo the width), in this order:
//!
//! 1. no frame seen yet (or after [`SequenceTracker::resync`]): [`Observation::Start`];
//! 2. `d == 0` and the sequence is the expected one: [`Observation::InOrder`];
//! 3. same sequence and index as the last accepted frame: [`Observation::Duplicate`] (CAN can
//!    deliver a frame twice when an error hits its last bit);
//! 4. sequence 0 and index 0: [`Observation::Restart`] (the node restarted);
//! 5. `d == 0` with an unexpected sequence: `InOrder`, counted as a sequence mismatch;
//! 6. `d > 0`: [`Observation::Gap`] of exactly `d` samples;
//! 7. `d < 0`: the frame is behind. If its index is nearer to 0 than to `e`, the node
//!    restarted and its first frames were lost: `Restart`; otherwise it is a late frame:
//!    [`Observation::Old`].
//!
//! Frames of one CAN id are never reordered on a bus, so 3 and 7 are rare; they are still
//! handled, and dropped, rather than corrupting the stream.
//!
//! # Limits
//!
//! A forward jump is unambiguous only below half the index width: 2^23 samples on classic
//! frames, 2^31 on FD. A classic bus carries at most about 18 000 samples/s (2 per frame, about
//! 9 000 frames/s at 1 Mbit/s), so 2^23 samples take more than 7.5 minutes; the daemon's
//! stale-stream deadline, far shorter, calls [`SequenceTracker::resync`] first. The classic
//! index is extended from its low 24 bits, so the 64-bit positions of a classic stream equal the
//! node's own counter only if the tracker saw the stream from the node's start; otherwise they
//! differ from it by a multiple of 2^24, which does not matter to the analysis.

use crate::frame::DataFrame;
use crate::id::FrameKind;

/// What a data frame is, relative to the ones before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Observation {
    /// First frame since the tracker was created or resynchronised.
    Start {
        /// Stream position of the frame's first sample.
        first_sample: u64,
    },
    /// Directly follows the previous frame.
    InOrder {
        /// Stream position of the frame's first sample.
        first_sample: u64,
    },
    /// Frames were lost before this one.
    Gap {
        /// Stream position of the frame's first sample.
        first_sample: u64,
        /// Samples missing between the previous frame and this one (exact).
        missing_samples: u64,
        /// Frames missing according to the sequence counter, modulo 2^8 (classic) or 2^16
        /// (FD): exact below that.
        lost_frames: u32,
    },
    /// The node restarted; positions start again from its new counters.
    Restart {
        /// Stream position of the frame's first sample in the new run; when it is not 0, the
        /// first `first_sample` samples after the restart were lost.
        first_sample: u64,
    },
    /// The same frame as the previous accepted one: drop it.
    Duplicate,
    /// A frame from before the expected position: drop it.
    Old {
        /// How far behind the expected position its first sample is.
        behind_samples: u64,
    },
}

impl Observation {
    /// Where the frame's samples go, or `None` if the frame must be dropped.
    pub fn position(&self) -> Option<u64> {
        match *self {
            Observation::Start { first_sample }
            | Observation::InOrder { first_sample }
            | Observation::Gap { first_sample, .. }
            | Observation::Restart { first_sample } => Some(first_sample),
            Observation::Duplicate | Observation::Old { .. } => None,
        }
    }
}

/// Running totals of one tracker.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TrackerCounters {
    /// Frames observed.
    pub frames: u64,
    /// Samples in accepted frames.
    pub samples: u64,
    /// [`Observation::Start`]s.
    pub starts: u64,
    /// [`Observation::InOrder`]s.
    pub in_order: u64,
    /// [`Observation::Gap`]s.
    pub gaps: u64,
    /// Sum of `missing_samples` over gaps.
    pub missing_samples: u64,
    /// Sum of `lost_frames` over gaps.
    pub lost_frames: u64,
    /// [`Observation::Restart`]s.
    pub restarts: u64,
    /// [`Observation::Duplicate`]s.
    pub duplicates: u64,
    /// [`Observation::Old`]s.
    pub old: u64,
    /// Frames whose index was contiguous but whose sequence number was not the expected one
    /// (or a gap with an unchanged sequence number): the node's counters disagree.
    pub sequence_mismatches: u64,
}

#[derive(Debug, Clone, Copy)]
struct Expected {
    /// Stream position of the next sample.
    next_index: u64,
    /// Next sequence number, truncated to the layout's width.
    next_sequence: u16,
    /// Truncated sequence and index of the last accepted frame.
    last_sequence: u16,
    last_index: u32,
}

/// Classifies the data frames of one (node, axis) stream; see the [module docs](self).
#[derive(Debug, Clone)]
pub struct SequenceTracker {
    kind: FrameKind,
    expected: Option<Expected>,
    counters: TrackerCounters,
}

impl SequenceTracker {
    /// A tracker for a stream sent in `kind` frames (the layout sets the counter widths; it is
    /// known from the CAN id, see [`crate::id::CanId`]).
    pub const fn new(kind: FrameKind) -> SequenceTracker {
        SequenceTracker {
            kind,
            expected: None,
            counters: TrackerCounters {
                frames: 0,
                samples: 0,
                starts: 0,
                in_order: 0,
                gaps: 0,
                missing_samples: 0,
                lost_frames: 0,
                restarts: 0,
                duplicates: 0,
                old: 0,
                sequence_mismatches: 0,
            },
        }
    }

    /// The layout this tracker expects.
    pub fn kind(&self) -> FrameKind {
        self.kind
    }

    /// Running totals.
    pub fn counters(&self) -> TrackerCounters {
        self.counters
    }

    /// Stream position of the next expected sample, if any frame was accepted.
    pub fn next_sample(&self) -> Option<u64> {
        self.expected.map(|e| e.next_index)
    }

    /// Forgets the stream position (counters are kept): the next frame is a
    /// [`Observation::Start`]. For a stream that was silent longer than its deadline, where a
    /// gap could exceed what the counters can measure.
    pub fn resync(&mut self) {
        self.expected = None;
    }

    fn index_mask(&self) -> u64 {
        (1u64 << self.kind.index_bits()) - 1
    }

    fn sequence_mask(&self) -> u16 {
        ((1u32 << self.kind.sequence_bits()) - 1) as u16
    }

    /// Classifies `frame` and, unless it is dropped, advances the expected position past it.
    pub fn observe(&mut self, frame: &DataFrame) -> Observation {
        let index_mask = self.index_mask();
        let sequence_mask = self.sequence_mask();
        let index = u64::from(frame.first_sample) & index_mask;
        let sequence = frame.sequence & sequence_mask;
        let len = frame.samples.len() as u64;
        self.counters.frames += 1;

        let Some(exp) = self.expected else {
            self.accept(sequence, index, index, len);
            self.counters.starts += 1;
            return Observation::Start {
                first_sample: index,
            };
        };

        let width = index_mask + 1;
        let forward = index.wrapping_sub(exp.next_index) & index_mask;
        let sequence_ok = sequence == exp.next_sequence;

        // 2. In order.
        if forward == 0 && sequence_ok {
            self.accept(sequence, index, exp.next_index, len);
            self.counters.in_order += 1;
            return Observation::InOrder {
                first_sample: exp.next_index,
            };
        }
        // 3. Duplicate of the last accepted frame.
        if sequence == exp.last_sequence && index == u64::from(exp.last_index) {
            self.counters.duplicates += 1;
            return Observation::Duplicate;
        }
        // 4. Counters back at zero: restart.
        if sequence == 0 && index == 0 {
            return self.restart(sequence, index, len);
        }
        // 5. Contiguous index, unexpected sequence.
        if forward == 0 {
            self.accept(sequence, index, exp.next_index, len);
            self.counters.in_order += 1;
            self.counters.sequence_mismatches += 1;
            return Observation::InOrder {
                first_sample: exp.next_index,
            };
        }
        if forward < width / 2 {
            // 6. Gap.
            let lost_frames = u32::from(sequence.wrapping_sub(exp.next_sequence) & sequence_mask);
            if lost_frames == 0 {
                self.counters.sequence_mismatches += 1;
            }
            let first_sample = exp.next_index.wrapping_add(forward);
            self.accept(sequence, index, first_sample, len);
            self.counters.gaps += 1;
            self.counters.missing_samples += forward;
            self.counters.lost_frames += u64::from(lost_frames);
            return Observation::Gap {
                first_sample,
                missing_samples: forward,
                lost_frames,
            };
        }
        // 7. Behind.
        let behind = width - forward;
        if index < behind {
            return self.restart(sequence, index, len);
        }
        self.counters.old += 1;
        Observation::Old {
            behind_samples: behind,
        }
    }

    fn restart(&mut self, sequence: u16, index: u64, len: u64) -> Observation {
        self.accept(sequence, index, index, len);
        self.counters.restarts += 1;
        Observation::Restart {
            first_sample: index,
        }
    }

    fn accept(&mut self, sequence: u16, index: u64, position: u64, len: u64) {
        self.counters.samples += len;
        self.expected = Some(Expected {
            next_index: position.wrapping_add(len),
            next_sequence: sequence.wrapping_add(1) & self.sequence_mask(),
            last_sequence: sequence,
            last_index: index as u32,
        });
    }
}
