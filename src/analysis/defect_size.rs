//! The length of a race defect from the time between its entry and exit events (issue 30),
//! measured only where the record can resolve them: at 40 kHz and above.
//!
//! A rolling element crossing a race defect of length `L` makes two events `Δt = Z·L/(2π r f_d)`
//! apart (MODELS.md §4; [`BearingGeometry::defect_length_mm`] is the inverse): it unloads as it
//! enters and is reloaded, or strikes, as it leaves (Sawalhi & Randall 2011). For the SKF 6205 at
//! 1800 rpm that is 0.57 ms per mm; at 12 kHz a 0.2 mm defect's events lie 1.4 samples apart,
//! inside one ring of the resonance (docs/DIAGNOSIS.md §5), which is why we do not try below
//! [`MIN_SAMPLE_RATE_HZ`].
//!
//! # How (each step chosen by measurement on the physics twin, DIAGNOSIS.md §5)
//!
//! 1. **Find the impacts**: the record's analytic signal in the fault's band; its envelope's
//!    maximum in each fault period (searched ±¼ period around the last one plus a period, so
//!    slip is followed). Only the strong ones (≥ half the 90th percentile) are kept: an
//!    inner-race defect strikes hard only in the load zone.
//! 2. **Synchronous average**: a segment of 0.9 periods around each impact, aligned to the
//!    average by the sub-sample peak of their cross-correlation in the band (two passes), then
//!    averaged: the thousands of impacts add coherently, the noise does not. Averaging at the
//!    nominal period instead smears: 1 % slip walks the impacts by many samples over a record.
//! 3. **Whitening**: an AR model of order `fs/3000` (16 at 48 kHz; Yule–Walker) of the
//!    *average* removes the structure's ringing, so what remains is where force enters: the
//!    entry and the exit. Fitted on the whole record instead, the model whitens the noise floor
//!    more than the resonance, and the ringing left over made a false "exit" 0.4 ms after a
//!    single event (0.3 mm read as 0.53 mm, 0.1 mm as 1.2 mm).
//! 4. **Events**: the envelope of the whitened average, each frequency weighted by how far the
//!    average stands above the impact-to-impact spread there (a Wiener weight: the whitening
//!    would otherwise lift the bare noise of the high frequencies), above 1 kHz, smoothed over
//!    ±1 sample at 48 kHz. The two most prominent peaks are the entry and the exit.
//! 5. **Only when clear**: the second event's prominence must be ≥ ¼ of the first's and ≥ 3×
//!    the envelope's median; no third peak may come within 0.7 of the second (else which pair
//!    is meant is a guess); in each of 4 interleaved sub-averages both events must stand ≥ 2.5×
//!    that sub-average's median, and the 4 spacings must agree within 25 %.
//!
//! The uncertainty combines the spread of the sub-averages' spacings (standard error of their
//! mean), the sample grid, and half the main event's half-width at half maximum: the peaks of
//! two events closer than about their width pull towards each other, which is where the
//! twin's largest errors (−10 … −20 %) are.
//!
//! What we tried and dropped: the power cepstrum of the average (its echo peak drowns in the
//! resonance's own cepstrum: no peak at the spacing for 0.1–1 mm at a 3 kHz resonance), and
//! the whitened envelope without the Wiener weight (reported 34 of the 96 grid records where
//! the chosen method reports 48, with the same error).
//!
//! Sans-IO: samples in, a size or the reason there is none out; no clock, no file.

use super::band::Band;
use super::diagnosis::Verdict;
use super::record::RecordAnalysis;
use crate::bearing::{BearingGeometry, FaultKind, Race};
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;
use serde::Serialize;
use std::f64::consts::TAU;

/// Below this sample rate the entry and exit of a defect under about 1 mm lie within a few
/// samples and one ring of the resonance: no size is reported.
pub const MIN_SAMPLE_RATE_HZ: f64 = 40_000.0;

/// What [`measure_defect_size`] reports in `method`.
pub const METHOD: &str = "entry-exit spacing in the AR-whitened synchronous average";

/// Impacts needed: 4 sub-averages of at least 4.
const MIN_IMPACTS: usize = 16;
/// Sub-averages the spacing is checked on.
const SUB_AVERAGES: usize = 4;
/// The longest defect searched for, mm.
const MAX_LENGTH_MM: f64 = 3.0;
/// Frequencies below this carry the structure's slow modes, not the events, Hz.
const HIGH_PASS_HZ: f64 = 1_000.0;
/// The second event's prominence against the first's and against the envelope's median.
const MIN_PROMINENCE_RATIO: f64 = 0.25;
const MIN_PROMINENCE_OVER_MEDIAN: f64 = 3.0;
/// A third peak this close (in prominence) to the second makes the pair ambiguous.
const MAX_THIRD_RATIO: f64 = 0.7;
/// Each sub-average's events against its envelope's median.
const MIN_SUB_EVENT_OVER_MEDIAN: f64 = 2.5;
/// The sub-averages' spacings may scatter by this fraction of the spacing (std).
const MAX_SUB_SPREAD: f64 = 0.25;

/// A measured defect length.
#[derive(Debug, Clone, Serialize)]
pub struct DefectSize {
    /// Circumferential length of the defect, mm.
    pub value_mm: f64,
    /// One standard uncertainty, mm.
    pub uncertainty_mm: f64,
    /// The entry-to-exit time it comes from, s.
    pub delay_s: f64,
    /// Impacts averaged.
    pub impacts: usize,
    pub method: &'static str,
}

/// Why no size is reported. Each message says what would make one possible.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NotMeasured {
    #[error("needs ≥ 40 kHz; this record is {} kHz", fmt_khz(*.fs_hz))]
    SampleRateTooLow { fs_hz: f64 },
    #[error(
        "only a race defect (outer or inner) has an entry and an exit to time; the verdict is {0}"
    )]
    NotARaceFault(&'static str),
    #[error("{0} is not usable for sizing")]
    BadInput(String),
    #[error("only {found} clear impacts in the record, {needed} needed; give a longer record")]
    TooFewImpacts { found: usize, needed: usize },
    #[error("the entry and exit events are not found clearly: {0}")]
    NotResolved(String),
}

fn fmt_khz(fs_hz: f64) -> String {
    let khz = fs_hz / 1e3;
    if (khz - khz.round()).abs() < 0.05 {
        format!("{khz:.0}")
    } else {
        format!("{khz:.1}")
    }
}

/// The defect size of the race fault the verdict names, in the band and at the fitted fault
/// frequency the analysis found for it.
pub fn measure_in_analysis(
    signal: &[f32],
    analysis: &RecordAnalysis,
    bearing: &BearingGeometry,
) -> Result<DefectSize, NotMeasured> {
    match analysis.diagnosis.verdict {
        Verdict::OuterRace => measure_for_fault(signal, analysis, FaultKind::OuterRace, bearing),
        Verdict::InnerRace => measure_for_fault(signal, analysis, FaultKind::InnerRace, bearing),
        other => Err(NotMeasured::NotARaceFault(other.name())),
    }
}

/// The defect size of `fault`, whatever the verdict, in the band and at the fitted frequency
/// of its hypothesis (the validation on the twin sizes every race defect it simulates).
pub fn measure_for_fault(
    signal: &[f32],
    analysis: &RecordAnalysis,
    fault: FaultKind,
    bearing: &BearingGeometry,
) -> Result<DefectSize, NotMeasured> {
    let hypothesis = analysis
        .hypotheses
        .iter()
        .find(|h| h.score.fault == fault)
        .ok_or(NotMeasured::NotARaceFault(fault.name()))?;
    measure_defect_size(
        signal,
        analysis.fs_hz,
        fault,
        hypothesis.score.frequency_hz,
        analysis.scan.bands[hypothesis.band_index].band,
        bearing,
    )
}

/// Measures the length of the `fault` (outer or inner race) defect whose impacts repeat at
/// `fault_hz` and show in `band`. See the module documentation for how and when.
pub fn measure_defect_size(
    signal: &[f32],
    fs_hz: f64,
    fault: FaultKind,
    fault_hz: f64,
    band: Band,
    bearing: &BearingGeometry,
) -> Result<DefectSize, NotMeasured> {
    let race = match fault {
        FaultKind::OuterRace => Race::Outer,
        FaultKind::InnerRace => Race::Inner,
        other => return Err(NotMeasured::NotARaceFault(other.name())),
    };
    if !(fs_hz.is_finite() && fs_hz > 0.0) {
        return Err(NotMeasured::BadInput(format!("sample rate {fs_hz} Hz")));
    }
    if fs_hz < MIN_SAMPLE_RATE_HZ {
        return Err(NotMeasured::SampleRateTooLow { fs_hz });
    }
    if !(fault_hz.is_finite() && fault_hz > 0.0 && fault_hz < fs_hz / 64.0) {
        return Err(NotMeasured::BadInput(format!(
            "fault frequency {fault_hz} Hz"
        )));
    }
    if !(band.lo_hz >= 0.0 && band.hi_hz > band.lo_hz && band.hi_hz <= fs_hz / 2.0 + 1e-9) {
        return Err(NotMeasured::BadInput(format!("band {band}")));
    }
    let mut fft = Fft::default();
    let period = fs_hz / fault_hz;
    let len = (0.9 * period) as usize;
    let averaged = Average::of(&mut fft, signal, fs_hz, band, period, len)?;
    let whitened = averaged.whitened(fs_hz);
    let events = Events {
        fs_hz,
        weights: &averaged.wiener_weights(&mut fft),
        max_delay: (bearing.entry_exit_delay_s(race, MAX_LENGTH_MM, fault_hz) * fs_hz)
            .min(0.4 * len as f64) as usize,
        min_separation: ((3.0 * fs_hz / 48_000.0).round() as usize).max(2),
    };
    let envelope = events.envelope(&mut fft, &mean_of(whitened.iter()));
    let pair = events.pair(&envelope)?;
    let spacings = events.sub_average_spacings(&mut fft, &whitened, pair)?;
    let delay = (pair.exit - pair.entry) / fs_hz;
    let delays: Vec<f64> = spacings.iter().map(|s| s / fs_hz).collect();
    let (mean, std) = mean_std(&delays);
    if std > MAX_SUB_SPREAD * delay {
        return Err(NotMeasured::NotResolved(format!(
            "the spacing in {SUB_AVERAGES} sub-averages scatters by {:.0} % ({:.3} ± {:.3} ms)",
            100.0 * std / delay,
            mean * 1e3,
            std * 1e3
        )));
    }
    let k = delays.len() as f64;
    let sample_s = 1.0 / fs_hz;
    let variance = std * std * k / (k - 1.0) / k
        + sample_s * sample_s / 6.0
        + (0.5 * pair.half_width / fs_hz).powi(2);
    let to_mm = |delay_s: f64| bearing.defect_length_mm(race, delay_s, fault_hz);
    Ok(DefectSize {
        value_mm: to_mm(delay),
        uncertainty_mm: to_mm(variance.sqrt()),
        delay_s: delay,
        impacts: whitened.len(),
        method: METHOD,
    })
}

/// Complex FFTs of any length, planned once per length.
struct Fft {
    planner: FftPlanner<f64>,
}

impl Default for Fft {
    fn default() -> Self {
        Fft {
            planner: FftPlanner::new(),
        }
    }
}

impl Fft {
    fn forward(&mut self, buf: &mut [Complex64]) {
        self.planner.plan_fft_forward(buf.len()).process(buf);
    }

    /// Inverse, scaled by 1/n.
    fn inverse(&mut self, buf: &mut [Complex64]) {
        self.planner.plan_fft_inverse(buf.len()).process(buf);
        let scale = 1.0 / buf.len() as f64;
        buf.iter_mut().for_each(|v| *v *= scale);
    }

    fn of_real(&mut self, x: &[f64]) -> Vec<Complex64> {
        let mut buf: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        self.forward(&mut buf);
        buf
    }
}

/// Signed frequency of bin `k` of an `n`-point FFT, in cycles per sample.
fn bin_frequency(k: usize, n: usize) -> f64 {
    if k <= (n - 1) / 2 {
        k as f64 / n as f64
    } else {
        k as f64 / n as f64 - 1.0
    }
}

/// `x` delayed by `delay` samples (fractional, circular), in the frequency domain.
fn delayed(fft: &mut Fft, x: &[Complex64], delay: f64) -> Vec<Complex64> {
    let n = x.len();
    let mut buf = x.to_vec();
    fft.forward(&mut buf);
    for (k, v) in buf.iter_mut().enumerate() {
        *v *= Complex64::from_polar(1.0, -TAU * bin_frequency(k, n) * delay);
    }
    fft.inverse(&mut buf);
    buf
}

fn mean_of<'a>(rows: impl Iterator<Item = &'a Vec<f64>>) -> Vec<f64> {
    let mut sum: Vec<f64> = Vec::new();
    let mut count = 0usize;
    for row in rows {
        if sum.is_empty() {
            sum = vec![0.0; row.len()];
        }
        sum.iter_mut().zip(row).for_each(|(s, v)| *s += v);
        count += 1;
    }
    sum.iter_mut().for_each(|s| *s /= count.max(1) as f64);
    sum
}

fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.get(sorted.len() / 2).copied().unwrap_or(0.0)
}

/// Index of the largest value in `values[range]` (clamped to the slice).
fn argmax(values: &[f64], from: usize, to: usize) -> usize {
    let to = to.min(values.len());
    (from.min(to)..to)
        .max_by(|&a, &b| values[a].total_cmp(&values[b]))
        .unwrap_or(from)
}

/// Sub-sample position of the peak at `i`: the vertex of the parabola through its neighbours.
fn vertex(values: &[f64], i: usize) -> f64 {
    if i == 0 || i + 1 >= values.len() {
        return i as f64;
    }
    let (a, b, c) = (values[i - 1], values[i], values[i + 1]);
    let curvature = a - 2.0 * b + c;
    if curvature == 0.0 {
        i as f64
    } else {
        i as f64 + 0.5 * (a - c) / curvature
    }
}

/// The aligned segments around the impacts: raw, for the whitening and the Wiener weights.
struct Average {
    segments: Vec<Vec<f64>>,
}

impl Average {
    fn of(
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
    fn whitened(&self, fs_hz: f64) -> Vec<Vec<f64>> {
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
    fn wiener_weights(&self, fft: &mut Fft) -> Vec<f64> {
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

/// A resolved entry and exit, in samples of the segment.
#[derive(Debug, Clone, Copy)]
struct Pair {
    entry: f64,
    exit: f64,
    /// Half-width at half maximum of the stronger event, samples.
    half_width: f64,
}

/// How the events are read off a whitened average.
struct Events<'a> {
    fs_hz: f64,
    weights: &'a [f64],
    max_delay: usize,
    min_separation: usize,
}

impl Events<'_> {
    /// The smoothed envelope of `x`, Wiener-weighted, above [`HIGH_PASS_HZ`].
    fn envelope(&self, fft: &mut Fft, x: &[f64]) -> Vec<f64> {
        let n = x.len();
        let mut buf = fft.of_real(x);
        for (k, v) in buf.iter_mut().enumerate() {
            let f = bin_frequency(k, n);
            let keep = f > 0.0 && f * self.fs_hz >= HIGH_PASS_HZ;
            *v *= if keep { 2.0 * self.weights[k] } else { 0.0 };
        }
        fft.inverse(&mut buf);
        let magnitude: Vec<f64> = buf.iter().map(|v| v.norm()).collect();
        let sigma = self.fs_hz / 48_000.0;
        let reach = (3.0 * sigma) as isize;
        let kernel: Vec<f64> = (-reach..=reach)
            .map(|i| (-0.5 * (i as f64 / sigma).powi(2)).exp())
            .collect();
        let total: f64 = kernel.iter().sum();
        (0..n as isize)
            .map(|i| {
                kernel
                    .iter()
                    .zip(-reach..)
                    .filter_map(|(w, d)| {
                        usize::try_from(i + d)
                            .ok()
                            .and_then(|j| magnitude.get(j))
                            .map(|m| w * m)
                    })
                    .sum::<f64>()
                    / total
            })
            .collect()
    }

    /// The entry and exit: the two most prominent peaks within the longest delay of the
    /// strongest event, if they are clear (module documentation, step 5).
    fn pair(&self, envelope: &[f64]) -> Result<Pair, NotMeasured> {
        let n = envelope.len();
        let strongest = argmax(envelope, n / 4, 3 * n / 4);
        let from = strongest.saturating_sub(self.max_delay).max(1);
        let to = (strongest + self.max_delay + 1).min(n - 1);
        let mut peaks: Vec<(usize, f64)> = (from..to)
            .filter(|&i| envelope[i] >= envelope[i - 1] && envelope[i] > envelope[i + 1])
            .map(|i| (i, prominence(&envelope[from - 1..=to], i + 1 - from)))
            .collect();
        peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
        let Some(&(first, first_prominence)) = peaks.first() else {
            return Err(NotMeasured::NotResolved("no event in the average".into()));
        };
        let mut others = peaks
            .iter()
            .filter(|(i, _)| i.abs_diff(first) >= self.min_separation);
        let floor = median(envelope);
        let Some(&(second, second_prominence)) = others.next() else {
            return Err(NotMeasured::NotResolved(
                "one event only (the entry and exit merge: the defect is shorter than the time resolution)".into(),
            ));
        };
        if second_prominence < MIN_PROMINENCE_RATIO * first_prominence
            || second_prominence < MIN_PROMINENCE_OVER_MEDIAN * floor
        {
            return Err(NotMeasured::NotResolved(format!(
                "one event only: the next one stands {:.1}× the strongest and {:.1}× the noise (needs {MIN_PROMINENCE_RATIO} and {MIN_PROMINENCE_OVER_MEDIAN})",
                second_prominence / first_prominence,
                second_prominence / floor
            )));
        }
        if let Some(&(_, third)) = others.next() {
            if third > MAX_THIRD_RATIO * second_prominence {
                return Err(NotMeasured::NotResolved(format!(
                    "a third event as strong ({:.0} % of the second) makes the pair ambiguous",
                    100.0 * third / second_prominence
                )));
            }
        }
        let half = 0.5 * envelope[first];
        let left = (0..first).rev().find(|&i| envelope[i] < half).unwrap_or(0);
        let right = (first..n).find(|&i| envelope[i] < half).unwrap_or(n - 1);
        let (a, b) = (first.min(second), first.max(second));
        Ok(Pair {
            entry: vertex(envelope, a),
            exit: vertex(envelope, b),
            half_width: 0.5 * (right - left) as f64,
        })
    }

    /// The spacing in each interleaved sub-average: the envelope's maximum within ±half the
    /// minimum separation of each event, both standing clear of that sub-average's noise.
    fn sub_average_spacings(
        &self,
        fft: &mut Fft,
        whitened: &[Vec<f64>],
        pair: Pair,
    ) -> Result<Vec<f64>, NotMeasured> {
        let reach = (self.min_separation / 2).max(2);
        (0..SUB_AVERAGES)
            .map(|k| {
                let envelope =
                    self.envelope(fft, &mean_of(whitened.iter().skip(k).step_by(SUB_AVERAGES)));
                let near = |at: f64| {
                    let centre = at.round() as usize;
                    argmax(&envelope, centre.saturating_sub(reach), centre + reach + 1)
                };
                let (entry, exit) = (near(pair.entry), near(pair.exit));
                let floor = median(&envelope);
                if envelope[entry].min(envelope[exit]) < MIN_SUB_EVENT_OVER_MEDIAN * floor {
                    return Err(NotMeasured::NotResolved(format!(
                        "the events do not stand out in every sub-average ({:.1}× the noise in one, needs {MIN_SUB_EVENT_OVER_MEDIAN})",
                        envelope[entry].min(envelope[exit]) / floor
                    )));
                }
                Ok(vertex(&envelope, exit) - vertex(&envelope, entry))
            })
            .collect()
    }
}

/// Prominence of the peak at `i` of `values`: its height above the higher of the lowest points
/// on either side before a higher value (or the slice's end).
fn prominence(values: &[f64], i: usize) -> f64 {
    let height = values[i];
    let mut left_base = height;
    for &v in values[..i].iter().rev() {
        if v > height {
            break;
        }
        left_base = left_base.min(v);
    }
    let mut right_base = height;
    for &v in &values[i + 1..] {
        if v > height {
            break;
        }
        right_base = right_base.min(v);
    }
    height - left_base.max(right_base)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::twin::{SimulatedFault, SimulationParams, Simulator};

    /// Two seconds of the signal model's race defect with entry and exit impacts `length_mm`
    /// apart (0: one impact per passage), resonance 3 kHz.
    fn signal_model(fault: SimulatedFault, fs_hz: f64, length_mm: f64) -> (Vec<f32>, f64) {
        let mut params = SimulationParams::example(fault);
        params.fs_hz = fs_hz;
        params.defect_length_mm = length_mm;
        params.noise_g = 0.1;
        let rate = params.impact_rate_hz();
        (Simulator::record(params, 2.0), rate)
    }

    fn size(
        signal: &[f32],
        fs_hz: f64,
        fault: FaultKind,
        rate: f64,
    ) -> Result<DefectSize, NotMeasured> {
        let bearing = BearingGeometry::from_catalog("skf-6205-2rs").unwrap();
        measure_defect_size(
            signal,
            fs_hz,
            fault,
            rate,
            Band::new(2_000.0, 4_000.0),
            &bearing,
        )
    }

    #[test]
    fn sizes_the_entry_and_exit_the_signal_model_draws() {
        let mut sized = 0;
        for (fault, kind) in [
            (SimulatedFault::OuterRace, FaultKind::OuterRace),
            (SimulatedFault::InnerRace, FaultKind::InnerRace),
        ] {
            for length_mm in [0.5, 1.0, 2.0] {
                let (signal, rate) = signal_model(fault, 48_000.0, length_mm);
                match size(&signal, 48_000.0, kind, rate) {
                    Ok(found) => {
                        let error = (found.value_mm - length_mm) / length_mm;
                        assert!(
                            error.abs() < 0.1 && found.uncertainty_mm > 0.0,
                            "{kind:?} {length_mm} mm: {found:?}"
                        );
                        assert_eq!(found.method, METHOD);
                        sized += 1;
                    }
                    // Refusing is allowed (0.5 mm on the outer race: a third peak as strong
                    // as the exit); a wrong number is not.
                    Err(NotMeasured::NotResolved(_)) => {}
                    Err(other) => panic!("{kind:?} {length_mm} mm: {other}"),
                }
            }
        }
        assert!(sized >= 5, "only {sized} of 6 sized");
    }

    #[test]
    fn one_event_per_passage_is_not_sized() {
        let (signal, rate) = signal_model(SimulatedFault::OuterRace, 48_000.0, 0.0);
        let found = size(&signal, 48_000.0, FaultKind::OuterRace, rate);
        assert!(
            matches!(found, Err(NotMeasured::NotResolved(_))),
            "{found:?}"
        );
    }

    #[test]
    fn noise_alone_is_not_sized() {
        let mut rng = crate::random::Rng::new(3);
        let signal: Vec<f32> = (0..96_000).map(|_| (0.2 * rng.normal()) as f32).collect();
        let found = size(&signal, 48_000.0, FaultKind::OuterRace, 107.0);
        assert!(found.is_err(), "{found:?}");
    }

    #[test]
    fn below_40_khz_the_reason_says_so() {
        let (signal, rate) = signal_model(SimulatedFault::OuterRace, 12_000.0, 2.0);
        let found = size(&signal, 12_000.0, FaultKind::OuterRace, rate);
        assert_eq!(
            found.unwrap_err().to_string(),
            "needs ≥ 40 kHz; this record is 12 kHz"
        );
    }

    #[test]
    fn only_race_defects_have_a_size() {
        let (signal, rate) = signal_model(SimulatedFault::Ball, 48_000.0, 1.0);
        for fault in [FaultKind::Ball, FaultKind::Cage] {
            let found = size(&signal, 48_000.0, fault, rate);
            assert!(
                matches!(found, Err(NotMeasured::NotARaceFault(_))),
                "{found:?}"
            );
        }
    }

    #[test]
    fn unusable_inputs_are_errors_not_panics() {
        let (signal, rate) = signal_model(SimulatedFault::OuterRace, 48_000.0, 1.0);
        for (fs, f, band) in [
            (f64::NAN, rate, Band::new(2e3, 4e3)),
            (48e3, 0.0, Band::new(2e3, 4e3)),
            (48e3, rate, Band::new(4e3, 2e3)),
            (48e3, rate, Band::new(2e3, 40e3)),
        ] {
            let bearing = BearingGeometry::from_catalog("skf-6205-2rs").unwrap();
            let found = measure_defect_size(&signal, fs, FaultKind::OuterRace, f, band, &bearing);
            assert!(matches!(found, Err(NotMeasured::BadInput(_))), "{found:?}");
        }
        let short = size(&signal[..1_000], 48_000.0, FaultKind::OuterRace, rate);
        assert!(
            matches!(short, Err(NotMeasured::TooFewImpacts { .. })),
            "{short:?}"
        );
        assert!(size(&[], 48_000.0, FaultKind::OuterRace, rate).is_err());
    }
}
