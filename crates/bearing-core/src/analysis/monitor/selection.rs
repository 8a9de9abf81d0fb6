//! The band selections of a channel monitor: started over the history on schedule (inline or
//! as jobs on another thread), their results used a fixed number of samples later, and the
//! flags following each verdict on a whole horizon of evidence.

use super::events::MonitorEvent;
use super::ChannelMonitor;
use crate::analysis::band_selection::{BandJob, BandResult, Evidence};
use crate::analysis::speed::SpeedMode;
use crate::messages::FaultKind;

impl ChannelMonitor {
    /// The history's filled part as counts, oldest first.
    pub(super) fn history_counts(&self) -> Vec<i16> {
        let n = self.history.len();
        let filled = self.history_filled.min(n);
        (0..filled)
            .map(|i| self.history[(self.history_at + n - filled + i) % n])
            .collect()
    }

    /// Starts a band selection over the history (unless one is under way, or nothing could
    /// be scored: no speed and no estimate); with no delay its result is used at once.
    pub(super) fn start_band_selection(&mut self, on_event: &mut impl FnMut(MonitorEvent)) {
        let estimating = matches!(self.settings.speed, SpeedMode::Estimate(_));
        if self.band_result_at.is_some() || (!self.speed_known && !estimating) {
            return;
        }
        let counts = self.history_counts();
        self.band_job_from = self.next_sample - counts.len() as u64;
        self.evidence_until = self.next_sample;
        self.band_selector.start(std::sync::Arc::new(BandJob {
            counts,
            scale: self.history_scale,
            fs_hz: self.settings.fs_hz,
            freqs: self.freqs,
            orders: self.orders,
            speed_known: self.speed_known,
            max_shaft_hz: self.settings.speed.max_shaft_hz(self.freqs.shaft),
            speed: self.settings.speed,
            analysis: self.settings.analysis.clone(),
            witness: self.witness.clone(),
        }));
        self.band_result_at = Some(self.next_sample + self.band_delay_samples);
        if self.band_delay_samples == 0 {
            self.use_band_result(on_event);
        }
    }

    /// Takes the result of the selection under way (waiting for it if it is not done) and
    /// follows its speed estimate, its verdict and its bands.
    ///
    /// The flags come before the newest window's band work still to be done (its report,
    /// scored on the bands it was taken with) and before the new bands' set-up: they follow
    /// the verdict alone, and the alerts they decide must not wait for that work (150–290 µs
    /// of a fault alert's latency in the daemon, where the band work is spread over the hop).
    /// So that window's report may come after a flag change at a later sample; it counts with
    /// the levels before it (`WindowFlagCount` in the lab). A speed estimate is the exception:
    /// the window is scored at the speed it was taken at, before the estimate is applied.
    pub(super) fn use_band_result(&mut self, on_event: &mut impl FnMut(MonitorEvent)) {
        self.band_result_at = None;
        let Some(BandResult {
            estimated_shaft_hz,
            bands,
            evidence,
        }) = self.band_selector.finish()
        else {
            return self.finish_window(on_event);
        };
        if let Some(hz) = estimated_shaft_hz {
            self.apply_speed(Some(hz), true, on_event);
        }
        let Some((bands, selected)) = bands.filter(|_| self.speed_known) else {
            return self.finish_window(on_event);
        };
        on_event(MonitorEvent::Bands {
            at_sample: self.next_sample,
            bands,
            selected,
            evidence: evidence.as_ref(),
            evidence_from: self.band_job_from,
        });
        // The flags move on a whole horizon of evidence, or on all there is at the signal's end:
        // a shorter stretch (the first seconds, the seconds after a gap) chooses bands only.
        if let Some(evidence) = evidence.filter(|e| e.samples >= self.history.len() || self.ending)
        {
            self.follow_evidence(&evidence, on_event);
        }
        self.finish_window(on_event);
        if !self.bands_known || bands != self.bands {
            self.rolling.set_bands(&bands);
            self.bands = bands;
        }
        self.bands_known = true;
    }

    /// The flags follow the verdict on the selection's history: the fault it names asks for
    /// its score's level (watch at least), every other fault for ok; a level asked for counts
    /// as asked since the history's first sample
    /// ([`crate::analysis::flags::FaultFlag::update_over`]), so a verdict on more evidence
    /// than the on-delay raises its flag at once.
    fn follow_evidence(&mut self, evidence: &Evidence, on_event: &mut impl FnMut(MonitorEvent)) {
        let at = self.next_sample;
        let from = self.band_job_from;
        self.agreed = evidence
            .verdict
            .fault()
            .filter(|_| evidence.named == Some(crate::analysis::diagnosis::Named::Agreed));
        for (i, kind) in FaultKind::ALL.iter().enumerate() {
            let score = &evidence.scores[i];
            let asked = if evidence.named.is_some() && evidence.verdict.faults().contains(kind) {
                score.score.max(self.flags[i].settings().watch_score)
            } else {
                0.0
            };
            if let Some(change) = self.flags[i].update_over(asked, from, at) {
                on_event(MonitorEvent::Flag {
                    fault: *kind,
                    change,
                    score: score.score,
                    frequency_hz: score.frequency_hz,
                    runner_up: evidence.runner_up(*kind),
                });
            }
        }
    }

    /// The end of the signal (a replay's, an evaluation's, or a clean stop): the selection
    /// under way is used now, and the evidence not yet analysed (the samples since the last
    /// selection) gets a last selection over the history, used at once, so that the flags end
    /// on the verdict of everything the channel saw.
    pub fn finish(&mut self, on_event: &mut impl FnMut(MonitorEvent)) {
        self.ending = true;
        self.finish_window(on_event);
        if self.band_result_at.is_some() {
            self.use_band_result(on_event);
        }
        if self.next_sample > self.evidence_until && self.history_filled > 0 {
            let delay = std::mem::replace(&mut self.band_delay_samples, 0);
            self.start_band_selection(on_event);
            self.band_delay_samples = delay;
        }
    }
}
