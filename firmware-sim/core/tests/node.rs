//! SensorNode: long runs pack every sample exactly once with contiguous indices; metadata comes
//! on schedule; overflow, reset and flush are counted, never silent.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use bearing_wire::{
    encode, AxisSet, ConfigError, FirmwareVersion, Frame, FrameKind, MetadataPage, NodeConfig,
    PushError, Pushed, SensorNode, SpeedSource,
};
use common::XorShift;

fn config(kind: FrameKind, axes: u8, period: u32) -> NodeConfig {
    NodeConfig {
        node: 6,
        axes: AxisSet::from_bits(axes).unwrap(),
        data_kind: kind,
        sample_rate_hz: 25_600,
        scale_g_per_count: 1.0 / 4096.0,
        firmware: FirmwareVersion {
            major: 0,
            minor: 3,
            patch: 1,
        },
        metadata_period_samples: period,
    }
}

/// The sample the test signal has on `axis` at `index`: distinct per axis, covers the i16 range.
fn signal(axis: u8, index: u64) -> i16 {
    (index.wrapping_mul(2_654_435_761) as i16) ^ (i16::from(axis) << 13)
}

fn add(total: &mut Pushed, p: Pushed) {
    total.queued += p.queued;
    total.dropped += p.dropped;
}

/// Per-axis receiver-side bookkeeping of the frames a node produced.
#[derive(Default, Clone)]
struct AxisSeen {
    samples: u64,
    frames: u64,
    next_sequence: u16,
}

/// Pushes `per_axis` samples on each configured axis in random chunks, round-robin over the
/// axes, popping everything after each chunk; checks every frame as it comes out.
fn long_run(kind: FrameKind, axes: u8, per_axis: u64, period: u32, seed: u64) {
    let cfg = config(kind, axes, period);
    // Room for the largest chunk (300 samples with a metadata burst per sample), so nothing
    // overflows here; overflow has its own test.
    let mut node: SensorNode<1024> = SensorNode::new(cfg).unwrap();
    let mut rng = XorShift::new(seed);
    let axis_list: Vec<u8> = cfg.axes.iter().collect();
    let reference = axis_list[0];
    let mut pushed = vec![0u64; 4];
    let mut seen = vec![AxisSeen::default(); 4];
    let mut metadata_frames = 0u64;
    let mut report = Pushed::default();
    let mut buf = Vec::new();
    let mut out = [0u8; 64];

    let mut check = |frame: Frame, pushed: &[u64]| match frame {
        Frame::Data(d) => {
            let s = &mut seen[usize::from(d.axis)];
            assert_eq!(d.node, 6);
            assert_eq!(u64::from(d.first_sample), s.samples, "axis {}", d.axis);
            assert_eq!(d.sequence, s.next_sequence, "axis {}", d.axis);
            assert!(!d.samples.is_empty() && d.samples.len() <= kind.max_samples());
            for (i, &v) in d.samples.iter().enumerate() {
                assert_eq!(v, signal(d.axis, s.samples + i as u64));
            }
            s.samples += d.samples.len() as u64;
            s.frames += 1;
            s.next_sequence = s.next_sequence.wrapping_add(1);
            encode(&Frame::Data(d), kind, &mut out).expect("node frames encode");
        }
        Frame::Metadata(m) => {
            // A burst is queued just before reference-axis sample k * period is taken, so
            // when it comes out, the reference axis has been packed up to a frame boundary at
            // or before k * period.
            if let MetadataPage::Stream(s) = m.page {
                let k = metadata_frames / 2;
                assert!(seen[usize::from(reference)].samples <= k * u64::from(period));
                assert!(pushed[usize::from(reference)] > k * u64::from(period));
                assert_eq!(s.data_kind, kind);
                assert_eq!(s.axes.bits(), axes);
            }
            metadata_frames += 1;
        }
        Frame::Speed(_) => unreachable!(),
    };

    while axis_list.iter().any(|&a| pushed[usize::from(a)] < per_axis) {
        for &axis in &axis_list {
            let a = usize::from(axis);
            let n = (1 + rng.below(300)).min(per_axis - pushed[a]);
            buf.clear();
            buf.extend((0..n).map(|i| signal(axis, pushed[a] + i)));
            if n == 1 && rng.below(2) == 0 {
                add(&mut report, node.push_sample(axis, buf[0]).unwrap());
            } else {
                add(&mut report, node.push_samples(axis, &buf).unwrap());
            }
            pushed[a] += n;
            while let Some(f) = node.pop_frame() {
                check(f, &pushed);
            }
        }
    }
    add(&mut report, node.flush());
    while let Some(f) = node.pop_frame() {
        check(f, &pushed);
    }

    let stats = node.stats();
    assert_eq!(report.dropped, 0);
    assert_eq!(stats.frames_dropped, 0);
    assert_eq!(stats.samples, per_axis * axis_list.len() as u64);
    let per_frame = kind.max_samples() as u64;
    for &axis in &axis_list {
        let s = &seen[usize::from(axis)];
        assert_eq!(
            s.samples, per_axis,
            "axis {axis}: every sample exactly once"
        );
        assert_eq!(
            s.frames,
            per_axis.div_ceil(per_frame),
            "axis {axis}: full frames"
        );
        assert_eq!(node.pending(axis), 0);
        assert_eq!(node.next_sample(axis), Some(per_axis as u32));
    }
    let bursts = per_axis.div_ceil(u64::from(period));
    assert_eq!(metadata_frames, 2 * bursts);
    assert_eq!(stats.metadata_frames, 2 * bursts);
    assert_eq!(
        report.queued as u64,
        stats.data_frames + stats.metadata_frames
    );
}

#[test]
fn fd_three_axes_one_million_samples_each() {
    long_run(FrameKind::Fd, 0b0111, 1_000_000, 25_600, 1);
}

#[test]
fn classic_one_axis_one_million_samples_wraps_the_sequence() {
    // 500 000 frames: the 16-bit sequence wraps 7 times.
    long_run(FrameKind::Classic, 0b1000, 1_000_000, 4_000, 2);
}

#[test]
fn odd_periods_and_axis_sets() {
    long_run(FrameKind::Fd, 0b1010, 10_007, 1, 3);
    long_run(FrameKind::Classic, 0b0101, 10_001, 997, 4);
    long_run(FrameKind::Fd, 0b1111, 28 * 50, 28, 5);
}

#[test]
fn overflow_drops_the_oldest_and_counts_everything() {
    let mut node: SensorNode<8> = SensorNode::new(config(FrameKind::Fd, 0b0001, 1_000)).unwrap();
    let samples: Vec<i16> = (0..2_800).map(|i| signal(0, i)).collect();
    let report = node.push_samples(0, &samples).unwrap();
    let stats = node.stats();
    // 100 data frames + 3 metadata bursts of 2 pages, 8 kept.
    assert_eq!(stats.data_frames, 100);
    assert_eq!(stats.metadata_frames, 6);
    assert_eq!(report.queued, 106);
    assert_eq!(report.dropped, 98);
    assert_eq!(stats.frames_dropped, 98);
    assert_eq!(node.queued(), 8);
    // The newest survive: the last 8 data frames, in order, their counters untouched.
    let kept: Vec<Frame> = std::iter::from_fn(|| node.pop_frame()).collect();
    let data: Vec<_> = kept
        .iter()
        .map(|f| match f {
            Frame::Data(d) => (d.sequence, d.first_sample),
            other => panic!("expected data, got {other:?}"),
        })
        .collect();
    let expected: Vec<_> = (92..100u16).map(|s| (s, u32::from(s) * 28)).collect();
    assert_eq!(data, expected);
    assert_eq!(stats.data_frames_dropped, 92);
    assert_eq!(stats.samples_dropped, 92 * 28);
    assert_eq!(stats.frames_dropped - stats.data_frames_dropped, 6);
    // Sample accounting closes: taken = dropped + kept.
    assert_eq!(stats.samples, stats.samples_dropped + 8 * 28);
}

#[test]
fn reset_restarts_counters_and_counts_what_it_loses() {
    let mut node: SensorNode<64> =
        SensorNode::new(config(FrameKind::Classic, 0b0011, 100)).unwrap();
    let _ = node.push_samples(0, &[1, 2, 3, 4, 5]).unwrap();
    let _ = node.push_samples(1, &[1, 2, 3]).unwrap();
    assert_eq!(
        node.push_speed(SpeedSource::Tachometer, Some(150_000))
            .queued,
        1
    );
    // Queued: 2 metadata, 2 + 1 data frames, 1 speed. Pending: 1 + 1 samples.
    assert_eq!(node.queued(), 6);
    node.reset();
    let stats = node.stats();
    assert_eq!(stats.resets, 1);
    assert_eq!(stats.frames_lost_on_reset, 6);
    assert_eq!(stats.samples_lost_on_reset, 8);
    assert_eq!(node.queued(), 0);
    assert_eq!(
        (node.next_sample(0), node.next_sample(1)),
        (Some(0), Some(0))
    );

    let _ = node.push_samples(1, &[7, 8]).unwrap();
    let _ = node.push_samples(0, &[9, 10]).unwrap();
    let _ = node.push_speed(SpeedSource::Drive, None);
    let frames: Vec<Frame> = std::iter::from_fn(|| node.pop_frame()).collect();
    // Axis 1 is not the reference axis: its frame comes before the metadata, which is sent
    // before the reference axis's first sample after the restart.
    let summary: Vec<String> = frames
        .iter()
        .map(|f| match f {
            Frame::Data(d) => format!("d{}:{}:{}", d.axis, d.sequence, d.first_sample),
            Frame::Metadata(m) => format!("m{}", m.page.index()),
            Frame::Speed(s) => format!("s{}:{:?}", s.sequence, s.centi_rpm),
        })
        .collect();
    assert_eq!(summary, ["d1:0:0", "m0", "m1", "d0:0:0", "s0:None"]);
}

#[test]
fn flush_sends_short_frames_that_encode() {
    for kind in [FrameKind::Classic, FrameKind::Fd] {
        let mut node: SensorNode<16> = SensorNode::new(config(kind, 0b0110, 1_000)).unwrap();
        let _ = node.push_samples(1, &[1; 29]).unwrap();
        let _ = node.push_sample(2, -5).unwrap();
        assert_eq!(node.flush().queued, 2);
        assert_eq!(node.flush(), Pushed::default(), "nothing left to flush");
        let mut lens = Vec::new();
        while let Some(f) = node.pop_frame() {
            let mut out = [0u8; 64];
            let (_, len) = encode(&f, kind, &mut out).unwrap();
            if let Frame::Data(d) = f {
                lens.push((d.axis, d.samples.len(), len));
            }
        }
        match kind {
            FrameKind::Classic => {
                assert_eq!(lens.len(), 16);
                assert_eq!(lens[14], (1, 1, 6));
                assert_eq!(lens[15], (2, 1, 6));
            }
            FrameKind::Fd => assert_eq!(lens, [(1, 28, 64), (1, 1, 64), (2, 1, 64)]),
        }
    }
}

#[test]
fn unconfigured_axes_are_refused_without_taking_anything() {
    let mut node: SensorNode<4> = SensorNode::new(config(FrameKind::Fd, 0b0001, 10)).unwrap();
    assert_eq!(
        node.push_samples(1, &[1, 2]),
        Err(PushError::AxisNotConfigured(1))
    );
    assert_eq!(node.push_sample(9, 1), Err(PushError::AxisNotConfigured(9)));
    assert_eq!(node.stats().samples, 0);
    assert_eq!(node.queued(), 0);
    assert_eq!(node.pending(1), 0);
    assert_eq!(node.next_sample(1), None);
}

#[test]
fn invalid_configs_are_refused() {
    let good = config(FrameKind::Fd, 1, 10);
    let cases = [
        (
            NodeConfig { node: 16, ..good },
            ConfigError::NodeOutOfRange(16),
        ),
        (
            NodeConfig {
                axes: AxisSet::default(),
                ..good
            },
            ConfigError::NoAxes,
        ),
        (
            NodeConfig {
                sample_rate_hz: 0,
                ..good
            },
            ConfigError::ZeroSampleRate,
        ),
        (
            NodeConfig {
                metadata_period_samples: 0,
                ..good
            },
            ConfigError::ZeroMetadataPeriod,
        ),
        (
            NodeConfig {
                scale_g_per_count: -1.0,
                ..good
            },
            ConfigError::BadScale(-1.0),
        ),
    ];
    for (cfg, err) in cases {
        assert_eq!(SensorNode::<4>::new(cfg).unwrap_err(), err);
    }
    assert!(SensorNode::<4>::new(NodeConfig {
        scale_g_per_count: f32::NAN,
        ..good
    })
    .is_err());
}

#[test]
fn speed_frames_count_and_never_send_the_reserved_value() {
    let mut node: SensorNode<300> = SensorNode::new(config(FrameKind::Fd, 1, 10)).unwrap();
    for i in 0..257u32 {
        let _ = node.push_speed(SpeedSource::Drive, Some(i));
    }
    let _ = node.push_speed(SpeedSource::Tachometer, Some(u32::MAX));
    let frames: Vec<Frame> = std::iter::from_fn(|| node.pop_frame()).collect();
    let Frame::Speed(s) = &frames[256] else {
        panic!()
    };
    assert_eq!((s.sequence, s.centi_rpm), (0, Some(256)), "sequence wraps");
    let Frame::Speed(s) = &frames[257] else {
        panic!()
    };
    assert_eq!(s.centi_rpm, None);
    assert!(encode(&frames[257], FrameKind::Classic, &mut [0; 64]).is_ok());
    assert_eq!(node.stats().speed_frames, 258);
}
