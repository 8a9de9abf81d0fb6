//! Turns the pipeline's flag changes into [`AlertMessage`]s, once for every consumer (the
//! iceoryx2 publisher, the fleet bridge): state (raised, escalated, relaxed, cleared),
//! confidence from the scores and the twin, a sequence number, and the bookkeeping that keeps
//! every active alert inside the alert service's history.
//!
//! Sans-IO and clock-free like the analysis: messages in, alerts out, so a replay numbers and
//! weighs them as the live run did. The publisher stamps the wall time when it sends.
//!
//! Why "repeated" alerts: iceoryx2 keeps the last `history_size` samples for late subscribers.
//! An alert raised long ago would fall out of that window after enough newer alerts (another
//! channel flapping), and a subscriber connecting then would not know it is active. So when an
//! active alert is about to leave the window it is sent again, unchanged, as `repeated`.

use crate::analysis::diagnosis::{score_evidence, DecisionRule};
use crate::analysis::AnalysisSettings;
use crate::messages::detect::{all_flags, FlagRecord};
use crate::messages::{
    AlertMessage, AlertState, AlertSubject, ChannelId, FaultKind, FlagLevel, FlagMessage,
    PipelineMessage, TwinMessage,
};
use crate::twin::diagnose::twin_adjusted_confidence;
use std::collections::{BTreeMap, HashMap};

use super::Output;

/// Passes `output` on; after a flag change, the alerts it decides: the pipeline's outputs as
/// its sinks see them.
pub(super) fn pass_on(alerts: &mut AlertTracker, output: Output, out: &mut impl FnMut(Output)) {
    let flag = match &output {
        Output::Message(m @ PipelineMessage::Flag(_)) => m,
        Output::Message(m @ PipelineMessage::Detector(d)) if d.as_flag().is_some() => m,
        _ => return out(output),
    };
    let mut decided = Vec::with_capacity(1);
    alerts.observe(flag, &mut |alert| decided.push(alert));
    out(output);
    for alert in decided {
        out(Output::Alert(alert));
    }
}

/// What the tracker keeps of a channel's latest twin fit.
#[derive(Debug, Clone, Copy)]
struct TwinSummary {
    best: FaultKind,
    margin: f64,
    /// Fit error per fault kind, in [`FaultKind::ALL`] order; NaN where the twin has no
    /// hypothesis (cage).
    errors: [f64; 4],
}

/// The alert state of every (channel, flag) and the numbering of one run.
pub struct AlertTracker {
    run_id: u64,
    sequence: u64,
    history_size: u64,
    rule: DecisionRule,
    rates: HashMap<String, f64>,
    twins: HashMap<ChannelId, TwinSummary>,
    active: BTreeMap<AlertKey, AlertMessage>,
}

/// One alert's identity: which channel, which flag.
type AlertKey = (ChannelId, AlertSubject);

/// History an alert service needs for `channels` analysed channels: room for every flag of
/// every channel (four faults and every detector's flags) to be active twice over, so repeats
/// stay rare.
pub fn history_size_for(channels: usize) -> usize {
    (2 * (FaultKind::ALL.len() + all_flags().count()) * channels).max(16)
}

impl AlertTracker {
    /// `run_id` identifies the run in every alert; `rates` maps sensor ids to sample rates;
    /// `history_size` is the alert service's ([`history_size_for`]).
    pub fn new(
        run_id: u64,
        history_size: usize,
        settings: &AnalysisSettings,
        rates: HashMap<String, f64>,
    ) -> AlertTracker {
        AlertTracker {
            run_id,
            sequence: 0,
            history_size: history_size.max(2) as u64,
            rule: settings.decision_rule(),
            rates,
            twins: HashMap::new(),
            active: BTreeMap::new(),
        }
    }

    /// Numbers the alerts of another run from now on (its first alert is still number 1 only
    /// if none was decided yet).
    pub fn set_run_id(&mut self, run_id: u64) {
        self.run_id = run_id;
    }

    /// The alerts active now (their latest version), ordered by channel and flag.
    pub fn active(&self) -> impl Iterator<Item = &AlertMessage> {
        self.active.values()
    }

    /// Takes one pipeline message; emits the alerts it causes (a flag change's, then the
    /// repeats that keep older active alerts in the history) through `emit`.
    pub fn observe(&mut self, message: &PipelineMessage, emit: &mut impl FnMut(AlertMessage)) {
        let alert = match message {
            PipelineMessage::Twin(m) => {
                self.note_twin(m);
                return;
            }
            PipelineMessage::Flag(flag) => self.fault_alert(flag),
            PipelineMessage::Detector(m) => match m.as_flag() {
                Some(flag) => self.detector_alert(flag),
                None => return,
            },
            _ => return,
        };
        self.emit(alert, emit);
        self.keep_active_in_history(emit);
    }

    /// Takes a twin fit (its confidence weighs in on the channel's later alerts).
    pub fn note_twin(&mut self, m: &TwinMessage) {
        self.twins.insert(
            m.channel.clone(),
            TwinSummary {
                best: m.hypothesis,
                margin: m.margin,
                errors: [
                    m.error_outer_race,
                    m.error_inner_race,
                    m.error_ball,
                    f64::NAN,
                ],
            },
        );
    }

    fn fault_alert(&self, flag: &FlagMessage) -> AlertMessage {
        let (fault, to) = (flag.fault, flag.to);
        // Without a runner-up (a flag read from a log older than the field), the others are
        // taken to be at the floor (score 1).
        let runner_up = flag.runner_up_score.unwrap_or(1.0);
        let (_, mut confidence) = score_evidence(flag.score, runner_up, &self.rule);
        let twin = self.twins.get(&flag.channel);
        if let (Some(twin), true) = (twin, to != FlagLevel::Ok) {
            confidence = twin_adjusted_confidence(confidence, twin.best == fault, twin.margin);
        }
        AlertMessage {
            fault_frequency_hz: Some(flag.fault_frequency_hz),
            score: flag.score,
            confidence,
            twin_error: twin
                .map(|t| t.errors[fault.index()])
                .filter(|e| !e.is_nan()),
            ..self.change_alert(
                &flag.channel,
                flag.end_sample,
                AlertSubject::Fault(fault),
                (flag.from, to),
            )
        }
    }

    /// The alert of a detector's flag: score and confidence as the detector gives them (the
    /// velocity zone: its RMS, and 1 for a measurement against the standard's boundary).
    fn detector_alert(&self, flag: &dyn FlagRecord) -> AlertMessage {
        AlertMessage {
            score: flag.score(),
            confidence: flag.confidence(),
            ..self.change_alert(
                flag.channel(),
                flag.end_sample(),
                AlertSubject::Detector(flag.flag()),
                flag.change(),
            )
        }
    }

    /// What every alert of a flag change (`from`, `to`) says: where, when, which flag and its
    /// state; its evidence (score, confidence NaN, no frequency or twin) for the caller to set;
    /// numbered when emitted.
    fn change_alert(
        &self,
        channel: &ChannelId,
        end_sample: u64,
        subject: AlertSubject,
        (from, to): (FlagLevel, FlagLevel),
    ) -> AlertMessage {
        AlertMessage {
            sequence: 0,
            run_id: self.run_id,
            channel: channel.clone(),
            end_sample,
            sample_rate_hz: self.rates.get(&channel.sensor).copied().unwrap_or(f64::NAN),
            subject,
            state: AlertState::of_change(from, to),
            severity: to,
            previous_severity: from,
            score: f64::NAN,
            confidence: f64::NAN,
            fault_frequency_hz: None,
            twin_error: None,
        }
    }

    fn emit(&mut self, mut alert: AlertMessage, emit: &mut impl FnMut(AlertMessage)) {
        self.sequence += 1;
        alert.sequence = self.sequence;
        let key = (alert.channel.clone(), alert.subject);
        if alert.state == AlertState::Cleared {
            self.active.remove(&key);
        } else {
            self.active.insert(key, alert.clone());
        }
        emit(alert);
    }

    /// Re-sends the oldest active alerts that would otherwise leave the history window before
    /// the next alert.
    fn keep_active_in_history(&mut self, emit: &mut impl FnMut(AlertMessage)) {
        for _ in 0..self.active.len() {
            let room = self
                .history_size
                .saturating_sub(self.active.len() as u64)
                .max(1);
            let Some(oldest) = self.active.values().min_by_key(|a| a.sequence) else {
                return;
            };
            if self.sequence - oldest.sequence < room {
                return;
            }
            let repeat = AlertMessage {
                state: AlertState::Repeated,
                previous_severity: oldest.severity,
                ..oldest.clone()
            };
            self.emit(repeat, emit);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use FaultKind::{Ball, InnerRace, OuterRace};
    use FlagLevel::{Alarm, Watch};
    const OK: FlagLevel = FlagLevel::Ok;

    fn flag(
        axis: &str,
        fault: FaultKind,
        from: FlagLevel,
        to: FlagLevel,
        at: u64,
    ) -> PipelineMessage {
        PipelineMessage::Flag(FlagMessage {
            channel: ChannelId {
                sensor: "motor-de".into(),
                axis: axis.into(),
            },
            end_sample: at,
            fault,
            from,
            to,
            score: 40.0,
            fault_frequency_hz: 107.0,
            runner_up_score: Some(1.0),
        })
    }

    fn tracker(history: usize) -> AlertTracker {
        let rates = HashMap::from([("motor-de".to_string(), 25_600.0)]);
        AlertTracker::new(99, history, &AnalysisSettings::default(), rates)
    }

    fn observe(t: &mut AlertTracker, m: &PipelineMessage) -> Vec<AlertMessage> {
        let mut out = Vec::new();
        t.observe(m, &mut |a| out.push(a));
        out
    }

    /// A twin fit of channel `motor-de/radial` whose best hypothesis is `hypothesis`.
    fn twin_fit(hypothesis: FaultKind) -> TwinMessage {
        TwinMessage {
            channel: ChannelId {
                sensor: "motor-de".into(),
                axis: "radial".into(),
            },
            end_sample: 0,
            hypothesis,
            error: 0.2,
            margin: 0.2,
            error_outer_race: 0.2,
            error_inner_race: 0.4,
            error_ball: 0.5,
            a: 1.0,
            decay_per_s: 1000.0,
            f_n: 3000.0,
            f_d: 107.0,
            jitter: 0.01,
            residual_energy_ratio: 0.1,
            residual_peak_hz: 10.0,
            residual_bin_hz: 1.0,
            residual: vec![],
            learned: None,
        }
    }

    /// The outputs `pass_on` gives for `output` with the pipeline's own tracker.
    fn passed_on(pipeline: &mut super::super::Pipeline, output: Output) -> Vec<Output> {
        let mut outputs = Vec::new();
        pass_on(&mut pipeline.alerts, output, &mut |o| outputs.push(o));
        outputs
    }

    #[test]
    fn the_pipeline_follows_a_flag_change_with_its_alert_for_its_run_and_twin() {
        let config = crate::config::Config::default_embedded().unwrap();
        let mut pipeline =
            super::super::Pipeline::new(&config, &BTreeMap::new(), None).with_run_id(7);
        // Other outputs pass alone.
        let health = PipelineMessage::Health(crate::messages::HealthMessage {
            channel: twin_fit(OuterRace).channel,
            end_sample: 1,
            kind: crate::messages::HealthKind::Gap,
            stage: None,
            detail: String::new(),
        });
        let outputs = passed_on(&mut pipeline, Output::Message(health.clone()));
        assert!(matches!(&outputs[..], [Output::Message(m)] if *m == health));

        let raise = flag("radial", OuterRace, OK, Watch, 2560);
        let outputs = passed_on(&mut pipeline, Output::Message(raise.clone()));
        let [Output::Message(first), Output::Alert(alert)] = &outputs[..] else {
            panic!("{outputs:?}");
        };
        assert_eq!(*first, raise);
        assert_eq!(
            (alert.run_id, alert.sequence, alert.end_sample),
            (7, 1, 2560)
        );
        assert_eq!(alert.sample_rate_hz, 25_600.0, "the config's rate");
        assert_eq!(alert.twin_error, None);

        // A fit noted by the pipeline weighs in on the next alert, and shows in the status.
        pipeline.note_twin(&twin_fit(OuterRace));
        assert_eq!(pipeline.status()[0].twin_hypothesis, Some(OuterRace));
        let outputs = passed_on(
            &mut pipeline,
            Output::Message(flag("radial", OuterRace, Watch, Alarm, 5120)),
        );
        let [_, Output::Alert(escalated)] = &outputs[..] else {
            panic!("{outputs:?}");
        };
        assert_eq!(
            (escalated.sequence, escalated.state),
            (2, AlertState::Escalated)
        );
        assert_eq!(escalated.twin_error, Some(0.2));
        assert!(escalated.confidence > alert.confidence);
    }

    #[test]
    fn a_repeat_follows_the_alert_that_pushes_it_out_of_the_history() {
        let config = crate::config::Config::default_embedded().unwrap();
        let mut pipeline = super::super::Pipeline::new(&config, &BTreeMap::new(), None);
        // One channel: a history of 16 (the least); the first alert stays active while
        // another fault's flag flaps.
        passed_on(
            &mut pipeline,
            Output::Message(flag("radial", OuterRace, OK, Watch, 1)),
        );
        let mut outputs = Vec::new();
        for j in 0..20u64 {
            let (from, to) = if j % 2 == 0 { (OK, Watch) } else { (Watch, OK) };
            outputs.push(passed_on(
                &mut pipeline,
                Output::Message(flag("radial", Ball, from, to, 100 + j)),
            ));
        }
        let repeated = outputs
            .iter()
            .find(|o| o.len() == 3)
            .expect("a flag change followed by its alert and a repeat");
        let [Output::Message(_), Output::Alert(change), Output::Alert(repeat)] = &repeated[..]
        else {
            panic!("{repeated:?}");
        };
        assert_eq!(change.subject, AlertSubject::Fault(Ball));
        assert_eq!(repeat.state, AlertState::Repeated);
        assert_eq!(repeat.subject, AlertSubject::Fault(OuterRace));
        assert_eq!(repeat.sequence, change.sequence + 1);
    }

    #[test]
    fn a_flag_cycle_gives_raised_escalated_relaxed_cleared_in_sequence() {
        let mut t = tracker(16);
        let steps = [
            (OK, Watch, AlertState::Raised),
            (Watch, Alarm, AlertState::Escalated),
            (Alarm, Watch, AlertState::Relaxed),
            (Watch, OK, AlertState::Cleared),
        ];
        for (j, (from, to, state)) in steps.into_iter().enumerate() {
            let alerts = observe(
                &mut t,
                &flag("radial", OuterRace, from, to, 1000 * j as u64),
            );
            assert_eq!(alerts.len(), 1);
            let alert = &alerts[0];
            assert_eq!(alert.state, state);
            assert_eq!(alert.sequence, j as u64 + 1);
            assert_eq!(alert.run_id, 99);
            assert_eq!(alert.end_sample, 1000 * j as u64);
            assert_eq!(alert.sample_rate_hz, 25_600.0);
            assert_eq!((alert.severity, alert.previous_severity), (to, from));
            assert_eq!(alert.subject, AlertSubject::Fault(OuterRace));
            assert_eq!(alert.channel.axis, "radial");
            assert_eq!(alert.fault_frequency_hz, Some(107.0));
            let active = t.active().count();
            assert_eq!(active, usize::from(to != OK));
        }
    }

    #[test]
    fn confidence_rises_with_an_agreeing_twin_and_falls_with_a_disagreeing_one() {
        // The window's other scores: inner race 5, ball 4, cage 2.
        let mut raise = flag("radial", OuterRace, OK, Watch, 10);
        if let PipelineMessage::Flag(f) = &mut raise {
            f.runner_up_score = Some(5.0);
        }
        let mut plain = tracker(16);
        let base = observe(&mut plain, &raise).remove(0);
        assert_eq!(base.twin_error, None);
        assert!(base.confidence > 0.5 && base.confidence < 1.0, "{base:?}");

        let mut agreeing = tracker(16);
        agreeing.note_twin(&twin_fit(OuterRace));
        let up = observe(&mut agreeing, &raise).remove(0);
        assert!(up.confidence > base.confidence);
        assert_eq!(up.twin_error, Some(0.2));

        // A twin fit that passes by as a message counts as one noted directly.
        let mut disagreeing = tracker(16);
        assert!(observe(
            &mut disagreeing,
            &PipelineMessage::Twin(twin_fit(InnerRace))
        )
        .is_empty());
        let down = observe(&mut disagreeing, &raise).remove(0);
        assert!(down.confidence < base.confidence);
        assert_eq!(down.twin_error, Some(0.2));
    }

    #[test]
    fn a_velocity_zone_flag_is_an_alert_of_its_own_beside_the_fault_alerts() {
        let mut t = tracker(16);
        let zone = |from, to, rms_mm_s, at| {
            PipelineMessage::from(crate::messages::VelocityFlagMessage {
                channel: ChannelId {
                    sensor: "motor-de".into(),
                    axis: "radial".into(),
                },
                end_sample: at,
                from,
                to,
                rms_mm_s,
                zone: crate::messages::IsoZone::C,
                watch_mm_s: 2.8,
                alarm_mm_s: 4.5,
            })
        };
        observe(&mut t, &flag("radial", OuterRace, OK, Watch, 5));
        let raised = observe(&mut t, &zone(OK, Watch, 3.7, 10)).remove(0);
        assert_eq!(raised.subject, AlertSubject::ISO_ZONE);
        assert_eq!((raised.state, raised.severity), (AlertState::Raised, Watch));
        assert_eq!((raised.score, raised.confidence), (3.7, 1.0));
        assert_eq!((raised.fault_frequency_hz, raised.twin_error), (None, None));
        // Both alerts are active, each under its own key.
        assert_eq!(t.active().count(), 2);
        let cleared = observe(&mut t, &zone(Watch, OK, 2.0, 20)).remove(0);
        assert_eq!(cleared.state, AlertState::Cleared);
        assert_eq!(t.active().count(), 1);
    }

    #[test]
    fn an_old_active_alert_is_repeated_before_it_leaves_the_history() {
        let history = 16;
        let mut t = tracker(history);
        let mut all = observe(&mut t, &flag("x", OuterRace, OK, Watch, 1));
        // Another axis flaps for a long time.
        for j in 0..40u64 {
            let (from, to) = if j % 2 == 0 { (OK, Watch) } else { (Watch, OK) };
            all.extend(observe(&mut t, &flag("y", Ball, from, to, 100 + j)));
        }
        let sequences: Vec<u64> = all.iter().map(|a| a.sequence).collect();
        assert_eq!(sequences, (1..=all.len() as u64).collect::<Vec<_>>());
        let repeats: Vec<&AlertMessage> = all
            .iter()
            .filter(|a| a.state == AlertState::Repeated)
            .collect();
        assert!(repeats.len() >= 2, "{} repeats", repeats.len());
        // A repeat is the active alert unchanged but for its number and state.
        for repeat in &repeats {
            assert_eq!(repeat.channel.axis, "x");
            assert_eq!(repeat.end_sample, 1);
            assert_eq!((repeat.severity, repeat.previous_severity), (Watch, Watch));
        }
        // After every alert, each active alert is among the last `history` sent.
        let mut active: BTreeMap<(String, AlertSubject), u64> = BTreeMap::new();
        for a in &all {
            let key = (a.channel.axis.clone(), a.subject);
            if a.state == AlertState::Cleared {
                active.remove(&key);
            } else {
                active.insert(key, a.sequence);
            }
        }
        let last = all.last().unwrap().sequence;
        for (key, sequence) in &active {
            assert!(last - sequence < history as u64, "{key:?} fell out");
        }
    }
}
