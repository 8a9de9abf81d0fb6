//! `bearingd evaluate --recordings MANIFEST`: real recordings through both ways a user meets
//! the diagnosis, judged against the truth the manifest states, and against each other.
//!
//! Why: the product promises that on a complete recording the faults the daemon flags equal
//! `bearingd analyze`'s verdict. The simulator sweep cannot show that on real machines, and a
//! user comparing them by hand (`import`, then `replay`) does one file at a time. So, for each
//! record (and channel) of a manifest:
//!
//! - the **record path**: exactly `bearingd analyze FILE --channel C` with default settings
//!   ([`crate::offline::analyze_recording`]); the manifest's `fs_hz`/`rpm` are given only where
//!   the file does not state them (CWRU files state both: the rate by their name, `normal_*`
//!   at 48 kHz, the speed in `XNNNRPM`; IMS states its rate; PRONOSTIA states neither speed);
//! - the **daemon path**: the same recording written as `bearingd import` writes it
//!   ([`crate::sinks::mcap::raw_log`]) into a scratch folder, replayed in-process through
//!   [`crate::daemon::replay`] with the log's own settings, as `bearingd replay DIR/*.mcap`
//!   does; a [`Sink`] watches its flag changes. What it says: the fault kinds whose flag rose
//!   (watch or alarm) at any time, and when the first rose. The daemon decides on the evidence
//!   of the whole recording at its end (the import's evidence horizon is the recording), and a
//!   flag rises on evidence that spans the flags' on-delay (1 s with the import's settings): a
//!   record shorter than that, or one the analysis cannot take, is "too short for the daemon",
//!   counted apart, never dropped: its silence would say nothing.
//!
//! Channels: the manifest's (`channel_var`) or the reader's default; IMS snapshots on every
//! channel always (each channel is a bearing of its own, and a 1 s snapshot is cheap). With
//! `all_channels`, CWRU records also on their fan-end and base channels, and every other file
//! on every channel it has. Every channel's truth is the record's: a channel names the kind of
//! defect it sees, not which bearing has it ([`ManifestRecord::truth_on`]).
//!
//! - [`manifest`]: the manifest and the truth of a row.
//! - [`tally`]: confusion matrices, confident-wrong, agreement, delays; the text table.

pub mod manifest;
pub mod tally;

pub use manifest::{Manifest, ManifestError, ManifestRecord, Truth};
pub use tally::{render_recordings, tally, Said, Tally};

use super::outcome::{MonitorOutcome, Predicted, RecordOutcome, WindowFlagCount};
use super::run::record_outcome;
use crate::analysis::agreement::{Agreement, Witness};
use crate::analysis::record::RecordAnalyzer;
use crate::analysis::AnalysisSettings;
use crate::config::Config;
use crate::daemon::events::{DaemonEvent, Events};
use crate::daemon::{replay, ReplayOptions, RunStart};
use crate::messages::{FaultKind, FlagLevel, HealthKind, PipelineMessage};
use crate::offline::{analyze_recording, resolve_conditions, AnalyzeRequest};
use crate::pipeline::{Sink, SinkError};
use crate::recording::{
    detect_format, list_channels, read_recording, ReadOptions, RecordingFormat,
};
use crate::sinks::mcap::raw_log::{import_recording, Import, LogSignal};
use crate::sources::replay::plan::{LoggedSettings, ReplayPlan};
use bearingd::learned::{ModelError, ModelSet};
use bearingd::report::SpeedSource;
use serde::Serialize;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// How to run.
#[derive(Debug, Clone)]
pub struct RecordingsOptions {
    /// Also the other channels of each record (CWRU fan end and base, every IMS/FEMTO axis).
    pub all_channels: bool,
    /// Worker threads.
    pub jobs: usize,
    /// Where the imported logs are written for their replay (a folder of this run's own is
    /// made inside, and removed at the end).
    pub scratch: PathBuf,
    /// The learned model's agreement both paths decide with (`--config`'s `agreement_*` and
    /// `twin.learned_model`), on the records of a bearing the model knows; `None`: the
    /// envelope alone, as `analyze` and `import` default to.
    pub agreement: Option<RecordingsAgreement>,
}

/// The agreement of [`RecordingsOptions::agreement`].
#[derive(Debug, Clone)]
pub struct RecordingsAgreement {
    pub agreement: Agreement,
    /// The model file, for the replay's config.
    pub model_path: PathBuf,
    pub model: Arc<ModelSet>,
}

impl RecordingsAgreement {
    /// The agreement of a config with both `agreement_*` and `twin.learned_model`; `None`
    /// without either.
    pub fn of(config: &Config) -> Result<Option<Self>, ModelError> {
        let (Some(agreement), Some(model_path)) =
            (config.analysis.agreement, config.twin.learned_model.clone())
        else {
            return Ok(None);
        };
        let model = Arc::new(ModelSet::load(&model_path)?);
        Ok(Some(RecordingsAgreement {
            agreement,
            model_path,
            model,
        }))
    }
}

/// What `recordings.json` holds: the run, its summary, and every entry the summary counts.
#[derive(Serialize)]
pub struct RecordingsReport<'a> {
    pub manifests: &'a [PathBuf],
    pub all_channels: bool,
    pub summary: &'a Tally,
    pub entries: &'a [Entry],
}

impl RecordingsReport<'_> {
    pub fn json(&self) -> serde_json::Result<Vec<u8>> {
        serde_json::to_vec_pretty(self)
    }
}

/// One record on one channel.
#[derive(Debug, Clone)]
pub struct Task {
    pub manifest: PathBuf,
    pub record: ManifestRecord,
    /// `None`: the reader's default channel.
    pub channel: Option<String>,
    /// Why this record cannot be run at all (its file is missing or unreadable).
    pub problem: Option<String>,
}

/// What the recording was analysed under.
#[derive(Debug, Clone, Serialize)]
pub struct Conditions {
    pub fs_hz: f64,
    pub rpm: f64,
    pub rpm_from: SpeedSource,
    pub bearing: String,
    pub seconds: f64,
}

/// A rise of a fault flag in the daemon's replay.
#[derive(Debug, Clone, Serialize)]
pub struct FlagChange {
    pub fault: FaultKind,
    pub from: FlagLevel,
    pub to: FlagLevel,
    /// Sample time of the change, s from the record's start.
    pub at_s: f64,
    pub score: f64,
}

/// The daemon path's outcome.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum DaemonOutcome {
    /// The daemon chose bands and scored windows: its flags are its answer.
    Judged {
        #[serde(flatten)]
        monitor: MonitorOutcome,
        /// Every flag change, in order.
        flags: Vec<FlagChange>,
        /// When it first chose its bands (before that a channel raises no flag), s.
        bands_at_s: f64,
    },
    /// The daemon could not raise a flag on this record (no verdict was reached, or the
    /// record is shorter than the flags' on-delay): its silence says nothing.
    TooShort {
        seconds: f64,
        /// What the daemon needs: evidence spanning the on-delay.
        needs_s: f64,
        /// When it chose its first bands, if it did.
        bands_at_s: Option<f64>,
    },
    Failed {
        error: String,
    },
}

/// One record on one channel through both paths.
#[derive(Debug, Clone, Serialize)]
pub struct Entry {
    pub manifest: PathBuf,
    pub line: usize,
    pub file: PathBuf,
    /// The channel read (as the file names it), else the one asked for.
    pub channel: Option<String>,
    pub truth: Truth,
    pub truth_from: String,
    pub conditions: Option<Conditions>,
    /// `Err`: the record path failed (the message says why).
    pub record: Result<RecordOutcome, String>,
    pub daemon: DaemonOutcome,
    /// Whether the daemon's flagged set equals analyze's verdict (`None`: not compared, a
    /// path failed or the record is too short for the daemon).
    pub agree: Option<bool>,
    /// What `analyze` assumed or warned about.
    pub warnings: Vec<String>,
}

impl Entry {
    /// `file [channel]`, for tables and messages.
    pub fn label(&self) -> String {
        let name = self
            .file
            .file_name()
            .map_or(self.file.display().to_string(), |n| {
                n.to_string_lossy().into_owned()
            });
        match &self.channel {
            Some(channel) => format!("{name} [{channel}]"),
            None => name,
        }
    }

    fn failed(task: &Task, channel: Option<String>, error: &str) -> Entry {
        Entry {
            manifest: task.manifest.clone(),
            line: task.record.line,
            file: task.record.file.clone(),
            channel,
            truth: task.record.truth,
            truth_from: task.record.truth_from.clone(),
            conditions: None,
            record: Err(error.to_string()),
            daemon: DaemonOutcome::Failed {
                error: error.to_string(),
            },
            agree: None,
            warnings: Vec::new(),
        }
    }
}

/// Whether two answers agree: the daemon flagged exactly the verdict's fault, exactly the two
/// flags of a pair verdict (`ball_or_inner`: inner race and ball), or nothing for a `none`
/// verdict. Several flags never agree.
pub fn agrees(record: Predicted, daemon: Predicted) -> bool {
    record == daemon && record != Predicted::Several
}

/// Whether the paths agree on an entry; `None` when one has no answer.
pub fn agreement(record: &Result<RecordOutcome, String>, daemon: &DaemonOutcome) -> Option<bool> {
    match (record, daemon) {
        (Ok(r), DaemonOutcome::Judged { monitor, .. }) => {
            Some(agrees(r.predicted, monitor.predicted))
        }
        _ => None,
    }
}

/// The CWRU channel variables' endings: drive end, fan end, base.
const CWRU_CHANNELS: [&str; 3] = ["_DE_time", "_FE_time", "_BA_time"];

/// The records of `manifests` on the channels to evaluate. A file that is missing or whose
/// channels cannot be listed becomes one task with its problem, reported as a failure.
pub fn plan(manifests: &[Manifest], all_channels: bool) -> Vec<Task> {
    let mut tasks = Vec::new();
    for manifest in manifests {
        for record in &manifest.records {
            let task = |channel: Option<String>, problem: Option<String>| Task {
                manifest: manifest.path.clone(),
                record: record.clone(),
                channel,
                problem,
            };
            match channels_of(record, all_channels) {
                Ok(channels) => tasks.extend(channels.into_iter().map(|c| task(c, None))),
                Err(problem) => tasks.push(task(record.channel.clone(), Some(problem))),
            }
        }
    }
    tasks
}

fn channels_of(record: &ManifestRecord, all_channels: bool) -> Result<Vec<Option<String>>, String> {
    let file = &record.file;
    if !file.is_file() {
        return Err(format!(
            "{}: file not found; put the recording there or fix the row's `file`",
            file.display()
        ));
    }
    let listed = || list_channels(file).map_err(|e| e.to_string());
    match &record.channel {
        // A CWRU variable: its siblings of the same record that the file has.
        Some(channel) if all_channels => {
            let Some(own) = CWRU_CHANNELS.iter().find(|s| channel.ends_with(*s)) else {
                return Ok(vec![Some(channel.clone())]);
            };
            let present = listed()?;
            let stem = &channel[..channel.len() - own.len()];
            Ok(CWRU_CHANNELS
                .iter()
                .map(|suffix| format!("{stem}{suffix}"))
                .filter(|name| name == channel || present.contains(name))
                .map(Some)
                .collect())
        }
        Some(channel) => Ok(vec![Some(channel.clone())]),
        None if all_channels || format_of(file)? == RecordingFormat::ImsText => {
            Ok(listed()?.into_iter().map(Some).collect())
        }
        None => Ok(vec![None]),
    }
}

fn format_of(file: &Path) -> Result<RecordingFormat, String> {
    let mut head = Vec::new();
    std::fs::File::open(file)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .map_err(|e| format!("{}: cannot read the file: {e}", file.display()))?;
    detect_format(file, &head).map_err(|e| e.to_string())
}

/// Runs every task on `options.jobs` threads; `progress(done, total, entry)` after each.
/// Entries come back in task order.
pub fn evaluate_recordings(
    tasks: &[Task],
    options: &RecordingsOptions,
    progress: &(dyn Fn(usize, usize, &Entry) + Sync),
) -> Vec<Entry> {
    let scratch = options
        .scratch
        .join(format!(".evaluate-imports-{}", std::process::id()));
    let numbered: Vec<(usize, &Task)> = tasks.iter().enumerate().collect();
    let entries = super::in_order(
        &numbered,
        options.jobs,
        RecordAnalyzer::default,
        |analyzer, (index, task)| {
            let agreement = options.agreement.as_ref();
            evaluate_task(task, &scratch.join(index.to_string()), agreement, analyzer)
        },
        progress,
    );
    let _ = std::fs::remove_dir_all(&scratch);
    entries
}

/// One task through both paths; `scratch` is its own folder for the imported log (removed);
/// both decide with `agreement` when the model knows the record's bearing.
pub fn evaluate_task(
    task: &Task,
    scratch: &Path,
    witness: Option<&RecordingsAgreement>,
    analyzer: &mut RecordAnalyzer,
) -> Entry {
    if let Some(problem) = &task.problem {
        return Entry::failed(task, task.channel.clone(), problem);
    }
    let file = &task.record.file;
    let read = ReadOptions {
        channel: task.channel.clone(),
        column: None,
        unit: None,
    };
    let recording = match read_recording(file, &read) {
        Ok(recording) => recording,
        Err(e) => return Entry::failed(task, task.channel.clone(), &e.to_string()),
    };
    let channel = Some(recording.channel.clone());
    let (truth, truth_from) = task.record.truth_on(&recording.channel);
    // What a user types: `--fs`/`--rpm` only when the file does not say.
    let request = AnalyzeRequest {
        file: Some(file.clone()),
        read,
        fs_hz: task.record.fs_hz.filter(|_| recording.fs_hz.is_none()),
        rpm: task.record.rpm.filter(|_| recording.rpm.is_none()),
        bearing: task.record.bearing.clone(),
        ..AnalyzeRequest::default()
    };
    let conditions = match resolve_conditions(&recording, &request, false) {
        Ok(conditions) => conditions,
        Err(e) => return Entry::failed(task, channel, &e.to_string()),
    };
    let seconds = recording.samples.len() as f64 / conditions.fs_hz;
    let witness = witness.filter(|a| a.model.knows(&conditions.bearing));
    let request = match witness {
        Some(a) => AnalyzeRequest {
            settings: AnalysisSettings {
                agreement: Some(a.agreement),
                ..request.settings
            },
            learned: Some(Arc::clone(&a.model)),
            ..request
        },
        None => request,
    };
    let (record, warnings) = match analyze_recording(&recording, false, &request, analyzer) {
        Ok(outcome) => (
            Ok(record_outcome(
                &outcome.analysis.diagnosis,
                &outcome.analysis,
            )),
            outcome.report.warnings,
        ),
        Err(e) => (Err(e.to_string()), conditions.warnings.clone()),
    };
    let daemon = match import_recording(&Import {
        file,
        signal: LogSignal {
            out: scratch,
            sensor: "imported",
            samples: &recording.samples,
            fs_hz: conditions.fs_hz,
            rpm: conditions.rpm,
            bearing: &conditions.bearing,
        },
    }) {
        Ok(_) => replay_imported(scratch, conditions.fs_hz, seconds, witness),
        Err(e) => DaemonOutcome::Failed {
            error: format!("import: {e}"),
        },
    };
    let _ = std::fs::remove_dir_all(scratch);
    let agree = agreement(&record, &daemon);
    Entry {
        manifest: task.manifest.clone(),
        line: task.record.line,
        file: file.clone(),
        channel,
        truth,
        truth_from,
        conditions: Some(Conditions {
            fs_hz: conditions.fs_hz,
            rpm: conditions.rpm,
            rpm_from: conditions.rpm_source,
            bearing: conditions.bearing.name.clone(),
            seconds,
        }),
        record,
        daemon,
        agree,
        warnings,
    }
}

/// What the watching sink saw of the replay.
#[derive(Debug)]
struct Watched {
    flags: Vec<FlagChange>,
    highest: [FlagLevel; 4],
    windows: WindowFlagCount,
}

impl Default for Watched {
    fn default() -> Self {
        Watched {
            flags: Vec::new(),
            highest: [FlagLevel::Ok; 4],
            windows: WindowFlagCount::default(),
        }
    }
}

/// A sink that watches the replay's messages: flag changes, the first band selection, and
/// the windows scored after it.
struct Watcher {
    fs_hz: f64,
    watched: Arc<Mutex<Watched>>,
}

impl Sink for Watcher {
    fn write(&mut self, message: &PipelineMessage) {
        let mut w = self.watched.lock().unwrap_or_else(|e| e.into_inner());
        match message {
            PipelineMessage::Flag(flag) => {
                let index = flag.fault.index();
                w.windows.flag_changed(flag.fault, flag.to, flag.end_sample);
                w.highest[index] = w.highest[index].max(flag.to);
                w.flags.push(FlagChange {
                    fault: flag.fault,
                    from: flag.from,
                    to: flag.to,
                    at_s: flag.end_sample as f64 / self.fs_hz,
                    score: flag.score,
                });
            }
            PipelineMessage::Health(health) if health.kind == HealthKind::Bands => {
                w.windows.selection(health.end_sample);
            }
            PipelineMessage::Indicators(window) => w.windows.window(window.end_sample),
            _ => {}
        }
    }

    fn finish(&mut self) -> Result<(), SinkError> {
        Ok(())
    }
}

/// Replays the log `bearingd import` wrote into `dir`, as `bearingd replay DIR/*.mcap` does
/// (the log's own settings, with `agreement` and its model added when given), and says what
/// the daemon concluded.
fn replay_imported(
    dir: &Path,
    fs_hz: f64,
    seconds: f64,
    agreement: Option<&RecordingsAgreement>,
) -> DaemonOutcome {
    let failed = |error: String| DaemonOutcome::Failed { error };
    let files = mcap_files(dir);
    let plan = match ReplayPlan::new(&files) {
        Ok(plan) => plan,
        Err(e) => return failed(format!("replay: {e}")),
    };
    let mut config: Config = match plan.logged_settings() {
        LoggedSettings::Logged { config, .. } => *config,
        _ => {
            return failed(format!(
                "replay: the imported log in {} carries no usable settings",
                dir.display()
            ))
        }
    };
    if let Some(a) = agreement {
        config.analysis.agreement = Some(a.agreement);
        config.twin.learned_model = Some(a.model_path.clone());
    }
    let watched = Arc::new(Mutex::new(Watched::default()));
    let unreadable = Arc::new(Mutex::new(Vec::new()));
    let mut open_sinks = |_: &RunStart| -> Result<Vec<Box<dyn Sink>>, SinkError> {
        Ok(vec![Box::new(Watcher {
            fs_hz,
            watched: watched.clone(),
        })])
    };
    let events: Events = {
        let unreadable = unreadable.clone();
        Arc::new(move |event| {
            if let DaemonEvent::ReplayUnreadable(e) = event {
                unreadable
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(e.to_string());
            }
        })
    };
    let replayed = replay(
        &plan,
        &config,
        &ReplayOptions::default(),
        &mut open_sinks,
        &events,
    );
    if let Err(e) = replayed {
        return failed(format!("replay: {e}"));
    }
    if let Some(first) = unreadable.lock().unwrap_or_else(|e| e.into_inner()).first() {
        return failed(format!(
            "replay: the imported log does not read back: {first}"
        ));
    }
    let w = std::mem::take(&mut *watched.lock().unwrap_or_else(|e| e.into_inner()));
    let on_delay_s = config.thresholds.on_delay_s;
    let bands_at_s = w.windows.first_selection().map(|at| at as f64 / fs_hz);
    match bands_at_s {
        Some(at) if on_delay_s <= seconds => DaemonOutcome::Judged {
            monitor: MonitorOutcome {
                highest: w.highest,
                first_flag_s: w.flags.iter().find(|f| f.to > f.from).map(|f| f.at_s),
                windows_scored: w.windows.scored,
                windows_flagged: w.windows.flagged,
                predicted: Predicted::of_flags(w.highest),
            },
            flags: w.flags,
            bands_at_s: at,
        },
        _ => DaemonOutcome::TooShort {
            seconds,
            needs_s: on_delay_s,
            bands_at_s,
        },
    }
}

/// The `.mcap` files directly in `dir`, by name.
fn mcap_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}
