//! The bearing's health stage (MODELS.md §7, seed 003): a baseline of kurtosis learned from the
//! first windows; the bearing leaves the healthy stage when kurtosis exceeds `μ + 3σ` of that
//! baseline, and enters the failure stage when RMS exceeds `μ + 3σ` of its values at the start
//! of the degradation stage.
//!
//! (choice) A stage change needs `confirm_windows` consecutive windows beyond the limit, so one
//! impulsive window does not move a bearing's life forward; stages only move forward (bearing
//! damage does not heal) until the baseline is deliberately reset. The baseline is plain data
//! ([`Baseline`]) so the daemon can keep it across restarts in its state directory.

use crate::messages::HealthStage;
use serde::{Deserialize, Serialize};

/// Consecutive windows beyond a limit that confirm a change of stage (the daemon's and
/// `bearingd trend`'s).
pub const CONFIRM_WINDOWS: u32 = 3;

/// Mean and standard deviation of a statistic over a number of windows (Welford).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RunningStats {
    pub count: u64,
    pub mean: f64,
    /// Sum of squared deviations.
    pub m2: f64,
}

impl RunningStats {
    pub fn add(&mut self, x: f64) {
        self.count += 1;
        let delta = x - self.mean;
        self.mean += delta / self.count as f64;
        self.m2 += delta * (x - self.mean);
    }

    pub fn std(&self) -> f64 {
        if self.count > 1 {
            (self.m2 / (self.count - 1) as f64).sqrt()
        } else {
            0.0
        }
    }
}

/// What the tracker has learned: persisted by the daemon.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Baseline {
    pub stage: Option<HealthStage>,
    /// Kurtosis over the healthy baseline windows.
    pub kurtosis: RunningStats,
    /// RMS over the first windows of the degradation stage.
    pub aging_rms: RunningStats,
}

/// The baselines of every channel as JSON (a list of `[channel, baseline]` pairs): what
/// `baselines.json` holds and what a log's `bearingd.state` record carries.
pub fn baselines_to_json(
    baselines: &std::collections::BTreeMap<crate::messages::ChannelId, Baseline>,
) -> Result<String, serde_json::Error> {
    let list: Vec<_> = baselines.iter().collect();
    serde_json::to_string_pretty(&list)
}

/// Reads what [`baselines_to_json`] wrote.
pub fn baselines_from_json(
    text: &str,
) -> Result<std::collections::BTreeMap<crate::messages::ChannelId, Baseline>, serde_json::Error> {
    serde_json::from_str::<Vec<(crate::messages::ChannelId, Baseline)>>(text)
        .map(|list| list.into_iter().collect())
}

/// A stage change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageChange {
    pub from: HealthStage,
    pub to: HealthStage,
    pub at_sample: u64,
}

/// Tracks the health stage of one channel.
#[derive(Debug, Clone)]
pub struct HealthTracker {
    baseline_windows: u64,
    sigma: f64,
    confirm_windows: u32,
    baseline: Baseline,
    beyond: u32,
}

impl HealthTracker {
    pub fn new(
        baseline_windows: u64,
        sigma: f64,
        confirm_windows: u32,
        stored: Option<Baseline>,
    ) -> Self {
        HealthTracker {
            baseline_windows: baseline_windows.max(2),
            sigma,
            confirm_windows: confirm_windows.max(1),
            baseline: stored.unwrap_or_default(),
            beyond: 0,
        }
    }

    pub fn stage(&self) -> HealthStage {
        self.baseline.stage.unwrap_or(HealthStage::Learning)
    }

    pub fn baseline(&self) -> &Baseline {
        &self.baseline
    }

    /// The kurtosis above which the healthy stage is left, once the baseline is learned.
    pub fn healthy_limit(&self) -> Option<f64> {
        self.limit_of(&self.baseline.kurtosis)
    }

    /// The RMS above which the failure stage is entered, once the aging baseline (the first
    /// windows of the degradation stage) is learned.
    pub fn failure_limit(&self) -> Option<f64> {
        self.limit_of(&self.baseline.aging_rms)
    }

    fn limit_of(&self, stats: &RunningStats) -> Option<f64> {
        (stats.count >= self.baseline_windows).then(|| stats.mean + self.sigma * stats.std())
    }

    /// Feeds one window's kurtosis and RMS.
    pub fn update(&mut self, kurtosis: f64, rms: f64, end_sample: u64) -> Option<StageChange> {
        if !(kurtosis.is_finite() && rms.is_finite()) {
            return None;
        }
        let stage = self.stage();
        let next = match stage {
            HealthStage::Learning => {
                self.baseline.kurtosis.add(kurtosis);
                (self.baseline.kurtosis.count >= self.baseline_windows)
                    .then_some(HealthStage::Healthy)
            }
            HealthStage::Healthy => {
                let limit = self.baseline.kurtosis.mean + self.sigma * self.baseline.kurtosis.std();
                self.confirmed(kurtosis > limit)
                    .then_some(HealthStage::Degrading)
            }
            HealthStage::Degrading => match self.failure_limit() {
                None => {
                    self.baseline.aging_rms.add(rms);
                    None
                }
                Some(limit) => self.confirmed(rms > limit).then_some(HealthStage::Failing),
            },
            HealthStage::Failing => None,
        };
        next.map(|to| {
            self.baseline.stage = Some(to);
            self.beyond = 0;
            StageChange {
                from: stage,
                to,
                at_sample: end_sample,
            }
        })
    }

    fn confirmed(&mut self, beyond: bool) -> bool {
        self.beyond = if beyond { self.beyond + 1 } else { 0 };
        self.beyond >= self.confirm_windows
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn learns_then_degrades_then_fails() {
        let mut tracker = HealthTracker::new(20, 3.0, 3, None);
        let mut changes = Vec::new();
        let mut sample = 0;
        let mut feed = |tracker: &mut HealthTracker,
                        k: f64,
                        r: f64,
                        n: usize,
                        changes: &mut Vec<StageChange>| {
            for i in 0..n {
                sample += 100;
                let wobble = if i % 2 == 0 { 0.05 } else { -0.05 };
                changes.extend(tracker.update(k + wobble, r + wobble * 0.01, sample));
            }
        };
        feed(&mut tracker, 3.0, 0.1, 20, &mut changes);
        assert_eq!(tracker.stage(), HealthStage::Healthy);
        feed(&mut tracker, 3.0, 0.1, 50, &mut changes);
        assert_eq!(
            tracker.stage(),
            HealthStage::Healthy,
            "normal wobble keeps it healthy"
        );
        feed(&mut tracker, 8.0, 0.12, 2, &mut changes);
        assert_eq!(
            tracker.stage(),
            HealthStage::Healthy,
            "two windows are not enough"
        );
        feed(&mut tracker, 8.0, 0.12, 3, &mut changes);
        assert_eq!(tracker.stage(), HealthStage::Degrading);
        feed(&mut tracker, 8.0, 0.12, 25, &mut changes);
        feed(&mut tracker, 8.0, 0.5, 3, &mut changes);
        assert_eq!(tracker.stage(), HealthStage::Failing);
        let stages: Vec<_> = changes.iter().map(|c| c.to).collect();
        assert_eq!(
            stages,
            [
                HealthStage::Healthy,
                HealthStage::Degrading,
                HealthStage::Failing
            ]
        );
    }

    #[test]
    fn a_stored_baseline_resumes_where_it_was() {
        let mut first = HealthTracker::new(5, 3.0, 1, None);
        for i in 0u32..5 {
            first.update(3.0 + 0.1 * f64::from(i), 0.1, u64::from(i));
        }
        let stored = serde_json::to_string(first.baseline()).unwrap();
        let restored = HealthTracker::new(5, 3.0, 1, Some(serde_json::from_str(&stored).unwrap()));
        assert_eq!(restored.stage(), HealthStage::Healthy);
        assert_eq!(restored.baseline(), first.baseline());
    }
}
