//! The shaft speed estimated from the vibration itself, near a nominal speed (MODELS.md §1: every
//! fault frequency is a multiple of the shaft rate, so a speed a few per cent off moves every
//! fault line out of its ±2 % search window).
//!
//! Method (choice): a harmonic sum. The Hann-windowed amplitude spectrum of the whole signal
//! (10 s give 0.1 Hz bins) is whitened harmonic by harmonic: around `k·f_nominal` each bin is
//! divided by the median of the search region, so a machine line's absolute level does not
//! matter, only how far it stands out of its neighbourhood. For each candidate `f` on a grid
//! over `f_nominal·(1 ± range)` the sum over `k = 1..=HARMONICS` of `ln(max(1, whitened(k·f)))`
//! is formed; the best candidate is refined by a parabola through it and its grid neighbours.
//! A log sum needs several harmonics to line up: one strong line that falls under a single
//! harmonic (the 60 Hz mains line near the second harmonic of a 1750 rpm shaft) cannot win alone.
//!
//! The best candidate is then refined from the harmonics' own peaks (see `refine`). The
//! estimate is refused (`None`) when the best candidate does not stand out of the other
//! candidates (`prominence`, its sum over the median sum, below [`MIN_PROMINENCE`]) or when no
//! harmonic near it stands 5× above its neighbourhood: the caller keeps the speed it had rather
//! than follow noise.
//!
//! Cost and allocation: one real FFT of the signal and a few small buffers, per call. The daemon
//! calls it at band-selection time only (every `band_period_s`), never per hop.

use super::envelope::FftPlans;

/// Shaft harmonics summed.
pub const HARMONICS: usize = 5;

/// Smallest prominence (best harmonic sum over the median over the candidates) accepted.
pub const MIN_PROMINENCE: f64 = 1.5;

/// Smallest whitened peak of a harmonic that takes part in the refinement.
const REFINE_MIN_RATIO: f64 = 5.0;

/// Grid candidates per bin of the first harmonic (the `HARMONICS`-th harmonic then moves by
/// `HARMONICS / GRID_PER_BIN` bins per step, less than a bin).
const GRID_PER_BIN: f64 = 2.0 * HARMONICS as f64;

/// Where to look for the shaft rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedSearch {
    /// The nominal shaft rate, Hz.
    pub nominal_hz: f64,
    /// Relative half-width of the search, e.g. 0.05 for ±5 %.
    pub range: f64,
}

/// Where a channel's shaft speed comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpeedMode {
    /// The speed the channel's monitor was made with, for good.
    Fixed,
    /// Given from outside at a sample position (the monitor's `set_speed_at`): `known_at_start`
    /// says whether the speed the monitor was made with may be used until then (a nominal
    /// speed) or the channel waits.
    /// Speeds above `max_shaft_hz` (the envelope spectrum is sized for it) are not usable.
    Given {
        known_at_start: bool,
        max_shaft_hz: f64,
    },
    /// Estimated from the history at every band selection, within the search.
    Estimate(SpeedSearch),
}

impl SpeedMode {
    /// The highest shaft rate the channel analyses, given the starting one.
    pub(crate) fn max_shaft_hz(&self, start_hz: f64) -> f64 {
        match *self {
            SpeedMode::Fixed => start_hz,
            SpeedMode::Given { max_shaft_hz, .. } => max_shaft_hz.max(start_hz),
            SpeedMode::Estimate(search) => search.nominal_hz * (1.0 + search.range),
        }
    }
}

/// An estimated shaft rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedEstimate {
    pub shaft_hz: f64,
    /// The best harmonic sum over the median over every candidate (≥ 1).
    pub prominence: f64,
}

impl SpeedEstimate {
    pub fn rpm(&self) -> f64 {
        self.shaft_hz * 60.0
    }
}

/// Estimates the shaft rate of `signal` (sampled at `fs_hz`) within `search`; `None` when the
/// signal is too short to resolve the search range, the search reaches past Nyquist, or no
/// candidate stands out (see the [module docs](self)).
pub fn estimate_shaft_hz(
    plans: &mut FftPlans,
    signal: &[f32],
    fs_hz: f64,
    search: SpeedSearch,
) -> Option<SpeedEstimate> {
    let n = signal.len();
    let (lo, hi) = (
        search.nominal_hz * (1.0 - search.range),
        search.nominal_hz * (1.0 + search.range),
    );
    if !(fs_hz > 0.0 && lo > 0.0 && hi > lo && n >= 64) {
        return None;
    }
    let bin_hz = fs_hz / n as f64;
    // The search must span a few bins of the first harmonic, or there is nothing to choose from.
    if (hi - lo) / bin_hz < 2.0 || HARMONICS as f64 * hi * (1.0 + search.range) >= fs_hz / 2.0 {
        return None;
    }
    let amplitude = amplitude_spectrum(plans, signal);
    let whitened = whiten(&amplitude, bin_hz, lo, hi);

    let step = bin_hz / GRID_PER_BIN;
    let candidates = ((hi - lo) / step).floor() as usize + 1;
    let sums: Vec<f64> = (0..candidates)
        .map(|i| {
            let f = lo + i as f64 * step;
            (1..=HARMONICS)
                .map(|k| {
                    let value = interpolate(&whitened, k as f64 * f / bin_hz);
                    value.max(1.0).ln()
                })
                .sum()
        })
        .collect();
    let (best, &best_sum) = sums.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let mut sorted = sums.clone();
    let middle = sorted.len() / 2;
    let median = *sorted.select_nth_unstable_by(middle, f64::total_cmp).1;
    let prominence = if median > 0.0 {
        best_sum / median
    } else if best_sum > 0.0 {
        f64::INFINITY
    } else {
        1.0
    };
    if prominence < MIN_PROMINENCE {
        return None;
    }
    // A parabola through the best candidate and its neighbours.
    let offset = match (best.checked_sub(1), sums.get(best + 1)) {
        (Some(left), Some(&right)) => {
            let (a, b, c) = (sums[left], best_sum, right);
            let curvature = a - 2.0 * b + c;
            if curvature < 0.0 {
                (0.5 * (a - c) / curvature).clamp(-0.5, 0.5)
            } else {
                0.0
            }
        }
        _ => 0.0,
    };
    let coarse = lo + (best as f64 + offset) * step;
    Some(SpeedEstimate {
        shaft_hz: refine(&amplitude, &whitened, bin_hz, coarse)?,
        prominence,
    })
}

/// Refines `coarse` from the harmonics' own peaks: each harmonic that stands out (whitened
/// peak at least [`REFINE_MIN_RATIO`]) within a bin and a half of `k·coarse` gives
/// `peak / k`, its peak located by a parabola through the log amplitudes (exact for a
/// Gaussian, close for Hann's main lobe); they are averaged with weights `k²` (a harmonic's
/// error divided by `k`, variance by `k²`). Without any such harmonic there is no shaft line
/// to speak of (white noise stands out by at most ≈ 3 in a region of a few hundred bins):
/// `None`.
fn refine(amplitude: &[f32], whitened: &[f32], bin_hz: f64, coarse: f64) -> Option<f64> {
    let (mut sum, mut weights) = (0.0, 0.0);
    for k in 1..=HARMONICS {
        let centre = k as f64 * coarse / bin_hz;
        let first = (centre - 1.5).round().max(1.0) as usize;
        let last = (centre + 1.5).round() as usize;
        if last + 1 >= amplitude.len() {
            break;
        }
        let peak = (first..=last).max_by(|&a, &b| amplitude[a].total_cmp(&amplitude[b]));
        let Some(peak) = peak else { continue };
        if f64::from(whitened[peak]) < REFINE_MIN_RATIO || peak == first || peak == last {
            continue;
        }
        let ln = |i: usize| f64::from(amplitude[i].max(f32::MIN_POSITIVE)).ln();
        let (a, b, c) = (ln(peak - 1), ln(peak), ln(peak + 1));
        let curvature = a - 2.0 * b + c;
        let offset = if curvature < 0.0 {
            (0.5 * (a - c) / curvature).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        let weight = (k * k) as f64;
        sum += weight * (peak as f64 + offset) * bin_hz / k as f64;
        weights += weight;
    }
    (weights > 0.0).then(|| sum / weights)
}

/// Amplitude spectrum of the Hann-windowed signal, bins from 0 Hz spaced `fs/n`.
fn amplitude_spectrum(plans: &mut FftPlans, signal: &[f32]) -> Vec<f32> {
    let n = signal.len();
    let window = plans.hann_window(n);
    let fft = plans.real_forward_plan(n);
    let mut input: Vec<f32> = signal
        .iter()
        .zip(window.iter())
        .map(|(x, w)| x * w)
        .collect();
    let mut spectrum = fft.make_output_vec();
    let mut scratch = fft.make_scratch_vec();
    // Lengths match by construction, so the transform cannot fail.
    let _ = fft.process_with_scratch(&mut input, &mut spectrum, &mut scratch);
    spectrum.iter().map(|c| c.norm()).collect()
}

/// `amplitude` divided, around each harmonic's search region `k·[lo, hi]`, by the median of that
/// region widened by half its width on each side; bins outside every region are 0.
fn whiten(amplitude: &[f32], bin_hz: f64, lo: f64, hi: f64) -> Vec<f32> {
    let mut out = vec![0.0f32; amplitude.len()];
    let mut region = Vec::new();
    for k in 1..=HARMONICS {
        let (a, b) = (k as f64 * lo, k as f64 * hi);
        let margin = 0.5 * (b - a);
        let first = (((a - margin) / bin_hz).floor().max(1.0)) as usize;
        let last = (((b + margin) / bin_hz).ceil() as usize + 2).min(amplitude.len() - 1);
        if first >= last {
            continue;
        }
        region.clear();
        region.extend_from_slice(&amplitude[first..=last]);
        let middle = region.len() / 2;
        let median = *region.select_nth_unstable_by(middle, f32::total_cmp).1;
        if median <= 0.0 {
            continue;
        }
        for (o, &x) in out[first..=last].iter_mut().zip(&amplitude[first..=last]) {
            *o = x / median;
        }
    }
    out
}

/// Linear interpolation of `values` at fractional index `at` (0 outside).
fn interpolate(values: &[f32], at: f64) -> f64 {
    let i = at.floor();
    if i < 0.0 {
        return 0.0;
    }
    let i = i as usize;
    match (values.get(i), values.get(i + 1)) {
        (Some(&a), Some(&b)) => {
            let t = at - i as f64;
            f64::from(a) * (1.0 - t) + f64::from(b) * t
        }
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn harmonics_and_noise(fs: f64, seconds: f64, shaft_hz: f64) -> Vec<f32> {
        let n = (fs * seconds) as usize;
        let mut state = 12345u64;
        (0..n)
            .map(|i| {
                let t = i as f64 / fs;
                let tone: f64 = (1..=4)
                    .map(|k| {
                        0.1 / k as f64 * (std::f64::consts::TAU * k as f64 * shaft_hz * t).sin()
                    })
                    .sum();
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let noise = ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 0.5;
                (tone + noise) as f32
            })
            .collect()
    }

    #[test]
    fn finds_a_shaft_rate_three_per_cent_off_the_nominal() {
        let signal = harmonics_and_noise(12_000.0, 10.0, 29.3);
        let estimate = estimate_shaft_hz(
            &mut FftPlans::default(),
            &signal,
            12_000.0,
            SpeedSearch {
                nominal_hz: 29.3 * 1.03,
                range: 0.05,
            },
        )
        .expect("an estimate");
        assert!((estimate.shaft_hz - 29.3).abs() < 0.01, "{estimate:?}");
    }

    #[test]
    fn white_noise_alone_gives_no_estimate() {
        let mut state = 99u64;
        let signal: Vec<f32> = (0..120_000)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) as f32
            })
            .collect();
        let estimate = estimate_shaft_hz(
            &mut FftPlans::default(),
            &signal,
            12_000.0,
            SpeedSearch {
                nominal_hz: 30.0,
                range: 0.05,
            },
        );
        assert_eq!(estimate, None);
    }

    #[test]
    fn too_short_or_bad_input_gives_none() {
        let plans = &mut FftPlans::default();
        let search = SpeedSearch {
            nominal_hz: 30.0,
            range: 0.05,
        };
        assert_eq!(
            estimate_shaft_hz(plans, &[0.0; 1000], 12_000.0, search),
            None
        );
        assert_eq!(estimate_shaft_hz(plans, &[], 12_000.0, search), None);
        assert_eq!(
            estimate_shaft_hz(plans, &[0.0; 120_000], f64::NAN, search),
            None
        );
    }
}
