//! The synchronous average of a race defect's impacts: found in the fault's band, aligned to
//! a sub-sample by cross-correlation, and whitened by the AR model of their average (steps 1–3
//! of the parent module's documentation).

use super::{argmax, bin_frequency, delayed, mean_of, Fft, NotMeasured, MIN_IMPACTS};
use crate::analysis::band::Band;
use rustfft::num_complex::Complex64;
use std::f64::consts::TAU;

/// The aligned segments around the impacts: raw, for the whitening and the Wiener weights.
pub(super) struct Average {
    segments: Vec<Vec<f64>>,
}

impl Average {
    pub(super) fn of(
        fft: &mut Fft,
        signal: &[f32],
        fs_hz: f64,
        band: Band,
        period: f64,
        len: usize,
    ) -> Result<Self, NotMeasured> {
        let n = signal.len();
        let mean = signal.iter().map(|&v| f64::from(v)).sum::<f64>() / n.max(1) as f64;
        let x: Vec<f64> = signal.iter().map(|&v| f64::from(v) - mean).collect();
        let analytic = analytic_in_band(fft, &x, fs_hz, band);
        let envelope: Vec<f64> = analytic.iter().map(|v| v.norm()).collect();
        let impacts = strong_impacts(&envelope, period, len);
        if impacts.len() < MIN_IMPACTS {
            return Err(NotMeasured::TooFewImpacts {
                found: impacts.len(),
                needed: MIN_IMPACTS,
            });
        }
        let before = len / 2;
        let band_segments: Vec<Vec<Complex64>> = impacts
            .iter()
            .map(|&i| analytic[i - before..i - before + len].to_vec())
            .collect();
        let shifts = alignment(fft, &band_segments);
        let segments = impacts
            .iter()
            .zip(&shifts)
            .map(|(&i, &shift)| {
                let raw: Vec<Complex64> = x[i - before..i - before + len]
                    .iter()
                    .map(|&v| Complex64::new(v, 0.0))
                    .collect();
                delayed(fft, &raw, -shift).iter().map(|v| v.re).collect()
            })
            .collect();
        Ok(Average { segments })
    }

    /// Each aligned segment through the whitening filter of the average's AR model.
    pub(super) fn whitened(&self, fs_hz: f64) -> Vec<Vec<f64>> {
        let order = ((fs_hz / 3_000.0).round() as usize).clamp(8, 64);
        let average = mean_of(self.segments.iter());
        let a = ar_whitener(&average, order);
        self.segments
            .iter()
            .map(|s| {
                (0..s.len())
                    .map(|n| {
                        if n < order {
                            0.0
                        } else {
                            a.iter().enumerate().map(|(k, ak)| ak * s[n - k]).sum()
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// Per frequency bin, `1 − noise/signal` (clamped to 0…1): the power of the average over
    /// the standard error of the mean from the impact-to-impact spread, both smoothed over 5
    /// bins.
    pub(super) fn wiener_weights(&self, fft: &mut Fft) -> Vec<f64> {
        let spectra: Vec<Vec<Complex64>> = self.segments.iter().map(|s| fft.of_real(s)).collect();
        let len = spectra.first().map_or(0, Vec::len);
        let count = spectra.len().max(1) as f64;
        let mut signal = vec![0.0; len];
        let mut noise = vec![0.0; len];
        for k in 0..len {
            let mean = spectra.iter().map(|s| s[k]).sum::<Complex64>() / count;
            signal[k] = mean.norm_sqr();
            noise[k] = spectra
                .iter()
                .map(|s| (s[k] - mean).norm_sqr())
                .sum::<f64>()
                / count
                / count;
        }
        let smooth = |v: &[f64]| -> Vec<f64> {
            (0..v.len())
                .map(|k| {
                    v[k.saturating_sub(2)..(k + 3).min(v.len())]
                        .iter()
                        .sum::<f64>()
                        / 5.0
                })
                .collect()
        };
        let (signal, noise) = (smooth(&signal), smooth(&noise));
        signal
            .iter()
            .zip(&noise)
            .map(|(s, n)| {
                if *s > 0.0 {
                    (1.0 - n / s).clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// The analytic signal of `x` restricted to `band`, by one FFT of the whole record.
fn analytic_in_band(fft: &mut Fft, x: &[f64], fs_hz: f64, band: Band) -> Vec<Complex64> {
    let n = x.len();
    let mut buf = fft.of_real(x);
    for (k, v) in buf.iter_mut().enumerate() {
        let f = bin_frequency(k, n) * fs_hz;
        *v *= if f >= band.lo_hz && f <= band.hi_hz && f > 0.0 {
            2.0
        } else {
            0.0
        };
    }
    fft.inverse(&mut buf);
    buf
}

/// The envelope's maximum in each fault period, followed from period to period (±¼ period),
/// keeping those at least half the 90th percentile and with a whole segment of `len` around.
fn strong_impacts(envelope: &[f64], period: f64, len: usize) -> Vec<usize> {
    let n = envelope.len();
    let mut found = Vec::new();
    let mut at = argmax(envelope, 0, period as usize) as f64;
    while (at as usize) < n {
        let from = (at - 0.25 * period).max(0.0) as usize;
        let to = ((at + 0.25 * period) as usize).min(n);
        if to <= from {
            break;
        }
        let peak = argmax(envelope, from, to);
        found.push(peak);
        at = peak as f64 + period;
    }
    let mut amplitudes: Vec<f64> = found.iter().map(|&i| envelope[i]).collect();
    amplitudes.sort_by(f64::total_cmp);
    let p90 = amplitudes
        .get((0.9 * amplitudes.len() as f64) as usize)
        .copied()
        .unwrap_or(0.0);
    let before = len / 2;
    found
        .into_iter()
        .filter(|&i| envelope[i] >= 0.5 * p90 && i >= before && i - before + len <= n)
        .collect()
}

/// Each segment's delay against the average, in samples: the sub-sample peak of the circular
/// cross-correlation magnitude, re-averaged once with the delays undone.
fn alignment(fft: &mut Fft, segments: &[Vec<Complex64>]) -> Vec<f64> {
    let len = segments.first().map_or(0, Vec::len);
    let spectra: Vec<Vec<Complex64>> = segments
        .iter()
        .map(|s| {
            let mut b = s.clone();
            fft.forward(&mut b);
            b
        })
        .collect();
    let mut reference = mean_spectrum(&spectra, &vec![0.0; spectra.len()]);
    let mut shifts = vec![0.0; spectra.len()];
    for _ in 0..2 {
        for (shift, spectrum) in shifts.iter_mut().zip(&spectra) {
            let mut cross: Vec<Complex64> = reference
                .iter()
                .zip(spectrum)
                .map(|(r, s)| r.conj() * s)
                .collect();
            fft.inverse(&mut cross);
            let magnitude: Vec<f64> = cross.iter().map(|v| v.norm()).collect();
            let k = argmax(&magnitude, 0, len);
            let wrap = |i: isize| magnitude[i.rem_euclid(len as isize) as usize];
            let (a, b, c) = (wrap(k as isize - 1), magnitude[k], wrap(k as isize + 1));
            let curvature = a - 2.0 * b + c;
            let mut lag = k as f64
                + if curvature == 0.0 {
                    0.0
                } else {
                    0.5 * (a - c) / curvature
                };
            if lag > len as f64 / 2.0 {
                lag -= len as f64;
            }
            *shift = lag;
        }
        reference = mean_spectrum(&spectra, &shifts);
    }
    shifts
}

/// The mean of `spectra`, each advanced by its shift (samples).
fn mean_spectrum(spectra: &[Vec<Complex64>], shifts: &[f64]) -> Vec<Complex64> {
    let len = spectra.first().map_or(0, Vec::len);
    let mut mean = vec![Complex64::new(0.0, 0.0); len];
    for (spectrum, shift) in spectra.iter().zip(shifts) {
        for (k, (m, v)) in mean.iter_mut().zip(spectrum).enumerate() {
            *m += v * Complex64::from_polar(1.0, TAU * bin_frequency(k, len) * shift);
        }
    }
    let count = spectra.len().max(1) as f64;
    mean.iter_mut().for_each(|m| *m /= count);
    mean
}

/// The prediction-error filter `[1, a₁, …, a_p]` of the Yule–Walker AR model of `x`
/// (Levinson–Durbin on the biased autocorrelation).
fn ar_whitener(x: &[f64], order: usize) -> Vec<f64> {
    let n = x.len();
    let mean = x.iter().sum::<f64>() / n.max(1) as f64;
    let r: Vec<f64> = (0..=order)
        .map(|lag| {
            (lag..n)
                .map(|i| (x[i] - mean) * (x[i - lag] - mean))
                .sum::<f64>()
                / n.max(1) as f64
        })
        .collect();
    let mut a = vec![0.0; order + 1];
    a[0] = 1.0;
    let mut error = r[0];
    for k in 1..=order {
        if error <= 0.0 {
            break;
        }
        let acc: f64 = (0..k).map(|j| a[j] * r[k - j]).sum();
        let reflection = -acc / error;
        let previous = a.clone();
        for j in 1..k {
            a[j] = previous[j] + reflection * previous[k - j];
        }
        a[k] = reflection;
        error *= 1.0 - reflection * reflection;
    }
    a
}
