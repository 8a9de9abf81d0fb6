//! How the learned opinion joins the envelope diagnosis: as the second witness of
//! [`crate::analysis::agreement::decide`], never as a replacement.
//!
//! The decision itself lives in the analysis core, so that `analyze --learned`, the daemon's
//! band job and `evaluate` make it with one function. Here: a model's opinion as the witness
//! gives it (the models as a `Witness`: [`super::set`]), and what the report says of the
//! outcome ([`Combined`]): on what the verdict rests, and whether the network's most probable
//! class is it.

use super::model::LearnedOpinion;
use crate::analysis::agreement::WitnessOpinion;
use crate::analysis::diagnosis::{Diagnosis, Named, Verdict};
use serde::Serialize;

impl LearnedOpinion {
    /// The opinion as a witness gives it: its most probable class; `None` without a segment.
    pub fn as_witness(&self) -> Option<WitnessOpinion> {
        (self.segments > 0).then(|| {
            let (class, probability) = self.top();
            WitnessOpinion {
                fault: class.kind(),
                probability,
            }
        })
    }
}

/// On what the combined answer rests.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// The envelope diagnosis alone (the network agreed, disagreed or was not sure).
    Envelope,
    /// The envelope's first-ranked fault, short of the envelope's own naming, with the network
    /// naming it too ([`Named::Agreed`]): a probable fault.
    Agreement,
}

/// The combined diagnosis, as the report shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Combined {
    pub verdict: Verdict,
    pub basis: Basis,
    /// Whether the network's most probable class is the combined verdict.
    pub learned_agrees: bool,
    /// With [`Basis::Envelope`]: what the network said, to add to the envelope's reason; with
    /// [`Basis::Agreement`]: the whole reason.
    pub reason: String,
}

/// What the report says of `decided` (the outcome of `decide` with `opinion` as the witness).
pub fn combined(decided: &Diagnosis, opinion: &LearnedOpinion) -> Combined {
    let (class, probability) = opinion.top();
    let learned_agrees = class.kind() == decided.verdict.fault();
    if decided.named == Some(Named::Agreed) {
        return Combined {
            verdict: decided.verdict,
            basis: Basis::Agreement,
            learned_agrees,
            reason: decided.reason.clone(),
        };
    }
    Combined {
        verdict: decided.verdict,
        basis: Basis::Envelope,
        learned_agrees,
        reason: format!(
            "the network says {} ({:.0} %)",
            class.name(),
            100.0 * probability
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::twin::SimulatedFault;

    fn opinion(class: SimulatedFault, p: f64, segments: usize) -> LearnedOpinion {
        LearnedOpinion {
            model: "m".into(),
            segments,
            probabilities: vec![(class, p), (SimulatedFault::None, 1.0 - p)],
        }
    }

    fn diagnosis(verdict: Verdict, named: Option<Named>) -> Diagnosis {
        Diagnosis {
            verdict,
            confidence: 0.9,
            candidates: Vec::new(),
            reason: "the envelope's reason".into(),
            named,
        }
    }

    #[test]
    fn an_agreed_verdict_rests_on_agreement_and_keeps_decides_reason() {
        let learned = opinion(SimulatedFault::OuterRace, 0.95, 3);
        let c = combined(
            &diagnosis(Verdict::OuterRace, Some(Named::Agreed)),
            &learned,
        );
        assert_eq!(c.basis, Basis::Agreement);
        assert!(c.learned_agrees);
        assert_eq!(c.reason, "the envelope's reason");
        let c = combined(
            &diagnosis(Verdict::InnerRace, Some(Named::BySize)),
            &learned,
        );
        assert_eq!(c.basis, Basis::Envelope);
        assert!(!c.learned_agrees);
        assert!(c.reason.contains("outer_race (95 %)"), "{}", c.reason);
    }

    #[test]
    fn an_opinion_without_segments_is_no_witness() {
        assert_eq!(opinion(SimulatedFault::Ball, 0.99, 0).as_witness(), None);
        assert_eq!(
            opinion(SimulatedFault::None, 0.8, 2).as_witness(),
            Some(WitnessOpinion {
                fault: None,
                probability: 0.8
            })
        );
    }
}
