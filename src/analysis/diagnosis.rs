//! The verdict: which fault, if any, the fault-band scores support, and how confidently.
//!
//! The rule is deliberately conservative, because the users hate false alarms: a fault is
//! named only when its score reaches `min_fault_score` AND exceeds every other fault's score by
//! `min_score_ratio`; otherwise the verdict is `none`. Close calls are reported as `none` with
//! the reason, never as a guess.

use super::fault_bands::FaultScore;
use crate::messages::FaultKind;
use serde::Serialize;

/// What the analysis concludes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    None,
    OuterRace,
    InnerRace,
    Ball,
    Cage,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::None => "none",
            Verdict::OuterRace => "outer_race",
            Verdict::InnerRace => "inner_race",
            Verdict::Ball => "ball",
            Verdict::Cage => "cage",
        }
    }

    pub fn fault(self) -> Option<FaultKind> {
        match self {
            Verdict::None => None,
            Verdict::OuterRace => Some(FaultKind::OuterRace),
            Verdict::InnerRace => Some(FaultKind::InnerRace),
            Verdict::Ball => Some(FaultKind::Ball),
            Verdict::Cage => Some(FaultKind::Cage),
        }
    }
}

impl From<FaultKind> for Verdict {
    fn from(kind: FaultKind) -> Self {
        match kind {
            FaultKind::OuterRace => Verdict::OuterRace,
            FaultKind::InnerRace => Verdict::InnerRace,
            FaultKind::Ball => Verdict::Ball,
            FaultKind::Cage => Verdict::Cage,
        }
    }
}

/// A verdict, its confidence in [0.5, 1] and the reason in words.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    pub verdict: Verdict,
    /// How far the evidence is from the decision boundary: 0.5 on the boundary, → 1 far from
    /// it (for `none` as much as for a fault).
    pub confidence: f64,
    pub reason: String,
}

/// How far a fault's `score` is from the decision boundary, in log units (positive: a fault),
/// and the confidence that gives, in [0.5, 1]. Both conditions (`score ≥ min_fault_score`,
/// `score ≥ min_score_ratio × runner_up`) must hold, so the weaker one counts.
pub fn score_evidence(
    score: f64,
    runner_up: f64,
    min_fault_score: f64,
    min_score_ratio: f64,
) -> (f64, f64) {
    let ratio = score / runner_up.max(1e-9);
    let evidence = (score.max(1e-9) / min_fault_score)
        .ln()
        .min((ratio / min_score_ratio).ln());
    (evidence, 1.0 - 0.5 * (-2.0 * evidence.abs()).exp())
}

/// Decides from the scores of every fault kind.
pub fn diagnose(scores: &[FaultScore], min_fault_score: f64, min_score_ratio: f64) -> Diagnosis {
    let mut ranked: Vec<&FaultScore> = scores.iter().collect();
    ranked.sort_by(|a, b| b.score.total_cmp(&a.score));
    let Some(best) = ranked.first() else {
        return Diagnosis {
            verdict: Verdict::None,
            confidence: 0.5,
            reason: "no fault frequency could be scored".into(),
        };
    };
    let runner_up = ranked.get(1).map_or(1.0, |s| s.score.max(1e-9));
    let ratio = best.score / runner_up;
    let (evidence, confidence) =
        score_evidence(best.score, runner_up, min_fault_score, min_score_ratio);
    let runner_name = ranked.get(1).map_or("none", |s| s.fault.name());
    if evidence >= 0.0 {
        Diagnosis {
            verdict: best.fault.into(),
            confidence,
            reason: format!(
                "{} score {:.1} ≥ {:.0} and {:.1}× the runner-up ({} {:.1})",
                best.fault.name(),
                best.score,
                min_fault_score,
                ratio,
                runner_name,
                runner_up
            ),
        }
    } else {
        let why = if best.score < min_fault_score {
            format!(
                "best score {} {:.1} < {:.0}",
                best.fault.name(),
                best.score,
                min_fault_score
            )
        } else {
            format!(
                "{} {:.1} is only {:.1}× {} {:.1} (needs {:.1}×)",
                best.fault.name(),
                best.score,
                ratio,
                runner_name,
                runner_up,
                min_score_ratio
            )
        };
        Diagnosis {
            verdict: Verdict::None,
            confidence,
            reason: format!("no clear fault: {why}"),
        }
    }
}
