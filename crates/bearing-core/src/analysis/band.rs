//! Frequency bands, the arithmetic that maps them onto FFT bins, and how wide a band the fault
//! combs need.

use crate::bearing::FaultFrequencies;
use serde::Serialize;

/// A frequency band `[lo_hz, hi_hz)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Band {
    pub lo_hz: f64,
    pub hi_hz: f64,
}

impl Band {
    pub fn new(lo_hz: f64, hi_hz: f64) -> Self {
        Band { lo_hz, hi_hz }
    }

    pub fn width_hz(&self) -> f64 {
        self.hi_hz - self.lo_hz
    }

    pub fn centre_hz(&self) -> f64 {
        0.5 * (self.lo_hz + self.hi_hz)
    }

    /// The bins `[first, last)` of a real FFT of `window` samples at `fs_hz` that fall in the
    /// band, clamped to `1..=window/2` (the DC bin never belongs to an analytic band).
    pub fn bins(&self, fs_hz: f64, window: usize) -> (usize, usize) {
        let per_hz = window as f64 / fs_hz;
        let nyquist_bin = window / 2;
        let first = ((self.lo_hz * per_hz).round().max(1.0) as usize).min(nyquist_bin);
        let last = ((self.hi_hz * per_hz).round() as usize).clamp(first, nyquist_bin + 1);
        (first, last)
    }
}

impl std::fmt::Display for Band {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.0}–{:.0} Hz", self.lo_hz, self.hi_hz)
    }
}

/// The highest envelope frequency the scores need: the last harmonic of the highest fault
/// frequency, its upper sideband, and the noise neighbourhood beyond it.
pub fn envelope_range_hz(freqs: &FaultFrequencies, harmonics: usize) -> f64 {
    comb_width_hz(freqs, harmonics) + 0.5 * top_fault_hz(freqs)
}

/// The highest fault frequency with a comb worth scoring.
fn top_fault_hz(freqs: &FaultFrequencies) -> f64 {
    freqs.bpfo.max(freqs.bpfi).max(freqs.two_bsf)
}

/// The envelope bandwidth the combs need: the highest fault frequency's last harmonic and its
/// upper sideband. A demodulation band narrower than this cannot hold them.
pub fn comb_width_hz(freqs: &FaultFrequencies, harmonics: usize) -> f64 {
    harmonics as f64 * top_fault_hz(freqs) + freqs.shaft.max(freqs.ftf)
}
