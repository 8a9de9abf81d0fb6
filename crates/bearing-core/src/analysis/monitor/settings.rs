//! What a channel monitor is given: everything it needs, with durations already in samples.

use crate::analysis::detectors::DetectorSettings;
use crate::analysis::flags::FlagSettings;
use crate::analysis::speed::SpeedMode;
use crate::analysis::AnalysisSettings;

/// Everything a monitor needs, with durations already in samples.
#[derive(Debug, Clone)]
pub struct MonitorSettings {
    pub fs_hz: f64,
    pub analysis: AnalysisSettings,
    pub band_period_samples: u64,
    /// Extra delay of the second band selection (the first is as soon as the history is
    /// full), so that the channels of one daemon take turns instead of all selecting at the
    /// same sample time: each selection holds the analysis thread for tens of ms, and a burst
    /// over all channels delays every block (and alert) behind it. 0 for a lone channel.
    pub band_phase_samples: u64,
    /// This channel's share of a hop, `(k, n)` for the k-th of n channels: its windows end
    /// k/n of a hop later than the first channel's, so that the daemon's channels do not all
    /// close a window (envelope spectra, scores, flags, velocity) on the same block, each
    /// waiting behind the others; a window's alert then waits for one channel's work, not
    /// all. `(0, 1)` for a lone channel.
    pub window_stagger: (usize, usize),
    pub band_history_samples: usize,
    pub flags: FlagSettings,
    pub baseline_windows: u64,
    pub sigma: f64,
    /// A count whose magnitude reaches this is clipped (i16 full scale: 32767).
    pub clip_count: i32,
    /// Samples without any change that make a flat line.
    pub flat_line_samples: u64,
    /// Where the shaft speed comes from.
    pub speed: SpeedMode,
    /// The detectors run besides the fault scores (the velocity zones, …).
    pub detectors: DetectorSettings,
    /// The RMS trend published with the health stage.
    pub trend: TrendSettings,
}

/// How the RMS trend is made ([`crate::analysis::degradation::RmsTrend`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrendSettings {
    /// Sample time per point (the median of its windows' RMS).
    pub point_s: f64,
    /// Points fitted (the newest).
    pub points: usize,
    /// Two-sided coverage of the band around the fit.
    pub confidence: f64,
}

impl Default for TrendSettings {
    /// A point a minute, the last 30 fitted, a 90 % band (`bearingd trend`'s coverage).
    fn default() -> Self {
        TrendSettings {
            point_s: 60.0,
            points: 30,
            confidence: 0.9,
        }
    }
}
