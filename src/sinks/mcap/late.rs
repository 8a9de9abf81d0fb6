//! What must not be lost while the log cannot be written (a full disk): flag changes and health
//! events, held in memory in the order they were decided, to be written first when logging
//! resumes, marked late. Everything else (raw blocks, spectra, indicators) is counted as not
//! logged: it is bulk, and the pause says how much.
//!
//! The hold is bounded (an edge box must not run out of memory on a long pause): at most
//! [`LATE_CAPACITY`] messages, of which health events take at most [`HEALTH_ROOM`], so that flag
//! changes, which the alerts and the operator act on, always keep room; a flag change arriving
//! when everything is full pushes out the newest health event. What does not fit is counted per
//! kind, never silently lost: the `/state` snapshot at the resume still has the latest flags
//! and health per channel. Sans-IO: messages and times in, messages out.

use crate::messages::PipelineMessage;
use std::collections::VecDeque;

/// Most messages held while paused (about 300 bytes each: a few hundred kB at most).
pub const LATE_CAPACITY: usize = 1024;
/// Health events are held only while fewer than this many messages are: the rest is for flags.
pub const HEALTH_ROOM: usize = 768;

/// A message held back, with the log time at which it was decided (its sample's time).
#[derive(Debug, Clone, PartialEq)]
pub struct Late {
    pub message: PipelineMessage,
    pub decided_ns: u64,
}

/// Counts per kind: flag changes (fault and ISO velocity flags) and health events.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LateCounts {
    pub flags: u64,
    pub health: u64,
}

impl LateCounts {
    pub fn total(&self) -> u64 {
        self.flags + self.health
    }

    fn add(&mut self, kind: LateKind, n: u64) {
        match kind {
            LateKind::Flag => self.flags += n,
            LateKind::Health => self.health += n,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LateKind {
    Flag,
    Health,
}

fn late_kind(message: &PipelineMessage) -> Option<LateKind> {
    match message {
        PipelineMessage::Flag(_) => Some(LateKind::Flag),
        PipelineMessage::Detector(m) if m.as_flag().is_some() => Some(LateKind::Flag),
        PipelineMessage::Health(_) => Some(LateKind::Health),
        _ => None,
    }
}

/// The held flag changes and health events, oldest first, and what did not fit.
#[derive(Debug, Clone)]
pub struct LateBacklog {
    held: VecDeque<Late>,
    dropped: LateCounts,
    capacity: usize,
    health_room: usize,
}

impl Default for LateBacklog {
    fn default() -> Self {
        LateBacklog::with_limits(LATE_CAPACITY, HEALTH_ROOM)
    }
}

impl LateBacklog {
    /// A backlog of at most `capacity` messages, health events only while fewer than
    /// `health_room` are held.
    pub fn with_limits(capacity: usize, health_room: usize) -> Self {
        LateBacklog {
            held: VecDeque::new(),
            dropped: LateCounts::default(),
            capacity,
            health_room: health_room.min(capacity),
        }
    }

    /// Holds `message` if it is a flag change or a health event and there is room for it
    /// (counted as dropped otherwise); other kinds are ignored. `true` if held.
    pub fn push(&mut self, message: &PipelineMessage, decided_ns: u64) -> bool {
        let Some(kind) = late_kind(message) else {
            return false;
        };
        let room = match kind {
            LateKind::Health => self.held.len() < self.health_room,
            LateKind::Flag => self.held.len() < self.capacity || self.evict_newest_health(),
        };
        if !room {
            self.dropped.add(kind, 1);
            return false;
        }
        self.held.push_back(Late {
            message: message.clone(),
            decided_ns,
        });
        true
    }

    /// Makes room for a flag change by dropping the newest health event; `false` if none held.
    fn evict_newest_health(&mut self) -> bool {
        let newest = self
            .held
            .iter()
            .rposition(|l| late_kind(&l.message) == Some(LateKind::Health));
        let Some(at) = newest else {
            return false;
        };
        self.held.remove(at);
        self.dropped.add(LateKind::Health, 1);
        true
    }

    /// Holds what `later` holds after what this one does (by the same rules), and adds up what
    /// both dropped.
    pub fn append(&mut self, later: LateBacklog) {
        for late in later.held {
            self.push(&late.message, late.decided_ns);
        }
        self.dropped.flags += later.dropped.flags;
        self.dropped.health += later.dropped.health;
    }

    /// The held messages, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &Late> {
        self.held.iter()
    }

    /// How many of each kind are held.
    pub fn held(&self) -> LateCounts {
        let mut counts = LateCounts::default();
        for kind in self.held.iter().filter_map(|l| late_kind(&l.message)) {
            counts.add(kind, 1);
        }
        counts
    }

    /// How many of each kind did not fit.
    pub fn dropped(&self) -> LateCounts {
        self.dropped
    }

    /// Nothing held and nothing dropped: nothing to say.
    pub fn is_empty(&self) -> bool {
        self.held.is_empty() && self.dropped.total() == 0
    }

    /// Forgets everything (written, or no longer needed).
    pub fn clear(&mut self) {
        self.held.clear();
        self.dropped = LateCounts::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{
        ChannelId, FaultKind, FlagLevel, FlagMessage, HealthKind, HealthMessage, SpectrumMessage,
    };

    fn channel() -> ChannelId {
        ChannelId {
            sensor: "s".into(),
            axis: "radial".into(),
        }
    }

    fn flag(end_sample: u64) -> PipelineMessage {
        PipelineMessage::Flag(FlagMessage {
            channel: channel(),
            end_sample,
            fault: FaultKind::OuterRace,
            from: FlagLevel::Ok,
            to: FlagLevel::Watch,
            score: 5.0,
            fault_frequency_hz: 107.4,
            runner_up_score: None,
        })
    }

    fn health(end_sample: u64) -> PipelineMessage {
        PipelineMessage::Health(HealthMessage {
            channel: channel(),
            end_sample,
            kind: HealthKind::Gap,
            stage: None,
            detail: String::new(),
        })
    }

    /// `F12` for a flag at sample 12, `H3` for a health event at sample 3.
    fn names(backlog: &LateBacklog) -> Vec<String> {
        backlog
            .iter()
            .map(|l| match &l.message {
                PipelineMessage::Flag(f) => format!("F{}", f.end_sample),
                PipelineMessage::Health(h) => format!("H{}", h.end_sample),
                other => format!("{other:?}"),
            })
            .collect()
    }

    fn spectrum() -> PipelineMessage {
        PipelineMessage::Spectrum(SpectrumMessage::new(
            channel(),
            0,
            [500.0, 2500.0],
            1.0,
            1,
            vec![1.0],
        ))
    }

    #[test]
    fn flags_and_health_are_held_in_the_order_decided_with_their_time_and_nothing_else() {
        let mut backlog = LateBacklog::default();
        assert!(backlog.push(&flag(1), 10));
        assert!(backlog.push(&health(2), 20));
        assert!(!backlog.push(&spectrum(), 25));
        assert!(backlog.push(&flag(3), 30));
        assert_eq!(names(&backlog), ["F1", "H2", "F3"]);
        let times: Vec<u64> = backlog.iter().map(|l| l.decided_ns).collect();
        assert_eq!(times, [10, 20, 30]);
        assert_eq!(
            backlog.held(),
            LateCounts {
                flags: 2,
                health: 1
            }
        );
        assert_eq!(backlog.dropped(), LateCounts::default());
        backlog.clear();
        assert!(backlog.is_empty());
    }

    #[test]
    fn health_yields_to_flags_and_what_does_not_fit_is_counted_per_kind() {
        let mut backlog = LateBacklog::with_limits(6, 4);
        for k in 0..6 {
            backlog.push(&health(k), k);
        }
        // Health is held only while fewer than 4 are: H4 and H5 were dropped.
        assert_eq!(names(&backlog), ["H0", "H1", "H2", "H3"]);
        assert_eq!(
            backlog.dropped(),
            LateCounts {
                flags: 0,
                health: 2
            }
        );
        // Flags fill the rest, then push out the newest health events one by one.
        for k in 10..15 {
            assert!(backlog.push(&flag(k), k));
        }
        assert_eq!(names(&backlog), ["H0", "F10", "F11", "F12", "F13", "F14"]);
        assert_eq!(
            backlog.held(),
            LateCounts {
                flags: 5,
                health: 1
            }
        );
        assert_eq!(
            backlog.dropped(),
            LateCounts {
                flags: 0,
                health: 5
            }
        );
        // No room for health at all now; the last health event yields to one more flag.
        assert!(!backlog.push(&health(20), 20));
        assert!(backlog.push(&flag(15), 15));
        // All flags: the capacity holds, the newest flag is the one dropped (the oldest
        // changes, the onset, are kept; the `/state` snapshot has the latest).
        assert!(!backlog.push(&flag(16), 16));
        assert_eq!(names(&backlog), ["F10", "F11", "F12", "F13", "F14", "F15"]);
        assert_eq!(
            backlog.dropped(),
            LateCounts {
                flags: 1,
                health: 7
            }
        );
        assert!(!backlog.is_empty());
    }

    #[test]
    fn appending_keeps_the_order_and_the_limits_and_adds_up_the_drops() {
        let mut logged_before_the_failure = LateBacklog::with_limits(4, 2);
        logged_before_the_failure.push(&flag(1), 1);
        logged_before_the_failure.push(&health(2), 2);
        let mut during_the_pause = LateBacklog::with_limits(4, 2);
        for k in 3..6 {
            during_the_pause.push(&health(k), k);
        }
        during_the_pause.push(&flag(6), 6);
        assert_eq!(names(&during_the_pause), ["H3", "H4", "F6"]);
        logged_before_the_failure.append(during_the_pause);
        // H3 and H4 find no room for health (2 held already), F6 does; H5 was dropped before.
        assert_eq!(names(&logged_before_the_failure), ["F1", "H2", "F6"]);
        assert_eq!(
            logged_before_the_failure.dropped(),
            LateCounts {
                flags: 0,
                health: 3
            }
        );
    }
}
