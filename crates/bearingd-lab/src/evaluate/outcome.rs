//! What a case gave: each path's conclusion ([`Predicted`]), the record path's and the monitor
//! path's outcomes, and the case's result. Types only, shared by the run that makes them and
//! the summaries and agreement grid that read them (so that none of those imports another).

use super::sweep::Case;
use crate::analysis::agreement::WitnessOpinion;
use crate::analysis::Verdict;
use crate::messages::{FaultKind, FlagLevel};
use serde::Serialize;

/// What one path concluded about one record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Predicted {
    None,
    Fault(FaultKind),
    /// Two faults named, not told apart: the record path's pair verdict
    /// ([`Verdict::PAIRS`]: `ball_or_cage`, `ball_or_inner`), or the monitor raising the flags
    /// of exactly such a pair. It carries the pair, so both paths saying the same pair agree.
    Ambiguous(Verdict),
    /// The monitor raised the flags of more than one fault kind.
    Several,
}

impl Predicted {
    pub fn name(self) -> &'static str {
        match self {
            Predicted::None => "none",
            Predicted::Fault(kind) => kind.name(),
            Predicted::Ambiguous(pair) => pair.name(),
            Predicted::Several => "several",
        }
    }

    /// The columns of a confusion matrix, in order.
    pub const COLUMNS: [Predicted; 8] = [
        Predicted::None,
        Predicted::Fault(FaultKind::OuterRace),
        Predicted::Fault(FaultKind::InnerRace),
        Predicted::Fault(FaultKind::Ball),
        Predicted::Fault(FaultKind::Cage),
        Predicted::Ambiguous(Verdict::BallOrCage),
        Predicted::Ambiguous(Verdict::BallOrInner),
        Predicted::Several,
    ];

    /// What the flags say, from the highest level each fault's flag reached (outer, inner,
    /// ball, cage): the one fault whose flag rose, none, the two of a verdict that cannot tell
    /// them apart (a rolling element or the cage, or the inner race: that pair), or several.
    pub fn of_flags(highest: [FlagLevel; 4]) -> Self {
        let raised: Vec<FaultKind> = FaultKind::ALL
            .into_iter()
            .zip(highest)
            .filter(|(_, level)| *level > FlagLevel::Ok)
            .map(|(kind, _)| kind)
            .collect();
        match raised.as_slice() {
            [] => Predicted::None,
            [kind] => Predicted::Fault(*kind),
            both => Verdict::PAIRS
                .into_iter()
                .find(|pair| pair.faults() == both)
                .map_or(Predicted::Several, Predicted::Ambiguous),
        }
    }

    /// What a verdict says. Written against the verdict's public meaning (`fault()` names one
    /// fault or none), so that a verdict added later for "both named, not separable" counts as
    /// that pair without a change here.
    pub fn of_verdict(verdict: Verdict) -> Self {
        match verdict.fault() {
            Some(kind) => Predicted::Fault(kind),
            None if verdict == Verdict::None => Predicted::None,
            None => Predicted::Ambiguous(verdict),
        }
    }
}

/// The record path's outcome.
#[derive(Debug, Clone, Serialize)]
pub struct RecordOutcome {
    pub verdict: String,
    pub predicted: Predicted,
    pub confidence: f64,
    pub reason: String,
    /// With a `none` verdict: the faults detected but not told apart.
    pub candidates: Vec<FaultKind>,
    /// Fault scores in outer, inner, ball, cage order.
    pub scores: [f64; 4],
    /// The learned model's opinion, when the bench has a model that knows the bearing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub learned: Option<WitnessOpinion>,
    /// With a model: the verdict at each point of [`super::agreement::grid`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub agreement_grid: Vec<Predicted>,
}

/// The monitor path's outcome.
#[derive(Debug, Clone, Serialize)]
pub struct MonitorOutcome {
    /// The highest level each fault's flag reached (outer, inner, ball, cage).
    pub highest: [FlagLevel; 4],
    /// When the first flag rose, s of sample time.
    pub first_flag_s: Option<f64>,
    /// Windows scored after the first band selection, and how many of them had a flag up.
    pub windows_scored: u64,
    pub windows_flagged: u64,
    pub predicted: Predicted,
}

/// Counts the windows scored after the first band selection and those of them that closed
/// with a flag up. A window counts by its end sample: scored if it ended after the first
/// selection's sample, flagged by the levels in force when it ended. The monitor decides a
/// selection's flags before it finishes the newest window's band work (the alert must not
/// wait for it), so that window's report may come after the selection and a flag change at a
/// later sample. A flag changes at most once between two reports.
#[derive(Debug, Clone, Copy)]
pub struct WindowFlagCount {
    /// The first band selection's sample.
    first_selection: Option<u64>,
    /// Each flag's level now, and before its latest change with that change's sample.
    levels: [FlagLevel; 4],
    before_change: [(FlagLevel, u64); 4],
    pub scored: u64,
    pub flagged: u64,
}

impl Default for WindowFlagCount {
    fn default() -> Self {
        WindowFlagCount {
            first_selection: None,
            levels: [FlagLevel::Ok; 4],
            before_change: [(FlagLevel::Ok, 0); 4],
            scored: 0,
            flagged: 0,
        }
    }
}

impl WindowFlagCount {
    /// A band selection was used at `at_sample`.
    pub fn selection(&mut self, at_sample: u64) {
        self.first_selection.get_or_insert(at_sample);
    }

    /// The first band selection's sample, once there was one.
    pub fn first_selection(&self) -> Option<u64> {
        self.first_selection
    }

    /// `fault`'s flag changed to `to` at sample `at_sample`.
    pub fn flag_changed(&mut self, fault: FaultKind, to: FlagLevel, at_sample: u64) {
        let i = fault.index();
        self.before_change[i] = (self.levels[i], at_sample);
        self.levels[i] = to;
    }

    /// The report of a window that ended at `end_sample`.
    pub fn window(&mut self, end_sample: u64) {
        if self.first_selection.is_none_or(|at| end_sample <= at) {
            return;
        }
        self.scored += 1;
        let raised = self
            .levels
            .iter()
            .zip(&self.before_change)
            .any(|(&now, &(before, at))| {
                let level = if end_sample > at { now } else { before };
                level > FlagLevel::Ok
            });
        if raised {
            self.flagged += 1;
        }
    }
}

/// One case's results.
#[derive(Debug, Clone, Serialize)]
pub struct CaseResult {
    pub case: Case,
    /// RMS of the broadband noise (white and shaft-modulated), g.
    pub noise_g: f64,
    /// The fault's RMS over the broadband noise's, dB (`None` for healthy records).
    pub snr_db: Option<f64>,
    /// `Err`: the record could not be analysed (the message says why); counts as a miss.
    pub record: Result<RecordOutcome, String>,
    pub monitor: MonitorOutcome,
}

impl CaseResult {
    pub fn truth(&self) -> Option<FaultKind> {
        self.case.fault.kind()
    }

    /// One line saying what was simulated and what both paths made of it (for test failures
    /// and logs).
    pub fn describe(&self) -> String {
        let record = match &self.record {
            Ok(o) => format!(
                "analyze: {} ({:.2}; scores outer {:.1} inner {:.1} ball {:.1} cage {:.1}; {})",
                o.verdict,
                o.confidence,
                o.scores[0],
                o.scores[1],
                o.scores[2],
                o.scores[3],
                o.reason
            ),
            Err(e) => format!("analyze failed: {e}"),
        };
        let flags: Vec<String> = FaultKind::ALL
            .iter()
            .zip(self.monitor.highest)
            .map(|(k, l)| format!("{} {}", k.name(), l.name()))
            .collect();
        format!(
            "{} on {} at {:.0} rpm, severity {} g, noise {} ({:.3} g{}): {record}; monitor flags: {}",
            self.case.fault.name(),
            self.case.bearing,
            self.case.rpm,
            self.case.severity,
            self.case.noise.label(),
            self.noise_g,
            self.snr_db
                .map_or(String::new(), |s| format!(", SNR {s:+.1} dB")),
            flags.join(", ")
        )
    }

    pub fn record_predicted(&self) -> Predicted {
        self.record
            .as_ref()
            .map_or(Predicted::None, |outcome| outcome.predicted)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flags_of_a_pair_verdict_are_ambiguous_and_other_pairs_are_several() {
        let (ok, alarm) = (FlagLevel::Ok, FlagLevel::Alarm);
        // Outer, inner, ball, cage.
        assert_eq!(
            Predicted::of_flags([ok, alarm, alarm, ok]),
            Predicted::Ambiguous(Verdict::BallOrInner)
        );
        assert_eq!(
            Predicted::of_flags([ok, ok, alarm, alarm]),
            Predicted::Ambiguous(Verdict::BallOrCage)
        );
        assert_eq!(
            Predicted::of_flags([alarm, alarm, ok, ok]),
            Predicted::Several
        );
        assert_eq!(
            Predicted::of_verdict(Verdict::BallOrInner),
            Predicted::Ambiguous(Verdict::BallOrInner)
        );
        assert_eq!(
            Predicted::Ambiguous(Verdict::BallOrInner).name(),
            "ball_or_inner"
        );
    }

    /// A window counts by its end sample, whenever its report comes: scored once it ended after
    /// the first selection, flagged by the levels in force when it ended.
    #[test]
    fn a_window_counts_with_the_levels_in_force_at_its_end() {
        let mut count = WindowFlagCount::default();
        count.window(100);
        count.selection(200);
        count.flag_changed(FaultKind::OuterRace, FlagLevel::Watch, 200);
        // Reports that came after the selection and its flag, of windows that ended before.
        count.window(150);
        count.window(200);
        assert_eq!((count.scored, count.flagged), (0, 0));
        count.window(250);
        count.flag_changed(FaultKind::OuterRace, FlagLevel::Ok, 400);
        count.window(380);
        count.window(450);
        assert_eq!((count.scored, count.flagged), (3, 2));
        assert_eq!(count.first_selection(), Some(200));
    }
}
