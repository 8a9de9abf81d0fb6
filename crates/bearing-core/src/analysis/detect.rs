//! The computing half of a detector: what the channel monitor runs for every detector the same
//! way, so that a new detector is its own file plus one line in [`super::detectors`], not edits
//! to the monitor, the pipeline and the status.
//!
//! Why a trait object per channel: the monitor owns a short list of detectors (one or two per
//! channel), each called once per block and once per envelope window; a vtable call there costs
//! nothing next to the FFTs, and the monitor then does not name any detector.
//!
//! What a detector gets ([`ChannelContext`] once, then samples and [`WindowView`]s) and gives
//! (records of `messages::detect`, whose channel the pipeline fills in, and its flags' levels).
//! A detector may also judge a whole record for `analyze` ([`RecordView`] in,
//! [`RecordFindings`] out: a key of its own in the JSON report and lines in the text one).
//! The message half (topics, MCAP schemas, alerts, fleet metrics) is `messages::detect`.
//!
//! Rules every detector keeps, as the rest of the monitor: sample time only (no clock), no
//! allocation per block or window after `new`, no panic on any sample value.

use rustfft::num_complex::Complex32;

use super::envelope::FftPlans;
use super::flags::FlagSettings;
use super::iso::VelocitySeverity;
use crate::messages::detect::FlagSpec;
use crate::messages::{DetectorMessage, FlagLevel};

/// What a detector is built with: the channel's rate, speed and windows.
pub struct ChannelContext<'a> {
    pub fs_hz: f64,
    /// The shaft rate at the start (the nominal speed, or the highest the channel allows when
    /// no starting speed is known), Hz.
    pub shaft_hz: f64,
    /// The envelope's window and hop, samples: a detector whose windows are these may take
    /// their spectra from [`WindowView`] instead of transforming the samples again.
    pub window: usize,
    pub hop: usize,
    /// The channel's share of a hop ([`super::monitor::MonitorSettings::window_stagger`]).
    pub window_stagger: (usize, usize),
    /// Windows the rolling spectra average.
    pub averages: usize,
    /// The fault flags' settings: hysteresis and delays a detector's flags follow too.
    pub flags: &'a FlagSettings,
    /// The process's FFT plans and windows.
    pub plans: &'a mut FftPlans,
}

impl ChannelContext<'_> {
    /// This channel's share of `hop` ([`share_of`]): where its windows of that hop end.
    pub fn phase_of(&self, hop: usize) -> usize {
        share_of(hop, self.window_stagger)
    }
}

/// The k/n share of `hop` of the k-th of n channels
/// ([`super::monitor::MonitorSettings::window_stagger`]).
pub fn share_of(hop: usize, (k, n): (usize, usize)) -> usize {
    (hop * k.min(n)) / n.max(1)
}

/// One envelope window, as it closes.
pub struct WindowView<'a> {
    /// One past the window's last sample.
    pub end_sample: u64,
    /// The real FFT of the window's raw samples, without a window function.
    pub spectrum: &'a [Complex32],
    /// The shaft rate the channel scores with, Hz; `None` while it is unknown.
    pub shaft_hz: Option<f64>,
}

/// A detector of one channel.
pub trait ChannelDetector: Send {
    /// Starts again at `first_sample` (after a gap or a sensor restart).
    fn restart_at(&mut self, first_sample: u64);

    /// A block of samples (g) following the last one.
    fn on_samples(&mut self, samples: &[f32], out: &mut dyn FnMut(DetectorMessage));

    /// An envelope window closed.
    fn on_window(&mut self, window: &WindowView<'_>, out: &mut dyn FnMut(DetectorMessage));

    /// Each of the detector's flags with its level now.
    fn flag_levels(&self, out: &mut dyn FnMut(&'static FlagSpec, FlagLevel));
}

/// A whole record as `analyze` measured it.
pub struct RecordView<'a> {
    /// The record's shaft rate, Hz.
    pub shaft_hz: f64,
    /// Its ISO velocity severity, with the velocity power per bin; `None` when the record has
    /// none (not in g, or too short).
    pub velocity: Option<&'a VelocitySeverity>,
}

/// What a detector says of a whole record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordFindings {
    /// Its key in `analyze --format json` (`machine_faults`).
    pub key: &'static str,
    pub json: serde_json::Value,
    /// Lines of the text report, for people.
    pub lines: Vec<String>,
}
