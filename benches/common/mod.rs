//! What the latency benches share (`alert_latency`, `block_cost`): reading their knobs from the
//! environment, percentiles, and the simulated-sensor config whose flags chatter, so that both
//! measure the same analysis on the same inputs.
#![allow(dead_code)] // each bench uses its own subset

use std::fmt::Write as _;

/// The environment variable `name` as a number, or `default` when unset or not a number.
pub fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The nearest-rank percentile `p` (0–100) of ascending `sorted`; NaN when empty.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// Config that makes the flags chatter: one window per average, thresholds at the middle of the
/// outer-race scores, no delays and almost no hysteresis. Since the fault flags follow band
/// selections (once per `band_period_s`), what chatters is the per-window ISO zone flag, with
/// [`CHATTERING_IMBALANCE_G`]: about 40 % of the windows raise or clear an alert. Everything
/// else is the default config's.
pub const CHATTERING_THRESHOLDS: &str = "[analysis]\naverages = 1\n\n[thresholds]\n\
     watch_score = 60.0\nalarm_score = 90.0\nclear_ratio = 0.999\non_delay_s = 0\noff_delay_s = 0\n";

/// An imbalance whose 1× velocity sits at the ISO zone B/C boundary of the default machine
/// group (2.8 mm/s; 0.1 g gives 3.74 mm/s): with one window per average the zone flag flips on
/// about 40 % of the windows (25 changes in 60 s of one sensor with an outer-race fault,
/// measured 2026-11-27).
pub const CHATTERING_IMBALANCE_G: f64 = 0.075;

/// The simulator's default imbalance (`[sensors.sim] imbalance_g`): zone B, no velocity flag.
pub const DEFAULT_IMBALANCE_G: f64 = 0.05;

/// `sensors` simulated SKF 6205 sensors at `rate_hz` and 1772 rpm with seeds 1, 2, …; sensor
/// j's outer race fails at `onset_s(j)`; `imbalance_g` of once-per-revolution tone.
pub fn simulated_sensors(
    sensors: usize,
    rate_hz: usize,
    onset_s: impl Fn(usize) -> f64,
    imbalance_g: f64,
) -> String {
    let mut text = String::new();
    for j in 0..sensors {
        let _ = write!(
            text,
            "\n[[sensors]]\nid = \"s{j:02}\"\ntransport = \"sim\"\nsample_rate_hz = {rate_hz}\n\
             bearing = \"skf-6205-2rs\"\n[sensors.speed]\nsource = \"fixed\"\nrpm = 1772\n\
             [sensors.sim]\nfault = \"outer\"\nonset_s = {onset:?}\nseverity = 1.5\nseed = {seed}\n\
             imbalance_g = {imbalance_g:?}\n",
            onset = onset_s(j),
            seed = j + 1
        );
    }
    text
}

/// The machine's own jitter, the floor under any latency tail measured on it: a fixed amount of
/// arithmetic (calibrated to take about `work_us` here, the size of one window's analysis),
/// done `rounds` times, each after a 2 ms sleep as the analysis thread sleeps between blocks.
/// Returns the durations in ms, ascending. On a virtual machine the p99 of this alone can be
/// several times its median (a host that takes the CPU away is not visible from inside).
pub fn host_jitter_ms(work_us: f64, rounds: usize) -> Vec<f64> {
    fn spin(iterations: u64) -> f64 {
        let mut acc = 0.0f64;
        for k in 0..iterations {
            acc = std::hint::black_box(acc + k as f64 * 1e-9);
        }
        acc
    }
    let timed = |iterations: u64| {
        let started = std::time::Instant::now();
        std::hint::black_box(spin(iterations));
        started.elapsed().as_secs_f64() * 1e3
    };
    // Iterations per µs: the fastest of a few calibration runs (the least disturbed).
    let probe = 200_000u64;
    let fastest_ms = (0..20).map(|_| timed(probe)).fold(f64::INFINITY, f64::min);
    let iterations = (probe as f64 * work_us / (fastest_ms * 1e3)).max(1.0) as u64;
    let mut durations: Vec<f64> = (0..rounds)
        .map(|_| {
            std::thread::sleep(std::time::Duration::from_millis(2));
            timed(iterations)
        })
        .collect();
    durations.sort_by(f64::total_cmp);
    durations
}
