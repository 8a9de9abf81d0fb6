//! Whole-record analysis, as `bearingd analyze` runs it: indicators, the band scan, band
//! selection, per-hypothesis band choice, fault scores and the verdict.
//!
//! Each hypothesis is scored in every candidate band wide enough to hold its comb (the full
//! band always among them) and keeps the band where its evidence against noise is strongest;
//! its significance then pays for that search ([`super::band_search`]). Band selection can
//! thereby only add evidence, never cut it away.

use super::agreement::{decide, WitnessOpinion};
use super::band::{comb_width_hz, envelope_range_hz, Band};
use super::band_search::{candidate_bands, search_significance};
use super::diagnosis::{diagnose, leader, Diagnosis};
use super::envelope::{window_samples, EnvelopeSpectrum, FftPlans};
use super::fault_bands::{FaultScore, FaultScorer};
use super::indicators::Indicators;
use super::kurtogram::{band_tree, scan_bands, BandScan, TreeLevel};
use super::settings::{AnalysisSettings, BandSelection};
use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;

/// Why a record could not be analysed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnalysisError {
    #[error("the record has {samples} samples ({seconds:.3} s) but one analysis window needs {window} ({window_s:.3} s at {fs_hz} Hz); give a longer record or a shorter window")]
    TooShort {
        samples: usize,
        seconds: f64,
        window: usize,
        window_s: f64,
        fs_hz: f64,
    },
    #[error("sample rate {0} Hz is not usable; give the rate in Hz, e.g. --fs 12000")]
    BadSampleRate(f64),
    #[error("shaft speed {0} Hz is not usable; give the speed, e.g. --rpm 1797")]
    BadSpeed(f64),
    #[error("{what} at {freq_hz:.1} Hz lies above the Nyquist frequency {nyquist:.0} Hz of this record; check --fs and --rpm")]
    AboveNyquist {
        what: String,
        freq_hz: f64,
        nyquist: f64,
    },
}

/// The band chosen for one fault hypothesis and the score it gives.
#[derive(Debug, Clone)]
pub struct Hypothesis {
    pub score: FaultScore,
    /// Index into [`RecordAnalysis::scan`]`.bands`.
    pub band_index: usize,
    /// The chosen band's own significance; `score.significance` is the search's
    /// ([`search_significance`] of this over `bands_searched` bands).
    pub search_significance: f64,
    /// How many candidate bands the fault was scored in.
    pub bands_searched: usize,
}

/// Everything `analyze` reports about one record.
#[derive(Debug, Clone)]
pub struct RecordAnalysis {
    pub fs_hz: f64,
    pub samples: usize,
    pub window: usize,
    pub frequencies: FaultFrequencies,
    pub indicators: Indicators,
    pub scan: BandScan,
    /// The band the selection method (kurtogram, GK or fixed) chose.
    pub selected_band_index: usize,
    pub hypotheses: Vec<Hypothesis>,
    /// The hypothesis that led the contest (the others were weighed with its comb explained
    /// away); `None` when nothing was scored.
    pub leader: Option<FaultKind>,
    /// The other hypotheses re-scored with the leader's comb explained away: what the verdict
    /// weighed them on.
    pub explained: Vec<FaultScore>,
    pub diagnosis: Diagnosis,
    /// The band behind the verdict: the diagnosed fault's band, else the selected band.
    pub reported_band_index: usize,
}

impl RecordAnalysis {
    pub fn duration_s(&self) -> f64 {
        self.samples as f64 / self.fs_hz
    }

    pub fn band(&self) -> Band {
        self.scan.bands[self.reported_band_index].band
    }

    pub fn spectrum(&self) -> &EnvelopeSpectrum {
        &self.scan.bands[self.reported_band_index].spectrum
    }

    pub fn selected_band(&self) -> Band {
        self.scan.bands[self.selected_band_index].band
    }

    pub fn score(&self, kind: FaultKind) -> f64 {
        self.hypotheses
            .iter()
            .find(|h| h.score.fault == kind)
            .map_or(0.0, |h| h.score.score)
    }

    /// Every hypothesis's score in its best band, in [`FaultKind::ALL`] order.
    pub fn scores(&self) -> Vec<FaultScore> {
        self.hypotheses.iter().map(|h| h.score).collect()
    }

    /// The verdict once a second witness (`opinion`, of the same samples) is heard, by
    /// [`decide`] with `settings.agreement` (none: the envelope's verdict stands).
    pub fn hear_witness(&mut self, opinion: Option<WitnessOpinion>, settings: &AnalysisSettings) {
        let Some(agreement) = settings.agreement else {
            return;
        };
        self.diagnosis = decide(
            &self.scores(),
            &self.explained,
            &self.diagnosis,
            &settings.decision_rule(),
            &agreement,
            opinion,
        );
        self.reported_band_index =
            reported_band(&self.hypotheses, &self.diagnosis, self.selected_band_index);
    }
}

/// The band behind a verdict: the named fault's band, else the selected band.
fn reported_band(hypotheses: &[Hypothesis], diagnosis: &Diagnosis, selected: usize) -> usize {
    diagnosis
        .verdict
        .fault()
        .and_then(|kind| hypotheses.iter().find(|h| h.score.fault == kind))
        .map_or(selected, |h| h.band_index)
}

/// Analyses whole records; keeps FFT plans between records so that only the first pays for
/// planning.
#[derive(Default)]
pub struct RecordAnalyzer {
    /// Shared with whoever analyses the same records further (the twin fit).
    pub plans: FftPlans,
}

/// Analyses one record with a fresh [`RecordAnalyzer`].
pub fn analyze_record(
    signal: &[f32],
    fs_hz: f64,
    freqs: &FaultFrequencies,
    settings: &AnalysisSettings,
) -> Result<RecordAnalysis, AnalysisError> {
    RecordAnalyzer::default().analyze(signal, fs_hz, freqs, settings)
}

impl RecordAnalyzer {
    /// Analyses a whole record of acceleration samples at `fs_hz`.
    pub fn analyze(
        &mut self,
        signal: &[f32],
        fs_hz: f64,
        freqs: &FaultFrequencies,
        settings: &AnalysisSettings,
    ) -> Result<RecordAnalysis, AnalysisError> {
        analyze_with_plans(&mut self.plans, signal, fs_hz, freqs, settings)
    }
}

/// [`RecordAnalyzer::analyze`] with the caller's plan cache (the daemon's channels share one).
pub fn analyze_with_plans(
    plans: &mut FftPlans,
    signal: &[f32],
    fs_hz: f64,
    freqs: &FaultFrequencies,
    settings: &AnalysisSettings,
) -> Result<RecordAnalysis, AnalysisError> {
    {
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            return Err(AnalysisError::BadSampleRate(fs_hz));
        }
        if !(freqs.shaft.is_finite() && freqs.shaft > 0.0) {
            return Err(AnalysisError::BadSpeed(freqs.shaft));
        }
        let window = record_window(signal.len(), fs_hz, freqs, settings);
        if signal.len() < window {
            return Err(AnalysisError::TooShort {
                samples: signal.len(),
                seconds: signal.len() as f64 / fs_hz,
                window,
                window_s: window as f64 / fs_hz,
                fs_hz,
            });
        }
        let nyquist = fs_hz / 2.0;
        let range_hz = envelope_range_hz(freqs, settings.harmonics);
        if range_hz >= nyquist {
            return Err(AnalysisError::AboveNyquist {
                what: "the highest fault harmonic".into(),
                freq_hz: range_hz,
                nyquist,
            });
        }
        let bin_hz = fs_hz / window as f64;
        let spectrum_bins = ((range_hz / bin_hz).ceil() as usize + 1).min(window / 2);

        let tree = match settings.band_selection {
            BandSelection::Fixed { lo_hz, hi_hz } => {
                if hi_hz > nyquist {
                    return Err(AnalysisError::AboveNyquist {
                        what: "the fixed band's upper edge".into(),
                        freq_hz: hi_hz,
                        nyquist,
                    });
                }
                vec![TreeLevel {
                    level: 0.0,
                    bands: vec![Band::new(lo_hz, hi_hz)],
                }]
            }
            _ => band_tree(
                fs_hz,
                settings
                    .min_band_hz
                    .unwrap_or_else(|| comb_width_hz(freqs, settings.harmonics)),
            ),
        };
        let with_gini = matches!(settings.band_selection, BandSelection::GiniKurtosis);
        let scan = scan_bands(
            plans,
            signal,
            fs_hz,
            window,
            settings.overlap,
            &tree,
            spectrum_bins,
            with_gini,
        );
        let selected_band_index = match settings.band_selection {
            BandSelection::Fixed { .. } => 0,
            BandSelection::Kurtogram => best_index(&scan, false),
            BandSelection::GiniKurtosis => best_index(&scan, true),
        };

        let mut scorer =
            FaultScorer::new(settings.fault_tolerance, settings.harmonics, spectrum_bins);
        let candidates = candidate_bands(&scan, selected_band_index, settings, freqs);
        let rule = settings.decision_rule();
        // Each candidate band's spectrum is prepared once (slot = its place among the
        // candidates), then scored for every fault and on what the leader does not explain.
        for (slot, &i) in candidates.iter().enumerate() {
            let spectrum = &scan.bands[i].spectrum;
            scorer.prepare(slot, &spectrum.amplitude, spectrum.bin_hz, freqs);
        }
        let best_band = |scorer: &mut FaultScorer, kind: FaultKind, winner: Option<&FaultScore>| {
            candidates
                .iter()
                .enumerate()
                .map(|(slot, &i)| {
                    let amplitude = &scan.bands[i].spectrum.amplitude;
                    let mut score = match winner {
                        None => scorer.score_prepared(slot, amplitude, kind, freqs),
                        Some(w) => scorer.score_explained_prepared(slot, amplitude, kind, freqs, w),
                    };
                    let own = score.significance;
                    score.significance = search_significance(own, candidates.len());
                    Hypothesis {
                        score,
                        band_index: i,
                        search_significance: own,
                        bands_searched: candidates.len(),
                    }
                })
                .max_by(|a, b| {
                    rule.naming_margin(&a.score)
                        .total_cmp(&rule.naming_margin(&b.score))
                        .then(a.search_significance.total_cmp(&b.search_significance))
                })
                .unwrap_or(Hypothesis {
                    score: FaultScore::unscored(kind, freqs),
                    band_index: selected_band_index,
                    search_significance: 0.0,
                    bands_searched: 0,
                })
        };
        let hypotheses: Vec<Hypothesis> = FaultKind::ALL
            .iter()
            .map(|&kind| best_band(&mut scorer, kind, None))
            .collect();
        let scores: Vec<FaultScore> = hypotheses.iter().map(|h| h.score).collect();
        let leader_kind = leader(&scores, &rule).map(|l| l.fault);
        let explained: Vec<FaultScore> = match leader(&scores, &rule) {
            Some(leader) => FaultKind::ALL
                .iter()
                .filter(|&&kind| kind != leader.fault)
                .map(|&kind| best_band(&mut scorer, kind, Some(leader)).score)
                .collect(),
            None => Vec::new(),
        };
        let diagnosis = diagnose(&scores, &explained, &rule);
        let reported_band_index = reported_band(&hypotheses, &diagnosis, selected_band_index);

        Ok(RecordAnalysis {
            fs_hz,
            samples: signal.len(),
            window,
            frequencies: *freqs,
            indicators: Indicators::of(signal),
            scan,
            selected_band_index,
            hypotheses,
            leader: leader_kind,
            explained,
            diagnosis,
            reported_band_index,
        })
    }
}

/// Windows a record should hold at least for a stable Welch average.
const MIN_WINDOWS: usize = 6;

/// (choice) The configured window, halved while a short record would give fewer than
/// [`MIN_WINDOWS`] windows and the frequency bin stays narrower than the slip tolerance of the
/// lowest fault frequency: a 1 s IMS snapshot is then averaged over 4 windows rather than
/// refused or left as one noisy window.
fn record_window(
    len: usize,
    fs_hz: f64,
    freqs: &FaultFrequencies,
    settings: &AnalysisSettings,
) -> usize {
    let hop_fraction = (1.0 - settings.overlap).max(0.05);
    let windows = |w: usize| {
        if len >= w {
            ((len - w) as f64 / (w as f64 * hop_fraction)) as usize + 1
        } else {
            0
        }
    };
    let narrowest_bin_hz = settings.fault_tolerance * freqs.bpfo.min(freqs.bpfi).min(freqs.two_bsf);
    let mut window = window_samples(settings.window_s, fs_hz);
    while windows(window) < MIN_WINDOWS
        && window > 256
        && fs_hz / (window / 2) as f64 <= narrowest_bin_hz
    {
        window /= 2;
    }
    window.min(short_record_window(len, fs_hz, freqs))
}

/// Bins the lowest fault frequency must lie above 0 Hz in a short record's spectrum: the Hann
/// window's main lobe spans ±2 bins, so 4 keeps the first harmonic clear of the DC lobe.
const MIN_LINE_BINS: f64 = 4.0;

/// (choice) A record shorter than the configured window (a 0.1 s PRONOSTIA snapshot) is
/// analysed as one window of the largest power of two it holds: the finest resolution the
/// record allows (2,048 of 2,560 samples at 25.6 kHz: bins of 12.5 Hz), provided the lowest
/// fault frequency sits at least [`MIN_LINE_BINS`] bins above 0 Hz; otherwise the window that
/// needs (longer than the record: the caller reports the record as too short). For a record
/// that holds the configured window this is never the smaller one.
fn short_record_window(len: usize, fs_hz: f64, freqs: &FaultFrequencies) -> usize {
    let lowest_hz = freqs.bpfo.min(freqs.bpfi).min(freqs.two_bsf);
    let needed = (MIN_LINE_BINS * fs_hz / lowest_hz)
        .ceil()
        .clamp(64.0, (1u64 << 30) as f64) as usize;
    let fitting = if len >= 1 { 1usize << len.ilog2() } else { 0 };
    if fitting >= needed {
        fitting
    } else {
        needed.next_power_of_two()
    }
}

fn best_index(scan: &BandScan, use_gk: bool) -> usize {
    let key = |i: &usize| {
        if use_gk {
            scan.bands[*i].gk
        } else {
            scan.bands[*i].kurtosis
        }
    };
    (0..scan.bands.len())
        .max_by(|a, b| key(a).total_cmp(&key(b)))
        .unwrap_or(0)
}
