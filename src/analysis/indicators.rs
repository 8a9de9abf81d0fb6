//! Time-domain condition indicators of a block of samples.

use serde::Serialize;

/// RMS, peak, crest factor and kurtosis of a signal (mean removed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Indicators {
    /// Root mean square, in the signal's unit (g).
    pub rms: f64,
    /// Largest absolute deviation from the mean (g).
    pub peak: f64,
    /// Peak / RMS.
    pub crest: f64,
    /// Pearson kurtosis `E[(x−μ)⁴]/σ⁴` (3 for Gaussian noise; impacts raise it).
    pub kurtosis: f64,
}

impl Indicators {
    /// Indicators of `samples`, which may come as several slices (a ring buffer's halves).
    pub fn of_slices(parts: &[&[f32]]) -> Self {
        let count: usize = parts.iter().map(|p| p.len()).sum();
        if count == 0 {
            return Indicators::default();
        }
        let n = count as f64;
        let mean = parts
            .iter()
            .flat_map(|p| p.iter())
            .map(|&x| f64::from(x))
            .sum::<f64>()
            / n;
        let (mut m2, mut m4, mut peak) = (0.0, 0.0, 0.0f64);
        for &x in parts.iter().flat_map(|p| p.iter()) {
            let d = f64::from(x) - mean;
            let d2 = d * d;
            m2 += d2;
            m4 += d2 * d2;
            peak = peak.max(d.abs());
        }
        let variance = m2 / n;
        let rms = variance.sqrt();
        Indicators {
            rms,
            peak,
            crest: if rms > 0.0 { peak / rms } else { 0.0 },
            kurtosis: if variance > 0.0 {
                (m4 / n) / (variance * variance)
            } else {
                0.0
            },
        }
    }

    pub fn of(samples: &[f32]) -> Self {
        Self::of_slices(&[samples])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sine_has_crest_sqrt2_and_kurtosis_one_and_a_half() {
        let x: Vec<f32> = (0..48_000)
            .map(|i| (std::f32::consts::TAU * 50.0 * i as f32 / 48_000.0).sin())
            .collect();
        let ind = Indicators::of(&x);
        assert!((ind.rms - 0.5f64.sqrt()).abs() < 1e-3);
        assert!((ind.crest - 2f64.sqrt()).abs() < 1e-2);
        assert!((ind.kurtosis - 1.5).abs() < 1e-2);
    }
}
