//! The sensor watch of a channel monitor: clipping (counts at full scale) and a flat line (no
//! change for a while), reported when each starts and when it ends. It looks at the raw counts,
//! before any scaling, so a sensor stuck at full scale is told apart from a loud machine.

use super::events::{MonitorEvent, SensorCondition};

/// Clipping and flat-line state over the counts, judged sample by sample.
pub(super) struct SensorWatch {
    /// A count whose magnitude reaches this is clipped.
    clip_count: i32,
    /// Samples without any change that make a flat line; also the quiet stretch that ends
    /// clipping.
    flat_line_samples: u64,
    clipping: bool,
    last_clip: u64,
    flat: bool,
    flat_since: u64,
    last_count: Option<i32>,
}

impl SensorWatch {
    pub(super) fn new(clip_count: i32, flat_line_samples: u64) -> Self {
        SensorWatch {
            clip_count,
            flat_line_samples,
            clipping: false,
            last_clip: 0,
            flat: false,
            flat_since: 0,
            last_count: None,
        }
    }

    /// After a gap: the next count starts a new flat-line run (no run is bridged over missing
    /// samples).
    pub(super) fn restart(&mut self) {
        self.last_count = None;
    }

    /// Clipping starts at the first count at full scale and ends after a quiet stretch as long
    /// as the flat-line length; a flat line starts once the count has not changed for that
    /// long. Both are judged sample by sample, so block boundaries do not matter. `at` is the
    /// sample index of `counts[0]`.
    pub(super) fn check(
        &mut self,
        at: u64,
        counts: &[i16],
        on_event: &mut impl FnMut(MonitorEvent),
    ) {
        if !self.skim(at, counts) {
            self.check_each(at, counts, on_event);
        }
    }

    /// The usual case, without a branch per sample: neither condition is on, no count reaches
    /// full scale and no run of equal counts reaches the flat-line length, so nothing can start
    /// or end and only the current run has to be followed. Returns false, having changed
    /// nothing, when the counts need [`Self::check_each`].
    fn skim(&mut self, at: u64, counts: &[i16]) -> bool {
        let (Some(&last), Some(previous)) = (counts.last(), self.last_count) else {
            return false;
        };
        let loudest = counts.iter().map(|c| c.unsigned_abs()).max().unwrap_or(0);
        if self.clipping
            || self.flat
            || i32::from(loudest) >= self.clip_count
            || counts.len() as u64 >= self.flat_line_samples
        {
            return false;
        }
        // Shorter than a flat line, the block can only hold one if the run it continues
        // (from `flat_since`) or the run it ends with reaches the length.
        let first_change = counts.iter().position(|&c| i32::from(c) != previous);
        let last_run_from = counts.windows(2).rposition(|w| w[0] != w[1]).map(|i| i + 1);
        let continued_to = at + first_change.unwrap_or(counts.len()) as u64;
        if continued_to.saturating_sub(self.flat_since) >= self.flat_line_samples {
            return false;
        }
        if first_change.is_some() {
            self.flat_since = at + last_run_from.unwrap_or(0).max(first_change.unwrap_or(0)) as u64;
            self.last_count = Some(i32::from(last));
        }
        true
    }

    /// Sample by sample: every start and end at its exact sample.
    fn check_each(&mut self, at: u64, counts: &[i16], on_event: &mut impl FnMut(MonitorEvent)) {
        for (i, &c) in counts.iter().enumerate() {
            let sample = at + i as u64;
            let c = i32::from(c);
            if c.abs() >= self.clip_count {
                self.last_clip = sample;
                if !self.clipping {
                    self.clipping = true;
                    on_event(MonitorEvent::Sensor {
                        condition: SensorCondition::Clipping,
                        active: true,
                        at_sample: sample,
                    });
                }
            } else if self.clipping && sample - self.last_clip >= self.flat_line_samples {
                self.clipping = false;
                on_event(MonitorEvent::Sensor {
                    condition: SensorCondition::Clipping,
                    active: false,
                    at_sample: sample,
                });
            }
            if self.last_count != Some(c) {
                self.flat_since = sample;
                self.last_count = Some(c);
                if self.flat {
                    self.flat = false;
                    on_event(MonitorEvent::Sensor {
                        condition: SensorCondition::FlatLine,
                        active: false,
                        at_sample: sample,
                    });
                }
            } else if !self.flat && sample + 1 - self.flat_since >= self.flat_line_samples {
                self.flat = true;
                on_event(MonitorEvent::Sensor {
                    condition: SensorCondition::FlatLine,
                    active: true,
                    at_sample: sample,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The (condition, active, sample) of every event `counts` raises, fed in blocks of `block`.
    fn events(counts: &[i16], block: usize) -> Vec<(SensorCondition, bool, u64)> {
        let mut watch = SensorWatch::new(32_767, 100);
        let mut seen = Vec::new();
        for (k, chunk) in counts.chunks(block).enumerate() {
            watch.check((k * block) as u64, chunk, &mut |event| {
                if let MonitorEvent::Sensor {
                    condition,
                    active,
                    at_sample,
                } = event
                {
                    seen.push((condition, active, at_sample));
                }
            });
        }
        seen
    }

    /// A changing signal: never flat.
    fn moving(len: usize) -> Vec<i16> {
        (0..len).map(|i| (i % 7) as i16 - 3).collect()
    }

    #[test]
    fn clipping_starts_at_full_scale_and_ends_after_a_quiet_stretch() {
        let mut counts = moving(1_000);
        counts[200] = i16::MAX;
        counts[250] = i16::MIN;
        let want = vec![
            (SensorCondition::Clipping, true, 200),
            // 100 samples after the last clipped count (250).
            (SensorCondition::Clipping, false, 350),
        ];
        assert_eq!(events(&counts, 1_000), want);
    }

    #[test]
    fn a_flat_line_starts_after_its_length_and_ends_at_the_first_change() {
        let mut counts = moving(1_000);
        counts[300..600].fill(5);
        let want = vec![
            // The run starts at 300; its 100th equal count is sample 399.
            (SensorCondition::FlatLine, true, 399),
            (SensorCondition::FlatLine, false, 600),
        ];
        assert_eq!(events(&counts, 1_000), want);
        // One equal count short of the length: nothing.
        let mut short = moving(1_000);
        short[300..399].fill(5);
        assert_eq!(events(&short, 1_000), vec![]);
    }

    #[test]
    fn block_boundaries_do_not_move_an_event() {
        let mut counts = moving(3_000);
        counts[500..900].fill(-2);
        counts[1_200] = i16::MAX;
        counts[2_000..2_150].fill(i16::MAX);
        let whole = events(&counts, counts.len());
        // Flat 599-900, clipping 1200-1300, then a stuck full scale: clipping from 2000 and
        // flat from 2099 to 2150, clipping until 2249.
        let starts: Vec<u64> = whole.iter().map(|e| e.2).collect();
        assert_eq!(
            starts,
            [599, 900, 1200, 1300, 2000, 2099, 2150, 2249],
            "{whole:?}"
        );
        for block in [1, 7, 64, 99, 1_000] {
            assert_eq!(events(&counts, block), whole, "blocks of {block}");
        }
    }

    /// Blocks shorter than a flat line go through [`SensorWatch::skim`]: the events and the
    /// state they leave must be those of the sample-by-sample check.
    #[test]
    fn skimming_a_block_changes_nothing_the_sample_by_sample_check_would_not() {
        // Runs of every length around the flat-line length (100), clipped counts, and noise.
        let mut counts = Vec::new();
        let mut state = 12_345u32;
        for run in (1..=130).chain([99, 100, 101, 250]) {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let value = (state >> 16) as i16 % 50;
            counts.extend(std::iter::repeat_n(value, run));
            if run % 37 == 0 {
                counts.push(i16::MIN);
            }
        }
        let sensor_event = |e: MonitorEvent| match e {
            MonitorEvent::Sensor {
                condition,
                active,
                at_sample,
            } => (condition, active, at_sample),
            _ => unreachable!("the sensor watch reports sensor events only"),
        };
        let mut exact = SensorWatch::new(32_767, 100);
        let mut want = Vec::new();
        exact.check_each(0, &counts, &mut |e| want.push(sensor_event(e)));
        for block in [1, 2, 3, 50, 99] {
            let mut watch = SensorWatch::new(32_767, 100);
            let mut seen = Vec::new();
            for (k, chunk) in counts.chunks(block).enumerate() {
                watch.check((k * block) as u64, chunk, &mut |e| {
                    seen.push(sensor_event(e))
                });
            }
            assert_eq!(seen, want, "blocks of {block}");
            assert_eq!(
                (
                    watch.flat_since,
                    watch.last_count,
                    watch.flat,
                    watch.clipping
                ),
                (
                    exact.flat_since,
                    exact.last_count,
                    exact.flat,
                    exact.clipping
                ),
                "blocks of {block}"
            );
        }
        assert!(
            want.len() > 10,
            "the sequence must start and end both conditions: {want:?}"
        );
    }

    #[test]
    fn a_restart_does_not_bridge_a_flat_run_over_a_gap() {
        let mut watch = SensorWatch::new(32_767, 100);
        let mut seen = 0;
        let mut count_events = |_: MonitorEvent| seen += 1;
        watch.check(0, &[4; 60], &mut count_events);
        watch.restart();
        // 60 + 60 equal counts would make a line if the gap were bridged.
        watch.check(10_000, &[4; 60], &mut count_events);
        assert_eq!(seen, 0);
    }
}
