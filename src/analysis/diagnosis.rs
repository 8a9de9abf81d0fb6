//! The verdict: which fault, if any, the fault-band scores support, and how confidently.
//!
//! One rule for `analyze`, the daemon and `replay` (docs/DIAGNOSIS.md has how its thresholds
//! were chosen). A hypothesis is *detected* when its comb is both
//! - statistically significant: noise alone would give such a comb with probability at most
//!   `false_alarm_rate` (its [`FaultScore::significance`] ≥ `−log10 false_alarm_rate`), and
//! - large enough to matter: its score (geometric-mean peak-to-floor ratio) ≥ `min_fault_score`.
//!   Real machines carry lines no noise model predicts; this floor sits above what healthy
//!   machines and other faults' stray lines reach in the simulator sweep and the dev data.
//!
//! The strongest hypothesis leads; the others are re-scored with its comb explained away. A
//! leader is named when it is detected and no other hypothesis is detected on the evidence the
//! leader does not explain, or the leader is `min_score_ratio` times stronger. Two detected,
//! inseparable hypotheses give `none` with both named: a close call is said, never guessed.

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
    /// With a `none` verdict: the hypotheses that were each detected but could not be told
    /// apart (empty otherwise).
    pub candidates: Vec<FaultKind>,
    pub reason: String,
}

/// The thresholds of the decision (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecisionRule {
    pub false_alarm_rate: f64,
    pub min_fault_score: f64,
    pub min_score_ratio: f64,
}

impl DecisionRule {
    /// Significance (decades) a comb needs.
    pub fn min_significance(&self) -> f64 {
        -self.false_alarm_rate.clamp(1e-300, 1.0).log10()
    }

    /// Whether `score` is significant against noise (the flag's gate; the flag's own
    /// thresholds then act on the score, with hysteresis).
    pub fn significant(&self, score: &FaultScore) -> bool {
        score.significance >= self.min_significance()
    }

    /// Significant and large enough to name.
    pub fn detected(&self, score: &FaultScore) -> bool {
        self.significant(score) && score.score >= self.min_fault_score
    }
}

/// The strongest hypothesis and the strongest of the others once the leader is explained away.
#[derive(Debug, Clone, Copy)]
pub struct Contest<'a> {
    pub leader: &'a FaultScore,
    /// `None` when there is no other hypothesis.
    pub runner_up: Option<&'a FaultScore>,
}

impl<'a> Contest<'a> {
    /// `scores`: every hypothesis; `explained`: the others re-scored with the leader (the
    /// highest score in `scores`) explained away. `None` when nothing was scored.
    pub fn new(scores: &'a [FaultScore], explained: &'a [FaultScore]) -> Option<Self> {
        let leader = scores.iter().max_by(|a, b| a.score.total_cmp(&b.score))?;
        let runner_up = explained
            .iter()
            .filter(|s| s.fault != leader.fault)
            .max_by(|a, b| a.score.total_cmp(&b.score));
        Some(Contest { leader, runner_up })
    }

    /// The leader, when it is significant and separable from every other significant
    /// hypothesis: the fault the daemon's flags follow.
    pub fn lead(&self, rule: &DecisionRule) -> Option<FaultKind> {
        (rule.significant(self.leader) && self.separated(rule)).then_some(self.leader.fault)
    }

    fn runner_up_detected(&self, rule: &DecisionRule) -> bool {
        self.runner_up.is_some_and(|r| rule.detected(r))
    }

    fn ratio(&self) -> f64 {
        self.leader.score / self.runner_up.map_or(1.0, |r| r.score.max(1e-9))
    }

    fn separated(&self, rule: &DecisionRule) -> bool {
        !self.runner_up_detected(rule) || self.ratio() >= rule.min_score_ratio
    }
}

/// How far a fault's `score` is from the decision boundary, in log units (positive: a fault),
/// and the confidence that gives, in [0.5, 1]. Both conditions (`score ≥ min_fault_score`,
/// `score ≥ min_score_ratio × runner_up`) count, so the weaker one counts.
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

/// Decides from the scores of every fault kind (`scores`) and the others' scores with the
/// leader explained away (`explained`; see [`Contest::new`]).
pub fn diagnose(scores: &[FaultScore], explained: &[FaultScore], rule: &DecisionRule) -> Diagnosis {
    let Some(contest) = Contest::new(scores, explained) else {
        return Diagnosis {
            verdict: Verdict::None,
            confidence: 0.5,
            candidates: Vec::new(),
            reason: "no fault frequency could be scored".into(),
        };
    };
    let best = contest.leader;
    let runner = contest.runner_up;
    let runner_score = runner.map_or(1.0, |r| r.score.max(1e-9));
    let runner_text = runner.map_or_else(
        || "no other hypothesis".to_string(),
        |r| {
            format!(
                "{} {:.1} (10^-{:.1}) once {} is explained",
                r.fault.name(),
                r.score,
                r.significance,
                best.fault.name()
            )
        },
    );
    let min_sig = rule.min_significance();
    let size_evidence = (best.score.max(1e-9) / rule.min_fault_score).ln();
    let significance_evidence = (best.significance - min_sig) * std::f64::consts::LN_10;
    let separation_evidence = if contest.runner_up_detected(rule) {
        (contest.ratio() / rule.min_score_ratio).ln()
    } else {
        f64::INFINITY
    };
    let evidence = size_evidence
        .min(significance_evidence)
        .min(separation_evidence);
    let confidence = 1.0 - 0.5 * (-2.0 * evidence.abs()).exp();
    let header = format!(
        "{} score {:.1} (noise would give it with p = 10^-{:.1})",
        best.fault.name(),
        best.score,
        best.significance
    );
    if rule.detected(best) && contest.separated(rule) {
        return Diagnosis {
            verdict: best.fault.into(),
            confidence,
            candidates: Vec::new(),
            reason: format!(
                "{header} ≥ {:.1}, p ≤ {:.0e}; runner-up {runner_text}",
                rule.min_fault_score, rule.false_alarm_rate
            ),
        };
    }
    let (candidates, why) = if !rule.detected(best) {
        let what = if !rule.significant(best) {
            format!("not significant (needs p ≤ {:.0e})", rule.false_alarm_rate)
        } else {
            format!("below {:.1}", rule.min_fault_score)
        };
        (Vec::new(), format!("{header} is {what}"))
    } else {
        let other = runner.map(|r| r.fault).into_iter();
        (
            std::iter::once(best.fault).chain(other).collect(),
            format!(
                "{header} and {runner_text} are both detected and only {:.1}× apart (needs {:.1}×): either fault",
                best.score / runner_score,
                rule.min_score_ratio
            ),
        )
    };
    Diagnosis {
        verdict: Verdict::None,
        confidence,
        candidates,
        reason: format!("no clear fault: {why}"),
    }
}
