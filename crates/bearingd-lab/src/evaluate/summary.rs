//! From the cases' results to the numbers an engineer judges a detector by: detection
//! probability per fault and noise level, false alarms on healthy records (per record, and per
//! window for the monitor), the confusion matrix and the confident-wrong count, for each path.

use super::outcome::{CaseResult, Predicted};
use super::sweep::{NoiseLevel, DEFAULT_SEVERITY};
use crate::messages::FaultKind;
use crate::twin::SimulatedFault;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write;

/// The two ways the pipeline meets a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Path {
    /// `bearingd analyze`: the verdict.
    Record,
    /// The daemon's channel monitor: the flags raised.
    Monitor,
}

impl Path {
    pub const BOTH: [Path; 2] = [Path::Record, Path::Monitor];

    pub fn title(self) -> &'static str {
        match self {
            Path::Record => "record path (bearingd analyze: verdict)",
            Path::Monitor => "monitor path (bearingd run/replay: flags raised)",
        }
    }

    /// What this path concluded about a case.
    pub fn predicted(self, result: &CaseResult) -> Predicted {
        match self {
            Path::Record => result.record_predicted(),
            Path::Monitor => result.monitor.predicted,
        }
    }
}

/// Successes out of trials.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Rate {
    pub hits: u64,
    pub trials: u64,
}

impl Rate {
    fn add(&mut self, hit: bool) {
        self.trials += 1;
        self.hits += u64::from(hit);
    }

    pub fn fraction(self) -> Option<f64> {
        (self.trials > 0).then(|| self.hits as f64 / self.trials as f64)
    }

    /// "83 %" or "-" without trials.
    pub fn percent(self) -> String {
        self.fraction()
            .map_or("-".into(), |f| format!("{:.0} %", 100.0 * f))
    }
}

/// One path's numbers.
#[derive(Debug, Clone, Serialize)]
pub struct PathSummary {
    pub path: Path,
    /// Detection probability per fault and noise level (every severity, speed and machine).
    pub pd: BTreeMap<String, BTreeMap<String, Rate>>,
    /// The same at the simulator's default severity and noise, per fault and machine.
    pub pd_default: BTreeMap<String, BTreeMap<String, Rate>>,
    /// Healthy records with a fault named (record) or any flag raised (monitor).
    pub false_alarms_per_record: Rate,
    /// Monitor only: scored windows of healthy records during which a flag was up.
    pub false_alarms_per_window: Option<Rate>,
    /// Rows: the simulated condition; columns: [`Predicted::COLUMNS`].
    pub confusion: BTreeMap<String, BTreeMap<String, u64>>,
    /// Faulty records where another fault was named (or its flag raised), and healthy
    /// records where a fault was.
    pub confident_wrong: u64,
    /// Records the path could not analyse (counted as misses).
    pub errors: u64,
}

/// Both paths' numbers, and the noise levels in table order.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub runs: usize,
    pub noise_levels: Vec<String>,
    pub paths: Vec<PathSummary>,
}

fn condition_names() -> [&'static str; 5] {
    SimulatedFault::ALL.map(SimulatedFault::name)
}

/// Whether `predicted` is a wrong, named answer for a record whose truth is `truth`.
pub fn is_confident_wrong(truth: Option<FaultKind>, predicted: Predicted) -> bool {
    match predicted {
        Predicted::Fault(kind) => truth != Some(kind),
        // Several flags on a faulty record: at least one is wrong; on a healthy one, all are.
        Predicted::Several => true,
        // A pair is wrong when the true fault is not one of its two (on a healthy record both
        // of its flags are false alarms); naming the true fault among two is not wrong.
        Predicted::Ambiguous(pair) => truth.is_none_or(|kind| !pair.faults().contains(&kind)),
        Predicted::None => false,
    }
}

/// Whether the path detected the record's true fault (the monitor: its flag rose, whatever
/// else rose with it).
pub fn detected(path: Path, result: &CaseResult) -> bool {
    let Some(truth) = result.truth() else {
        return false;
    };
    match path {
        Path::Record => result.record_predicted() == Predicted::Fault(truth),
        Path::Monitor => {
            let index = FaultKind::ALL.iter().position(|&k| k == truth).unwrap_or(0);
            result.monitor.highest[index] > crate::messages::FlagLevel::Ok
        }
    }
}

/// Summarises a sweep's results.
pub fn summarize(results: &[CaseResult]) -> Summary {
    let mut levels: Vec<NoiseLevel> = Vec::new();
    for r in results {
        if !levels.contains(&r.case.noise) {
            levels.push(r.case.noise);
        }
    }
    levels.sort_by(|a, b| a.order().total_cmp(&b.order()));
    let paths = Path::BOTH
        .into_iter()
        .map(|path| summarize_path(path, results))
        .collect();
    Summary {
        runs: results.len(),
        noise_levels: levels.into_iter().map(NoiseLevel::label).collect(),
        paths,
    }
}

fn summarize_path(path: Path, results: &[CaseResult]) -> PathSummary {
    let mut pd: BTreeMap<String, BTreeMap<String, Rate>> = BTreeMap::new();
    let mut pd_default: BTreeMap<String, BTreeMap<String, Rate>> = BTreeMap::new();
    let mut per_record = Rate::default();
    let mut per_window = Rate::default();
    let mut confusion: BTreeMap<String, BTreeMap<String, u64>> = BTreeMap::new();
    let mut confident_wrong = 0;
    let mut errors = 0;
    for r in results {
        let predicted = path.predicted(r);
        *confusion
            .entry(r.case.fault.name().into())
            .or_default()
            .entry(predicted.name().into())
            .or_default() += 1;
        if is_confident_wrong(r.truth(), predicted) {
            confident_wrong += 1;
        }
        if path == Path::Record && r.record.is_err() {
            errors += 1;
        }
        match r.truth() {
            None => {
                // An ambiguous verdict still names faults: on a healthy machine it is an alarm.
                per_record.add(predicted != Predicted::None);
                per_window.trials += r.monitor.windows_scored;
                per_window.hits += r.monitor.windows_flagged;
            }
            Some(kind) => {
                let hit = detected(path, r);
                pd.entry(kind.name().into())
                    .or_default()
                    .entry(r.case.noise.label())
                    .or_default()
                    .add(hit);
                if r.case.noise == NoiseLevel::SimulatorDefault
                    && r.case.severity == DEFAULT_SEVERITY
                {
                    pd_default
                        .entry(kind.name().into())
                        .or_default()
                        .entry(r.case.bearing.clone())
                        .or_default()
                        .add(hit);
                }
            }
        }
    }
    PathSummary {
        path,
        pd,
        pd_default,
        false_alarms_per_record: per_record,
        false_alarms_per_window: (path == Path::Monitor).then_some(per_window),
        confusion,
        confident_wrong,
        errors,
    }
}

/// The summary as text tables, for a terminal.
pub fn render_tables(summary: &Summary) -> String {
    let mut out = String::new();
    for p in &summary.paths {
        let _ = writeln!(out, "== {} ==", p.path.title());
        // Pd per fault × noise level.
        let _ = write!(out, "{:<12}", "Pd");
        for level in &summary.noise_levels {
            let _ = write!(out, "{level:>13}");
        }
        let _ = writeln!(out);
        for kind in FaultKind::ALL {
            let _ = write!(out, "{:<12}", kind.name());
            for level in &summary.noise_levels {
                let rate =
                    p.pd.get(kind.name())
                        .and_then(|row| row.get(level))
                        .copied()
                        .unwrap_or_default();
                let cell = format!("{} ({}/{})", rate.percent(), rate.hits, rate.trials);
                let _ = write!(out, "{cell:>13}");
            }
            let _ = writeln!(out);
        }
        if !p.pd_default.is_empty() {
            let _ = write!(out, "at the simulator's default severity and noise:");
            for (fault, row) in &p.pd_default {
                for (bearing, rate) in row {
                    let _ = write!(out, "  {fault}@{bearing} {}/{}", rate.hits, rate.trials);
                }
            }
            let _ = writeln!(out);
        }
        let _ = writeln!(
            out,
            "false alarms on healthy records: {} per record ({}/{}){}",
            p.false_alarms_per_record.percent(),
            p.false_alarms_per_record.hits,
            p.false_alarms_per_record.trials,
            p.false_alarms_per_window.map_or(String::new(), |w| format!(
                ", {:.4} per window ({}/{} windows with a flag up)",
                w.fraction().unwrap_or(0.0),
                w.hits,
                w.trials
            ))
        );
        let _ = writeln!(
            out,
            "confident wrong: {}{}",
            p.confident_wrong,
            if p.errors > 0 {
                format!("; records not analysable: {}", p.errors)
            } else {
                String::new()
            }
        );
        render_confusion(&mut out, p.path, &p.confusion, &condition_names(), &[]);
        let _ = writeln!(out);
    }
    out
}

/// A confusion matrix as a text table: `rows` in order (those present), the columns of
/// [`Predicted::COLUMNS`] this path can produce, any other that occurred, then those of
/// `extra_columns` that occurred.
pub fn render_confusion(
    out: &mut String,
    path: Path,
    confusion: &BTreeMap<String, BTreeMap<String, u64>>,
    rows: &[&str],
    extra_columns: &[&'static str],
) {
    let occurred = |column: &str| {
        confusion
            .values()
            .any(|row| row.get(column).is_some_and(|&n| n > 0))
    };
    let columns: Vec<&'static str> = Predicted::COLUMNS
        .into_iter()
        .filter(|c| {
            let possible = !matches!(
                (path, c),
                (Path::Record, Predicted::Several) | (Path::Monitor, Predicted::Ambiguous(_))
            );
            possible || occurred(c.name())
        })
        .map(Predicted::name)
        .chain(extra_columns.iter().copied().filter(|c| occurred(c)))
        .collect();
    // Each column as wide as its name and a space, at least 11 (`ball_or_inner` is 13).
    let width = |c: &str| (c.len() + 1).max(11);
    let _ = write!(out, "{:<12}", "true\\said");
    for c in &columns {
        let _ = write!(out, "{c:>w$}", w = width(c));
    }
    let _ = writeln!(out);
    for &name in rows {
        let Some(row) = confusion.get(name) else {
            continue;
        };
        let _ = write!(out, "{name:<12}");
        for c in &columns {
            let n = row.get(*c).copied().unwrap_or(0);
            let _ = write!(out, "{n:>w$}", w = width(c));
        }
        let _ = writeln!(out);
    }
}

/// One line per case, for a spreadsheet.
pub fn render_csv(results: &[CaseResult]) -> String {
    let mut out = String::from(
        "fault,bearing,rpm,severity_g,noise,noise_g,snr_db,seed,repeat,record_verdict,\
         record_confidence,score_outer_race,score_inner_race,score_ball,score_cage,\
         record_detected,monitor_predicted,flag_outer_race,flag_inner_race,flag_ball,flag_cage,\
         first_flag_s,windows_scored,windows_flagged,monitor_detected\n",
    );
    for r in results {
        let (verdict, confidence, scores) = match &r.record {
            Ok(o) => (o.verdict.clone(), format!("{:.3}", o.confidence), o.scores),
            Err(e) => (
                format!("error: {}", e.replace(',', ";")),
                String::new(),
                [0.0; 4],
            ),
        };
        let _ = writeln!(
            out,
            "{},{},{:.1},{},{},{:.4},{},{},{},{},{},{:.2},{:.2},{:.2},{:.2},{},{},{},{},{},{},{},{},{},{}",
            r.case.fault.name(),
            r.case.bearing,
            r.case.rpm,
            r.case.severity,
            r.case.noise.label(),
            r.noise_g,
            r.snr_db.map_or(String::new(), |s| format!("{s:.2}")),
            r.case.seed,
            r.case.repeat,
            verdict,
            confidence,
            scores[0],
            scores[1],
            scores[2],
            scores[3],
            detected(Path::Record, r),
            r.monitor.predicted.name(),
            r.monitor.highest[0].name(),
            r.monitor.highest[1].name(),
            r.monitor.highest[2].name(),
            r.monitor.highest[3].name(),
            r.monitor
                .first_flag_s
                .map_or(String::new(), |s| format!("{s:.2}")),
            r.monitor.windows_scored,
            r.monitor.windows_flagged,
            detected(Path::Monitor, r),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::Verdict;

    #[test]
    fn a_pair_is_wrong_only_when_the_truth_is_not_one_of_its_two() {
        let ball_or_inner = Predicted::Ambiguous(Verdict::BallOrInner);
        assert!(!is_confident_wrong(Some(FaultKind::Ball), ball_or_inner));
        assert!(!is_confident_wrong(
            Some(FaultKind::InnerRace),
            ball_or_inner
        ));
        assert!(is_confident_wrong(
            Some(FaultKind::OuterRace),
            ball_or_inner
        ));
        // On a healthy record its two flags are false alarms.
        assert!(is_confident_wrong(None, ball_or_inner));
        assert!(!is_confident_wrong(None, Predicted::None));
    }

    #[test]
    fn a_pair_column_is_as_wide_as_its_name() {
        let mut confusion: BTreeMap<String, BTreeMap<String, u64>> = BTreeMap::new();
        confusion
            .entry("ball".into())
            .or_default()
            .insert("ball_or_inner".into(), 3);
        let mut out = String::new();
        render_confusion(&mut out, Path::Record, &confusion, &["ball"], &[]);
        let header: Vec<&str> = out.lines().next().unwrap().split_whitespace().collect();
        assert!(header.contains(&"ball_or_cage"), "{out}");
        assert!(header.contains(&"ball_or_inner"), "{out}");
        let row: Vec<&str> = out.lines().nth(1).unwrap().split_whitespace().collect();
        assert_eq!(row.len(), header.len(), "{out}");
        let at = header.iter().position(|c| *c == "ball_or_inner").unwrap();
        assert_eq!(row[at], "3", "{out}");
    }
}
