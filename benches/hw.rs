//! Hammerstein–Wiener identification time (issue 13): the seed's configuration (order 0,
//! inputs a⁽¹⁾…a⁽³⁾, 3 poles, 0 zeros, delay 1, cubic output) on one PRONOSTIA snapshot
//! (2,560 samples, 0.1 s at 25.6 kHz) and on 1 s at 25.6 kHz (ten snapshots of the same
//! bearing joined end to end), and on the snapshot warm-started from an earlier snapshot's model
//! (the daemon's periodic re-fit). Needs ../shared/data/femto.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::recording::{read_recording, ReadOptions};
use bearingd::twin::hw::{identify_record, HwConfig};
use criterion::{criterion_group, criterion_main, Criterion};
use std::path::Path;

const FS_HZ: f64 = 25_600.0;

fn snapshot(index: usize) -> Vec<f64> {
    let path = format!("../shared/data/femto/Bearing1_2/acc_{index:05}.csv");
    read_recording(Path::new(&path), &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{path}: {e} (the bench needs ../shared/data/femto)"))
        .samples
}

fn identification(c: &mut Criterion) {
    let short = snapshot(1);
    let long: Vec<f64> = (0..10).flat_map(|i| snapshot(1 + 10 * i)).collect();
    assert_eq!(long.len(), 25_600);
    let mut group = c.benchmark_group("hw_identify");
    group.sample_size(10);
    for order in [0, 2] {
        let config = HwConfig::for_order(order);
        group.bench_function(format!("snapshot_2560_order{order}"), |b| {
            b.iter(|| identify_record(&short, FS_HZ, &config, None).unwrap())
        });
        // The daemon's re-fit: warm-started from the model of an earlier snapshot.
        let earlier = identify_record(&snapshot(11), FS_HZ, &config, None)
            .unwrap()
            .model;
        group.bench_function(format!("snapshot_2560_order{order}_warm"), |b| {
            b.iter(|| identify_record(&short, FS_HZ, &config, Some(&earlier)).unwrap())
        });
        group.bench_function(format!("one_second_25600_order{order}"), |b| {
            b.iter(|| identify_record(&long, FS_HZ, &config, None).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, identification);
criterion_main!(benches);
