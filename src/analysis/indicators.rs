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

/// Independent partial sums per pass: the sums run over a whole window at every hop on the
/// analysis thread, and one long chain of dependent additions was its largest single cost
/// (docs/PERFORMANCE.md, alert latency).
const LANES: usize = 4;

/// Calls `each(lane, x)` for every sample of `parts`, lane by lane.
#[inline(always)]
fn for_each_lane(parts: &[&[f32]], mut each: impl FnMut(usize, f32)) {
    for part in parts {
        let chunks = part.chunks_exact(LANES);
        let rest = chunks.remainder();
        for chunk in chunks {
            for (lane, &x) in chunk.iter().enumerate() {
                each(lane, x);
            }
        }
        for (lane, &x) in rest.iter().enumerate() {
            each(lane, x);
        }
    }
}

/// `Σ x` over `parts` in f64, in independent partial sums.
pub fn sum_of(parts: &[&[f32]]) -> f64 {
    let mut sums = [0.0f64; LANES];
    for_each_lane(parts, |lane, x| sums[lane] += f64::from(x));
    sums.iter().sum()
}

impl Indicators {
    /// Indicators of `samples`, which may come as several slices (a ring buffer's halves).
    pub fn of_slices(parts: &[&[f32]]) -> Self {
        let count: usize = parts.iter().map(|p| p.len()).sum();
        if count == 0 {
            return Indicators::default();
        }
        let n = count as f64;
        let mean = sum_of(parts) / n;
        let (mut m2, mut m4, mut peaks) = ([0.0f64; LANES], [0.0f64; LANES], [0.0f64; LANES]);
        for_each_lane(parts, |lane, x| {
            let d = f64::from(x) - mean;
            let d2 = d * d;
            m2[lane] += d2;
            m4[lane] += d2 * d2;
            peaks[lane] = peaks[lane].max(d.abs());
        });
        let (m2, m4) = (m2.iter().sum::<f64>(), m4.iter().sum::<f64>());
        let peak = peaks.iter().copied().fold(0.0, f64::max);
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

    #[test]
    fn however_the_window_is_cut_the_indicators_match_the_plain_two_pass_sums() {
        let x: Vec<f32> = (0..10_007)
            .map(|i| {
                ((i * 7919 % 1000) as f32 / 500.0 - 1.0) * if i % 97 == 0 { 8.0 } else { 1.0 } + 0.3
            })
            .collect();
        let n = x.len() as f64;
        let mean = x.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let d: Vec<f64> = x.iter().map(|&v| f64::from(v) - mean).collect();
        let variance = d.iter().map(|v| v * v).sum::<f64>() / n;
        let kurtosis = d.iter().map(|v| v.powi(4)).sum::<f64>() / n / (variance * variance);
        let peak = d.iter().fold(0.0f64, |p, v| p.max(v.abs()));
        for cut in [0, 1, 3, 4, 5, 5_000, 10_006, 10_007] {
            let ind = Indicators::of_slices(&[&x[..cut], &x[cut..]]);
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
            assert!(close(ind.rms, variance.sqrt()), "cut {cut}: {ind:?}");
            assert!(close(ind.kurtosis, kurtosis), "cut {cut}: {ind:?}");
            assert_eq!(ind.peak, peak, "cut {cut}");
        }
        assert_eq!(Indicators::of_slices(&[&[], &[]]), Indicators::default());
    }
}
