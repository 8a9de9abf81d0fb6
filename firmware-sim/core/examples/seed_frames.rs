//! Writes the frames a sensor node sends (metadata, speed, then data of two axes) to stdout as
//! `[CAN id u32 LE][length u8][bytes]` records: the input format of the `can_frames` fuzz
//! target, made by the node's own code (`scripts/fuzz_seeds.sh` calls it).
//!
//! Usage: `cargo run -p bearing-wire --example seed_frames -- fd|classic SAMPLES`

use bearing_wire::{
    encode, AxisSet, FirmwareVersion, FrameKind, NodeConfig, SensorNode, SpeedSource,
};
use std::io::Write;

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let kind = match args.next().as_deref() {
        Some("fd") => FrameKind::Fd,
        Some("classic") => FrameKind::Classic,
        other => return Err(format!("layout {other:?}: give fd or classic")),
    };
    let samples: usize = match args.next() {
        Some(n) => n.parse().map_err(|e| format!("sample count {n:?}: {e}"))?,
        None => 200,
    };
    let axes = AxisSet::from_axes(&[0, 1]).ok_or("axes 0 and 1")?;
    let mut node: SensorNode<64> = SensorNode::new(NodeConfig {
        node: 3,
        axes,
        data_kind: kind,
        sample_rate_hz: 25_600,
        scale_g_per_count: 1.0 / 2048.0,
        firmware: FirmwareVersion {
            major: 1,
            minor: 2,
            patch: 3,
        },
        metadata_period_samples: 100,
    })
    .map_err(|e| format!("node config: {e:?}"))?;
    let mut out = Vec::new();
    let mut dropped = node
        .push_speed(SpeedSource::Tachometer, Some(177_200))
        .dropped;
    for i in 0..samples {
        // A coarse sine in counts: realistic enough to decode, small enough to mutate.
        let value = ((i as f64 * 0.3).sin() * 1000.0) as i16;
        for axis in [0, 1] {
            let pushed = node.push_samples(axis, &[value]);
            dropped += pushed.map_err(|e| format!("push: {e:?}"))?.dropped;
        }
        drain(&mut node, kind, &mut out)?;
    }
    dropped += node.flush().dropped;
    drain(&mut node, kind, &mut out)?;
    if dropped > 0 {
        return Err(format!("{dropped} frames dropped by the node's queue"));
    }
    std::io::stdout()
        .write_all(&out)
        .map_err(|e| format!("stdout: {e}"))
}

fn drain(node: &mut SensorNode<64>, kind: FrameKind, out: &mut Vec<u8>) -> Result<(), String> {
    let mut bytes = [0u8; 64];
    while let Some(frame) = node.pop_frame() {
        let (id, len) = encode(&frame, kind, &mut bytes).map_err(|e| format!("encode: {e}"))?;
        out.extend_from_slice(&u32::from(id).to_le_bytes());
        out.push(len as u8);
        out.extend_from_slice(&bytes[..len]);
    }
    Ok(())
}
