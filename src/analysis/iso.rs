//! Vibration severity after ISO 10816-3 / ISO 20816-3: the broadband velocity RMS of the
//! machine, integrated from the measured acceleration, and the evaluation zone it falls in.
//!
//! Why it is here: envelope analysis answers "which bearing part is damaged"; plant
//! engineers also judge a machine by its overall velocity against the standard's zones, and
//! will not trust a monitor that cannot tell them that number. It is sans-IO like the rest of
//! `analysis`: samples in, readings out, buffers owned, nothing allocated per window.
//!
//! Method (see `docs/ISO.md`):
//! - the velocity is integrated in the frequency domain: per window (Hann, mean removed), the
//!   one-sided power of every bin of the acceleration spectrum is divided by `(2πf)²`;
//! - only bins whose centre lies in the standard's band count: 10–1000 Hz, or 2–1000 Hz for
//!   machines below 600 rpm (a brick-wall band; the standard's instruments roll off, which
//!   changes little for a broadband signal);
//! - the mean square is averaged over windows (Welch, 50 % overlap); the RMS in mm/s is its
//!   square root; the zone follows from the boundaries of the machine's group and foundation.
//!
//! The window is long enough to put the lower band limit [`LOW_EDGE_BINS`] bins above 0 Hz
//! (16,384 samples at 12 or 25.6 kHz for 10 Hz), or as long as the record allows; a record too
//! short to resolve the lower limit is measured all the same and says so.

use super::envelope::{hop_samples, window_starts, FftPlans};
use super::flags::FlagSettings;
use super::indicators::sum_of;
use crate::messages::IsoZone;
use realfft::RealToComplex;
use rustfft::num_complex::Complex32;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Standard gravity, m/s² per g.
pub const G: f64 = 9.806_65;

/// The machine groups of ISO 10816-3 / 20816-3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MachineGroup {
    /// Group 1: large machines, rated power above 300 kW (electrical machines with shaft
    /// height H ≥ 315 mm).
    Large,
    /// Group 2: medium-sized machines, 15 kW to 300 kW (electrical machines with
    /// 160 mm ≤ H < 315 mm).
    Medium,
}

impl MachineGroup {
    /// The group's number in the standard.
    pub fn number(self) -> u8 {
        match self {
            MachineGroup::Large => 1,
            MachineGroup::Medium => 2,
        }
    }

    /// Group 1 or 2.
    pub fn from_number(n: i64) -> Option<Self> {
        match n {
            1 => Some(MachineGroup::Large),
            2 => Some(MachineGroup::Medium),
            _ => None,
        }
    }
}

/// The support of the machine: rigid (lowest natural frequency of machine and support above
/// 1.25 × the main excitation) or flexible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Foundation {
    Rigid,
    Flexible,
}

impl Foundation {
    pub fn name(self) -> &'static str {
        match self {
            Foundation::Rigid => "rigid",
            Foundation::Flexible => "flexible",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "rigid" => Some(Foundation::Rigid),
            "flexible" => Some(Foundation::Flexible),
            _ => None,
        }
    }
}

/// IsoZone boundaries, velocity RMS in mm/s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ZoneLimits {
    pub ab_mm_s: f64,
    pub bc_mm_s: f64,
    pub cd_mm_s: f64,
}

impl ZoneLimits {
    /// The boundaries of ISO 10816-3:2009 Annex A, Tables A.1 (group 1) and A.2 (group 2),
    /// kept by ISO 20816-3:2022 for these groups (docs/ISO.md).
    pub fn of(group: MachineGroup, foundation: Foundation) -> Self {
        let (ab_mm_s, bc_mm_s, cd_mm_s) = match (group, foundation) {
            (MachineGroup::Large, Foundation::Rigid) => (2.3, 4.5, 7.1),
            (MachineGroup::Large, Foundation::Flexible) => (3.5, 7.1, 11.0),
            (MachineGroup::Medium, Foundation::Rigid) => (1.4, 2.8, 4.5),
            (MachineGroup::Medium, Foundation::Flexible) => (2.3, 4.5, 7.1),
        };
        ZoneLimits {
            ab_mm_s,
            bc_mm_s,
            cd_mm_s,
        }
    }

    /// The zone of a velocity RMS; a value on a boundary belongs to the zone above.
    pub fn zone(&self, v_mm_s: f64) -> IsoZone {
        if v_mm_s < self.ab_mm_s {
            IsoZone::A
        } else if v_mm_s < self.bc_mm_s {
            IsoZone::B
        } else if v_mm_s < self.cd_mm_s {
            IsoZone::C
        } else {
            IsoZone::D
        }
    }

    /// Flag thresholds for zone C (watch) and zone D (alarm), with the fault flags' clear
    /// ratio and delays: the daemon's zone flag is a [`super::flags::FaultFlag`] fed with
    /// the velocity RMS.
    pub fn flag_settings(&self, like: &FlagSettings) -> FlagSettings {
        FlagSettings {
            watch_score: self.bc_mm_s,
            alarm_score: self.cd_mm_s,
            ..*like
        }
    }
}

/// Which machine is measured: its group and foundation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeveritySettings {
    pub group: MachineGroup,
    pub foundation: Foundation,
}

impl Default for SeveritySettings {
    /// Group 2 on a rigid foundation: the medium-sized motor bearingd is made for, with the
    /// strictest boundaries of group 2.
    fn default() -> Self {
        SeveritySettings {
            group: MachineGroup::Medium,
            foundation: Foundation::Rigid,
        }
    }
}

/// Machines slower than this use the 2 Hz lower band limit.
pub const SLOW_MACHINE_RPM: f64 = 600.0;

/// The measurement band of the standard, Hz: 10–1000, or 2–1000 below 600 rpm.
pub fn band_hz(rpm: f64) -> (f64, f64) {
    if rpm < SLOW_MACHINE_RPM {
        (2.0, 1000.0)
    } else {
        (10.0, 1000.0)
    }
}

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
    /// reaches only bins 0 and 1, below the band ([`Self::takes_unwindowed`]).
    pub fn mean_square_of_unwindowed(&self, spectrum: &[Complex32]) -> f64 {
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
        self.in_band(|k| bin(k) * 0.5 - (bin(k - 1) + bin(k + 1)) * 0.25, None)
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
        let ms = self.integrator.mean_square_of_unwindowed(spectrum);
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
    use super::*;

    fn sine(amplitude_g: f64, f: f64, fs: f64, seconds: f64) -> Vec<f32> {
        (0..(fs * seconds) as usize)
            .map(|n| (amplitude_g * (std::f64::consts::TAU * f * n as f64 / fs).sin()) as f32)
            .collect()
    }

    /// v_rms of a sine of peak acceleration `a` g at `f` Hz: a·g/(2πf)/√2, in mm/s.
    fn analytic_mm_s(a: f64, f: f64) -> f64 {
        a * G / (std::f64::consts::TAU * f) / 2f64.sqrt() * 1e3
    }

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
    fn zones_of_each_group_and_foundation() {
        let medium_rigid = ZoneLimits::of(MachineGroup::Medium, Foundation::Rigid);
        assert_eq!(
            [0.5, 1.4, 2.0, 2.8, 4.49, 4.5].map(|v| medium_rigid.zone(v)),
            [
                IsoZone::A,
                IsoZone::B,
                IsoZone::B,
                IsoZone::C,
                IsoZone::C,
                IsoZone::D
            ]
        );
        let large_flexible = ZoneLimits::of(MachineGroup::Large, Foundation::Flexible);
        assert_eq!(
            (
                large_flexible.ab_mm_s,
                large_flexible.bc_mm_s,
                large_flexible.cd_mm_s
            ),
            (3.5, 7.1, 11.0)
        );
        assert_eq!(large_flexible.zone(10.0), IsoZone::C);
        assert_eq!(
            ZoneLimits::of(MachineGroup::Large, Foundation::Rigid).zone(4.0),
            IsoZone::B
        );
        assert_eq!(
            ZoneLimits::of(MachineGroup::Medium, Foundation::Flexible).zone(7.1),
            IsoZone::D
        );
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
        let mut flag = super::super::flags::FaultFlag::new(tracker.limits().flag_settings(&like));
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
