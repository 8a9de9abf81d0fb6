//! How the learned opinion joins the envelope diagnosis: as a second opinion that may settle
//! what the envelope's own thresholds leave open, never as a replacement.
//!
//! The rule (in this order):
//! 1. the envelope names a fault: that is the answer, whatever the network says (so the
//!    combination loses no case the envelope gets right);
//! 2. the envelope says "no clear fault" but names candidates it could not tell apart: the
//!    network may pick one of them, if it is at least [`CONFIRM_PROBABILITY`] sure of it;
//! 3. the envelope says "no clear fault" and its first-ranked fault is significant against the
//!    noise floor (at the configured false-alarm rate) and leads the runner-up by the rule's
//!    own ratio, but its comb score is below the naming threshold: the network may confirm that
//!    very fault, at the same probability. So the network can stand in for the score's
//!    *size*, never for the *separation* between faults: on CWRU ball record 224 the envelope
//!    ranks the inner race first at 1.3× the runner-up and the network is 99 % sure of the
//!    inner race, and the record is a ball fault;
//! 4. otherwise the envelope's answer stands. The network alone never names a fault: what it
//!    says must be visible as significant lines in the envelope spectrum a user can check.

use super::model::LearnedOpinion;
use crate::analysis::diagnosis::{DecisionRule, Diagnosis, Verdict};
use crate::analysis::fault_bands::FaultScore;
use crate::messages::FaultKind;
use serde::Serialize;

/// (choice, made before any test set was run) How sure the network must be to settle an open
/// case. It is not what keeps the network's confident mistakes out: on CWRU ball record 224 it
/// is 99 % sure of the inner race; the envelope's separation condition (rule 3) is.
pub const CONFIRM_PROBABILITY: f64 = 0.9;

/// What the envelope diagnosis says of a record, as far as the combination needs it.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvelopeView {
    pub verdict: Verdict,
    /// With `none`: the faults each detected but not told apart.
    pub candidates: Vec<FaultKind>,
    /// The fault with the highest comb score, if its comb is significant and it leads the
    /// runner-up by the rule's ratio (`min_score_ratio`).
    pub clear_leader: Option<FaultKind>,
}

impl EnvelopeView {
    /// The view of an envelope diagnosis and the fault scores it was made from.
    pub fn of<'s>(
        diagnosis: &Diagnosis,
        scores: impl IntoIterator<Item = &'s FaultScore>,
        rule: &DecisionRule,
    ) -> Self {
        EnvelopeView {
            verdict: diagnosis.verdict,
            candidates: diagnosis.candidates.clone(),
            clear_leader: clear_leader(scores, rule),
        }
    }
}

/// The fault with the highest comb score, if its comb is significant and it leads the
/// runner-up by the rule's ratio.
pub fn clear_leader<'s>(
    scores: impl IntoIterator<Item = &'s FaultScore>,
    rule: &DecisionRule,
) -> Option<FaultKind> {
    let mut ranked: Vec<&FaultScore> = scores.into_iter().collect();
    ranked.sort_by(|a, b| b.score.total_cmp(&a.score));
    let (first, rest) = ranked.split_first()?;
    let runner_up = rest.first().map_or(1.0, |s| s.score.max(1.0));
    (rule.significant(first) && first.score >= rule.min_score_ratio * runner_up)
        .then_some(first.fault)
}

/// On what the combined answer rests.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// The envelope diagnosis alone (the network agreed, disagreed or was not sure).
    Envelope,
    /// The envelope's candidates or its significant first-ranked fault, confirmed by the
    /// network.
    EnvelopeConfirmedByLearned,
}

/// The combined diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Combined {
    pub verdict: Verdict,
    pub basis: Basis,
    /// Whether the network's most probable class is the combined verdict.
    pub learned_agrees: bool,
    /// With [`Basis::Envelope`]: what the network said, to add to the envelope's reason; with
    /// [`Basis::EnvelopeConfirmedByLearned`]: the whole reason.
    pub reason: String,
}

pub fn combine(envelope: &EnvelopeView, learned: &LearnedOpinion) -> Combined {
    let (class, probability) = learned.top();
    let learned_kind = class.kind();
    let says = format!(
        "the network says {} ({:.0} %)",
        class.name(),
        100.0 * probability
    );
    let envelope_only = |reason: String| Combined {
        verdict: envelope.verdict,
        basis: Basis::Envelope,
        learned_agrees: learned_kind == envelope.verdict.fault(),
        reason,
    };
    if envelope.verdict != Verdict::None {
        return envelope_only(says);
    }
    let Some(kind) = learned_kind else {
        return envelope_only(says);
    };
    if probability < CONFIRM_PROBABILITY {
        return envelope_only(format!(
            "{says}, short of the {:.0} % it needs to settle it",
            100.0 * CONFIRM_PROBABILITY
        ));
    }
    let confirmed = |why: &str| Combined {
        verdict: Verdict::from(kind),
        basis: Basis::EnvelopeConfirmedByLearned,
        learned_agrees: true,
        reason: format!("{why}; {says}"),
    };
    if envelope.candidates.contains(&kind) {
        return confirmed(&format!(
            "the envelope detects {} but cannot tell them apart",
            envelope
                .candidates
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(" and ")
        ));
    }
    match envelope.clear_leader {
        Some(first) if first == kind => confirmed(&format!(
            "the envelope ranks {} first, significant and clear of the runner-up, but below its naming score",
            first.name()
        )),
        _ => envelope_only(format!(
            "{says}, but the envelope does not rank {} first, significant and clear of the runner-up, so no clear fault stands",
            kind.name()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::twin::SimulatedFault;

    fn opinion(class: SimulatedFault, p: f64) -> LearnedOpinion {
        LearnedOpinion {
            model: "m".into(),
            segments: 3,
            probabilities: vec![(class, p), (SimulatedFault::None, 1.0 - p)],
        }
    }

    fn view(verdict: Verdict, candidates: &[FaultKind], leader: Option<FaultKind>) -> EnvelopeView {
        EnvelopeView {
            verdict,
            candidates: candidates.to_vec(),
            clear_leader: leader,
        }
    }

    #[test]
    fn an_envelope_verdict_is_never_overruled() {
        let combined = combine(
            &view(Verdict::OuterRace, &[], Some(FaultKind::OuterRace)),
            &opinion(SimulatedFault::Ball, 0.99),
        );
        assert_eq!(combined.verdict, Verdict::OuterRace);
        assert_eq!(combined.basis, Basis::Envelope);
        assert!(!combined.learned_agrees);
    }

    #[test]
    fn the_network_settles_candidates_or_a_significant_leader_only() {
        let both = [FaultKind::InnerRace, FaultKind::Ball];
        let pick = combine(
            &view(Verdict::None, &both, None),
            &opinion(SimulatedFault::Ball, 0.95),
        );
        assert_eq!(pick.verdict, Verdict::Ball);
        assert_eq!(pick.basis, Basis::EnvelopeConfirmedByLearned);
        let leader = Some(FaultKind::InnerRace);
        let confirm = combine(
            &view(Verdict::None, &[], leader),
            &opinion(SimulatedFault::InnerRace, 0.95),
        );
        assert_eq!(confirm.verdict, Verdict::InnerRace);
        // Not sure enough, another fault than the leader, or no clear leader: none.
        for (first, class, p) in [
            (leader, SimulatedFault::InnerRace, 0.8),
            (leader, SimulatedFault::OuterRace, 0.99),
            (None, SimulatedFault::InnerRace, 0.99),
        ] {
            let combined = combine(&view(Verdict::None, &[], first), &opinion(class, p));
            assert_eq!(combined.verdict, Verdict::None, "{first:?} {class:?} {p}");
        }
    }
}
