//! The entries of a recordings run counted: per path a confusion matrix (truth × what it
//! said), right, missed, ambiguous, confident-wrong; the agreement between the paths with
//! every disagreeing record; the daemon's first-flag times; the records that failed. Counted
//! only from the entries, so the JSON's entries and its summary cannot disagree.

use super::{DaemonOutcome, Entry, FlagChange, Truth};
use crate::evaluate::outcome::Predicted;
use crate::evaluate::summary::{is_confident_wrong, render_confusion, Path};
use crate::messages::FaultKind;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write;

/// What one path said about one entry: an answer, or why there is none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Said {
    Answer(Predicted),
    /// The daemon path only: the record ended before the daemon could score.
    TooShort,
    Failed,
}

impl Said {
    pub const TOO_SHORT: &'static str = "too_short";
    pub const FAILED: &'static str = "failed";

    pub fn name(self) -> &'static str {
        match self {
            Said::Answer(p) => p.name(),
            Said::TooShort => Self::TOO_SHORT,
            Said::Failed => Self::FAILED,
        }
    }

    /// What `path` said about `entry`.
    pub fn of(path: Path, entry: &Entry) -> Said {
        match path {
            Path::Record => entry
                .record
                .as_ref()
                .map_or(Said::Failed, |r| Said::Answer(r.predicted)),
            Path::Monitor => match &entry.daemon {
                DaemonOutcome::Judged { monitor, .. } => Said::Answer(monitor.predicted),
                DaemonOutcome::TooShort { .. } => Said::TooShort,
                DaemonOutcome::Failed { .. } => Said::Failed,
            },
        }
    }
}

/// One path's counts.
#[derive(Debug, Clone, Default, Serialize)]
pub struct PathTally {
    /// Rows: the truth ([`Truth::name`]); columns: [`Said::name`].
    pub confusion: BTreeMap<String, BTreeMap<String, u64>>,
    /// Entries with a known truth and an answer.
    pub judged: u64,
    /// The true fault named, or none on a healthy record.
    pub right: u64,
    /// A faulty record said to be none.
    pub missed: u64,
    /// A verdict that names no single fault and is not none.
    pub ambiguous: u64,
    /// A fault named that is not the truth (on a healthy record: any fault).
    pub confident_wrong: u64,
    /// Of those, on healthy records.
    pub false_alarms: u64,
    /// Entries with an answer but no known truth (compared between paths, not judged).
    pub unknown_truth: u64,
    pub too_short: u64,
    pub failed: u64,
}

/// A record the two paths answered differently.
#[derive(Debug, Clone, Serialize)]
pub struct Disagreement {
    pub record: String,
    pub truth: String,
    pub analyze: String,
    pub daemon: String,
}

/// Median and largest of some times, s.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Times {
    pub count: usize,
    pub median_s: Option<f64>,
    pub max_s: Option<f64>,
}

impl Times {
    fn of(mut times: Vec<f64>) -> Times {
        times.sort_by(f64::total_cmp);
        let n = times.len();
        let median_s = (n > 0).then(|| {
            if n % 2 == 1 {
                times[n / 2]
            } else {
                0.5 * (times[n / 2 - 1] + times[n / 2])
            }
        });
        Times {
            count: n,
            median_s,
            max_s: times.last().copied(),
        }
    }
}

/// Everything counted.
#[derive(Debug, Clone, Serialize)]
pub struct Tally {
    pub entries: usize,
    pub record: PathTally,
    pub daemon: PathTally,
    /// Entries both paths answered.
    pub compared: u64,
    pub agree: u64,
    pub disagreements: Vec<Disagreement>,
    /// The daemon's first flag (any fault), over the entries where one rose.
    pub first_flag: Times,
    /// The true fault's first rise, over the faulty entries where it rose.
    pub detection_delay: Times,
    /// `record: what went wrong` for every entry where a path failed.
    pub failures: Vec<String>,
}

impl Tally {
    /// Confident-wrong answers (both paths), disagreements and failures: what `--strict`
    /// refuses.
    pub fn problems(&self) -> u64 {
        self.record.confident_wrong
            + self.daemon.confident_wrong
            + self.disagreements.len() as u64
            + self.failures.len() as u64
    }

    pub fn path(&self, path: Path) -> &PathTally {
        match path {
            Path::Record => &self.record,
            Path::Monitor => &self.daemon,
        }
    }
}

fn count(path: Path, entries: &[Entry]) -> PathTally {
    let mut t = PathTally::default();
    for entry in entries {
        let said = Said::of(path, entry);
        *t.confusion
            .entry(entry.truth.name().into())
            .or_default()
            .entry(said.name().into())
            .or_default() += 1;
        let predicted = match said {
            Said::Answer(p) => p,
            Said::TooShort => {
                t.too_short += 1;
                continue;
            }
            Said::Failed => {
                t.failed += 1;
                continue;
            }
        };
        let Some(truth) = entry.truth.judged() else {
            t.unknown_truth += 1;
            continue;
        };
        t.judged += 1;
        let right = match truth {
            Some(kind) => predicted == Predicted::Fault(kind),
            None => predicted == Predicted::None,
        };
        t.right += u64::from(right);
        t.missed += u64::from(truth.is_some() && predicted == Predicted::None);
        t.ambiguous += u64::from(matches!(predicted, Predicted::Ambiguous(_)));
        if is_confident_wrong(truth, predicted) {
            t.confident_wrong += 1;
            t.false_alarms += u64::from(truth.is_none());
        }
    }
    t
}

/// Counts `entries`.
pub fn tally(entries: &[Entry]) -> Tally {
    let mut disagreements = Vec::new();
    let mut failures = Vec::new();
    let (mut first_flags, mut delays) = (Vec::new(), Vec::new());
    for entry in entries {
        let said = |path| Said::of(path, entry).name().to_string();
        if entry.agree == Some(false) {
            disagreements.push(Disagreement {
                record: entry.label(),
                truth: entry.truth.name().into(),
                analyze: said(Path::Record),
                daemon: daemon_answer(entry),
            });
        }
        let daemon_error = match &entry.daemon {
            DaemonOutcome::Failed { error } => Some(error),
            _ => None,
        };
        let problem = match (entry.record.as_ref().err(), daemon_error) {
            (Some(a), Some(d)) if a == d => Some(a.clone()),
            (Some(a), Some(d)) => Some(format!("analyze: {a}; daemon: {d}")),
            (Some(a), None) => Some(format!("analyze: {a}")),
            (None, Some(d)) => Some(format!("daemon: {d}")),
            (None, None) => None,
        };
        if let Some(problem) = problem {
            failures.push(format!("{}: {problem}", entry.label()));
        }
        if let DaemonOutcome::Judged { monitor, flags, .. } = &entry.daemon {
            first_flags.extend(monitor.first_flag_s);
            if let Truth::Fault(kind) = entry.truth {
                delays.extend(
                    flags
                        .iter()
                        .find(|f| f.fault == kind && f.to > f.from)
                        .map(|f| f.at_s),
                );
            }
        }
    }
    Tally {
        entries: entries.len(),
        record: count(Path::Record, entries),
        daemon: count(Path::Monitor, entries),
        compared: entries.iter().filter(|e| e.agree.is_some()).count() as u64,
        agree: entries.iter().filter(|e| e.agree == Some(true)).count() as u64,
        disagreements,
        first_flag: Times::of(first_flags),
        detection_delay: Times::of(delays),
        failures,
    }
}

/// The daemon's answer in words: the flags that rose with their highest level and first rise.
fn daemon_answer(entry: &Entry) -> String {
    let DaemonOutcome::Judged { monitor, flags, .. } = &entry.daemon else {
        return Said::of(Path::Monitor, entry).name().to_string();
    };
    let mut first_rises: Vec<&FlagChange> = FaultKind::ALL
        .iter()
        .filter_map(|&kind| flags.iter().find(|f| f.fault == kind && f.to > f.from))
        .collect();
    first_rises.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
    let raised: Vec<String> = first_rises
        .iter()
        .map(|f| {
            format!(
                "{} {} from {:.1} s",
                f.fault.name(),
                monitor.highest[f.fault.index()].name(),
                f.at_s
            )
        })
        .collect();
    if raised.is_empty() {
        "none".into()
    } else {
        raised.join(", ")
    }
}

/// The tally as text tables, for a terminal.
pub fn render_recordings(tally: &Tally) -> String {
    let mut out = String::new();
    let rows = Truth::ROWS.map(Truth::name);
    for path in Path::BOTH {
        let t = tally.path(path);
        let title = match path {
            Path::Record => "record path (bearingd analyze FILE: verdict)",
            Path::Monitor => "daemon path (bearingd import + replay: flags raised)",
        };
        let _ = writeln!(out, "== {title} ==");
        render_confusion(
            &mut out,
            path,
            &t.confusion,
            &rows,
            &[Said::TOO_SHORT, Said::FAILED],
        );
        let too_short = match path {
            Path::Monitor => format!("; TOO SHORT FOR THE DAEMON {}", t.too_short),
            Path::Record => String::new(),
        };
        let _ = writeln!(
            out,
            "judged {}: right {}, missed {} (a fault said none), ambiguous {}, confident wrong {} \
             (false alarms on healthy records {}); truth unknown {}{too_short}; failed {}",
            t.judged,
            t.right,
            t.missed,
            t.ambiguous,
            t.confident_wrong,
            t.false_alarms,
            t.unknown_truth,
            t.failed
        );
        let _ = writeln!(out);
    }
    let times = |t: &Times| match (t.median_s, t.max_s) {
        (Some(median), Some(max)) => {
            format!("median {median:.1} s, max {max:.1} s over {}", t.count)
        }
        _ => "none".to_string(),
    };
    let _ = writeln!(
        out,
        "daemon's first flag: {}; the true fault's first rise: {}",
        times(&tally.first_flag),
        times(&tally.detection_delay)
    );
    let _ = writeln!(
        out,
        "agreement (daemon's flags = analyze's verdict): {} of {} compared agree, {} disagree; \
         {} not compared (too short for the daemon, or a path failed)",
        tally.agree,
        tally.compared,
        tally.disagreements.len(),
        tally.entries as u64 - tally.compared
    );
    for d in &tally.disagreements {
        let _ = writeln!(
            out,
            "  {}: truth {}; analyze said {}; daemon flagged {}",
            d.record, d.truth, d.analyze, d.daemon
        );
    }
    if !tally.failures.is_empty() {
        let _ = writeln!(out, "failed ({}):", tally.failures.len());
        for f in &tally.failures {
            let _ = writeln!(out, "  {f}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluate::outcome::{MonitorOutcome, RecordOutcome};
    use crate::evaluate::recordings::{agreement, agrees};
    use crate::messages::FlagLevel;
    use std::path::PathBuf;

    fn record(predicted: Predicted) -> Result<RecordOutcome, String> {
        Ok(RecordOutcome {
            verdict: predicted.name().into(),
            predicted,
            confidence: 0.9,
            reason: String::new(),
            candidates: Vec::new(),
            scores: [0.0; 4],
            learned: None,
            agreement_grid: Vec::new(),
        })
    }

    fn judged(raised: &[(FaultKind, f64)]) -> DaemonOutcome {
        let mut highest = [FlagLevel::Ok; 4];
        let flags: Vec<FlagChange> = raised
            .iter()
            .map(|&(fault, at_s)| {
                highest[fault.index()] = FlagLevel::Watch;
                FlagChange {
                    fault,
                    from: FlagLevel::Ok,
                    to: FlagLevel::Watch,
                    at_s,
                    score: 20.0,
                }
            })
            .collect();
        DaemonOutcome::Judged {
            monitor: MonitorOutcome {
                highest,
                first_flag_s: flags.first().map(|f| f.at_s),
                windows_scored: 10,
                windows_flagged: 0,
                predicted: Predicted::of_flags(highest),
            },
            flags,
            bands_at_s: 4.5,
        }
    }

    fn entry(
        name: &str,
        truth: Truth,
        record: Result<RecordOutcome, String>,
        daemon: DaemonOutcome,
    ) -> Entry {
        let agree = agreement(&record, &daemon);
        Entry {
            manifest: PathBuf::from("m.csv"),
            line: 2,
            file: PathBuf::from(name),
            channel: None,
            truth,
            truth_from: String::new(),
            conditions: None,
            record,
            daemon,
            agree,
            warnings: Vec::new(),
        }
    }

    #[test]
    fn confusion_confident_wrong_and_agreement_are_counted_from_the_entries() {
        use FaultKind::*;
        use Predicted as P;
        let entries = [
            // Right by both, flagged at 6 s.
            entry(
                "a",
                Truth::Fault(InnerRace),
                record(P::Fault(InnerRace)),
                judged(&[(InnerRace, 6.0)]),
            ),
            // analyze misses, the daemon flags the wrong fault and the right one: several.
            entry(
                "b",
                Truth::Fault(OuterRace),
                record(P::None),
                judged(&[(Ball, 5.0), (OuterRace, 8.0)]),
            ),
            // A false alarm by analyze on a healthy record; the daemon stays quiet.
            entry("c", Truth::Healthy, record(P::Fault(Cage)), judged(&[])),
            // Too short for the daemon; truth unknown.
            entry(
                "d",
                Truth::Unknown,
                record(P::None),
                DaemonOutcome::TooShort {
                    seconds: 0.1,
                    needs_s: 5.5,
                    bands_at_s: None,
                },
            ),
            // Both failed with one error.
            entry(
                "e",
                Truth::Healthy,
                Err("unreadable".into()),
                DaemonOutcome::Failed {
                    error: "unreadable".into(),
                },
            ),
            // Both say none on a healthy record.
            entry("f", Truth::Healthy, record(P::None), judged(&[])),
        ];
        let t = tally(&entries);
        assert_eq!(t.entries, 6);
        let r = &t.record;
        assert_eq!(
            (
                r.judged,
                r.right,
                r.missed,
                r.confident_wrong,
                r.false_alarms
            ),
            (4, 2, 1, 1, 1)
        );
        assert_eq!((r.unknown_truth, r.too_short, r.failed), (1, 0, 1));
        assert_eq!(r.confusion["outer_race"]["none"], 1);
        assert_eq!(r.confusion["none"]["cage"], 1);
        assert_eq!(r.confusion["none"]["failed"], 1);
        let d = &t.daemon;
        assert_eq!(
            (
                d.judged,
                d.right,
                d.missed,
                d.confident_wrong,
                d.false_alarms
            ),
            (4, 3, 0, 1, 0)
        );
        assert_eq!((d.unknown_truth, d.too_short, d.failed), (0, 1, 1));
        assert_eq!(d.confusion["outer_race"]["several"], 1);
        assert_eq!(d.confusion["unknown"]["too_short"], 1);
        // Every entry is in each matrix once.
        for p in [r, d] {
            let cells: u64 = p.confusion.values().flat_map(|row| row.values()).sum();
            assert_eq!(cells, 6);
        }
        // Compared: a, b, c, f; b and c disagree.
        assert_eq!((t.compared, t.agree), (4, 2));
        let names: Vec<&str> = t.disagreements.iter().map(|d| d.record.as_str()).collect();
        assert_eq!(names, ["b", "c"]);
        assert_eq!(
            t.disagreements[0].daemon,
            "ball watch from 5.0 s, outer_race watch from 8.0 s"
        );
        assert_eq!(t.disagreements[1].analyze, "cage");
        // First flags: a 6 s, b 5 s; the true fault rose at 6 s (a) and 8 s (b).
        assert_eq!(
            (
                t.first_flag.count,
                t.first_flag.median_s,
                t.first_flag.max_s
            ),
            (2, Some(5.5), Some(6.0))
        );
        assert_eq!(t.detection_delay.median_s, Some(7.0));
        assert_eq!(t.failures, ["e: unreadable"]);
        // Confident wrong: 1 + 1; disagreements 2; failures 1.
        assert_eq!(t.problems(), 5);
        let text = render_recordings(&t);
        assert!(text.contains("too_short"), "{text}");
        assert!(
            text.contains("b: truth outer_race; analyze said none"),
            "{text}"
        );
    }

    #[test]
    fn the_same_fault_pair_or_none_on_both_sides_agrees() {
        use crate::analysis::Verdict;
        use Predicted as P;
        let inner = P::Fault(FaultKind::InnerRace);
        let (ball_or_inner, ball_or_cage) = (
            P::Ambiguous(Verdict::BallOrInner),
            P::Ambiguous(Verdict::BallOrCage),
        );
        assert!(agrees(P::None, P::None));
        assert!(agrees(inner, inner));
        assert!(!agrees(inner, P::None));
        assert!(!agrees(P::None, inner));
        assert!(agrees(ball_or_inner, ball_or_inner));
        assert!(!agrees(ball_or_inner, ball_or_cage));
        assert!(!agrees(ball_or_inner, inner));
        assert!(!agrees(inner, P::Several));
        assert!(!agrees(P::Several, P::Several));
    }
}
