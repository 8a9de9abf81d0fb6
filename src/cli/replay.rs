//! `bearingd replay LOG.mcap...`: logged raw samples through the same pipeline, into a new log.
//!
//! Says every decision that could make a replay differ from the live run: where the settings
//! come from (the log, `--config`, or the embedded default for a log without them) and what an
//! override changes, the order the files are read in, run boundaries, gaps and what could not
//! be read.

use super::format::FormatOrJsonArg;
use super::progress::ProgressLine;
use super::run::{event_line, print_events};
use super::CliError;
use crate::config::{self, Config};
use crate::daemon::events::{DaemonEvent, Events};
use crate::daemon::lock::DirLock;
use crate::daemon::{assemble, replay, BaselinesFrom, ReplayOptions, ReplaySummary, RunStart};
use crate::daemon::{SinkPlan, Sinks};
use crate::mcap_log::files::utc_text;
use crate::mcap_log::LogHeader;
use crate::pipeline::{Sink, SinkError};
use crate::sources::replay::plan::{differences, file_list, LoggedSettings, ReplayPlan};
use clap::Args;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

#[derive(Args)]
pub struct ReplayArgs {
    /// MCAP logs written by `bearingd run` (or `bearingd import`), in any order: they are
    /// replayed by run, then by their sequence in the run.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Analyse with this configuration instead of the one the log was recorded with (needed
    /// for logs without it: older files, `bearingd import`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Replay speed: 1 = real time; default: as fast as possible.
    #[arg(long)]
    speed: Option<f64>,
    /// Directory of the replay's own MCAP log.
    #[arg(long, default_value = "bearingd-replay")]
    out: PathBuf,
    /// No progress (neither the bar on a terminal nor the lines elsewhere).
    #[arg(long)]
    quiet: bool,
    // With json, the summary as one line of JSON (flags with their sample times).
    #[command(flatten)]
    format: FormatOrJsonArg,
}

/// Where the replay's settings came from.
#[derive(Clone, Copy, serde::Serialize)]
#[serde(rename_all = "snake_case")]
enum SettingsFrom {
    Log,
    Config,
    EmbeddedDefault,
}

pub fn run(args: &ReplayArgs) -> Result<(), CliError> {
    // What the replay creates is never more open than 0750/0640, whatever umask it inherits.
    crate::fsafe::restrict_umask();
    if let Some(speed) = args.speed {
        if !(speed.is_finite() && speed > 0.0) {
            return Err(CliError::input(format!(
                "--speed {speed} is not a speed; give a factor of real time, e.g. --speed 1"
            )));
        }
    }
    for file in &args.files {
        if !file.is_file() {
            return Err(CliError::input(format!(
                "{}: not found; give the path of an MCAP log",
                file.display()
            )));
        }
        check_mcap_magic(file)?;
    }
    let plan = ReplayPlan::new(&args.files).map_err(CliError::input)?;
    plan.files.iter().try_for_each(check_holds_a_message)?;
    if plan.reordered {
        eprintln!(
            "bearingd: replay: reading the files by run and sequence, not in the order given: {}",
            file_list(
                &plan
                    .files
                    .iter()
                    .map(|f| f.path.clone())
                    .collect::<Vec<_>>()
            )
        );
    }
    let (mut config, from, config_differences) = resolve_settings(args, &plan)?;
    config.outputs.mcap_dir = args.out.clone();
    // The output directory has one owner too: recovery at open would otherwise rewrite the
    // open file of a daemon (or another replay) writing there.
    // Created 0750, and refused if others can write in it (they could plant links there).
    crate::fsafe::prepare_private_dir(&args.out).map_err(CliError::input)?;
    let _lock = DirLock::acquire(&args.out).map_err(CliError::input)?;
    let bar = progress_line(args);
    let options = ReplayOptions {
        speed: args.speed,
        progress_every: match (&bar, args.quiet) {
            (Some(_), _) => Some(Duration::from_millis(100)),
            (None, false) => Some(Duration::from_secs(1)),
            (None, true) => None,
        },
    };
    let events = match &bar {
        Some(bar) => line_events(Arc::clone(bar)),
        None => print_events(args.format.json()),
    };
    let mut open_sinks = |run: &RunStart| -> Result<Vec<Box<dyn Sink>>, SinkError> {
        let sinks = assemble(
            &config,
            SinkPlan::replay(Vec::new()),
            &run.sink_start(),
            &events,
        )?;
        Ok(Sinks::all(sinks))
    };
    let replayed = replay(&plan, &config.clone(), &options, &mut open_sinks, &events);
    if let Some(bar) = &bar {
        bar.clear();
    }
    let summary = replayed.map_err(CliError::failure)?;
    if args.format.json() {
        print_json(&summary, &plan, from, &config_differences);
    } else {
        print_text(&summary, &args.out);
    }
    report_boundaries_and_losses(&summary, &plan);
    Ok(())
}

/// The config to analyse with, where it came from, and how an override differs from the log;
/// each decision said on stderr.
fn resolve_settings(
    args: &ReplayArgs,
    plan: &ReplayPlan,
) -> Result<(Config, SettingsFrom, Vec<String>), CliError> {
    let logged = plan.logged_settings();
    if let Some(path) = &args.config {
        let given = config::load(path).map_err(CliError::input)?;
        eprintln!(
            "bearingd: replay: analysing with --config {}, not with the settings the log was recorded with",
            path.display()
        );
        let lines = match &logged {
            LoggedSettings::Logged { config, .. } => differences(config, &given),
            LoggedSettings::Disagree(groups) => vec![format!(
                "the files were recorded with {} different settings",
                groups.len()
            )],
            LoggedSettings::Absent | LoggedSettings::Unusable { .. } => Vec::new(),
        };
        if lines.is_empty() && matches!(logged, LoggedSettings::Logged { .. }) {
            eprintln!("bearingd: replay: --config has the log's rates, geometry and settings");
        }
        for line in &lines {
            eprintln!("bearingd: replay: --config differs from the log: {line}");
        }
        return Ok((given, SettingsFrom::Config, lines));
    }
    match logged {
        LoggedSettings::Logged {
            config,
            files_without,
        } => {
            let sensors: Vec<String> = config
                .sensors
                .iter()
                .map(|s| format!("{} at {} Hz on {}", s.id, s.sample_rate_hz, s.bearing.name))
                .collect();
            eprintln!(
                "bearingd: replay: settings from the log: {} (give --config to override)",
                sensors.join("; ")
            );
            if !files_without.is_empty() {
                eprintln!(
                    "bearingd: replay: {} carry no settings of their own and are analysed with the log's",
                    file_list(&files_without)
                );
            }
            Ok((*config, SettingsFrom::Log, Vec::new()))
        }
        LoggedSettings::Absent => {
            eprintln!(
                "bearingd: replay: the log carries no settings (written by an older bearingd or \
                 by `bearingd import`): analysing with the embedded default's; give --config to choose"
            );
            let config = Config::default_embedded().map_err(CliError::failure)?;
            Ok((config, SettingsFrom::EmbeddedDefault, Vec::new()))
        }
        LoggedSettings::Disagree(groups) => Err(CliError::input(format!(
            "the files were recorded with different settings: {}; replay each group on its \
             own, or give --config to analyse them all with one",
            groups
                .iter()
                .map(|g| format!("[{}]", file_list(g)))
                .collect::<Vec<_>>()
                .join(" vs ")
        ))),
        LoggedSettings::Unusable { path, problem } => Err(CliError::input(format!(
            "{}: {problem}; give --config to replay it with a configuration of your own",
            path.display()
        ))),
    }
}

/// A progress line over the bytes of the files, when stderr is a terminal and not `--quiet`.
fn progress_line(args: &ReplayArgs) -> Option<Arc<ProgressLine>> {
    if args.quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    Some(Arc::new(ProgressLine::default()))
}

/// Events to stderr above the progress line; progress redraws the line.
fn line_events(line: Arc<ProgressLine>) -> Events {
    Arc::new(move |event| match event {
        DaemonEvent::ReplayProgress {
            sample_seconds,
            bytes_read,
            bytes_total,
            flag_changes,
            ..
        } => line.show(
            bytes_read,
            bytes_total,
            &format!("{sample_seconds:.0} s, {flag_changes} flag changes"),
        ),
        other => line.print_above(&event_line(&other)),
    })
}

fn print_json(
    summary: &ReplaySummary,
    plan: &ReplayPlan,
    from: SettingsFrom,
    config_differences: &[String],
) {
    let read = &summary.read;
    let runs: Vec<_> = summary
        .runs
        .iter()
        .map(|r| {
            serde_json::json!({
                "run_id": r.run_id,
                "origin_ns": r.origin_ns,
                "origin_utc": utc_text(r.origin_ns),
                "first_file": r.first_file,
                "baselines_from": r.baselines_from,
            })
        })
        .collect();
    let json = serde_json::json!({
        "raw_blocks": summary.raw_blocks,
        "samples": summary.samples,
        "sample_seconds": summary.sample_seconds,
        "elapsed_s": summary.elapsed.as_secs_f64(),
        "settings_from": from,
        "config_differences": config_differences,
        "order": plan.files.iter().map(|f| &f.path).collect::<Vec<_>>(),
        "reordered": plan.reordered,
        "runs": runs,
        "run_boundaries": summary.runs.len().saturating_sub(1),
        "gaps": summary.gaps,
        "gap_count": summary.gap_count,
        "gap_seconds": summary.gap_seconds,
        "missing_files": plan.missing,
        "unreadable_bytes": read.unreadable_bytes(),
        "unfinished_files": read.unfinished_files(),
        "undecodable_messages": read.undecodable_messages(),
        "unknown_channels": summary.unknown_channels,
        "flags": summary.flags,
    });
    println!("{json}");
}

fn print_text(summary: &ReplaySummary, out: &Path) {
    for flag in &summary.flags {
        println!("{}", super::run::flag_recap(flag));
    }
    println!(
        "replayed {} blocks, {} samples ({:.1} s of signal) in {} run(s) in {:.2} s ({:.0}× real time); output in {}",
        summary.raw_blocks,
        summary.samples,
        summary.sample_seconds,
        summary.runs.len(),
        summary.elapsed.as_secs_f64(),
        summary.sample_seconds / summary.elapsed.as_secs_f64().max(1e-9),
        out.display()
    );
}

/// Where a replayed run's starting health baselines came from, for stderr.
fn baselines_said(run: &RunStart) -> String {
    match run.baselines_from {
        BaselinesFrom::Log => format!(
            "from the {} channel baseline(s) the daemon loaded then (the log's record)",
            run.baselines.len()
        ),
        BaselinesFrom::PreviousRun => "from the baselines the run before reached (the log does \
                                       not record what the daemon loaded)"
            .to_string(),
        BaselinesFrom::None => "learning its baselines from scratch".to_string(),
        BaselinesFrom::UnreadableRecord => format!(
            "{}: the log's bearingd.state record does not read",
            if run.baselines.is_empty() {
                "learning its baselines from scratch"
            } else {
                "from the baselines the run before reached"
            }
        ),
    }
}

/// Run boundaries, gaps, missing files and what could not be read, on stderr.
fn report_boundaries_and_losses(summary: &ReplaySummary, plan: &ReplayPlan) {
    if let Some(first) = summary
        .runs
        .first()
        .filter(|r| r.baselines_from == BaselinesFrom::UnreadableRecord)
    {
        eprintln!(
            "bearingd: replay: {}: {}",
            first.first_file.display(),
            baselines_said(first)
        );
    }
    for pair in summary.runs.windows(2) {
        let (before, after) = (&pair[0], &pair[1]);
        let baselines = baselines_said(after);
        eprintln!(
            "bearingd: replay: run boundary at {}: run {} (sample 0 at {}) follows run {}: the \
             daemon restarted (a crash or a stop); the pipeline starts again, {baselines}",
            after.first_file.display(),
            after
                .run_id
                .map_or("without metadata".into(), |r| r.to_string()),
            utc_text(after.origin_ns),
            before
                .run_id
                .map_or("without metadata".into(), |r| r.to_string()),
        );
    }
    const GAP_LINES: usize = 10;
    for gap in summary.gaps.iter().take(GAP_LINES) {
        eprintln!(
            "bearingd: replay: gap in {}: {:.3} s ({} samples) missing from sample {}",
            gap.channel, gap.seconds, gap.missing_samples, gap.at_sample
        );
    }
    if summary.gap_count > GAP_LINES as u64 {
        eprintln!(
            "bearingd: replay: {} gaps in all, {:.3} s of signal missing (--json lists them)",
            summary.gap_count, summary.gap_seconds
        );
    }
    for missing in &plan.missing {
        eprintln!(
            "bearingd: replay: run {}: file {} of the run is not among those given (after {}; \
             deleted by retention, or not given)",
            missing.run_id,
            missing.sequence,
            missing.after.display()
        );
    }
    let read = &summary.read;
    if read.unreadable_bytes() > 0 || read.unfinished_files() > 0 {
        eprintln!(
            "bearingd: replay: {} unfinished file(s); {} bytes could not be read (read up to the last complete chunk)",
            read.unfinished_files(),
            read.unreadable_bytes()
        );
    }
    if !summary.unknown_channels.is_empty() {
        eprintln!(
            "bearingd: replay: channels not in the config were skipped: {}; give --config with these sensors",
            summary.unknown_channels.join(", ")
        );
    }
}

/// Refuses a file that does not start with the MCAP magic: replaying it would read nothing and
/// succeed, which looks like an empty log rather than the wrong file.
fn check_mcap_magic(file: &Path) -> Result<(), CliError> {
    use std::io::Read;
    let mut magic = [0u8; 8];
    let read = std::fs::File::open(file).and_then(|mut f| f.read_exact(&mut magic));
    match read {
        Ok(()) if magic == *mcap::MAGIC => Ok(()),
        Ok(()) | Err(_) => Err(CliError::input(format!(
            "{}: not an MCAP log (it does not start with the MCAP magic bytes); give a log \
             written by `bearingd run` or `bearingd import` (a .mcap file)",
            file.display()
        ))),
    }
}

/// Refuses a file from which not one message could be read because reading stopped on a
/// defect (random bytes after the magic, a hostile length, a cut before the first chunk):
/// replaying it would succeed with 0 blocks, which looks like an empty log rather than a broken
/// file. A complete log that simply holds no message is replayed (it says so: 0 blocks).
fn check_holds_a_message(header: &LogHeader) -> Result<(), CliError> {
    match header.no_message_reason() {
        Some(why) => Err(CliError::input(format!(
            "{}: {why}; leave it out of the replay",
            header.path.display()
        ))),
        None => Ok(()),
    }
}
