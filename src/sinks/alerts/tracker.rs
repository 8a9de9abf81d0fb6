//! Turns the pipeline's flag changes into [`Alert`]s: state (raised, escalated, relaxed,
//! cleared), confidence from the scores and the twin, a sequence number, and the bookkeeping
//! that keeps every active alert inside the service's history.
//!
//! Sans-IO like the analysis: messages and the wall time in, alerts out, so the rules are
//! tested without iceoryx2. Wall time is only stamped on alerts, never used to decide.
//!
//! Why "repeated" alerts: iceoryx2 keeps the last `history_size` samples for late subscribers.
//! An alert raised long ago would fall out of that window after enough newer alerts (another
//! channel flapping), and a subscriber connecting then would not know it is active. So when an
//! active alert is about to leave the window it is sent again, unchanged, as `repeated`.

use super::payload::{
    fault_code, name_field, severity_code, Alert, AlertState, ALERT_VERSION, ISO_ZONE_CODE,
};
use crate::analysis::diagnosis::{score_evidence, DecisionRule};
use crate::analysis::AnalysisSettings;
use crate::messages::{ChannelId, FlagMessage, PipelineMessage, TwinMessage, VelocityFlagMessage};
use crate::messages::{FaultKind, FlagLevel};
use crate::twin::diagnose::twin_adjusted_confidence;
use std::collections::{BTreeMap, HashMap};

/// What the tracker keeps of a channel's latest twin fit.
#[derive(Debug, Clone, Copy)]
struct TwinSummary {
    best: Option<FaultKind>,
    margin: f64,
    /// Fit error per fault kind, in [`FaultKind::ALL`] order; NaN where the twin has no
    /// hypothesis (cage).
    errors: [f64; 4],
}

/// The alert state of every (channel, fault) and the numbering of one daemon run.
pub struct AlertTracker {
    run_id: u64,
    sequence: u64,
    history_size: u64,
    rule: DecisionRule,
    rates: HashMap<String, f64>,
    twins: HashMap<ChannelId, TwinSummary>,
    active: BTreeMap<AlertKey, Alert>,
}

/// One alert's identity: which channel, which fault code ([`Alert::fault`]: a fault kind or
/// the ISO velocity zone).
type AlertKey = (ChannelId, u8);

/// History an alert service needs for `channels` analysed channels: room for every flag of
/// every channel (four faults and the velocity zone) to be active twice over, so repeats stay
/// rare.
pub fn history_size_for(channels: usize) -> usize {
    (2 * (FaultKind::ALL.len() + 1) * channels).max(16)
}

impl AlertTracker {
    /// `run_id` identifies this daemon run in every alert; `rates` maps sensor ids to sample
    /// rates; `history_size` is the alert service's.
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

    /// The alerts active now (their latest version), ordered by channel and fault.
    pub fn active(&self) -> impl Iterator<Item = &Alert> {
        self.active.values()
    }

    /// Takes one pipeline message; emits the alerts it causes through `publish`.
    pub fn observe(
        &mut self,
        message: &PipelineMessage,
        wall_time_ns: u64,
        publish: &mut impl FnMut(Alert),
    ) {
        match message {
            PipelineMessage::Twin(m) => self.note_twin(m),
            PipelineMessage::Flag(flag) => {
                if let Some((key, alert)) = self.alert_for(flag, wall_time_ns) {
                    self.emit(key, alert, publish);
                    self.keep_active_in_history(wall_time_ns, publish);
                }
            }
            PipelineMessage::VelocityFlag(flag) => {
                let (key, alert) = self.zone_alert_for(flag, wall_time_ns);
                self.emit(key, alert, publish);
                self.keep_active_in_history(wall_time_ns, publish);
            }
            _ => {}
        }
    }

    /// Takes a twin fit (also called by `run` for fits made on the re-fit thread).
    pub fn note_twin(&mut self, m: &TwinMessage) {
        self.twins.insert(
            m.channel.clone(),
            TwinSummary {
                best: Some(m.hypothesis),
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

    fn alert_for(&self, flag: &FlagMessage, wall_time_ns: u64) -> Option<(AlertKey, Alert)> {
        let (fault, from, to) = (flag.fault, flag.from, flag.to);
        let index = fault.index();
        // Without a runner-up (a flag read from a log older than the field), the others are
        // taken to be at the floor (score 1).
        let runner_up = flag.runner_up_score.unwrap_or(1.0);
        let (_, mut confidence) = score_evidence(flag.score, runner_up, &self.rule);
        let twin = self.twins.get(&flag.channel);
        if let (Some(twin), true) = (twin, to != FlagLevel::Ok) {
            if let Some(best) = twin.best {
                confidence = twin_adjusted_confidence(confidence, best == fault, twin.margin);
            }
        }
        let alert = Alert {
            fault_frequency_hz: flag.fault_frequency_hz,
            score: flag.score,
            confidence,
            twin_error: twin.map_or(f64::NAN, |t| t.errors[index]),
            ..self.change_alert(
                &flag.channel,
                flag.end_sample,
                wall_time_ns,
                fault_code(fault),
                (from, to),
            )
        };
        Some(((flag.channel.clone(), fault_code(fault)), alert))
    }

    /// The alert of a velocity zone flag: a measurement against the standard's boundary, not
    /// a hypothesis, so its confidence is 1.
    fn zone_alert_for(&self, flag: &VelocityFlagMessage, wall_time_ns: u64) -> (AlertKey, Alert) {
        let alert = Alert {
            score: flag.rms_mm_s,
            confidence: 1.0,
            ..self.change_alert(
                &flag.channel,
                flag.end_sample,
                wall_time_ns,
                ISO_ZONE_CODE,
                (flag.from, flag.to),
            )
        };
        ((flag.channel.clone(), ISO_ZONE_CODE), alert)
    }

    /// What every alert of a flag change (`from`, `to`) says: where, when, which flag (`code`,
    /// see [`Alert::fault`]) and its state; its evidence (frequency, score, confidence, twin)
    /// NaN, for the caller to set.
    fn change_alert(
        &self,
        channel: &ChannelId,
        end_sample: u64,
        wall_time_ns: u64,
        code: u8,
        (from, to): (FlagLevel, FlagLevel),
    ) -> Alert {
        Alert {
            sequence: 0,
            run_id: self.run_id,
            end_sample,
            wall_time_ns,
            sample_rate_hz: self.rates.get(&channel.sensor).copied().unwrap_or(f64::NAN),
            fault_frequency_hz: f64::NAN,
            score: f64::NAN,
            confidence: f64::NAN,
            twin_error: f64::NAN,
            version: ALERT_VERSION,
            state: AlertState::of_change(from, to) as u8,
            fault: code,
            severity: severity_code(to),
            previous_severity: severity_code(from),
            sensor: name_field(&channel.sensor),
            axis: name_field(&channel.axis),
        }
    }

    fn emit(&mut self, key: AlertKey, mut alert: Alert, publish: &mut impl FnMut(Alert)) {
        self.sequence += 1;
        alert.sequence = self.sequence;
        if alert.state == AlertState::Cleared as u8 {
            self.active.remove(&key);
        } else {
            self.active.insert(key, alert);
        }
        publish(alert);
    }

    /// Re-sends the oldest active alerts that would otherwise leave the history window before
    /// the next alert.
    fn keep_active_in_history(&mut self, wall_time_ns: u64, publish: &mut impl FnMut(Alert)) {
        for _ in 0..self.active.len() {
            let room = self
                .history_size
                .saturating_sub(self.active.len() as u64)
                .max(1);
            let Some((key, oldest)) = self
                .active
                .iter()
                .min_by_key(|(_, a)| a.sequence)
                .map(|(k, a)| (k.clone(), *a))
            else {
                return;
            };
            if self.sequence - oldest.sequence < room {
                return;
            }
            let repeat = Alert {
                state: AlertState::Repeated as u8,
                previous_severity: oldest.severity,
                wall_time_ns,
                ..oldest
            };
            self.emit(key, repeat, publish);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sinks::alerts::payload::AlertState;
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

    fn observe(t: &mut AlertTracker, m: &PipelineMessage) -> Vec<Alert> {
        let mut out = Vec::new();
        t.observe(m, 1, &mut |a| out.push(a));
        out
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
            let view = alerts[0].view().unwrap();
            assert_eq!(view.state, state);
            assert_eq!(view.sequence, j as u64 + 1);
            assert_eq!(view.run_id, 99);
            assert_eq!(view.severity, to.name());
            assert_eq!(view.previous_severity, from.name());
            assert_eq!(view.fault, "outer_race");
            assert_eq!(view.axis, "radial");
            let active = t.active().count();
            assert_eq!(active, usize::from(to != OK));
        }
    }

    #[test]
    fn confidence_rises_with_an_agreeing_twin_and_falls_with_a_disagreeing_one() {
        let channel = ChannelId {
            sensor: "motor-de".into(),
            axis: "radial".into(),
        };
        let twin = |hypothesis: FaultKind| TwinMessage {
            channel: channel.clone(),
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
        };
        // The window's other scores: inner race 5, ball 4, cage 2.
        let mut raise = flag("radial", OuterRace, OK, Watch, 10);
        if let PipelineMessage::Flag(f) = &mut raise {
            f.runner_up_score = Some(5.0);
        }
        let mut plain = tracker(16);
        let base = observe(&mut plain, &raise)[0];
        assert!(base.twin_error.is_nan());
        assert!(base.confidence > 0.5 && base.confidence < 1.0, "{base:?}");

        let mut agreeing = tracker(16);
        agreeing.note_twin(&twin(OuterRace));
        let up = observe(&mut agreeing, &raise)[0];
        assert!(up.confidence > base.confidence);
        assert_eq!(up.twin_error, 0.2);

        let mut disagreeing = tracker(16);
        disagreeing.note_twin(&twin(InnerRace));
        let down = observe(&mut disagreeing, &raise)[0];
        assert!(down.confidence < base.confidence);
    }

    #[test]
    fn a_velocity_zone_flag_is_an_alert_of_its_own_beside_the_fault_alerts() {
        let mut t = tracker(16);
        let zone = |from, to, rms_mm_s, at| {
            PipelineMessage::VelocityFlag(VelocityFlagMessage {
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
        let raised = observe(&mut t, &zone(OK, Watch, 3.7, 10))[0];
        let view = raised.view().unwrap();
        assert_eq!(view.fault, "iso_zone");
        assert_eq!((view.state, view.severity), (AlertState::Raised, "watch"));
        assert_eq!((view.score, view.confidence), (3.7, 1.0));
        assert!(
            view.line().contains("ISO velocity 3.70 mm/s"),
            "{}",
            view.line()
        );
        // Both alerts are active, each under its own key.
        assert_eq!(t.active().count(), 2);
        let cleared = observe(&mut t, &zone(Watch, OK, 2.0, 20))[0];
        assert_eq!(cleared.view().unwrap().state, AlertState::Cleared);
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
        let repeats = all
            .iter()
            .filter(|a| a.state == AlertState::Repeated as u8)
            .count();
        assert!(repeats >= 2, "{repeats} repeats");
        // After every alert, each active alert is among the last `history` sent.
        let mut active: BTreeMap<(String, u8), u64> = BTreeMap::new();
        for a in &all {
            let view = a.view().unwrap();
            let key = (view.axis.clone(), a.fault);
            if view.state == AlertState::Cleared {
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
