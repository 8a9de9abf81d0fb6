//! What the learned diagnosis looks at: the squared-envelope spectrum of a segment of the
//! record on an **order axis**, in decibel-like units above its own median floor.
//!
//! Why this input and not raw samples: a network trained only on simulated signals meets real
//! machines with other resonances, gains, noise and speeds. On an order axis a fault's comb
//! sits at the same place whatever the speed; against the median floor, whatever the gain; and
//! the envelope of a wide band keeps the comb whatever the resonance. What stays for the network
//! to learn is the pattern the envelope diagnosis also reads (harmonics, sidebands, their
//! decay), from examples rather than rules, so it can give a second opinion where the rules'
//! thresholds are not met.
//!
//! Two axes ([`OrderAxis`]): on **shaft orders** a fault's lines sit where its bearing's
//! geometry puts them, so such a model knows one bearing (its card records which); on
//! **fault-relative orders** the input is three parts, each the spectrum on the axis of one
//! fault's own order (outer race, inner race, ball), so a comb sits on the same bins whatever
//! the geometry and one model, trained on many geometries, serves any bearing.

use crate::analysis::band::Band;
use crate::analysis::envelope::{fast_fft_len, welch_envelope_spectrum, FftPlans};
use crate::bearing::FaultFrequencies;

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
    /// What the `order_bins` are orders of (absent in a card: shaft orders, the first models').
    #[serde(default, skip_serializing_if = "OrderAxis::is_shaft")]
    pub axis: OrderAxis,
}

/// The axis of the network's input.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum OrderAxis {
    /// `order_bins` bins of `order_step` shaft orders from 0: the model knows one geometry.
    #[default]
    Shaft,
    /// Three equal parts of `order_bins`: the outer race's (BPFO), the inner race's (BPFI) and
    /// the ball's (BSF) own order, each from 0 to `harmonics` times that fault's rate. Each bin
    /// holds the highest line it covers. The model knows any geometry.
    FaultRelative { harmonics: f64 },
}

impl OrderAxis {
    /// (choice) The fault-relative axis of `bearingd train --axis fault-relative`: four
    /// harmonics of each fault and half a spacing beyond, where the envelope diagnosis also
    /// looks (its combs score up to the fifth).
    pub const FAULT_RELATIVE: OrderAxis = OrderAxis::FaultRelative { harmonics: 4.5 };

    pub fn is_shaft(&self) -> bool {
        matches!(self, OrderAxis::Shaft)
    }

    /// The number of parts `order_bins` is cut into.
    pub fn parts(&self) -> usize {
        match self {
            OrderAxis::Shaft => 1,
            OrderAxis::FaultRelative { .. } => FAULT_RELATIVE_PARTS,
        }
    }
}

/// The faults of a fault-relative input, in order: outer race, inner race, ball.
const FAULT_RELATIVE_PARTS: usize = 3;

impl Default for FeatureSettings {
    fn default() -> Self {
        FeatureSettings {
            segment_revolutions: 24.0,
            hop_revolutions: 12.0,
            order_bins: 192,
            order_step: 1.0 / 16.0,
            band_low_fraction: 0.04,
            band_high_fraction: 0.45,
            axis: OrderAxis::Shaft,
        }
    }
}

/// (choice) Orders below this are the envelope's DC and slow gain changes: set to the floor.
const LOWEST_ORDER: f64 = 0.3;
/// (choice) The input is clamped to this range (natural log of amplitude over the floor): a
/// comb 400× its floor says all there is to say.
const LOG_RANGE: (f32, f32) = (-3.0, 6.0);

impl FeatureSettings {
    /// The settings of `bearingd train --axis fault-relative`: [`OrderAxis::FAULT_RELATIVE`],
    /// with 128 bins per fault (a bin of 0.035 of the fault's own order: 0.13 shaft orders at
    /// the 6205's BPFO, about the spectrum's resolution), the rest as the default.
    pub fn fault_relative() -> Self {
        FeatureSettings {
            axis: OrderAxis::FAULT_RELATIVE,
            order_bins: 3 * 128,
            ..FeatureSettings::default()
        }
    }

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

    /// The network's input for one segment (`order_bins` values), the shaft and the faults at
    /// `freqs` (Hz).
    pub fn order_spectrum(
        &self,
        plans: &mut FftPlans,
        segment: &[f32],
        fs_hz: f64,
        freqs: &FaultFrequencies,
    ) -> Vec<f32> {
        let shaft_hz = freqs.shaft;
        // Welch over half-segment windows (three averages at 50 % overlap): order resolution
        // shaft / (fs / window) ≈ 1 / (revolutions per window) ≈ 0.08 orders.
        let window = fast_fft_len(segment.len() / 2).min(segment.len()).max(64);
        let top_hz = self.top_order(freqs) * shaft_hz;
        let bin_hz = fs_hz / window as f64;
        let bins = ((top_hz / bin_hz).ceil() as usize + 2).min(window / 2);
        let band = Band::new(
            self.band_low_fraction * fs_hz,
            self.band_high_fraction * fs_hz,
        );
        let spectrum = welch_envelope_spectrum(plans, segment, fs_hz, band, window, 0.5, bins);
        let amplitude = &spectrum.amplitude;
        // The highest spectrum line from the bin below order `from` to the bin above order
        // `to` (shaft orders): a line between bins keeps its height.
        let highest = |from: f64, to: f64| -> f32 {
            let last = amplitude.len().saturating_sub(1);
            let below = ((from * shaft_hz / bin_hz).floor() as usize).min(last);
            let above = ((to * shaft_hz / bin_hz).floor() as usize + 1).min(last);
            amplitude
                .get(below..=above.max(below))
                .map_or(0.0, |lines| lines.iter().fold(0.0, |a, &b| a.max(b)))
        };
        match self.axis {
            OrderAxis::Shaft => {
                let mut values: Vec<f32> = (0..self.order_bins)
                    .map(|k| {
                        let order = k as f64 * self.order_step;
                        highest(order, order)
                    })
                    .collect();
                let first = (LOWEST_ORDER / self.order_step).ceil() as usize;
                log_over_floor(&mut values, first);
                values
            }
            OrderAxis::FaultRelative { harmonics } => {
                let per_part = self.order_bins / FAULT_RELATIVE_PARTS;
                let mut values = Vec::with_capacity(self.order_bins);
                for fault_hz in [freqs.bpfo, freqs.bpfi, freqs.bsf] {
                    // One bin of this part, in shaft orders.
                    let step = harmonics * fault_hz / shaft_hz / per_part as f64;
                    let mut part: Vec<f32> = (0..per_part)
                        .map(|j| {
                            let centre = j as f64 * step;
                            highest(centre - step / 2.0, centre + step / 2.0)
                        })
                        .collect();
                    log_over_floor(&mut part, (LOWEST_ORDER / step).ceil() as usize);
                    values.extend(part);
                }
                values.resize(self.order_bins, 0.0);
                values
            }
        }
    }

    /// The highest shaft order the input looks at, at `freqs`.
    fn top_order(&self, freqs: &FaultFrequencies) -> f64 {
        match self.axis {
            OrderAxis::Shaft => (self.order_bins as f64 + 1.0) * self.order_step,
            OrderAxis::FaultRelative { harmonics } => {
                let per_part = (self.order_bins / FAULT_RELATIVE_PARTS).max(1) as f64;
                let fastest = freqs.bpfo.max(freqs.bpfi).max(freqs.bsf) / freqs.shaft;
                harmonics * fastest * (per_part + 1.0) / per_part
            }
        }
    }

    /// Why these settings cannot make an input, if they cannot (a model card's are checked
    /// with this when the model is read).
    pub fn problem(&self) -> Option<String> {
        match self.axis {
            OrderAxis::Shaft => None,
            OrderAxis::FaultRelative { harmonics } => {
                if !(harmonics.is_finite() && harmonics > 0.0) {
                    Some(format!(
                        "its fault-relative axis spans {harmonics} harmonics; it must be a positive number"
                    ))
                } else if !self.order_bins.is_multiple_of(FAULT_RELATIVE_PARTS) {
                    Some(format!(
                        "its {} order bins do not split into {FAULT_RELATIVE_PARTS} equal fault-relative parts",
                        self.order_bins
                    ))
                } else {
                    None
                }
            }
        }
    }

    /// The input of every segment of a record, one after the other (`order_bins` each), the
    /// shaft and the faults at `freqs` (Hz).
    pub fn record_inputs(
        &self,
        plans: &mut FftPlans,
        samples: &[f32],
        fs_hz: f64,
        freqs: &FaultFrequencies,
    ) -> Vec<f32> {
        let segment = self.segment_samples(fs_hz, freqs.shaft);
        self.segment_starts(samples.len(), fs_hz, freqs.shaft)
            .into_iter()
            .flat_map(|start| {
                self.order_spectrum(plans, &samples[start..start + segment], fs_hz, freqs)
            })
            .collect()
    }
}

/// Turns line heights into the input's units: bins below `first` set to the floor, the rest the
/// natural log of their height over the median of those, clamped to [`LOG_RANGE`].
fn log_over_floor(values: &mut [f32], first: usize) {
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
            let input =
                settings.order_spectrum(&mut FftPlans::default(), &signal, fs, &freqs(shaft_hz));
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

    fn freqs(shaft_hz: f64) -> FaultFrequencies {
        bearing("skf-6205-2rs").fault_frequencies(shaft_hz)
    }

    fn bearing(name: &str) -> crate::bearing::BearingGeometry {
        crate::bearing::BearingGeometry::parse(name).expect("a catalog bearing")
    }

    /// A 2 kHz carrier amplitude-modulated by short bursts at `rate_hz`, in noise: an
    /// envelope comb with harmonics.
    fn comb(fs: f64, len: usize, rate_hz: f64, seed: u64) -> Vec<f32> {
        let mut rng = crate::random::Rng::new(seed);
        (0..len)
            .map(|i| {
                let t = i as f64 / fs;
                let phase = (rate_hz * t).fract();
                let burst = if phase < 0.1 { 1.0 } else { 0.0 };
                (burst * (std::f64::consts::TAU * 2_000.0 * t).sin() + 0.3 * rng.normal()) as f32
            })
            .collect()
    }

    #[test]
    fn on_fault_relative_orders_an_outer_race_comb_lands_on_the_same_bins_for_any_geometry() {
        let settings = FeatureSettings {
            axis: OrderAxis::FaultRelative { harmonics: 4.5 },
            ..FeatureSettings::default()
        };
        assert_eq!(settings.problem(), None);
        let per_part = settings.order_bins / 3;
        let fs = 12_000.0;
        let shaft_hz = 25.0;
        // The bin of each harmonic of the part's own fault (x = k at bin k·per/4.5).
        let harmonic_bin = |k: f64| (k * per_part as f64 / 4.5).round() as usize;
        for name in [
            "skf-6205-2rs",
            "rexnord-za-2115",
            "z=13,d=3.5mm,D=26mm,alpha=0",
        ] {
            let f = bearing(name).fault_frequencies(shaft_hz);
            let signal = comb(fs, settings.segment_samples(fs, shaft_hz), f.bpfo, 5);
            let input = settings.order_spectrum(&mut FftPlans::default(), &signal, fs, &f);
            assert_eq!(input.len(), settings.order_bins);
            assert!(input.iter().all(|v| v.is_finite()));
            let outer = &input[..per_part];
            for k in [1.0, 2.0, 3.0] {
                let at = harmonic_bin(k);
                let line = outer[at - 1..=at + 1]
                    .iter()
                    .fold(f32::MIN, |a, &b| a.max(b));
                assert!(
                    line > 2.0,
                    "{name}: harmonic {k} of BPFO is {line} over the floor at bin {at} of the outer part: {outer:?}"
                );
            }
            // Halfway between harmonics the outer part is near its floor.
            let between = outer[harmonic_bin(1.5)];
            assert!(between < 1.5, "{name}: between harmonics {between}");
        }
    }

    #[test]
    fn fault_relative_settings_that_cannot_make_an_input_say_why() {
        for (harmonics, bins) in [(0.0, 192), (f64::NAN, 192), (4.5, 190)] {
            let settings = FeatureSettings {
                axis: OrderAxis::FaultRelative { harmonics },
                order_bins: bins,
                ..FeatureSettings::default()
            };
            assert!(settings.problem().is_some(), "{harmonics} {bins}");
        }
        assert_eq!(FeatureSettings::default().problem(), None);
    }

    #[test]
    fn a_card_without_an_axis_reads_as_shaft_orders_and_writes_none() {
        let json = serde_json::to_string(&FeatureSettings::default()).expect("serialises");
        assert!(!json.contains("axis"), "{json}");
        let read: FeatureSettings = serde_json::from_str(&json).expect("reads");
        assert_eq!(read.axis, OrderAxis::Shaft);
        let relative = FeatureSettings {
            axis: OrderAxis::FaultRelative { harmonics: 4.5 },
            ..FeatureSettings::default()
        };
        let json = serde_json::to_string(&relative).expect("serialises");
        let read: FeatureSettings = serde_json::from_str(&json).expect("reads");
        assert_eq!(read, relative);
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
