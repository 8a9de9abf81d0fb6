//! iceoryx2 across real processes: the `firmware-sim` binary publishes, this test process
//! subscribes through bearingd's shm source. Ready handshake first, then zero loss over more
//! than a million samples per stream, with every sample checked against the twin.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::iox::IoxSettings;
use bearingd::sources::handoff::WhenFull;
use bearingd::sources::shm::{self, ShmSourceConfig};
use bearingd::sources::IngestEvent;
use bearingd::twin::{SimulatedFault, SimulationParams, Simulator};
use std::collections::BTreeMap;
use std::process::{Command, Stdio};
use std::time::Duration;

const FS: u32 = 25_600;
const SECONDS: u32 = 40; // 1,024,000 samples per stream
const SCALE: f32 = 1.0 / 2048.0;

/// What the simulator sends on stream `index` (node-major, axis-minor), as counts.
fn expected_counts(index: u64, seed: u64, samples: usize) -> Vec<i16> {
    let mut params = SimulationParams::example(SimulatedFault::OuterRace);
    params.rpm = 1772.0;
    params.fs_hz = f64::from(FS);
    params.noise_g = 0.05;
    params.onset_s = 0.0;
    params.seed = seed + index;
    let mut sim = Simulator::new(params);
    let mut g = vec![0f32; samples];
    // The twin is deterministic for a seed *and* block sizes (noise and impact jitter share
    // one random stream), so fill in firmware-sim's chunks: fs/100 samples.
    for chunk in g.chunks_mut((FS / 100) as usize) {
        sim.fill(chunk);
    }
    g.iter()
        .map(|x| {
            (f64::from(*x) / f64::from(SCALE))
                .round()
                .clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
        })
        .collect()
}

#[test]
fn zero_loss_over_a_million_samples_per_stream() {
    let prefix = format!("bdtest{}_", std::process::id());
    let sensor = "shmtest";
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let (events_tx, mut events_rx) = tokio::sync::mpsc::channel(256);
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let config = ShmSourceConfig {
        sensor: sensor.into(),
        iox: IoxSettings {
            prefix: Some(prefix.clone()),
            root_path: None,
        },
        silence_timeout: Duration::from_secs(5),
        handoff_capacity: 16,
        when_full: WhenFull::Block,
        stats_interval: None,
    };
    let summary = runtime.block_on(async move {
        let source = tokio::spawn(shm::run(config, events_tx, async move {
            let _ = stop_rx.await;
        }));
        let sim = Command::new(env!("CARGO_BIN_EXE_firmware-sim"))
            .args([
                "--transport",
                "shm",
                "--sensor",
                sensor,
                "--iox-prefix",
                &prefix,
            ])
            .args(["--fd", "--nodes", "2", "--axes", "2", "--speed-factor", "0"])
            .args(["--duration", &SECONDS.to_string(), "--fs", &FS.to_string()])
            .args(["--seed", "11", "--wait-ready", "20"])
            .stdout(Stdio::piped())
            .spawn()
            .expect("spawn firmware-sim");
        let mut received: BTreeMap<(u8, u8), Vec<i16>> = BTreeMap::new();
        let mut problems = Vec::new();
        let total = (FS * SECONDS) as usize;
        while received.len() < 4 || received.values().any(|v| v.len() < total) {
            let event = tokio::time::timeout(Duration::from_secs(30), events_rx.recv())
                .await
                .expect("no event for 30 s")
                .expect("source ended");
            match event {
                IngestEvent::Samples(block) => {
                    let stream = received.entry((block.node, block.axis)).or_default();
                    assert_eq!(block.first_sample, stream.len() as u64, "discontinuity");
                    stream.extend_from_slice(&block.samples);
                }
                IngestEvent::Metadata { .. } | IngestEvent::Speed { .. } => {}
                other => problems.push(other),
            }
        }
        let status = tokio::task::spawn_blocking(move || sim.wait_with_output())
            .await
            .unwrap()
            .unwrap();
        assert!(status.status.success(), "firmware-sim failed");
        let _ = stop_tx.send(());
        let summary = source.await.unwrap().unwrap();
        assert!(problems.is_empty(), "{problems:?}");
        (summary, received)
    });
    let (summary, received) = summary;
    assert_eq!(summary.stats.gaps, 0);
    assert_eq!(summary.stats.missing_samples, 0);
    assert_eq!(summary.stats.malformed.total(), 0);
    assert_eq!(summary.stats.handoff_dropped, 0);
    assert_eq!(summary.stats.samples, 4 * u64::from(FS * SECONDS));
    assert_eq!(summary.streams.len(), 4);
    for (index, ((node, axis), samples)) in received.iter().enumerate() {
        assert_eq!(
            samples.len(),
            (FS * SECONDS) as usize,
            "node {node} axis {axis}"
        );
        let expected = expected_counts(index as u64, 11, samples.len());
        let first_difference = samples.iter().zip(&expected).position(|(a, b)| a != b);
        assert_eq!(
            first_difference, None,
            "node {node} axis {axis} differs from the twin"
        );
    }
}
