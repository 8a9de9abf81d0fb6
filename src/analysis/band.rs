//! Frequency bands and the arithmetic that maps them onto FFT bins.

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
