//! A bearing's life from a series of snapshots in time order (`bearingd trend`): per snapshot
//! the indicators (RMS, kurtosis), the Hammerstein–Wiener model's residual (seed 003) and the
//! envelope fault score; the daemon's own [`HealthTracker`] turning them into stages (healthy →
//! degrading → failing); and a trend of RMS with the time it will take to reach the failure
//! limit ([`crate::analysis::degradation`]).
//!
//! Why a separate driver and not the daemon's [`crate::analysis::monitor::ChannelMonitor`]: run-to-failure
//! data comes as short snapshots far apart (PRONOSTIA: 0.1 s every 10 s), not as a continuous
//! stream, so one snapshot is one window of the tracker. The tracker is the same type with the
//! same 3σ rule and the same confirmation count as the daemon's; what differs, and why, is
//! documented in docs/HEALTH.md:
//!
//! - (choice) The baseline is the first `baseline_snapshots` snapshots (15 by default: early
//!   life, not the daemon's 30 one-second windows, which would be a third to half of a sparse
//!   PRONOSTIA life).
//! - (choice) The tracker sees the running median of the last `smoothing` snapshots' kurtosis
//!   and RMS (3 by default): a 0.1 s snapshot holding one rig transient has a kurtosis of 40–400
//!   (PRONOSTIA Bearing1_2 at 7 %, 14 %, 28 % of its life), where a 1 s window of the daemon
//!   dilutes it; the median drops such lone snapshots before the 3σ rule sees them.
//!
//! Sans-IO: the caller reads the files and says when each snapshot was taken.

use crate::analysis::degradation::{TrendFit, HORIZON_SPANS};
use crate::analysis::health::{HealthTracker, CONFIRM_WINDOWS};
use crate::analysis::indicators::Indicators;
use crate::analysis::record::RecordAnalyzer;
use crate::analysis::AnalysisSettings;
use crate::bearing::FaultFrequencies;
use crate::messages::{FaultKind, HealthStage};
use crate::twin::hw::{identify_record, HwConfig};
use serde::Serialize;
use std::collections::VecDeque;

/// How the life is tracked.
#[derive(Debug, Clone, PartialEq)]
pub struct LifeSettings {
    /// Snapshots that form the healthy baseline (and, at the start of degradation, the aging
    /// baseline of RMS).
    pub baseline_snapshots: u64,
    /// Standard deviations above a baseline that mark a change of stage (the daemon's 3).
    pub sigma: f64,
    /// Running median over this many snapshots before the tracker; 1 feeds them as they are.
    pub smoothing: usize,
    /// Snapshots in the sliding window of the RMS trend.
    pub trend_window: usize,
    /// Two-sided coverage of the trend's band.
    pub confidence: f64,
    /// RMS threshold (g) for the time-to-threshold; `None`: the tracker's failure limit, once
    /// it is known.
    pub threshold_rms: Option<f64>,
    /// The HW model whose simulation residual is tracked; `None` skips it.
    pub hw: Option<HwConfig>,
    /// Settings of the envelope analysis behind the fault score.
    pub analysis: AnalysisSettings,
}

impl Default for LifeSettings {
    fn default() -> Self {
        LifeSettings {
            baseline_snapshots: 15,
            sigma: 3.0,
            smoothing: 3,
            trend_window: 12,
            confidence: 0.9,
            threshold_rms: None,
            hw: Some(HwConfig::default()),
            analysis: AnalysisSettings::default(),
        }
    }
}

/// Fewest samples a snapshot must have.
pub const MIN_SNAPSHOT_SAMPLES: usize = 256;

/// One snapshot's place in the life.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LifePoint {
    /// Where it came from (a file name, or a file name and a window).
    pub source: String,
    /// Seconds since the first snapshot.
    pub time_s: f64,
    pub rms: f64,
    pub kurtosis: f64,
    /// What the tracker saw (the running medians).
    pub rms_tracked: f64,
    pub kurtosis_tracked: f64,
    /// `100·NRMSE` (%) of the HW model's free run on this snapshot; `None` if not identified.
    pub hw_residual_percent: Option<f64>,
    /// Where the HW residual came from: `fit` (identified here) or `log` (the fit the daemon
    /// logged in this snapshot's span); `None` without one.
    pub hw_from: Option<HwFrom>,
    /// The strongest envelope fault score and its fault; `None` without a shaft speed.
    pub fault_score: Option<f64>,
    pub fault: Option<FaultKind>,
    /// The stage after this snapshot.
    pub stage: HealthStage,
    /// The kurtosis limit of the healthy stage, once learned.
    pub kurtosis_limit: Option<f64>,
    /// The RMS limit of the failure stage, once learned.
    pub rms_limit: Option<f64>,
    /// The RMS trend and its time-to-threshold, once there is a threshold and (for the
    /// failure limit) the bearing is degrading.
    pub trend: Option<TrendFit>,
}

/// Where a snapshot's HW residual comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HwFrom {
    /// Identified on the snapshot by [`LifeTracker`].
    Fit,
    /// The daemon's own fit, logged on `/hw/<sensor>/<axis>` in the snapshot's span.
    Log,
}

/// The HW residual of one snapshot: identified here, or what the daemon logged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SnapshotHw {
    /// Identify the model on the snapshot (when the settings ask for one).
    Identify,
    /// The residual (%) of the daemon's fit in the snapshot's span; `None`: no fit there
    /// (the daemon fits once per twin re-fit, every `twin.refit_period_s`).
    Logged(Option<f64>),
}

/// A change of stage, placed in the life.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageEvent {
    pub from: HealthStage,
    pub to: HealthStage,
    pub time_s: f64,
    /// Index of the snapshot in the series.
    pub snapshot: usize,
    pub source: String,
}

/// Why a snapshot could not be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LifeError {
    #[error("{file}: {got} samples; a snapshot needs at least {MIN_SNAPSHOT_SAMPLES}")]
    TooShort { file: String, got: usize },
    #[error("{file}: taken at {time_s} s, before the previous snapshot ({previous_s} s); snapshots must come in time order")]
    OutOfOrder {
        file: String,
        time_s: f64,
        previous_s: f64,
    },
}

/// Follows one bearing through its snapshots.
pub struct LifeTracker {
    settings: LifeSettings,
    health: HealthTracker,
    recent_kurtosis: VecDeque<f64>,
    recent_rms: VecDeque<f64>,
    analyzer: RecordAnalyzer,
    times: Vec<f64>,
    rms: Vec<f64>,
    events: Vec<StageEvent>,
}

impl LifeTracker {
    pub fn new(settings: LifeSettings) -> Self {
        LifeTracker {
            health: HealthTracker::new(
                settings.baseline_snapshots,
                settings.sigma,
                CONFIRM_WINDOWS,
                None,
            ),
            settings,
            recent_kurtosis: VecDeque::new(),
            recent_rms: VecDeque::new(),
            analyzer: RecordAnalyzer::default(),
            times: Vec::new(),
            rms: Vec::new(),
            events: Vec::new(),
        }
    }

    /// The stage changes so far.
    pub fn events(&self) -> &[StageEvent] {
        &self.events
    }

    pub fn stage(&self) -> HealthStage {
        self.health.stage()
    }

    /// Takes the next snapshot: `samples` (g) at `fs_hz`, taken `time_s` after the first;
    /// `freqs` (the fault frequencies at the shaft speed) when the speed is known. The HW model
    /// is identified on it when the settings ask for one.
    pub fn push(
        &mut self,
        source: &str,
        time_s: f64,
        samples: &[f64],
        fs_hz: f64,
        freqs: Option<&FaultFrequencies>,
    ) -> Result<LifePoint, LifeError> {
        self.push_with_hw(source, time_s, samples, fs_hz, freqs, SnapshotHw::Identify)
    }

    /// [`LifeTracker::push`] with the HW residual given (`hw`): a daemon log's own fits are
    /// used as they are instead of identifying the model again (0.8 s of CPU per 1 s window).
    pub fn push_with_hw(
        &mut self,
        source: &str,
        time_s: f64,
        samples: &[f64],
        fs_hz: f64,
        freqs: Option<&FaultFrequencies>,
        hw: SnapshotHw,
    ) -> Result<LifePoint, LifeError> {
        if samples.len() < MIN_SNAPSHOT_SAMPLES {
            return Err(LifeError::TooShort {
                file: source.into(),
                got: samples.len(),
            });
        }
        if let Some(&previous_s) = self.times.last() {
            if time_s < previous_s || !time_s.is_finite() {
                return Err(LifeError::OutOfOrder {
                    file: source.into(),
                    time_s,
                    previous_s,
                });
            }
        }
        let signal: Vec<f32> = samples.iter().map(|&x| x as f32).collect();
        let indicators = Indicators::of_slices(&[&signal]);
        let rms_tracked = push_median(
            &mut self.recent_rms,
            indicators.rms,
            self.settings.smoothing,
        );
        let kurtosis_tracked = push_median(
            &mut self.recent_kurtosis,
            indicators.kurtosis,
            self.settings.smoothing,
        );
        let snapshot = self.times.len();
        if let Some(change) = self
            .health
            .update(kurtosis_tracked, rms_tracked, snapshot as u64)
        {
            self.events.push(StageEvent {
                from: change.from,
                to: change.to,
                time_s,
                snapshot,
                source: source.into(),
            });
        }
        self.times.push(time_s);
        self.rms.push(indicators.rms);

        let (hw_residual_percent, hw_from) = match hw {
            SnapshotHw::Logged(residual) => (residual, residual.map(|_| HwFrom::Log)),
            SnapshotHw::Identify => {
                let residual = self.settings.hw.as_ref().and_then(|config| {
                    identify_record(samples, fs_hz, config, None)
                        .ok()
                        .map(|fit| 100.0 - fit.accuracy.simulation)
                });
                (residual, residual.map(|_| HwFrom::Fit))
            }
        };
        let strongest = freqs.and_then(|freqs| {
            let analysis = self
                .analyzer
                .analyze(&signal, fs_hz, freqs, &self.settings.analysis)
                .ok()?;
            analysis
                .hypotheses
                .iter()
                .map(|h| (h.score.fault, h.score.score))
                .max_by(|a, b| a.1.total_cmp(&b.1))
        });

        let stage = self.health.stage();
        let kurtosis_limit = (stage != HealthStage::Learning)
            .then(|| self.health.healthy_limit())
            .flatten();
        let rms_limit = self.health.failure_limit();
        let threshold = match self.settings.threshold_rms {
            Some(given) => Some(given),
            None if stage >= HealthStage::Degrading => rms_limit,
            None => None,
        };
        let trend = threshold.and_then(|threshold| {
            let from = self.times.len().saturating_sub(self.settings.trend_window);
            TrendFit::fit(
                &self.times[from..],
                &self.rms[from..],
                threshold,
                self.settings.confidence,
                HORIZON_SPANS,
            )
        });
        Ok(LifePoint {
            source: source.into(),
            time_s,
            rms: indicators.rms,
            kurtosis: indicators.kurtosis,
            rms_tracked,
            kurtosis_tracked,
            hw_residual_percent,
            hw_from,
            fault_score: strongest.map(|s| s.1),
            fault: strongest.map(|s| s.0),
            stage,
            kurtosis_limit,
            rms_limit,
            trend,
        })
    }
}

/// Appends `x` to the last `len` values and returns their median.
fn push_median(recent: &mut VecDeque<f64>, x: f64, len: usize) -> f64 {
    recent.push_back(x);
    while recent.len() > len.max(1) {
        recent.pop_front();
    }
    let mut sorted: Vec<f64> = recent.iter().copied().collect();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    if sorted.len() % 2 == 1 {
        sorted[mid]
    } else {
        0.5 * (sorted[mid - 1] + sorted[mid])
    }
}

/// How the trend's time-to-threshold compared with what happened, judged after the fact.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrendHindsight {
    pub threshold: f64,
    /// When RMS really crossed the threshold: the first snapshot of the first run of
    /// [`CONFIRM_WINDOWS`] snapshots above it (s).
    pub crossed_s: f64,
    /// Estimates made before the crossing.
    pub estimates: usize,
    /// The first estimate that predicted a crossing: how long before the real one it was made
    /// and how far off it was (predicted − real, s).
    pub first_lead_s: Option<f64>,
    pub first_error_s: Option<f64>,
    /// The first estimate whose band held the real crossing: its lead (s).
    pub first_in_band_lead_s: Option<f64>,
    /// The last estimate before the crossing: lead and error (s).
    pub last_lead_s: Option<f64>,
    pub last_error_s: Option<f64>,
    /// Median of |predicted − real| over the estimates that predicted a crossing (s).
    pub median_abs_error_s: Option<f64>,
    /// Estimates that predicted a crossing within the horizon.
    pub predicted: usize,
}

/// Compares each trend estimate made before RMS crossed its threshold with the crossing
/// itself; `None` if the threshold was never set or never crossed.
pub fn hindsight(points: &[LifePoint]) -> Option<TrendHindsight> {
    let threshold = points.iter().find_map(|p| p.trend.map(|t| t.threshold))?;
    let confirm = CONFIRM_WINDOWS as usize;
    let start = points.iter().position(|p| p.trend.is_some())?;
    let crossed_at = (start..points.len()).find(|&i| {
        i + confirm <= points.len() && points[i..i + confirm].iter().all(|p| p.rms > threshold)
    })?;
    let crossed_s = points[crossed_at].time_s;
    // (made at, predicted crossing, band) of each estimate before the crossing.
    type Estimate = (f64, Option<f64>, Option<(f64, f64)>);
    let before: Vec<Estimate> = points[..crossed_at]
        .iter()
        .filter_map(|p| {
            let t = p.trend.filter(|t| t.threshold == threshold)?;
            let band = t.earliest_s.zip(t.latest_s);
            Some((p.time_s, t.crossing_s, band))
        })
        .collect();
    let predicted: Vec<(f64, f64)> = before
        .iter()
        .filter_map(|&(at, crossing, _)| crossing.map(|c| (at, c - crossed_s)))
        .collect();
    let mut abs_errors: Vec<f64> = predicted.iter().map(|p| p.1.abs()).collect();
    abs_errors.sort_by(f64::total_cmp);
    Some(TrendHindsight {
        threshold,
        crossed_s,
        estimates: before.len(),
        first_lead_s: predicted.first().map(|p| crossed_s - p.0),
        first_error_s: predicted.first().map(|p| p.1),
        first_in_band_lead_s: before
            .iter()
            .find(|(_, _, band)| band.is_some_and(|(lo, hi)| (lo..=hi).contains(&crossed_s)))
            .map(|b| crossed_s - b.0),
        last_lead_s: predicted.last().map(|p| crossed_s - p.0),
        last_error_s: predicted.last().map(|p| p.1),
        median_abs_error_s: abs_errors.get(abs_errors.len() / 2).copied(),
        predicted: predicted.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Rng;

    fn noise(rng: &mut Rng, rms: f64, impulses: usize) -> Vec<f64> {
        let mut x: Vec<f64> = (0..2560).map(|_| rms * rng.normal()).collect();
        for k in 0..impulses {
            x[100 + k * 200] += 12.0 * rms;
        }
        x
    }

    #[test]
    fn a_synthetic_life_goes_healthy_degrading_failing() {
        let settings = LifeSettings {
            hw: None,
            ..LifeSettings::default()
        };
        let mut life = LifeTracker::new(settings);
        let mut rng = Rng::new(7);
        let mut stages = Vec::new();
        for i in 0..120 {
            let (rms, impulses) = match i {
                0..=59 => (0.3, 0),
                60..=99 => (0.3, 8),
                _ => (0.3 * (1.0 + f64::from(i - 99)), 8),
            };
            // One lone rig transient in healthy life must not move the stage.
            let impulses = if i == 30 { 12 } else { impulses };
            let point = life
                .push(
                    &format!("s{i}"),
                    f64::from(i) * 10.0,
                    &noise(&mut rng, rms, impulses),
                    25_600.0,
                    None,
                )
                .unwrap();
            stages.push(point.stage);
        }
        let events: Vec<_> = life.events().iter().map(|e| (e.to, e.snapshot)).collect();
        assert_eq!(events[0], (HealthStage::Healthy, 14));
        assert_eq!(events[1].0, HealthStage::Degrading);
        assert!((60..66).contains(&events[1].1), "{events:?}");
        assert_eq!(events[2].0, HealthStage::Failing);
        assert!((100..106).contains(&events[2].1), "{events:?}");
    }

    #[test]
    fn short_and_out_of_order_snapshots_are_refused() {
        let mut life = LifeTracker::new(LifeSettings::default());
        assert!(matches!(
            life.push("a", 0.0, &[0.0; 10], 25_600.0, None),
            Err(LifeError::TooShort { .. })
        ));
        let mut rng = Rng::new(1);
        life.push("b", 10.0, &noise(&mut rng, 0.3, 0), 25_600.0, None)
            .unwrap();
        assert!(matches!(
            life.push("c", 5.0, &noise(&mut rng, 0.3, 0), 25_600.0, None),
            Err(LifeError::OutOfOrder { .. })
        ));
    }

    #[test]
    fn running_median() {
        let mut recent = VecDeque::new();
        assert_eq!(push_median(&mut recent, 1.0, 3), 1.0);
        assert_eq!(push_median(&mut recent, 100.0, 3), 50.5);
        assert_eq!(push_median(&mut recent, 2.0, 3), 2.0);
        assert_eq!(push_median(&mut recent, 3.0, 3), 3.0);
        assert_eq!(push_median(&mut recent, 7.0, 1), 7.0);
    }
}
