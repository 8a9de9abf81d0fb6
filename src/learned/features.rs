//! What the learned diagnosis looks at: the squared-envelope spectrum of a segment of the
//! record on a **shaft-order axis**, in decibel-like units above its own median floor.
//!
//! Why this input and not raw samples: a network trained only on simulated signals meets real
//! machines with other resonances, gains, noise and speeds. On the order axis a fault's comb
//! sits at the same place whatever the speed; against the median floor, whatever the gain; and
//! the envelope of a wide band keeps the comb whatever the resonance. What stays for the network
//! to learn is the pattern the envelope diagnosis also reads (harmonics, sidebands, their
//! decay), from examples rather than rules, so it can give a second opinion where the rules'
//! thresholds are not met. The input is only valid for the bearing the model was trained for
//! (the comb's orders depend on its geometry), which the model card records.

use crate::analysis::band::Band;
use crate::analysis::envelope::{fast_fft_len, welch_envelope_spectrum, FftPlans};

/// How a record is cut into segments and each segment turned into the network's input. Stored
/// in the model card, so that inference computes exactly what training saw.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FeatureSettings {
    /// One segment: this many shaft revolutions.
    pub segment_revolutions: f64,
    /// Consecutive segments start this many revolutions apart.
    pub hop_revolutions: f64,
    /// The order axis: `order_bins` bins of `order_step` shaft orders from 0.
    pub order_bins: usize,
    pub order_step: f64,
    /// The envelope's band, as fractions of the sample rate (wide: the full band but the
    /// lowest frequencies, where shaft harmonics and the 1/f rise live).
    pub band_low_fraction: f64,
    pub band_high_fraction: f64,
}

impl Default for FeatureSettings {
    fn default() -> Self {
        FeatureSettings {
            segment_revolutions: 24.0,
            hop_revolutions: 12.0,
            order_bins: 192,
            order_step: 1.0 / 16.0,
            band_low_fraction: 0.04,
            band_high_fraction: 0.45,
        }
    }
}

/// (choice) Orders below this are the envelope's DC and slow gain changes: set to the floor.
const LOWEST_ORDER: f64 = 0.3;
/// (choice) The input is clamped to this range (natural log of amplitude over the floor): a
/// comb 400× its floor says all there is to say.
const LOG_RANGE: (f32, f32) = (-3.0, 6.0);

impl FeatureSettings {
    /// Samples in one segment at `fs_hz` and shaft frequency `shaft_hz`.
    pub fn segment_samples(&self, fs_hz: f64, shaft_hz: f64) -> usize {
        (self.segment_revolutions / shaft_hz * fs_hz).round() as usize
    }

    /// Start of every whole segment in a record of `len` samples.
    pub fn segment_starts(&self, len: usize, fs_hz: f64, shaft_hz: f64) -> Vec<usize> {
        let segment = self.segment_samples(fs_hz, shaft_hz);
        let hop = ((self.hop_revolutions / shaft_hz * fs_hz).round() as usize).max(1);
        if segment == 0 || len < segment {
            return Vec::new();
        }
        (0..=(len - segment) / hop).map(|i| i * hop).collect()
    }

    /// The network's input for one segment (`order_bins` values).
    pub fn order_spectrum(
        &self,
        plans: &mut FftPlans,
        segment: &[f32],
        fs_hz: f64,
        shaft_hz: f64,
    ) -> Vec<f32> {
        // Welch over half-segment windows (three averages at 50 % overlap): order resolution
        // shaft / (fs / window) ≈ 1 / (revolutions per window) ≈ 0.08 orders.
        let window = fast_fft_len(segment.len() / 2).min(segment.len()).max(64);
        let top_hz = (self.order_bins as f64 + 1.0) * self.order_step * shaft_hz;
        let bin_hz = fs_hz / window as f64;
        let bins = ((top_hz / bin_hz).ceil() as usize + 2).min(window / 2);
        let band = Band::new(
            self.band_low_fraction * fs_hz,
            self.band_high_fraction * fs_hz,
        );
        let spectrum = welch_envelope_spectrum(plans, segment, fs_hz, band, window, 0.5, bins);
        let amplitude = &spectrum.amplitude;
        // Each order bin takes the larger of the two spectrum bins around it: a line between
        // bins keeps its height.
        let at = |order: f64| -> f32 {
            let position = order * shaft_hz / bin_hz;
            let below = (position.floor() as usize).min(amplitude.len().saturating_sub(1));
            let above = (below + 1).min(amplitude.len().saturating_sub(1));
            amplitude
                .get(below)
                .copied()
                .unwrap_or(0.0)
                .max(amplitude.get(above).copied().unwrap_or(0.0))
        };
        let mut values: Vec<f32> = (0..self.order_bins)
            .map(|k| at(k as f64 * self.order_step))
            .collect();
        let first = (LOWEST_ORDER / self.order_step).ceil() as usize;
        let floor = median(&values[first.min(values.len())..]).max(f32::MIN_POSITIVE);
        for (k, v) in values.iter_mut().enumerate() {
            *v = if k < first {
                0.0
            } else {
                (*v / floor)
                    .max(f32::MIN_POSITIVE)
                    .ln()
                    .clamp(LOG_RANGE.0, LOG_RANGE.1)
            };
        }
        values
    }

    /// The input of every segment of a record, one after the other (`order_bins` each).
    pub fn record_inputs(
        &self,
        plans: &mut FftPlans,
        samples: &[f32],
        fs_hz: f64,
        shaft_hz: f64,
    ) -> Vec<f32> {
        let segment = self.segment_samples(fs_hz, shaft_hz);
        self.segment_starts(samples.len(), fs_hz, shaft_hz)
            .into_iter()
            .flat_map(|start| {
                self.order_spectrum(plans, &samples[start..start + segment], fs_hz, shaft_hz)
            })
            .collect()
    }
}

fn median(values: &[f32]) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f32::total_cmp);
    sorted[sorted.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_envelope_comb_lands_on_its_orders_at_any_speed() {
        let settings = FeatureSettings::default();
        let fs = 12_000.0;
        for shaft_hz in [15.0, 30.0] {
            // A 2 kHz carrier, amplitude-modulated at 3.5 × the shaft frequency, in noise (a
            // clean tone would clamp its harmonic to the same height as its fundamental).
            let len = settings.segment_samples(fs, shaft_hz);
            let rate = 3.5 * shaft_hz;
            let mut rng = crate::random::Rng::new(3);
            let signal: Vec<f32> = (0..len)
                .map(|i| {
                    let t = i as f64 / fs;
                    ((1.0 + 0.5 * (std::f64::consts::TAU * rate * t).cos())
                        * (std::f64::consts::TAU * 2_000.0 * t).sin()
                        + 0.5 * rng.normal()) as f32
                })
                .collect();
            let input = settings.order_spectrum(&mut FftPlans::default(), &signal, fs, shaft_hz);
            assert_eq!(input.len(), settings.order_bins);
            let peak = input
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map(|(k, _)| k as f64 * settings.order_step)
                .unwrap_or_default();
            assert!(
                (peak - 3.5).abs() <= 2.0 * settings.order_step,
                "at {shaft_hz} Hz the comb's line is at order {peak}, not 3.5"
            );
            assert!(input.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn a_record_shorter_than_a_segment_gives_no_input() {
        let settings = FeatureSettings::default();
        let starts = settings.segment_starts(1_000, 12_000.0, 30.0);
        assert!(starts.is_empty());
        let starts = settings.segment_starts(24_000, 12_000.0, 30.0);
        assert_eq!(starts, vec![0, 4800, 9600, 14400]);
    }
}
