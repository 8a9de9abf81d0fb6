//! SequenceTracker: in order, gaps, duplicates, old frames, restarts, wraparound of both
//! layouts' counters, and an end-to-end run node → bytes → tracker where every lost sample is
//! accounted for.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use bearing_wire::{
    decode, encode, AxisSet, FirmwareVersion, Frame, FrameKind, NodeConfig, Observation,
    SensorNode, SequenceTracker,
};
use common::{data, XorShift};

/// A frame of `n` samples starting at `first`, with sequence `seq`.
fn frame(seq: u16, first: u32, n: usize) -> bearing_wire::DataFrame {
    data(1, 0, seq, first, &vec![7; n])
}

#[test]
fn in_order_frames_advance_by_their_length() {
    let mut t = SequenceTracker::new(FrameKind::Fd);
    assert_eq!(t.next_sample(), None);
    assert_eq!(
        t.observe(&frame(0, 0, 28)),
        Observation::Start { first_sample: 0 }
    );
    assert_eq!(
        t.observe(&frame(1, 28, 28)),
        Observation::InOrder { first_sample: 28 }
    );
    // A short frame (a flush) is fine too.
    assert_eq!(
        t.observe(&frame(2, 56, 3)),
        Observation::InOrder { first_sample: 56 }
    );
    assert_eq!(t.next_sample(), Some(59));
    let c = t.counters();
    assert_eq!((c.frames, c.samples, c.starts, c.in_order), (3, 59, 1, 2));
}

#[test]
fn gaps_are_measured_exactly() {
    let mut t = SequenceTracker::new(FrameKind::Fd);
    t.observe(&frame(10, 280, 28));
    // Frames 11, 12, 13 lost.
    assert_eq!(
        t.observe(&frame(14, 392, 28)),
        Observation::Gap {
            first_sample: 392,
            missing_samples: 84,
            lost_frames: 3
        }
    );
    assert_eq!(
        t.observe(&frame(15, 420, 28)),
        Observation::InOrder { first_sample: 420 }
    );
    let c = t.counters();
    assert_eq!((c.gaps, c.missing_samples, c.lost_frames), (1, 84, 3));
    assert_eq!(c.sequence_mismatches, 0);
}

#[test]
fn duplicates_and_old_frames_are_dropped_without_moving_the_stream() {
    let mut t = SequenceTracker::new(FrameKind::Fd);
    for s in 100..110u16 {
        t.observe(&frame(s, u32::from(s) * 28, 28));
    }
    let next = t.next_sample();
    assert_eq!(t.observe(&frame(109, 109 * 28, 28)), Observation::Duplicate);
    assert_eq!(
        t.observe(&frame(105, 105 * 28, 28)),
        Observation::Old {
            behind_samples: 5 * 28
        }
    );
    assert_eq!(t.observe(&frame(105, 105 * 28, 28)).position(), None);
    assert_eq!(t.next_sample(), next);
    assert_eq!(
        t.observe(&frame(110, 110 * 28, 28)),
        Observation::InOrder {
            first_sample: 110 * 28
        }
    );
    let c = t.counters();
    assert_eq!((c.duplicates, c.old, c.frames), (1, 2, 14));
}

#[test]
fn restarts_are_recognised_with_and_without_their_first_frame() {
    let mut t = SequenceTracker::new(FrameKind::Fd);
    for s in 0..1000u16 {
        t.observe(&frame(s, u32::from(s) * 28, 28));
    }
    // Counters back at zero.
    assert_eq!(
        t.observe(&frame(0, 0, 28)),
        Observation::Restart { first_sample: 0 }
    );
    assert_eq!(
        t.observe(&frame(1, 28, 28)),
        Observation::InOrder { first_sample: 28 }
    );
    // A second restart whose first 5 frames were lost: behind, and nearer to zero than to
    // where the stream was.
    for s in 2..500u16 {
        t.observe(&frame(s, u32::from(s) * 28, 28));
    }
    assert_eq!(
        t.observe(&frame(5, 140, 28)),
        Observation::Restart { first_sample: 140 }
    );
    assert_eq!(
        t.observe(&frame(6, 168, 28)),
        Observation::InOrder { first_sample: 168 }
    );
    // A restart to (0, 0) just after a restart is a restart again, not a duplicate.
    assert_eq!(
        t.observe(&frame(0, 0, 28)),
        Observation::Restart { first_sample: 0 }
    );
    // ...but the same (0, 0) frame twice is a duplicate.
    assert_eq!(t.observe(&frame(0, 0, 28)), Observation::Duplicate);
    assert_eq!(t.counters().restarts, 3);
}

#[test]
fn classic_counters_wrap_and_positions_keep_growing() {
    let mut t = SequenceTracker::new(FrameKind::Classic);
    // Start 10 samples before the 24-bit index wraps, sequence near its 8-bit wrap.
    let start: u64 = (1 << 24) - 10;
    let mut seq: u16 = 250;
    let mut pos = start;
    assert_eq!(
        t.observe(&frame(seq, pos as u32, 2)),
        Observation::Start {
            first_sample: start
        }
    );
    for _ in 0..20 {
        pos += 2;
        seq = seq.wrapping_add(1);
        // The wire carries the low bits only; the node's full counters may be anything above.
        let obs = t.observe(&frame(seq & 0xFF, (pos as u32) & 0xFF_FFFF, 2));
        assert_eq!(obs, Observation::InOrder { first_sample: pos });
    }
    assert!(pos > 1 << 24);
    // A gap across nothing special, sequence wrapping inside it: 300 frames lost.
    pos += 2 + 600;
    seq = seq.wrapping_add(301);
    assert_eq!(
        t.observe(&frame(seq & 0xFF, (pos as u32) & 0xFF_FFFF, 2)),
        Observation::Gap {
            first_sample: pos,
            missing_samples: 600,
            // Exact only modulo 2^8 on classic frames.
            lost_frames: 300 % 256
        }
    );
    assert_eq!(t.counters().sequence_mismatches, 0);
}

#[test]
fn classic_gaps_are_exact_up_to_half_the_index_width() {
    for (jump, expected_gap) in [((1u64 << 23) - 1, true), (1 << 23, false)] {
        let mut t = SequenceTracker::new(FrameKind::Classic);
        let base = 5_000_000u64;
        t.observe(&frame(0x12, base as u32, 2));
        let obs = t.observe(&frame(0x13 + 7, (base + 2 + jump) as u32 & 0xFF_FFFF, 2));
        if expected_gap {
            assert_eq!(
                obs,
                Observation::Gap {
                    first_sample: base + 2 + jump,
                    missing_samples: jump,
                    lost_frames: 7
                }
            );
        } else {
            // Beyond the window the jump reads as going back: not a gap.
            assert!(
                matches!(obs, Observation::Old { .. } | Observation::Restart { .. }),
                "{obs:?}"
            );
        }
    }
}

#[test]
fn fd_index_wraps_at_32_bits() {
    let mut t = SequenceTracker::new(FrameKind::Fd);
    let mut pos = u64::from(u32::MAX) - 27 - 28 * 3;
    let mut seq = u16::MAX - 1;
    t.observe(&frame(seq, pos as u32, 28));
    for _ in 0..10 {
        pos += 28;
        seq = seq.wrapping_add(1);
        assert_eq!(
            t.observe(&frame(seq, pos as u32, 28)),
            Observation::InOrder { first_sample: pos }
        );
    }
    assert!(pos > u64::from(u32::MAX));
    assert_eq!(t.counters().restarts, 0);
    // The largest measurable FD gap.
    let jump = (1u64 << 31) - 1;
    pos += 28 + jump;
    assert_eq!(
        t.observe(&frame(seq.wrapping_add(5), pos as u32, 28)),
        Observation::Gap {
            first_sample: pos,
            missing_samples: jump,
            lost_frames: 4
        }
    );
}

#[test]
fn resync_starts_over_and_mismatches_are_counted() {
    let mut t = SequenceTracker::new(FrameKind::Fd);
    t.observe(&frame(0, 0, 28));
    // Contiguous index, wrong sequence: placed, but counted.
    assert_eq!(
        t.observe(&frame(7, 28, 28)),
        Observation::InOrder { first_sample: 28 }
    );
    // Gap in samples with no gap in sequence.
    assert!(matches!(
        t.observe(&frame(8, 1000, 28)),
        Observation::Gap { lost_frames: 0, .. }
    ));
    assert_eq!(t.counters().sequence_mismatches, 2);
    t.resync();
    assert_eq!(t.next_sample(), None);
    assert_eq!(
        t.observe(&frame(3, 9_999, 28)),
        Observation::Start {
            first_sample: 9_999
        }
    );
    assert_eq!(t.counters().starts, 2);
}

/// A node with a small queue that is drained irregularly (so it overflows), restarted once,
/// sending through the real bytes: the tracker's gaps add up to exactly the samples the node
/// dropped, and every sample lands at its own index.
fn end_to_end(kind: FrameKind, total: u64, seed: u64) {
    let cfg = NodeConfig {
        node: 11,
        axes: AxisSet::from_bits(0b0001).unwrap(),
        data_kind: kind,
        sample_rate_hz: 20_000,
        scale_g_per_count: 1e-3,
        firmware: FirmwareVersion::default(),
        metadata_period_samples: 20_000,
    };
    let mut node: SensorNode<16> = SensorNode::new(cfg).unwrap();
    let mut tracker = SequenceTracker::new(kind);
    let mut rng = XorShift::new(seed);
    let signal = |i: u64| (i.wrapping_mul(40_503) >> 3) as i16;
    let mut run_index = 0u64; // index of the next sample in the node's current run
    let mut restart_skipped = 0u64;
    let mut received = 0u64;
    let mut reset_done = false;
    let mut taken = 0u64;

    let mut drain = |node: &mut SensorNode<16>, budget: usize| {
        for _ in 0..budget {
            let Some(f) = node.pop_frame() else { break };
            let mut out = [0u8; 64];
            let (id, len) = encode(&f, kind, &mut out).unwrap();
            let Ok(Frame::Data(d)) = decode(u32::from(id), &out[..len]) else {
                continue;
            };
            let obs = tracker.observe(&d);
            let pos = obs
                .position()
                .expect("nothing is duplicated or reordered here");
            // Samples dropped before the first frame the tracker sees of a run (the node
            // starts every run at index 0) are visible only as that frame's index.
            if let Observation::Restart { first_sample } | Observation::Start { first_sample } = obs
            {
                restart_skipped += first_sample;
            }
            for (i, &s) in d.samples.iter().enumerate() {
                assert_eq!(s, signal(pos + i as u64), "{obs:?}");
            }
            received += d.samples.len() as u64;
        }
    };

    while taken < total {
        let n = 1 + rng.below(200);
        let chunk: Vec<i16> = (run_index..run_index + n).map(signal).collect();
        let _ = node.push_samples(0, &chunk).unwrap();
        run_index += n;
        taken += n;
        // Usually keep up, sometimes fall behind.
        let budget = if rng.below(10) == 0 { 0 } else { 40 };
        drain(&mut node, budget);
        if !reset_done && taken > total / 2 {
            drain(&mut node, usize::MAX);
            node.reset();
            run_index = 0;
            reset_done = true;
        }
    }
    let _ = node.flush();
    drain(&mut node, usize::MAX);

    let stats = node.stats();
    let c = tracker.counters();
    assert!(
        stats.samples_dropped > 0,
        "the queue must overflow in this test"
    );
    assert_eq!(stats.samples, taken);
    assert_eq!(c.restarts, 1);
    assert_eq!(c.duplicates + c.old, 0);
    assert_eq!(c.missing_samples + restart_skipped, stats.samples_dropped);
    assert_eq!(
        received + stats.samples_dropped + stats.samples_lost_on_reset,
        taken
    );
    assert_eq!(c.samples, received);
}

#[test]
fn end_to_end_fd_one_million_samples_with_overflow_and_a_restart() {
    end_to_end(FrameKind::Fd, 1_000_000, 7);
}

#[test]
fn end_to_end_classic_with_overflow_and_a_restart() {
    end_to_end(FrameKind::Classic, 400_000, 8);
}
