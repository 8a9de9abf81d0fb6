//! One channel, streaming: the daemon's and the replay's analysis of a sensor axis, sans-IO.
//!
//! Samples go in with their sample index; events come out: every hop the indicators and fault
//! scores, flag changes, health-stage changes, sensor-health findings, band re-selections.
//! Every decision is taken in sample time, so a replay of the raw samples reproduces every event
//! at the same sample (the replay test checks it).
//!
//! - Evidence and bands: every `band_period_samples` the channel's history (the samples since
//!   its last gap or restart, at most `band_history_samples`: the evidence horizon) goes
//!   through the same whole-record analysis as `bearingd analyze` (band search, scores, the
//!   verdict). Its bands are the ones the rolling envelope follows (one per fault kind); its
//!   verdict is what the **flags** follow: the fault it names asks for its level, the others
//!   for ok, each counted over the history it rests on ([`FaultFlag::update_over`]). So the
//!   flags accumulate the evidence of the whole horizon, not of one window, and the end of a
//!   signal ([`ChannelMonitor::finish`]) leaves them on the verdict `analyze` gives the same
//!   samples. (choice) Only a verdict on a whole horizon moves the flags (or, at the signal's
//!   end, one on all there is): the first seconds and the seconds after a gap choose bands but
//!   decide nothing, so every decision rests on the same amount of evidence and has the same
//!   false-alarm rate (a verdict on 3 s of a CWRU ball record named the inner race that 10 s
//!   do not). Until the first selection the channel is learning and raises no flag.
//! - Scores: every hop, each fault's score in its own band's rolling (averaged) envelope
//!   spectrum, for the log, the status and the twin: what the spectrum shows now. They decide
//!   nothing, so they do not hold up what does: the block that closes a window runs the
//!   window's FFT and what decides on it (detectors, indicators, health, trend); each band's
//!   envelope and scores follow a fifth of a hop apart in the next blocks
//!   ([`RollingEnvelope::spread_bands`]), the window's report with the last. Anything the
//!   report depends on (bands, speed, a gap, the signal's end) first finishes it.
//! - Health: the stage tracker, fed with each window's kurtosis and RMS, and the RMS trend
//!   (one point per `trend.point_s`, fitted against the failure limit once degrading).
//! - Sensor: clipping (counts at full scale) and a flat line (no change for a second) are
//!   reported when they start and when they end.
//! - Speed ([`SpeedMode`]): fixed, given from outside at a sample position (speed frames, or a
//!   replay of the logged speed), or estimated from the history at every band selection
//!   ([`super::speed`]). (choice) While the speed is unknown (no speed frame yet and no nominal
//!   speed, a frame saying "not available", 0 or above the configured maximum, no estimate
//!   yet) the channel scores nothing, its flags hold their level (neither rise nor fall on a
//!   wrong speed) and no band selection runs; indicators and health go on. A speed change takes
//!   effect at a sample, so a replay that feeds the logged changes at their samples repeats
//!   every event.
//!
//! - Detectors ([`super::detect`], listed in [`super::detectors`]): given every block and every
//!   envelope window, they emit their own messages (the ISO velocity reading and its zone
//!   flag, …). Independent of the band selection: they run from the first window on.
//!
//! - Band selections run as jobs ([`super::band_selection`]): inline by default; with
//!   [`ChannelMonitor::with_band_selector`] on another thread, their results used a fixed number
//!   of samples after they started, so that the analysis never waits 30–100 ms for one.
//!
//! Allocation: the per-hop path allocates nothing; a band re-selection (once a minute) does.
//!
//! The files: this one holds the channel's state and its per-hop path; `selection` the band
//! selections and the flags following their verdicts, `sensor` the clipping and flat-line
//! watch, `events` what comes out, `settings` what goes in.

mod events;
mod selection;
mod sensor;
mod settings;
#[cfg(test)]
mod tests;

pub use events::{MonitorEvent, SensorCondition, WindowReport};
pub use settings::{MonitorSettings, TrendSettings};

use super::agreement::Witness;
use super::band::envelope_range_hz;
use super::band_selection::{scaled, usable_shaft_hz, BandSelector, InlineSelector};
use super::degradation::RmsTrend;
use super::detect::{share_of, ChannelContext, ChannelDetector, WindowView};
use super::envelope::{window_samples, HopStage, RollingEnvelope};
use super::fault_bands::{FaultScore, FaultScorer};
use super::flags::FaultFlag;
use super::health::{Baseline, HealthTracker, CONFIRM_WINDOWS};
use super::indicators::{Indicators, WindowIndicators};
use super::speed::SpeedMode;
use super::Band;
use crate::bearing::FaultFrequencies;
use crate::messages::detect::FlagSpec;
use crate::messages::{FaultKind, FlagLevel, HealthStage};
use sensor::SensorWatch;

/// The streaming analysis of one channel.
pub struct ChannelMonitor {
    settings: MonitorSettings,
    freqs: FaultFrequencies,
    /// Fault frequencies per Hz of shaft rate: `freqs` at any speed.
    orders: FaultFrequencies,
    /// Whether `freqs` may be scored (see [`SpeedMode`]).
    speed_known: bool,
    /// A speed change given for a sample not reached yet: (sample, shaft rate).
    pending_speed: Option<(u64, Option<f64>)>,
    rolling: RollingEnvelope,
    /// The time-domain indicators of each window, from segments shared by overlapping windows.
    indicators: WindowIndicators,
    scorer: FaultScorer,
    flags: [FaultFlag; 4],
    health: HealthTracker,
    trend: RmsTrend,
    scores: [FaultScore; 4],
    bands: [Band; 4],
    bands_known: bool,
    /// The last `band_history_samples` samples, for band re-selection, kept as the sensor's
    /// integer counts (half the memory of f32: this is most of a channel's memory).
    history: Vec<i16>,
    /// g per count of the samples in `history`.
    history_scale: f64,
    history_at: usize,
    history_filled: usize,
    next_band_selection: u64,
    /// [`MonitorSettings::band_phase_samples`] until it has been added once.
    band_phase_left: u64,
    next_sample: u64,
    scratch: Vec<f32>,
    sensor: SensorWatch,
    /// Runs the band selections ([`InlineSelector`] unless given one).
    band_selector: Box<dyn BandSelector>,
    /// The fault the latest verdict the flags followed named by agreement with the witness.
    agreed: Option<FaultKind>,
    /// The second witness the band jobs' verdicts hear ([`super::agreement`]); `None`: none.
    witness: Option<std::sync::Arc<dyn Witness>>,
    /// Samples from a band selection's start to the sample where its result is used.
    band_delay_samples: u64,
    /// Where the band selection under way (if any) is used.
    band_result_at: Option<u64>,
    /// The first sample the selection under way analyses.
    band_job_from: u64,
    /// The sample the newest selection's history ended at (0 before any).
    evidence_until: u64,
    /// The fewest samples of history a selection analyses (one window, or the whole history
    /// if shorter).
    min_evidence_samples: usize,
    /// The signal has ended ([`Self::finish`]): a verdict on less than a whole horizon moves
    /// the flags too.
    ending: bool,
    /// The detectors run besides the fault scores ([`MonitorSettings::detectors`]).
    detectors: Vec<Box<dyn ChannelDetector>>,
    /// The newest window's indicators, for its report once its bands are done.
    window_indicators: Indicators,
}

/// A window's fault scores and report, built from its band stages as they come
/// ([`HopStage::Band`], then [`HopStage::Bands`]).
struct ReportScoring<'m> {
    scorer: &'m mut FaultScorer,
    scores: &'m mut [FaultScore; 4],
    bands: &'m [Band; 4],
    freqs: &'m FaultFrequencies,
    speed_known: bool,
    indicators: &'m mut Indicators,
}

impl ReportScoring<'_> {
    /// Each band's spectrum is prepared once, in the scorer slot of its engine, then scored
    /// for the faults whose band it is. Before the first band selection there are no band
    /// engines: every fault is scored on nothing (as without a speed to score against).
    fn on_band_stage(&mut self, stage: HopStage, on_event: &mut impl FnMut(MonitorEvent)) {
        match stage {
            HopStage::Window(_) => {}
            HopStage::Band {
                engine,
                band,
                band_of,
                bin_hz,
            } => {
                let spectrum = if self.speed_known {
                    band.averaged_amplitude()
                } else {
                    &[]
                };
                self.scorer.prepare(engine, spectrum, bin_hz, self.freqs);
                // The faults whose band this engine computes (a band asked for twice is one
                // engine); `engine` is at most the first such fault's index.
                for (i, kind) in FaultKind::ALL.iter().enumerate() {
                    if band_of.get(i) == Some(&engine) {
                        self.scores[i] = self
                            .scorer
                            .score_prepared(engine, spectrum, *kind, self.freqs);
                    }
                }
            }
            HopStage::Bands(update) => {
                if update.bands.is_empty() {
                    for (i, kind) in FaultKind::ALL.iter().enumerate() {
                        self.scorer.prepare(i, &[], update.bin_hz, self.freqs);
                        self.scores[i] = self.scorer.score_prepared(i, &[], *kind, self.freqs);
                    }
                }
                let scores = &*self.scores;
                let top = (0..4)
                    .max_by(|&a, &b| scores[a].score.total_cmp(&scores[b].score))
                    .unwrap_or(0);
                on_event(MonitorEvent::Window(WindowReport {
                    end_sample: update.end_sample,
                    indicators: *self.indicators,
                    scores,
                    bands: self.bands,
                    spectrum: update.band(top).map_or(&[][..], |b| b.averaged_amplitude()),
                    spectrum_band: update.band(top).map_or(self.bands[top], |b| b.band()),
                    bin_hz: update.bin_hz,
                    windows_averaged: update.windows_averaged,
                }));
            }
        }
    }
}

/// Samples converted per chunk (the scratch buffer's size).
const CHUNK: usize = 4096;

impl ChannelMonitor {
    pub fn new(
        settings: MonitorSettings,
        freqs: FaultFrequencies,
        baseline: Option<Baseline>,
    ) -> Self {
        let window = window_samples(settings.analysis.window_s, settings.fs_hz);
        let hop = crate::analysis::envelope::hop_samples(window, settings.analysis.overlap);
        let bin_hz = settings.fs_hz / window as f64;
        let orders = scaled(&freqs, 1.0 / freqs.shaft);
        let fastest = scaled(&orders, settings.speed.max_shaft_hz(freqs.shaft));
        let bins = ((envelope_range_hz(&fastest, settings.analysis.harmonics) / bin_hz).ceil()
            as usize
            + 1)
        .min(window / 2);
        let speed_known = match settings.speed {
            SpeedMode::Fixed => true,
            SpeedMode::Given { known_at_start, .. } => known_at_start,
            SpeedMode::Estimate(_) => false,
        };
        let whole = Band::new(0.0, settings.fs_hz / 2.0);
        // No band engines until the first selection: they would be full-band (large) and
        // unused, since no flag rises before the bands are known.
        let mut scorer = FaultScorer::new(
            settings.analysis.fault_tolerance,
            settings.analysis.harmonics,
            bins,
        );
        let scores = scorer.score_all(&[], bin_hz, &freqs);
        let detectors = settings.detectors.build(&mut ChannelContext {
            fs_hz: settings.fs_hz,
            shaft_hz: freqs.shaft,
            window,
            hop,
            window_stagger: settings.window_stagger,
            averages: settings.analysis.averages,
            flags: &settings.flags,
            // The process's cache: plans and Hann windows once per size, not per channel.
            plans: &mut crate::analysis::envelope::FftPlans::shared(),
        });
        ChannelMonitor {
            detectors,
            indicators: WindowIndicators::new(window, hop),
            rolling: RollingEnvelope::new(
                settings.fs_hz,
                window,
                hop,
                settings.analysis.averages,
                &[],
                bins,
            )
            .with_phase(share_of(hop, settings.window_stagger))
            .spread_bands(),
            scorer,
            flags: std::array::from_fn(|_| FaultFlag::new(settings.flags)),
            health: HealthTracker::new(
                settings.baseline_windows,
                settings.sigma,
                CONFIRM_WINDOWS,
                baseline,
            ),
            trend: RmsTrend::new(
                settings.trend.point_s,
                settings.fs_hz,
                (settings.trend.point_s * settings.fs_hz / hop.max(1) as f64).ceil() as usize + 2,
                settings.trend.points,
                settings.trend.confidence,
            ),
            scores,
            bands: [whole; 4],
            bands_known: false,
            history: vec![0; settings.band_history_samples.max(window)],
            history_scale: 1.0,
            history_at: 0,
            history_filled: 0,
            // The first selection when the history is full, or one band period in if that
            // comes first (with the evidence there is by then).
            next_band_selection: (settings.band_history_samples.max(window) as u64)
                .min(settings.band_period_samples.max(window as u64)),
            band_phase_left: settings.band_phase_samples,
            next_sample: 0,
            scratch: vec![0.0; CHUNK],
            sensor: SensorWatch::new(settings.clip_count, settings.flat_line_samples),
            band_selector: Box::new(InlineSelector::default()),
            witness: None,
            agreed: None,
            band_delay_samples: 0,
            band_result_at: None,
            band_job_from: 0,
            evidence_until: 0,
            min_evidence_samples: window.min(settings.band_history_samples.max(1)),
            ending: false,
            freqs,
            orders,
            speed_known,
            pending_speed: None,
            window_indicators: Indicators::default(),
            settings,
        }
    }

    /// Runs the band selections with `selector` and uses each result `delay_samples` after the
    /// selection started (0: at once, as inline); the first selection comes
    /// `first_extra_samples` later than when the history is full (to spread the first
    /// selections of many channels over the delay).
    pub fn with_band_selector(
        mut self,
        selector: Box<dyn BandSelector>,
        delay_samples: u64,
        first_extra_samples: u64,
    ) -> Self {
        self.band_selector = selector;
        self.band_delay_samples = delay_samples;
        self.next_band_selection += first_extra_samples;
        self
    }

    /// The monitor with a second witness its verdicts hear (the learned model), by
    /// `analysis.agreement` ([`crate::analysis::agreement::decide`]).
    pub fn with_witness(mut self, witness: std::sync::Arc<dyn Witness>) -> Self {
        self.witness = Some(witness);
        self
    }

    pub fn frequencies(&self) -> &FaultFrequencies {
        &self.freqs
    }

    /// The shaft rate the channel scores with, Hz; `None` while it is unknown.
    pub fn shaft_hz(&self) -> Option<f64> {
        self.speed_known.then_some(self.freqs.shaft)
    }

    /// A shaft rate given from outside (`None`: not available), to take effect at
    /// `at_sample`: now if the channel is there (or past it: a late change applies at once),
    /// else when its samples reach it. Only one change waits; a second one arriving first
    /// makes the waiting one take effect at once (its samples never came). Ignored in the
    /// fixed and estimating modes.
    pub fn set_speed_at(
        &mut self,
        at_sample: u64,
        shaft_hz: Option<f64>,
        on_event: &mut impl FnMut(MonitorEvent),
    ) {
        if !matches!(self.settings.speed, SpeedMode::Given { .. }) {
            return;
        }
        if at_sample > self.next_sample {
            if let Some((_, waiting)) = self.pending_speed.take() {
                self.apply_speed(waiting, false, on_event);
            }
            self.pending_speed = Some((at_sample, shaft_hz));
        } else {
            self.apply_speed(shaft_hz, false, on_event);
        }
    }

    /// Uses `given` from the current sample on, if usable; selects the bands at once when the
    /// speed becomes known with a full history and no bands yet.
    fn apply_speed(
        &mut self,
        given: Option<f64>,
        estimated: bool,
        on_event: &mut impl FnMut(MonitorEvent),
    ) {
        self.finish_window(on_event);
        let max = self.settings.speed.max_shaft_hz(self.freqs.shaft);
        let usable = usable_shaft_hz(given, max);
        let was_known = self.speed_known;
        if let Some(hz) = usable {
            self.freqs = scaled(&self.orders, hz);
        }
        self.speed_known = usable.is_some();
        on_event(MonitorEvent::Speed {
            at_sample: self.next_sample,
            shaft_hz: usable,
            given_hz: given,
            estimated,
        });
        if !was_known
            && self.speed_known
            && !estimated
            && !self.bands_known
            && self.history_filled >= self.min_evidence_samples
        {
            self.start_band_selection(on_event);
        }
    }

    pub fn bands(&self) -> Option<&[Band; 4]> {
        self.bands_known.then_some(&self.bands)
    }

    /// The fault the latest verdict the flags followed named by agreement with the second
    /// witness ([`crate::analysis::diagnosis::Named::Agreed`]), if it did.
    pub fn agreed_fault(&self) -> Option<FaultKind> {
        self.agreed
    }

    /// The latest window's fault scores, in [`FaultKind::ALL`] order.
    pub fn latest_scores(&self) -> &[FaultScore; 4] {
        &self.scores
    }

    /// The verdict's rule the flags are fed by.
    pub fn decision_rule(&self) -> crate::analysis::diagnosis::DecisionRule {
        self.settings.analysis.decision_rule()
    }

    pub fn flag_levels(&self) -> [FlagLevel; 4] {
        self.flags.each_ref().map(|f| f.level())
    }

    /// Each running detector's flags with their levels.
    pub fn detector_flags(&self, out: &mut dyn FnMut(&'static FlagSpec, FlagLevel)) {
        for detector in &self.detectors {
            detector.flag_levels(out);
        }
    }

    pub fn health(&self) -> &HealthTracker {
        &self.health
    }

    pub fn next_sample(&self) -> u64 {
        self.next_sample
    }

    /// The newest `len` samples, oldest first (for the twin's re-fit).
    pub fn recent_samples(&self, len: usize) -> Vec<f32> {
        let len = len.min(self.history_filled);
        let n = self.history.len();
        (0..len)
            .map(|i| self.history_sample((self.history_at + n - len + i) % n))
            .collect()
    }

    /// Feeds a block of integer counts starting at sample `first_sample`, scaled by
    /// `scale_g_per_count`. A block that does not start where the last one ended is a gap: it
    /// is reported and the windows restart, never bridged.
    pub fn push_counts(
        &mut self,
        first_sample: u64,
        counts: &[i16],
        scale_g_per_count: f64,
        on_event: &mut impl FnMut(MonitorEvent),
    ) {
        if first_sample != self.next_sample {
            self.finish_window(on_event);
            // A selection under way is used before the jump (a restart may go back).
            if self.band_result_at.is_some() {
                self.use_band_result(on_event);
            }
            if first_sample > self.next_sample {
                on_event(MonitorEvent::Gap {
                    at_sample: self.next_sample,
                    missing: first_sample - self.next_sample,
                });
            }
            self.rolling.restart_at(first_sample);
            self.indicators.restart();
            for detector in &mut self.detectors {
                detector.restart_at(first_sample);
            }
            self.history_filled = 0;
            self.next_sample = first_sample;
            self.sensor.restart();
        }
        if scale_g_per_count != self.history_scale {
            // A new scale (a reconfigured sensor): the history in the old one is dropped.
            self.history_scale = scale_g_per_count;
            self.history_filled = 0;
        }
        for chunk in counts.chunks(CHUNK) {
            self.sensor.check(self.next_sample, chunk, on_event);
            let mut scratch = std::mem::take(&mut self.scratch);
            for (s, &c) in scratch.iter_mut().zip(chunk) {
                *s = (f64::from(c) * scale_g_per_count) as f32;
            }
            self.push_samples(&scratch[..chunk.len()], chunk, on_event);
            self.scratch = scratch;
        }
    }

    /// Cuts `samples` (in g) and their `counts` at the scheduled band selections, so that a
    /// selection happens at the same sample whatever the block sizes.
    fn push_samples(
        &mut self,
        mut samples: &[f32],
        mut counts: &[i16],
        on_event: &mut impl FnMut(MonitorEvent),
    ) {
        while !samples.is_empty() {
            if self.band_result_at.is_some_and(|at| at <= self.next_sample) {
                self.use_band_result(on_event);
            }
            if let Some((at, hz)) = self.pending_speed {
                if at <= self.next_sample {
                    self.pending_speed = None;
                    self.apply_speed(hz, false, on_event);
                }
            }
            let until_selection = self.next_band_selection.saturating_sub(self.next_sample);
            let mut take = if until_selection == 0 {
                samples.len()
            } else {
                samples.len().min(until_selection as usize)
            };
            if let Some((at, _)) = self.pending_speed {
                take = take.min((at - self.next_sample) as usize);
            }
            if let Some(at) = self.band_result_at {
                take = take.min((at - self.next_sample) as usize);
            }
            self.analyse(&samples[..take], &counts[..take], on_event);
            samples = &samples[take..];
            counts = &counts[take..];
            if self.next_sample >= self.next_band_selection {
                let enough = self.history_filled >= self.min_evidence_samples;
                if enough {
                    self.start_band_selection(on_event);
                }
                let phase = if enough {
                    std::mem::take(&mut self.band_phase_left)
                } else {
                    0
                };
                self.next_band_selection =
                    self.next_sample + self.settings.band_period_samples.max(1) + phase;
            }
        }
    }

    /// `samples` are `counts` in g.
    fn analyse(
        &mut self,
        samples: &[f32],
        counts: &[i16],
        on_event: &mut impl FnMut(MonitorEvent),
    ) {
        // Keep the history for band selection, as counts (a quarter of the memory of f64).
        let n = self.history.len();
        // Only the newest `n` counts can stay; copied in at most two runs around the ring.
        let kept = &counts[counts.len().saturating_sub(n)..];
        self.history_at = (self.history_at + counts.len() - kept.len()) % n;
        let first_run = kept.len().min(n - self.history_at);
        let (to_end, from_start) = kept.split_at(first_run);
        self.history[self.history_at..self.history_at + first_run].copy_from_slice(to_end);
        self.history[..from_start.len()].copy_from_slice(from_start);
        self.history_at = (self.history_at + kept.len()) % n;
        self.history_filled = (self.history_filled + samples.len()).min(n);
        self.next_sample += samples.len() as u64;

        for detector in &mut self.detectors {
            detector.on_samples(samples, &mut |m| on_event(MonitorEvent::Detector(m)));
        }

        self.run_hops(Some(samples), on_event);
    }

    /// Does the newest window's band work still to be done (its scores and report), before
    /// anything its report depends on changes: the bands, the speed, the time base.
    fn finish_window(&mut self, on_event: &mut impl FnMut(MonitorEvent)) {
        if self.rolling.bands_pending() {
            self.run_hops(None, on_event);
        }
    }

    /// Feeds `samples` (in g) to the rolling envelope, or with `None` finishes the newest
    /// window's band work, and handles the hop stages that come out.
    fn run_hops(&mut self, samples: Option<&[f32]>, on_event: &mut impl FnMut(MonitorEvent)) {
        let ChannelMonitor {
            rolling,
            indicators,
            detectors,
            scorer,
            health,
            trend,
            scores,
            bands,
            freqs,
            speed_known,
            window_indicators,
            ..
        } = self;
        // What decides on the window alone (detectors, indicators, health stage, trend) runs
        // as soon as its FFT is done, in the block that closes the window: its flags and
        // alerts never wait for the band envelopes and fault scores, which only feed the
        // window's report and follow in the next blocks ([`RollingEnvelope::spread_bands`]).
        let mut report = ReportScoring {
            scorer,
            scores,
            bands,
            freqs,
            speed_known: *speed_known,
            indicators: window_indicators,
        };
        let mut on_hop = |stage: HopStage<'_>| match stage {
            HopStage::Window(ready) => {
                let window = WindowView {
                    end_sample: ready.end_sample,
                    spectrum: ready.window_spectrum,
                    shaft_hz: report.speed_known.then_some(report.freqs.shaft),
                };
                for detector in detectors.iter_mut() {
                    detector.on_window(&window, &mut |m| on_event(MonitorEvent::Detector(m)));
                }
                let indicators = indicators.of_window(ready.end_sample, ready.window_samples);
                if let Some(change) =
                    health.update(indicators.kurtosis, indicators.rms, ready.end_sample)
                {
                    on_event(MonitorEvent::Stage(change));
                }
                let stage = health.stage();
                let threshold = health
                    .failure_limit()
                    .filter(|_| stage >= HealthStage::Degrading);
                if let Some(point) = trend.push(indicators.rms, ready.end_sample, threshold) {
                    on_event(MonitorEvent::Trend { point, stage });
                }
                *report.indicators = indicators;
            }
            stage => report.on_band_stage(stage, on_event),
        };
        match samples {
            Some(samples) => rolling.push_staged(samples, &mut on_hop),
            None => rolling.finish_bands(&mut on_hop),
        }
    }

    fn history_sample(&self, index: usize) -> f32 {
        (f64::from(self.history[index]) * self.history_scale) as f32
    }
}
