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
//!
//! [`decide`] is the rule meant to replace [`combine`] (issue 30 item 3): one decision for
//! `analyze`, the daemon and `evaluate`, in which the network's agreement lets the envelope
//! name its first-ranked fault on less evidence ([`Agreement`]), never on less separation. It is
//! not called yet: its parameters are to be calibrated first, and under [`Agreement::OFF`] it
//! is the envelope's diagnosis unchanged.

use super::model::LearnedOpinion;
pub use crate::analysis::diagnosis::Agreement;
use crate::analysis::diagnosis::{
    Contest, DecisionRule, Diagnosis, Named, Verdict, LONE_HARMONIC_RATIO,
};
use crate::analysis::fault_bands::FaultScore;
use crate::messages::FaultKind;
use crate::twin::SimulatedFault;
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

/// How far the contest's leader clears `agreement`'s thresholds, in log units (positive: by the
/// factor `exp` of it on its weakest condition), the units of [`DecisionRule::naming_margin`];
/// `None` when the network (`named` at `p`) does not name the leader at `min_probability`, or
/// the leader is the cage (the network has no cage class), or its harmonics do not stand. The
/// probability is quantised to 10^-4 first, so that the last bits of another CPU's arithmetic
/// do not flip it at the boundary.
fn agreement_margin(
    agreement: &Agreement,
    contest: &Contest,
    rule: &DecisionRule,
    named: SimulatedFault,
    p: f64,
) -> Option<f64> {
    let leader = contest.leader;
    let sure = (p * 1e4).round() / 1e4 >= agreement.min_probability;
    if !sure
        || leader.fault == FaultKind::Cage
        || named != SimulatedFault::of(leader.fault)
        || !leader.harmonics_stand(LONE_HARMONIC_RATIO)
    {
        return None;
    }
    let needed = rule.min_significance() - agreement.significance_relief_decades;
    let significance = (leader.significance - needed) * std::f64::consts::LN_10;
    let size = (leader.score.max(1e-9) / agreement.min_score).ln();
    let lead = (lead_ratio(contest) / agreement.min_lead).ln();
    Some(significance.min(size).min(lead))
}

/// The leader's score over the runner-up's (taken as at least 1).
fn lead_ratio(contest: &Contest) -> f64 {
    contest.leader.score / contest.runner_up.map_or(1.0, |r| r.score.max(1.0))
}

/// The envelope's diagnosis (`diagnosis`, made by `diagnose` from `scores` and `explained`),
/// with the learned model's `opinion` joined by `agreement`:
/// 1. a fault the envelope names stands, whatever the network says: disagreement never
///    removes a fault, and never adds one;
/// 2. otherwise the envelope's first-ranked fault ([`Contest`]: the cage giving way as in the
///    diagnosis) is named ([`Named::Agreed`]) when the network's most probable class is that
///    fault at `min_probability` or more, and the comb scores `min_score`, is significant to
///    `significance_relief_decades` short of the rule, leads the runner-up left once it is
///    explained away by `min_lead`, and has every harmonic but one standing
///    ([`LONE_HARMONIC_RATIO`]). Never the cage: the network has no cage class. CWRU ball
///    record 224 is why the lead is always asked: the inner-race comb 4.3 leads the outer
///    race's 3.2 by 1.34×, and the network is 99 % sure of the inner race;
/// 3. otherwise (no opinion included) the envelope's diagnosis.
pub fn decide(
    scores: &[FaultScore],
    explained: &[FaultScore],
    diagnosis: &Diagnosis,
    rule: &DecisionRule,
    agreement: &Agreement,
    opinion: Option<&LearnedOpinion>,
) -> Diagnosis {
    if diagnosis.named.is_some() {
        return diagnosis.clone();
    }
    let (Some(opinion), Some(contest)) = (opinion, Contest::new(scores, explained, rule)) else {
        return diagnosis.clone();
    };
    let (class, p) = opinion.top();
    let Some(margin) = agreement_margin(agreement, &contest, rule, class, p).filter(|&m| m >= 0.0)
    else {
        return diagnosis.clone();
    };
    let leader = contest.leader;
    let runner = contest.runner_up.map_or_else(
        || "no other hypothesis".to_string(),
        |r| format!("{} {:.1} once it is explained", r.fault.name(), r.score),
    );
    Diagnosis {
        verdict: leader.fault.into(),
        confidence: 1.0 - 0.5 * (-2.0 * margin).exp(),
        candidates: Vec::new(),
        reason: format!(
            "{} score {:.1} (noise would give it with p = 10^-{:.1}) is short of the envelope's \
             own naming, but {:.1}× the runner-up {runner} (needs {:.1}×), ≥ {:.1}, every harmonic \
             but one standing, and the learned model names it too ({:.0} %): probable",
            leader.fault.name(),
            leader.score,
            leader.significance,
            lead_ratio(&contest),
            agreement.min_lead,
            agreement.min_score,
            100.0 * p
        ),
        named: Some(Named::Agreed),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::diagnosis::tests::{rule, scores};
    use crate::analysis::diagnosis::{diagnose, leader};

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

    /// Looser than the envelope: a comb of 2.0, 1.5× the runner-up, a decade short of
    /// significance, with the network 90 % sure.
    const LOOSE: Agreement = Agreement {
        min_probability: 0.9,
        min_score: 2.0,
        min_lead: 1.5,
        significance_relief_decades: 1.0,
    };

    /// Scores in `FaultKind::ALL` order: (score, significance) each; the weak outer-race comb
    /// the agreement is for: below `lone_fault_score` (2.5) and a thousand times short of the
    /// significance a lone comb needs, 1.7× the runner-up.
    const WEAK_OUTER: [(f64, f64); 4] = [(2.2, 4.0), (1.3, 1.0), (1.2, 0.5), (1.1, 0.2)];

    /// The envelope's diagnosis of `all` and what [`decide`] makes of it (the others as
    /// `explained`: the test's leader explains nothing of theirs).
    fn envelope_and_decided(
        all: &[FaultScore],
        agreement: &Agreement,
        learned: Option<&LearnedOpinion>,
    ) -> (Diagnosis, Diagnosis) {
        let rule = rule();
        let top = leader(all, &rule).expect("scored").fault;
        let explained: Vec<FaultScore> = all.iter().filter(|s| s.fault != top).copied().collect();
        let envelope = diagnose(all, &explained, &rule);
        let decided = decide(all, &explained, &envelope, &rule, agreement, learned);
        (envelope, decided)
    }

    fn decided(values: [(f64, f64); 4], class: SimulatedFault, p: f64) -> Diagnosis {
        envelope_and_decided(&scores(values), &LOOSE, Some(&opinion(class, p))).1
    }

    #[test]
    fn a_weak_lone_comb_the_network_names_too_is_agreed() {
        let (envelope, agreed) = envelope_and_decided(
            &scores(WEAK_OUTER),
            &LOOSE,
            Some(&opinion(SimulatedFault::OuterRace, 0.95)),
        );
        assert_eq!(envelope.verdict, Verdict::None, "{}", envelope.reason);
        assert_eq!(agreed.verdict, Verdict::OuterRace, "{}", agreed.reason);
        assert_eq!(agreed.named, Some(Named::Agreed));
        assert!(agreed.candidates.is_empty());
        // Cleared by ln(2.2 / 2.0) on its weakest condition, the score.
        let expected = 1.0 - 0.5 * (-2.0 * (2.2_f64 / 2.0).ln()).exp();
        assert!(
            (agreed.confidence - expected).abs() < 1e-12,
            "{}",
            agreed.confidence
        );
        assert!(agreed.reason.contains("learned model"), "{}", agreed.reason);
        // The network short of 90 %, the comb short of the score asked, or more than a decade
        // short of significance: none.
        let larger = Agreement {
            min_score: 2.5,
            ..LOOSE
        };
        let far_short = [(2.2, 1.9), (1.3, 1.0), (1.2, 0.5), (1.1, 0.2)];
        for (agreement, values, p) in [
            (LOOSE, WEAK_OUTER, 0.85),
            (larger, WEAK_OUTER, 0.99),
            (LOOSE, far_short, 0.99),
        ] {
            let learned = opinion(SimulatedFault::OuterRace, p);
            let (_, d) = envelope_and_decided(&scores(values), &agreement, Some(&learned));
            assert_eq!(d.verdict, Verdict::None, "{values:?} {p}: {}", d.reason);
            assert_eq!(d.named, None);
        }
        // Half a decade short of significance: named with a decade's relief, not with none.
        let short = [(2.2, 2.5), (1.3, 1.0), (1.2, 0.5), (1.1, 0.2)];
        assert_eq!(
            decided(short, SimulatedFault::OuterRace, 0.99).verdict,
            Verdict::OuterRace
        );
        let no_relief = Agreement {
            significance_relief_decades: 0.0,
            ..LOOSE
        };
        let learned = opinion(SimulatedFault::OuterRace, 0.99);
        let (_, d) = envelope_and_decided(&scores(short), &no_relief, Some(&learned));
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
    }

    #[test]
    fn disagreement_never_adds_a_fault_nor_removes_a_named_one() {
        let others = [
            SimulatedFault::None,
            SimulatedFault::InnerRace,
            SimulatedFault::Ball,
            SimulatedFault::Cage,
        ];
        let named_outer = [(8.0, 20.0), (1.5, 1.0), (2.0, 1.0), (1.4, 0.2)];
        for values in [WEAK_OUTER, named_outer] {
            for class in others {
                let learned = opinion(class, 0.99);
                let (envelope, d) = envelope_and_decided(&scores(values), &LOOSE, Some(&learned));
                assert_eq!(d, envelope, "{values:?} {class:?}");
            }
        }
        // The named fault stands whatever the network says, and without its opinion too.
        let (envelope, d) = envelope_and_decided(&scores(named_outer), &LOOSE, None);
        assert_eq!(envelope.verdict, Verdict::OuterRace);
        assert_eq!(d, envelope);
        let (envelope, d) = envelope_and_decided(&scores(WEAK_OUTER), &LOOSE, None);
        assert_eq!(envelope.verdict, Verdict::None);
        assert_eq!(d, envelope);
    }

    #[test]
    fn a_leader_close_to_its_runner_up_stays_open_however_sure_the_network() {
        // CWRU ball record 224: the inner-race comb 4.3 ranks first, the outer race's 3.2 is
        // left once it is explained (1.34×), and the network is 99 % sure of the inner race.
        let record_224 = [(3.2, 8.0), (4.3, 12.0), (1.5, 1.0), (1.3, 0.5)];
        let d = decided(record_224, SimulatedFault::InnerRace, 0.99);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // It is the lead that holds it: asked for 1.3× it would be named.
        let lax = Agreement {
            min_lead: 1.3,
            ..LOOSE
        };
        let learned = opinion(SimulatedFault::InnerRace, 0.99);
        let (_, d) = envelope_and_decided(&scores(record_224), &lax, Some(&learned));
        assert_eq!(d.verdict, Verdict::InnerRace, "{}", d.reason);
    }

    #[test]
    fn a_comb_of_two_tall_lines_stays_open_however_sure_the_network() {
        let freqs = crate::bearing::BearingGeometry::from_catalog("skf-6205-2rs")
            .expect("a catalog bearing")
            .fault_frequencies(29.5);
        let mut all = scores(WEAK_OUTER);
        let mut tones = FaultScore::unscored(FaultKind::OuterRace, &freqs)
            .with_harmonic_ratios(&[6.0, 1.0, 1.1, 1.2, 5.0]);
        tones.score = 2.2;
        tones.significance = 4.0;
        all[0] = tones;
        let learned = opinion(SimulatedFault::OuterRace, 0.99);
        let (envelope, d) = envelope_and_decided(&all, &LOOSE, Some(&learned));
        assert_eq!(d, envelope);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
    }

    #[test]
    fn the_cage_is_never_agreed() {
        // A weak cage comb leads (nothing significant beside it to give way to).
        let weak_cage = [(1.2, 0.5), (1.3, 1.0), (1.2, 0.4), (2.2, 4.0)];
        assert_eq!(
            leader(&scores(weak_cage), &rule()).map(|l| l.fault),
            Some(FaultKind::Cage)
        );
        for class in SimulatedFault::ALL {
            let d = decided(weak_cage, class, 0.99);
            assert_eq!(d.verdict, Verdict::None, "{class:?}: {}", d.reason);
        }
    }

    #[test]
    fn without_agreement_or_with_the_envelopes_own_thresholds_decide_is_diagnose() {
        let rule = rule();
        let strict = Agreement {
            min_probability: 0.0,
            min_score: rule.min_fault_score,
            min_lead: rule.min_score_ratio,
            significance_relief_decades: 0.0,
        };
        let cases = [
            WEAK_OUTER,
            [(1.5, 0.5), (8.0, 20.0), (2.0, 1.0), (1.4, 0.2)],
            [(1.5, 0.5), (4.9, 20.0), (2.0, 1.0), (1.4, 0.2)],
            [(1.5, 0.5), (3.5, 30.0), (1.4, 1.0), (1.3, 0.2)],
            [(2.6, 4.0), (3.5, 30.0), (1.4, 1.0), (1.3, 0.2)],
            [(6.0, 10.0), (7.0, 12.0), (1.4, 1.0), (1.3, 0.2)],
            [(3.2, 8.0), (4.3, 12.0), (1.5, 1.0), (1.3, 0.5)],
            [(1.5, 0.5), (1.3, 1.0), (2.0, 2.5), (7.9, 20.0)],
            [(1.3, 0.5), (1.6, 11.0), (2.5, 26.0), (4.9, 23.0)],
            [(1.0, 0.0), (2.4, 30.0), (1.0, 0.0), (1.0, 0.0)],
        ];
        for values in cases {
            for class in SimulatedFault::ALL {
                let learned = opinion(class, 1.0);
                for agreement in [Agreement::OFF, strict] {
                    let (envelope, d) =
                        envelope_and_decided(&scores(values), &agreement, Some(&learned));
                    assert_eq!(d, envelope, "{values:?} {class:?} {agreement:?}");
                }
            }
        }
        // And the loose agreement does change some of them (the cases are not all beyond it).
        let changed = cases
            .iter()
            .filter(|&&values| {
                let learned = opinion(SimulatedFault::OuterRace, 1.0);
                let (envelope, d) = envelope_and_decided(&scores(values), &LOOSE, Some(&learned));
                d != envelope
            })
            .count();
        assert!(changed >= 1);
    }
}
