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
//!
//! The files: `zones` (the standard's machine groups, foundations, zone boundaries and
//! band), `integrate` (acceleration windows to velocity, and the severity of a whole record),
//! `tracker` (the rolling per-channel reading of the daemon). The daemon's detector (the reading
//! and its zone flag) is `analysis::velocity`.

mod integrate;
mod tracker;
mod zones;

pub use integrate::{
    record_severity, window_for, VelocityIntegrator, VelocitySeverity, LOW_EDGE_BINS,
};
pub use tracker::{VelocityReading, VelocityTracker};
pub use zones::{
    band_hz, Foundation, MachineGroup, SeveritySettings, ZoneLimits, G, SLOW_MACHINE_RPM,
};

/// Test signals shared by the files' tests.
#[cfg(test)]
mod test_signals {
    use super::G;

    pub fn sine(amplitude_g: f64, f: f64, fs: f64, seconds: f64) -> Vec<f32> {
        (0..(fs * seconds) as usize)
            .map(|n| (amplitude_g * (std::f64::consts::TAU * f * n as f64 / fs).sin()) as f32)
            .collect()
    }

    /// v_rms of a sine of peak acceleration `a` g at `f` Hz: a·g/(2πf)/√2, in mm/s.
    pub fn analytic_mm_s(a: f64, f: f64) -> f64 {
        a * G / (std::f64::consts::TAU * f) / 2f64.sqrt() * 1e3
    }
}
