//! Fault-band scores (MODELS.md §1–2): how strongly an envelope spectrum shows a fault
//! frequency and its harmonics, searched within a slip tolerance, against the local noise floor.
//!
//! The score of a fault is the geometric mean, over harmonics `k = 1..H`, of the largest
//! amplitude within `k·f·(1 ± tol)` divided by the median amplitude around `k·f` (the peak
//! window excluded). A geometric mean needs every harmonic to stand out, so one strong line
//! (a machine line that happens to sit near `f`) does not make a fault. Inner-race faults are
//! also modulated by the shaft (sidebands at `k·BPFI ± fr`) and ball faults by the cage
//! (`k·2BSF ± FTF`): their sideband ratio is reported as supporting evidence.

use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;
use serde::Serialize;

/// Most harmonics a score may use.
pub const MAX_HARMONICS: usize = 10;

/// One harmonic's peak.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct HarmonicPeak {
    pub order: usize,
    pub expected_hz: f64,
    /// Where in the tolerance window the largest amplitude sits.
    pub found_hz: f64,
    pub amplitude: f64,
    /// Peak amplitude / local median amplitude.
    pub ratio: f64,
}

/// How strongly a spectrum shows one fault.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FaultScore {
    pub fault: FaultKind,
    pub frequency_hz: f64,
    /// Geometric mean of the harmonics' peak-to-median ratios (≈ 2–4 for noise alone).
    pub score: f64,
    /// Geometric mean of the sidebands' peak-to-median ratios, for faults that have them.
    pub sideband_score: Option<f64>,
    #[serde(skip)]
    peaks: [HarmonicPeak; MAX_HARMONICS],
    #[serde(skip)]
    peak_count: usize,
}

impl FaultScore {
    pub fn peaks(&self) -> &[HarmonicPeak] {
        &self.peaks[..self.peak_count]
    }
}

/// Scores envelope spectra; owns its scratch space so that scoring never allocates.
pub struct FaultScorer {
    tolerance: f64,
    harmonics: usize,
    scratch: Vec<f32>,
}

impl FaultScorer {
    pub fn new(tolerance: f64, harmonics: usize, spectrum_bins: usize) -> Self {
        FaultScorer {
            tolerance,
            harmonics: harmonics.clamp(1, MAX_HARMONICS),
            scratch: Vec::with_capacity(spectrum_bins),
        }
    }

    /// The score of `fault` in `amplitude` (bins spaced `bin_hz` from 0 Hz).
    pub fn score(
        &mut self,
        amplitude: &[f32],
        bin_hz: f64,
        fault: FaultKind,
        freqs: &FaultFrequencies,
    ) -> FaultScore {
        let f = fault.frequency(freqs);
        let mut result = FaultScore {
            fault,
            frequency_hz: f,
            score: 0.0,
            sideband_score: None,
            peaks: [HarmonicPeak::default(); MAX_HARMONICS],
            peak_count: 0,
        };
        let mut log_sum = 0.0;
        let mut sideband_log_sum = 0.0;
        for order in 1..=self.harmonics {
            let target = order as f64 * f;
            let Some(peak) = self.peak_ratio(amplitude, bin_hz, target, f) else {
                break;
            };
            log_sum += peak.ratio.max(1e-9).ln();
            if let Some(spacing) = fault.sideband_spacing(freqs) {
                let lower = self
                    .peak_ratio(amplitude, bin_hz, target - spacing, f)
                    .map_or(1.0, |p| p.ratio);
                let upper = self
                    .peak_ratio(amplitude, bin_hz, target + spacing, f)
                    .map_or(1.0, |p| p.ratio);
                sideband_log_sum += (0.5 * (lower + upper)).max(1e-9).ln();
            }
            result.peaks[result.peak_count] = HarmonicPeak { order, ..peak };
            result.peak_count += 1;
        }
        if result.peak_count > 0 {
            let n = result.peak_count as f64;
            result.score = (log_sum / n).exp();
            if fault.sideband_spacing(freqs).is_some() {
                result.sideband_score = Some((sideband_log_sum / n).exp());
            }
        }
        result
    }

    /// Scores of every fault kind, in [`FaultKind::ALL`] order.
    pub fn score_all(
        &mut self,
        amplitude: &[f32],
        bin_hz: f64,
        freqs: &FaultFrequencies,
    ) -> [FaultScore; 4] {
        FaultKind::ALL.map(|kind| self.score(amplitude, bin_hz, kind, freqs))
    }

    /// The largest amplitude within `target·(1 ± tol)` over the median of the neighbourhood
    /// `target ± 0.3·fundamental` outside that window. `None` when the spectrum ends first.
    fn peak_ratio(
        &mut self,
        amplitude: &[f32],
        bin_hz: f64,
        target: f64,
        fundamental: f64,
    ) -> Option<HarmonicPeak> {
        if target <= 0.0 || bin_hz <= 0.0 {
            return None;
        }
        let half_peak = (self.tolerance * target / bin_hz).max(1.0);
        let half_noise = (0.3 * fundamental / bin_hz).max(half_peak + 8.0);
        let centre = target / bin_hz;
        let noise_hi = (centre + half_noise).ceil() as usize;
        if noise_hi >= amplitude.len() {
            return None;
        }
        let noise_lo = (centre - half_noise).floor().max(1.0) as usize;
        let peak_lo = (centre - half_peak).round().max(1.0) as usize;
        let peak_hi = ((centre + half_peak).round() as usize).max(peak_lo);

        let (mut best_bin, mut best) = (peak_lo, f32::MIN);
        for (bin, &a) in amplitude.iter().enumerate().take(peak_hi + 1).skip(peak_lo) {
            if a > best {
                best = a;
                best_bin = bin;
            }
        }
        self.scratch.clear();
        self.scratch.extend(
            amplitude[noise_lo..=noise_hi]
                .iter()
                .enumerate()
                .filter(|(i, _)| !(peak_lo..=peak_hi).contains(&(i + noise_lo)))
                .map(|(_, &a)| a),
        );
        if self.scratch.is_empty() {
            return None;
        }
        let middle = self.scratch.len() / 2;
        let median = *self
            .scratch
            .select_nth_unstable_by(middle, f32::total_cmp)
            .1;
        let ratio = if median > 0.0 {
            f64::from(best) / f64::from(median)
        } else if best > 0.0 {
            1e6
        } else {
            1.0
        };
        Some(HarmonicPeak {
            order: 0,
            expected_hz: target,
            found_hz: best_bin as f64 * bin_hz,
            amplitude: f64::from(best),
            ratio,
        })
    }
}
