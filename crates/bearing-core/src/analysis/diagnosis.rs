//! The verdict: which fault, if any, the fault-band scores support, and how confidently.
//!
//! One rule for `analyze`, the daemon and `replay` (docs/DIAGNOSIS.md has how its thresholds
//! were chosen). A hypothesis is *detected* when its comb is both
//! - statistically significant: noise alone would give such a comb with probability at most
//!   `false_alarm_rate` (its [`FaultScore::significance`] ≥ `−log10 false_alarm_rate`), and
//! - large enough to matter: its score (geometric-mean peak-to-floor ratio) ≥ `min_fault_score`.
//!   Real machines carry lines no noise model predicts; this floor sits above what healthy
//!   machines and other faults' stray lines reach in the simulator sweep and the dev data.
//!   Those lines lift several combs at once (a cluttered spectrum scores 2–4 for two or three
//!   faults), so a weaker comb is also *detected* when it stands alone: score ≥
//!   `lone_fault_score`, ≥ `lone_score_ratio` × every other hypothesis once it is explained away,
//!   significant at the square of the false-alarm rate (a weaker comb needs stronger proof
//!   that it is not noise), and every harmonic but one standing clear of the floor.
//!
//! The strongest hypothesis leads; the others are re-scored with its comb explained away. A
//! leader is named when it is detected and no other hypothesis is detected on the evidence the
//! leader does not explain, or the leader is `min_score_ratio` times stronger. Two detected,
//! inseparable hypotheses give `none` with both named: a close call is said, never guessed.
//! A third way of naming, a weaker leader a second witness (the learned model) names too
//! ([`Named::Agreed`]), is decided after this rule, by [`super::agreement::decide`].

use super::fault_bands::FaultScore;
use super::rolling_element::{ball_or_inner, rival_leads};
use crate::messages::FaultKind;
use serde::Serialize;

/// What the analysis concludes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    None,
    OuterRace,
    InnerRace,
    Ball,
    Cage,
    /// A damaged rolling element or a damaged cage, and the evidence cannot say which: the cage
    /// comb stands, and the ball comb is significant beside it (a damaged ball, carried by the
    /// cage through the load zone once per cage turn, makes a cage comb of its own, often the
    /// taller one).
    BallOrCage,
    /// A damaged rolling element or an inner-race defect, and the evidence cannot say which:
    /// both combs sit on the same lines and their sidebands point to neither, or each shows its
    /// own pattern ([`super::rolling_element`]).
    BallOrInner,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::None => "none",
            Verdict::OuterRace => "outer_race",
            Verdict::InnerRace => "inner_race",
            Verdict::Ball => "ball",
            Verdict::Cage => "cage",
            Verdict::BallOrCage => "ball_or_cage",
            Verdict::BallOrInner => "ball_or_inner",
        }
    }

    /// The one fault the verdict names (`None` for none, and for a verdict naming two).
    pub fn fault(self) -> Option<FaultKind> {
        match self.faults() {
            [one] => Some(*one),
            _ => None,
        }
    }

    /// Every fault the verdict names: none, one, or the two it cannot tell apart.
    pub fn faults(self) -> &'static [FaultKind] {
        match self {
            Verdict::None => &[],
            Verdict::OuterRace => &[FaultKind::OuterRace],
            Verdict::InnerRace => &[FaultKind::InnerRace],
            Verdict::Ball => &[FaultKind::Ball],
            Verdict::Cage => &[FaultKind::Cage],
            Verdict::BallOrCage => &[FaultKind::Ball, FaultKind::Cage],
            Verdict::BallOrInner => &[FaultKind::InnerRace, FaultKind::Ball],
        }
    }

    /// The verdicts that name two faults they cannot tell apart.
    pub const PAIRS: [Verdict; 2] = [Verdict::BallOrCage, Verdict::BallOrInner];
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
    /// How the verdict's fault was named (`None` with a `none` verdict).
    #[serde(skip)]
    pub named: Option<Named>,
}

/// The thresholds of the decision (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecisionRule {
    pub false_alarm_rate: f64,
    pub min_fault_score: f64,
    pub min_score_ratio: f64,
    pub lone_fault_score: f64,
    pub lone_score_ratio: f64,
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

    /// Significant at `false_alarm_rate²`: the stronger proof a weaker comb needs.
    fn strongly_significant(&self, score: &FaultScore) -> bool {
        score.significance >= 2.0 * self.min_significance()
    }

    /// Significant and large enough to name whatever else the spectrum holds.
    pub fn detected(&self, score: &FaultScore) -> bool {
        self.significant(score) && score.score >= self.min_fault_score
    }

    /// How near `score` comes to being named on its own size and significance, in log units
    /// (positive: it would be, were no other fault near it): the larger of the two ways of
    /// naming, each the smaller of its size margin and its significance margin. What a fault's
    /// scoring band is chosen by ([`super::band_search`]).
    pub fn naming_margin(&self, score: &FaultScore) -> f64 {
        let decades = |needed: f64| (score.significance - needed) * std::f64::consts::LN_10;
        let size = |needed: f64| (score.score.max(1e-9) / needed).ln();
        let by_size = size(self.min_fault_score).min(decades(self.min_significance()));
        let alone = size(self.lone_fault_score).min(decades(2.0 * self.min_significance()));
        by_size.max(alone)
    }

    /// Large enough to name when it stands alone (`runner_up`: the strongest other hypothesis
    /// once this one is explained away, 1 for none).
    fn detected_alone(&self, score: &FaultScore, runner_up: f64) -> bool {
        self.strongly_significant(score)
            && score.score >= self.lone_fault_score
            && score.score >= self.lone_score_ratio * runner_up.max(1.0)
            && score.harmonics_stand(LONE_HARMONIC_RATIO)
    }
}

/// (choice) A comb named because it stands alone (or with the learned model's agreement) has
/// every harmonic but one at least this many times its floor: on the simulator's machine (gear
/// mesh, 100 Hz tone, shaft harmonics) the stray combs of healthy records at 0.6× speed reach
/// 2–3 with two tall lines and three at the floor, while the weakest faults it should name show
/// 2.7–3.8 on all five.
pub const LONE_HARMONIC_RATIO: f64 = 2.0;

/// How the leader of a [`Contest`] was named.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Named {
    /// Its comb is large enough whatever else the spectrum holds ([`DecisionRule::detected`]).
    BySize,
    /// A weaker comb with nothing near it (`lone_fault_score`, `lone_score_ratio`).
    Alone,
    /// A weaker comb, clear of the runner-up, that the learned model names too: the network
    /// stands in for the comb's size and part of its significance, never for its separation
    /// ([`super::agreement::decide`]; [`diagnose`] never gives it). A probable fault at most.
    Agreed,
}

/// The strongest hypothesis and the strongest of the others once the leader is explained away.
#[derive(Debug, Clone, Copy)]
pub struct Contest<'a> {
    pub leader: &'a FaultScore,
    /// `None` when there is no other hypothesis.
    pub runner_up: Option<&'a FaultScore>,
}

impl<'a> Contest<'a> {
    /// `scores`: every hypothesis; `explained`: the others re-scored with the leader (see
    /// [`leader`]) explained away. `None` when nothing was scored.
    pub fn new(
        scores: &'a [FaultScore],
        explained: &'a [FaultScore],
        rule: &DecisionRule,
    ) -> Option<Self> {
        let leader = leader(scores, rule)?;
        let runner_up = explained
            .iter()
            .filter(|s| s.fault != leader.fault)
            .max_by(|a, b| a.score.total_cmp(&b.score));
        Some(Contest { leader, runner_up })
    }

    /// How the leader is named, if it is.
    pub fn named(&self, rule: &DecisionRule) -> Option<Named> {
        if rule.detected(self.leader) && self.separated(rule) {
            Some(Named::BySize)
        } else if rule.detected_alone(self.leader, self.runner_up_score()) {
            Some(Named::Alone)
        } else {
            None
        }
    }

    fn runner_up_score(&self) -> f64 {
        self.runner_up.map_or(1.0, |r| r.score)
    }

    fn runner_up_detected(&self, rule: &DecisionRule) -> bool {
        self.runner_up.is_some_and(|r| rule.detected(r))
    }

    fn ratio(&self) -> f64 {
        self.leader.score / self.runner_up_score().max(1e-9)
    }

    fn separated(&self, rule: &DecisionRule) -> bool {
        !self.runner_up_detected(rule) || self.ratio() >= rule.min_score_ratio
    }
}

/// The hypothesis that leads: the highest score, except that a cage comb gives way to an
/// outer-race or ball comb that is significant and at least `lone_fault_score`, or however
/// small, significant at `false_alarm_rate²`. Both faults make a cage comb of their own (an
/// outer-race defect is met by balls the cage carries; a damaged ball is carried through the
/// load zone once per cage turn, so its impacts swell and fade at FTF), often a taller one than
/// their own, and it outlasts their own comb in noise; a damaged cage makes no race or ball
/// comb. And an inner-race or ball comb gives way to its rival when the two share their lines
/// and the sidebands speak for the rival ([`rival_leads`]).
pub fn leader<'a>(scores: &'a [FaultScore], rule: &DecisionRule) -> Option<&'a FaultScore> {
    let top = scores.iter().max_by(|a, b| a.score.total_cmp(&b.score))?;
    if top.fault != FaultKind::Cage {
        return Some(rival_leads(top, scores).unwrap_or(top));
    }
    let cause = scores
        .iter()
        .filter(|s| matches!(s.fault, FaultKind::OuterRace | FaultKind::Ball))
        .filter(|s| {
            (rule.significant(s) && s.score >= rule.lone_fault_score)
                || rule.strongly_significant(s)
        })
        .max_by(|a, b| a.score.total_cmp(&b.score));
    Some(cause.unwrap_or(top))
}

/// The ball hypothesis, when its comb shows beside the cage's: beyond noise at ten times the
/// false-alarm rate and at least [`BALL_BEHIND_CAGE_SCORE`]. Then a cage comb may be the damaged
/// ball's own cage-rate modulation (see [`Verdict::BallOrCage`]).
///
/// (choice) Ten times looser than naming: what is asked is not whether the ball is damaged but
/// whether the cage can be named alone, and a cage named when the ball shows a sign of its own
/// is the confident wrong answer a damaged ball gave.
fn ball_behind_cage<'a>(scores: &'a [FaultScore], rule: &DecisionRule) -> Option<&'a FaultScore> {
    let needed = rule.min_significance() - 1.0;
    scores
        .iter()
        .find(|s| s.fault == FaultKind::Ball)
        .filter(|ball| ball.significance >= needed && ball.score >= BALL_BEHIND_CAGE_SCORE)
}

/// (choice, on the simulator sweep) The ball comb a damaged ball shows beside the taller cage
/// comb it makes is 2.3–2.8 even buried in noise (−10 dB); a damaged cage's own record shows a
/// ball comb of 1.1–1.4, often beyond noise at p ≤ 10^-2 (the cage's knocks and rubbing modulate
/// everything at FTF, the ball comb's sideband spacing). 1.8 lies between them (their geometric
/// middle).
const BALL_BEHIND_CAGE_SCORE: f64 = 1.8;

/// Why a rolling-element pair cannot be told apart, in a few words.
fn pair_words(leader: &FaultScore, rival: &FaultScore) -> String {
    let z = |s: &FaultScore| s.modulation.map_or(0.0, |m| m.contrast_z);
    if super::rolling_element::shared_combs(leader, rival) {
        format!(
            "both combs sit on the same lines and their sidebands point to neither (contrast \
             {:+.1})",
            z(leader)
        )
    } else {
        format!(
            "each shows its own sidebands ({} contrast {:+.1})",
            rival.fault.name(),
            z(rival)
        )
    }
}

/// How far a fault's `score` is from the decision boundary on scores alone (the alert's view:
/// its significance was checked when its flag rose), in log units (positive: a fault), and the
/// confidence that gives, in [0.5, 1]. Either way of naming counts (large enough and
/// `min_score_ratio` × the runner-up, or alone: `lone_fault_score` and `lone_score_ratio` ×);
/// within each, the weaker condition counts.
pub fn score_evidence(score: f64, runner_up: f64, rule: &DecisionRule) -> (f64, f64) {
    let ratio = score / runner_up.max(1e-9);
    let by_size = (score.max(1e-9) / rule.min_fault_score)
        .ln()
        .min((ratio / rule.min_score_ratio).ln());
    let alone = (score.max(1e-9) / rule.lone_fault_score)
        .ln()
        .min((score / runner_up.max(1.0) / rule.lone_score_ratio).ln());
    let evidence = by_size.max(alone);
    (evidence, 1.0 - 0.5 * (-2.0 * evidence.abs()).exp())
}

/// Decides from the scores of every fault kind (`scores`) and the others' scores with the
/// leader explained away (`explained`; see [`Contest::new`]).
pub fn diagnose(scores: &[FaultScore], explained: &[FaultScore], rule: &DecisionRule) -> Diagnosis {
    let Some(contest) = Contest::new(scores, explained, rule) else {
        return Diagnosis {
            verdict: Verdict::None,
            confidence: 0.5,
            candidates: Vec::new(),
            reason: "no fault frequency could be scored".into(),
            named: None,
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
    let by_size = size_evidence
        .min(significance_evidence)
        .min(separation_evidence);
    let alone_ratio = best.score / runner_score.max(1.0);
    let alone = (best.score.max(1e-9) / rule.lone_fault_score)
        .ln()
        .min((alone_ratio / rule.lone_score_ratio).ln())
        .min((best.significance - 2.0 * min_sig) * std::f64::consts::LN_10);
    // Either way of naming suffices: the evidence is the better of the two.
    let evidence = by_size.max(alone);
    let confidence = 1.0 - 0.5 * (-2.0 * evidence.abs()).exp();
    let header = format!(
        "{} score {:.1} (noise would give it with p = 10^-{:.1})",
        best.fault.name(),
        best.score,
        best.significance
    );
    let named = contest.named(rule);
    if named.is_some() && best.fault == FaultKind::Cage {
        if let Some(ball) = ball_behind_cage(scores, rule) {
            return Diagnosis {
                verdict: Verdict::BallOrCage,
                confidence,
                candidates: vec![FaultKind::Ball, FaultKind::Cage],
                reason: format!(
                    "{header} stands, but the ball comb is significant beside it ({:.1}, p = \
                     10^-{:.1}): a damaged ball makes a cage comb too, so a rolling element or \
                     the cage",
                    ball.score, ball.significance
                ),
                named,
            };
        }
    }
    if named.is_some() {
        if let Some(rival) = ball_or_inner(best, scores, |s| rule.detected(s)) {
            return Diagnosis {
                verdict: Verdict::BallOrInner,
                confidence,
                candidates: Verdict::BallOrInner.faults().to_vec(),
                reason: format!(
                    "{header} stands, but it cannot be told from the {} comb ({:.1}, p = \
                     10^-{:.1}): {}, so a rolling element or the inner race",
                    rival.fault.name(),
                    rival.score,
                    rival.significance,
                    pair_words(best, rival)
                ),
                named,
            };
        }
    }
    match named {
        Some(Named::BySize) => {
            return Diagnosis {
                verdict: best.fault.into(),
                confidence,
                candidates: Vec::new(),
                reason: format!(
                    "{header} ≥ {:.1}, p ≤ {:.0e}; runner-up {runner_text}",
                    rule.min_fault_score, rule.false_alarm_rate
                ),
                named: Some(Named::BySize),
            }
        }
        Some(Named::Alone) => {
            return Diagnosis {
                verdict: best.fault.into(),
                confidence,
                candidates: Vec::new(),
                reason: format!(
                    "{header} stands alone: ≥ {:.1}, {alone_ratio:.1}× the runner-up {runner_text} \
                     (needs {:.1}×), p ≤ {:.0e}",
                    rule.lone_fault_score,
                    rule.lone_score_ratio,
                    rule.false_alarm_rate * rule.false_alarm_rate
                ),
                named: Some(Named::Alone),
            }
        }
        // Only the learned combination names by agreement.
        Some(Named::Agreed) | None => {}
    }
    let (candidates, why) = if !rule.detected(best) {
        let what = if !rule.significant(best) {
            format!("not significant (needs p ≤ {:.0e})", rule.false_alarm_rate)
        } else {
            format!(
                "below {:.1} and not alone ({alone_ratio:.1}× the runner-up; alone needs ≥ {:.1} \
                 and {:.1}×)",
                rule.min_fault_score, rule.lone_fault_score, rule.lone_score_ratio
            )
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
        named: None,
    }
}

/// Also the fixtures of the agreement's tests (`super::agreement`).
#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::analysis::AnalysisSettings;
    use crate::bearing::BearingGeometry;

    pub(crate) fn rule() -> DecisionRule {
        AnalysisSettings::default().decision_rule()
    }

    /// Scores in [`FaultKind::ALL`] order: (score, significance) each, every harmonic at the
    /// score (a consistent comb).
    pub(crate) fn scores(values: [(f64, f64); 4]) -> Vec<FaultScore> {
        let freqs = BearingGeometry::from_catalog("skf-6205-2rs")
            .expect("a catalog bearing")
            .fault_frequencies(29.5);
        FaultKind::ALL
            .iter()
            .zip(values)
            .map(|(&kind, (score, significance))| {
                let mut s = FaultScore::unscored(kind, &freqs).with_harmonic_ratios(&[score; 5]);
                s.score = score;
                s.significance = significance;
                s
            })
            .collect()
    }

    /// The others as `explained` (the test's leader explains nothing of theirs).
    fn verdict(values: [(f64, f64); 4]) -> Diagnosis {
        let all = scores(values);
        let rule = rule();
        let top = leader(&all, &rule).expect("scored").fault;
        let explained: Vec<FaultScore> = all.iter().filter(|s| s.fault != top).copied().collect();
        diagnose(&all, &explained, &rule)
    }

    #[test]
    fn a_large_significant_comb_is_named() {
        let d = verdict([(1.5, 0.5), (8.0, 20.0), (2.0, 1.0), (1.4, 0.2)]);
        assert_eq!(d.verdict, Verdict::InnerRace, "{}", d.reason);
        assert!(d.confidence > 0.6);
    }

    #[test]
    fn a_weaker_comb_is_named_when_it_stands_alone_and_not_in_clutter() {
        // Alone: 3.5, 2.3× the next, p = 10^-30.
        let d = verdict([(1.5, 0.5), (3.5, 30.0), (1.4, 1.0), (1.3, 0.2)]);
        assert_eq!(d.verdict, Verdict::InnerRace, "{}", d.reason);
        assert!(d.reason.contains("stands alone"), "{}", d.reason);
        // The same comb beside another comb at 2.6 (a machine's lines): no.
        let d = verdict([(2.6, 4.0), (3.5, 30.0), (1.4, 1.0), (1.3, 0.2)]);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // Alone but barely beyond noise (p = 10^-4 < the 10^-6 a weak comb needs): no.
        let d = verdict([(1.2, 0.5), (3.5, 4.0), (1.2, 1.0), (1.1, 0.2)]);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // Below the lone floor: no.
        let d = verdict([(1.0, 0.0), (2.4, 30.0), (1.0, 0.0), (1.0, 0.0)]);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
    }

    #[test]
    fn a_lone_comb_of_two_tall_lines_is_a_machines_not_a_fault() {
        let freqs = BearingGeometry::from_catalog("skf-6205-2rs")
            .expect("a catalog bearing")
            .fault_frequencies(29.5);
        let mut all = scores([(3.4, 30.0), (1.4, 1.0), (1.3, 1.0), (1.2, 0.2)]);
        let consistent = verdict([(3.4, 30.0), (1.4, 1.0), (1.3, 1.0), (1.2, 0.2)]);
        assert_eq!(
            consistent.verdict,
            Verdict::OuterRace,
            "{}",
            consistent.reason
        );
        let mut tones = FaultScore::unscored(FaultKind::OuterRace, &freqs)
            .with_harmonic_ratios(&[8.0, 1.0, 1.1, 1.2, 9.0]);
        tones.score = 3.4;
        tones.significance = 30.0;
        all[0] = tones;
        let explained: Vec<FaultScore> = all[1..].to_vec();
        let d = diagnose(&all, &explained, &rule());
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
    }

    #[test]
    fn a_cage_comb_gives_way_to_the_ball_or_race_comb_that_makes_it() {
        // A damaged ball: its cage comb is taller than its own.
        let all = scores([(1.5, 0.5), (2.0, 1.0), (4.6, 40.0), (6.5, 20.0)]);
        assert_eq!(
            leader(&all, &rule()).map(|l| l.fault),
            Some(FaultKind::Ball)
        );
        // A damaged cage: nothing else significant, the cage leads.
        let all = scores([(1.5, 0.5), (1.3, 1.0), (1.2, 0.4), (7.9, 20.0)]);
        assert_eq!(
            leader(&all, &rule()).map(|l| l.fault),
            Some(FaultKind::Cage)
        );
        let d = verdict([(1.5, 0.5), (1.3, 1.0), (1.2, 0.4), (7.9, 20.0)]);
        assert_eq!(d.verdict, Verdict::Cage, "{}", d.reason);
        // A ball buried in noise: its own comb small but far beyond noise, its cage comb tall.
        // The ball leads and, too small to name, gives none; never "cage".
        let all = scores([(1.3, 0.5), (1.6, 11.0), (2.5, 26.0), (4.9, 23.0)]);
        assert_eq!(
            leader(&all, &rule()).map(|l| l.fault),
            Some(FaultKind::Ball)
        );
        let d = verdict([(1.3, 0.5), (1.6, 11.0), (2.5, 26.0), (4.9, 23.0)]);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // A significant but small ball comb does not take the lead from a cage.
        let all = scores([(1.5, 0.5), (1.3, 1.0), (2.2, 4.0), (7.9, 20.0)]);
        assert_eq!(
            leader(&all, &rule()).map(|l| l.fault),
            Some(FaultKind::Cage)
        );
    }

    #[test]
    fn a_cage_comb_with_the_ball_showing_beside_it_is_a_rolling_element_or_the_cage() {
        // A lone cage comb with nothing else: the cage.
        let d = verdict([(1.5, 0.5), (1.3, 1.0), (1.2, 0.4), (7.9, 20.0)]);
        assert_eq!(d.verdict, Verdict::Cage, "{}", d.reason);
        // A ball comb at the floor's level but beyond noise (what a damaged cage's knocks
        // make of it): still the cage.
        let d = verdict([(1.5, 0.5), (1.3, 1.0), (1.3, 2.5), (7.9, 20.0)]);
        assert_eq!(d.verdict, Verdict::Cage, "{}", d.reason);
        // A ball comb of its own beside it (2.0, p = 10^-2.5): either.
        let d = verdict([(1.5, 0.5), (1.3, 1.0), (2.0, 2.5), (7.9, 20.0)]);
        assert_eq!(d.verdict, Verdict::BallOrCage, "{}", d.reason);
        assert_eq!(d.candidates, vec![FaultKind::Ball, FaultKind::Cage]);
        assert_eq!(d.verdict.faults(), &[FaultKind::Ball, FaultKind::Cage]);
        assert_eq!(d.verdict.fault(), None);
    }

    /// Inner race and ball at (score, significance, contrast z), found at `inner_hz` and
    /// `ball_hz` (× k, 1 Hz bins); outer race and cage small. The diagnosis, with the others as
    /// `explained` (the ball at `explained_ball` once the leader is explained: what shared lines
    /// leave of it).
    fn pair_verdict(
        inner: (f64, f64, f64),
        ball: (f64, f64, f64),
        (inner_hz, ball_hz): (f64, f64),
        explained_ball: f64,
    ) -> Diagnosis {
        let mut all = scores([(1.2, 0.5), (inner.0, inner.1), (ball.0, ball.1), (1.1, 0.2)]);
        for (s, (z, hz)) in all[1..3]
            .iter_mut()
            .zip([(inner.2, inner_hz), (ball.2, ball_hz)])
        {
            let found: Vec<f64> = (1..=5).map(|k| k as f64 * hz).collect();
            *s = s.with_found_peaks(1.0, &found);
            s.modulation = Some(crate::analysis::modulation::Modulation {
                own: 1.0,
                other: 1.0,
                contrast_z: z,
            });
        }
        let rule = rule();
        let top = leader(&all, &rule).expect("scored").fault;
        let explained: Vec<FaultScore> = all
            .iter()
            .filter(|s| s.fault != top)
            .map(|s| {
                let mut s = *s;
                if matches!(s.fault, FaultKind::InnerRace | FaultKind::Ball) {
                    s.score = s.score.min(explained_ball);
                }
                s
            })
            .collect();
        diagnose(&all, &explained, &rule)
    }

    #[test]
    fn a_61804_tie_is_a_rolling_element_or_the_inner_race_never_a_coin_toss() {
        // Shared lines, no sidebands either way (a uniform load): explaining the taller comb
        // away leaves the other nothing, yet the two cannot be told apart.
        let d = pair_verdict((5.4, 20.0, 0.4), (5.3, 20.0, -0.4), (221.0, 221.0), 1.0);
        assert_eq!(d.verdict, Verdict::BallOrInner, "{}", d.reason);
        assert_eq!(d.verdict.faults(), &[FaultKind::InnerRace, FaultKind::Ball]);
        assert_eq!(d.verdict.fault(), None);
        assert_eq!(d.verdict.name(), "ball_or_inner");
        // Cage-rate sidebands on the shared lines: the ball leads and is named.
        let d = pair_verdict((5.4, 20.0, -2.5), (5.3, 20.0, 2.5), (221.0, 221.0), 1.0);
        assert_eq!(d.verdict, Verdict::Ball, "{}", d.reason);
        // Shaft-rate sidebands: the inner race.
        let d = pair_verdict((5.4, 20.0, 2.5), (5.3, 20.0, -2.5), (221.0, 221.0), 1.0);
        assert_eq!(d.verdict, Verdict::InnerRace, "{}", d.reason);
    }

    #[test]
    fn apart_combs_are_either_only_when_both_patterns_show_and_none_stays_none() {
        // 105-like: a tall inner comb, the ball comb it feeds shows no cage-rate pattern.
        let d = pair_verdict((15.0, 14.7, 1.3), (4.9, 6.4, 0.1), (162.0, 141.0), 1.5);
        assert_eq!(d.verdict, Verdict::InnerRace, "{}", d.reason);
        // A detected ball comb with cage-rate sidebands of its own beside it: either.
        let d = pair_verdict((20.0, 30.0, 1.0), (6.0, 6.0, 3.5), (162.0, 141.0), 1.5);
        assert_eq!(d.verdict, Verdict::BallOrInner, "{}", d.reason);
        assert!(d.reason.contains("own sidebands"), "{}", d.reason);
        // A leader not named stays none whatever its rival shows.
        let d = pair_verdict((2.0, 2.5, 1.0), (1.9, 2.5, 3.5), (162.0, 141.0), 1.5);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // A damaged ball on a 6205 at 0.6× speed: the machine's shaft-modulated nuisance makes
        // an inner comb of 2.9 with shaft-rate sidebands beside it; the ball stands.
        let d = pair_verdict((2.9, 6.0, 6.0), (13.0, 20.0, 1.0), (162.0, 141.0), 1.5);
        assert_eq!(d.verdict, Verdict::Ball, "{}", d.reason);
        let d = pair_verdict((2.0, 2.5, 1.0), (1.9, 2.5, 3.5), (162.0, 141.0), 1.5);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // 224-like: never the ball, never the pair.
        let d = pair_verdict((4.3, 19.1, 3.7), (2.3, 3.2, 0.2), (162.0, 141.0), 1.5);
        assert!(
            !matches!(d.verdict, Verdict::Ball | Verdict::BallOrInner),
            "{}",
            d.reason
        );
    }

    #[test]
    fn two_detected_combs_close_together_give_none_with_both_named() {
        let d = verdict([(6.0, 10.0), (7.0, 12.0), (1.4, 1.0), (1.3, 0.2)]);
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        assert_eq!(
            d.candidates,
            vec![FaultKind::InnerRace, FaultKind::OuterRace]
        );
    }

    #[test]
    fn the_alert_confidence_counts_either_way_of_naming() {
        let rule = rule();
        let (alone, _) = score_evidence(3.5, 1.4, &rule);
        assert!(
            alone > 0.0,
            "a lone comb at 3.5 is on the fault side: {alone}"
        );
        let (cluttered, _) = score_evidence(3.5, 2.6, &rule);
        assert!(cluttered < 0.0, "{cluttered}");
        let (large, _) = score_evidence(9.0, 2.6, &rule);
        assert!(large > 0.0, "{large}");
    }
}
