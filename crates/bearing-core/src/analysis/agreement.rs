//! The third way of naming a fault: by agreement with a second witness.
//!
//! The envelope's rule ([`super::diagnosis`]) names a fault on the comb's evidence alone. A
//! second witness of the same samples (the learned model, `crate::learned`, trained only on
//! synthetic records) may let the envelope name its first-ranked fault on less evidence, when
//! it names that very fault: [`decide`]. The witness stands in for the comb's size and part of
//! its significance, never for its separation from the runner-up nor for its shape, and it
//! never adds a fault the envelope does not rank first nor removes one it names. What is named
//! this way stays visible as lines a user can check in the envelope spectrum.
//!
//! Why here, in the sans-IO core: `analyze`, the daemon's band job and `evaluate` call this one
//! function on the same input, so they cannot disagree. The witness is a trait
//! ([`Witness`]) so that the core does not link the model's runtime.

use super::diagnosis::{Contest, DecisionRule, Diagnosis, Named, LONE_HARMONIC_RATIO};
use super::fault_bands::FaultScore;
use crate::bearing::{BearingGeometry, FaultFrequencies};
use crate::messages::FaultKind;
use serde::{Deserialize, Serialize};

/// How much less evidence the envelope needs for its first-ranked fault when the witness names
/// the same fault ([`decide`]). The witness stands in for the comb's size and for part of its
/// significance, never for its separation from the runner-up nor for its shape. A parameter of
/// the decision like [`DecisionRule`], held by the analysis settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Agreement {
    /// The network's probability of the leader's class, at least.
    pub min_probability: f64,
    /// The leader's comb score, at least: below `min_fault_score` and `lone_fault_score`, the
    /// point of the agreement.
    pub min_score: f64,
    /// The leader's score over the runner-up's once the leader is explained away (taken as at
    /// least 1), at least; required whether the runner-up is detected or not.
    pub min_lead: f64,
    /// By how many decades the leader's significance may fall short of the rule's
    /// (`min_significance`).
    pub significance_relief_decades: f64,
}

impl Agreement {
    /// No agreement counts: no probability reaches it, so `decide` gives the envelope's
    /// diagnosis.
    pub const OFF: Agreement = Agreement {
        min_probability: f64::INFINITY,
        min_score: f64::INFINITY,
        min_lead: f64::INFINITY,
        significance_relief_decades: 0.0,
    };
}

/// What a witness says of a signal: its most probable class (`None`: healthy) and how sure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WitnessOpinion {
    pub fault: Option<FaultKind>,
    pub probability: f64,
}

/// A second opinion of a signal, e.g. the learned models, one per bearing
/// (`crate::learned::ModelSet`).
pub trait Witness: Send + Sync + std::fmt::Debug {
    /// The opinion of `signal` (g, at `fs_hz`, the shaft and the faults at `freqs`);
    /// `Ok(None)` when it has none (the signal is too short for it), `Err` with why when it
    /// failed.
    fn witness(
        &self,
        signal: &[f32],
        fs_hz: f64,
        freqs: &FaultFrequencies,
    ) -> Result<Option<WitnessOpinion>, String>;

    /// Whether it can judge signals of `bearing` (a model is trained for one geometry).
    fn knows(&self, bearing: &BearingGeometry) -> bool;
}

/// How far the contest's leader clears `agreement`'s thresholds, in log units (positive: by the
/// factor `exp` of it on its weakest condition), the units of [`DecisionRule::naming_margin`];
/// `None` when the network (`opinion`) does not name the leader at `min_probability`, or
/// the leader is the cage (the network has no cage class), or its harmonics do not stand. The
/// probability is quantised to 10^-4 first, so that the last bits of another CPU's arithmetic
/// do not flip it at the boundary.
fn agreement_margin(
    agreement: &Agreement,
    contest: &Contest,
    rule: &DecisionRule,
    opinion: WitnessOpinion,
) -> Option<f64> {
    let leader = contest.leader;
    let sure = (opinion.probability * 1e4).round() / 1e4 >= agreement.min_probability;
    if !sure
        || leader.fault == FaultKind::Cage
        || opinion.fault != Some(leader.fault)
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
    opinion: Option<WitnessOpinion>,
) -> Diagnosis {
    if diagnosis.named.is_some() {
        return diagnosis.clone();
    }
    let (Some(opinion), Some(contest)) = (opinion, Contest::new(scores, explained, rule)) else {
        return diagnosis.clone();
    };
    let Some(margin) = agreement_margin(agreement, &contest, rule, opinion).filter(|&m| m >= 0.0)
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
            100.0 * opinion.probability
        ),
        named: Some(Named::Agreed),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::diagnosis::tests::{rule, scores};
    use crate::analysis::diagnosis::{diagnose, leader, Verdict};

    /// Every class a witness may name: healthy and the four faults.
    const CLASSES: [Option<FaultKind>; 5] = [
        None,
        Some(FaultKind::OuterRace),
        Some(FaultKind::InnerRace),
        Some(FaultKind::Ball),
        Some(FaultKind::Cage),
    ];

    fn opinion(fault: Option<FaultKind>, probability: f64) -> WitnessOpinion {
        WitnessOpinion { fault, probability }
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
        learned: Option<WitnessOpinion>,
    ) -> (Diagnosis, Diagnosis) {
        let rule = rule();
        let top = leader(all, &rule).expect("scored").fault;
        let explained: Vec<FaultScore> = all.iter().filter(|s| s.fault != top).copied().collect();
        let envelope = diagnose(all, &explained, &rule);
        let decided = decide(all, &explained, &envelope, &rule, agreement, learned);
        (envelope, decided)
    }

    fn decided(values: [(f64, f64); 4], class: Option<FaultKind>, p: f64) -> Diagnosis {
        envelope_and_decided(&scores(values), &LOOSE, Some(opinion(class, p))).1
    }

    #[test]
    fn a_weak_lone_comb_the_network_names_too_is_agreed() {
        let (envelope, agreed) = envelope_and_decided(
            &scores(WEAK_OUTER),
            &LOOSE,
            Some(opinion(Some(FaultKind::OuterRace), 0.95)),
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
            let learned = opinion(Some(FaultKind::OuterRace), p);
            let (_, d) = envelope_and_decided(&scores(values), &agreement, Some(learned));
            assert_eq!(d.verdict, Verdict::None, "{values:?} {p}: {}", d.reason);
            assert_eq!(d.named, None);
        }
        // Half a decade short of significance: named with a decade's relief, not with none.
        let short = [(2.2, 2.5), (1.3, 1.0), (1.2, 0.5), (1.1, 0.2)];
        assert_eq!(
            decided(short, Some(FaultKind::OuterRace), 0.99).verdict,
            Verdict::OuterRace
        );
        let no_relief = Agreement {
            significance_relief_decades: 0.0,
            ..LOOSE
        };
        let learned = opinion(Some(FaultKind::OuterRace), 0.99);
        let (_, d) = envelope_and_decided(&scores(short), &no_relief, Some(learned));
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
    }

    #[test]
    fn disagreement_never_adds_a_fault_nor_removes_a_named_one() {
        let others = [
            None,
            Some(FaultKind::InnerRace),
            Some(FaultKind::Ball),
            Some(FaultKind::Cage),
        ];
        let named_outer = [(8.0, 20.0), (1.5, 1.0), (2.0, 1.0), (1.4, 0.2)];
        for values in [WEAK_OUTER, named_outer] {
            for class in others {
                let learned = opinion(class, 0.99);
                let (envelope, d) = envelope_and_decided(&scores(values), &LOOSE, Some(learned));
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
        let d = decided(record_224, Some(FaultKind::InnerRace), 0.99);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // It is the lead that holds it: asked for 1.3× it would be named.
        let lax = Agreement {
            min_lead: 1.3,
            ..LOOSE
        };
        let learned = opinion(Some(FaultKind::InnerRace), 0.99);
        let (_, d) = envelope_and_decided(&scores(record_224), &lax, Some(learned));
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
        let learned = opinion(Some(FaultKind::OuterRace), 0.99);
        let (envelope, d) = envelope_and_decided(&all, &LOOSE, Some(learned));
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
        for class in CLASSES {
            let d = decided(weak_cage, class, 0.99);
            assert_eq!(d.verdict, Verdict::None, "{class:?}: {}", d.reason);
        }
    }

    #[test]
    fn a_pair_verdict_stands_and_the_witness_never_splits_it() {
        let all = scores([(1.2, 0.5), (8.0, 20.0), (3.0, 6.0), (1.1, 0.2)]);
        let envelope = Diagnosis {
            verdict: Verdict::BallOrInner,
            confidence: 0.9,
            candidates: Verdict::BallOrInner.faults().to_vec(),
            reason: "either".into(),
            named: Some(Named::BySize),
        };
        let explained: Vec<FaultScore> = all[..1].iter().chain(&all[2..]).copied().collect();
        for class in [FaultKind::InnerRace, FaultKind::Ball] {
            let opinion = Some(opinion(Some(class), 0.99));
            let decided = decide(&all, &explained, &envelope, &rule(), &LOOSE, opinion);
            assert_eq!(decided, envelope);
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
            for class in CLASSES {
                let learned = opinion(class, 1.0);
                for agreement in [Agreement::OFF, strict] {
                    let (envelope, d) =
                        envelope_and_decided(&scores(values), &agreement, Some(learned));
                    assert_eq!(d, envelope, "{values:?} {class:?} {agreement:?}");
                }
            }
        }
        // And the loose agreement does change some of them (the cases are not all beyond it).
        let changed = cases
            .iter()
            .filter(|&&values| {
                let learned = opinion(Some(FaultKind::OuterRace), 1.0);
                let (envelope, d) = envelope_and_decided(&scores(values), &LOOSE, Some(learned));
                d != envelope
            })
            .count();
        assert!(changed >= 1);
    }
}
