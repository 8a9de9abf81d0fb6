//! The verdict in a technician's words: one line that says what is wrong, how sure the analysis
//! is and what to do, ahead of the numbers the engineer reads; and, per fault, why it was not
//! named.
//!
//! Why a module of its own: the decision rule reasons in combs, p-values and ratios, and its
//! `reason` text says so; a technician needs "outer race, clear, plan an inspection". The words
//! come only from the report's structured fields (verdict, confidence, candidates, each fault's
//! score and significance and what is left of it once the leader is explained away, the
//! thresholds, the learned model's basis), never from the `reason` text, so rewording the rule
//! cannot garble them. A new verdict is worded in one place: `named_by`.

use super::HypothesisReport;
use crate::analysis::diagnosis::{DecisionRule, Verdict};
use crate::learned::Basis;
use crate::messages::{FaultKind, FlagLevel};

/// What the plain words are made from: the report's structured fields.
#[derive(Debug, Clone, Copy)]
pub struct Facts<'a> {
    pub verdict: Verdict,
    /// The verdict's confidence in [0.5, 1] (0.5 on the decision boundary).
    pub confidence: f64,
    /// With `none`: the faults each detected but not told apart.
    pub candidates: &'a [FaultKind],
    pub hypotheses: &'a [HypothesisReport],
    pub rule: DecisionRule,
    /// The learned model's part, when it gave an opinion.
    pub learned: Option<LearnedFacts>,
    /// The fault the signal-model twin fits best, when it is not the named one.
    pub twin_prefers: Option<FaultKind>,
}

/// The learned model's part of the verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LearnedFacts {
    pub basis: Basis,
    /// Whether its most probable class is the verdict.
    pub agrees: bool,
}

/// The faults a verdict names, and how the line calls them.
struct Named {
    what: &'static str,
    faults: Vec<FaultKind>,
}

impl Named {
    fn one(kind: FaultKind) -> Self {
        Named {
            what: fault_words(kind),
            faults: vec![kind],
        }
    }
}

/// What a verdict names: the one place a new verdict is worded.
fn named_by(verdict: Verdict) -> Option<Named> {
    match verdict {
        Verdict::None => None,
        Verdict::OuterRace => Some(Named::one(FaultKind::OuterRace)),
        Verdict::InnerRace => Some(Named::one(FaultKind::InnerRace)),
        Verdict::Ball => Some(Named::one(FaultKind::Ball)),
        Verdict::Cage => Some(Named::one(FaultKind::Cage)),
        Verdict::BallOrCage => Some(Named {
            what: "rolling element (ball) or cage",
            faults: verdict.faults().to_vec(),
        }),
        Verdict::BallOrInner => Some(Named {
            what: "rolling element (ball) or inner race",
            faults: verdict.faults().to_vec(),
        }),
    }
}

/// A fault in the technician's words.
pub fn fault_words(kind: FaultKind) -> &'static str {
    match kind {
        FaultKind::OuterRace => "outer race",
        FaultKind::InnerRace => "inner race",
        FaultKind::Ball => "rolling element (ball)",
        FaultKind::Cage => "cage",
    }
}

/// How sure a verdict is, in words ("borderline" rather than "weak": "a weak inner race
/// defect" would read as a small one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Sureness {
    Weak,
    Probable,
    Clear,
}

impl Sureness {
    /// (choice) The confidence is `1 − ½·exp(−2e)`, where `e` is the log factor by which the
    /// weakest condition of the decision is cleared (or, for `none`, missed). 0.9 is `e` = 0.8:
    /// cleared 2.2 times over (a score of 11 where 5 is needed, 3.3× the runner-up where 1.5×
    /// is), which another measurement will hardly undo: clear. 0.7 is `e` = 0.26: cleared by
    /// 30 %: probable. Below, the evidence sits within a few tenths of the line and the next
    /// record may fall on the other side: weak.
    fn of(confidence: f64) -> Self {
        if confidence >= 0.9 {
            Sureness::Clear
        } else if confidence >= 0.7 {
            Sureness::Probable
        } else {
            Sureness::Weak
        }
    }

    fn word(self) -> &'static str {
        match self {
            Sureness::Clear => "clear",
            Sureness::Probable => "probable",
            Sureness::Weak => "borderline",
        }
    }
}

/// (choice) How likely noise alone is to give a comb, at the rule's own two levels: the
/// false-alarm rate every named fault must meet, and its square, the proof a lone comb needs.
fn noise_words(significance: f64, rule: &DecisionRule) -> &'static str {
    if significance >= 2.0 * rule.min_significance() {
        "very unlikely to be noise"
    } else if significant(significance, rule) {
        "unlikely to be noise"
    } else {
        "could be noise"
    }
}

/// The rule's significance test on a bare significance (`−log10 p`).
fn significant(significance: f64, rule: &DecisionRule) -> bool {
    significance >= rule.min_significance()
}

/// What to do about a named fault.
fn fault_action(sure: Sureness) -> &'static str {
    match sure {
        Sureness::Clear => "Plan an inspection.",
        Sureness::Probable => "Watch it: analyse again within a week.",
        Sureness::Weak => "Measure again soon to confirm it.",
    }
}

/// What to do when no fault is named: the closer a fault came, the sooner to look again.
fn none_action(sure: Sureness) -> &'static str {
    match sure {
        Sureness::Clear => "Nothing to do.",
        Sureness::Probable => "Nothing to do now; measure again at the next routine check.",
        Sureness::Weak => "Watch it: analyse again within a week.",
    }
}

/// The plain line: what is wrong, how sure, what to do.
pub fn summary(f: &Facts) -> String {
    match named_by(f.verdict) {
        Some(named) => fault_line(f, &named),
        None => no_fault_line(f),
    }
}

fn fault_line(f: &Facts, named: &Named) -> String {
    let evidence = f
        .hypotheses
        .iter()
        .filter(|h| named.faults.contains(&h.fault))
        .max_by(|a, b| a.score.total_cmp(&b.score));
    let mut notes: Vec<String> = evidence
        .map(|h| noise_words(h.significance, &f.rule).to_string())
        .into_iter()
        .collect();
    let mut sure = Sureness::of(f.confidence);
    match f.learned {
        Some(LearnedFacts {
            basis: Basis::Agreement,
            ..
        }) => {
            // The spectrum alone did not name it, and the confidence is that of its `none`:
            // probable, whatever that says.
            sure = Sureness::Probable;
            notes.push(
                "the spectrum alone does not settle it; the learned model confirms it".into(),
            );
        }
        Some(LearnedFacts { agrees: false, .. }) => {
            notes.push("the learned model disagrees".into())
        }
        _ => {}
    }
    if let Some(other) = f.twin_prefers {
        notes.push(format!(
            "the signal-model twin fits the {} better",
            fault_words(other)
        ));
    }
    let notes = if notes.is_empty() {
        String::new()
    } else {
        format!(" ({})", notes.join("; "))
    };
    format!(
        "{} defect, {}{notes}. {}",
        capitalized(named.what),
        sure.word(),
        fault_action(sure)
    )
}

fn no_fault_line(f: &Facts) -> String {
    if !f.candidates.is_empty() {
        return format!(
            "No clear fault: {} both show, and cannot be told apart. Check the spectrum; measure again.",
            and_list(f.candidates)
        );
    }
    let Some(leader) = leader(f) else {
        return "No verdict: the fault frequencies could not be scored. Check the speed and the sample rate.".into();
    };
    let sure = Sureness::of(f.confidence);
    let rule = &f.rule;
    let opening = if sure == Sureness::Weak {
        "No bearing fault named, but one comes close"
    } else {
        "No bearing fault found"
    };
    let needs = times(rule.min_fault_score);
    // The sign to speak of: the leader when it is more than noise, else the strongest that is.
    let sign = Some(leader)
        .filter(|l| significant(l.significance, rule))
        .or_else(|| {
            f.hypotheses
                .iter()
                .filter(|h| significant(h.significance, rule))
                .max_by(|a, b| a.score.total_cmp(&b.score))
        });
    let detail = match sign {
        None => format!(
            "{opening}: nothing stands out from the noise (strongest sign: {}, {} the floor, \
             which noise can give; a fault needs {needs} and to stand clearly above noise).",
            fault_words(leader.fault),
            times(leader.score)
        ),
        Some(sign) => {
            let which = if sign.fault == leader.fault {
                "strongest"
            } else {
                "clearest"
            };
            let otherwise = if sign.score < rule.lone_fault_score {
                format!(" ({} standing alone)", times(rule.lone_fault_score))
            } else {
                format!(
                    ", or to stand alone ({} every other sign, far beyond noise),",
                    times(rule.lone_score_ratio)
                )
            };
            format!(
                "{opening}. The {which} sign, {}, stands {} above the floor but would need \
                 {needs}{otherwise} to be named.",
                fault_words(sign.fault),
                times(sign.score)
            )
        }
    };
    format!("{detail} {}", none_action(sure))
}

/// The hypothesis that led the contest: the one the others were explained by.
fn leader<'a>(f: &Facts<'a>) -> Option<&'a HypothesisReport> {
    let by = f.hypotheses.iter().find_map(|h| h.explained.map(|e| e.by));
    match by {
        Some(kind) => f.hypotheses.iter().find(|h| h.fault == kind),
        None => f
            .hypotheses
            .iter()
            .filter(|h| h.score > 0.0)
            .max_by(|a, b| a.score.total_cmp(&b.score)),
    }
}

/// Why a fault was not named (`None`: it was), in a few words for the per-fault list.
pub fn why_not(f: &Facts, h: &HypothesisReport) -> Option<String> {
    let named = named_by(f.verdict);
    if named.as_ref().is_some_and(|n| n.faults.contains(&h.fault)) {
        return None;
    }
    let rule = &f.rule;
    let leader = leader(f);
    let is_leader = leader.is_some_and(|l| l.fault == h.fault);
    if f.candidates.contains(&h.fault) {
        let others: Vec<FaultKind> = f
            .candidates
            .iter()
            .copied()
            .filter(|&k| k != h.fault)
            .collect();
        return Some(format!("not separable from {}", and_list(&others)));
    }
    if !significant(h.significance, rule) {
        return Some("not significant (noise could give it)".into());
    }
    if h.score < rule.min_fault_score {
        let naming = format!("below the naming score {:.1}", rule.min_fault_score);
        return Some(match is_leader {
            true if h.score >= rule.lone_fault_score => format!("{naming} and not standing alone"),
            true => format!("{naming} ({:.1} standing alone)", rule.lone_fault_score),
            false => naming,
        });
    }
    if let (
        Some(n),
        Some(LearnedFacts {
            basis: Basis::Agreement,
            ..
        }),
    ) = (&named, f.learned)
    {
        return Some(format!("the learned model picked the {}", n.what));
    }
    if let Some(l) = leader.filter(|l| {
        h.fault == FaultKind::Cage
            && matches!(l.fault, FaultKind::OuterRace | FaultKind::Ball)
            && h.score > l.score
    }) {
        return Some(format!(
            "made by the {} (its defect shows at the cage frequency too)",
            fault_words(l.fault)
        ));
    }
    if let Some(e) = h.explained {
        let by = fault_words(e.by);
        if !significant(e.significance, rule) {
            return Some(format!(
                "explained by the {by} (what is left: {}, could be noise)",
                times(e.score)
            ));
        }
        if e.score < rule.min_fault_score {
            return Some(format!(
                "explained by the {by} (what is left: {})",
                times(e.score)
            ));
        }
        if named.is_some() {
            return Some(format!(
                "the {by} is {} stronger",
                times(leader.map_or(0.0, |l| l.score) / e.score.max(1e-9))
            ));
        }
    }
    Some("not named by the decision rule (see the reason)".into())
}

/// A flag change in the technician's words (the daemon's `FLAG` line).
pub fn flag_words(kind: FaultKind, from: FlagLevel, to: FlagLevel) -> String {
    let what = fault_words(kind);
    match (from, to) {
        (_, FlagLevel::Alarm) => format!("{what} defect: plan an inspection"),
        (FlagLevel::Alarm, FlagLevel::Watch) => format!("{what} signs easing: keep watching"),
        (_, FlagLevel::Watch) => format!("possible {what} defect: watch it"),
        (_, FlagLevel::Ok) => format!("{what} signs gone: nothing to do"),
    }
}

/// `5` → `5×`, `2.5` → `2.5×`, `52.24` → `52.2×`.
fn times(x: f64) -> String {
    let text = format!("{x:.1}");
    format!("{}×", text.strip_suffix(".0").unwrap_or(&text))
}

/// `[a]` → `a`, `[a, b]` → `a and b`, `[a, b, c]` → `a, b and c`.
fn and_list(kinds: &[FaultKind]) -> String {
    let words: Vec<&str> = kinds.iter().map(|&k| fault_words(k)).collect();
    match words.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        Some((last, _)) => (*last).to_string(),
        None => String::new(),
    }
}

fn capitalized(text: &str) -> String {
    let mut chars = text.chars();
    chars.next().map_or_else(String::new, |first| {
        first.to_uppercase().chain(chars).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::AnalysisSettings;
    use FaultKind::{Ball, Cage, InnerRace, OuterRace};

    fn hypothesis(fault: FaultKind, score: f64, significance: f64) -> HypothesisReport {
        HypothesisReport {
            fault,
            frequency_hz: 100.0,
            band_hz: [0.0, 6000.0],
            score,
            significance,
            slip: 0.0,
            sideband_score: None,
            modulation: None,
            harmonics: Vec::new(),
            explained: None,
            named: false,
            why_not: None,
        }
    }

    /// Four hypotheses (outer race, inner race, ball, cage) as (score, significance); the
    /// leader `by` explains the others down to `left` (score, significance) each.
    fn contest(
        values: [(f64, f64); 4],
        by: FaultKind,
        left: [(f64, f64); 4],
    ) -> Vec<HypothesisReport> {
        FaultKind::ALL
            .iter()
            .zip(values.iter().zip(left))
            .map(|(&kind, (&(score, significance), (s, sig)))| {
                let mut h = hypothesis(kind, score, significance);
                h.explained = (kind != by).then_some(super::super::ExplainedScore {
                    by,
                    score: s,
                    significance: sig,
                });
                h
            })
            .collect()
    }

    fn facts<'a>(
        verdict: Verdict,
        confidence: f64,
        candidates: &'a [FaultKind],
        hypotheses: &'a [HypothesisReport],
    ) -> Facts<'a> {
        Facts {
            verdict,
            confidence,
            candidates,
            hypotheses,
            rule: AnalysisSettings::default().decision_rule(),
            learned: None,
            twin_prefers: None,
        }
    }

    fn why(f: &Facts, kind: FaultKind) -> Option<String> {
        let h = f
            .hypotheses
            .iter()
            .find(|h| h.fault == kind)
            .expect("scored");
        why_not(f, h)
    }

    /// The technician's line carries no statistics jargon.
    fn assert_plain(line: &str) {
        for jargon in [
            "p=",
            "p ≤",
            "10^",
            "comb",
            "GK",
            "kurtogram",
            "_race",
            "significan",
        ] {
            assert!(!line.contains(jargon), "'{jargon}' in: {line}");
        }
    }

    #[test]
    fn a_clear_fault_reads_what_how_sure_and_what_to_do() {
        let h = contest(
            [(52.0, 9.0), (10.8, 3.6), (6.0, 1.1), (5.0, 0.0)],
            OuterRace,
            [(0.0, 0.0), (7.0, 1.7), (1.4, 0.1), (1.2, 0.0)],
        );
        let f = facts(Verdict::OuterRace, 0.99, &[], &h);
        let line = summary(&f);
        assert_eq!(
            line,
            "Outer race defect, clear (very unlikely to be noise). Plan an inspection."
        );
        assert_plain(&line);
        assert_eq!(why(&f, OuterRace), None);
        // Striking on its own (p = 10^-3.6), but explained by the outer race: it says so.
        assert_eq!(
            why(&f, InnerRace).as_deref(),
            Some("explained by the outer race (what is left: 7×, could be noise)")
        );
        assert_eq!(
            why(&f, Ball).as_deref(),
            Some("not significant (noise could give it)")
        );
    }

    #[test]
    fn a_fault_near_the_line_is_probable_or_borderline_and_asks_for_another_look() {
        let h = contest(
            [(1.5, 0.5), (6.4, 4.0), (3.6, 3.9), (1.2, 0.0)],
            InnerRace,
            [(1.4, 0.3), (0.0, 0.0), (2.0, 1.0), (1.1, 0.0)],
        );
        let probable = summary(&facts(Verdict::InnerRace, 0.8, &[], &h));
        assert_eq!(
            probable,
            "Inner race defect, probable (unlikely to be noise). Watch it: analyse again within a week."
        );
        let borderline = summary(&facts(Verdict::InnerRace, 0.6, &[], &h));
        assert!(
            borderline.starts_with("Inner race defect, borderline")
                && borderline.ends_with("Measure again soon to confirm it."),
            "{borderline}"
        );
        assert_plain(&borderline);
        let f = facts(Verdict::InnerRace, 0.6, &[], &h);
        assert_eq!(why(&f, Ball).as_deref(), Some("below the naming score 5.0"));
    }

    #[test]
    fn no_fault_with_nothing_above_the_noise_says_what_a_fault_would_need() {
        let h = contest(
            [(2.8, 1.8), (2.5, 1.6), (2.2, 2.8), (1.5, 0.0)],
            OuterRace,
            [(0.0, 0.0), (2.4, 1.5), (2.1, 2.7), (1.5, 0.0)],
        );
        let f = facts(Verdict::None, 1.0, &[], &h);
        let line = summary(&f);
        assert_eq!(
            line,
            "No bearing fault found: nothing stands out from the noise (strongest sign: outer \
             race, 2.8× the floor, which noise can give; a fault needs 5× and to stand clearly \
             above noise). Nothing to do."
        );
        assert_plain(&line);
        for kind in FaultKind::ALL {
            assert_eq!(
                why(&f, kind).as_deref(),
                Some("not significant (noise could give it)")
            );
        }
    }

    #[test]
    fn no_fault_with_a_significant_but_small_leader_names_it_and_what_it_lacked() {
        let h = contest(
            [(3.2, 3.4), (2.6, 3.3), (1.5, 0.5), (1.3, 0.0)],
            OuterRace,
            [(0.0, 0.0), (2.5, 3.2), (1.5, 0.5), (1.3, 0.0)],
        );
        let f = facts(Verdict::None, 0.8, &[], &h);
        let line = summary(&f);
        assert_eq!(
            line,
            "No bearing fault found. The strongest sign, outer race, stands 3.2× above the floor \
             but would need 5×, or to stand alone (2× every other sign, far beyond noise), to be \
             named. Nothing to do now; measure again at the next routine check."
        );
        assert_plain(&line);
        assert_eq!(
            why(&f, OuterRace).as_deref(),
            Some("below the naming score 5.0 and not standing alone")
        );
        // Close to the line: look again soon.
        let close = summary(&facts(Verdict::None, 0.6, &[], &h));
        assert!(
            close.starts_with("No bearing fault named, but one comes close.")
                && close.ends_with("Watch it: analyse again within a week."),
            "{close}"
        );
        // A small leader that is not significant, beside a smaller one that is: the line speaks
        // of the one that is more than noise.
        let h = contest(
            [(2.6, 4.7), (2.6, 1.0), (1.5, 0.5), (1.3, 0.0)],
            InnerRace,
            [(2.6, 4.7), (0.0, 0.0), (1.5, 0.5), (1.3, 0.0)],
        );
        let line = summary(&facts(Verdict::None, 0.98, &[], &h));
        assert!(
            line.contains("The clearest sign, outer race, stands 2.6× above the floor"),
            "{line}"
        );
    }

    #[test]
    fn two_faults_that_cannot_be_told_apart_say_so_and_ask_for_a_look() {
        let h = contest(
            [(6.0, 10.0), (7.0, 12.0), (1.4, 1.0), (1.3, 0.2)],
            InnerRace,
            [(5.8, 9.0), (0.0, 0.0), (1.4, 1.0), (1.3, 0.2)],
        );
        let candidates = [InnerRace, OuterRace];
        let f = facts(Verdict::None, 0.55, &candidates, &h);
        let line = summary(&f);
        assert_eq!(
            line,
            "No clear fault: inner race and outer race both show, and cannot be told apart. \
             Check the spectrum; measure again."
        );
        assert_plain(&line);
        assert_eq!(
            why(&f, OuterRace).as_deref(),
            Some("not separable from inner race")
        );
        assert_eq!(
            why(&f, InnerRace).as_deref(),
            Some("not separable from outer race")
        );
    }

    #[test]
    fn a_fault_the_learned_model_confirms_is_probable_at_most_and_says_so() {
        let h = contest(
            [(6.0, 10.0), (7.0, 12.0), (1.4, 1.0), (1.3, 0.2)],
            InnerRace,
            [(5.8, 9.0), (0.0, 0.0), (1.4, 1.0), (1.3, 0.2)],
        );
        // The confidence is that of the spectrum's own `none`, whatever it is.
        let mut f = facts(Verdict::OuterRace, 0.55, &[], &h);
        f.learned = Some(LearnedFacts {
            basis: Basis::Agreement,
            agrees: true,
        });
        let line = summary(&f);
        assert_eq!(
            line,
            "Outer race defect, probable (very unlikely to be noise; the spectrum alone does not \
             settle it; the learned model confirms it). Watch it: analyse again within a week."
        );
        assert_plain(&line);
        assert_eq!(
            why(&f, InnerRace).as_deref(),
            Some("the learned model picked the outer race")
        );
        // A learned model that disagrees with a named fault, and a twin that prefers another.
        f.learned = Some(LearnedFacts {
            basis: Basis::Envelope,
            agrees: false,
        });
        f.twin_prefers = Some(Ball);
        f.confidence = 0.99;
        let line = summary(&f);
        assert!(
            line.contains("the learned model disagrees; the signal-model twin fits the rolling element (ball) better")
                && line.starts_with("Outer race defect, clear"),
            "{line}"
        );
    }

    #[test]
    fn a_cage_comb_a_ball_defect_makes_is_not_named_for_that_reason() {
        let h = contest(
            [(1.5, 0.5), (2.0, 1.0), (7.7, 40.0), (18.7, 20.0)],
            Ball,
            [(1.5, 0.5), (2.0, 1.0), (0.0, 0.0), (1.3, 0.0)],
        );
        let f = facts(Verdict::Ball, 0.97, &[], &h);
        assert!(summary(&f).starts_with("Rolling element (ball) defect, clear"));
        assert_eq!(
            why(&f, Cage).as_deref(),
            Some("made by the rolling element (ball) (its defect shows at the cage frequency too)")
        );
    }

    #[test]
    fn a_detected_runner_up_clear_of_the_named_fault_is_outweighed() {
        let h = contest(
            [(30.0, 20.0), (8.0, 9.0), (1.4, 1.0), (1.3, 0.2)],
            OuterRace,
            [(0.0, 0.0), (6.0, 8.0), (1.4, 1.0), (1.3, 0.2)],
        );
        let f = facts(Verdict::OuterRace, 0.99, &[], &h);
        assert_eq!(
            why(&f, InnerRace).as_deref(),
            Some("the outer race is 5× stronger")
        );
    }

    #[test]
    fn nothing_scored_asks_for_the_inputs() {
        let h: Vec<HypothesisReport> = FaultKind::ALL
            .iter()
            .map(|&k| hypothesis(k, 0.0, 0.0))
            .collect();
        let line = summary(&facts(Verdict::None, 0.5, &[], &h));
        assert!(line.starts_with("No verdict"), "{line}");
    }

    #[test]
    fn flag_changes_read_as_what_to_do() {
        assert_eq!(
            flag_words(OuterRace, FlagLevel::Ok, FlagLevel::Watch),
            "possible outer race defect: watch it"
        );
        assert_eq!(
            flag_words(InnerRace, FlagLevel::Watch, FlagLevel::Alarm),
            "inner race defect: plan an inspection"
        );
        assert_eq!(
            flag_words(Cage, FlagLevel::Alarm, FlagLevel::Watch),
            "cage signs easing: keep watching"
        );
        assert_eq!(
            flag_words(Ball, FlagLevel::Watch, FlagLevel::Ok),
            "rolling element (ball) signs gone: nothing to do"
        );
    }
}
