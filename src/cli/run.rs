//! `bearingd run`: the service. With no config, the embedded default: a simulated sensor that
//! develops an outer-race fault after 30 s, so that a new user sees the whole loop.

use super::format::FormatArg;
use super::CliError;
use crate::config::{self, Config};
use crate::daemon::state::StateError;
use crate::daemon::{run, DaemonEvent, Events, RunOptions, SinkPlan};
use crate::mcap_log::files::utc_text;
use crate::messages::{FlagMessage, HealthKind, PipelineMessage, SpeedSource};
use crate::pipeline::{ChannelStatus, Sink, SinkError};
use crate::report::plain::flag_words;
use crate::sinks::mcap::{LateCounts, LogNotice, RecoveryAction, RecoveryReport, RetentionReport};
use clap::Args;
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(Args)]
pub struct RunArgs {
    /// Configuration file; without it, the embedded default (a simulated sensor).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Stop after this many seconds of sample time (default: run until SIGINT/SIGTERM).
    #[arg(long)]
    duration: Option<f64>,
    /// Run simulated sensors as fast as the analysis allows instead of in real time.
    #[arg(long)]
    fast: bool,
    /// Where to keep state (DIR/state) and logs (DIR/mcap); overrides outputs.state_dir and
    /// outputs.mcap_dir of --config. Without --config, default ./bearingd-data.
    #[arg(long)]
    data_dir: Option<PathBuf>,
    /// No status lines (flags and the summary are still printed).
    #[arg(long)]
    quiet: bool,
    /// Also publish to this MQTT broker (mqtt://HOST:PORT or mqtts://HOST:PORT) with the fleet
    /// bridge's defaults, node id = this host's name: a first look; a service sets [fleet] in
    /// its config (docs/FLEET.md).
    #[arg(long, value_name = "BROKER")]
    fleet: Option<String>,
    // With json, the status lines, flags, health changes and the summary are one JSON object
    // per line on stdout (NDJSON), each with its "type".
    #[command(flatten)]
    format: FormatArg,
}

/// Prints every flag change as it happens (with `json`, one JSON object per line).
struct FlagPrinter {
    json: bool,
}

impl Sink for FlagPrinter {
    fn write(&mut self, message: &PipelineMessage) {
        if self.json {
            if let Some(value) = message_json(message) {
                println!("{value}");
            }
            return;
        }
        match message {
            PipelineMessage::Flag(f) => println!(
                "FLAG {}: {} {} -> {} — {} (score {:.1}, {:.1} Hz) at sample {}",
                f.channel,
                f.fault,
                f.from,
                f.to,
                flag_words(f.fault, f.from, f.to),
                f.score,
                f.fault_frequency_hz,
                f.end_sample
            ),
            PipelineMessage::Detector(m) => {
                if let Some(f) = m.as_flag() {
                    let (from, to) = f.change();
                    println!(
                        "FLAG {}: {} {from} -> {to} ({}) at sample {}",
                        f.channel(),
                        f.flag().name,
                        f.evidence(),
                        f.end_sample()
                    );
                }
            }
            PipelineMessage::Health(h) if h.kind != HealthKind::Bands => {
                println!(
                    "HEALTH {}: {} at sample {}",
                    h.channel, h.detail, h.end_sample
                )
            }
            _ => {}
        }
    }

    fn finish(&mut self) -> Result<(), SinkError> {
        Ok(())
    }
}

/// A flag change or a health change as a line of `run --format json` (`None`: not printed).
fn message_json(message: &PipelineMessage) -> Option<serde_json::Value> {
    match message {
        PipelineMessage::Flag(f) => Some(typed("flag", f)),
        PipelineMessage::Detector(m) => m.as_flag().map(|f| {
            let (from, to) = f.change();
            serde_json::json!({
                "type": "flag",
                "channel": f.channel().to_string(),
                "flag": f.flag().name,
                "from": from.to_string(),
                "to": to.to_string(),
                "score": f.score(),
                "evidence": f.evidence(),
                "end_sample": f.end_sample(),
            })
        }),
        PipelineMessage::Health(h) if h.kind != HealthKind::Bands => Some(typed("health", h)),
        _ => None,
    }
}

/// The daemon's part of the alerts' latency, for the summary line.
fn in_service_text(d: &crate::sinks::alerts::DelaySpread) -> String {
    let ms = |us: u64| us as f64 / 1e3;
    format!(
        ", each in the service p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms after its input arrived \
         (the subscribers' wake-up comes on top)",
        ms(d.p50_us),
        ms(d.p99_us),
        ms(d.max_us)
    )
}

/// `value` as a JSON object with `"type": kind` added (a line of `--format json`).
fn typed(kind: &str, value: &impl serde::Serialize) -> serde_json::Value {
    let mut value = serde_json::to_value(value).unwrap_or_default();
    if let Some(object) = value.as_object_mut() {
        object.insert("type".into(), kind.into());
    }
    value
}

pub fn run_command(args: &RunArgs) -> Result<(), CliError> {
    // What the daemon creates is never more open than 0750/0640, whatever umask it inherits.
    crate::fsafe::restrict_umask();
    let mut config = match &args.config {
        Some(path) => {
            let mut config = config::load(path).map_err(CliError::input)?;
            if let Some(data) = &args.data_dir {
                // The command line wins over the file, as without a config: the same layout.
                // A fleet queue left at its default (under the state directory) follows it.
                if let Some(fleet) = config.fleet.as_mut() {
                    if fleet.queue_dir == config.outputs.state_dir.join("fleet") {
                        fleet.queue_dir = data.join("state").join("fleet");
                    }
                }
                config.outputs.state_dir = data.join("state");
                config.outputs.mcap_dir = data.join("mcap");
                eprintln!(
                    "bearingd: --data-dir overrides outputs.state_dir and outputs.mcap_dir of {}: state in {}, logs in {}",
                    path.display(),
                    config.outputs.state_dir.display(),
                    config.outputs.mcap_dir.display()
                );
            }
            config
        }
        None => embedded_default(args)?,
    };
    if let Some(broker) = &args.fleet {
        if config.fleet.is_some() {
            // The command line wins over the file, as --data-dir does, and says so.
            eprintln!(
                "bearingd: --fleet {broker} overrides the [fleet] section of {}",
                args.config
                    .as_deref()
                    .map_or_else(|| "the config".into(), |p| p.display().to_string())
            );
        }
        let fleet =
            config::FleetConfig::for_broker(broker, &host_node_id(), &config.outputs.state_dir)
                .map_err(CliError::input)?;
        config.fleet = Some(fleet);
    }
    let options = RunOptions {
        duration_s: args.duration,
        realtime: !args.fast,
        status_lines: !args.quiet,
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .on_thread_start(crate::pipeline::priority::lower_this_thread)
        .enable_all()
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the async runtime: {e}")))?;
    let json = args.format.json();
    let sinks = SinkPlan::run(vec![Box::new(FlagPrinter { json })]);
    let summary = runtime.block_on(async {
        let shutdown = shutdown_signal().map_err(|e| {
            CliError::failure(format!("cannot install the SIGINT/SIGTERM handlers: {e}"))
        })?;
        run(config, options, sinks, print_events(json), shutdown)
            .await
            .map_err(CliError::input)
    })?;
    if json {
        println!("{}", typed("summary", &summary));
        return Ok(());
    }
    println!(
        "summary: {} messages, {} twin fits ({} dropped), {} alerts published{}{}",
        summary.messages,
        summary.twin_fits,
        summary.twin_requests_skipped,
        summary.alerts_published,
        if summary.alerts_failed > 0 {
            format!(
                " ({} NOT PUBLISHED: iceoryx2 refused them, see the errors above)",
                summary.alerts_failed
            )
        } else {
            String::new()
        },
        summary
            .alerts_in_service
            .map(|d| in_service_text(&d))
            .unwrap_or_default()
    );
    for channel in &summary.channels {
        println!("  {}", status_line(channel));
    }
    for flag in &summary.flags {
        println!("  {}", flag_recap(flag));
    }
    Ok(())
}

/// One flag change of a run's or a replay's summary, with what it means for the technician.
pub(super) fn flag_recap(flag: &FlagMessage) -> String {
    format!(
        "flag {}: {} {} -> {} — {} at sample {} (score {:.1})",
        flag.channel,
        flag.fault,
        flag.from,
        flag.to,
        flag_words(flag.fault, flag.from, flag.to),
        flag.end_sample,
        flag.score
    )
}

fn embedded_default(args: &RunArgs) -> Result<Config, CliError> {
    let config = embedded_config(args.data_dir.as_deref())?;
    let data = data_dir(args.data_dir.as_deref());
    eprintln!(
        "bearingd: no --config: running the embedded default (a simulated sensor on an SKF 6205-2RS that develops an outer-race fault after 30 s); state and logs in {}",
        data.display()
    );
    Ok(config)
}

/// Installs the SIGINT and SIGTERM handlers now (tokio owns the signals) and returns a future
/// that resolves on either. Installed before `run` starts, so a stop that comes right after
/// READY is not taken by the default action (which would leave the MCAP file unfinished).
fn shutdown_signal() -> std::io::Result<impl std::future::Future<Output = ()>> {
    use tokio::signal::unix::{signal, SignalKind};
    let mut interrupt = signal(SignalKind::interrupt())?;
    let mut terminate = signal(SignalKind::terminate())?;
    Ok(async move {
        tokio::select! {
            _ = interrupt.recv() => {},
            _ = terminate.recv() => {},
        }
    })
}

/// The data directory of a run without a config: `--data-dir`, or `./bearingd-data`.
fn data_dir(given: Option<&Path>) -> PathBuf {
    given.map_or_else(|| PathBuf::from("bearingd-data"), Path::to_path_buf)
}

/// The embedded default config for `--data-dir` (or `./bearingd-data`); see
/// [`Config::embedded_in`].
pub(super) fn embedded_config(data_dir_arg: Option<&Path>) -> Result<Config, CliError> {
    let data = data_dir(data_dir_arg);
    Config::embedded_in(&data).map_err(CliError::input)
}

/// The daemon's events as lines: status lines on stdout (with `json`, one JSON object per
/// channel, `"type": "status"`), everything else on stderr (the journal under systemd).
pub(super) fn print_events(json: bool) -> Events {
    Arc::new(move |event| match event {
        DaemonEvent::Status(board) => {
            for channel in &board {
                if json {
                    println!("{}", typed("status", channel));
                } else {
                    println!("{}", status_line(channel));
                }
            }
        }
        other => eprintln!("{}", event_line(&other)),
    })
}

/// How a notice of the MCAP log reads on stderr.
fn log_notice_line(notice: &LogNotice) -> String {
    match notice {
        LogNotice::Retention(report) => retention_line(report),
        LogNotice::Paused {
            path,
            error,
            flushed_until_ns,
        } => format!(
            "bearingd: warning: logging PAUSED: {error}; {} is left unfinished (its data up to {} is kept and recovered when there is room); analysis and alerts go on; logging resumes by itself when the log directory has room again (free some space, or lower outputs.mcap_disk_budget_mb below the file system's size)",
            path.display(),
            utc_text(*flushed_until_ns)
        ),
        LogNotice::Resumed {
            path,
            messages_not_logged,
            seconds_not_logged,
        } => format!(
            "bearingd: logging resumed in {}: {messages_not_logged} messages not logged during the pause, {seconds_not_logged:.1} s of signal lost",
            path.display()
        ),
        LogNotice::LateWritten {
            path,
            written,
            dropped,
        } => format!(
            "bearingd: written late to {} (\"late\": true, publish_time = when decided): flag changes {}, health events {} decided during the pause{}",
            path.display(),
            written.flags,
            written.health,
            dropped_line(dropped)
        ),
        LogNotice::LateLost { held, dropped } => format!(
            "bearingd: warning: stopped while logging was paused: flag changes {}, health events {} held for the log were never written (the FLAG lines above have the flag changes){}",
            held.flags,
            held.health,
            dropped_line(dropped)
        ),
        LogNotice::PausedFileRecovered(report) => recovery_line(report),
        LogNotice::PausedFileNotRecovered { path, error } => format!(
            "bearingd: warning: {} (left by the pause) could not be recovered now: {error}; the next start recovers it",
            path.display()
        ),
    }
}

/// What a pause could not hold in memory, said after what it held.
fn dropped_line(dropped: &LateCounts) -> String {
    if dropped.total() == 0 {
        return String::new();
    }
    format!(
        "; {} flag changes and {} health events dropped for lack of room in memory (the /state snapshot at the resume has the latest)",
        dropped.flags, dropped.health
    )
}

/// How an event other than a status reads on stderr.
pub(super) fn event_line(event: &DaemonEvent) -> String {
    match event {
        DaemonEvent::Recovered(report) => recovery_line(report),
        DaemonEvent::StaleLockTakenOver { path, previous } => format!(
            "bearingd: {}: taken over from a previous bearingd that did not stop cleanly ({previous})",
            path.display()
        ),
        DaemonEvent::Log(notice) => log_notice_line(notice),
        DaemonEvent::LoggingTo(path) => format!("bearingd: logging to {}", path.display()),
        DaemonEvent::CpuLatencyCapped { latency_us } => format!(
            "bearingd: CPU wake-up latency capped at {latency_us} µs while running \
             (outputs.cpu_wakeup_latency_us)"
        ),
        DaemonEvent::CpuLatencyRefused(error) => format!("bearingd: warning: {error}"),
        DaemonEvent::HeapInSmallPages { missing } => format!(
            "bearingd: note: the analysis' memory is in 4 KiB pages (GLIBC_TUNABLES lacks {}); \
             on a VM whose host reclaims idle memory an alert can wait milliseconds for it. \
             Start bearingd with GLIBC_TUNABLES={}, as the systemd unit does (docs/PERFORMANCE.md)",
            missing.join(":"),
            crate::daemon::heap_pages::HEAP_TUNABLES
        ),
        DaemonEvent::IoxRootTightened { root, from } => format!(
            "bearingd: iceoryx2 root {} was mode {from:04o}: now 0700 (only bearingd's user may use it)",
            root.display()
        ),
        DaemonEvent::AlertsOn {
            service,
            root,
            reopened,
        } => format!(
            "bearingd: alerts on iceoryx2 service {service} (root {}){}",
            root.display(),
            if *reopened {
                "; reopened our previous run's service, kept alive by its subscribers"
            } else {
                ""
            }
        ),
        #[cfg(feature = "shm")]
        DaemonEvent::DeadIoxNode { root, node } => match &node.removed {
            Ok(()) => format!(
                "bearingd: iceoryx2: removed the stale resources of a dead {} under {} (a process that did not stop cleanly)",
                node.description,
                root.display()
            ),
            Err(why) => format!(
                "bearingd: warning: iceoryx2: the dead {} under {} left resources that could not be removed ({why}); remove them as the user that ran it",
                node.description,
                root.display()
            ),
        },
        #[cfg(feature = "shm")]
        DaemonEvent::DeadIoxNodesUnknown(why) => {
            format!("bearingd: warning: iceoryx2: dead nodes not looked for: {why}")
        }
        DaemonEvent::NoAlertService => {
            "bearingd: built without the `shm` feature: no iceoryx2 alerts are published".into()
        }
        #[cfg(feature = "shm")]
        DaemonEvent::AlertFailed(error) => format!("bearingd: {error}"),
        DaemonEvent::TwinFitDropped {
            channel,
            dropped_end_sample,
            total,
        } => format!(
            "bearingd: twin re-fit of {channel} at sample {dropped_end_sample} dropped: the \
             re-fit thread is behind and the channel asked again ({total} dropped so far)"
        ),
        DaemonEvent::SourceStopped { source, error } => {
            format!("bearingd: {source} stopped: {error}")
        }
        DaemonEvent::Fleet(line) => format!("bearingd: {line}"),
        DaemonEvent::SourceTaskFailed(error) => format!("bearingd: a source task failed: {error}"),
        DaemonEvent::UnknownChannel { channel, blocks } => format!(
            "bearingd: {blocks} blocks of {channel} skipped: no such sensor/axis in the config"
        ),
        DaemonEvent::StateLoaded(loaded) => format!(
            "bearingd: loaded the health baselines of {} channel(s) from {}, saved {}",
            loaded.channels,
            loaded.path.display(),
            if loaded.saved_at_ns == 0 {
                "at an unknown time".to_string()
            } else {
                utc_text(loaded.saved_at_ns)
            }
        ),
        DaemonEvent::NoState(dir) => format!(
            "bearingd: no saved health baselines in {}: learning them from the start",
            dir.display()
        ),
        DaemonEvent::State(problem @ StateError::Unreadable { .. }) => {
            format!("bearingd: warning: {problem}; health baselines are learned again")
        }
        DaemonEvent::State(problem) => format!("bearingd: warning: {problem}"),
        DaemonEvent::Notify(problem) => format!("bearingd: {problem}"),
        DaemonEvent::Status(board) => board.iter().map(status_line).collect::<Vec<_>>().join("\n"),
        DaemonEvent::ReplayUnreadable(error) => format!("bearingd: replay: {error}"),
        DaemonEvent::ReplayProgress {
            sample_seconds,
            bytes_read,
            bytes_total,
            raw_blocks,
            flag_changes,
        } => format!(
            "replay: {:.0} % of {} bytes, {sample_seconds:.0} s of signal, {raw_blocks} blocks, \
             {flag_changes} flag changes",
            100.0 * *bytes_read as f64 / (*bytes_total).max(1) as f64,
            bytes_total,
        ),
    }
}

/// What a retention pass deleted, and what it left alone (names that are not its files).
fn retention_line(report: &RetentionReport) -> String {
    let mut lines = Vec::new();
    if !report.deleted.is_empty() {
        lines.push(format!(
            "bearingd: retention: deleted {} ({} bytes) to keep the logs within outputs.mcap_disk_budget_mb; {} bytes of logs left",
            report
                .deleted
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            report.bytes_deleted,
            report.total_bytes_after
        ));
    }
    for skipped in &report.skipped {
        lines.push(format!("bearingd: warning: retention left alone {skipped}"));
    }
    lines.join("\n")
}

/// What recovery did with one unfinished file, in one line.
fn recovery_line(report: &RecoveryReport) -> String {
    let problem = report
        .problem
        .as_ref()
        .map(|(at, why)| format!(" (from byte {at}: {why})"))
        .unwrap_or_default();
    let path = report.path.display();
    match &report.action {
        RecoveryAction::Rewritten { original_kept } => format!(
            "bearingd: recovered {path}: {} messages kept, {} bytes unreadable{problem}{}",
            report.messages_recovered,
            report.unreadable_bytes,
            original_kept
                .as_ref()
                .map(|k| format!("; damaged original kept as {}", k.display()))
                .unwrap_or_default()
        ),
        RecoveryAction::Quarantined { to, reason } => format!(
            "bearingd: warning: {path} could not be recovered ({reason}); moved, untouched, to {}",
            to.display()
        ),
        RecoveryAction::Skipped(why) => {
            format!("bearingd: warning: recovery left alone {why}")
        }
        RecoveryAction::RemovedEmpty => {
            format!("bearingd: removed {path}: an empty file (0 bytes) left by an earlier start")
        }
    }
}

/// One channel's status in one line (its fields: docs/DAEMON.md "Status line").
pub fn status_line(s: &ChannelStatus) -> String {
    let band = s.band_hz.map_or("learning".to_string(), |b| {
        format!("{:.0}-{:.0} Hz", b[0], b[1])
    });
    // A window with no score (no band or no speed yet) has no top fault, whatever the order
    // of four zeros would make the first.
    let top = s
        .top_fault
        .filter(|_| s.top_score > 0.0)
        .map_or("-".to_string(), |f| format!("{f} {:.1}", s.top_score));
    let twin = match (&s.twin_hypothesis, s.twin_error) {
        (Some(h), Some(e)) => format!("{h} err {e:.3}"),
        _ => "-".into(),
    };
    let rpm = match (s.rpm, s.speed_source) {
        (Some(rpm), SpeedSource::Fixed) => format!("{rpm:.0}"),
        (Some(rpm), source) => format!("{rpm:.0}({source})"),
        (None, SpeedSource::Estimate) => "?(no estimate yet: scoring waits)".to_string(),
        (None, _) => "?(no usable speed frame: scoring waits)".to_string(),
    };
    let readings: String = s
        .readings
        .iter()
        .map(|(key, text)| format!(" {key}={text}"))
        .collect();
    format!(
        "{} t={:.1}s rpm={} band={} top={} twin={} stage={}{} flags={}{}{}",
        s.channel,
        s.seconds,
        rpm,
        band,
        top,
        twin,
        s.stage,
        readings,
        s.flags_summary(),
        if s.gaps > 0 {
            format!(" GAPS {} ({} samples missing)", s.gaps, s.missing_samples)
        } else {
            String::new()
        },
        if s.sensor_lost { " SENSOR LOST" } else { "" }
    )
}

/// This host's name as a Sparkplug node id (characters outside `A-Z a-z 0-9 - _ .` become
/// `-`); `bearingd` when it has none.
fn host_node_id() -> String {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let id: String = name
        .trim()
        .chars()
        .take(64)
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '-'
            }
        })
        .collect();
    if id.is_empty() {
        "bearingd".into()
    } else {
        id
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{ChannelId, FaultKind, HealthStage};

    fn status() -> ChannelStatus {
        ChannelStatus {
            samples: 25_600,
            seconds: 1.0,
            band_hz: Some([1067.0, 2133.0]),
            top_fault: Some(FaultKind::Cage),
            ..ChannelStatus::new(
                ChannelId {
                    sensor: "s1".into(),
                    axis: "radial".into(),
                },
                Some(1772.0),
                SpeedSource::Fixed,
                HealthStage::Learning,
            )
        }
    }

    #[test]
    fn an_unscored_window_shows_no_top_fault() {
        let line = status_line(&status());
        assert!(line.contains(" top=- "), "{line}");
        let scored = ChannelStatus {
            top_fault: Some(FaultKind::OuterRace),
            top_score: 12.34,
            ..status()
        };
        let line = status_line(&scored);
        assert!(line.contains(" top=outer_race 12.3 "), "{line}");
        assert!(line.contains(" band=1067-2133 Hz "), "{line}");
    }
}
