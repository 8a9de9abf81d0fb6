//! Choosing the resonance band (MODELS.md §3): the fast kurtogram's 1/3-binary tree of bands,
//! the spectral kurtosis and the GK index (Gini index × kurtosis, seed 001) of each band, and,
//! in the same pass, each band's envelope spectrum for the fault-band SNR refinement.
//!
//! Why one pass: every band of the tree is computed from the same window FFTs
//! ([`WindowTransform`]), so the kurtogram costs a few short inverse FFTs per window instead of
//! a filter bank over the whole record, and the candidate bands' envelope spectra come for the
//! price of one more short FFT each.
//!
//! (choice) The tree uses ideal (FFT-mask) band-pass filters rather than Antoni's
//! quasi-analytic FIR bank; the statistics of a window are taken from the central half of its
//! analytic signal (the halves of 50 %-overlapping windows tile the record), away from the
//! circular edges of the FFT filter.
//!
//! (choice) The Gini index is computed from a histogram of the squared envelope with 32 bins
//! per octave instead of a full sort, each value counted at its bin's geometric centre: values
//! inside one bin differ by at most 2.2 %, which moves the index by far less than the
//! differences between bands, and the cost is linear. It is only computed when asked for.

use super::band::Band;
use super::envelope::{
    averaged_amplitude, hop_samples, power_moments, window_starts, BandEnvelope, EnvelopeSpectrum,
    FftPlans, WindowTransform,
};
use serde::Serialize;

/// One level of the 1/3-binary tree: `level` 0, 1, 1.6, 2, 2.6, … and its equal-width bands
/// spanning 0 … fs/2.
#[derive(Debug, Clone, Serialize)]
pub struct TreeLevel {
    pub level: f64,
    pub bands: Vec<Band>,
}

/// The fast kurtogram's tree over `0 … fs/2`, down to the narrowest level whose bands are
/// still at least `min_band_hz` wide.
pub fn band_tree(fs_hz: f64, min_band_hz: f64) -> Vec<TreeLevel> {
    let nyquist = fs_hz / 2.0;
    let mut levels = vec![TreeLevel {
        level: 0.0,
        bands: vec![Band::new(0.0, nyquist)],
    }];
    for k in 1..=12u32 {
        for (level, count) in [
            (f64::from(k), 1usize << k),
            (f64::from(k) + 0.6, 3usize << (k - 1)),
        ] {
            let width = nyquist / count as f64;
            if width < min_band_hz {
                return levels;
            }
            let bands = (0..count)
                .map(|i| Band::new(i as f64 * width, (i + 1) as f64 * width))
                .collect();
            levels.push(TreeLevel { level, bands });
        }
    }
    levels
}

/// What the scan found for one band.
#[derive(Debug, Clone)]
pub struct ScannedBand {
    pub band: Band,
    pub level: f64,
    /// Spectral kurtosis of the complex envelope, `E|c|⁴ / (E|c|²)² − 2` (0 for Gaussian noise).
    pub kurtosis: f64,
    /// Gini index of the squared envelope (0 = flat, → 1 = sparse, impulsive).
    pub gini: f64,
    /// GK index: `gini · max(kurtosis, 0)`, normalised by its maximum over the tree.
    pub gk: f64,
    /// Welch-averaged squared-envelope spectrum of the band.
    pub spectrum: EnvelopeSpectrum,
}

/// The result of scanning every band of the tree over a record.
#[derive(Debug, Clone)]
pub struct BandScan {
    pub levels: Vec<f64>,
    /// Bands in tree order: level by level, low to high frequency.
    pub bands: Vec<ScannedBand>,
}

impl BandScan {
    /// The band of highest kurtosis (fast kurtogram) or highest GK index.
    pub fn best_by(&self, use_gk: bool) -> Option<&ScannedBand> {
        let key = |b: &&ScannedBand| if use_gk { b.gk } else { b.kurtosis };
        self.bands
            .iter()
            .filter(|b| key(b).is_finite())
            .max_by(|a, b| key(a).total_cmp(&key(b)))
    }
}

/// f32 bits >> 18 keep the exponent and 5 mantissa bits: 32 histogram bins per octave.
const GINI_KEY_SHIFT: u32 = 18;
const GINI_LOWEST_KEY: u32 = (127 - 80) << 5; // 2^-80
const GINI_KEYS: usize = 160 << 5; // 2^-80 … 2^80

/// Running statistics of one band's squared envelope.
struct EnvelopeMoments {
    count: u64,
    sum2: f64,
    sum4: f64,
    /// Empty when the Gini index is not wanted.
    histogram: Vec<u32>,
}

impl EnvelopeMoments {
    fn new(with_gini: bool) -> Self {
        EnvelopeMoments {
            count: 0,
            sum2: 0.0,
            sum4: 0.0,
            histogram: if with_gini {
                vec![0; GINI_KEYS]
            } else {
                Vec::new()
            },
        }
    }

    /// Adds the squared envelope of a run of analytic-signal samples.
    fn add(&mut self, analytic: &[rustfft::num_complex::Complex32]) {
        let (sum2, sum4) = power_moments(analytic);
        self.count += analytic.len() as u64;
        self.sum2 += f64::from(sum2);
        self.sum4 += f64::from(sum4);
        if !self.histogram.is_empty() {
            for c in analytic {
                let key = (c.norm_sqr().to_bits() >> GINI_KEY_SHIFT).saturating_sub(GINI_LOWEST_KEY)
                    as usize;
                self.histogram[key.min(GINI_KEYS - 1)] += 1;
            }
        }
    }

    /// The value a histogram bin stands for: its geometric centre.
    fn bin_value(key: usize) -> f64 {
        let low = f32::from_bits((key as u32 + GINI_LOWEST_KEY) << GINI_KEY_SHIFT);
        f64::from(low) * 2f64.powf(0.5 / 32.0)
    }

    fn kurtosis(&self) -> f64 {
        if self.count == 0 || self.sum2 <= 0.0 {
            return 0.0;
        }
        let n = self.count as f64;
        (self.sum4 / n) / (self.sum2 / n).powi(2) - 2.0
    }

    /// `Gini = 1 − 2 Σ (c(i)/‖c‖₁)(N − i + ½)/N` over the sorted values, with every value of a
    /// histogram bin placed at the bin's mean rank.
    fn gini(&self) -> f64 {
        let n = self.count as f64;
        if self.count == 0 || self.histogram.is_empty() {
            return 0.0;
        }
        let (mut rank_before, mut weighted, mut total) = (0.0, 0.0, 0.0);
        for (key, &count) in self.histogram.iter().enumerate().filter(|(_, &c)| c > 0) {
            let count = f64::from(count);
            let sum = count * Self::bin_value(key);
            weighted += sum * (n - rank_before - count / 2.0);
            total += sum;
            rank_before += count;
        }
        if total <= 0.0 {
            return 0.0;
        }
        1.0 - 2.0 * weighted / (n * total)
    }
}

/// Scans every band of `tree` over `signal`: kurtosis, the envelope spectrum, and, if
/// `with_gini`, the Gini and GK indices.
#[allow(clippy::too_many_arguments)]
pub fn scan_bands(
    plans: &mut FftPlans,
    signal: &[f32],
    fs_hz: f64,
    window: usize,
    overlap: f64,
    tree: &[TreeLevel],
    spectrum_bins: usize,
    with_gini: bool,
) -> BandScan {
    let mut transform = WindowTransform::new(window, plans);
    let mut engines: Vec<(f64, BandEnvelope)> = tree
        .iter()
        .flat_map(|level| level.bands.iter().map(move |band| (level.level, *band)))
        .map(|(level, band)| {
            (
                level,
                BandEnvelope::new(band, fs_hz, window, spectrum_bins, plans),
            )
        })
        .collect();
    let mut moments: Vec<EnvelopeMoments> = engines
        .iter()
        .map(|_| EnvelopeMoments::new(with_gini))
        .collect();
    let mut power_sums = vec![vec![0f64; spectrum_bins]; engines.len()];
    let mut power = vec![0f32; spectrum_bins];
    let mut windows = 0;

    for start in window_starts(signal.len(), window, hop_samples(window, overlap)) {
        let spectrum = transform.transform(&signal[start..start + window], &[]);
        for ((_, engine), (stats, sum)) in engines
            .iter_mut()
            .zip(moments.iter_mut().zip(&mut power_sums))
        {
            let analytic = engine.analytic_from(spectrum);
            let quarter = analytic.len() / 4;
            stats.add(&analytic[quarter..analytic.len() - quarter]);
            engine.squared_envelope_power(&mut power);
            for (s, p) in sum.iter_mut().zip(&power) {
                *s += f64::from(*p);
            }
        }
        windows += 1;
    }

    let bin_hz = fs_hz / window as f64;
    let mut bands: Vec<ScannedBand> = engines
        .iter()
        .zip(&moments)
        .zip(&power_sums)
        .map(|(((level, engine), stats), sum)| ScannedBand {
            band: engine.band(),
            level: *level,
            kurtosis: stats.kurtosis(),
            gini: stats.gini(),
            gk: 0.0,
            spectrum: EnvelopeSpectrum {
                band: engine.band(),
                bin_hz,
                amplitude: averaged_amplitude(sum, windows),
                windows_averaged: windows,
            },
        })
        .collect();
    let gk_max = bands
        .iter()
        .map(|b| b.gini * b.kurtosis.max(0.0))
        .fold(0.0, f64::max);
    for b in &mut bands {
        b.gk = if gk_max > 0.0 {
            b.gini * b.kurtosis.max(0.0) / gk_max
        } else {
            0.0
        };
    }
    BandScan {
        levels: tree.iter().map(|l| l.level).collect(),
        bands,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tree_follows_the_one_third_binary_pattern() {
        let tree = band_tree(12_000.0, 450.0);
        let shape: Vec<(f64, usize)> = tree.iter().map(|l| (l.level, l.bands.len())).collect();
        assert_eq!(
            shape,
            vec![
                (0.0, 1),
                (1.0, 2),
                (1.6, 3),
                (2.0, 4),
                (2.6, 6),
                (3.0, 8),
                (3.6, 12)
            ]
        );
        assert!((tree[6].bands[11].hi_hz - 6000.0).abs() < 1e-9);
    }

    #[test]
    fn gini_of_equal_values_is_zero_and_of_one_spike_near_one() {
        use rustfft::num_complex::Complex32;
        let mut flat = EnvelopeMoments::new(true);
        let mut spike = EnvelopeMoments::new(true);
        for i in 0..1000 {
            flat.add(&[Complex32::new(2.0, 0.0)]);
            spike.add(&[Complex32::new(if i == 500 { 1000.0 } else { 1e-3 }, 0.0)]);
        }
        assert!(flat.gini().abs() < 1e-6, "{}", flat.gini());
        assert!(spike.gini() > 0.99, "{}", spike.gini());
    }
}
