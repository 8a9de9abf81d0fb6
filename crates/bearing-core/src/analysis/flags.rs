//! Fault flags: `ok | watch | alarm` per fault kind, with hysteresis and on/off delays counted
//! in samples (sample time, so a replay raises the same flags at the same samples).
//!
//! A flag rises to a level once its score has stayed at or above that level's threshold for
//! `on_delay` samples, and falls once the score has stayed below `clear_ratio ×` the threshold
//! of its current level for `off_delay` samples. Scores between the two thresholds change
//! nothing: that band is the hysteresis that keeps a flag from chattering around a threshold.

use crate::messages::FlagLevel;
use serde::Serialize;

/// Thresholds and delays of a flag, delays already in samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FlagSettings {
    pub watch_score: f64,
    pub alarm_score: f64,
    pub clear_ratio: f64,
    pub on_delay_samples: u64,
    pub off_delay_samples: u64,
}

/// A change of level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlagChange {
    pub from: FlagLevel,
    pub to: FlagLevel,
    pub at_sample: u64,
}

/// One fault's flag.
#[derive(Debug, Clone)]
pub struct FaultFlag {
    settings: FlagSettings,
    level: FlagLevel,
    /// Where the score started to ask for a level other than the current one, and which.
    pending: Option<(FlagLevel, u64)>,
    /// The sample of the last change of level (0 before any).
    changed_at: u64,
}

impl FaultFlag {
    pub fn new(settings: FlagSettings) -> Self {
        FaultFlag {
            settings,
            level: FlagLevel::Ok,
            pending: None,
            changed_at: 0,
        }
    }

    pub fn level(&self) -> FlagLevel {
        self.level
    }

    pub fn settings(&self) -> &FlagSettings {
        &self.settings
    }

    fn threshold(&self, level: FlagLevel) -> f64 {
        match level {
            FlagLevel::Ok => 0.0,
            FlagLevel::Watch => self.settings.watch_score,
            FlagLevel::Alarm => self.settings.alarm_score,
        }
    }

    /// The level the score asks for, given the current level (hysteresis).
    fn wanted(&self, score: f64) -> FlagLevel {
        let raise_to = if score >= self.settings.alarm_score {
            FlagLevel::Alarm
        } else if score >= self.settings.watch_score {
            FlagLevel::Watch
        } else {
            FlagLevel::Ok
        };
        if raise_to >= self.level {
            return raise_to;
        }
        // Falling: only below clear_ratio × the current level's threshold, and then to the
        // highest level whose own clear threshold the score still reaches.
        let clear = |level: FlagLevel| self.settings.clear_ratio * self.threshold(level);
        if score >= clear(self.level) {
            self.level
        } else if self.level == FlagLevel::Alarm && score >= clear(FlagLevel::Watch) {
            FlagLevel::Watch
        } else {
            FlagLevel::Ok
        }
    }

    /// Feeds the score of the window ending at `end_sample`; returns a change of level, if any.
    pub fn update(&mut self, score: f64, end_sample: u64) -> Option<FlagChange> {
        self.update_over(score, end_sample, end_sample)
    }

    /// Feeds a score that rests on the evidence from `from_sample` to `end_sample` (a whole
    /// stretch of signal analysed at once): a level it asks for anew counts as asked since
    /// `from_sample`, though not from before the flag's last change, so the on- and off-delays
    /// are met when that evidence spans them.
    pub fn update_over(
        &mut self,
        score: f64,
        from_sample: u64,
        end_sample: u64,
    ) -> Option<FlagChange> {
        let wanted = self.wanted(score);
        if wanted == self.level {
            self.pending = None;
            return None;
        }
        // The same wish keeps its start; so does a rise that turns into a higher rise (a
        // fast-growing fault is not delayed twice); anything else starts its delay now.
        let since = match self.pending {
            Some((level, since))
                if level == wanted || (level > self.level && wanted > self.level) =>
            {
                since
            }
            _ => from_sample.max(self.changed_at).min(end_sample),
        };
        self.pending = Some((wanted, since));
        let delay = if wanted > self.level {
            self.settings.on_delay_samples
        } else {
            self.settings.off_delay_samples
        };
        if end_sample.saturating_sub(since) >= delay {
            let change = FlagChange {
                from: self.level,
                to: wanted,
                at_sample: end_sample,
            };
            self.level = wanted;
            self.pending = None;
            self.changed_at = end_sample;
            return Some(change);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> FlagSettings {
        FlagSettings {
            watch_score: 10.0,
            alarm_score: 15.0,
            clear_ratio: 0.8,
            on_delay_samples: 100,
            off_delay_samples: 300,
        }
    }

    #[test]
    fn rises_after_the_on_delay_and_not_before() {
        let mut flag = FaultFlag::new(settings());
        assert_eq!(flag.update(20.0, 1_000), None);
        assert_eq!(flag.update(20.0, 1_050), None);
        let change = flag.update(20.0, 1_100).unwrap();
        assert_eq!(
            (change.from, change.to, change.at_sample),
            (FlagLevel::Ok, FlagLevel::Alarm, 1_100)
        );
    }

    #[test]
    fn a_short_spike_raises_nothing() {
        let mut flag = FaultFlag::new(settings());
        assert_eq!(flag.update(50.0, 0), None);
        assert_eq!(flag.update(3.0, 50), None);
        assert_eq!(flag.update(50.0, 120), None);
        assert_eq!(flag.level(), FlagLevel::Ok);
    }

    #[test]
    fn hysteresis_holds_between_clear_and_raise_thresholds() {
        let mut flag = FaultFlag::new(settings());
        flag.update(12.0, 0);
        flag.update(12.0, 100);
        assert_eq!(flag.level(), FlagLevel::Watch);
        // 8.5 is below watch (10) but above 0.8 × 10: stays watch however long.
        for t in (200..5_000).step_by(100) {
            assert_eq!(flag.update(8.5, t), None);
        }
        assert_eq!(flag.update(7.0, 5_000), None);
        assert_eq!(flag.update(7.0, 5_200), None);
        assert_eq!(flag.update(7.0, 5_300).map(|c| c.to), Some(FlagLevel::Ok));
    }

    #[test]
    fn alarm_falls_to_watch_then_ok() {
        let mut flag = FaultFlag::new(settings());
        flag.update(30.0, 0);
        flag.update(30.0, 100);
        assert_eq!(flag.level(), FlagLevel::Alarm);
        flag.update(11.0, 200);
        assert_eq!(flag.update(11.0, 500).map(|c| c.to), Some(FlagLevel::Watch));
        flag.update(1.0, 600);
        assert_eq!(flag.update(1.0, 900).map(|c| c.to), Some(FlagLevel::Ok));
    }

    #[test]
    fn evidence_over_a_stretch_counts_from_its_start_but_not_before_the_last_change() {
        let mut flag = FaultFlag::new(settings());
        // Evidence over samples 0..150 asks for alarm: it spans the 100-sample on-delay.
        let change = flag.update_over(20.0, 0, 150).unwrap();
        assert_eq!((change.to, change.at_sample), (FlagLevel::Alarm, 150));
        // Evidence over 0..400 says nothing is there: asked since the change at 150, 250 < 300.
        assert_eq!(flag.update_over(0.0, 0, 400), None);
        assert_eq!(
            flag.update_over(0.0, 100, 450).map(|c| c.to),
            Some(FlagLevel::Ok)
        );
    }
}
