//! Fault-band scores (MODELS.md §1–2): how strongly an envelope spectrum shows a fault
//! frequency and its harmonics, searched within a slip tolerance, against the local noise floor.
//!
//! The spectrum is first turned into its *excess*: log amplitude minus a running median of the
//! log amplitude (the local noise floor, 0.6 × the lowest fault frequency wide), with the shaft
//! harmonics (machine lines every bearing shows) pushed down to the floor. A fault's *comb* is
//! its harmonics `k·f`, `k = 1..H`, and the sidebands that belong to it (inner race `k·BPFI ±
//! fr`, ball `k·2BSF ± FTF`, weight ½ each; outer race and cage none). One common slip `δ`
//! (within ±tol) moves the whole comb, as a real speed error does; each line takes the largest
//! excess within ±max(1 bin, 0.4 %) of `k·f·(1+δ)`. The comb's effect size `C` is the weighted
//! mean of the lines' positive excess at the best `δ`; its **score** is `exp(C)`, the
//! geometric-mean peak-to-floor ratio over the comb (1 = nothing above the floor). A mean
//! over all lines needs the comb to stand out, so one machine line near `f` does not make a
//! fault.
//!
//! Its **significance** is `−log10` of the probability that noise alone gives a comb at least
//! this strong: `C` over the spectrum's robust spread of excess (1.4826 × MAD) is, for a
//! noise-only envelope spectrum, nearly independent of how many windows were averaged, and its
//! tail was measured by simulation (see [`noise_significance`]; docs/DIAGNOSIS.md).
//!
//! Explaining away: a strong fault leaks into other combs where their lines coincide (on a
//! 6205, `2·BPFI ≈ 3·BPFO`) and through its sidebands. [`FaultScorer::score_explained`] scores a
//! hypothesis with the winner's comb (harmonics, ±1–2·fr and, for a ball, ±1–2·FTF) removed,
//! so a runner-up is judged only on evidence the winner does not explain.

use super::modulation::{anchored_contrast, spacings, Modulation};
use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;
use serde::Serialize;

mod explain;
mod floor;

use explain::floor_comb;
use floor::{median_of, subtract_running_median, FloorScratch};

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
    /// Peak amplitude over the local noise floor (running median).
    pub ratio: f64,
}

/// How strongly a spectrum shows one fault.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FaultScore {
    pub fault: FaultKind,
    /// The fault frequency at the fitted slip.
    pub frequency_hz: f64,
    /// Geometric-mean peak-to-floor ratio over the fault's comb (1 = nothing above the floor,
    /// 0 = not scored).
    pub score: f64,
    /// `−log10` of the probability that noise alone gives a comb this strong.
    pub significance: f64,
    /// The common slip of the comb that fits best, relative (−0.02 … 0.02).
    pub slip: f64,
    /// Geometric-mean peak-to-floor ratio of the sidebands alone, for faults that have them.
    pub sideband_score: Option<f64>,
    /// For an inner race or a ball: its own sideband spacing against the other's, around the
    /// peaks the comb found ([`super::modulation`]).
    pub modulation: Option<Modulation>,
    /// The spectrum's bin width (0 when not scored): peaks of two combs within a bin of each
    /// other are the same line.
    #[serde(skip)]
    bin_hz: f64,
    #[serde(skip)]
    peaks: [HarmonicPeak; MAX_HARMONICS],
    #[serde(skip)]
    peak_count: usize,
}

impl FaultScore {
    /// A fault that could not be scored (no spectrum, no speed).
    pub fn unscored(fault: FaultKind, freqs: &FaultFrequencies) -> Self {
        FaultScore {
            fault,
            frequency_hz: fault.frequency(freqs),
            score: 0.0,
            significance: 0.0,
            slip: 0.0,
            sideband_score: None,
            modulation: None,
            bin_hz: 0.0,
            peaks: [HarmonicPeak::default(); MAX_HARMONICS],
            peak_count: 0,
        }
    }

    pub fn peaks(&self) -> &[HarmonicPeak] {
        &self.peaks[..self.peak_count]
    }

    /// The width of the spectrum's bins it was scored on (0 when not scored).
    pub fn bin_hz(&self) -> f64 {
        self.bin_hz
    }

    /// Whether every harmonic of the comb but one stands at least `ratio` times its floor: a
    /// fault's impulse train lifts all of its first harmonics, while a machine's tones (gear
    /// mesh, electrical, structural) meet one or two of them.
    pub fn harmonics_stand(&self, ratio: f64) -> bool {
        let standing = self.peaks().iter().filter(|p| p.ratio >= ratio).count();
        self.peak_count >= 2 && standing + 1 >= self.peak_count
    }

    /// A score whose harmonics stood at `ratios` times their floor (tests of the decision).
    #[cfg(test)]
    pub(crate) fn with_harmonic_ratios(mut self, ratios: &[f64]) -> Self {
        self.peak_count = ratios.len().min(MAX_HARMONICS);
        for (k, (peak, &ratio)) in self.peaks.iter_mut().zip(ratios).enumerate() {
            peak.order = k + 1;
            peak.ratio = ratio;
        }
        self
    }

    /// A score whose harmonics were found at `found_hz` on bins `bin_hz` wide (tests of the
    /// decision).
    #[cfg(test)]
    pub(crate) fn with_found_peaks(mut self, bin_hz: f64, found_hz: &[f64]) -> Self {
        self.bin_hz = bin_hz;
        self.peak_count = self.peak_count.max(found_hz.len().min(MAX_HARMONICS));
        for (k, (peak, &hz)) in self.peaks.iter_mut().zip(found_hz).enumerate() {
            peak.order = k + 1;
            peak.found_hz = hz;
        }
        self
    }

    /// The comb's effect size `C = ln score` (0 when not scored).
    pub fn effect(&self) -> f64 {
        if self.score > 0.0 {
            self.score.ln()
        } else {
            0.0
        }
    }
}

/// `−log10` of the probability that a noise-only envelope spectrum gives a comb whose effect
/// size is `z` times the spectrum's robust spread of excess; `with_sidebands` for the combs
/// that carry sidebands (more lines: a narrower null), `harmonics` the comb's length.
///
/// (measured) This scorer on 12,000 noise spectra (Gamma-distributed power with 2, 8 and 32
/// averages, 2.9 Hz bins, a 6205 at 1797 rpm, 5 harmonics), per comb type the worse of its two
/// faults: the quantiles 50/90/99/99.9 % of `z` are 1.14/1.64/2.13/2.59 (harmonics only: outer
/// race, cage) and 1.10/1.39/1.68/1.92 (with sidebands: inner race, ball). The test
/// `noise_alone_reaches_the_false_alarm_rate_no_more_often_than_it_says` re-measures it. Between
/// the knots we interpolate; beyond 99.9 % we extend with the slope of the 99–99.9 % stretch,
/// which overstates the probability further out (the measured tail falls faster), so the
/// significance errs low. Another comb length scales the spread about the median by
/// `sqrt(harmonics / 5)` (a mean over more independent lines is narrower).
pub fn noise_significance(z: f64, with_sidebands: bool, harmonics: usize) -> f64 {
    const HARMONICS_ONLY: [(f64, f64); 5] = [
        (0.0, 0.0),
        (1.14, 0.301),
        (1.64, 1.0),
        (2.13, 2.0),
        (2.59, 3.0),
    ];
    const WITH_SIDEBANDS: [(f64, f64); 5] = [
        (0.0, 0.0),
        (1.10, 0.301),
        (1.39, 1.0),
        (1.68, 2.0),
        (1.92, 3.0),
    ];
    let knots = if with_sidebands {
        &WITH_SIDEBANDS
    } else {
        &HARMONICS_ONLY
    };
    if !z.is_finite() || z <= 0.0 {
        return 0.0;
    }
    let median = knots[1].0;
    let z = median + (z - median) * (harmonics.max(1) as f64 / 5.0).sqrt();
    if z <= 0.0 {
        return 0.0;
    }
    for pair in knots.windows(2) {
        let ((z0, s0), (z1, s1)) = (pair[0], pair[1]);
        if z <= z1 {
            return s0 + (s1 - s0) * (z - z0) / (z1 - z0);
        }
    }
    let (z99, _) = knots[3];
    let (z999, s999) = knots[4];
    s999 + (z - z999) / (z999 - z99)
}

/// One line of a comb: harmonic order, offset from `k·f` in multiples of the sideband spacing,
/// weight.
#[derive(Debug, Clone, Copy)]
struct CombLine {
    order: usize,
    sideband: f64,
    weight: f64,
}

/// One spectrum made ready for scoring ([`FaultScorer::prepare`]): scored for every fault, and
/// again on what the leader does not explain, it is prepared once.
#[derive(Debug, Default)]
struct Prepared {
    /// Excess (log amplitude over the running-median floor); empty when there is nothing to
    /// score.
    excess: Vec<f32>,
    /// Robust spread (1.4826 × MAD) of `excess`.
    spread: f64,
    bin_hz: f64,
}

/// Scores envelope spectra; owns its scratch space so that scoring never allocates once warm.
/// Spectra are prepared into numbered slots (one per band a caller scores) and scored from
/// there.
pub struct FaultScorer {
    tolerance: f64,
    harmonics: usize,
    spectrum_bins: usize,
    slots: Vec<Prepared>,
    /// When scoring explained: the prepared excess with the bins the winner's comb explains at
    /// the floor (0).
    unexplained: Vec<f32>,
    /// Scratch for the spread's medians.
    keys: Vec<i32>,
    /// Scratch for the running-median floor.
    floor: FloorScratch,
}

/// Relative half-width of a line's search window beside the slip (bearing-geometry and
/// frequency-resolution smear).
const LINE_HALF_WIDTH: f64 = 0.004;

/// (choice) A cage comb is scored on its first 3 harmonics at most: the cage's speed wanders
/// (it slips against the shaft and its loaded pocket leads and lags), which widens the k-th
/// harmonic k times, so the higher ones sink into the floor while the first stand clear (the
/// simulator's damaged cage: peak-to-floor 11.7, 8.0, 4.9, 2.2, 1.2 for k = 1…5).
const CAGE_HARMONICS: usize = 3;

impl FaultScorer {
    pub fn new(tolerance: f64, harmonics: usize, spectrum_bins: usize) -> Self {
        FaultScorer {
            tolerance,
            harmonics: harmonics.clamp(1, MAX_HARMONICS),
            spectrum_bins,
            // One per fault's band, as the daemon scores them; more are made on first use.
            slots: (0..FaultKind::ALL.len())
                .map(|_| Prepared {
                    excess: Vec::with_capacity(spectrum_bins),
                    ..Prepared::default()
                })
                .collect(),
            unexplained: Vec::with_capacity(spectrum_bins),
            keys: Vec::with_capacity(spectrum_bins),
            floor: FloorScratch::with_capacity(spectrum_bins),
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
        self.prepare(0, amplitude, bin_hz, freqs);
        self.score_prepared(0, amplitude, fault, freqs)
    }

    /// Scores of every fault kind, in [`FaultKind::ALL`] order.
    pub fn score_all(
        &mut self,
        amplitude: &[f32],
        bin_hz: f64,
        freqs: &FaultFrequencies,
    ) -> [FaultScore; 4] {
        self.prepare(0, amplitude, bin_hz, freqs);
        FaultKind::ALL.map(|kind| self.score_prepared(0, amplitude, kind, freqs))
    }

    /// The score of `fault` on the evidence `winner` does not explain: the winner's comb (at its
    /// fitted slip), its ±1–2·fr sidebands and, for a ball, its ±1–2·FTF sidebands are removed
    /// from the spectrum first.
    pub fn score_explained(
        &mut self,
        amplitude: &[f32],
        bin_hz: f64,
        fault: FaultKind,
        freqs: &FaultFrequencies,
        winner: &FaultScore,
    ) -> FaultScore {
        self.prepare(0, amplitude, bin_hz, freqs);
        self.score_explained_prepared(0, amplitude, fault, freqs, winner)
    }

    /// Prepares `amplitude` (bins spaced `bin_hz` from 0 Hz) into `slot` for
    /// [`Self::score_prepared`] and [`Self::score_explained_prepared`]; false when there is
    /// nothing to score (those then say unscored).
    pub fn prepare(
        &mut self,
        slot: usize,
        amplitude: &[f32],
        bin_hz: f64,
        freqs: &FaultFrequencies,
    ) -> bool {
        while self.slots.len() <= slot {
            self.slots.push(Prepared {
                excess: Vec::with_capacity(self.spectrum_bins),
                ..Prepared::default()
            });
        }
        let FaultScorer {
            slots, keys, floor, ..
        } = self;
        let prepared = &mut slots[slot];
        prepared.excess.clear();
        prepared.bin_hz = bin_hz;
        let lowest = freqs.bpfo.min(freqs.bpfi).min(freqs.two_bsf);
        if amplitude.len() < 16 || !is_positive(bin_hz) || !is_positive(lowest) {
            return false;
        }
        let excess = &mut prepared.excess;
        let tiny = f32::MIN_POSITIVE;
        excess.extend(amplitude.iter().map(|&a| a.max(tiny).ln()));
        let half = ((0.3 * lowest / bin_hz).round() as usize).max(8);
        subtract_running_median(excess, half, floor);
        // The first bins hold the envelope's DC leakage.
        for e in excess.iter_mut().take(3) {
            *e = 0.0;
        }
        // Shaft harmonics: every rotating machine shows them; they are nobody's fault line.
        if freqs.shaft > 0.0 {
            let n = excess.len();
            let mut order = 1.0;
            while order * freqs.shaft / bin_hz < n as f64 - 1.0 {
                let centre = order * freqs.shaft / bin_hz;
                let lo = (centre - 1.5).max(0.0) as usize;
                let hi = ((centre + 1.5) as usize).min(n - 1);
                for e in &mut excess[lo..=hi] {
                    *e = e.min(0.0);
                }
                order += 1.0;
            }
        }
        let median = median_of(excess.iter().copied(), keys);
        let mad = median_of(excess.iter().map(|&x| (x - median).abs()), keys);
        prepared.spread = 1.4826 * f64::from(mad);
        true
    }

    /// The score of `fault` in the spectrum prepared in `slot` (`amplitude` is that spectrum,
    /// for the peaks' amplitudes).
    pub fn score_prepared(
        &mut self,
        slot: usize,
        amplitude: &[f32],
        fault: FaultKind,
        freqs: &FaultFrequencies,
    ) -> FaultScore {
        match self.slots.get(slot).filter(|p| !p.excess.is_empty()) {
            Some(prepared) => self.comb_score(prepared, &prepared.excess, amplitude, fault, freqs),
            None => FaultScore::unscored(fault, freqs),
        }
    }

    /// [`Self::score_explained`] on the spectrum prepared in `slot`.
    pub fn score_explained_prepared(
        &mut self,
        slot: usize,
        amplitude: &[f32],
        fault: FaultKind,
        freqs: &FaultFrequencies,
        winner: &FaultScore,
    ) -> FaultScore {
        let Some(prepared) = self.slots.get(slot).filter(|p| !p.excess.is_empty()) else {
            return FaultScore::unscored(fault, freqs);
        };
        self.unexplained.clear();
        self.unexplained.extend_from_slice(&prepared.excess);
        floor_comb(
            &mut self.unexplained,
            prepared.bin_hz,
            self.harmonics.min(CAGE_HARMONICS),
            winner,
            freqs,
        );
        self.comb_score(prepared, &self.unexplained, amplitude, fault, freqs)
    }

    /// How many harmonics `fault`'s comb has.
    fn comb_harmonics(&self, fault: FaultKind) -> usize {
        match fault {
            FaultKind::Cage => self.harmonics.min(CAGE_HARMONICS),
            _ => self.harmonics,
        }
    }

    fn comb_lines(
        &self,
        fault: FaultKind,
        freqs: &FaultFrequencies,
    ) -> ([CombLine; 3 * MAX_HARMONICS], usize) {
        let mut lines = [CombLine {
            order: 0,
            sideband: 0.0,
            weight: 0.0,
        }; 3 * MAX_HARMONICS];
        let mut count = 0;
        let has_sidebands = fault.sideband_spacing(freqs).is_some();
        for order in 1..=self.comb_harmonics(fault) {
            lines[count] = CombLine {
                order,
                sideband: 0.0,
                weight: 1.0,
            };
            count += 1;
            if has_sidebands {
                for sideband in [-1.0, 1.0] {
                    lines[count] = CombLine {
                        order,
                        sideband,
                        weight: 0.5,
                    };
                    count += 1;
                }
            }
        }
        (lines, count)
    }

    /// The score of `fault` on `excess`: the prepared spectrum's, or what a winner leaves of it.
    fn comb_score(
        &self,
        prepared: &Prepared,
        excess: &[f32],
        amplitude: &[f32],
        fault: FaultKind,
        freqs: &FaultFrequencies,
    ) -> FaultScore {
        let f = fault.frequency(freqs);
        let spacing = fault.sideband_spacing(freqs).unwrap_or(0.0);
        let bin = prepared.bin_hz;
        let mut result = FaultScore::unscored(fault, freqs);
        if !is_positive(f) {
            return result;
        }
        let (lines, count) = self.comb_lines(fault, freqs);
        let lines = &lines[..count];
        // Slip steps: the last harmonic moves by at most one bin per step.
        let harmonics = self.comb_harmonics(fault);
        let step = (bin / (harmonics as f64 * f)).max(1e-4);
        let steps = ((self.tolerance / step).ceil() as i64).min(100);
        let mut best: Option<(f64, f64)> = None; // (effect, slip)
        for s in -steps..=steps {
            let slip = if steps == 0 {
                0.0
            } else {
                self.tolerance * s as f64 / steps as f64
            };
            let Some(effect) = comb_effect(excess, bin, lines, f, spacing, slip) else {
                continue;
            };
            if best.is_none_or(|(b, _)| effect > b) {
                best = Some((effect, slip));
            }
        }
        let Some((effect, slip)) = best else {
            return result;
        };
        result.score = effect.exp();
        result.slip = slip;
        result.frequency_hz = f * (1.0 + slip);
        result.significance = if prepared.spread > 0.0 {
            noise_significance(effect / prepared.spread, spacing > 0.0, harmonics)
        } else {
            0.0
        };
        // The harmonics and sidebands at the fitted slip, for the report.
        let mut side_sum = 0.0;
        let mut side_n = 0usize;
        for line in lines {
            let target =
                line.order as f64 * f * (1.0 + slip) + line.sideband * spacing * (1.0 + slip);
            let half = (LINE_HALF_WIDTH * line.order as f64 * f / bin).max(1.0);
            let Some((peak_bin, e)) = line_excess(excess, target / bin, half) else {
                continue;
            };
            if line.sideband != 0.0 {
                side_sum += f64::from(e.max(0.0));
                side_n += 1;
            } else if result.peak_count < MAX_HARMONICS {
                result.peaks[result.peak_count] = HarmonicPeak {
                    order: line.order,
                    expected_hz: line.order as f64 * f,
                    found_hz: peak_bin as f64 * bin,
                    amplitude: f64::from(amplitude.get(peak_bin).copied().unwrap_or(0.0)),
                    ratio: f64::from(e).exp(),
                };
                result.peak_count += 1;
            }
        }
        if spacing > 0.0 && side_n > 0 {
            result.sideband_score = Some((side_sum / side_n as f64).exp());
        }
        result.bin_hz = bin;
        result.modulation = spacings(fault, freqs).and_then(|pair| {
            let found = result.peaks().iter().map(|p| p.found_hz);
            anchored_contrast(excess, bin, prepared.spread, found, pair, freqs.ftf)
        });
        result
    }
}

/// The comb's weighted mean positive excess at `slip` in `excess` (bins spaced `bin_hz`);
/// `None` when not one harmonic fits in the spectrum.
fn comb_effect(
    excess: &[f32],
    bin_hz: f64,
    lines: &[CombLine],
    f: f64,
    spacing: f64,
    slip: f64,
) -> Option<f64> {
    let (mut sum, mut weights, mut harmonics) = (0.0, 0.0, 0);
    for line in lines {
        let target = line.order as f64 * f * (1.0 + slip) + line.sideband * spacing * (1.0 + slip);
        let half = (LINE_HALF_WIDTH * line.order as f64 * f / bin_hz).max(1.0);
        let Some((_, e)) = line_excess(excess, target / bin_hz, half) else {
            continue;
        };
        sum += line.weight * f64::from(e.max(0.0));
        weights += line.weight;
        if line.sideband == 0.0 {
            harmonics += 1;
        }
    }
    (harmonics > 0).then(|| sum / weights)
}

/// The first largest of `excess` within ±`half` bins of bin `centre`, and its bin; `None`
/// when that reaches past either end.
fn line_excess(excess: &[f32], centre: f64, half: f64) -> Option<(usize, f32)> {
    let n = excess.len();
    if centre <= 0.0 || centre + half >= (n - 1) as f64 {
        return None;
    }
    let lo = (centre - half).round().max(1.0) as usize;
    let hi = ((centre + half).round() as usize).clamp(lo, n - 1);
    let mut best = (lo, f32::MIN);
    for (bin, &e) in excess.iter().enumerate().take(hi + 1).skip(lo) {
        if e > best.1 {
            best = (bin, e);
        }
    }
    Some(best)
}

/// `x > 0` and a number (NaN is not).
fn is_positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bearing::BearingGeometry;
    use crate::random::Rng;

    const BIN_HZ: f64 = 12_000.0 / 4096.0;

    fn cwru() -> FaultFrequencies {
        BearingGeometry::from_catalog("skf-6205-2rs")
            .expect("catalog entry")
            .fault_frequencies(1797.0 / 60.0)
    }

    /// An envelope amplitude spectrum of noise alone: power averaged over `averages` windows.
    fn noise_spectrum(rng: &mut Rng, bins: usize, averages: usize) -> Vec<f32> {
        (0..bins)
            .map(|_| {
                let power: f64 = (0..averages)
                    .map(|_| 0.5 * (rng.normal().powi(2) + rng.normal().powi(2)))
                    .sum::<f64>()
                    / averages as f64;
                power.sqrt() as f32
            })
            .collect()
    }

    fn add_line(spectrum: &mut [f32], hz: f64, amplitude: f32) {
        let bin = (hz / BIN_HZ).round() as usize;
        if let Some(a) = spectrum.get_mut(bin) {
            *a += amplitude;
        }
    }

    #[test]
    fn noise_alone_reaches_the_false_alarm_rate_no_more_often_than_it_says() {
        // The calibration of `noise_significance`, re-measured: 1000 noise spectra per
        // averaging count, every hypothesis; p ≤ 10^-2 must happen in at most about 1 % of
        // the decisions (binomial allowance: 2 %), p ≤ 10^-3 in at most 0.5 %.
        let freqs = cwru();
        let mut rng = Rng::new(7);
        let mut scorer = FaultScorer::new(0.02, 5, 400);
        let (mut decisions, mut at_2, mut at_3) = (0usize, 0usize, 0usize);
        for averages in [2, 8, 32] {
            for _ in 0..1000 {
                let spectrum = noise_spectrum(&mut rng, 340, averages);
                for score in scorer.score_all(&spectrum, BIN_HZ, &freqs) {
                    decisions += 1;
                    at_2 += usize::from(score.significance >= 2.0);
                    at_3 += usize::from(score.significance >= 3.0);
                }
            }
        }
        let rate_2 = at_2 as f64 / decisions as f64;
        let rate_3 = at_3 as f64 / decisions as f64;
        assert!(
            rate_2 <= 0.02,
            "p ≤ 1e-2 in {rate_2:.4} of {decisions} noise decisions"
        );
        assert!(
            rate_3 <= 0.005,
            "p ≤ 1e-3 in {rate_3:.4} of {decisions} noise decisions"
        );
    }

    #[test]
    fn a_slipped_comb_is_found_at_its_slip_and_is_significant() {
        let freqs = cwru();
        let mut rng = Rng::new(3);
        let mut spectrum = noise_spectrum(&mut rng, 340, 8);
        let slip = -0.01;
        for k in 1..=5 {
            add_line(&mut spectrum, k as f64 * freqs.bpfo * (1.0 + slip), 8.0);
        }
        let mut scorer = FaultScorer::new(0.02, 5, 400);
        let [outer, inner, ..] = scorer.score_all(&spectrum, BIN_HZ, &freqs);
        // On a 6205, 2·BPFO ≈ 7.17·fr and 5·BPFO ≈ 17.9·fr sit on shaft harmonics, which are
        // removed: 3 of the 5 lines remain, and they alone make the comb.
        assert!(
            outer.score > 3.0,
            "outer comb score {:.2} {:?}",
            outer.score,
            outer.peaks()
        );
        assert!(
            outer.significance > 3.0,
            "outer significance {:.1}",
            outer.significance
        );
        assert!(outer.slip < 0.0, "fitted slip {:+.4}", outer.slip);
        assert_eq!(outer.peaks().len(), 5);
        assert!(inner.score < outer.score / 2.0);
    }

    #[test]
    fn a_line_the_winner_explains_does_not_count_for_another_fault() {
        // On a 6205, 3·BPFO ≈ 2·BPFI: an outer-race comb with shaft sidebands lifts the inner
        // comb; once the outer race is explained away the inner race has nothing left.
        let freqs = cwru();
        let mut rng = Rng::new(11);
        let mut spectrum = noise_spectrum(&mut rng, 340, 8);
        for k in 1..=6 {
            let line = k as f64 * freqs.bpfo;
            add_line(&mut spectrum, line, 6.0);
            add_line(&mut spectrum, line - freqs.shaft, 2.0);
            add_line(&mut spectrum, line + freqs.shaft, 2.0);
        }
        let mut scorer = FaultScorer::new(0.02, 5, 400);
        let [outer, inner, ..] = scorer.score_all(&spectrum, BIN_HZ, &freqs);
        let explained =
            scorer.score_explained(&spectrum, BIN_HZ, FaultKind::InnerRace, &freqs, &outer);
        assert!(
            explained.score < inner.score && explained.score < 2.0,
            "inner {:.2} before, {:.2} once the outer race is explained",
            inner.score,
            explained.score
        );
    }

    #[test]
    fn shaft_harmonics_are_nobodys_fault() {
        let freqs = cwru();
        let mut rng = Rng::new(5);
        let mut spectrum = noise_spectrum(&mut rng, 340, 8);
        for k in 1..=30 {
            add_line(&mut spectrum, k as f64 * freqs.shaft, 10.0);
        }
        let mut scorer = FaultScorer::new(0.02, 5, 400);
        for score in scorer.score_all(&spectrum, BIN_HZ, &freqs) {
            assert!(score.score < 3.0, "{:?} {:.2}", score.fault, score.score);
        }
    }

    #[test]
    fn noise_significance_is_monotone_and_zero_at_nothing() {
        assert_eq!(noise_significance(0.0, false, 5), 0.0);
        let mut last = 0.0;
        for i in 1..60 {
            let s = noise_significance(f64::from(i) * 0.1, true, 5);
            assert!(s >= last);
            last = s;
        }
        assert!((noise_significance(2.59, false, 5) - 3.0).abs() < 1e-9);
    }
}
