//! False alarms per hour of operation (`bearingd evaluate --false-alarm-hours H`, issue 30
//! item 4): hours of healthy signal through the daemon's channel monitor, every flag that rises
//! counted.
//!
//! Why: the sweep's healthy records last 30 s, a daemon runs for months, and its flags follow a
//! fresh verdict every band period (180 an hour per channel at the default 20 s). A rate too
//! small to show in 126 records can still be an alarm a week per machine, which is what an
//! operator judges the product by. So the sweep's machines, speeds and nuisance, at noise levels
//! of its healthy records, run for hours through [`ChannelMonitor`] with the daemon's settings
//! (the same path as [`super::run`]'s monitor), and each rise from ok is kept with its time,
//! fault and score.
//!
//! Streamed: the simulator fills one block at a time, so an hour costs a block's memory. Each
//! machine's hours are shared equally by its speeds and noise levels, cut into runs of at most
//! [`MAX_RUN_S`] (each a daemon started on a healthy machine, with a seed of its own), which
//! threads share. With no rise in T hours the rate's 95 % upper bound is 3.0/T (Poisson:
//! e^(-λT) = 0.05); with k rises, the exact Poisson bound ([`poisson_upper_95`]).

use super::run::{
    to_counts, witnessed_monitor, Bench, CaseSignal, FlagRise, MonitorWatch, StrongestEvidence,
    BLOCK,
};
use super::sweep::{Case, Machine, NoiseLevel, Sweep};
use crate::analysis::monitor::{ChannelMonitor, MonitorEvent};
use crate::twin::{Nuisance, SimulatedFault, Simulator};
use serde::Serialize;
use std::fmt::Write;

/// The longest run, s of sample time (choice: long against the 20 s band period and the flags'
/// delays, short enough that threads share a few hours evenly and progress moves).
pub const MAX_RUN_S: f64 = 600.0;

/// Keeps the runs' seeds apart from the sweep's healthy records of the same coordinates.
const SEED_STREAM: &str = "false-alarm|";

/// What runs: machines, speeds, noise levels and hours.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FalseAlarmPlan {
    pub seed: u64,
    /// Hours of healthy signal per machine, shared equally by its speeds and noise levels.
    pub hours_per_machine: f64,
    pub machines: Vec<Machine>,
    /// Fractions of each machine's nominal speed.
    pub speed_factors: Vec<f64>,
    pub noise: Vec<NoiseLevel>,
    pub nuisance: Nuisance,
    /// The longest run, s.
    pub max_run_s: f64,
}

/// One run: a healthy case streamed for `seconds` from a fresh monitor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HealthyRun {
    pub case: Case,
    pub seconds: f64,
}

impl FalseAlarmPlan {
    /// The full sweep's machines, speeds (0.6 and 1 × nominal) and nuisance, at four of its
    /// noise levels: −10, 0 and +10 dB (the noise of an outer-race fault of default severity at
    /// that SNR: the quietest leaves the nuisance's tones and impulses the most room) and the
    /// simulator's default.
    pub fn new(hours_per_machine: f64, seed: u64) -> Self {
        let full = Sweep::full(seed);
        FalseAlarmPlan {
            seed,
            hours_per_machine,
            machines: full.machines,
            speed_factors: full.speed_factors,
            noise: vec![
                NoiseLevel::Snr(-10.0),
                NoiseLevel::Snr(0.0),
                NoiseLevel::Snr(10.0),
                NoiseLevel::SimulatorDefault,
            ],
            nuisance: full.nuisance,
            max_run_s: MAX_RUN_S,
        }
    }

    /// Every run, machine by machine, in a fixed order; each machine's runs add up to its hours.
    pub fn runs(&self) -> Vec<HealthyRun> {
        let shares = (self.speed_factors.len() * self.noise.len()).max(1);
        let share_s = self.hours_per_machine * 3600.0 / shares as f64;
        let per_share = (share_s / self.max_run_s.max(1.0)).ceil().max(1.0) as usize;
        let seconds = share_s / per_share as f64;
        let mut runs = Vec::new();
        for (machine_index, machine) in self.machines.iter().enumerate() {
            for &speed in &self.speed_factors {
                for &noise in &self.noise {
                    for repeat in 0..per_share {
                        let mut case = Case {
                            fault: SimulatedFault::None,
                            machine: machine_index,
                            bearing: machine.bearing.name.clone(),
                            rpm: machine.nominal_rpm * speed,
                            severity: 0.0,
                            noise,
                            repeat,
                            seed: 0,
                        };
                        case.seed = case.derive_seed(SEED_STREAM, self.seed);
                        runs.push(HealthyRun { case, seconds });
                    }
                }
            }
        }
        runs
    }

    pub fn total_hours(&self) -> f64 {
        self.hours_per_machine * self.machines.len() as f64
    }
}

/// What one run saw.
#[derive(Debug, Clone, Serialize)]
pub struct RunResult {
    pub run: HealthyRun,
    /// RMS of the broadband noise, g.
    pub noise_g: f64,
    /// Verdicts the flags followed (band selections, the end's included).
    pub decisions: u64,
    /// Every flag that rose from ok (each a false alarm: the machine is healthy).
    pub rises: Vec<FlagRise>,
    /// The fault score that came nearest to being named in any verdict.
    pub strongest: Option<StrongestEvidence>,
}

impl RunResult {
    /// Which case this was: enough to run it again.
    pub fn describe_case(&self) -> String {
        let case = &self.run.case;
        format!(
            "{} at {:.0} rpm, noise {} ({:.3} g), seed {} (run {} of its speed and noise)",
            case.bearing,
            case.rpm,
            case.noise.label(),
            self.noise_g,
            case.seed,
            case.repeat,
        )
    }
}

/// Streams one run's case (healthy, as the plan makes them) through a fresh channel monitor
/// with the daemon's settings, in blocks of the sensor's counts, and ends it as a clean stop
/// does ([`ChannelMonitor::finish`]).
pub fn stream_run(bench: &Bench, plan: &FalseAlarmPlan, run: &HealthyRun) -> RunResult {
    let machine = &plan.machines[run.case.machine];
    let signal = CaseSignal::of(&run.case, machine, &plan.nuisance);
    let freqs = signal.params.frequencies();
    let total = (run.seconds * signal.params.fs_hz).round() as u64;
    let scale = bench.scale_g_per_count();
    let settings = bench.monitor_settings(machine, run.case.rpm);
    let mut watch = MonitorWatch::new(&settings);
    let mut see = |event: MonitorEvent| watch.see(event);
    let mut monitor = witnessed_monitor(
        ChannelMonitor::new(settings, freqs, None),
        bench.witness_for(machine),
    );
    let mut simulator = Simulator::new(signal.params);
    let mut block = vec![0f32; BLOCK];
    let mut counts = Vec::with_capacity(BLOCK);
    while simulator.next_sample() < total {
        let first = simulator.next_sample();
        let n = (total - first).min(BLOCK as u64) as usize;
        simulator.fill(&mut block[..n]);
        to_counts(&block[..n], scale, &mut counts);
        monitor.push_counts(first, &counts, scale, &mut see);
    }
    monitor.finish(&mut see);
    RunResult {
        run: run.clone(),
        noise_g: signal.noise_g,
        decisions: watch.decisions(),
        rises: watch.rises().to_vec(),
        strongest: watch.strongest(),
    }
}

/// Hours, decisions and flag rises of a group of runs.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Tally {
    pub label: String,
    pub hours: f64,
    pub decisions: u64,
    pub rises: u64,
    /// The fault score nearest to being named in any of the verdicts, and its run's case.
    pub strongest: Option<(StrongestEvidence, String)>,
}

impl Tally {
    fn add(&mut self, result: &RunResult) {
        self.hours += result.run.seconds / 3600.0;
        self.decisions += result.decisions;
        self.rises += result.rises.len() as u64;
        if let Some(evidence) = result.strongest {
            if self
                .strongest
                .as_ref()
                .is_none_or(|(s, _)| evidence.margin > s.margin)
            {
                self.strongest = Some((evidence, result.describe_case()));
            }
        }
    }

    pub fn rises_per_hour(&self) -> f64 {
        self.rises as f64 / self.hours.max(f64::MIN_POSITIVE)
    }

    /// The 95 % upper bound of the rate of rises per hour.
    pub fn upper_95_per_hour(&self) -> f64 {
        poisson_upper_95(self.rises) / self.hours.max(f64::MIN_POSITIVE)
    }

    pub fn decisions_per_hour(&self) -> f64 {
        self.decisions as f64 / self.hours.max(f64::MIN_POSITIVE)
    }
}

/// The runs' numbers: per machine, per noise level and overall, and every rise.
#[derive(Debug, Clone, Serialize)]
pub struct FalseAlarmSummary {
    pub machines: Vec<Tally>,
    pub noise_levels: Vec<Tally>,
    pub all: Tally,
    /// Each rise with the case it came from ([`RunResult::describe_case`]).
    pub rises: Vec<String>,
}

/// Adds `result` to the tally labelled `label`, made if new (kept in first-seen order).
fn tally_into(tallies: &mut Vec<Tally>, label: String, result: &RunResult) {
    let index = match tallies.iter().position(|t| t.label == label) {
        Some(index) => index,
        None => {
            tallies.push(Tally {
                label,
                ..Tally::default()
            });
            tallies.len() - 1
        }
    };
    tallies[index].add(result);
}

pub fn summarize_false_alarms(results: &[RunResult]) -> FalseAlarmSummary {
    let mut machines = Vec::new();
    let mut noise_levels = Vec::new();
    let mut all = Tally {
        label: "all".into(),
        ..Tally::default()
    };
    for result in results {
        tally_into(&mut machines, result.run.case.bearing.clone(), result);
        tally_into(&mut noise_levels, result.run.case.noise.label(), result);
        all.add(result);
    }
    let rises = results
        .iter()
        .flat_map(|r| {
            r.rises
                .iter()
                .map(|rise| format!("{}: {}", r.describe_case(), rise.describe()))
        })
        .collect();
    FalseAlarmSummary {
        machines,
        noise_levels,
        all,
        rises,
    }
}

/// The summary as a text table, for a terminal.
pub fn render_false_alarms(summary: &FalseAlarmSummary) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "== false alarms per hour of operation (healthy machines, the daemon's channel monitor) =="
    );
    let _ = writeln!(
        out,
        "{:<16}{:>9}{:>11}{:>13}{:>12}{:>11}{:>20}",
        "", "hours", "decisions", "decisions/h", "flag rises", "rises/h", "95 % upper, /h"
    );
    let rows = summary
        .machines
        .iter()
        .chain(&summary.noise_levels)
        .chain(std::iter::once(&summary.all));
    for t in rows {
        let _ = writeln!(
            out,
            "{:<16}{:>9.2}{:>11}{:>13.1}{:>12}{:>11.3}{:>20.3}",
            t.label,
            t.hours,
            t.decisions,
            t.decisions_per_hour(),
            t.rises,
            t.rises_per_hour(),
            t.upper_95_per_hour()
        );
    }
    let _ = writeln!(
        out,
        "nearest to being named (naming margin in log units; > 0 large and significant enough \
         were no other fault near):"
    );
    for t in summary.machines.iter().chain(std::iter::once(&summary.all)) {
        if let Some((evidence, case)) = &t.strongest {
            let _ = writeln!(out, "  {}: {} on {case}", t.label, evidence.describe());
        }
    }
    if summary.rises.is_empty() {
        let _ = writeln!(out, "no flag rose");
    } else {
        let _ = writeln!(out, "flags that rose (each a false alarm):");
        for rise in &summary.rises {
            let _ = writeln!(out, "  {rise}");
        }
    }
    out
}

/// The 95 % upper confidence bound of a Poisson mean after `k` events (one-sided: the mean at
/// which `k` or fewer events have probability 0.05); 2.996 for none.
pub fn poisson_upper_95(k: u64) -> f64 {
    let at_most_k = |mean: f64| {
        let mut term = (-mean).exp();
        let mut sum = term;
        for i in 1..=k {
            term *= mean / i as f64;
            sum += term;
        }
        sum
    };
    // P(X ≤ k) falls with the mean: bisect between 0 and a mean far above k.
    let (mut low, mut high) = (0.0, 10.0 + 2.0 * k as f64);
    for _ in 0..100 {
        let mid = 0.5 * (low + high);
        if at_most_k(mid) > 0.05 {
            low = mid;
        } else {
            high = mid;
        }
    }
    0.5 * (low + high)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poisson_bounds_match_the_tables() {
        // Garwood's exact one-sided 95 % bounds: 2.996, 4.744, 6.296, 16.96 (k = 10).
        for (k, bound) in [(0, 2.996), (1, 4.744), (2, 6.296), (10, 16.96)] {
            let got = poisson_upper_95(k);
            assert!((got - bound).abs() < 0.01, "k = {k}: {got} (want {bound})");
        }
    }

    #[test]
    fn runs_add_up_to_the_hours_with_seeds_of_their_own() {
        let plan = FalseAlarmPlan::new(2.0, 5);
        let runs = plan.runs();
        for machine in 0..plan.machines.len() {
            let seconds: f64 = runs
                .iter()
                .filter(|r| r.case.machine == machine)
                .map(|r| r.seconds)
                .sum();
            assert!(
                (seconds - 7200.0).abs() < 1e-6,
                "machine {machine}: {seconds} s"
            );
        }
        assert!(runs.iter().all(|r| r.seconds <= MAX_RUN_S));
        let mut seeds: Vec<u64> = runs.iter().map(|r| r.case.seed).collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), runs.len(), "two runs share a seed");
        let sweep = Sweep::full(5).cases();
        assert!(
            !sweep.iter().any(|c| seeds.binary_search(&c.seed).is_ok()),
            "a run repeats a sweep record"
        );
    }
}
