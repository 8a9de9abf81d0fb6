//! The learned model's agreement, calibrated on the simulator: every record of a sweep is
//! decided once per point of a grid of [`Agreement`] parameters, from one analysis and one
//! opinion, and the points are compared by what they name right, what they name on healthy
//! records and what they name wrong (`bearingd evaluate --config C` with `twin.learned_model`
//! set: `agreement_grid.txt`).
//!
//! Why a grid on stored inputs: re-simulating the sweep per point would cost its CPU 96 times;
//! the decision is cheap once the analysis and the opinion are made. The point chosen is then
//! confirmed by real runs of both paths (docs/DIAGNOSIS.md, "Agreement with the learned
//! model").

use super::outcome::{CaseResult, Predicted};
use super::summary::is_confident_wrong;
use crate::analysis::agreement::{decide, Agreement, WitnessOpinion};
use crate::analysis::record::RecordAnalysis;
use crate::analysis::AnalysisSettings;
use std::fmt::Write as _;

/// (choice) The grid: the network's probability, the comb's score, its lead over the
/// runner-up, and the significance relief in decades.
const PROBABILITIES: [f64; 4] = [0.7, 0.8, 0.9, 0.95];
const SCORES: [f64; 6] = [2.0, 2.5, 3.0, 3.5, 4.0, 4.5];
const LEADS: [f64; 2] = [1.5, 2.0];
const RELIEFS: [f64; 2] = [0.0, 1.0];

/// Every point of the grid, in a fixed order (the order of each record's `agreement_grid`).
pub fn grid() -> Vec<Agreement> {
    let mut points = Vec::new();
    for min_probability in PROBABILITIES {
        for min_score in SCORES {
            for min_lead in LEADS {
                for significance_relief_decades in RELIEFS {
                    points.push(Agreement {
                        min_probability,
                        min_score,
                        min_lead,
                        significance_relief_decades,
                    });
                }
            }
        }
    }
    points
}

/// What the record path would answer at each grid point, `analysis` being the envelope's
/// (not yet heard the witness).
pub fn grid_verdicts(
    analysis: &RecordAnalysis,
    settings: &AnalysisSettings,
    opinion: Option<WitnessOpinion>,
) -> Vec<Predicted> {
    let scores = analysis.scores();
    let rule = settings.decision_rule();
    grid()
        .into_iter()
        .map(|agreement| {
            let decided = decide(
                &scores,
                &analysis.explained,
                &analysis.diagnosis,
                &rule,
                &agreement,
                opinion,
            );
            Predicted::of_verdict(decided.verdict)
        })
        .collect()
}

/// One grid point's counts on the record path.
#[derive(Debug, Clone, PartialEq)]
pub struct PointTally {
    pub agreement: Agreement,
    /// Fault records named right.
    pub right: usize,
    /// Healthy records given a fault.
    pub false_alarms: usize,
    /// Named, wrong answers (healthy records included).
    pub confident_wrong: usize,
}

/// The counts of every grid point over `results` (records without grid verdicts: none).
pub fn tally(results: &[CaseResult]) -> Vec<PointTally> {
    let mut tallies: Vec<PointTally> = grid()
        .into_iter()
        .map(|agreement| PointTally {
            agreement,
            right: 0,
            false_alarms: 0,
            confident_wrong: 0,
        })
        .collect();
    for result in results {
        let Ok(outcome) = &result.record else {
            continue;
        };
        let truth = result.truth();
        for (tally, &predicted) in tallies.iter_mut().zip(&outcome.agreement_grid) {
            if truth.is_some_and(|t| predicted == Predicted::Fault(t)) {
                tally.right += 1;
            }
            if truth.is_none() && predicted != Predicted::None {
                tally.false_alarms += 1;
            }
            if is_confident_wrong(truth, predicted) {
                tally.confident_wrong += 1;
            }
        }
    }
    tallies
}

/// The grid as a table, best first: clean points (no false alarm, nothing named wrong) by
/// faults named right, then the rest; with the configured decision's count for comparison.
pub fn render(results: &[CaseResult]) -> String {
    let witnessed = results
        .iter()
        .filter(|r| {
            r.record
                .as_ref()
                .is_ok_and(|o| !o.agreement_grid.is_empty())
        })
        .collect::<Vec<_>>();
    let configured_right = witnessed
        .iter()
        .filter(|r| {
            r.truth()
                .is_some_and(|t| r.record_predicted() == Predicted::Fault(t))
        })
        .count();
    let faulty = witnessed.iter().filter(|r| r.truth().is_some()).count();
    let mut tallies = tally(results);
    tallies.sort_by(|a, b| {
        let clean = |t: &PointTally| t.false_alarms == 0 && t.confident_wrong == 0;
        clean(b)
            .cmp(&clean(a))
            .then(b.right.cmp(&a.right))
            .then(
                b.agreement
                    .min_probability
                    .total_cmp(&a.agreement.min_probability),
            )
            .then(b.agreement.min_score.total_cmp(&a.agreement.min_score))
            .then(b.agreement.min_lead.total_cmp(&a.agreement.min_lead))
            .then(
                a.agreement
                    .significance_relief_decades
                    .total_cmp(&b.agreement.significance_relief_decades),
            )
    });
    let mut out = format!(
        "Agreement grid, record path: {} records the model knows ({faulty} with a fault); \
         the configured decision (the envelope alone unless the config sets agreement_*) \
         names {configured_right} right\n\n\
         | probability | score | lead | relief (decades) | named right | false alarms | confident wrong |\n\
         |---|---|---|---|---|---|---|\n",
        witnessed.len()
    );
    for t in &tallies {
        let a = &t.agreement;
        let _ = writeln!(
            out,
            "| {:.2} | {:.1} | {:.1} | {:.0} | {} | {} | {} |",
            a.min_probability,
            a.min_score,
            a.min_lead,
            a.significance_relief_decades,
            t.right,
            t.false_alarms,
            t.confident_wrong
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::record::RecordAnalyzer;
    use crate::twin::{SimulatedFault, SimulationParams, Simulator};

    #[test]
    fn the_grid_holds_each_point_once_and_without_an_opinion_every_point_is_the_envelope() {
        let points = grid();
        assert_eq!(points.len(), 96);
        let distinct: std::collections::BTreeSet<String> =
            points.iter().map(|p| format!("{p:?}")).collect();
        assert_eq!(distinct.len(), points.len());
        let params = SimulationParams::example(SimulatedFault::OuterRace);
        let signal = Simulator::record(params.clone(), 4.0);
        let settings = AnalysisSettings::default();
        let analysis = RecordAnalyzer::default()
            .analyze(&signal, params.fs_hz, &params.frequencies(), &settings)
            .expect("the example record analyses");
        let envelope = Predicted::of_verdict(analysis.diagnosis.verdict);
        assert_eq!(
            envelope,
            Predicted::Fault(crate::messages::FaultKind::OuterRace)
        );
        let verdicts = grid_verdicts(&analysis, &settings, None);
        assert_eq!(verdicts.len(), points.len());
        assert!(verdicts.iter().all(|&v| v == envelope), "{verdicts:?}");
    }
}
