//! The protobuf payload sizes of the bridge's messages, made by the real metric book and edge
//! node from fixed observations: printed by `benches/fleet.rs` and checked against the table of
//! docs/FLEET.md by the suite (`the_documented_message_sizes_are_the_measured_ones`), so that the
//! table cannot go stale when metrics are added.
#![allow(dead_code)]

use bearingd::messages::{FaultKind, FlagLevel};
use bearingd::sinks::fleet::metrics::{MetricBook, Observation, Observed};
use bearingd::sinks::fleet::node::{EdgeNode, Kind};
use bearingd::sinks::fleet::sparkplug::Value;

/// The channel of the measurements, and the topic length's example.
pub const DEVICE: &str = "motor-de.radial";

/// Payload bytes of each message.
#[derive(Debug, Clone, Copy)]
pub struct Sizes {
    /// With the `Properties/bearingd version` metric the bridge adds.
    pub nbirth: usize,
    pub nbirth_bare: usize,
    pub dbirth: usize,
    /// The first DDATA of a session: every metric of a window is new.
    pub ddata_first: usize,
    /// One window's metrics changed: speed, 4 indicators, 4 scores, the record number.
    pub ddata_typical: usize,
    pub ddata_flag: usize,
    pub ddata_twin: usize,
    pub ndeath: usize,
    /// The DDATA topic `spBv1.0/plant/DDATA/press-7/motor-de.radial`.
    pub topic: usize,
}

/// An analysis window's metrics; `k` varies them (an unchanged value is no news).
pub fn window(device: usize, at_ms: u64, k: f64) -> Observation {
    Observation {
        device,
        at_ms,
        what: Observed::Window {
            rpm: Some(1772.0),
            rms_g: 0.5 + 0.01 * k,
            peak_g: 2.0 + 0.01 * k,
            crest: 4.0 + 0.001 * k,
            kurtosis: 3.1 + 0.001 * k,
            scores: [12.0 + k, 1.5, 1.2 + 0.1 * k, 0.9],
        },
    }
}

/// A typical DDATA of one channel: the metrics of one analysis window changed.
pub fn typical_ddata(book: &mut MetricBook, node: &mut EdgeNode, at_ms: u64) -> Vec<u8> {
    // The values change with every period (a value that comes back unchanged is no news and
    // makes no record: `at_ms % 97` repeated when two stamps were a multiple of 97 ms apart).
    let k = ((at_ms / 1000) % 97) as f64;
    let record = book
        .observe(window(0, at_ms, k))
        .expect("a record per period");
    let publishes = node
        .data(book, &record, at_ms / 1000, false, at_ms)
        .expect("a known device");
    publishes.last().expect("the DDATA").payload.clone()
}

/// The node as the bridge makes it (its NBIRTH carries the bearingd version), one channel.
pub fn book_and_node() -> (MetricBook, EdgeNode) {
    let book = MetricBook::new(vec![DEVICE.into()], 1000);
    let mut node = EdgeNode::new("plant", "press-7", 1, 0);
    node.set_properties(vec![(
        "Properties/bearingd version".into(),
        Value::String(env!("CARGO_PKG_VERSION").into()),
    )]);
    (book, node)
}

/// Every size, at `t0` (milliseconds since the epoch: today's stamps take 6 bytes each).
pub fn measure(t0: u64) -> Sizes {
    let (mut book, mut node) = book_and_node();
    let births = node.births(&book, t0);
    let nbirth_bare = EdgeNode::new("plant", "press-7", 1, 0).births(&book, t0)[0]
        .payload
        .len();
    let first = typical_ddata(&mut book, &mut node, t0);
    let typical = typical_ddata(&mut book, &mut node, t0 + 1000);
    let flag = book
        .observe(Observation {
            device: 0,
            at_ms: t0 + 1500,
            what: Observed::Flag {
                fault: FaultKind::OuterRace,
                level: FlagLevel::Alarm,
                score: 25.0,
                confidence: 0.93,
            },
        })
        .expect("a flag goes at once");
    let flag = node.data(&book, &flag, 3, false, t0 + 1500).unwrap();
    let twin = book
        .observe(Observation {
            device: 0,
            at_ms: t0 + 2500,
            what: Observed::Twin {
                hypothesis: FaultKind::OuterRace,
                error: 0.03,
                margin: 0.4,
                errors: [0.03, 0.4, 0.5],
                residual_energy_ratio: 0.1,
                residual_peak_hz: 3100.0,
            },
        })
        .expect("a record");
    let twin = node.data(&book, &twin, 4, false, t0 + 2500).unwrap();
    Sizes {
        nbirth: births[0].payload.len(),
        nbirth_bare,
        dbirth: births[1].payload.len(),
        ddata_first: first.len(),
        ddata_typical: typical.len(),
        ddata_flag: flag[0].payload.len(),
        ddata_twin: twin[0].payload.len(),
        ndeath: node.death(t0).payload.len(),
        topic: node.topic(Kind::DData, Some(DEVICE)).len(),
    }
}
