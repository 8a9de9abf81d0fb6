//! One case through the real pipeline, both ways a user meets it:
//!
//! - the record path of `bearingd analyze` ([`RecordAnalyzer`] → the diagnosis), on the first
//!   [`Sweep::record_s`] seconds;
//! - the daemon's per-channel monitor ([`ChannelMonitor`], as `run` and `replay` drive it, with
//!   the settings the daemon derives from the embedded default config), fed the whole record
//!   as the sensor's integer counts in blocks with their sample positions, in sample time.

use super::agreement::grid_verdicts;
use super::outcome::{CaseResult, MonitorOutcome, Predicted, RecordOutcome, WindowFlagCount};
use super::sweep::{Case, Machine, NoiseLevel, Sweep, DEFAULT_SEVERITY};
use crate::analysis::agreement::Witness;
use crate::analysis::diagnosis::DecisionRule;
use crate::analysis::monitor::{ChannelMonitor, MonitorEvent, MonitorSettings};
use crate::analysis::record::RecordAnalyzer;
use crate::analysis::{AnalysisSettings, Diagnosis};
use crate::config::{Config, SensorConfig, SimConfig, Speed, Transport};
use crate::messages::FaultKind;
use crate::messages::FlagLevel;
use crate::pipeline::{load_learned, monitor_settings};
use crate::twin::{Nuisance, SimulatedFault, SimulationParams, Simulator};
use bearingd::learned::ModelError;
use serde::Serialize;
use std::sync::Arc;

/// What every case of a sweep shares: the daemon's settings, and the learned model its
/// verdicts hear (`twin.learned_model`, with `analysis.agreement_*`).
pub struct Bench {
    pub config: Config,
    pub witness: Option<Arc<dyn Witness>>,
}

impl Bench {
    /// The embedded default config: the analysis and flag settings a new user's daemon runs.
    pub fn embedded() -> Result<Self, String> {
        let config = Config::default_embedded().map_err(|e| e.to_string())?;
        Bench::new(config).map_err(|e| e.to_string())
    }

    /// A bench with `config`'s settings and its learned model, loaded once.
    pub fn new(config: Config) -> Result<Self, ModelError> {
        let witness = load_learned(&config.twin)?.map(|m| m as Arc<dyn Witness>);
        Ok(Bench { config, witness })
    }

    /// The witness, if it knows `machine`'s bearing (the model is trained for one geometry).
    pub fn witness_for(&self, machine: &Machine) -> Option<&Arc<dyn Witness>> {
        self.witness.as_ref().filter(|w| w.knows(&machine.bearing))
    }

    pub fn analysis(&self) -> &AnalysisSettings {
        &self.config.analysis
    }

    /// The sensor's scale, g per count: the config's first sensor's (the embedded default's:
    /// ±16 g in an i16).
    pub fn scale_g_per_count(&self) -> f64 {
        self.config
            .sensors
            .first()
            .map_or(0.000_488, |s| s.scale_g_per_count)
    }

    /// The monitor settings the daemon would derive for a sensor on `machine` at `rpm`.
    pub fn monitor_settings(&self, machine: &Machine, rpm: f64) -> MonitorSettings {
        let sensor = SensorConfig {
            id: "evaluate".into(),
            transport: Transport::Sim(SimConfig::default()),
            sample_rate_hz: machine.fs_hz,
            scale_g_per_count: self.scale_g_per_count(),
            axes: vec!["radial".into()],
            bearing: machine.bearing.clone(),
            speed: Speed::Fixed { rpm },
        };
        MonitorSettings {
            // The sweep judges the envelope decision; the velocity zones are not part of it.
            detectors: Default::default(),
            ..monitor_settings(&self.config, &sensor, 0, 1)
        }
    }
}

/// The simulation parameters of a case, noise not yet set.
fn params_of(case: &Case, machine: &Machine, nuisance: &Nuisance) -> SimulationParams {
    SimulationParams {
        fault: case.fault,
        rpm: case.rpm,
        bearing: machine.bearing.clone(),
        fs_hz: machine.fs_hz,
        amplitude_g: case.severity,
        resonance_hz: machine.resonance_hz,
        nuisance: nuisance.clone(),
        seed: case.seed,
        ..SimulationParams::example(case.fault)
    }
}

/// Seconds of noiseless signal the fault's RMS is measured over.
const RMS_SECONDS: f64 = 4.0;

/// RMS of the fault's own signal (no noise, no tones, no nuisance), g.
fn fault_rms_g(params: &SimulationParams) -> f64 {
    let quiet = SimulationParams {
        noise_g: 0.0,
        shaft_tone_g: 0.0,
        nuisance: Nuisance::none(),
        ..params.clone()
    };
    let samples = Simulator::record(quiet, RMS_SECONDS);
    let power: f64 =
        samples.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / samples.len().max(1) as f64;
    power.sqrt()
}

/// Samples per block fed to the monitor (0.1 s at 12 kHz, like a sensor's frames batched).
pub(super) const BLOCK: usize = 1200;

/// What a case simulates: the simulator's parameters with the case's noise set, and the noise
/// and SNR that gives.
pub struct CaseSignal {
    pub params: SimulationParams,
    /// RMS of the broadband noise (white and shaft-modulated), g.
    pub noise_g: f64,
    /// The fault's RMS over the broadband noise's, dB (`None` for healthy records).
    pub snr_db: Option<f64>,
}

impl CaseSignal {
    /// The signal of `case` on `machine` with `nuisance`: an SNR sets the broadband noise (the
    /// white noise and the nuisance's shaft-modulated noise together, in the preset's
    /// proportion between them) against the fault's RMS, or for a healthy case against an
    /// outer-race fault's of the default severity.
    pub fn of(case: &Case, machine: &Machine, nuisance: &Nuisance) -> Self {
        let mut params = params_of(case, machine, nuisance);
        let fault_rms = fault_rms_g(&params);
        let modulation_power = 1.0 + 0.5 * params.nuisance.modulation_depth.powi(2);
        let modulated_per_white = params.nuisance.modulated_noise_g / params.noise_g.max(1e-12);
        let broadband_per_white = (1.0 + modulated_per_white.powi(2) * modulation_power).sqrt();
        if let NoiseLevel::Snr(db) = case.noise {
            let reference = if case.fault == SimulatedFault::None {
                let outer = Case {
                    fault: SimulatedFault::OuterRace,
                    severity: DEFAULT_SEVERITY,
                    ..case.clone()
                };
                fault_rms_g(&params_of(&outer, machine, &Nuisance::none()))
            } else {
                fault_rms
            };
            let broadband = reference / 10f64.powf(db / 20.0);
            params.noise_g = broadband / broadband_per_white;
            params.nuisance.modulated_noise_g = modulated_per_white * params.noise_g;
        }
        let noise_g = params.noise_g * broadband_per_white;
        let snr_db = (case.fault != SimulatedFault::None && noise_g > 0.0)
            .then(|| 20.0 * (fault_rms / noise_g).log10());
        CaseSignal {
            params,
            noise_g,
            snr_db,
        }
    }
}

/// Runs one case through both paths.
pub fn run_case(
    bench: &Bench,
    sweep: &Sweep,
    case: &Case,
    analyzer: &mut RecordAnalyzer,
) -> CaseResult {
    let machine = &sweep.machines[case.machine];
    let CaseSignal {
        params,
        noise_g,
        snr_db,
    } = CaseSignal::of(case, machine, &sweep.nuisance);
    let freqs = params.frequencies();
    let fs = params.fs_hz;
    let signal = Simulator::record(params, sweep.monitor_s);

    let record_len = ((sweep.record_s * fs).round() as usize).min(signal.len());
    let witness = bench.witness_for(machine);
    let record = analyzer
        .analyze(&signal[..record_len], fs, &freqs, bench.analysis())
        .map(|mut analysis| {
            let Some(witness) = witness else {
                return record_outcome(&analysis.diagnosis, &analysis);
            };
            let opinion = witness
                .witness(&signal[..record_len], fs, &freqs)
                .ok()
                .flatten();
            let grid = grid_verdicts(&analysis, bench.analysis(), opinion);
            analysis.hear_witness(opinion, bench.analysis());
            RecordOutcome {
                learned: opinion,
                agreement_grid: grid,
                ..record_outcome(&analysis.diagnosis, &analysis)
            }
        })
        .map_err(|e| e.to_string());

    let settings = bench.monitor_settings(machine, case.rpm);
    let scale = bench.scale_g_per_count();
    let mut counts = Vec::new();
    to_counts(&signal, scale, &mut counts);
    let monitor = run_monitor(settings, freqs, &counts, scale, witness);

    CaseResult {
        case: case.clone(),
        noise_g,
        snr_db,
        record,
        monitor,
    }
}

/// `monitor`, hearing `witness` if there is one.
pub fn witnessed_monitor(
    monitor: ChannelMonitor,
    witness: Option<&Arc<dyn Witness>>,
) -> ChannelMonitor {
    match witness {
        Some(witness) => monitor.with_witness(Arc::clone(witness)),
        None => monitor,
    }
}

/// The sensor's integer counts of a signal in g (rounded, clamped to the i16 range), into
/// `counts` (cleared first).
pub fn to_counts(signal: &[f32], scale_g_per_count: f64, counts: &mut Vec<i16>) {
    counts.clear();
    counts.extend(signal.iter().map(|&g| {
        (f64::from(g) / scale_g_per_count)
            .round()
            .clamp(-32768.0, 32767.0) as i16
    }));
}

/// What the record path concluded, from its analysis.
pub fn record_outcome(
    diagnosis: &Diagnosis,
    analysis: &crate::analysis::RecordAnalysis,
) -> RecordOutcome {
    RecordOutcome {
        verdict: diagnosis.verdict.name().to_string(),
        predicted: Predicted::of_verdict(diagnosis.verdict),
        confidence: diagnosis.confidence,
        reason: diagnosis.reason.clone(),
        candidates: diagnosis.candidates.clone(),
        scores: FaultKind::ALL.map(|kind| analysis.score(kind)),
        learned: None,
        agreement_grid: Vec::new(),
    }
}

/// A flag that rose from ok: which fault, to what level, when, and the verdict it followed.
#[derive(Debug, Clone, Serialize)]
pub struct FlagRise {
    pub fault: FaultKind,
    pub level: FlagLevel,
    /// Sample time of the rise, s from the start of the run.
    pub at_s: f64,
    /// The fault's score in the verdict's evidence, its comb's frequency, and the largest
    /// score of the other faults.
    pub score: f64,
    pub frequency_hz: f64,
    pub runner_up: f64,
}

impl FlagRise {
    pub fn describe(&self) -> String {
        format!(
            "{} {} at {:.1} s (score {:.1} at {:.1} Hz, runner-up {:.1})",
            self.fault.name(),
            self.level.name(),
            self.at_s,
            self.score,
            self.frequency_hz,
            self.runner_up
        )
    }
}

/// The fault score of a verdict's evidence that came nearest to being named on its own size and
/// significance ([`DecisionRule::naming_margin`]): on a healthy machine, how near a run came
/// to a false alarm.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StrongestEvidence {
    pub fault: FaultKind,
    /// Sample time of the verdict, s from the start of the run.
    pub at_s: f64,
    pub score: f64,
    /// `−log10` p of the comb against noise.
    pub significance: f64,
    /// Log units: positive when the comb was large and significant enough to be named, were no
    /// other fault near it; −0.69 is half the size (or 0.3 decades short of the significance)
    /// it needed.
    pub margin: f64,
}

impl StrongestEvidence {
    pub fn describe(&self) -> String {
        format!(
            "{} {:.1} at p = 10^-{:.1}, margin {:+.2} (at {:.0} s)",
            self.fault.name(),
            self.score,
            self.significance,
            self.margin,
            self.at_s
        )
    }
}

/// Watches a channel monitor's events: each flag's level and the highest it reached, the rises
/// from ok, the decisions (band selections with their verdict), the strongest evidence of any
/// of them, and the windows scored after the first one.
pub struct MonitorWatch {
    fs_hz: f64,
    rule: DecisionRule,
    strongest: Option<StrongestEvidence>,
    highest: [FlagLevel; 4],
    rises: Vec<FlagRise>,
    decisions: u64,
    windows: WindowFlagCount,
}

impl MonitorWatch {
    /// For a monitor with `settings`.
    pub fn new(settings: &MonitorSettings) -> Self {
        MonitorWatch {
            fs_hz: settings.fs_hz,
            rule: settings.analysis.decision_rule(),
            strongest: None,
            highest: [FlagLevel::Ok; 4],
            rises: Vec::new(),
            decisions: 0,
            windows: WindowFlagCount::default(),
        }
    }

    pub fn see(&mut self, event: MonitorEvent) {
        match event {
            MonitorEvent::Bands {
                evidence,
                at_sample,
                ..
            } => {
                self.decisions += 1;
                self.windows.selection(at_sample);
                for score in evidence.iter().flat_map(|e| e.scores.iter()) {
                    let margin = self.rule.naming_margin(score);
                    if self.strongest.is_none_or(|s| margin > s.margin) {
                        self.strongest = Some(StrongestEvidence {
                            fault: score.fault,
                            at_s: at_sample as f64 / self.fs_hz,
                            score: score.score,
                            significance: score.significance,
                            margin,
                        });
                    }
                }
            }
            MonitorEvent::Flag {
                fault,
                change,
                score,
                frequency_hz,
                runner_up,
            } => {
                let index = fault.index();
                self.windows
                    .flag_changed(fault, change.to, change.at_sample);
                self.highest[index] = self.highest[index].max(change.to);
                if change.from == FlagLevel::Ok && change.to > FlagLevel::Ok {
                    self.rises.push(FlagRise {
                        fault,
                        level: change.to,
                        at_s: change.at_sample as f64 / self.fs_hz,
                        score,
                        frequency_hz,
                        runner_up,
                    });
                }
            }
            MonitorEvent::Window(w) => self.windows.window(w.end_sample),
            _ => {}
        }
    }

    /// The rises from ok so far, in order.
    pub fn rises(&self) -> &[FlagRise] {
        &self.rises
    }

    /// Band selections so far: each a verdict the flags followed.
    pub fn decisions(&self) -> u64 {
        self.decisions
    }

    pub fn strongest(&self) -> Option<StrongestEvidence> {
        self.strongest
    }

    pub fn outcome(&self) -> MonitorOutcome {
        MonitorOutcome {
            highest: self.highest,
            first_flag_s: self.rises.first().map(|rise| rise.at_s),
            windows_scored: self.windows.scored,
            windows_flagged: self.windows.flagged,
            predicted: Predicted::of_flags(self.highest),
        }
    }
}

/// Feeds the counts to a fresh channel monitor block by block and watches its flags.
fn run_monitor(
    settings: MonitorSettings,
    freqs: crate::bearing::FaultFrequencies,
    counts: &[i16],
    scale: f64,
    witness: Option<&Arc<dyn Witness>>,
) -> MonitorOutcome {
    let mut watch = MonitorWatch::new(&settings);
    let mut see = |event: MonitorEvent| watch.see(event);
    let mut monitor = witnessed_monitor(ChannelMonitor::new(settings, freqs, None), witness);
    for (i, block) in counts.chunks(BLOCK).enumerate() {
        monitor.push_counts((i * BLOCK) as u64, block, scale, &mut see);
    }
    // The record's end, as a replay's: the last verdict on what was not analysed yet.
    monitor.finish(&mut see);
    watch.outcome()
}
