//! The velocity zone detector of one channel: the rolling reading ([`VelocityTracker`]) and
//! its zone flag (watch from zone C, alarm from zone D, with the fault flags' hysteresis and
//! delays), run by the channel monitor through [`ChannelDetector`]. The measurement itself is
//! [`super::iso`].

use super::detect::{ChannelContext, ChannelDetector, WindowView};
use super::flags::FaultFlag;
use super::iso::{SeveritySettings, VelocityReading, VelocityTracker, ZoneLimits};
use crate::messages::detect::FlagSpec;
use crate::messages::{
    DetectorMessage, FlagLevel, VelocityFlagMessage, VelocityMessage, ISO_ZONE_FLAG,
};

/// The velocity reading and zone flag of one channel.
pub struct VelocityDetector {
    tracker: VelocityTracker,
    flag: FaultFlag,
}

impl VelocityDetector {
    pub fn new(settings: SeveritySettings, context: &mut ChannelContext<'_>) -> Self {
        let tracker = VelocityTracker::new(
            context.fs_hz,
            context.shaft_hz * 60.0,
            settings,
            context.averages,
            context.plans,
        );
        let phase = context.phase_of(tracker.hop());
        let tracker = tracker
            .with_phase(phase)
            .share_windows_with(context.window, context.hop);
        let flag = FaultFlag::new(tracker.limits().flag_settings(context.flags));
        VelocityDetector { tracker, flag }
    }

    /// The zone flag's change (if any), then the reading.
    fn emit(&mut self, reading: VelocityReading, out: &mut dyn FnMut(DetectorMessage)) {
        let limits: ZoneLimits = self.tracker.limits();
        if let Some(change) = self.flag.update(reading.rms_mm_s, reading.end_sample) {
            out(VelocityFlagMessage {
                channel: Default::default(),
                end_sample: change.at_sample,
                from: change.from,
                to: change.to,
                rms_mm_s: reading.rms_mm_s,
                zone: reading.zone,
                watch_mm_s: limits.bc_mm_s,
                alarm_mm_s: limits.cd_mm_s,
            }
            .into());
        }
        let (lo, hi) = self.tracker.band();
        out(VelocityMessage {
            channel: Default::default(),
            end_sample: reading.end_sample,
            rms_mm_s: reading.rms_mm_s,
            zone: reading.zone,
            band_hz: [lo, hi],
            windows_averaged: reading.windows_averaged,
            flag: self.flag.level(),
        }
        .into());
    }
}

impl ChannelDetector for VelocityDetector {
    fn restart_at(&mut self, first_sample: u64) {
        self.tracker.restart_at(first_sample);
    }

    fn on_samples(&mut self, samples: &[f32], out: &mut dyn FnMut(DetectorMessage)) {
        // A chunk of at most a hop ends at most one hop, so it makes at most one reading.
        for chunk in samples.chunks(self.tracker.hop().max(1)) {
            let mut reading = None;
            self.tracker.push(chunk, |r| reading = Some(r));
            if let Some(reading) = reading {
                self.emit(reading, out);
            }
        }
    }

    fn on_window(&mut self, window: &WindowView<'_>, out: &mut dyn FnMut(DetectorMessage)) {
        if self.tracker.shares_windows() {
            let reading = self
                .tracker
                .reading_of_unwindowed(window.spectrum, window.end_sample);
            self.emit(reading, out);
        }
    }

    fn flag_levels(&self, out: &mut dyn FnMut(&'static FlagSpec, FlagLevel)) {
        out(&ISO_ZONE_FLAG, self.flag.level());
    }
}
