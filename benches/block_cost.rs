//! The analysis thread's share of alert latency (issue 12 item 4), in process, without the
//! daemon's threads, queues or iceoryx2: for each 0.1 s block of `BENCH_SENSORS` simulated
//! sensors, the time `Pipeline::handle` takes, and for a block that decides an alert, the time
//! from the start of `handle` to the moment the flag change comes out (when the daemon hands
//! it to the alert publisher).
//!
//! The config is the alert-latency bench's (every sensor's outer race faulty, one window per
//! average, thresholds at the middle of the scores). Since the flags follow the verdicts of band
//! selections over a whole evidence horizon (issue 30 item 4), a flag changes only in the block
//! that takes a selection's result, once per `band_period_s` and channel: few blocks decide
//! an alert. This bench runs faster than real time, so such a block also waits for the band
//! worker to finish the selection (tens of ms), which the daemon at real time does not: read
//! the alert rows as an upper bound, and the window row as the per-window analysis. The inputs
//! are seeded: two builds on one machine compare fairly.
//!
//! A block closes a window when the window's ISO velocity reading comes out of it (every
//! window has one); the window's band envelopes, fault scores and report follow in the
//! channel's next blocks (`RollingEnvelope::spread_bands`), so they count in the blocks
//! closing no window, whose p90 and max show them.
//!
//! Unpaced, this bench hands blocks over back to back, with the caches warm from the block
//! before and the band selections' thread always behind; `BENCH_PACE=4` feeds the signal at 4×
//! real time, closer to a daemon's situation (with margin): use it to compare two builds.
//!
//! Run: `cargo bench --bench block_cost` (`BENCH_SENSORS`, default 16; `BENCH_SECONDS` of
//! signal, default 60; `BENCH_PACE`, times real time, default 0: unpaced).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use bearingd::config::{parse, Transport};
use bearingd::messages::PipelineMessage;
use bearingd::pipeline::{Output, Pipeline};
use bearingd::sources::sim::SimSource;
use common::{
    env_or, percentile, simulated_sensors, CHATTERING_IMBALANCE_G, CHATTERING_THRESHOLDS,
};
use std::collections::BTreeMap;
use std::time::Instant;

fn config_text(sensors: usize) -> String {
    CHATTERING_THRESHOLDS.to_string()
        + &simulated_sensors(sensors, 25_600, |_| 0.0, CHATTERING_IMBALANCE_G)
}

/// Rounds of 0.1 s left out of the figures.
const WARM_UP_ROUNDS: usize = 20;

fn report(what: &str, mut values_us: Vec<f64>) {
    values_us.sort_by(f64::total_cmp);
    println!(
        "{what:<44} {:>6} blocks  p50 {:>7.1} µs  p90 {:>7.1}  p99 {:>7.1}  max {:>7.1}",
        values_us.len(),
        percentile(&values_us, 50.0),
        percentile(&values_us, 90.0),
        percentile(&values_us, 99.0),
        values_us.last().copied().unwrap_or(f64::NAN),
    );
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let sensors = env_or("BENCH_SENSORS", 16);
    let seconds = env_or("BENCH_SECONDS", 60);
    let pace = env_or("BENCH_PACE", 0);
    let config = parse(&config_text(sensors), "block_cost bench").expect("bench config");
    let mut sources: Vec<SimSource> = config
        .sensors
        .iter()
        .filter_map(|s| match &s.transport {
            Transport::Sim(sim) => Some(SimSource::new(s, sim, 0.1)),
            _ => None,
        })
        .collect();
    let mut pipeline = Pipeline::new(&config, &BTreeMap::new(), None);
    let (mut quiet, mut window, mut to_flag, mut deciding) = (vec![], vec![], vec![], vec![]);
    let mut every = vec![];
    let start = Instant::now();
    for round in 0..seconds * 10 {
        if pace > 0 {
            let due = std::time::Duration::from_secs_f64(round as f64 * 0.1 / pace as f64);
            std::thread::sleep(due.saturating_sub(start.elapsed()));
        }
        for source in &mut sources {
            for input in source.next_blocks() {
                let started = Instant::now();
                let mut first_flag_us = None;
                let mut windows = 0;
                pipeline.handle(input, &mut |output| {
                    // A fault flag's change, or a detector's (the ISO zone flag chatters here);
                    // a detector's reading: a window closed.
                    let (flag, reading) = match &output {
                        Output::Message(PipelineMessage::Flag(_)) => (true, false),
                        Output::Message(PipelineMessage::Detector(m)) => {
                            (m.as_flag().is_some(), m.as_flag().is_none())
                        }
                        _ => (false, false),
                    };
                    if flag {
                        first_flag_us.get_or_insert_with(|| started.elapsed().as_secs_f64() * 1e6);
                    }
                    if reading {
                        windows += 1;
                    }
                });
                let took_us = started.elapsed().as_secs_f64() * 1e6;
                // The first 2 s are left out: every channel's first window (cold caches) closes
                // in them.
                if round < WARM_UP_ROUNDS {
                    continue;
                }
                every.push(took_us);
                match (windows, first_flag_us) {
                    (0, _) => quiet.push(took_us),
                    (_, None) => window.push(took_us),
                    (_, Some(flag_us)) => {
                        to_flag.push(flag_us);
                        deciding.push(took_us);
                    }
                }
            }
        }
    }
    println!(
        "Pipeline::handle, {sensors} sensors × 25.6 kHz, {seconds} s of signal in 0.1 s blocks:"
    );
    report("every block", every);
    report("block closing no window", quiet);
    report("block closing a window, no alert", window);
    report("block deciding an alert: whole block", deciding);
    report("block deciding an alert: until the flag", to_flag);
}
