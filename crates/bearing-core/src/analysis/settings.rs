//! Settings of the analysis core, already validated. The config module builds them from TOML,
//! `analyze` from its command line; the core never parses text itself.

use super::agreement::Agreement;
use serde::{Deserialize, Serialize};

/// How the resonance band for envelope analysis is chosen (MODELS.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "method")]
pub enum BandSelection {
    /// The band of highest spectral kurtosis in the fast kurtogram.
    Kurtogram,
    /// The band of highest GK index (Gini index times kurtosis, seed 001).
    GiniKurtosis,
    /// A fixed band, in Hz.
    Fixed { lo_hz: f64, hi_hz: f64 },
}

/// Everything the analysis core needs besides the samples, the sample rate and the bearing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnalysisSettings {
    /// Length of one envelope-spectrum window, in seconds; rounded up to a power of two samples.
    pub window_s: f64,
    /// Overlap of successive windows, as a fraction of the window (0.5 = Welch's 50 %).
    pub overlap: f64,
    /// Rolling form: how many window spectra are averaged.
    pub averages: usize,
    /// How the resonance band is chosen.
    pub band_selection: BandSelection,
    /// Where a fault hypothesis exists, pick per hypothesis the candidate band whose envelope
    /// spectrum shows that fault's harmonics best (fault-band signal-to-noise ratio).
    pub refine_band_by_snr: bool,
    /// Narrowest band the kurtogram may choose, in Hz. `None`: what the comb needs, the
    /// highest fault frequency's last harmonic and its upper sideband (a narrower band cuts
    /// the evidence away before it is scored).
    pub min_band_hz: Option<f64>,
    /// Relative search tolerance around each fault frequency (slip), e.g. 0.02 = ±2 %.
    pub fault_tolerance: f64,
    /// Harmonics of each fault frequency that count in its score.
    pub harmonics: usize,
    /// A fault is named only if noise alone would give its comb with at most this
    /// probability (per hypothesis and decision: per record, or per window in the daemon)...
    pub false_alarm_rate: f64,
    /// ...its score (geometric-mean peak-to-floor ratio over the comb) reaches this value...
    pub min_fault_score: f64,
    /// ...and it is this many times stronger than any other detected hypothesis once it is
    /// explained away; otherwise the diagnosis is `none` (with both named).
    pub min_score_ratio: f64,
    /// A weaker comb is named when it stands alone: score ≥ this...
    pub lone_fault_score: f64,
    /// ...this many times every other hypothesis once it is explained away, and significant
    /// at `false_alarm_rate²`.
    pub lone_score_ratio: f64,
    /// How much less evidence a first-ranked fault needs when the learned model names it too
    /// ([`super::agreement::decide`]). `None`, the default, is off (its parameters are not
    /// calibrated yet); logs written before it existed read as off.
    #[serde(default)]
    pub agreement: Option<Agreement>,
}

impl AnalysisSettings {
    /// The decision rule these settings give.
    pub fn decision_rule(&self) -> super::diagnosis::DecisionRule {
        super::diagnosis::DecisionRule {
            false_alarm_rate: self.false_alarm_rate,
            min_fault_score: self.min_fault_score,
            min_score_ratio: self.min_score_ratio,
            lone_fault_score: self.lone_fault_score,
            lone_score_ratio: self.lone_score_ratio,
        }
    }
}

impl Default for AnalysisSettings {
    fn default() -> Self {
        AnalysisSettings {
            window_s: 1.0,
            overlap: 0.5,
            averages: 8,
            band_selection: BandSelection::GiniKurtosis,
            refine_band_by_snr: true,
            min_band_hz: None,
            fault_tolerance: 0.02,
            harmonics: 5,
            false_alarm_rate: 1e-3,
            min_fault_score: 5.0,
            min_score_ratio: 1.5,
            lone_fault_score: 2.5,
            lone_score_ratio: 2.0,
            agreement: None,
        }
    }
}
