//! Which rhythm modulates a comb: shaft rate or cage rate (docs/DIAGNOSIS.md, ball against
//! inner race).
//!
//! An inner-race defect turns with the shaft, so its impacts swell and fade once per turn: its
//! harmonics carry sidebands at ±`fr`. A damaged ball is carried through the load zone by the
//! cage: its harmonics carry sidebands at ±`FTF`. On some bearings (the 61804: BPFI 7.375·fr,
//! 2·BSF 7.294·fr) both combs land on the very same peaks, and only these sidebands can tell the
//! two faults apart. So, *anchored* on the peaks a comb found, we compare the lines its own
//! spacing predicts with the lines the other spacing predicts:
//!
//! `C = mean(own excess⁺) − mean(other excess⁺)` (log units: the log of the ratio of their
//! geometric-mean peak-to-floor ratios), and `z = C / spread`, the spectrum's robust spread of
//! excess, as for the comb's own significance. `z > 0`: the comb's own modulation shows;
//! `z < 0`: the other fault's does. Noise alone gives `|z|` above
//! [`super::rolling_element::RIVAL_CONTRAST_Z`] rarely (measured in the tests below).
//!
//! This module knows nothing of how the peaks were found; [`super::fault_bands`] calls it with
//! the peaks of its comb.

use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;
use serde::Serialize;

/// How a comb's peaks are modulated: its own sideband spacing against its rival's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Modulation {
    /// Geometric-mean peak-to-floor ratio of the lines at ± the comb's own spacing from its
    /// peaks (`fr` for an inner race, `FTF` for a ball); 1 = at the floor.
    pub own: f64,
    /// The same at ± the other spacing (`FTF` for an inner race, `fr` for a ball).
    pub other: f64,
    /// `ln(own / other)` over the spectrum's robust spread of excess.
    pub contrast_z: f64,
}

/// The sideband spacings (own, other) of a rolling-element hypothesis; `None` for the outer
/// race and the cage, whose combs have no rival of this kind.
pub fn spacings(fault: FaultKind, freqs: &FaultFrequencies) -> Option<(f64, f64)> {
    match fault {
        FaultKind::InnerRace => Some((freqs.shaft, freqs.ftf)),
        FaultKind::Ball => Some((freqs.ftf, freqs.shaft)),
        FaultKind::OuterRace | FaultKind::Cage => None,
    }
}

/// (choice) A sideband is sought within ±2 % of the cage rate (at least one bin) of where it
/// should be: the cage slips 1–2 % against kinematics, and at fine resolution (48 kHz, long
/// windows) a bare ±1 bin would miss it.
const SIDEBAND_HALF_WIDTH_OF_FTF: f64 = 0.02;

/// The anchored contrast of the peaks at `peaks_hz` in `excess` (log amplitude over the floor,
/// bins `bin_hz` apart from 0 Hz; `spread` its robust spread): `own` and `other` the sideband
/// spacings, `ftf` the cage rate (for the search window). `None` when no sideband of either
/// spacing falls inside the spectrum, or when the spread or a spacing is not positive.
pub fn anchored_contrast(
    excess: &[f32],
    bin_hz: f64,
    spread: f64,
    peaks_hz: impl IntoIterator<Item = f64>,
    (own, other): (f64, f64),
    ftf: f64,
) -> Option<Modulation> {
    if !(spread > 0.0 && bin_hz > 0.0 && own > 0.0 && other > 0.0) {
        return None;
    }
    let half_bins = (SIDEBAND_HALF_WIDTH_OF_FTF * ftf / bin_hz).max(1.0);
    let (mut own_sum, mut other_sum, mut lines) = (0.0, 0.0, 0usize);
    for peak in peaks_hz {
        for side in [-1.0, 1.0] {
            let own_line = largest_near(excess, (peak + side * own) / bin_hz, half_bins);
            let other_line = largest_near(excess, (peak + side * other) / bin_hz, half_bins);
            // Both or neither: the two means are taken over the same places.
            if let (Some(o), Some(t)) = (own_line, other_line) {
                own_sum += o.max(0.0);
                other_sum += t.max(0.0);
                lines += 1;
            }
        }
    }
    if lines == 0 {
        return None;
    }
    let own_mean = own_sum / lines as f64;
    let other_mean = other_sum / lines as f64;
    Some(Modulation {
        own: own_mean.exp(),
        other: other_mean.exp(),
        contrast_z: (own_mean - other_mean) / spread,
    })
}

/// The largest of `excess` within ±`half` bins of bin `centre` (the DC bin excluded); `None`
/// when the window reaches past either end.
fn largest_near(excess: &[f32], centre: f64, half: f64) -> Option<f64> {
    let last = excess.len().checked_sub(1)? as f64;
    if centre - half < 1.0 || centre + half > last {
        return None;
    }
    let lo = (centre - half).round() as usize;
    let hi = (centre + half).round() as usize;
    excess
        .get(lo..=hi)?
        .iter()
        .copied()
        .reduce(f32::max)
        .map(f64::from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bearing::BearingGeometry;
    use crate::random::Rng;

    const BIN_HZ: f64 = 12_000.0 / 4096.0;

    /// The 61804 at 1800 rpm: BPFI and 2·BSF 1.1 % apart.
    fn freqs_61804() -> FaultFrequencies {
        BearingGeometry::from_catalog("skf-61804")
            .expect("catalog entry")
            .fault_frequencies(30.0)
    }

    /// The excess of a noise-only envelope spectrum (`averages` windows): log amplitude minus
    /// its median (a flat floor), and its robust spread.
    fn noise_excess(rng: &mut Rng, bins: usize, averages: usize) -> (Vec<f32>, f64) {
        let mut excess: Vec<f32> = (0..bins)
            .map(|_| {
                let power: f64 = (0..averages)
                    .map(|_| 0.5 * (rng.normal().powi(2) + rng.normal().powi(2)))
                    .sum::<f64>()
                    / averages as f64;
                (0.5 * power.ln()) as f32
            })
            .collect();
        let centre = median(&excess);
        excess.iter_mut().for_each(|e| *e -= centre);
        let deviations: Vec<f32> = excess.iter().map(|e| e.abs()).collect();
        (excess, 1.4826 * f64::from(median(&deviations)))
    }

    fn median(values: &[f32]) -> f32 {
        let mut sorted = values.to_vec();
        sorted.sort_by(f32::total_cmp);
        sorted[sorted.len() / 2]
    }

    fn raise(excess: &mut [f32], hz: f64, by: f32) {
        if let Some(e) = excess.get_mut((hz / BIN_HZ).round() as usize) {
            *e += by;
        }
    }

    /// Five harmonics of `f` at `peak` excess with sidebands at ±`spacing` at `side` excess
    /// (0 for none), on noise; the peaks' places.
    fn comb(f: f64, spacing: f64, peak: f32, side: f32, seed: u64) -> (Vec<f32>, f64, Vec<f64>) {
        let mut rng = Rng::new(seed);
        let (mut excess, spread) = noise_excess(&mut rng, 400, 8);
        let peaks: Vec<f64> = (1..=5).map(|k| k as f64 * f).collect();
        for &p in &peaks {
            raise(&mut excess, p, peak);
            raise(&mut excess, p - spacing, side);
            raise(&mut excess, p + spacing, side);
        }
        (excess, spread, peaks)
    }

    fn contrast(excess: &[f32], spread: f64, peaks: &[f64], fault: FaultKind) -> Modulation {
        let freqs = freqs_61804();
        let pair = spacings(fault, &freqs).expect("a rolling-element fault");
        anchored_contrast(
            excess,
            BIN_HZ,
            spread,
            peaks.iter().copied(),
            pair,
            freqs.ftf,
        )
        .expect("sidebands inside the spectrum")
    }

    #[test]
    fn shaft_rate_sidebands_speak_for_the_inner_race_and_against_the_ball() {
        let freqs = freqs_61804();
        for seed in 1..=5 {
            let (excess, spread, peaks) = comb(freqs.bpfi, freqs.shaft, 2.0, 1.2, seed);
            let inner = contrast(&excess, spread, &peaks, FaultKind::InnerRace);
            let ball = contrast(&excess, spread, &peaks, FaultKind::Ball);
            assert!(inner.contrast_z >= 3.0, "seed {seed}: inner {inner:?}");
            assert!((inner.contrast_z + ball.contrast_z).abs() < 1e-9);
            assert!(inner.own > 2.0 && inner.other < 1.6, "{inner:?}");
        }
    }

    #[test]
    fn cage_rate_sidebands_speak_for_the_ball_and_against_the_inner_race() {
        let freqs = freqs_61804();
        for seed in 1..=5 {
            let (excess, spread, peaks) = comb(freqs.two_bsf, freqs.ftf, 2.0, 1.2, seed);
            let ball = contrast(&excess, spread, &peaks, FaultKind::Ball);
            let inner = contrast(&excess, spread, &peaks, FaultKind::InnerRace);
            assert!(ball.contrast_z >= 3.0, "seed {seed}: ball {ball:?}");
            assert!(inner.contrast_z <= -3.0, "seed {seed}: inner {inner:?}");
        }
    }

    #[test]
    fn unmodulated_shared_lines_favour_neither() {
        // A uniform load: the harmonics stand, no sidebands. |z| stays below the separation a
        // shared comb needs ([`super::super::rolling_element::SEPARATION_Z`]).
        let freqs = freqs_61804();
        for seed in 1..=5 {
            let (excess, spread, peaks) = comb(freqs.bpfi, freqs.shaft, 2.5, 0.0, seed);
            let inner = contrast(&excess, spread, &peaks, FaultKind::InnerRace);
            assert!(
                inner.contrast_z.abs() < super::super::rolling_element::SEPARATION_Z,
                "seed {seed}: {inner:?}"
            );
        }
    }

    #[test]
    fn outside_the_spectrum_or_without_a_pair_there_is_no_contrast() {
        let freqs = freqs_61804();
        assert!(spacings(FaultKind::OuterRace, &freqs).is_none());
        assert!(spacings(FaultKind::Cage, &freqs).is_none());
        let excess = vec![0.0_f32; 50];
        let pair = spacings(FaultKind::InnerRace, &freqs).expect("inner race");
        let far = [freqs.bpfi * 40.0];
        assert!(anchored_contrast(&excess, BIN_HZ, 0.3, far, pair, freqs.ftf).is_none());
        assert!(anchored_contrast(&excess, BIN_HZ, 0.0, [60.0], pair, freqs.ftf).is_none());
    }

    #[test]
    fn noise_alone_rarely_shows_a_modulation_pattern() {
        // The contrast's null: 3 × 1000 noise spectra (2, 8 and 32 averages), anchored on the
        // largest bin near each harmonic of the 61804's BPFI, as the comb would find them.
        // |z| ≥ RIVAL_CONTRAST_Z must happen in at most 0.5 % of them. (measured: the |z|
        // quantiles 50/99/99.5/99.9 % are 0.18/0.69/0.74/0.85, none at 3.)
        let freqs = freqs_61804();
        let pair = spacings(FaultKind::InnerRace, &freqs).expect("inner race");
        let mut rng = Rng::new(17);
        let (mut total, mut beyond) = (0usize, 0usize);
        let mut all = Vec::new();
        for averages in [2, 8, 32] {
            for _ in 0..1000 {
                let (excess, spread) = noise_excess(&mut rng, 400, averages);
                let peaks: Vec<f64> = (1..=5)
                    .map(|k| {
                        let centre = k as f64 * freqs.bpfi / BIN_HZ;
                        let half = (0.004 * k as f64 * freqs.bpfi / BIN_HZ).max(1.0);
                        let lo = (centre - half).round() as usize;
                        let hi = (centre + half).round() as usize;
                        let top = (lo..=hi)
                            .max_by(|&a, &b| excess[a].total_cmp(&excess[b]))
                            .unwrap_or(lo);
                        top as f64 * BIN_HZ
                    })
                    .collect();
                let Some(m) = anchored_contrast(&excess, BIN_HZ, spread, peaks, pair, freqs.ftf)
                else {
                    continue;
                };
                total += 1;
                all.push(m.contrast_z.abs());
                beyond += usize::from(
                    m.contrast_z.abs() >= super::super::rolling_element::RIVAL_CONTRAST_Z,
                );
            }
        }
        all.sort_by(f64::total_cmp);
        let quantile = |q: f64| all[((all.len() - 1) as f64 * q) as usize];
        let rate = beyond as f64 / total.max(1) as f64;
        assert!(
            total == 3000,
            "{total} of 3000 noise spectra gave a contrast"
        );
        assert!(
            rate <= 0.005,
            "|z| ≥ {} in {rate:.4} of {total} noise spectra (|z| quantiles 50/99/99.9 %: \
             {:.2}/{:.2}/{:.2})",
            super::super::rolling_element::RIVAL_CONTRAST_Z,
            quantile(0.5),
            quantile(0.99),
            quantile(0.999)
        );
    }
}
