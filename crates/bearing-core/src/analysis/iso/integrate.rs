//! Acceleration to velocity: the frequency-domain integration of one window, and the
//! Welch-averaged severity of a whole record (`analyze`).

use super::zones::{band_hz, SeveritySettings, ZoneLimits, G};
use crate::analysis::envelope::{hop_samples, window_starts, FftPlans};
use crate::analysis::indicators::sum_of;
use crate::messages::IsoZone;
use realfft::RealToComplex;
use rustfft::num_complex::Complex32;
use serde::Serialize;
use std::sync::Arc;

/// Bins the lower band limit should lie above 0 Hz: a Hann window's main lobe spans ±2 bins,
/// so DC and the lowest lines stay out of the band.
pub const LOW_EDGE_BINS: f64 = 8.0;

/// The window for the band: a power of two putting the lower limit [`LOW_EDGE_BINS`] bins up,
/// shortened to the largest power of two the record holds (at least 64 samples).
pub fn window_for(len: usize, fs_hz: f64, band: (f64, f64)) -> usize {
    let wanted = (LOW_EDGE_BINS * fs_hz / band.0)
        .ceil()
        .clamp(64.0, (1u64 << 24) as f64) as usize;
    let fitting = if len >= 64 { 1usize << len.ilog2() } else { 64 };
    wanted.next_power_of_two().min(fitting)
}

/// Integrates acceleration windows to velocity in the frequency domain.
pub struct VelocityIntegrator {
    fft: Arc<dyn RealToComplex<f32>>,
    hann: Arc<[f32]>,
    input: Vec<f32>,
    spectrum: Vec<Complex32>,
    scratch: Vec<Complex32>,
    /// `1 / (N Σw²) · (g / 2π)²`: bin `k` at `f` in the band weighs `sides · scale / f²` (sides
    /// 2, or 1 for DC and Nyquist), and bin power × weight is that bin's share of the velocity
    /// mean square in (m/s)². Computed per window, not stored per bin: a table would be 128 KiB
    /// per channel for a few thousand divisions every half second.
    scale: f64,
    /// The bins inside the band.
    bins: std::ops::RangeInclusive<usize>,
    fs_hz: f64,
    band: (f64, f64),
}

impl VelocityIntegrator {
    pub fn new(window: usize, fs_hz: f64, band: (f64, f64), plans: &mut FftPlans) -> Self {
        let window = window.max(4);
        let fft = plans.real_forward_plan(window);
        let hann = plans.hann_window(window);
        let sum_w2: f64 = hann.iter().map(|&w| f64::from(w) * f64::from(w)).sum();
        let bin_hz = fs_hz / window as f64;
        let scale = (G / std::f64::consts::TAU).powi(2) / (window as f64 * sum_w2);
        // Bins strictly above 0 Hz whose frequency lies in the band.
        let first = ((band.0 / bin_hz).ceil() as usize).max(1);
        let last = ((band.1 / bin_hz).floor() as usize).min(window / 2);
        let bins = first..=last;
        VelocityIntegrator {
            input: fft.make_input_vec(),
            spectrum: fft.make_output_vec(),
            scratch: fft.make_scratch_vec(),
            fft,
            hann,
            scale,
            bins,
            fs_hz,
            band,
        }
    }

    pub fn window(&self) -> usize {
        self.input.len()
    }

    pub fn bin_hz(&self) -> f64 {
        self.fs_hz / self.window() as f64
    }

    pub fn band(&self) -> (f64, f64) {
        self.band
    }

    /// The velocity mean square, (m/s)², of one window of acceleration in g given as two
    /// consecutive parts (a ring buffer's older and newer halves); `per_bin`, if given, gets
    /// each bin's share added (for the spectrum of the plot).
    pub fn mean_square(
        &mut self,
        older: &[f32],
        newer: &[f32],
        per_bin: Option<&mut [f64]>,
    ) -> f64 {
        let n = self.input.len();
        if older.len() + newer.len() != n {
            return f64::NAN;
        }
        let mean = (sum_of(&[older, newer]) / n as f64) as f32;
        // The two parts one after the other (a chained iterator would not vectorise).
        let (input_older, input_newer) = self.input.split_at_mut(older.len());
        let (hann_older, hann_newer) = self.hann.split_at(older.len());
        for (input, part, hann) in [
            (input_older, older, hann_older),
            (input_newer, newer, hann_newer),
        ] {
            for ((slot, &x), &w) in input.iter_mut().zip(part).zip(hann) {
                *slot = (x - mean) * w;
            }
        }
        // Lengths match by construction, so the transform cannot fail.
        let _ =
            self.fft
                .process_with_scratch(&mut self.input, &mut self.spectrum, &mut self.scratch);
        let spectrum = &self.spectrum;
        self.in_band(|k| spectrum[k], per_bin)
    }

    /// The same mean square from the *unwindowed* real FFT of the same window (the envelope's,
    /// `window / 2 + 1` bins), which saves the daemon one window FFT per hop: a periodic Hann
    /// window is, in the frequency domain, `Xw[k] = ½X[k] − ¼(X[k−1] + X[k+1])`, and the mean
    /// reaches only bins 0 and 1, below the band ([`Self::takes_unwindowed`]). `per_bin`, if
    /// given, gets each bin's share added, as in [`Self::mean_square`].
    pub fn mean_square_of_unwindowed(
        &self,
        spectrum: &[Complex32],
        per_bin: Option<&mut [f64]>,
    ) -> f64 {
        let n = self.input.len();
        if spectrum.len() != n / 2 + 1 {
            return f64::NAN;
        }
        // Bins above n/2 mirror those below (a real signal).
        let bin = |k: usize| {
            if k <= n / 2 {
                spectrum[k]
            } else {
                spectrum[n - k].conj()
            }
        };
        self.in_band(|k| bin(k) * 0.5 - (bin(k - 1) + bin(k + 1)) * 0.25, per_bin)
    }

    /// Whether [`Self::mean_square_of_unwindowed`] applies: the band starts above bin 1.
    pub fn takes_unwindowed(&self) -> bool {
        *self.bins.start() >= 2
    }

    /// `Σ` over the band's bins of bin power × the integration weight; `per_bin`, if given,
    /// gets each bin's share added.
    fn in_band(&self, bin: impl Fn(usize) -> Complex32, mut per_bin: Option<&mut [f64]>) -> f64 {
        let half = self.input.len() / 2;
        let mut total = 0.0;
        for k in self.bins.clone() {
            let f = k as f64 * self.bin_hz();
            // The Nyquist bin has no mirror image: counted once, not twice.
            let sides = if k == half { 1.0 } else { 2.0 };
            let share = f64::from(bin(k).norm_sqr()) * sides * self.scale / (f * f);
            if let Some(out) = per_bin.as_deref_mut().and_then(|o| o.get_mut(k)) {
                *out += share;
            }
            total += share;
        }
        total
    }
}

/// The velocity severity of a whole record.
#[derive(Debug, Clone, Serialize)]
pub struct VelocitySeverity {
    /// Velocity RMS in the band, mm/s.
    pub rms_mm_s: f64,
    pub band_hz: [f64; 2],
    pub zone: IsoZone,
    pub limits: ZoneLimits,
    pub settings: SeveritySettings,
    pub window_samples: usize,
    pub windows_averaged: usize,
    pub bin_hz: f64,
    /// The record is too short to resolve the lower band limit (fewer than 4 bins up): the
    /// lowest part of the band is measured only roughly.
    pub low_edge_resolved: bool,
    /// Per bin from 0 Hz: velocity RMS² (mm/s)² of that bin (0 outside the band), for plots.
    #[serde(skip)]
    pub per_bin_mm2_s2: Vec<f64>,
}

impl VelocitySeverity {
    /// One line for people: the value, its zone and what the zone means, and the boundaries
    /// it was judged against (the text report and the plot say the same).
    pub fn summary(&self) -> String {
        let l = &self.limits;
        let rough = if self.low_edge_resolved {
            ""
        } else {
            "; the record is too short to resolve the lower band limit, so the lowest part of the band is measured roughly"
        };
        format!(
            "ISO 10816-3 velocity {:.2} mm/s RMS in {:.0}–{:.0} Hz: zone {} ({}); group {}, {} foundation: B from {}, C from {}, D from {} mm/s{rough}",
            self.rms_mm_s,
            self.band_hz[0],
            self.band_hz[1],
            self.zone.name(),
            self.zone.meaning(),
            self.settings.group.number(),
            self.settings.foundation.name(),
            l.ab_mm_s,
            l.bc_mm_s,
            l.cd_mm_s
        )
    }
}

/// The velocity severity of `signal` (acceleration in g at `fs_hz`) of a machine turning at
/// `rpm`. `None` when the record is shorter than 64 samples or the band lies above Nyquist.
pub fn record_severity(
    plans: &mut FftPlans,
    signal: &[f32],
    fs_hz: f64,
    rpm: f64,
    settings: SeveritySettings,
) -> Option<VelocitySeverity> {
    let (lo, hi) = band_hz(rpm);
    if signal.len() < 64 || fs_hz.is_nan() || fs_hz <= 2.0 * lo {
        return None;
    }
    let band = (lo, hi.min(fs_hz / 2.0));
    let window = window_for(signal.len(), fs_hz, band);
    let mut integrator = VelocityIntegrator::new(window, fs_hz, band, plans);
    let mut per_bin = vec![0.0; window / 2 + 1];
    let hop = hop_samples(window, 0.5);
    let mut sum = 0.0;
    let mut count = 0usize;
    for start in window_starts(signal.len(), window, hop) {
        sum += integrator.mean_square(&signal[start..start + window], &[], Some(&mut per_bin));
        count += 1;
    }
    if count == 0 {
        return None;
    }
    let scale = 1e6 / count as f64; // (m/s)² → (mm/s)², averaged
    per_bin.iter_mut().for_each(|v| *v *= scale);
    let rms_mm_s = (sum * scale).sqrt();
    let limits = ZoneLimits::of(settings.group, settings.foundation);
    let bin_hz = integrator.bin_hz();
    Some(VelocitySeverity {
        rms_mm_s,
        band_hz: [band.0, band.1],
        zone: limits.zone(rms_mm_s),
        limits,
        settings,
        window_samples: window,
        windows_averaged: count,
        bin_hz,
        low_edge_resolved: band.0 >= 4.0 * bin_hz,
        per_bin_mm2_s2: per_bin,
    })
}

#[cfg(test)]
mod tests {
    use super::super::test_signals::{analytic_mm_s, sine};
    use super::*;

    fn severity(signal: &[f32], fs: f64, rpm: f64) -> VelocitySeverity {
        record_severity(
            &mut FftPlans::default(),
            signal,
            fs,
            rpm,
            SeveritySettings::default(),
        )
        .unwrap()
    }

    #[test]
    fn one_g_at_100_hz_integrates_to_the_analytic_velocity() {
        // 1 g peak at 100 Hz: 9.80665/(2π·100)/√2 m/s = 11.036 mm/s.
        let want = analytic_mm_s(1.0, 100.0);
        assert!((want - 11.036).abs() < 1e-3, "{want}");
        for fs in [12_000.0, 25_600.0, 48_000.0] {
            let s = severity(&sine(1.0, 100.0, fs, 10.0), fs, 1800.0);
            let err = (s.rms_mm_s - want).abs() / want;
            assert!(err < 0.005, "fs {fs}: {} vs {want} mm/s", s.rms_mm_s);
            assert_eq!(s.zone, IsoZone::D);
            assert_eq!(s.band_hz, [10.0, 1000.0]);
            assert!(s.low_edge_resolved);
        }
        // Off-bin frequencies and other amplitudes too.
        for (a, f) in [(0.1, 37.3), (0.5, 512.7), (0.02, 950.0), (2.0, 12.5)] {
            let s = severity(&sine(a, f, 25_600.0, 10.0), 25_600.0, 1800.0);
            let want = analytic_mm_s(a, f);
            assert!(
                (s.rms_mm_s - want).abs() / want < 0.01,
                "{a} g at {f} Hz: {} vs {want}",
                s.rms_mm_s
            );
        }
    }

    #[test]
    fn band_limits_keep_out_what_the_standard_leaves_out() {
        let fs = 25_600.0;
        // 5 Hz and 1500 Hz lie outside 10-1000 Hz: next to nothing is measured.
        for f in [5.0, 1500.0, 3000.0] {
            let s = severity(&sine(1.0, f, fs, 20.0), fs, 1800.0);
            assert!(
                s.rms_mm_s < 0.01 * analytic_mm_s(1.0, f),
                "{f} Hz: {} mm/s",
                s.rms_mm_s
            );
        }
        // Below 600 rpm the band starts at 2 Hz: the 5 Hz line counts.
        let slow = severity(&sine(0.01, 5.0, fs, 40.0), fs, 300.0);
        assert_eq!(slow.band_hz, [2.0, 1000.0]);
        let want = analytic_mm_s(0.01, 5.0);
        assert!(
            (slow.rms_mm_s - want).abs() / want < 0.02,
            "{} vs {want}",
            slow.rms_mm_s
        );
        // Two lines, one in and one out of the band: only the one in counts.
        let mixed: Vec<f32> = sine(1.0, 100.0, fs, 10.0)
            .iter()
            .zip(sine(1.0, 2000.0, fs, 10.0))
            .map(|(a, b)| a + b)
            .collect();
        let s = severity(&mixed, fs, 1800.0);
        let want = analytic_mm_s(1.0, 100.0);
        assert!((s.rms_mm_s - want).abs() / want < 0.005);
    }

    #[test]
    fn a_dc_offset_adds_nothing() {
        let fs = 12_000.0;
        let with_offset: Vec<f32> = sine(0.1, 50.0, fs, 5.0).iter().map(|x| x + 3.0).collect();
        let s = severity(&with_offset, fs, 1800.0);
        let want = analytic_mm_s(0.1, 50.0);
        assert!((s.rms_mm_s - want).abs() / want < 0.01, "{}", s.rms_mm_s);
    }

    #[test]
    fn a_short_snapshot_is_measured_and_says_its_low_edge_is_rough() {
        let fs = 25_600.0;
        let s = severity(&sine(1.0, 100.0, fs, 0.1), fs, 1800.0);
        assert_eq!(s.window_samples, 2048);
        assert!(!s.low_edge_resolved);
        let want = analytic_mm_s(1.0, 100.0);
        assert!((s.rms_mm_s - want).abs() / want < 0.05, "{}", s.rms_mm_s);
    }
}
