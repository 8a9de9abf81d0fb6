//! Squared-envelope spectrum (MODELS.md §2): FFT band-pass, analytic signal, squared envelope,
//! Hann window, FFT, Welch averaging.
//!
//! Why it is built from two pieces: the real FFT of a window ([`WindowTransform`]) is shared by
//! every band analysed on that window, and the per-band work ([`BandEnvelope`]) runs on a
//! short, decimated buffer: the band's bins are moved to baseband and inverse-transformed at
//! the smallest length that keeps the envelope spectrum alias-free up to the highest frequency
//! asked for. The same two pieces serve the batch form ([`welch_envelope_spectrum`], used by
//! `analyze`) and the rolling form ([`RollingEnvelope`], used by the daemon), so both compute
//! every window the same way. All buffers are allocated at construction; nothing allocates per window.

use super::band::Band;
use super::real_fft::{RealFftBuffers, RealForwardFft};
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::collections::HashMap;
use std::sync::Arc;

/// Cached FFT plans and Hann windows. Planning is slow (twiddle factors, cosines); one
/// `FftPlans` kept for the life of an analyser shares them among every transform of a size.
pub struct FftPlans {
    complex: FftPlanner<f32>,
    real: RealFftPlanner<f32>,
    window: HashMap<usize, Arc<RealForwardFft>>,
    hann: HashMap<usize, Arc<[f32]>>,
}

impl Default for FftPlans {
    fn default() -> Self {
        FftPlans {
            complex: FftPlanner::new(),
            real: RealFftPlanner::new(),
            window: HashMap::new(),
            hann: HashMap::new(),
        }
    }
}

impl FftPlans {
    /// One cache for the whole process, for the daemon's many channels: plans and Hann
    /// windows of a size exist once, not once per channel. Locked only while planning
    /// (construction and band changes), never per hop.
    pub fn shared() -> std::sync::MutexGuard<'static, FftPlans> {
        static SHARED: std::sync::OnceLock<std::sync::Mutex<FftPlans>> = std::sync::OnceLock::new();
        let mutex = SHARED.get_or_init(|| std::sync::Mutex::new(FftPlans::default()));
        // A panic while planning cannot leave the cache inconsistent: take it as it is.
        mutex
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn hann(&mut self, len: usize) -> Arc<[f32]> {
        self.hann
            .entry(len)
            .or_insert_with(|| hann(len).into())
            .clone()
    }

    /// The cached Hann window of `len` samples.
    pub(crate) fn hann_window(&mut self, len: usize) -> Arc<[f32]> {
        self.hann(len)
    }

    /// The cached forward real FFT of `len` samples.
    pub(crate) fn real_forward_plan(&mut self, len: usize) -> Arc<dyn RealToComplex<f32>> {
        self.real_forward(len)
    }

    fn inverse(&mut self, len: usize) -> Arc<dyn Fft<f32>> {
        self.complex.plan_fft_inverse(len)
    }

    fn real_forward(&mut self, len: usize) -> Arc<dyn RealToComplex<f32>> {
        self.real.plan_fft_forward(len)
    }

    /// The cached window transform of `len` samples ([`RealForwardFft`]).
    fn window_forward(&mut self, len: usize) -> Arc<RealForwardFft> {
        let complex = &mut self.complex;
        self.window
            .entry(len)
            .or_insert_with(|| Arc::new(RealForwardFft::new(len, complex)))
            .clone()
    }
}

/// The smallest `2^a · 3^b` not below `n`: lengths that rustfft transforms fastest.
pub fn fast_fft_len(n: usize) -> usize {
    let n = n.max(2);
    let mut best = n.next_power_of_two();
    let mut three = 1usize;
    while three < best {
        let candidate = three * (n.div_ceil(three)).next_power_of_two();
        best = best.min(candidate);
        three *= 3;
    }
    best
}

/// The window length, in samples, for a window of `window_s` seconds at `fs_hz`: the nearest
/// power of two (in log scale), so that the main transform is as fast as it can be.
pub fn window_samples(window_s: f64, fs_hz: f64) -> usize {
    let exact = (window_s * fs_hz).max(64.0);
    1usize << (exact.log2().round() as u32).min(30)
}

/// `Σ |c|²` and `Σ |c|⁴` of a run of complex samples. Eight independent accumulators let the
/// compiler vectorise the loop (a single running sum is a serial dependency chain).
pub fn power_moments(values: &[Complex32]) -> (f32, f32) {
    let mut sum2 = [0f32; 8];
    let mut sum4 = [0f32; 8];
    let chunks = values.chunks_exact(8);
    let rest = chunks.remainder();
    for chunk in chunks {
        for ((s2, s4), c) in sum2.iter_mut().zip(sum4.iter_mut()).zip(chunk) {
            let e = c.norm_sqr();
            *s2 += e;
            *s4 += e * e;
        }
    }
    for (i, c) in rest.iter().enumerate() {
        let e = c.norm_sqr();
        sum2[i] += e;
        sum4[i] += e * e;
    }
    (sum2.iter().sum(), sum4.iter().sum())
}

/// Periodic Hann window of length `len`.
pub fn hann(len: usize) -> Vec<f32> {
    (0..len)
        .map(|i| {
            let phase = std::f64::consts::TAU * i as f64 / len as f64;
            (0.5 - 0.5 * phase.cos()) as f32
        })
        .collect()
}

/// The real FFT of one analysis window of raw samples.
pub struct WindowTransform {
    fft: Arc<RealForwardFft>,
    buffers: RealFftBuffers,
}

impl WindowTransform {
    pub fn new(window: usize, plans: &mut FftPlans) -> Self {
        let fft = plans.window_forward(window);
        WindowTransform {
            buffers: fft.buffers(),
            fft,
        }
    }

    pub fn window(&self) -> usize {
        self.fft.samples()
    }

    /// Transforms the window formed by `older` followed by `newer` (the two halves of a ring
    /// buffer, or one slice and an empty one); their lengths must add up to the window.
    pub fn transform(&mut self, older: &[f32], newer: &[f32]) -> &[Complex32] {
        self.fft.transform(older, newer, &mut self.buffers)
    }

    pub fn spectrum(&self) -> &[Complex32] {
        self.buffers.spectrum()
    }
}

/// Band-pass, analytic signal and squared-envelope spectrum of one band, on the spectrum of
/// a window computed by [`WindowTransform`].
pub struct BandEnvelope {
    band: Band,
    first_bin: usize,
    bin_count: usize,
    /// `2 / window`: scales the band's bins so that `|analytic|` is the signal's amplitude.
    bin_scale: f32,
    inverse: Arc<dyn Fft<f32>>,
    analytic: Vec<Complex32>,
    inverse_scratch: Vec<Complex32>,
    envelope_fft: Arc<dyn RealToComplex<f32>>,
    envelope: Vec<f32>,
    envelope_spectrum: Vec<Complex32>,
    envelope_scratch: Vec<Complex32>,
    hann: Arc<[f32]>,
    /// `(2 / Σ hann)²`: turns `|FFT|²` into the squared amplitude of each envelope component.
    power_scale: f32,
    spectrum_bins: usize,
}

impl BandEnvelope {
    /// `spectrum_bins`: how many envelope-spectrum bins (spaced `fs_hz / window`) to produce,
    /// from 0 Hz up.
    pub fn new(
        band: Band,
        fs_hz: f64,
        window: usize,
        spectrum_bins: usize,
        plans: &mut FftPlans,
    ) -> Self {
        let (first_bin, last_bin) = band.bins(fs_hz, window);
        let bin_count = last_bin - first_bin;
        // The squared envelope of a band of B bins reaches B bins; at a length L its spectrum
        // folds at L - B, so L >= B + spectrum_bins keeps [0, spectrum_bins) alias-free.
        let len = fast_fft_len((bin_count + spectrum_bins).max(2 * spectrum_bins));
        let inverse = plans.inverse(len);
        let envelope_fft = plans.real_forward(len);
        let hann = plans.hann(len);
        let hann_sum: f32 = hann.iter().sum();
        BandEnvelope {
            band,
            first_bin,
            bin_count,
            bin_scale: 2.0 / window as f32,
            inverse_scratch: vec![Complex32::default(); inverse.get_inplace_scratch_len()],
            inverse,
            analytic: vec![Complex32::default(); len],
            envelope: envelope_fft.make_input_vec(),
            envelope_spectrum: envelope_fft.make_output_vec(),
            envelope_scratch: envelope_fft.make_scratch_vec(),
            envelope_fft,
            hann,
            power_scale: (2.0 / hann_sum).powi(2),
            spectrum_bins,
        }
    }

    pub fn band(&self) -> Band {
        self.band
    }

    /// Length of the decimated analytic signal of one window.
    pub fn analytic_len(&self) -> usize {
        self.analytic.len()
    }

    pub fn spectrum_bins(&self) -> usize {
        self.spectrum_bins
    }

    /// The band's analytic signal over the window, shifted to baseband and decimated: its
    /// magnitude is the envelope.
    pub fn analytic_from(&mut self, window_spectrum: &[Complex32]) -> &[Complex32] {
        let source = &window_spectrum[self.first_bin..self.first_bin + self.bin_count];
        for (dst, src) in self.analytic.iter_mut().zip(source) {
            *dst = src * self.bin_scale;
        }
        self.analytic[self.bin_count..].fill(Complex32::default());
        self.inverse
            .process_with_scratch(&mut self.analytic, &mut self.inverse_scratch);
        &self.analytic
    }

    /// The squared-envelope power spectrum of the analytic signal last computed by
    /// [`Self::analytic_from`], written into `out` (`spectrum_bins` values, squared amplitude
    /// in g⁴ of each envelope component).
    pub fn squared_envelope_power(&mut self, out: &mut [f32]) {
        let len = self.envelope.len() as f32;
        let mean = power_moments(&self.analytic).0 / len;
        for ((e, c), w) in self
            .envelope
            .iter_mut()
            .zip(&self.analytic)
            .zip(self.hann.iter())
        {
            *e = (c.norm_sqr() - mean) * w;
        }
        let _ = self.envelope_fft.process_with_scratch(
            &mut self.envelope,
            &mut self.envelope_spectrum,
            &mut self.envelope_scratch,
        );
        for (o, s) in out.iter_mut().zip(&self.envelope_spectrum) {
            *o = s.norm_sqr() * self.power_scale;
        }
    }

    /// Both steps at once: the squared-envelope power spectrum of this band on a window.
    pub fn process(&mut self, window_spectrum: &[Complex32], out: &mut [f32]) {
        self.analytic_from(window_spectrum);
        self.squared_envelope_power(out);
    }
}

/// Start indices of the Welch windows over a record of `len` samples.
pub fn window_starts(len: usize, window: usize, hop: usize) -> impl Iterator<Item = usize> {
    let count = if len >= window {
        (len - window) / hop.max(1) + 1
    } else {
        0
    };
    (0..count).map(move |i| i * hop.max(1))
}

/// Hop length for a window and an overlap fraction.
pub fn hop_samples(window: usize, overlap: f64) -> usize {
    ((window as f64 * (1.0 - overlap)).round() as usize).clamp(1, window)
}

/// A Welch-averaged envelope spectrum: amplitude (square root of the mean power) per bin.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvelopeSpectrum {
    pub band: Band,
    /// Bin spacing in Hz (`fs / window`).
    pub bin_hz: f64,
    /// Amplitude of each envelope component, in g², from 0 Hz up.
    pub amplitude: Vec<f32>,
    pub windows_averaged: usize,
}

impl EnvelopeSpectrum {
    pub fn frequencies(&self) -> impl Iterator<Item = f64> + '_ {
        (0..self.amplitude.len()).map(|k| k as f64 * self.bin_hz)
    }
}

/// Turns a sum of power spectra into the averaged amplitude.
pub fn averaged_amplitude(power_sum: &[f64], count: usize) -> Vec<f32> {
    let count = count.max(1) as f64;
    power_sum
        .iter()
        .map(|p| (p / count).sqrt() as f32)
        .collect()
}

/// Batch form: the Welch-averaged squared-envelope spectrum of a whole record in one band.
pub fn welch_envelope_spectrum(
    plans: &mut FftPlans,
    signal: &[f32],
    fs_hz: f64,
    band: Band,
    window: usize,
    overlap: f64,
    spectrum_bins: usize,
) -> EnvelopeSpectrum {
    let mut transform = WindowTransform::new(window, plans);
    let mut envelope = BandEnvelope::new(band, fs_hz, window, spectrum_bins, plans);
    let mut power = vec![0f32; spectrum_bins];
    let mut sum = vec![0f64; spectrum_bins];
    let mut count = 0;
    for start in window_starts(signal.len(), window, hop_samples(window, overlap)) {
        let spectrum = transform.transform(&signal[start..start + window], &[]);
        envelope.process(spectrum, &mut power);
        for (s, p) in sum.iter_mut().zip(&power) {
            *s += f64::from(*p);
        }
        count += 1;
    }
    EnvelopeSpectrum {
        band,
        bin_hz: fs_hz / window as f64,
        amplitude: averaged_amplitude(&sum, count),
        windows_averaged: count,
    }
}

/// One band of the rolling form: its envelope engine, the newest spectrum and the average.
pub struct RollingBand {
    envelope: BandEnvelope,
    latest: Vec<f32>,
    /// `averages` power spectra, oldest overwritten first.
    history: Vec<f32>,
    averaged: Vec<f32>,
}

impl RollingBand {
    pub fn band(&self) -> Band {
        self.envelope.band()
    }

    /// The newest window's power spectrum.
    pub fn latest_power(&self) -> &[f32] {
        &self.latest
    }

    /// The average over the last windows, as amplitude (g²).
    pub fn averaged_amplitude(&self) -> &[f32] {
        &self.averaged
    }
}

/// A hop's window as soon as its FFT is done, before any band's envelope: what decides on the
/// window alone (a detector on its spectrum, the indicators on its samples) runs here, so that
/// its flag, and the alert it may raise, never waits for the bands.
pub struct WindowReady<'a> {
    /// Sample index (in the channel's sample time) one past the last sample of the window.
    pub end_sample: u64,
    /// The raw samples of the window, oldest first, as two slices of the ring buffer.
    pub window_samples: (&'a [f32], &'a [f32]),
    /// The real FFT of those samples (no window function), `window / 2 + 1` bins.
    pub window_spectrum: &'a [Complex32],
}

/// The stages of a hop, in this order ([`RollingEnvelope::push_staged`]): the window, each
/// band engine's envelope in turn, then the whole update.
pub enum HopStage<'a> {
    /// The window's FFT is done; the bands are not.
    Window(&'a WindowReady<'a>),
    /// One band engine's envelope spectrum and average are done (engine `engine` of
    /// [`EnvelopeUpdate::bands`]).
    Band {
        engine: usize,
        band: &'a RollingBand,
        /// For each band asked for, in order, the index of its engine.
        band_of: &'a [usize],
        bin_hz: f64,
    },
    /// Every band's envelope spectrum and average is done.
    Bands(&'a EnvelopeUpdate<'a>),
}

/// One update of the rolling envelope spectrum, handed to the caller every hop.
pub struct EnvelopeUpdate<'a> {
    /// Sample index (in the channel's sample time) one past the last sample of the window.
    pub end_sample: u64,
    pub bin_hz: f64,
    /// How many windows the averages hold.
    pub windows_averaged: usize,
    /// One engine per distinct band asked for ([`Self::band`] finds a band's engine).
    pub bands: &'a [RollingBand],
    /// For each band asked for, in order, the index of its engine in `bands`.
    pub band_of: &'a [usize],
    /// The real FFT of the window (no window function), `window / 2 + 1` bins.
    pub window_spectrum: &'a [Complex32],
}

impl EnvelopeUpdate<'_> {
    /// The engine of the `i`-th band asked for.
    pub fn band(&self, i: usize) -> Option<&RollingBand> {
        self.band_of
            .get(i)
            .and_then(|&engine| self.bands.get(engine))
    }
}

/// Rolling form: a ring buffer of the last window of samples; every hop, for each band, the
/// envelope spectrum of the newest window and the average of the last `averages` windows. The
/// window's FFT is shared by the bands, and a band asked for twice (two faults whose best band
/// is the same) is computed once.
///
/// The band work may be spread over the samples after the window ([`Self::spread_bands`]): the
/// daemon's block that closes a window then does only the window's FFT and what decides on it,
/// and each band engine's envelope follows at a fixed sample after the window's end, so a
/// replay cut in other blocks does the same work at the same samples.
///
/// All memory is allocated in [`RollingEnvelope::new`] and [`RollingEnvelope::set_bands`];
/// [`RollingEnvelope::push`] never allocates (tested with a counting allocator).
pub struct RollingEnvelope {
    fs_hz: f64,
    hop: usize,
    averages: usize,
    spectrum_bins: usize,
    ring: Vec<f32>,
    /// Index in `ring` where the next sample goes; also where the oldest sample is once full.
    write_at: usize,
    until_update: usize,
    /// Samples by which every window end is delayed, below a hop ([`Self::with_phase`]).
    phase: usize,
    samples_seen: u64,
    transform: WindowTransform,
    /// One engine per distinct band.
    bands: Vec<RollingBand>,
    /// For each band asked for, its engine.
    band_of: Vec<usize>,
    history_used: usize,
    history_next: usize,
    /// Samples between two band engines' envelopes after a window; 0: all at the window.
    band_step: usize,
    /// The newest window's band work not done yet.
    pending: Option<PendingBands>,
}

/// What is left of a window's band work: the engines from `next_engine` on, the next one
/// `until_step` samples from now, each writing its spectrum to history slot `slot`.
#[derive(Clone, Copy)]
struct PendingBands {
    next_engine: usize,
    until_step: usize,
    slot: usize,
    end_sample: u64,
}

impl RollingEnvelope {
    pub fn new(
        fs_hz: f64,
        window: usize,
        hop: usize,
        averages: usize,
        bands: &[Band],
        spectrum_bins: usize,
    ) -> Self {
        let transform = WindowTransform::new(window, &mut FftPlans::shared());
        let mut rolling = RollingEnvelope {
            fs_hz,
            hop: hop.clamp(1, window),
            averages: averages.max(1),
            spectrum_bins,
            ring: vec![0.0; window],
            write_at: 0,
            until_update: window,
            phase: 0,
            samples_seen: 0,
            transform,
            bands: Vec::new(),
            band_of: Vec::new(),
            history_used: 0,
            history_next: 0,
            band_step: 0,
            pending: None,
        };
        rolling.set_bands(bands);
        rolling
    }

    /// Ends every window `phase` samples later (less than a hop): the first after
    /// `window + phase` samples, then every hop. Channels of one daemon take different phases
    /// so that their windows do not all close on the same block.
    pub fn with_phase(mut self, phase: usize) -> Self {
        self.phase = phase.min(self.hop - 1);
        self.until_update = self.ring.len() + self.phase;
        self
    }

    /// Spreads each window's band work over the hop: the window's stage at its end, then one
    /// band engine every `hop / 5` samples (at most four engines, so all are done within the
    /// hop), the whole update with the last. A caller that changes the bands, the time base
    /// or what the update is read with first finishes the band work ([`Self::finish_bands`]).
    pub fn spread_bands(mut self) -> Self {
        self.band_step = (self.hop / 5).max(1);
        self
    }

    /// Whether a window's band work is still to be done.
    pub fn bands_pending(&self) -> bool {
        self.pending.is_some()
    }

    pub fn bands(&self) -> &[RollingBand] {
        &self.bands
    }

    pub fn window(&self) -> usize {
        self.ring.len()
    }

    pub fn hop(&self) -> usize {
        self.hop
    }

    pub fn bin_hz(&self) -> f64 {
        self.fs_hz / self.ring.len() as f64
    }

    pub fn samples_seen(&self) -> u64 {
        self.samples_seen
    }

    /// Switches to other bands (allocates; meant for the periodic band re-selection, not per
    /// hop). The averages restart, since spectra of different bands do not mix. A window's
    /// band work still to be done is dropped: finish it first ([`Self::finish_bands`]).
    pub fn set_bands(&mut self, bands: &[Band]) {
        debug_assert!(self.pending.is_none(), "a window's band work was dropped");
        self.pending = None;
        let (bins, averages, window) = (self.spectrum_bins, self.averages, self.ring.len());
        let mut plans = FftPlans::shared();
        self.bands.clear();
        self.band_of.clear();
        for &band in bands {
            let engine = match self.bands.iter().position(|b| b.band() == band) {
                Some(engine) => engine,
                None => {
                    self.bands.push(RollingBand {
                        envelope: BandEnvelope::new(band, self.fs_hz, window, bins, &mut plans),
                        latest: vec![0.0; bins],
                        history: vec![0.0; averages * bins],
                        averaged: vec![0.0; bins],
                    });
                    self.bands.len() - 1
                }
            };
            self.band_of.push(engine);
        }
        self.history_used = 0;
        self.history_next = 0;
    }

    /// Forgets the buffered samples (after a gap in the signal: a window must never straddle
    /// a gap) and restarts the averages. `next_sample` is the sample index of the next sample.
    /// A window's band work still to be done is dropped: finish it first.
    pub fn restart_at(&mut self, next_sample: u64) {
        debug_assert!(self.pending.is_none(), "a window's band work was dropped");
        self.pending = None;
        self.write_at = 0;
        self.until_update = self.ring.len() + self.phase;
        self.samples_seen = next_sample;
        self.history_used = 0;
        self.history_next = 0;
    }

    /// Feeds samples; calls `on_update` once per completed hop.
    pub fn push(&mut self, samples: &[f32], mut on_update: impl FnMut(&EnvelopeUpdate)) {
        self.push_staged(samples, |stage| {
            if let HopStage::Bands(update) = stage {
                on_update(update);
            }
        });
    }

    /// Feeds samples; calls `on_hop` with each stage of each completed hop ([`HopStage`]): the
    /// window once its FFT is done, each band engine's envelope, then the whole update. With
    /// [`Self::spread_bands`] the band stages come at their samples after the window's end (in
    /// this call or a later one); without it, at once.
    pub fn push_staged(&mut self, mut samples: &[f32], mut on_hop: impl FnMut(HopStage)) {
        let window = self.ring.len();
        while !samples.is_empty() {
            let mut take = samples
                .len()
                .min(self.until_update)
                .min(window - self.write_at);
            if let Some(pending) = &self.pending {
                take = take.min(pending.until_step);
            }
            self.ring[self.write_at..self.write_at + take].copy_from_slice(&samples[..take]);
            samples = &samples[take..];
            self.write_at = (self.write_at + take) % window;
            self.until_update -= take;
            self.samples_seen += take as u64;
            if let Some(pending) = &mut self.pending {
                pending.until_step -= take;
                if pending.until_step == 0 {
                    self.band_stage(&mut on_hop);
                }
            }
            if self.until_update == 0 {
                self.until_update = self.hop;
                self.finish_bands(&mut on_hop);
                self.update(&mut on_hop);
            }
        }
    }

    /// Does the band work of the newest window still to be done, at once.
    pub fn finish_bands(&mut self, mut on_hop: impl FnMut(HopStage)) {
        while self.pending.is_some() {
            self.band_stage(&mut on_hop);
        }
    }

    fn update(&mut self, on_hop: &mut impl FnMut(HopStage)) {
        let (newer, older) = self.ring.split_at(self.write_at);
        self.transform.transform(older, newer);
        on_hop(HopStage::Window(&WindowReady {
            end_sample: self.samples_seen,
            window_samples: (older, newer),
            window_spectrum: self.transform.spectrum(),
        }));
        let slot = self.history_next;
        self.history_next = (self.history_next + 1) % self.averages;
        self.history_used = (self.history_used + 1).min(self.averages);
        self.pending = Some(PendingBands {
            next_engine: 0,
            until_step: self.band_step,
            slot,
            end_sample: self.samples_seen,
        });
        if self.band_step == 0 {
            self.finish_bands(on_hop);
        }
    }

    /// The next step of the newest window's band work: one engine's envelope and average,
    /// and after the last engine (or at once if there is none), the whole update.
    fn band_stage(&mut self, on_hop: &mut impl FnMut(HopStage)) {
        let Some(mut pending) = self.pending.take() else {
            return;
        };
        let bin_hz = self.fs_hz / self.ring.len() as f64;
        if let Some(band) = self.bands.get_mut(pending.next_engine) {
            band.process(self.transform.spectrum(), pending.slot, self.history_used);
            on_hop(HopStage::Band {
                engine: pending.next_engine,
                band,
                band_of: &self.band_of,
                bin_hz,
            });
            pending.next_engine += 1;
        }
        if pending.next_engine < self.bands.len() {
            pending.until_step = self.band_step;
            self.pending = Some(pending);
            return;
        }
        on_hop(HopStage::Bands(&EnvelopeUpdate {
            end_sample: pending.end_sample,
            bin_hz,
            windows_averaged: self.history_used,
            bands: &self.bands,
            band_of: &self.band_of,
            window_spectrum: self.transform.spectrum(),
        }));
    }
}

impl RollingBand {
    /// The envelope spectrum of a window into history slot `slot`, and the average of the
    /// `used` newest slots.
    fn process(&mut self, window_spectrum: &[Complex32], slot: usize, used: usize) {
        self.envelope.process(window_spectrum, &mut self.latest);
        let bins = self.latest.len();
        self.history[slot * bins..(slot + 1) * bins].copy_from_slice(&self.latest);
        // Recomputed from the history each hop (not a running sum) so that rounding never
        // drifts over months of operation.
        self.averaged.fill(0.0);
        for past in self.history.chunks_exact(bins).take(used) {
            for (a, p) in self.averaged.iter_mut().zip(past) {
                *a += p;
            }
        }
        let scale = 1.0 / used as f32;
        for a in &mut self.averaged {
            *a = (*a * scale).sqrt();
        }
    }
}

/// The Welch power spectrum of the raw signal (Hann windows, `overlap`), per bin from 0 Hz:
/// where the resonances are. Units: squared amplitude of each component, g².
pub fn welch_power_spectrum(
    plans: &mut FftPlans,
    signal: &[f32],
    window: usize,
    overlap: f64,
) -> Vec<f32> {
    let mut transform = WindowTransform::new(window, plans);
    let hann = plans.hann(window);
    let scale = (2.0 / hann.iter().sum::<f32>()).powi(2);
    let mut tapered = vec![0f32; window];
    let mut sum = vec![0f64; window / 2 + 1];
    let mut count = 0usize;
    for start in window_starts(signal.len(), window, hop_samples(window, overlap)) {
        for ((t, x), w) in tapered
            .iter_mut()
            .zip(&signal[start..start + window])
            .zip(hann.iter())
        {
            *t = x * w;
        }
        for (s, c) in sum.iter_mut().zip(transform.transform(&tapered, &[])) {
            *s += f64::from(c.norm_sqr() * scale);
        }
        count += 1;
    }
    sum.iter()
        .map(|s| (s / count.max(1) as f64) as f32)
        .collect()
}
