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
        Moments::of(parts).indicators()
    }

    pub fn of(samples: &[f32]) -> Self {
        Self::of_slices(&[samples])
    }
}

/// Mean, central moment sums (`Σ(x−μ)^k`, k = 2, 3, 4) and extremes of a run of samples: a
/// summary two runs merge into the summary of both (Pébay 2008, "Formulas for robust, one-pass
/// parallel computation of covariances and arbitrary-order statistical moments").
#[derive(Debug, Clone, Copy)]
struct Moments {
    count: f64,
    mean: f64,
    m2: f64,
    m3: f64,
    m4: f64,
    min: f32,
    max: f32,
}

impl Moments {
    /// Two passes (the mean, then the sums about it), as [`Indicators::of_slices`] does.
    fn of(parts: &[&[f32]]) -> Self {
        let count = parts.iter().map(|p| p.len()).sum::<usize>() as f64;
        let mean = sum_of(parts) / count.max(1.0);
        let (mut m2, mut m3, mut m4) = ([0.0f64; LANES], [0.0f64; LANES], [0.0f64; LANES]);
        for_each_lane(parts, |lane, x| {
            let d = f64::from(x) - mean;
            let d2 = d * d;
            m2[lane] += d2;
            m3[lane] += d2 * d;
            m4[lane] += d2 * d2;
        });
        let (min, max) = extremes(parts);
        Moments {
            count,
            mean,
            m2: m2.iter().sum(),
            m3: m3.iter().sum(),
            m4: m4.iter().sum(),
            min,
            max,
        }
    }

    /// The summary of `self`'s samples followed by `later`'s.
    fn merge(self, later: Moments) -> Moments {
        let (na, nb) = (self.count, later.count);
        let n = na + nb;
        if na == 0.0 || nb == 0.0 {
            return if na == 0.0 { later } else { self };
        }
        let delta = later.mean - self.mean;
        let (d2, d3, d4) = (
            delta * delta,
            delta * delta * delta,
            delta * delta * delta * delta,
        );
        Moments {
            count: n,
            mean: self.mean + delta * nb / n,
            m2: self.m2 + later.m2 + d2 * na * nb / n,
            m3: self.m3
                + later.m3
                + d3 * na * nb * (na - nb) / (n * n)
                + 3.0 * delta * (na * later.m2 - nb * self.m2) / n,
            m4: self.m4
                + later.m4
                + d4 * na * nb * (na * na - na * nb + nb * nb) / (n * n * n)
                + 6.0 * d2 * (na * na * later.m2 + nb * nb * self.m2) / (n * n)
                + 4.0 * delta * (na * later.m3 - nb * self.m3) / n,
            min: self.min.min(later.min),
            max: self.max.max(later.max),
        }
    }

    fn indicators(&self) -> Indicators {
        if self.count == 0.0 {
            return Indicators::default();
        }
        let variance = self.m2 / self.count;
        let rms = variance.sqrt();
        // |x − μ| is largest at an extreme, and rounding keeps that order.
        let peak = (f64::from(self.max) - self.mean)
            .abs()
            .max((f64::from(self.min) - self.mean).abs());
        Indicators {
            rms,
            peak,
            crest: if rms > 0.0 { peak / rms } else { 0.0 },
            kurtosis: if variance > 0.0 {
                (self.m4 / self.count) / (variance * variance)
            } else {
                0.0
            },
        }
    }
}

/// Below this many samples per segment, [`WindowIndicators`] sums every window whole: the
/// cache would be longer than it saves.
const MIN_SEGMENT: usize = 256;

/// The indicators of overlapping windows, each sample summed once instead of once per window
/// it falls in: a window is cut into segments of `gcd(window, hop)` samples, a segment's
/// summary is kept (by its first sample) while windows still cover it, and a window's
/// indicators merge its segments' summaries. At the daemon's default (1 s windows, half
/// overlap) this halves the indicators' cost per window; at 7/8 overlap it divides it by 8.
///
/// The result depends only on the window's samples, not on what was computed before, so a
/// replay gives the same numbers as the run it replays. It equals the whole-window sums
/// ([`Indicators::of_slices`]) to rounding (relative 1e-12; the peak exactly).
pub struct WindowIndicators {
    /// Samples per segment; 0 when windows are summed whole.
    segment: usize,
    /// The summary of each segment of the newest window, by first sample, at the slot
    /// `(first sample / segment) % slots`.
    cached: Vec<Option<(u64, Moments)>>,
}

impl WindowIndicators {
    pub fn new(window: usize, hop: usize) -> Self {
        let segment = gcd(window, hop.max(1));
        let segment = if segment >= MIN_SEGMENT { segment } else { 0 };
        WindowIndicators {
            segment,
            cached: vec![None; window.checked_div(segment).unwrap_or(0)],
        }
    }

    /// Forgets every summary: after a jump in sample time, sample indices seen before may
    /// come again with other samples.
    pub fn restart(&mut self) {
        self.cached.fill(None);
    }

    /// The indicators of the window of `older` followed by `newer` (a ring buffer's halves),
    /// which ends one before sample `end_sample`.
    pub fn of_window(&mut self, end_sample: u64, (older, newer): (&[f32], &[f32])) -> Indicators {
        let window = older.len() + newer.len();
        let segment = self.segment;
        if segment == 0 || window != self.cached.len() * segment {
            return Indicators::of_slices(&[older, newer]);
        }
        let start = end_sample.saturating_sub(window as u64);
        let slots = self.cached.len();
        let mut whole: Option<Moments> = None;
        for j in 0..slots {
            let first = start + (j * segment) as u64;
            let slot = (first / segment as u64) as usize % slots;
            let moments = match self.cached[slot] {
                Some((at, moments)) if at == first => moments,
                _ => {
                    let (from, to) = (j * segment, (j + 1) * segment);
                    let moments = Moments::of(&range_of(older, newer, from, to));
                    self.cached[slot] = Some((first, moments));
                    moments
                }
            };
            whole = Some(whole.map_or(moments, |w| w.merge(moments)));
        }
        whole.map_or_else(Indicators::default, |w| w.indicators())
    }
}

/// The smallest and the largest sample of `parts` (NaN ignored). Written as comparisons in
/// independent lanes, which the compiler turns into vector min/max (`f32::min` is not, for its
/// NaN rule).
fn extremes(parts: &[&[f32]]) -> (f32, f32) {
    const WIDE: usize = 8;
    let (mut min, mut max) = ([f32::INFINITY; WIDE], [f32::NEG_INFINITY; WIDE]);
    for part in parts {
        let chunks = part.chunks_exact(WIDE);
        let rest = chunks.remainder();
        for chunk in chunks {
            for ((lo, hi), &x) in min.iter_mut().zip(max.iter_mut()).zip(chunk) {
                *lo = if x < *lo { x } else { *lo };
                *hi = if x > *hi { x } else { *hi };
            }
        }
        for (lane, &x) in rest.iter().enumerate() {
            min[lane] = if x < min[lane] { x } else { min[lane] };
            max[lane] = if x > max[lane] { x } else { max[lane] };
        }
    }
    (
        min.iter().copied().fold(f32::INFINITY, f32::min),
        max.iter().copied().fold(f32::NEG_INFINITY, f32::max),
    )
}

/// Samples `from..to` of `older` followed by `newer`, as two slices.
fn range_of<'a>(older: &'a [f32], newer: &'a [f32], from: usize, to: usize) -> [&'a [f32]; 2] {
    let split = older.len();
    [
        &older[from.min(split)..to.min(split)],
        &newer[from.max(split) - split..to.max(split) - split],
    ]
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
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

    /// A test signal with impacts and an offset, as a sensor gives.
    fn impacts(len: usize, seed: usize) -> Vec<f32> {
        (0..len)
            .map(|i| {
                let j = i + seed;
                ((j * 7919 % 1000) as f32 / 500.0 - 1.0)
                    * if j.is_multiple_of(97) { 8.0 } else { 1.0 }
                    + 0.3
            })
            .collect()
    }

    #[test]
    fn merged_segments_give_the_whole_window_sums_to_rounding() {
        let x = impacts(40_000, 0);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        for (window, hop) in [(4_096, 512), (4_096, 2_048), (8_192, 3_072), (4_096, 100)] {
            let mut windows = WindowIndicators::new(window, hop);
            let mut end = window;
            while end <= x.len() {
                // The window as a ring buffer holds it: cut at a moving place.
                let cut = (end / hop * 977) % window;
                let samples = &x[end - window..end];
                let whole = Indicators::of(samples);
                let got = windows.of_window(end as u64, (&samples[..cut], &samples[cut..]));
                assert!(
                    close(got.rms, whole.rms),
                    "{window}/{hop} at {end}: {got:?} {whole:?}"
                );
                assert!(
                    close(got.kurtosis, whole.kurtosis),
                    "{window}/{hop} at {end}"
                );
                assert!(close(got.crest, whole.crest), "{window}/{hop} at {end}");
                assert_eq!(got.peak, whole.peak, "{window}/{hop} at {end}");
                end += hop;
            }
        }
    }

    #[test]
    fn a_window_after_a_restart_is_summed_from_its_own_samples() {
        let (a, b) = (impacts(4_096, 0), impacts(4_096, 31));
        let mut windows = WindowIndicators::new(4_096, 1_024);
        windows.of_window(4_096, (&a, &[]));
        // The same sample indices again, with other samples (a replay going back).
        windows.restart();
        let again = windows.of_window(4_096, (&b, &[]));
        assert_eq!(again.peak, Indicators::of(&b).peak);
        assert!((again.rms - Indicators::of(&b).rms).abs() <= 1e-12 * again.rms);
    }
}
