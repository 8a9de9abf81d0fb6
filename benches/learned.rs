//! Speed of the learned diagnosis (issue 14: inference ≤ 1 ms per window on one core),
//! reported in docs/PHYSICS.md, "Learned diagnosis" and docs/PERFORMANCE.md:
//! - the input of one segment (24 revolutions' envelope spectrum on the order axis);
//! - the network on one segment (autoencoder + CNN);
//! - the whole opinion of a 10 s record (its segments, one after the other).
//!
//! Run: `cargo bench --bench learned`. One core: the plain forward pass is single-threaded, and
//! the threads of any other kernel (rayon) are set to 1.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::analysis::envelope::FftPlans;
use bearingd::learned::LearnedModel;
use bearingd::twin::{SimulatedFault, SimulationParams, Simulator};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::path::Path;

fn learned(c: &mut Criterion) {
    let model = LearnedModel::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("models/skf-6205-2rs.safetensors"),
    )
    .unwrap();
    let params = SimulationParams::example(SimulatedFault::OuterRace);
    let record = Simulator::record(params.clone(), 10.0);
    let shaft_hz = params.rpm / 60.0;
    let freqs = params.bearing.fault_frequencies(shaft_hz);
    let features = model.card.features;
    let segment = features.segment_samples(params.fs_hz, shaft_hz);
    let mut plans = FftPlans::default();
    let input = features.order_spectrum(&mut plans, &record[..segment], params.fs_hz, &freqs);
    c.bench_function(
        "learned: input of one segment (24 revolutions, 12 kHz)",
        |b| {
            b.iter(|| {
                features.order_spectrum(
                    &mut plans,
                    black_box(&record[..segment]),
                    params.fs_hz,
                    &freqs,
                )
            })
        },
    );
    c.bench_function("learned: network on one segment", |b| {
        b.iter(|| model.classify(black_box(&input)))
    });
    c.bench_function("learned: opinion of a 10 s record", |b| {
        b.iter(|| {
            model
                .opinion(black_box(&record), params.fs_hz, shaft_hz, &params.bearing)
                .unwrap()
        })
    });
}

fn one_core() -> Criterion {
    // rayon (candle's CPU kernels, when training code is measured) sizes its pool from this.
    std::env::set_var("RAYON_NUM_THREADS", "1");
    Criterion::default()
}

criterion_group! {
    name = benches;
    config = one_core();
    targets = learned
}
criterion_main!(benches);
