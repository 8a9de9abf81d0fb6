//! How long after its input arrived each alert was in the service: the daemon's own part of
//! an alert's latency.
//!
//! A subscriber measures receipt minus the alert's `wall_time_ns`, which adds the machine's
//! wake-up of the subscriber to the daemon's work; on a virtual machine that part can be as
//! large as the daemon's. The publisher reads the clock once more, right after the alert is in
//! shared memory and before it wakes the subscribers, so a run on any machine can tell the two
//! apart (the run's summary, and the `alert_latency` bench beside its own numbers). A fixed
//! histogram of 1 µs buckets: a daemon that runs for months keeps the same 40 kB.

use serde::Serialize;

/// Delays up to this many µs are counted to the µs; longer ones only in the total and the
/// maximum (a percentile that falls among them is the maximum).
const BUCKETS: usize = 10_000;

/// The distribution of the delays recorded so far.
pub struct PublishDelays {
    counts: Box<[u32]>,
    recorded: u64,
    max_ns: u64,
}

/// Percentiles of [`PublishDelays`], for the run's summary (µs, a bucket's upper edge).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct DelaySpread {
    pub alerts: u64,
    pub p50_us: u64,
    pub p90_us: u64,
    pub p99_us: u64,
    pub max_us: u64,
}

impl Default for PublishDelays {
    fn default() -> Self {
        PublishDelays {
            counts: vec![0; BUCKETS].into_boxed_slice(),
            recorded: 0,
            max_ns: 0,
        }
    }
}

impl PublishDelays {
    /// One alert, in the service `delay_ns` after its input arrived.
    pub fn record(&mut self, delay_ns: u64) {
        if let Some(count) = self.counts.get_mut((delay_ns / 1_000) as usize) {
            *count = count.saturating_add(1);
        }
        self.recorded += 1;
        self.max_ns = self.max_ns.max(delay_ns);
    }

    /// `None` before the first alert.
    pub fn spread(&self) -> Option<DelaySpread> {
        if self.recorded == 0 {
            return None;
        }
        let max_us = self.max_ns.div_ceil(1_000);
        Some(DelaySpread {
            alerts: self.recorded,
            p50_us: self.percentile_us(50, max_us),
            p90_us: self.percentile_us(90, max_us),
            p99_us: self.percentile_us(99, max_us),
            max_us,
        })
    }

    /// The nearest-rank percentile, as the upper edge of its bucket (never above the maximum);
    /// one past the histogram is the maximum itself.
    fn percentile_us(&self, percent: u64, max_us: u64) -> u64 {
        let rank = (self.recorded * percent).div_ceil(100).max(1);
        let mut seen = 0u64;
        for (bucket, &count) in self.counts.iter().enumerate() {
            seen += u64::from(count);
            if seen >= rank {
                return (bucket as u64 + 1).min(max_us);
            }
        }
        max_us
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_recorded_has_no_spread() {
        assert_eq!(PublishDelays::default().spread(), None);
    }

    #[test]
    fn percentiles_are_nearest_rank_to_the_microsecond() {
        let mut delays = PublishDelays::default();
        // 1..=100 µs, each once, plus a little inside each µs.
        for us in 1..=100u64 {
            delays.record(us * 1_000 - 400);
        }
        let spread = delays.spread().expect("recorded");
        assert_eq!(spread.alerts, 100);
        assert_eq!(spread.p50_us, 50);
        assert_eq!(spread.p90_us, 90);
        assert_eq!(spread.p99_us, 99);
        assert_eq!(spread.max_us, 100);
    }

    #[test]
    fn delays_past_the_histogram_count_and_set_the_maximum() {
        let mut delays = PublishDelays::default();
        delays.record(119_500);
        delays.record(25_000_000);
        let spread = delays.spread().expect("recorded");
        assert_eq!(spread.p50_us, 120);
        assert_eq!(
            spread.p99_us, 25_000,
            "the rank past the histogram is the maximum"
        );
        assert_eq!(spread.max_us, 25_000);
    }

    #[test]
    fn a_single_alert_is_every_percentile() {
        let mut delays = PublishDelays::default();
        delays.record(0);
        let spread = delays.spread().expect("recorded");
        assert_eq!((spread.p50_us, spread.p99_us, spread.max_us), (0, 0, 0));
    }
}
