//! The daemon's rolling velocity reading of one channel: a ring of samples (or the envelope's
//! window spectra) in, a reading every hop out, with nothing allocated per window.

use super::integrate::{window_for, VelocityIntegrator};
use super::zones::{band_hz, SeveritySettings, ZoneLimits};
use crate::analysis::envelope::{hop_samples, FftPlans};
use crate::messages::IsoZone;
use rustfft::num_complex::Complex32;
use serde::Serialize;

/// One reading of the rolling tracker.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VelocityReading {
    /// One past the last sample the reading covers (sample time).
    pub end_sample: u64,
    pub rms_mm_s: f64,
    pub zone: IsoZone,
    /// Windows in the mean (fewer than the tracker's `averages` just after a start or gap).
    pub windows_averaged: usize,
}

/// The velocity RMS of one channel, updated every hop over the last `averages` windows, for
/// the daemon's pipeline. Every buffer is allocated in [`VelocityTracker::new`]; `push`
/// allocates nothing.
pub struct VelocityTracker {
    integrator: VelocityIntegrator,
    band: (f64, f64),
    limits: ZoneLimits,
    /// The last `window` samples, circular; `ring_pos` is where the oldest sample sits.
    ring: Vec<f32>,
    ring_pos: usize,
    hop: usize,
    /// One past the last sample pushed, in the channel's sample time.
    samples: u64,
    /// Samples until the next hop ends.
    to_next_hop: usize,
    /// Samples by which every window end is delayed, below a hop ([`Self::with_phase`]).
    phase: usize,
    /// Mean squares of the last windows, circular.
    history: Vec<f64>,
    /// Readings come from the envelope's window spectra ([`Self::share_windows_with`]).
    shares_windows: bool,
    history_len: usize,
    history_pos: usize,
}

impl VelocityTracker {
    /// A tracker for a channel at `fs_hz` on a machine at `rpm` (which picks the band), with
    /// windows of the length the band needs, hops of half a window, and the mean over the
    /// last `averages` windows.
    pub fn new(
        fs_hz: f64,
        rpm: f64,
        settings: SeveritySettings,
        averages: usize,
        plans: &mut FftPlans,
    ) -> Self {
        let (lo, hi) = band_hz(rpm);
        let band = (lo, hi.min(fs_hz / 2.0));
        let window = window_for(usize::MAX, fs_hz, band);
        let integrator = VelocityIntegrator::new(window, fs_hz, band, plans);
        let window = integrator.window();
        let hop = hop_samples(window, 0.5);
        VelocityTracker {
            integrator,
            band,
            limits: ZoneLimits::of(settings.group, settings.foundation),
            ring: vec![0.0; window],
            ring_pos: 0,
            hop,
            samples: 0,
            to_next_hop: window,
            phase: 0,
            history: vec![0.0; averages.max(1)],
            shares_windows: false,
            history_len: 0,
            history_pos: 0,
        }
    }

    /// Ends every window `phase` samples later (less than a hop), as
    /// [`RollingEnvelope::with_phase`](crate::analysis::envelope::RollingEnvelope::with_phase).
    pub fn with_phase(mut self, phase: usize) -> Self {
        self.phase = phase.min(self.hop.saturating_sub(1));
        self.to_next_hop = self.integrator.window() + self.phase;
        self
    }

    pub fn window(&self) -> usize {
        self.integrator.window()
    }

    pub fn hop(&self) -> usize {
        self.hop
    }

    pub fn limits(&self) -> ZoneLimits {
        self.limits
    }

    /// The measurement band, Hz.
    pub fn band(&self) -> (f64, f64) {
        self.band
    }

    /// Starts again at `first_sample` of the channel's sample time (after a gap or a sensor
    /// restart): the next reading comes one whole window later, from new windows only.
    pub fn restart_at(&mut self, first_sample: u64) {
        self.samples = first_sample;
        self.to_next_hop = self.integrator.window() + self.phase;
        self.ring_pos = 0;
        self.history_len = 0;
        self.history_pos = 0;
    }

    /// Feeds a block of acceleration samples (g); hands every reading whose hop ends inside
    /// the block to `on_reading`, in order.
    /// Does nothing when the tracker shares the envelope's windows (its readings come from
    /// [`Self::reading_of_unwindowed`]).
    pub fn push(&mut self, block: &[f32], mut on_reading: impl FnMut(VelocityReading)) {
        if self.shares_windows {
            return;
        }
        let mut rest = block;
        while !rest.is_empty() {
            let take = rest.len().min(self.to_next_hop);
            self.write(&rest[..take]);
            rest = &rest[take..];
            self.samples += take as u64;
            self.to_next_hop -= take;
            if self.to_next_hop == 0 {
                self.to_next_hop = self.hop;
                on_reading(self.update());
            }
        }
    }

    fn write(&mut self, samples: &[f32]) {
        let n = self.ring.len();
        let mut rest = samples;
        while !rest.is_empty() {
            let take = rest.len().min(n - self.ring_pos);
            self.ring[self.ring_pos..self.ring_pos + take].copy_from_slice(&rest[..take]);
            self.ring_pos = (self.ring_pos + take) % n;
            rest = &rest[take..];
        }
    }

    /// Makes the tracker take its windows' spectra from the envelope's windows (the real FFT
    /// of the same raw samples) when those are its own windows: the same `window` and `hop`
    /// (and so the same phase, which both take from the hop). Then
    /// [`Self::reading_of_unwindowed`] replaces [`Self::push`] and the tracker keeps no samples.
    pub fn share_windows_with(mut self, window: usize, hop: usize) -> Self {
        if window == self.ring.len() && hop == self.hop && self.integrator.takes_unwindowed() {
            self.shares_windows = true;
            self.ring = Vec::new();
        }
        self
    }

    /// Whether readings come from [`Self::reading_of_unwindowed`] (see
    /// [`Self::share_windows_with`]).
    pub fn shares_windows(&self) -> bool {
        self.shares_windows
    }

    /// The reading of the window ending at `end_sample`, from that window's unwindowed real
    /// FFT (the envelope's).
    pub fn reading_of_unwindowed(
        &mut self,
        spectrum: &[Complex32],
        end_sample: u64,
    ) -> VelocityReading {
        self.samples = end_sample;
        let ms = self.integrator.mean_square_of_unwindowed(spectrum, None);
        self.record(ms)
    }

    fn update(&mut self) -> VelocityReading {
        let (newer, older) = self.ring.split_at(self.ring_pos);
        let ms = self.integrator.mean_square(older, newer, None);
        self.record(ms)
    }

    /// Takes the newest window's mean square into the average.
    fn record(&mut self, ms: f64) -> VelocityReading {
        self.history[self.history_pos] = ms;
        self.history_pos = (self.history_pos + 1) % self.history.len();
        self.history_len = (self.history_len + 1).min(self.history.len());
        let mean = self.history[..self.history_len].iter().sum::<f64>() / self.history_len as f64;
        let rms_mm_s = mean.sqrt() * 1e3;
        VelocityReading {
            end_sample: self.samples,
            rms_mm_s,
            zone: self.limits.zone(rms_mm_s),
            windows_averaged: self.history_len,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_signals::{analytic_mm_s, sine};
    use super::*;
    use crate::analysis::flags::FlagSettings;

    #[test]
    fn the_rolling_tracker_agrees_with_the_record_and_its_zone_flag_has_hysteresis() {
        let fs = 12_000.0;
        let mut plans = FftPlans::default();
        let mut tracker =
            VelocityTracker::new(fs, 1800.0, SeveritySettings::default(), 4, &mut plans);
        let quiet = sine(0.05, 100.0, fs, 6.0); // 0.55 mm/s: zone A
        let loud = sine(0.4, 100.0, fs, 6.0); // 4.4 mm/s: zone C
        let mut readings = Vec::new();
        for block in quiet.chunks(750).chain(loud.chunks(750)) {
            tracker.push(block, |r| readings.push(r));
        }
        let hop = tracker.window() as u64 / 2;
        assert!(readings
            .windows(2)
            .all(|w| w[1].end_sample - w[0].end_sample == hop));
        let first = readings[0];
        let want = analytic_mm_s(0.05, 100.0);
        assert!((first.rms_mm_s - want).abs() / want < 0.01, "{first:?}");
        assert_eq!(first.zone, IsoZone::A);
        let last = readings.last().unwrap();
        assert!((last.rms_mm_s - analytic_mm_s(0.4, 100.0)).abs() < 0.05);
        assert_eq!(last.zone, IsoZone::C);

        let like = FlagSettings {
            watch_score: 0.0,
            alarm_score: 0.0,
            clear_ratio: 0.8,
            on_delay_samples: 12_000,
            off_delay_samples: 24_000,
        };
        let mut flag =
            crate::analysis::flags::FaultFlag::new(tracker.limits().flag_settings(&like));
        let changes: Vec<_> = readings
            .iter()
            .filter_map(|r| flag.update(r.rms_mm_s, r.end_sample))
            .collect();
        assert_eq!(changes.len(), 1, "{changes:?}");
        assert_eq!(changes[0].to, crate::messages::FlagLevel::Watch);
    }

    #[test]
    fn a_tracker_sharing_the_envelopes_windows_reads_what_its_own_fft_reads() {
        use crate::analysis::envelope::RollingEnvelope;
        let fs = 25_600.0;
        let mut plans = FftPlans::default();
        let own = VelocityTracker::new(fs, 1772.0, SeveritySettings::default(), 4, &mut plans);
        let (window, hop) = (own.window(), own.hop());
        let mut own = own.with_phase(300);
        let mut shared =
            VelocityTracker::new(fs, 1772.0, SeveritySettings::default(), 4, &mut plans)
                .with_phase(300)
                .share_windows_with(window, hop);
        assert!(shared.shares_windows());
        let mut rolling = RollingEnvelope::new(fs, window, hop, 1, &[], 16).with_phase(300);
        // A 1 g offset (gravity), two tones and a little noise: the offset must not leak in.
        let mut rng = crate::random::Rng::new(7);
        let signal: Vec<f32> = (0..(fs * 6.0) as usize)
            .map(|n| {
                let t = n as f64 / fs;
                (1.0 + 0.3 * (std::f64::consts::TAU * 29.5 * t).sin()
                    + 0.05 * (std::f64::consts::TAU * 480.0 * t).sin()
                    + 0.01 * rng.normal()) as f32
            })
            .collect();
        let (mut mine, mut theirs) = (Vec::new(), Vec::new());
        for block in signal.chunks(2_560) {
            own.push(block, |r| mine.push(r));
            shared.push(block, |_| {
                panic!("a sharing tracker reads from the envelope only")
            });
            rolling.push(block, |update| {
                theirs.push(shared.reading_of_unwindowed(update.window_spectrum, update.end_sample))
            });
        }
        assert_eq!(mine.len(), theirs.len());
        assert!(mine.len() >= 8, "{} readings", mine.len());
        for (a, b) in mine.iter().zip(&theirs) {
            assert_eq!(a.end_sample, b.end_sample);
            let relative = (a.rms_mm_s - b.rms_mm_s).abs() / a.rms_mm_s;
            assert!(relative < 1e-4, "{a:?} vs {b:?}");
            assert_eq!(a.zone, b.zone);
        }
        // Different windows: no sharing.
        let other = VelocityTracker::new(fs, 1772.0, SeveritySettings::default(), 4, &mut plans)
            .share_windows_with(window / 2, hop / 2);
        assert!(!other.shares_windows());
    }
}
